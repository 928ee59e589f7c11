#!/usr/bin/env python3
"""bench_python: a flight from Python against the same flight by `rig run --clock inprocess`.

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [--rig build/bin/rig] [--runs N]
        [--scenario F] [--duration S] [--json F]

Flies the scenario (default rig_configs/id_doublet_train_fast.yaml for 30 s of simulated time,
seed 1, its LCM log written, as `rig run` writes one), N times each way (default 7), alternating,
in one run on one machine, and prints the medians of:
 - the flight alone: each run's own report (wall_time_s: from the first to the last step, the
   log written), from nimble_rig.fly() and from `rig run --clock inprocess`;
 - what the user waits for, against `rig run`'s process from start to exit (its own loading, no
   arrays): fly() of a scenario loaded once (planned at its first flight, flown again with the
   same seed), and load_scenario() + fly() of a fresh one; every channel handed over as arrays;
 - the ratio Python / rig of each. The target: the flight from Python within 5 % of rig run's
   (ratio <= 1.05), as bench_inprocess measures a flight. Both sides run on this machine in this
   run, so the ratios travel;
 - the same flight with a controller written in Python in the loop (docs/examples/python_pd.py,
   nimble_rig.fly(participants=), each step called with the GIL taken) against the rig's C++
   controller: each flight's wall time and speed [x real time]. The target: >= 30x;
 - the same in lockstep (`rig run --clock lockstep`, --lockstep-runs times, default 3): the Python
   controller as a process of its own over LCM (the scenario's `participants` section, python -m
   nimble_rig.node) against the rig's C++ controller process, each run's wall time and speed.
Not a test: figures depend on the machine and on what else runs on it.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import nimble_rig


def main():
    source = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rig", default=os.path.join(source, "build", "bin", "rig"))
    ap.add_argument("--scenario", default=os.path.join(source, "rig_configs", "id_doublet_train_fast.yaml"))
    ap.add_argument("--duration", type=float, default=30.0, help="simulated seconds [s]")
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--lockstep-runs", type=int, default=3)
    ap.add_argument("--json", help="write the figures here")
    a = ap.parse_args()
    if a.runs < 1 or a.duration <= 0:
        ap.error("--runs must be >= 1 and --duration > 0")

    sys.path.insert(0, os.path.join(source, "docs", "examples"))
    from python_pd import PythonPD

    py_flight, py_call, py_total, rig_flight, rig_total, pd_flight = [], [], [], [], [], []
    loaded = nimble_rig.load_scenario(a.scenario, {"duration_s": a.duration})
    with tempfile.TemporaryDirectory() as tmp:
        log_py, log_rig, report = (os.path.join(tmp, n) for n in ("py.lcmlog", "rig.lcmlog", "rig.json"))
        command = [a.rig, "run", a.scenario, "--clock", "inprocess", "--seed", "1", "--set",
                   "duration_s=%g" % a.duration, "--no-progress", "--log", log_rig, "--json", report]
        for _ in range(a.runs):
            start = time.perf_counter()
            flight = nimble_rig.fly(nimble_rig.load_scenario(a.scenario, {"duration_s": a.duration}), seed=1, log=log_py)
            py_total.append(time.perf_counter() - start)
            py_flight.append(flight.report["wall_time_s"])
            if flight.report["result"] != "ok":
                sys.exit("bench_python: the flight from Python ended " + flight.report["result"])
            start = time.perf_counter()
            nimble_rig.fly(loaded, seed=1, log=log_py)
            py_call.append(time.perf_counter() - start)
            start = time.perf_counter()
            done = subprocess.run(command, capture_output=True, text=True)
            rig_total.append(time.perf_counter() - start)
            if done.returncode != 0:
                sys.exit("bench_python: rig run failed: " + done.stderr)
            with open(report) as f:
                rig_flight.append(json.load(f)["wall_time_s"])
            pd = nimble_rig.fly(loaded, seed=1, log=log_py, participants={"controller": PythonPD()})
            if pd.report["result"] != "ok":
                sys.exit("bench_python: the flight with the Python controller ended " + pd.report["result"])
            pd_flight.append(pd.report["wall_time_s"])
        # Lockstep: every process its own, over LCM in the run's private network namespace.
        pd_file = os.path.join(source, "docs", "examples", "python_pd.py")
        section = "participants={controller: {python: %s, class: PythonPD}}" % pd_file
        lockstep = {"python": [], "cpp": []}
        for _ in range(a.lockstep_runs):
            for who, extra in (("cpp", []), ("python", ["--set", section])):
                cmd = [a.rig, "run", a.scenario, "--clock", "lockstep", "--seed", "1", "--set",
                       "duration_s=%g" % a.duration, "--no-progress", "--log", log_rig, "--json", report] + extra
                done = subprocess.run(cmd, capture_output=True, text=True)
                if done.returncode != 0:
                    sys.exit("bench_python: rig run --clock lockstep (%s controller) failed: %s" % (who, done.stderr))
                with open(report) as f:
                    lockstep[who].append(json.load(f)["wall_time_s"])

    med = statistics.median
    figures = {
        "scenario": a.scenario, "sim_time_s": a.duration, "runs": a.runs,
        "flight_s": {"python": med(py_flight), "rig_run": med(rig_flight), "ratio": med(py_flight) / med(rig_flight)},
        "call_s": {"python": med(py_call), "rig_run": med(rig_total), "ratio": med(py_call) / med(rig_total)},
        "total_s": {"python": med(py_total), "rig_run": med(rig_total), "ratio": med(py_total) / med(rig_total)},
    }
    figures["within_5_percent"] = figures["flight_s"]["ratio"] <= 1.05
    figures["python_controller"] = {"flight_s": med(pd_flight), "speed_x": a.duration / med(pd_flight),
                                    "cpp_flight_s": med(py_flight), "cpp_speed_x": a.duration / med(py_flight)}
    figures["python_controller"]["at_least_30x"] = figures["python_controller"]["speed_x"] >= 30.0
    if a.lockstep_runs > 0:
        figures["lockstep"] = {"python_flight_s": med(lockstep["python"]), "cpp_flight_s": med(lockstep["cpp"]),
                               "python_speed_x": a.duration / med(lockstep["python"]),
                               "cpp_speed_x": a.duration / med(lockstep["cpp"]), "runs": a.lockstep_runs}
    print("bench_python: %s, %g s simulated, seed 1, log written, medians of %d runs each (alternating)"
          % (os.path.basename(a.scenario), a.duration, a.runs))
    for key, what in (("flight_s", "the flight (its report's wall time)"),
                      ("call_s", "fly() + arrays, loaded / rig run's process"),
                      ("total_s", "load + fly + arrays / rig run's process")):
        f = figures[key]
        print("  %-42s python %7.3f s (%5.0fx)  rig run %7.3f s (%5.0fx)  ratio %.3f"
              % (what, f["python"], a.duration / f["python"], f["rig_run"], a.duration / f["rig_run"], f["ratio"]))
    print("  the flight within 5 %% of rig run's: %s" % ("yes" if figures["within_5_percent"] else "NO"))
    pc = figures["python_controller"]
    print("  the flight with the controller in Python: %.3f s (%.0fx real time; the C++ controller's %.3f s, %.0fx); "
          ">= 30x: %s" % (pc["flight_s"], pc["speed_x"], pc["cpp_flight_s"], pc["cpp_speed_x"],
                          "yes" if pc["at_least_30x"] else "NO"))
    if a.lockstep_runs > 0:
        ls = figures["lockstep"]
        print("  lockstep, every process its own over LCM (medians of %d): the Python controller's process %.3f s "
              "(%.0fx), the C++ controller's %.3f s (%.0fx)" % (ls["runs"], ls["python_flight_s"], ls["python_speed_x"],
                                                             ls["cpp_flight_s"], ls["cpp_speed_x"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(figures, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
