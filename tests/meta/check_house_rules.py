#!/usr/bin/env python3
"""The house rules a compiler does not check, over the rig's sources (tests excluded).

1. Channel names are spelled only in contract/channels.h: no other source holds a string
   literal that is a channel's name.
2. No rate literal in a process: every set_expected_rate() takes its rate from the run
   (Scenario::expected_rate()), never a number written in the call.
3. No include runs up to the programs: cli/ is included only from cli/; launcher/ only from
   launcher/ and the folders above it (cli/, reproduce/, detection_power/, bench/, tools/, fuzz/).
4. No source file is longer than MAX_LINES: a longer one holds more than one job, and is split
   by job.
5. No function is longer than MAX_FUNCTION_LINES (from its header's line to its closing brace).
6. No file name is in two rooms (a room: a top-level folder, or tools/<tool>).
7. Every include across rooms is one the layer map of docs/layout.md allows, every room with
   sources is on the map, and the map's rows name only rooms on lower floors.
8. No rate literal in a process: a process room's .cc files give no rate a literal fallback
   (a rate comes from the process's configuration or the contract, contract/rates.h).
9. An effect's name is spelled only in its own file pair (effects/<name>.{h,cc}): no other
   source holds a string literal that is an effect's name, so that no code outside the effect
   picks it by name (the workflow reads the effect's properties, effects/effect.h).
10. JSON is written through nlohmann (core/json_line.h: a document built as an OrderedJson,
   written by json_line()): no source writes it key by key through a writer of its own
   (`.key("...")`). lcmjson/ is the one serialiser by hand: it walks an LCM message's bytes.
11. No rate default outside the contract: a rate's default (`..._rate_hz = 512.0;`) is one of
   contract/rates.h's constants, so that each default is written once, where the contract
   derives the channels' rates from them.

Usage: check_house_rules.py <source dir>. Prints every breach as file:line and exits 1 if
there is one.
"""
import collections
import pathlib
import re
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from cxx_functions import functions  # noqa: E402

SKIP_DIRS = {"tests", "lcmtypes", ".git", "corpus"}
ABOVE_LAUNCHER = {"launcher", "campaign", "cli", "python", "reproduce", "detection_power", "bench", "tools", "fuzz"}
MAX_LINES = 650
MAX_FUNCTION_LINES = 120
PROCESS_ROOMS = {"plant", "controller", "estimator", "mocap", "can_bridge", "sensors", "transport"}
KEY_WRITER = re.compile(r'\.key\(\s*"')
RATE_DEFAULT = re.compile(r"\b(?!\w*burst)\w*rate_hz\s*=\s*(?=[\d.]*[1-9])\d*\.?\d*([eE][-+]?\d+)?\s*;")
RATE_FALLBACK = re.compile(r"(rate|_hz)\b.*\?.*:\s*\d+(\.\d*)?([eE][-+]?\d+)?\s*;|_hz\s*=\s*\d+(\.\d*)?\s*;")


def sources(root):
    for path in sorted(root.rglob("*")):
        rel = path.relative_to(root)
        if not path.is_file() or path.suffix not in (".cc", ".h"):
            continue
        if rel.parts[0] in SKIP_DIRS or rel.parts[0].startswith("build"):
            continue
        yield rel, path.read_text(errors="replace").splitlines()


def room_of(rel):
    return "/".join(rel.parts[:2]) if rel.parts[0] == "tools" and len(rel.parts) > 2 else rel.parts[0]


