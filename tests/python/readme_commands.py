#!/usr/bin/env python3
"""python.readme: the README's Python commands run exactly as it prints them.

Takes the first ```sh block of the README's "From Python" section and runs each of its lines with
bash in the source tree's root, as a user pastes them, with nothing of the test's environment added
but TMPDIR (the outputs go to "${TMPDIR:-/tmp}"). Each must exit 0; the first must print the
flight's result and the TRUTH attitude's shape; the notebook's executed copy must hold its figures;
the Python controller's example must fly the same flight in process and in lockstep and draw its
figure. Nothing under docs/ may change: each writes its figures only where it is told.

Usage: readme_commands.py <source dir> <build dir> <scratch dir>. The README's PYTHONPATH is the
source tree's build/: run from another build directory, this says so and fails.
"""
import hashlib
import json
import os
import pathlib
import re
import subprocess
import sys


def commands(readme):
    text = readme.read_text()
    section = text.split("\n## From Python\n", 1)
    if len(section) != 2:
        sys.exit("readme_commands: README.md has no '## From Python' section")
    block = re.search(r"```sh\n(.*?)```", section[1].split("\n## ", 1)[0], re.S)
    if not block:
        sys.exit("readme_commands: the 'From Python' section has no ```sh block")
    lines = [line for line in block.group(1).splitlines() if line.strip() and not line.startswith("#")]
    if len(lines) < 3:
        sys.exit("readme_commands: expected the flight, the notebook and the Python controller's commands, "
                 "found %d lines" % len(lines))
    return lines


def snapshot(folder):
    """Every file under `folder`: its content's digest and its modification time (a file written
    again with the same bytes is written all the same)."""
    return {str(p.relative_to(folder)): (hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file()}


def main():
    source, build, scratch = (pathlib.Path(a).resolve() for a in sys.argv[1:4])
    if build != source / "build":
        sys.exit("readme_commands: the README's commands use build/python of the source tree; this build is %s, "
                 "so they would run another build's module (run the tests from %s/build, as scripts/test.sh does)"
                 % (build, source))
    lines = commands(source / "README.md")
    before = snapshot(source / "docs")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "RIG_SOURCE_DIR", "RIG_NOTEBOOK_FIGURES")}
    env["TMPDIR"] = str(scratch)
    scratch.mkdir(parents=True, exist_ok=True)
    outputs = []
    for line in lines:
        done = subprocess.run(["bash", "-c", line], cwd=source, env=env, capture_output=True, text=True, timeout=280)
        if done.returncode != 0:
            print(done.stdout[-3000:], done.stderr[-3000:])
            sys.exit("readme_commands: exit %d from the README's line: %s" % (done.returncode, line))
        outputs.append(done.stdout)
    if not re.match(r"ok \(\d+, 3\)\s*$", outputs[0]):
        sys.exit("readme_commands: the flight printed %r, not 'ok (N, 3)'" % outputs[0])
    executed = scratch / "rig_from_python.ipynb"
    if not executed.is_file():
        sys.exit("readme_commands: the notebook's executed copy is not in TMPDIR (%s)" % executed)
    figures = sum("image/png" in out.get("data", {})
                  for cell in json.loads(executed.read_text())["cells"] for out in cell.get("outputs", []))
    if figures < 3:
        sys.exit("readme_commands: the executed notebook shows %d figures, not 3" % figures)
    # The Python LQR against the C++ PD (docs/examples/lqr_vs_pd.py): every flight controlled (its exit
    # code), the two clocks' TRUTH identical, the figure where it was told.
    if "TRUTH in process and in lockstep: identical" not in outputs[2]:
        sys.exit("readme_commands: the Python controller's example printed no identical flights:\n" + outputs[2][-2000:])
    if not (scratch / "lqr_vs_pd.png").is_file():
        sys.exit("readme_commands: the Python controller's figure is not in TMPDIR (%s)" % scratch)
    after = snapshot(source / "docs")
    changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
    if changed:
        sys.exit("readme_commands: the README's commands changed docs/: %s" % ", ".join(changed))
    print("readme_commands: %d lines ran as the README prints them; the flight printed %s; the notebook showed "
          "%d figures and left docs/ as it was" % (len(lines), outputs[0].strip(), figures))


if __name__ == "__main__":
    main()
