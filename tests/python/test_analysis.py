"""nimble_rig's analyses (python/py_analysis.cc) on a real flight: each gives what its command's
--json gives, on a rig log, a CSV file and a dict of numpy arrays alike; identify() against a
numpy least-squares fit of the same regressors; the errors carry where the problem is."""
import json
import os
import subprocess

import numpy as np
import pytest

import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
RIG = os.environ["RIG_BIN"]
TRAIN = os.path.join(SOURCE, "rig_configs", "id_doublet_train_fast.yaml")
SET1 = os.path.join(SOURCE, "rig_configs", "models", "nimble_lateral_set1.yaml")
ARRAYS = ("signals", "equations", "eigenvalues", "t", "measured", "predicted", "simulated", "phi_sp", "phi_ref")


@pytest.fixture(scope="module")
def train(tmp_path_factory):
    """The identification train flown once from Python (seed 1), its log and its CSV export."""
    d = tmp_path_factory.mktemp("train")
    log = str(d / "train.lcmlog")
    nimble_rig.fly(nimble_rig.load_scenario(TRAIN), seed=1, log=log)
    csv = str(d / "train.csv")
    subprocess.run([RIG, "export", log, "--csv", csv], check=True, capture_output=True)
    return {"dir": d, "log": log, "csv": csv}


