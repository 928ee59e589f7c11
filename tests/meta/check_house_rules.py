#!/usr/bin/env python3
"""The house rules a compiler does not check, over the rig's sources (tests excluded).

1. Channel names are spelled only in contract/channels.h: no other source holds a string
   literal that is a channel's name.
2. No rate literal in a process: every set_expected_rate() takes its rate from the run
   (Scenario::expected_rate()), never a number written in the call.
3. No include runs up to the programs: cli/ is included only from cli/; launcher/ only from
   launcher/ and the folders above it (cli/, reproduce/, power/, bench/, tools/, fuzz/).
4. No source file is longer than MAX_LINES: a longer one holds more than one job, and is split
   by job.

Usage: check_house_rules.py <source dir>. Prints every breach as file:line and exits 1 if
there is one.
"""
import pathlib
import re
import sys

SKIP_DIRS = {"tests", "lcmtypes", ".git", "corpus"}
ABOVE_LAUNCHER = {"launcher", "cli", "reproduce", "power", "bench", "tools", "fuzz"}
MAX_LINES = 650


def sources(root):
    for path in sorted(root.rglob("*")):
        rel = path.relative_to(root)
        if not path.is_file() or path.suffix not in (".cc", ".h"):
            continue
        if rel.parts[0] in SKIP_DIRS or rel.parts[0].startswith("build"):
            continue
        yield rel, path.read_text(errors="replace").splitlines()


def channel_names(root):
    text = (root / "contract" / "channels.h").read_text()
    names = re.findall(r'inline const std::string k\w+ = "([A-Z_]+)";', text)
    if len(names) < 10:
        sys.exit("check_house_rules: found only %d channel names in contract/channels.h" % len(names))
    return set(names)


def main():
    root = pathlib.Path(sys.argv[1]).resolve()
    names = channel_names(root)
    literal = re.compile(r'"([A-Z_]+)"')
    rate_call = re.compile(r"set_expected_rate\s*\(([^;]*)\)")
    number = re.compile(r"(?<![\w.])\d+(\.\d*)?([eE][-+]?\d+)?(?![\w.])")
    include = re.compile(r'#include\s+"(cli|launcher)/')
    breaches = []
    checked = 0
    for rel, lines in sources(root):
        checked += 1
        top = rel.parts[0]
        if len(lines) > MAX_LINES:
            breaches.append("%s: %d lines, over %d: split it by job" % (rel, len(lines), MAX_LINES))
        for n, line in enumerate(lines, 1):
            code = line.split("//", 1)[0]
            if str(rel) != "contract/channels.h":
                for name in literal.findall(code):
                    if name in names:
                        breaches.append('%s:%d: channel "%s" spelled outside contract/channels.h' % (rel, n, name))
            for args in rate_call.findall(code):
                if number.search(args.split(",", 1)[-1]):
                    breaches.append("%s:%d: set_expected_rate with a rate literal: %s" % (rel, n, line.strip()))
            m = include.search(code)
            if m:
                folder = m.group(1)
                allowed = {"cli"} if folder == "cli" else ABOVE_LAUNCHER
                if top not in allowed:
                    breaches.append("%s:%d: %s/ included from %s/, a folder below it" % (rel, n, folder, top))
    for b in breaches:
        print(b)
    print("check_house_rules: %d source files, %d channel names, %d breaches" % (checked, len(names), len(breaches)))
    return 1 if breaches else 0


if __name__ == "__main__":
    sys.exit(main())
