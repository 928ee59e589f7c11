"""nimble_rig.loop (python/py_loop.cc): `rig loop --json`'s content, and its frequency response
and margins checked by scipy.signal on the same discrete loop (python-control is not in Debian)."""
import json
import os
import subprocess

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import scipy.signal

import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
RIG = os.environ["RIG_BIN"]
TRAIN = os.path.join(SOURCE, "rig_configs", "id_doublet_train_fast.yaml")
ARRAYS = ("frequency_hz", "ratio", "tracking", "discrete", "closed_loop_poles", "closed_loop_damping",
          "closed_loop_natural_hz", "dominant_pair")
# scipy.signal.dfreqresp goes through a transfer function, whose polynomials it warns about on
# this loop; its values are checked all the same (below, to 1e-3).
pytestmark = pytest.mark.filterwarnings("ignore:Badly conditioned", "ignore:invalid value encountered")


def scipy_loop(discrete):
    """The loop as scipy's discrete LTI system (zeros, poles, gain), and L(omega) = -G(e^{j omega
    dt}) from the state space by scipy.linalg (G = C (zI - A)^-1 B + D, solved at each z): the
    conversion to zeros and poles costs about 1e-4 of relative accuracy on this loop (its delay
    states), the state space nothing."""
    a, b, c, d, dt = (discrete[k] for k in ("A", "B", "C", "D", "dt"))
    z, p, k = scipy.signal.ss2zpk(a, b, c, np.atleast_2d(d))

    def ratio(omega_radps):
        out = []
        for w in np.atleast_1d(omega_radps):
            zi = np.exp(1j * w * dt)
            out.append(-((c @ scipy.linalg.solve(zi * np.eye(a.shape[0]) - a, b))[0, 0] + np.asarray(d).item()))
        return np.array(out)

    return scipy.signal.dlti(z, p, k, dt=dt), ratio


def crossings(f, grid):
    """Every root of f between grid points where it changes sign, refined by brentq."""
    values = np.array([f(w) for w in grid])
    out = []
    for i in np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0]:
        out.append(scipy.optimize.brentq(f, grid[i], grid[i + 1], xtol=1e-12, rtol=1e-12))
    return out


