#!/usr/bin/env python3
"""Checks that the truth side of the rig does not depend on the estimator under test.

The truth side is plant/, mocap/ and sensors/: their sources must not include an estimator/
header and their CMakeLists.txt must not link an estimator library (nimble_estimation,
nimble_sensing_config). The data types both sides exchange live in core/rig_values.h.
Fails naming each file and line that does.

Usage: check_truth_side.py SOURCE_DIR
"""
import pathlib
import re
import sys

TRUTH_SIDE = ("plant", "mocap", "sensors")
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]estimator/')
LINK = re.compile(r"\bnimble_(estimation|sensing_config)\b")


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    root = pathlib.Path(sys.argv[1])
    problems = []
    for folder in TRUTH_SIDE:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix in (".h", ".cc"):
                pattern, what = INCLUDE, "includes an estimator header"
            elif path.name == "CMakeLists.txt":
                pattern, what = LINK, "names an estimator library"
            else:
                continue
            for number, line in enumerate(path.read_text().splitlines(), start=1):
                if line.lstrip().startswith("#") and path.name == "CMakeLists.txt":
                    continue  # CMake comments may name the estimator
                if pattern.search(line):
                    problems.append(f"{path.relative_to(root)}:{number}: {what}: {line.strip()}")
    for problem in problems:
        print(problem)
    if problems:
        print(f"{len(problems)} dependencies of the truth side ({', '.join(TRUTH_SIDE)}) on the estimator")
        return 1
    print(f"truth side ({', '.join(TRUTH_SIDE)}) independent of the estimator")
    return 0


if __name__ == "__main__":
    sys.exit(main())
