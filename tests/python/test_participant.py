"""Participants written in Python in the rig's loop (nimble_rig.fly(participants=),
python/py_participant.cc, nimble_rig/participant.py): the example PD in place of the attitude
controller holds hover, the same every time; what it raises ends the flight naming it, the log
kept; a participant the contract does not allow is refused before anything flies."""
import os
import sys

import numpy as np
import pytest

import nimble
import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
HOVER = os.path.join(SOURCE, "rig_configs", "hover.yaml")
sys.path.insert(0, os.path.join(SOURCE, "docs", "examples"))
from python_pd import PythonPD  # noqa: E402


@pytest.fixture(scope="module")
def hover():
    return nimble_rig.load_scenario(HOVER, {"duration_s": 4})


def test_a_python_pd_in_place_of_the_controller_holds_hover_the_same_every_time(hover, tmp_path):
    log = str(tmp_path / "pd.lcmlog")
    flight = nimble_rig.fly(hover, seed=1, log=log, participants={"controller": PythonPD(roll_sp_rad=0.05)})
    assert flight.report["result"] == "ok", flight.report["result"]
    assert flight.report["processes"]["controller"]["exit_code"] == 0
    # Its commands are the ones the plant flew: every ACTUATOR_CMD from it, one per 1/512 s.
    cmd = flight.channels["ACTUATOR_CMD"]
    assert set(cmd["source"]) == {"python_pd"}
    np.testing.assert_array_equal(cmd["seq"], np.arange(len(cmd["seq"])))
    assert cmd["utime"][0] == 0 and set(np.diff(cmd["utime"])) <= {1953, 1954}  # its steps' times [us]
    assert len(cmd["seq"]) == pytest.approx(4 * 512, abs=2)
    # It holds the roll it was given, steady: 0.05 rad less the steady error a PD without integral
    # action leaves against the side velocity's roll moment (0.044 rad).
    phi = flight.channels["TRUTH"]["euler_rad"][:, 0]
    assert abs(phi[-1] - 0.05) < 0.01
    assert np.ptp(phi[-500:]) < 1e-5
    # Its heartbeat is the controller's: the process is there, as the rig's own would be.
    log_read = nimble_rig.read_log(log)
    assert "controller" in set(log_read["HEARTBEAT"]["process"])
    again = nimble_rig.fly(hover, seed=1, participants={"controller": PythonPD(roll_sp_rad=0.05)})
    np.testing.assert_array_equal(again.channels["TRUTH"]["euler_rad"], flight.channels["TRUTH"]["euler_rad"])


def test_an_exception_in_step_ends_the_flight_naming_it_and_the_time_and_keeps_the_log(hover, tmp_path):
    class Boom(PythonPD):
        def step(self, t_s, inputs):
            if t_s >= 1.5:
                raise ValueError("the gain table ran out")
            return super().step(t_s, inputs)

    log = str(tmp_path / "boom.lcmlog")
    flight = nimble_rig.fly(hover, seed=1, log=log, participants={"controller": Boom()})
    result = flight.report["result"]
    assert result.startswith("failed")
    assert "controller (Python Boom) raised ValueError: the gain table ran out" in result
    assert "t = 1.500000 s" in result
    assert flight.report["exit_code"] != 0
    truth = nimble_rig.read_log(log)["TRUTH"]
    assert truth["utime"][-1] == 1_500_000  # everything until then, kept

    class Wrong(PythonPD):
        def step(self, t_s, inputs):
            return {"ACTUATOR_CMD": nimble.truth_state_t()}

    wrong = nimble_rig.fly(hover, participants={"controller": Wrong()}).report["result"]
    assert "step() returned a truth_state_t on ACTUATOR_CMD, whose messages are nimble.actuator_command_t" in wrong


@pytest.mark.parametrize("process, change, message", [
    ("controller", {"inputs": "TRUTH"}, "inputs must be a list of channel names"),
    ("controller", {"inputs": ("NOPE",)}, "inputs NOPE: no such channel"),
    ("controller", {"outputs": ("TRUTH",)}, "outputs TRUTH: the contract does not let controller publish them"),
    ("controller", {"rate_hz": 0}, "rate_hz must be a number in (0, 1e5] Hz"),
    ("controller", {"step": None}, "has no step(t_s, inputs)"),
    ("plant", {}, "the contract does not let plant publish them"),
])
def test_a_participant_the_contract_does_not_allow_is_refused_naming_the_process(hover, process, change, message):
    p = PythonPD()
    for key, value in change.items():
        setattr(p, key, value)
    with pytest.raises((TypeError, ValueError)) as caught:
        nimble_rig.fly(hover, participants={process: p})
    assert "participant in place of " + process in str(caught.value)
    assert message in str(caught.value)


def test_a_participant_in_place_of_a_process_the_scenario_does_not_run_is_refused(hover):
    class Nothing(nimble_rig.Participant):
        inputs, outputs, rate_hz = (), (), 100.0

        def step(self, t_s, inputs):
            return None

    with pytest.raises(nimble_rig.ConfigError, match="a participant in place of a process the scenario does not run"):
        nimble_rig.fly(hover, participants={"can_flight": Nothing()})


def test_the_scenarios_faults_apply_to_a_participants_outputs_as_to_the_process_it_replaces():
    faulted = nimble_rig.load_scenario(HOVER, {"duration_s": 3, "faults": [
        {"target": "ACTUATOR_CMD", "kind": "off", "start_s": 1.0, "duration_s": 0.5}]})
    flight = nimble_rig.fly(faulted, seed=1, participants={"controller": PythonPD()})
    t = flight.channels["ACTUATOR_CMD"]["utime"] * 1e-6
    assert ((t >= 1.0) & (t < 1.5)).sum() == 0 and (t >= 1.5).sum() > 700  # none while off, all after
    announced = [f for f in flight.report["faults"] if f["channel"] == "ACTUATOR_CMD"]
    assert announced[0]["process"] == "controller" and "ACTUATOR_CMD off" in announced[0]["message"]
    assert any(f["process"] == "plant" and "no actuator command" in f["message"] for f in announced)
