#!/usr/bin/env python3
"""Checks that every CTest entry discovered from a Catch2 executable runs exactly one test case.

CTest splits a test name at ';', and catch_discover_tests then registers entries whose test spec
matches no test case: Catch2 prints "No test cases matched" and the entry passes without running
anything. This check lists the build's entries (ctest --show-only=json-v1) and, for each one that
runs a Catch2 executable with a test spec, asks the executable which test cases the spec selects
(--list-test-names-only). It fails, naming the entry, when a spec selects no case or several, when
an entry lacks `--warn NoTests`, or when a test case of an executable is selected by no entry.

Usage: check_ctest_entries.py BUILD_DIR [LABEL_REGEX]
With LABEL_REGEX only the entries of those labels are checked: the sanitizer build builds only
what its pass runs (target sanitizer_pass), and the other executables' entries are the first
build's to check.
"""
import json
import subprocess
import sys
from collections import defaultdict

# Entries that run a whole Catch2 executable (one VM boot each) and this check itself.
WHOLE_EXECUTABLE_ENTRIES = {"can.vcan", "can.rig"}
SELF = "meta.ctest_entries"
# Entries that run a script, not a Catch2 executable.
SCRIPT_ENTRIES = {"meta.truth_side", "meta.house_rules", "meta.format", "meta.house_rules_catch", "python.module", "python.readme", "resource.bounded_input.python", "resource.garbled.python", "install.prefix", "can.canvm_out", "system.dashboard.browser",
                  "system.foxglove.dashboard_replay", "system.foxglove.dashboard_late"}
# Entries of the sanitizer build that run a libFuzzer target (fuzz/CMakeLists.txt), not Catch2.
FUZZ_PREFIX = "fuzz."


def catch_list(exe, spec=None):
    cmd = [exe] + ([spec] if spec is not None else []) + ["--list-test-names-only"]
    out = subprocess.run(cmd, capture_output=True, text=True, check=False).stdout
    return [line for line in out.splitlines() if line.strip()]


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__, file=sys.stderr)
        return 2
    labels = ["-L", sys.argv[2]] if len(sys.argv) == 3 else []
    shown = subprocess.run(["ctest", "--test-dir", sys.argv[1], "--show-only=json-v1"] + labels,
                           capture_output=True, text=True, check=True).stdout
    tests = json.loads(shown)["tests"]
    # The entries of other labels run test cases of the same executables: with a label filter,
    # their cases count as run too (listed from the executables this check runs anyway).
    others = []
    if labels:
        everything = subprocess.run(["ctest", "--test-dir", sys.argv[1], "--show-only=json-v1"],
                                    capture_output=True, text=True, check=True).stdout
        checked_names = {t["name"] for t in tests}
        others = [t for t in json.loads(everything)["tests"] if t["name"] not in checked_names]
    problems = []
    selected = defaultdict(set)   # executable -> test case names some entry selects
    checked = 0
    for test in tests:
        name, command = test["name"], test.get("command", [])
        if name == SELF or name in SCRIPT_ENTRIES or name.startswith(FUZZ_PREFIX):
            continue
        if name in WHOLE_EXECUTABLE_ENTRIES:
            if "NoTests" not in command:
                problems.append(f"{name}: runs a whole Catch2 executable without --warn NoTests")
            continue
        if len(command) < 2 or command[1].startswith("-"):
            problems.append(f"{name}: not a discovered Catch2 entry (command {command}); "
                            "register it with rig_discover_tests or list it in this check")
            continue
        exe, spec = command[0], command[1]
        if "--warn" not in command or "NoTests" not in command:
            problems.append(f"{name}: discovered without --warn NoTests (use rig_discover_tests)")
        cases = catch_list(exe, spec)
        checked += 1
        if len(cases) != 1:
            problems.append(f"{name}: its test spec {spec!r} selects {len(cases)} test cases "
                            f"of {exe} ({cases[:3]}); a ';' in a test name splits the entry")
        selected[exe].update(cases)
    for test in others:
        command = test.get("command", [])
        if len(command) >= 2 and command[0] in selected and not command[1].startswith("-"):
            selected[command[0]].update(catch_list(command[0], command[1]))
    for exe, cases in selected.items():
        missed = sorted(set(catch_list(exe)) - cases)
        for case in missed:
            problems.append(f"{exe}: test case {case!r} is run by no CTest entry")
    for problem in problems:
        print("FAIL", problem)
    print(f"{checked} discovered entries in {len(selected)} executables checked; "
          f"{len(problems)} problems")
    return 1 if problems or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
