"""A Python LQR designed on the identified model, flown against the rig's C++ PD (docs/python.md,
"Python in the loop"):

  1. flies the identification train (rig_configs/id_doublet_train_fast.yaml) with the rig's
     controller and identifies the lateral model from that flight (nimble_rig.identify(flight));
  2. designs the LQR of python_lqr.py on it (scipy);
  3. flies the 10 deg roll step three times: the rig's C++ PD (rig_configs/roll_step_fast.yaml),
     the Python LQR in process (nimble_rig.fly), and the Python LQR in lockstep as a process of its
     own over LCM (`rig run docs/examples/python_lqr.yaml`);
  4. draws the three flights' roll in one figure, and says whether the two clocks flew the LQR's
     flight alike, message for message.

    /usr/bin/python3 docs/examples/lqr_vs_pd.py --out "${TMPDIR:-/tmp}"

With the build tree's module (build/python) when nimble_rig is not installed. Writes into --out:
identified.yaml, the lockstep run's log and lqr_vs_pd.png (docs/examples/lqr_vs_pd.png is one).
Exit code 1 if a flight is not controlled or the two clocks differ.
"""
import argparse
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
if not any(os.path.isdir(os.path.join(p, "nimble_rig")) for p in sys.path if p):
    sys.path.insert(0, os.path.join(ROOT, "build", "python"))
sys.path.insert(0, HERE)

import nimble_rig  # noqa: E402
from python_lqr import PythonLQR  # noqa: E402


def rig_tool():
    """$RIG_BIN, else the rig tool of the build tree, else the installed one."""
    built = os.path.join(ROOT, "build", "bin", "rig")
    return os.environ.get("RIG_BIN") or (built if os.path.exists(built) else "rig")


def roll_deg(channels):
    truth = channels["TRUTH"]
    return truth["utime"] * 1e-6, np.degrees(truth["euler_rad"][:, 0])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder for the identified model, the log and the figure")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    # 1. The identification flight and the model identified from it.
    train = nimble_rig.load_scenario(os.path.join(ROOT, "rig_configs", "id_doublet_train_fast.yaml"))
    train_flight = nimble_rig.fly(train, seed=args.seed, log=os.path.join(args.out, "id_train.lcmlog"))
    model = os.path.join(args.out, "identified.yaml")
    ident = nimble_rig.identify(train_flight, model_out=model)
    print("identified from the train: eigenvalues", np.round(ident["eigenvalues"], 2), "1/s")

    # 2. The design on it.
    lqr = PythonLQR(model=model)
    print("LQR gain K on [p v phi]:", np.round(lqr.k, 3), " closed-loop poles:", np.round(lqr.closed_loop_poles, 2))

    # 3. Three flights of the roll step.
    pd = nimble_rig.fly(nimble_rig.load_scenario(os.path.join(ROOT, "rig_configs", "roll_step_fast.yaml")),
                        seed=args.seed)
    example = os.path.join(HERE, "python_lqr.yaml")
    override = {"participants.controller.arguments.model": model}
    start = time.monotonic()
    inproc = nimble_rig.fly(nimble_rig.load_scenario(example, overrides=override), seed=args.seed)
    inproc_wall = time.monotonic() - start
    log = os.path.join(args.out, "python_lqr_lockstep.lcmlog")
    cmd = [rig_tool(), "run", example, "--clock", "lockstep", "--seed", str(args.seed), "--log", log,
           "--set", "participants.controller.arguments.model=" + model]
    start = time.monotonic()
    run = subprocess.run(cmd, capture_output=True, text=True)
    lockstep_wall = time.monotonic() - start
    print(run.stdout, end="")
    lockstep = nimble_rig.read_log(log)

    results = {"C++ PD": pd.report["result"], "Python LQR in process": inproc.report["result"],
               "Python LQR in lockstep": "exit code %d" % run.returncode}
    for name, result in results.items():
        print("%-24s %s" % (name, result))
    duration = inproc.report.get("sim_time_s", 9.0)
    print("Python LQR: in process %.2f s of wall time (%.0fx real time), lockstep %.2f s with its start (%.1fx)"
          % (inproc_wall, duration / inproc_wall, lockstep_wall, duration / lockstep_wall))

    # The two clocks, message for message.
    a, b = inproc.channels["TRUTH"], lockstep["TRUTH"]
    same = len(a["utime"]) == len(b["utime"]) and all(np.array_equal(a[k], b[k]) for k in a)
    print("TRUTH in process and in lockstep:", "identical (%d messages)" % len(a["utime"]) if same else "DIFFERENT")

    # 4. One figure.
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4))
    t = np.arange(0.0, duration, 0.01)
    ax.plot(t, [np.degrees(lqr.roll_sp_rad(x)) for x in t], "k:", label="roll set-point")
    ax.plot(*roll_deg(pd.channels), label="C++ PD (rig controller, fast gains)")
    ax.plot(*roll_deg(inproc.channels), label="Python LQR, in process")
    ax.plot(*roll_deg(lockstep), "--", label="Python LQR, lockstep (own process over LCM)")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("roll phi [deg] (TRUTH)")
    ax.set_title("10 deg roll step, seed %d: LQR designed on the model identified from a flight" % args.seed)
    ax.grid(True)
    ax.legend(loc="upper right", fontsize=8)
    figure = os.path.join(args.out, "lqr_vs_pd.png")
    fig.tight_layout()
    fig.savefig(figure, dpi=100)
    print("figure:", figure)

    controlled = all(r.startswith("ok") or r.startswith("controlled") for r in
                     (pd.report["result"], inproc.report["result"])) and run.returncode == 0
    return 0 if controlled and same else 1


if __name__ == "__main__":
    sys.exit(main())