def rig_json(*args):
    """`rig ARGS --json -` as Python objects."""
    done = subprocess.run([RIG, *args, "--json", "-"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def without_arrays(result):
    return {k: v for k, v in result.items() if k not in ARRAYS}


def csv_arrays(path):
    """An identification CSV as a dict of arrays (the user's own measurements, no file given)."""
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    table = np.genfromtxt(lines, delimiter=",", names=True)
    return {name: np.asarray(table[name]) for name in table.dtype.names}


def test_identify_gives_rig_identify_and_numpy_least_squares(train):
    got = nimble_rig.identify(train["log"], method="ols")
    expected = rig_json("identify", train["log"], "--method", "ols")
    assert without_arrays(got) == without_arrays(expected)
    # The eigenvalues as numpy gives eigenvalues: a complex array [1/s], the command's [re, im] pairs.
    assert got["eigenvalues"].dtype == np.complex128
    np.testing.assert_array_equal(got["eigenvalues"], [complex(re, im) for re, im in expected["eigenvalues"]])
    signals = got["signals"]
    assert signals["t"].shape == signals["p"].shape and len(signals["t"]) > 2000
    for eq in got["equations"]:
        x = np.column_stack([signals[r] for r in eq["regressors"]])
        theta, *_ = np.linalg.lstsq(x, eq["y"], rcond=None)
        ours = np.array([got["parameters"][p]["value"] for p in eq["parameters"]])
        np.testing.assert_allclose(ours, theta, rtol=1e-7, atol=1e-12, err_msg=eq["name"])
        assert np.allclose(eq["y"], eq["scale"] * signals[eq["dependent"]])


def test_identify_blackbox_gives_rig_identify_and_an_unconstrained_least_squares_fit(train):
    """A black box (thesis Eq 8.6): every state derivative on every state and input, unscaled."""
    got = nimble_rig.identify(train["log"], structure="blackbox3", method="ols")
    assert without_arrays(got) == without_arrays(rig_json("identify", train["log"], "--structure", "blackbox3",
                                                          "--method", "ols"))
    signals = got["signals"]
    assert [eq["dependent"] for eq in got["equations"]] == ["p_dot", "v_dot", "phi_dot"]
    for eq in got["equations"]:
        assert eq["scale"] == 1.0 and eq["regressors"] == ["p", "v", "phi", "delta_f", "delta_t"]
        x = np.column_stack([signals[r] for r in eq["regressors"]])
        theta, *_ = np.linalg.lstsq(x, signals[eq["dependent"]], rcond=None)
        ours = np.array([got["parameters"][p]["value"] for p in eq["parameters"]])
        np.testing.assert_allclose(ours, theta, rtol=1e-7, atol=1e-12, err_msg=eq["name"])
    assert got["parameters"]["a_phi_p"]["value"] == pytest.approx(1.0, abs=0.02)  # the kinematic row


def test_identify_takes_a_csv_file_and_a_dict_of_arrays_alike(train, tmp_path):
    from_csv = nimble_rig.identify(train["csv"], model_out=str(tmp_path / "m.yaml"))
    from_dict = nimble_rig.identify(csv_arrays(train["csv"]))
    for name, p in from_csv["parameters"].items():
        assert from_dict["parameters"][name]["value"] == pytest.approx(p["value"], rel=1e-12), name
    assert (tmp_path / "m.yaml").read_text().startswith("#")
    assert from_csv == {**from_csv, **without_arrays(from_csv)}


def test_validate_gives_rig_validate_open_and_closed_loop(train):
    open_loop = nimble_rig.validate(SET1, train["log"])
    assert without_arrays(open_loop) == rig_json("validate", SET1, train["log"])
    assert set(open_loop["measured"]) == set(open_loop["metrics"])
    closed = nimble_rig.validate(SET1, train["log"], closed_loop=True)
    assert without_arrays(closed) == rig_json("validate", SET1, train["log"], "--closed-loop")
    n = closed["samples"]
    assert closed["t"].shape == (n,) and closed["simulated"]["phi"].shape == (n,)
    # The R^2 the report gives is that of the arrays handed over.
    m, s = closed["measured"]["phi"], closed["simulated"]["phi"]
    r2 = 1 - np.sum((m - s) ** 2) / np.sum((m - m.mean()) ** 2)
    assert r2 == pytest.approx(closed["closed_loop"]["phi"]["r2"], rel=1e-9)


def test_a_model_given_as_a_dict_is_the_model_file_it_holds(train, monkeypatch):
    import yaml

    with open(SET1) as f:
        content = yaml.safe_load(f)
    # Its vehicle path is taken from the current directory: the model file's own directory here.
    monkeypatch.chdir(os.path.dirname(SET1))
    from_dict = nimble_rig.validate(content, train["log"])
    from_file = nimble_rig.validate(SET1, train["log"])
    assert from_dict["metrics"] == from_file["metrics"]
    changed = dict(content, derivatives=dict(content["derivatives"], Lp=2 * content["derivatives"]["Lp"]))
    assert nimble_rig.validate(changed, train["log"])["metrics"] != from_file["metrics"]
    loop = nimble_rig.loop(TRAIN, model=content, gains="fast")["loops"][0]
    assert loop["phase_margin_deg"] == nimble_rig.loop(TRAIN, model=SET1, gains="fast")["loops"][0]["phase_margin_deg"]
    with pytest.raises(nimble_rig.ConfigError, match="Lp"):
        nimble_rig.validate(dict(content, derivatives=dict(content["derivatives"], Lp="fast")), train["log"])
    with pytest.raises(TypeError):
        nimble_rig.validate(42, train["log"])


def test_discrepancy_gives_rig_discrepancy(train):
    got = nimble_rig.discrepancy(train["log"], model=SET1)
    assert got == rig_json("discrepancy", train["log"], "--model", SET1)
    assert got["verdict"]


def test_export_mcap_gives_rig_export(train, tmp_path):
    got = nimble_rig.export_mcap(train["log"], tmp_path / "py.mcap")
    expected = rig_json("export", train["log"], "--out", str(tmp_path / "cli.mcap"))
    for key in ("events", "messages", "mcap_channels", "undecodable", "channels", "start_time_ns", "end_time_ns"):
        assert got[key] == expected[key], key
    assert (tmp_path / "py.mcap").read_bytes()[:8] == b"\x89MCAP0\r\n"


def test_bad_data_raises_data_error_naming_the_channel_and_sample(train, tmp_path):
    data = csv_arrays(train["csv"])
    data["t"] = data["t"].copy()
    data["t"][7] = data["t"][6]
    with pytest.raises(nimble_rig.DataError) as caught:
        nimble_rig.identify(data)
    assert caught.value.column == "t" and "increas" in str(caught.value)
    data = csv_arrays(train["csv"])
    data["phi"] = data["phi"].copy()
    data["phi"][3] = np.nan
    with pytest.raises(nimble_rig.DataError) as caught:
        nimble_rig.identify(data)
    assert caught.value.column == "phi"
    with pytest.raises(ValueError, match="unknown channel 'roll'"):
        nimble_rig.identify({"t": np.arange(3.0), "roll": np.zeros(3)})
    with pytest.raises(ValueError, match="order must be in"):
        nimble_rig.identify(train["log"], order=-1)
    with pytest.raises(ValueError, match="not a rig log"):
        nimble_rig.identify(train["csv"], states="truth")
    damaged = tmp_path / "damaged.lcmlog"
    damaged.write_bytes(open(train["log"], "rb").read()[:200000] + b"\x00" * 40)
    with pytest.raises(nimble_rig.DataError):
        nimble_rig.identify(str(damaged))


def test_options_out_of_the_command_lines_ranges_are_refused_as_there(train):
    """nan, inf and out-of-range options raise ValueError naming them, as the command line refuses them."""
    for bad in ({"command_latency_s": float("nan")}, {"delay_max_s": float("inf")}, {"delay_max_s": 0.0},
                {"partial_f": float("nan")}, {"folds": 2}, {"command_latency_s": 0.5}):
        name = next(iter(bad))
        with pytest.raises(ValueError, match=name):
            nimble_rig.discrepancy(train["log"], model=SET1, **bad)
    for bad in ({"rate_hz": float("nan")}, {"cutoff_hz": float("inf")}, {"cutoff_hz": -1.0}, {"order": 41}):
        name = next(iter(bad))
        with pytest.raises(ValueError, match=name):
            nimble_rig.identify(train["log"], **bad)


def test_identify_takes_every_option_of_the_command_line_and_a_flight(train, tmp_path):
    # The trim of Eq 21: set 1's w0 of -0.30 m/s, as `rig identify --w0 -0.30` (without it Yp comes out
    # with the other sign on this train).
    got = nimble_rig.identify(train["log"], w0=-0.30)
    assert without_arrays(got) == without_arrays(rig_json("identify", train["log"], "--w0", "-0.30"))
    assert got["parameters"]["Yp"]["value"] > 0
    assert nimble_rig.identify(train["log"])["parameters"]["Yp"]["value"] < 0
    # Output error, as `rig identify --method output-error`.
    oe = nimble_rig.identify(train["log"], w0=-0.30, method="output-error", oe_segment_s=1.5)
    assert without_arrays(oe) == without_arrays(
        rig_json("identify", train["log"], "--w0", "-0.30", "--method", "output-error", "--oe-segment", "1.5"))
    # Terms as texts, and the PSD segments.
    with_term = nimble_rig.identify(train["log"], w0=-0.30, terms=["Y: v*abs(v)"], hover=[(0.5, 4.0)])
    assert "Y:v*abs(v)" in with_term["parameters"]
    with pytest.raises(ValueError, match="EQUATION: EXPRESSION"):
        nimble_rig.identify(train["log"], terms=["v*abs(v)"])
    with pytest.raises(ValueError, match="hover"):
        nimble_rig.identify(train["log"], hover=[(4.0, 1.0)])
    # A Flight flown with a log is read from it; one flown without says how to keep one.
    log = str(tmp_path / "f.lcmlog")
    flight = nimble_rig.fly(nimble_rig.load_scenario(TRAIN), seed=1, log=log)
    assert without_arrays(nimble_rig.identify(flight, w0=-0.30)) == without_arrays(got) | {"source": log}
    bare = nimble_rig.fly(nimble_rig.load_scenario(TRAIN), seed=1)
    with pytest.raises(Exception, match="flown without a log"):
        nimble_rig.identify(bare)
