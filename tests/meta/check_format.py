#!/usr/bin/env python3
"""Checks that every C++ source of the rig is laid out as .clang-format says.

Runs `clang-format --dry-run -Werror` (Debian's clang-format, which scripts/setup.sh installs)
on each .h, .cc and .hpp the repository holds (git ls-files when SOURCE_DIR is a checkout, else
every such file under it but build directories), and fails naming each file that differs, with
clang-format's first complaint. Without clang-format it fails and says which package to install:
the check is never skipped.

Usage: check_format.py SOURCE_DIR
"""
import pathlib
import shutil
import subprocess
import sys

SUFFIXES = (".h", ".cc", ".hpp")


def sources(root):
    try:
        out = subprocess.run(["git", "-C", str(root), "ls-files", "-z"], capture_output=True, check=True).stdout
        names = [n for n in out.decode().split("\0") if n]
    except (OSError, subprocess.CalledProcessError):
        names = [str(p.relative_to(root)) for p in root.rglob("*") if p.is_file()]
        names = [n for n in names if not n.split("/")[0].startswith("build")]
    return sorted(n for n in names if n.endswith(SUFFIXES) and (root / n).is_file())


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    root = pathlib.Path(sys.argv[1]).resolve()
    tool = shutil.which("clang-format")
    if tool is None:
        print("check_format: clang-format is not on the PATH: install the Debian package clang-format "
              "(scripts/setup.sh does)")
        return 1
    files = sources(root)
    bad = []
    for i in range(0, len(files), 50):
        batch = files[i:i + 50]
        r = subprocess.run([tool, "--dry-run", "-Werror", "--style=file"] + batch, cwd=root, capture_output=True,
                           text=True)
        if r.returncode != 0:
            for name in batch:
                one = subprocess.run([tool, "--dry-run", "-Werror", "--style=file", name], cwd=root,
                                     capture_output=True, text=True)
                if one.returncode != 0:
                    first = next((l for l in one.stderr.splitlines() if "error:" in l), one.stderr.strip()[:200])
                    bad.append("%s: %s" % (name, first))
    for b in bad:
        print(b)
    print("check_format: %d sources, %d not as .clang-format lays them out%s" %
          (len(files), len(bad), " (clang-format -i FILE lays one out)" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