def layer_map(root):
    """{room: (floor, allowed rooms or None for any room below)} from docs/layout.md."""
    text = (root / "docs" / "layout.md").read_text()
    section = text.split("## The layer map", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| (\d+) \| `([\w/]+)` \| ([^|]+) \|$", section, re.M)
    if len(rows) < 10:
        sys.exit("check_house_rules: found only %d rows in docs/layout.md's layer map" % len(rows))
    out = {}
    for floor, room, allowed in rows:
        allowed = allowed.strip()
        if allowed == "any room below":
            out[room] = (int(floor), None)
        elif allowed == "nothing of the rig":
            out[room] = (int(floor), set())
        else:
            out[room] = (int(floor), {a.strip() for a in allowed.split(",")})
    return out


def check_map(layers, breaches):
    for room, (floor, allowed) in layers.items():
        for other in allowed or ():
            if other not in layers:
                breaches.append("docs/layout.md: %s may include %s, which is not on the map" % (room, other))
            elif layers[other][0] >= floor:
                breaches.append("docs/layout.md: %s (floor %d) may include %s on floor %d, not below it"
                                % (room, floor, other, layers[other][0]))


def check_include(rel, n, target, layers, breaches):
    room = room_of(rel)
    if target == rel.parts[0] or room not in layers:
        return
    target_room = target
    if target_room not in layers:
        return  # not a room of the rig (a generated or system path)
    floor, allowed = layers[room]
    ok = layers[target_room][0] < floor if allowed is None else target_room in allowed
    if not ok:
        breaches.append("%s:%d: %s/ included from %s/, which the layer map (docs/layout.md) does not allow"
                        % (rel, n, target_room, room))


def channel_names(root):
    text = (root / "contract" / "channels.h").read_text()
    names = re.findall(r'inline const std::string k\w+ = "([A-Z_]+)";', text)
    if len(names) < 10:
        sys.exit("check_house_rules: found only %d channel names in contract/channels.h" % len(names))
    return set(names)


def effect_names(root):
    """{name: its file pair's stem} of every effect of effects/, from its definition (or its name's constant)."""
    out = {}
    for path in sorted((root / "effects").glob("*.[ch]*")):
        text = path.read_text()
        for name in re.findall(r'definition = \{\s*"([a-z_0-9]+)"', text) + re.findall(r'k\w*Name = "([a-z_0-9]+)"', text):
            out[name] = path.stem
    registry = root / "effects" / "registry.cc"
    listed = len(re.findall(r"^\s+\w+_effect\(\),", registry.read_text(), re.M)) if registry.exists() else len(out)
    if len(out) < 10 or len(out) != listed:
        sys.exit("check_house_rules: found %d effect names in effects/, and effects/registry.cc lists %d effects"
                 % (len(out), listed))
    return out


def main():
    root = pathlib.Path(sys.argv[1]).resolve()
    channel_set = channel_names(root)
    effect_set = effect_names(root)
    string_literal = re.compile(r'"([a-z_0-9]+)"')
    literal = re.compile(r'"([A-Z_]+)"')
    rate_call = re.compile(r"set_expected_rate\s*\(([^;]*)\)")
    number = re.compile(r"(?<![\w.])\d+(\.\d*)?([eE][-+]?\d+)?(?![\w.])")
    include = re.compile(r'#include\s+"(cli|launcher)/')
    any_include = re.compile(r'#include\s+"([\w]+)/')
    breaches = []
    checked = 0
    layers = layer_map(root)
    check_map(layers, breaches)
    names = collections.defaultdict(set)
    rooms = set()
    for rel, lines in sources(root):
        checked += 1
        top = rel.parts[0]
        rooms.add(room_of(rel))
        names[rel.name].add(room_of(rel))
        if len(lines) > MAX_LINES:
            breaches.append("%s: %d lines, over %d: split it by job" % (rel, len(lines), MAX_LINES))
        for first, last, header in functions("\n".join(lines)):
            if last - first + 1 > MAX_FUNCTION_LINES:
                breaches.append("%s:%d: %s: %d lines, over %d: split it by job"
                                % (rel, first, header[:60], last - first + 1, MAX_FUNCTION_LINES))
        for n, line in enumerate(lines, 1):
            code = line.split("//", 1)[0]
            if str(rel) != "contract/channels.h":
                for name in literal.findall(code):
                    if name in channel_set:
                        breaches.append('%s:%d: channel "%s" spelled outside contract/channels.h' % (rel, n, name))
            for name in string_literal.findall(code):
                if name in effect_set and not (top == "effects" and rel.stem == effect_set[name]):
                    breaches.append('%s:%d: effect "%s" named outside its file pair effects/%s.{h,cc}: use its '
                                    "properties (effects/effect.h)" % (rel, n, name, effect_set[name]))
            for args in rate_call.findall(code):
                if number.search(args.split(",", 1)[-1]):
                    breaches.append("%s:%d: set_expected_rate with a rate literal: %s" % (rel, n, line.strip()))
            if top in PROCESS_ROOMS and rel.suffix == ".cc" and RATE_FALLBACK.search(code):
                breaches.append("%s:%d: a rate literal in a process (take it from the configuration or "
                                "contract/rates.h): %s" % (rel, n, line.strip()))
            if KEY_WRITER.search(code) and top != "lcmjson":
                breaches.append("%s:%d: JSON written key by key: build an OrderedJson and write it with json_line() "
                                "(core/json_line.h)" % (rel, n))
            if top != "contract" and RATE_DEFAULT.search(code):
                breaches.append("%s:%d: a rate default outside the contract (use contract/rates.h's constant): %s"
                                % (rel, n, line.strip()))
            m_any = any_include.search(code)
            if m_any:
                check_include(rel, n, m_any.group(1), layers, breaches)
            m = include.search(code)
            if m:
                folder = m.group(1)
                allowed = {"cli"} if folder == "cli" else ABOVE_LAUNCHER
                if top not in allowed:
                    breaches.append("%s:%d: %s/ included from %s/, a folder below it" % (rel, n, folder, top))
    for name, where in sorted(names.items()):
        if len(where) > 1:
            breaches.append("%s is a file name in %d rooms (%s): name each for its job"
                            % (name, len(where), ", ".join(sorted(where))))
    for room in sorted(rooms - set(layers)):
        breaches.append("%s/ has sources and is not on the layer map of docs/layout.md" % room)
    for b in breaches:
        print(b)
    print("check_house_rules: %d source files, %d rooms, %d channel names, %d effect names, %d breaches"
          % (checked, len(rooms), len(channel_set), len(effect_set), len(breaches)))
    return 1 if breaches else 0


if __name__ == "__main__":
    sys.exit(main())
