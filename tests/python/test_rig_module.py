"""nimble_rig's compiled module (python/rig_module.cc) on real flights: the same truth as
`rig run --clock inprocess`, the arrays read_log gives, scenario errors with file and line, and
SIGINT ending a flight as it ends `rig run`. Run by ctest (tests/CMakeLists.txt, python.module)
with PYTHONPATH at the build tree's python/ and RIG_BIN, RIG_SOURCE_DIR set."""
import fcntl
import json
import os
import signal
import struct
import subprocess
import threading

import numpy as np
import pytest

import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
RIG = os.environ["RIG_BIN"]
TRAIN = os.path.join(SOURCE, "rig_configs", "id_doublet_train_fast.yaml")
HOVER = os.path.join(SOURCE, "rig_configs", "hover.yaml")


def truth_messages(path):
    """Every TRUTH message of an LCM log, as bytes, in log order."""
    data = open(path, "rb").read()
    out, i = [], 0
    while i + 28 <= len(data):
        _, _, _, clen, dlen = struct.unpack(">IqqII", data[i:i + 28])
        channel = data[i + 28:i + 28 + clen].decode()
        if channel == "TRUTH":
            out.append(data[i + 28 + clen:i + 28 + clen + dlen])
        i += 28 + clen + dlen
    return out


def test_a_flight_from_python_has_the_truth_of_rig_run_and_read_logs_arrays(tmp_path):
    scenario = nimble_rig.load_scenario(TRAIN)
    assert scenario.name and scenario.duration_s > 0
    flight = nimble_rig.fly(scenario, seed=1, log=str(tmp_path / "py.lcmlog"))
    done = subprocess.run([RIG, "run", TRAIN, "--clock", "inprocess", "--seed", "1", "--no-progress",
                           "--log", str(tmp_path / "cli.lcmlog"), "--json", str(tmp_path / "cli.json")],
                          capture_output=True, text=True)
    assert done.returncode in (0, 1), done.stderr
    ours, theirs = truth_messages(tmp_path / "py.lcmlog"), truth_messages(tmp_path / "cli.lcmlog")
    assert len(ours) > 1000
    assert ours == theirs
    cli = json.load(open(tmp_path / "cli.json"))
    assert flight.report["result"] == cli["result"]
    assert flight.report["exit_code"] == cli["exit_code"]
    assert set(flight.report) == set(cli)
    # Every channel of the flight, laid out as read_log lays out the same log.
    log = nimble_rig.read_log(str(tmp_path / "py.lcmlog"))
    assert set(flight.channels) == set(log.channels())
    for channel in ("TRUTH", "IMU", "ESTIMATE", "ACTUATOR_CMD"):
        for field, values in flight.channels[channel].items():
            if values.dtype != object:
                np.testing.assert_array_equal(values, log[channel][field], err_msg=channel + "." + field)
    assert flight.channels["TRUTH"]["euler_rad"].shape == (len(ours), 3)
    # A channel as a pandas DataFrame: indexed by t_s [s], a column per field or element, the
    # flight's and the log's the same.
    frame = flight.frame("TRUTH")
    assert frame.index.name == "t_s" and len(frame) == len(ours)
    np.testing.assert_array_equal(frame.index.to_numpy(), flight.channels["TRUTH"]["utime"] * 1e-6)
    np.testing.assert_array_equal(frame["euler_rad[0]"].to_numpy(), flight.channels["TRUTH"]["euler_rad"][:, 0])
    assert "euler_rad[2]" in frame and "euler_rad" not in frame
    logged = log.frame("TRUTH")
    assert set(frame.columns) <= set(logged.columns)
    np.testing.assert_array_equal(logged["euler_rad[1]"].to_numpy(), frame["euler_rad[1]"].to_numpy())
    with pytest.raises(KeyError, match="NOPE"):
        flight.frame("NOPE")