@pytest.mark.parametrize("gains", ["fast", "slow"])
def test_loop_gives_rig_loop_and_scipy_agrees_on_its_response_and_margins(gains):
    got = nimble_rig.loop(TRAIN, gains=gains)
    done = subprocess.run([RIG, "loop", TRAIN, "--gains", gains, "--json", "-"], capture_output=True, text=True)
    expected = json.loads(done.stdout)
    assert got["ok"] == (done.returncode == 0)
    plain = {k: v for k, v in got.items() if k != "ok"}
    plain["loops"] = [{k: v for k, v in loop.items() if k not in ARRAYS} for loop in got["loops"]]
    assert plain == {**expected, "loops": [{k: v for k, v in loop.items() if k not in ARRAYS} for loop in expected["loops"]]}
    loop = got["loops"][0]
    # The poles as numpy arrays: s complex [1/s] with damping and natural frequency, in the command's order.
    said = expected["loops"][0]
    assert loop["closed_loop_poles"].dtype == np.complex128
    np.testing.assert_array_equal(loop["closed_loop_poles"], [complex(p["re"], p["im"]) for p in said["closed_loop_poles"]])
    np.testing.assert_array_equal(loop["closed_loop_damping"], [p["damping"] for p in said["closed_loop_poles"]])
    np.testing.assert_array_equal(loop["closed_loop_natural_hz"], [p["natural_hz"] for p in said["closed_loop_poles"]])
    assert loop["dominant_pair"]["pole"] == complex(said["dominant_pair"]["re"], said["dominant_pair"]["im"])
    system, ratio = scipy_loop(loop["discrete"])
    omega = 2 * np.pi * loop["frequency_hz"]
    # The response the Bode and Nyquist plots draw is scipy's, where it is not lost in rounding:
    # from the state space to 1e-7, from scipy.signal's zeros and poles to their own accuracy.
    big = np.abs(loop["ratio"]) > 1e-9 * np.abs(loop["ratio"]).max()
    assert big.sum() > 600
    np.testing.assert_allclose(loop["ratio"][big], ratio(omega[big]), rtol=1e-7)
    _, g = scipy.signal.dfreqresp(system, w=omega * loop["discrete"]["dt"])
    np.testing.assert_allclose(loop["ratio"][big], -g[big], rtol=1e-3)
    # Stability: the loop closed by w = y, from scipy's poles of the closed loop.
    d = loop["discrete"]
    closed = scipy.signal.dlti(d["A"] + d["B"] @ d["C"], np.zeros_like(d["B"]), d["C"], 0, dt=d["dt"])
    assert (np.abs(closed.poles).max() < 1) == loop["closed_loop_stable"]
    # The same poles from scipy: s = ln(z) / dt of the closed loop's eigenvalues off the origin.
    z = np.linalg.eigvals(d["A"] + d["B"] @ d["C"])
    s = np.log(z[np.abs(z) > 1e-6]) / d["dt"]
    for pole in loop["closed_loop_poles"]:
        assert np.min(np.abs(s - pole)) < 1e-6 * max(1.0, abs(pole)), pole
    # The discrete loop plugs into scipy as it is: a dlti with the same matrices and step.
    assert isinstance(d["dlti"], scipy.signal.dlti) and d["dlti"].dt == d["dt"]
    np.testing.assert_array_equal(d["dlti"].A, d["A"])
    assert d["D"].shape == (1, 1)
    assert (np.abs(system.poles).max() < 1) == loop["open_loop_stable"]
    # Phase margin at the gain crossover, found on scipy's response.
    fine = np.geomspace(omega[0], omega[-1], 4000)
    wc = crossings(lambda w: np.abs(ratio(w)[0]) - 1.0, fine)
    assert len(wc) == len(loop["crossovers_hz"])
    assert wc[0] / (2 * np.pi) == pytest.approx(loop["crossover_hz"], rel=1e-6)
    pm = 180.0 + np.degrees(np.angle(ratio(wc[0])[0]))
    assert pm == pytest.approx(loop["phase_margin_deg"], abs=1e-4)
    # Gain margins where the phase is -180 deg: the smallest increase and the largest reduction.
    w180 = [w for w in crossings(lambda w: ratio(w)[0].imag, fine) if ratio(w)[0].real < 0]
    factors = [1.0 / abs(ratio(w)[0]) for w in w180]
    up = [f for f in factors if f > 1]
    down = [f for f in factors if f < 1]
    if up:
        assert 20 * np.log10(min(up)) == pytest.approx(loop["gain_margin_db"], abs=1e-4)
    if down:
        assert 20 * np.log10(max(down)) == pytest.approx(loop["gain_reduction_margin_db"], abs=1e-4)
    assert up or down


def test_loop_takes_a_scenario_and_overrides_and_names_a_bad_gain_set():
    scenario = nimble_rig.load_scenario(TRAIN)
    a = nimble_rig.loop(scenario, gains="2.0,0.25")
    b = nimble_rig.loop(TRAIN, gains="2.0,0.25")
    assert a["loops"][0]["phase_margin_deg"] == b["loops"][0]["phase_margin_deg"]
    assert a["loops"][0]["kp_per_rad"] == 2.0
    with pytest.raises(ValueError, match="nonesuch"):
        nimble_rig.loop(TRAIN, gains="nonesuch")
    # Gains as numbers: a pair (KP [1/rad], KD [s/rad]) or a loop entry's own keys, as the text.
    for gains in ((2.0, 0.25), [2.0, 0.25], {"kp_per_rad": 2.0, "kd_per_radps": 0.25}):
        c = nimble_rig.loop(TRAIN, gains=gains)
        assert c["loops"][0]["phase_margin_deg"] == b["loops"][0]["phase_margin_deg"], gains
    for bad in ((2.0,), {"kp": 2.0, "kd": 0.25}, 2.0):
        with pytest.raises(TypeError, match="gains"):
            nimble_rig.loop(TRAIN, gains=bad)
    design = nimble_rig.loop(TRAIN, design="phase_margin_deg=45,crossover_hz=2")
    assert "design" in design
