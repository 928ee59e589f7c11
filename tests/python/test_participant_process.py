"""Python participants named by the scenario (section `participants`), flown in every clock: in
lockstep and real time each is a process of its own over LCM (python -m nimble_rig.node, started
and supervised by the launcher), in process by nimble_rig.fly(). Lockstep flies the flight
in-process flies, message for message; an exception ends the run naming the participant, the
exception and the simulated time, the log kept; the scenario names a missing file or class with
its file and line; `rig run --clock inprocess` says that it needs nimble_rig.fly()."""
import json
import os
import subprocess

import numpy as np
import pytest

import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
RIG = os.environ["RIG_BIN"]
HOVER = os.path.join(SOURCE, "rig_configs", "hover.yaml")
EXAMPLES = os.path.join(SOURCE, "docs", "examples")

SCENARIO = """\
base: {hover}
name: hover_python_pd
duration_s: {duration}
clock: lockstep
participants:
  controller:
    python: {python}
    class: {cls}
    arguments: {{roll_sp_rad: 0.05}}
"""

BOOM = """\
import sys
sys.path.insert(0, {examples!r})
from python_pd import PythonPD


class Boom(PythonPD):
    def step(self, t_s, inputs):
        if t_s >= 1.5:
            raise ValueError("the gain table ran out")
        return super().step(t_s, inputs)
"""


def scenario(tmp_path, duration=3, python=os.path.join(EXAMPLES, "python_pd.py"), cls="PythonPD", text=None):
    path = tmp_path / "scenario.yaml"
    path.write_text(text or SCENARIO.format(hover=HOVER, duration=duration, python=python, cls=cls))
    return str(path)


def rig_run(tmp_path, scenario_file, *args):
    log, report = str(tmp_path / "run.lcmlog"), str(tmp_path / "run.json")
    done = subprocess.run([RIG, "run", scenario_file, "--no-progress", "--log", log, "--json", report, *args],
                          capture_output=True, text=True, timeout=120)
    parsed = json.load(open(report)) if os.path.exists(report) else None
    return done, log, parsed


def test_lockstep_flies_the_python_controller_as_its_own_process_the_flight_in_process_flies(tmp_path):
    s = scenario(tmp_path)
    done, log, report = rig_run(tmp_path, s)
    assert done.returncode == 0, done.stdout + done.stderr
    assert report["result"] == "ok"
    controller = report["processes"]["controller"]
    assert controller["exit_code"] == 0
    # It ran as the interpreter with the node module, started by the launcher like the others.
    output = open(log + ".controller.out").read()
    assert "Traceback" not in output
    recorded = nimble_rig.read_log(log)
    assert set(recorded["ACTUATOR_CMD"]["source"]) == {"python_pd"}
    assert "controller" in set(recorded["HEARTBEAT"]["process"])
    # The same flight in process (the section read by nimble_rig.fly), message for message.
    flown = nimble_rig.fly(nimble_rig.load_scenario(s), seed=1)
    assert flown.report["result"] == "ok"
    for field in ("utime", "euler_rad", "omega_body_radps", "velocity_body_mps"):
        np.testing.assert_array_equal(recorded["TRUTH"][field], flown.channels["TRUTH"][field])
    np.testing.assert_array_equal(recorded["ACTUATOR_CMD"]["delta_f_radps"],
                                  flown.channels["ACTUATOR_CMD"]["delta_f_radps"])


def test_an_exception_in_the_python_process_ends_the_run_naming_it_and_the_time_with_the_log_kept(tmp_path):
    boom = tmp_path / "boom.py"
    boom.write_text(BOOM.format(examples=EXAMPLES))
    done, log, report = rig_run(tmp_path, scenario(tmp_path, python=str(boom), cls="Boom"))
    assert done.returncode != 0
    result = report["result"]
    assert result.startswith("failed"), result
    assert "process 'controller'" in result
    assert "controller (Python Boom) raised ValueError: the gain table ran out at simulated t = 1.500000 s" in result
    assert "raised ValueError" in open(log + ".controller.out").read()  # with its traceback
    truth = nimble_rig.read_log(log)["TRUTH"]
    assert 1_490_000 <= truth["utime"][-1] <= 1_500_000  # everything until the lockstep stopped, kept


def test_a_real_time_run_has_the_python_process_heartbeat_and_timing_in_its_summary(tmp_path):
    done, log, report = rig_run(tmp_path, scenario(tmp_path, duration=2), "--clock", "realtime")
    assert done.returncode == 0, done.stdout + done.stderr
    # Judged like the rig's own processes: a loaded machine may make the run real-time degraded.
    assert report["result"] == "ok" or report["result"].startswith("real-time degraded"), report["result"]
    timing = report["timing"]["controller"]
    assert timing["loop_count"] >= 0.9 * 2 * 512  # its task ran at its rate
    assert "overruns" in timing
    # It flew on the TRUTH it subscribed to over LCM: its commands name the TRUTH they answer.
    cmd = nimble_rig.read_log(log)["ACTUATOR_CMD"]
    assert set(cmd["source"]) == {"python_pd"} and (cmd["input_utime"] >= 0).mean() > 0.99
    assert "controller" in done.stdout


@pytest.mark.parametrize("change, key, problem", [
    ({"cls": "NoSuchClass"}, "participants.controller.class", "defines no top-level class NoSuchClass"),
    ({"python": "/nonexistent/ctl.py"}, "participants.controller.python", "/nonexistent/ctl.py"),
    ({"cls": "1abc"}, "participants.controller.class", "is not a Python class name"),
])
def test_the_scenario_names_a_missing_file_or_class_with_its_file_and_line(tmp_path, change, key, problem):
    s = scenario(tmp_path, **change)
    with pytest.raises(nimble_rig.ConfigError) as caught:
        nimble_rig.load_scenario(s)
    e = caught.value
    assert e.file == s and e.key == key and problem in str(e)
    line = {"participants.controller.class": 8, "participants.controller.python": 7}[key]
    assert e.line == line, str(e)


def test_a_participant_in_place_of_the_plant_or_a_process_not_run_is_refused(tmp_path):
    text = SCENARIO.format(hover=HOVER, duration=2, python=os.path.join(EXAMPLES, "python_pd.py"), cls="PythonPD")
    with pytest.raises(nimble_rig.ConfigError, match="replaces the controller, mocap or estimator"):
        nimble_rig.load_scenario(scenario(tmp_path, text=text.replace("  controller:", "  plant:")))
    with pytest.raises(nimble_rig.ConfigError, match="not one of the run's processes"):
        nimble_rig.load_scenario(scenario(tmp_path, text=text + "processes: [plant, mocap, estimator]\n"))


def test_rig_run_in_process_says_a_python_participant_needs_nimble_rig_fly(tmp_path):
    done, log, _ = rig_run(tmp_path, scenario(tmp_path), "--clock", "inprocess")
    assert done.returncode == 2, done.stderr
    assert "participants.controller" in done.stderr and "nimble_rig.fly(scenario)" in done.stderr
    assert "the rig tool embeds no Python" in done.stderr


def test_a_class_that_fails_to_start_ends_the_run_before_it_starts_naming_it(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("class Bad:\n    def __init__(self, roll_sp_rad):\n        raise RuntimeError('no gains')\n")
    done, log, report = rig_run(tmp_path, scenario(tmp_path, python=str(bad), cls="Bad"))
    assert done.returncode != 0
    assert "process 'controller' exited with code 2 before it was ready" in done.stderr
    assert "RuntimeError: no gains" in done.stderr
