#!/usr/bin/env python3
"""Runs the rig's libFuzzer targets (fuzz/) and prints, per target, executions, time, crashes and
exit status as a table. Exits non-zero if any target crashed or ended with a non-zero status.

Each target runs on a fresh working corpus (a copy of its seeds in fuzz/corpus/<target>/, so
the repository's seeds are never written to) under BUILD/fuzz/run/<target>/, with its log
(log.txt) and any crashing input (artifacts/) there.

Usage: fuzz.py [--build-dir DIR] [--time SECONDS] [--runs N] [--jobs J] [TARGET...]
  --time  time budget of each target [s] (default 60; 0: none, with --runs)
  --runs  stop each target after N executions (default: none)
  --jobs  targets run at a time (default: the number of CPUs)
Called by scripts/fuzz.sh, which builds the targets first.
"""
import argparse
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run_target(build, name, seconds, runs):
    work = os.path.join(build, "fuzz", "run", name)
    shutil.rmtree(work, ignore_errors=True)
    corpus = os.path.join(work, "corpus")
    artifacts = os.path.join(work, "artifacts")
    os.makedirs(artifacts)
    seeds = os.path.join(ROOT, "fuzz", "corpus", name)
    shutil.copytree(seeds, corpus) if os.path.isdir(seeds) else os.makedirs(corpus)
    cmd = [os.path.join(build, "bin", name), f"-max_total_time={seconds}", "-timeout=10",
           "-rss_limit_mb=2048", "-print_final_stats=1", f"-artifact_prefix={artifacts}/"]
    if runs:
        cmd.append(f"-runs={runs}")
    cmd.append(corpus)
    env = dict(os.environ)
    # Shorter allocation stacks in ASan reports (the crash's own stack stays whole): the
    # allocation-heavy targets (YAML, logs) spend less time unwinding at every malloc.
    env.setdefault("ASAN_OPTIONS", "malloc_context_size=5")
    log_path = os.path.join(work, "log.txt")
    start = time.monotonic()
    with open(log_path, "w") as log:
        status = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, check=False).returncode
    elapsed = time.monotonic() - start
    with open(log_path, errors="replace") as log:
        text = log.read()
    m = re.findall(r"stat::number_of_executed_units:\s*(\d+)", text)
    if not m:
        m = re.findall(r"^#(\d+)\s", text, re.MULTILINE)
    executions = int(m[-1]) if m else 0
    crashes = sorted(os.listdir(artifacts))
    return {"name": name, "executions": executions, "seconds": elapsed, "crashes": crashes,
            "status": status, "log": log_path}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build-dir", default=os.path.join(ROOT, "build-san"))
    parser.add_argument("--time", type=int, default=60)
    parser.add_argument("--runs", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("targets", nargs="*")
    args = parser.parse_args()
    build = os.path.abspath(args.build_dir)
    listed = os.path.join(build, "fuzz", "targets.txt")
    if not os.path.exists(listed):
        print(f"fuzz: {listed} not found: configure {build} with -DRIG_FUZZ=ON (scripts/fuzz.sh does)",
              file=sys.stderr)
        return 2
    with open(listed) as f:
        known = [line.strip() for line in f if line.strip()]
    targets = args.targets or known
    unknown = [t for t in targets if t not in known]
    if unknown:
        print(f"fuzz: unknown target(s) {' '.join(unknown)}; known: {' '.join(known)}", file=sys.stderr)
        return 2
    if args.time <= 0 and args.runs <= 0:
        print("fuzz: give a time budget (--time) or a number of executions (--runs)", file=sys.stderr)
        return 2
    budget = f"{args.time} s" if args.time > 0 else "no time limit"
    print(f"fuzz: {len(targets)} targets, {budget} each" + (f", at most {args.runs} executions" if args.runs else "")
          + f", {args.jobs} at a time", flush=True)
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        results = list(pool.map(lambda t: run_target(build, t, max(args.time, 0), args.runs), targets))

    header = f"{'target':<24} {'executions':>12} {'time [s]':>9} {'exec/s':>8} {'crashes':>8} {'exit':>5}"
    print(header)
    print("-" * len(header))
    failed = False
    for r in results:
        rate = r["executions"] / r["seconds"] if r["seconds"] > 0 else 0
        print(f"{r['name']:<24} {r['executions']:>12} {r['seconds']:>9.0f} {rate:>8.0f} {len(r['crashes']):>8} "
              f"{r['status']:>5}")
        failed = failed or r["crashes"] or r["status"] != 0
    for r in results:
        if r["crashes"] or r["status"] != 0:
            print(f"\n{r['name']}: exit status {r['status']}; log {r['log']}")
            for c in r["crashes"]:
                print(f"  input: {os.path.join(os.path.dirname(r['log']), 'artifacts', c)}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
