#!/usr/bin/env python3
"""The house rules' checker catches what it is for: a small tree that breaks each rule once,
and the same tree mended, which it passes. Usage: test_house_rules.py (no arguments)."""
import pathlib
import subprocess
import sys
import tempfile

CHECKER = pathlib.Path(__file__).resolve().parent / "check_house_rules.py"

ROOMS = ["core", "effects", "contract", "scenario", "transport", "plant", "ident", "launcher", "reproduce", "cli", "bench"]
MAP = """# Layout

## The layer map

| floor | room | may include |
|---|---|---|
| 1 | `core` | nothing of the rig |
| 2 | `contract` | core |
| 2 | `effects` | core |
| 3 | `scenario` | contract, core |
| 4 | `transport` | contract, core, scenario |
| 5 | `plant` | contract, core, scenario, transport |
| 6 | `ident` | core |
| 6 | `launcher` | plant, transport |
| 7 | `reproduce` | ident, launcher |
| 8 | `cli` | any room below |
| 8 | `bench` | any room below |

## Conventions
"""
CHANNELS = "\n".join('inline const std::string k%d = "CH_%s";' % (i, chr(65 + i)) for i in range(12))


def write(root, rel, text):
    path = root / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def tree(root, broken):
    write(root, "docs/layout.md", MAP)
    write(root, "contract/channels.h", CHANNELS + "\n")
    for room in ROOMS:
        write(root, "%s/%s_part.cc" % (room, room), "int %s_part() { return 1; }\n" % room)
    for i in range(10):  # ten effects, each named in its own file pair
        write(root, "effects/effect_%d.cc" % i, 'Effect effect_%d() {\n  e.definition = {"effect_%d", "x"};\n}\n' % (i, i))
    long_body = "".join("  x += %d;\n" % i for i in range(130 if broken else 100))
    write(root, "ident/fit.cc", '#include "core/x.h"\nint fit() {\n  int x = 0;\n' + long_body + "  return x;\n}\n")
    write(root, "plant/node.cc", '#include "transport/bus.h"\ndouble rate_hz(bool set) { return set ? 100.0 : %s; }\n'
          % ("512.0" if broken else "kDefaultRateHz"))
    write(root, "ident/grid.h", "struct G {\n  double rate_hz = %s;\n  double cutoff_hz = 9.0;\n};\n"
          % ("512.0" if broken else "kDefaultImuRateHz"))  # a rate default
    if broken:
        write(root, "ident/uses_plant.cc", '#include "plant/model.h"\n')     # not on ident's row
        write(root, "scenario/up.cc", '#include "transport/bus.h"\n')        # not on scenario's row
        write(root, "launcher/fit.cc", "int g() { return 2; }\n")            # fit.cc in ident/ too
        write(root, "mcap/writer.cc", "int w() { return 3; }\n")             # a room not on the map
        write(root, "core/names.cc", 'const char* c = "CH_C";\n')           # a channel name
        write(root, "plant/long.cc", "\n" * 700)                             # a file over 650 lines
        write(root, "ident/pick.cc", 'bool f(const S& s) { return s == "effect_3"; }\n')  # an effect by name
        write(root, "ident/report.cc", 'void r(W& w) { w.key("a").value(1); }\n')  # JSON key by key


def run(broken):
    with tempfile.TemporaryDirectory() as d:
        root = pathlib.Path(d)
        tree(root, broken)
        done = subprocess.run([sys.executable, str(CHECKER), str(root)], capture_output=True, text=True)
        return done.returncode, done.stdout


def main():
    code, out = run(broken=False)
    if code != 0:
        print(out)
        sys.exit("the mended tree failed the house rules")
    code, out = run(broken=True)
    expected = [
        "ident/fit.cc:2: int fit(): 134 lines, over 120",
        "ident/uses_plant.cc:1: plant/ included from ident/",
        "scenario/up.cc:1: transport/ included from scenario/",
        "fit.cc is a file name in 2 rooms (ident, launcher)",
        "mcap/ has sources and is not on the layer map",
        'core/names.cc:1: channel "CH_C" spelled outside contract/channels.h',
        "plant/node.cc:2: a rate literal in a process",
        "plant/long.cc: 700 lines, over 650",
        'ident/pick.cc:1: effect "effect_3" named outside its file pair effects/effect_3.{h,cc}',
        "ident/report.cc:1: JSON written key by key",
        "ident/grid.h:2: a rate default outside the contract",
    ]
    missing = [e for e in expected if e not in out]
    if code != 1 or missing:
        print(out)
        sys.exit("the checker missed: %s (exit %d)" % (missing, code))
    print("test_house_rules: every rule caught its breach (%d), the mended tree passed" % len(expected))


if __name__ == "__main__":
    main()