def test_a_bad_value_raises_config_error_with_file_line_and_key(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("base: %s\nname: bad\nduration_s: -3\n" % TRAIN)
    with pytest.raises(nimble_rig.ConfigError) as caught:
        nimble_rig.load_scenario(str(bad))
    e = caught.value
    assert e.file.endswith("bad.yaml")
    assert e.line == 3
    assert e.key == "duration_s"
    assert "duration_s" in str(e)
    assert not e.override
    # A value of the overrides dict: named as one, with no file and no line to point at.
    with pytest.raises(nimble_rig.ConfigError) as caught:
        nimble_rig.load_scenario(TRAIN, {"plant.effects.lateral_gust.sigma_mps": 99.0})
    e = caught.value
    assert str(e).startswith("overrides: key 'plant.effects.lateral_gust.sigma_mps'")
    assert e.override and e.file is None and e.line is None
    assert e.key == "plant.effects.lateral_gust.sigma_mps" and e.value == "99.0"
    with pytest.raises(ValueError):
        nimble_rig.fly(nimble_rig.load_scenario(TRAIN), clock="lockstep")


def test_sigint_ends_a_flight_as_it_ends_rig_run(tmp_path):
    scenario = nimble_rig.load_scenario(HOVER, {"duration_s": 3000})
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    flight = nimble_rig.fly(scenario, seed=1, log=str(tmp_path / "hover.lcmlog"))
    timer.join()
    assert flight.report["result"] == "interrupted"
    assert 0 < flight.report["sim_time_s"] < 3000
    log = nimble_rig.read_log(str(tmp_path / "hover.lcmlog"))
    assert len(log["TRUTH"]["utime"]) == len(flight.channels["TRUTH"]["utime"]) > 0
    # The Ctrl-C is spent: the next flight flies whole.
    again = nimble_rig.fly(nimble_rig.load_scenario(HOVER, {"duration_s": 1}), seed=1)
    assert again.report["result"] == "ok"
    assert again.report["sim_time_s"] == 1.0


def _without_times(result):
    """A sweep's JSON without what depends on the machine and the jobs ("machine": wall times,
    speeds, hosts)."""
    result = json.loads(json.dumps(result))
    result.pop("machine")
    for run in result["runs"]:
        run.pop("machine")
    return result


def test_sweep_gives_what_rig_sweep_gives(tmp_path):
    models = [os.path.join(SOURCE, "rig_configs", "models", f"nimble_lateral_set{k}.yaml") for k in (1, 2)]
    scenario = nimble_rig.load_scenario(HOVER, {"duration_s": 1})
    got = nimble_rig.sweep(scenario, seeds="1-3", vary={"model": models}, jobs=2)
    out = tmp_path / "sweep.json"
    subprocess.run([RIG, "sweep", HOVER, "--seeds", "1-3", "--set", "duration_s=1", "--vary", "model=" + ",".join(models),
                    "--jobs", "1", "--no-progress", "--json", str(out)], check=True, capture_output=True)
    expected = json.loads(out.read_text())
    assert len(got["runs"]) == 6
    assert _without_times(got) == _without_times(expected)


def test_sweep_dir_is_the_campaigns_own_and_has_one_writer(tmp_path):
    """sweep(dir=...) refuses what rig sweep --dir refuses, by the same code: a directory of the
    user's (left untouched) and one that another writer holds (naming its pid); its own campaign
    there is finished, not flown again."""
    scenario = nimble_rig.load_scenario(HOVER, {"duration_s": 0.5})
    user = tmp_path / "user"
    user.mkdir()
    (user / "scenario.yaml").write_text("name: mine\n")
    with pytest.raises(RuntimeError, match=f"{user} is not empty and holds no campaign .*it holds scenario.yaml"):
        nimble_rig.sweep(scenario, seeds="1-2", dir=str(user))
    assert (user / "scenario.yaml").read_text() == "name: mine\n"
    assert [p.name for p in user.iterdir()] == ["scenario.yaml"]

    held = tmp_path / "held"
    held.mkdir()
    fd = os.open(held, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(RuntimeError, match=rf"the campaign directory {held} is being written by another process "
                                               rf"\(pid {os.getpid()}"):
            nimble_rig.sweep(scenario, seeds="1-2", dir=str(held))
        assert list(held.iterdir()) == []
    finally:
        os.close(fd)
    first = nimble_rig.sweep(scenario, seeds="1-2", dir=str(held))
    kept = {p.name: p.stat().st_mtime_ns for p in (held / "runs").iterdir()}
    again = nimble_rig.sweep(scenario, seeds="1-2", dir=str(held))
    assert {p.name: p.stat().st_mtime_ns for p in (held / "runs").iterdir()} == kept
    assert _without_times(again) == _without_times(first)


def test_sweep_envelopes_are_rig_sweep_reports(tmp_path):
    scenario = nimble_rig.load_scenario(HOVER, {"duration_s": 1, "plant.effects.lateral_gust.enabled": True})
    got = nimble_rig.sweep(scenario, seeds="1-5", jobs=2, envelopes=True, report=str(tmp_path / "py"))
    subprocess.run([RIG, "sweep", HOVER, "--seeds", "1-5", "--set", "duration_s=1", "--set",
                    "plant.effects.lateral_gust.enabled=true", "--no-progress", "--report", str(tmp_path / "cli")],
                   check=True, capture_output=True)
    csv = (tmp_path / "cli" / "envelopes.csv").read_text()
    assert (tmp_path / "py" / "envelopes.csv").read_text() == csv
    (env,) = got["envelopes"]
    assert env["runs"] == 5 and env["traces"] == 5
    rows = [line.split(",") for line in csv.splitlines()[1:]]
    for quantity in ("p", "v", "phi_deg"):
        mine = [r for r in rows if r[2] == (quantity if quantity != "phi_deg" else "phi")]
        assert len(mine) == len(env["t_s"]) > 10
        np.testing.assert_array_equal(env["t_s"], [float(r[4]) for r in mine])
        for column, key in ((6, "p5"), (7, "p50"), (8, "p95")):
            np.testing.assert_allclose(env[quantity][key], [float(r[column]) for r in mine], rtol=1e-15, atol=0,
                                       err_msg=quantity + " " + key)
        assert env[quantity]["n"] == [int(r[5]) for r in mine]


def test_sweep_jobs_out_of_rig_sweeps_range_are_refused():
    scenario = nimble_rig.load_scenario(HOVER, {"duration_s": 1})
    for jobs in (0, -5, 257):
        with pytest.raises(ValueError, match=r"jobs must be in \[1, 256\]"):
            nimble_rig.sweep(scenario, seeds="1-2", jobs=jobs)
