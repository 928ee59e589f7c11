"""A roll LQR in Python, designed with scipy on a lateral model, flying in place of the rig's
attitude controller on the EKF's estimate (nimble_rig.Participant; docs/python.md, "Python in the
loop"). docs/examples/python_lqr.yaml flies it in every clock; docs/examples/lqr_vs_pd.py designs
it on the model identified from a flight and flies it against the rig's C++ PD.

    import nimble_rig
    from python_lqr import PythonLQR
    scenario = nimble_rig.load_scenario("rig_configs/roll_step_fast.yaml")
    lqr = PythonLQR(model="../../rig_configs/models/nimble_lateral_set1.yaml")
    flight = nimble_rig.fly(scenario, participants={"controller": lqr})

The design: the lateral3 model x = [p v phi], u = delta_f (docs/models.md), LQR weights Q on
the states and R on the command (scipy.linalg.solve_continuous_are), and a roll set-point
tracked through the model's own steady state for that roll: u = u_ss - K (x - x_ss). The roll
set-point is the one of rig_configs/manoeuvres/roll_step_10deg.yaml (10 deg from 1 s to 5 s), so
that the flight sets beside the C++ PD flying that manoeuvre. Pitch is held by the rig's pitch PD
(rig_configs/controller/nimble_attitude.yaml), as in docs/examples/python_pd.py.
"""
import os

import sys

import numpy as np
import scipy.linalg
import yaml

import nimble_rig

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from python_pd import command  # noqa: E402  (the rig controller's mixing at trim)

def lateral_model(model_file):
    """(A, B) of a lateral3 model file for x = [p v phi] and u = delta_f [rad/s] (docs/models.md),
    with the vehicle the file names (relative to the model file)."""
    with open(model_file) as f:
        model = yaml.safe_load(f)
    if model.get("structure") != "lateral3":
        raise ValueError("%s: a lateral3 model is needed, not %r" % (model_file, model.get("structure")))
    vehicle_file = os.path.join(os.path.dirname(model_file), model["vehicle"])
    with open(vehicle_file) as f:
        vehicle = yaml.safe_load(f)
    d, trim = model["derivatives"], model["trim"]
    m = vehicle["mass_kg"]
    ixx, izz, ixz = (vehicle["inertia_kgm2"][k] for k in ("Ixx", "Izz", "Ixz"))
    roll = izz / (ixx * izz - ixz * ixz)  # Izz / Ic: roll acceleration per N m of roll moment
    g_term = vehicle["gravity_mps2"] * np.cos(trim["theta0_rad"]) * np.cos(trim["phi0_rad"])
    a = np.array([[roll * d["Lp"], roll * d["Lv"], 0.0],
                  [d["Yp"] / m + trim["w0_mps"], d["Yv"] / m, g_term],
                  [1.0, 0.0, 0.0]])
    b = np.array([[roll * d["L_df"]], [d["Y_df"] / m], [0.0]])
    return a, b


def design(a, b, q_diag, r):
    """The LQR gain K (1x3) of x' = A x + B u for the cost of x' Q x + u' R u, Q = diag(q_diag)."""
    q = np.diag(q_diag)
    r = np.array([[r]])
    p = scipy.linalg.solve_continuous_are(a, b, q, r)
    return np.linalg.solve(r, b.T @ p)


def steady_state_per_rad(a, b):
    """(x_ss, u_ss) of the model holding 1 rad of roll: A x + B u = 0 with phi = 1."""
    m = np.block([[a, b], [np.array([[0.0, 0.0, 1.0, 0.0]])]])
    sol = np.linalg.solve(m, np.array([0.0, 0.0, 0.0, 1.0]))
    return sol[:3], sol[3]


class PythonLQR(nimble_rig.Participant):
    inputs = ("ESTIMATE",)
    outputs = ("ACTUATOR_CMD",)
    rate_hz = 512.0  # the onboard loop's rate, the IMU's (controller.rate_hz) [Hz]

    DELTA_F_MAX = 125.0  # mixing.roll_cmd_to_delta_f_radps: the PD's largest delta_f [rad/s]
    KP_PITCH = 0.115  # pitch_gains.kp_per_rad [1/rad]
    KD_PITCH = 0.011  # pitch_gains.kd_per_radps [s/rad]
    PITCH_TO_DIHEDRAL = 0.35  # mixing.pitch_cmd_to_dihedral_rad [rad]

    def __init__(self, model, q=(1.0, 0.05, 30.0), r=1e-4, step_deg=10.0, step_on_s=1.0, step_off_s=5.0):
        """model: a lateral3 model file, relative to this file's folder when not absolute; q: the
        state weights of p [1/(rad/s)^2], v [1/(m/s)^2], phi [1/rad^2]; r: the command weight
        [1/(rad/s)^2]; the roll set-point step_deg [deg] from step_on_s to step_off_s [s]."""
        if not os.path.isabs(model):
            model = os.path.join(os.path.dirname(os.path.abspath(__file__)), model)
        a, b = lateral_model(model)
        self.k = design(a, b, q, r)[0]
        self.x_per_rad, self.u_per_rad = steady_state_per_rad(a, b)
        self.closed_loop_poles = np.linalg.eigvals(a - b @ self.k[np.newaxis, :])
        self.step_rad = np.radians(step_deg)
        self.step_on_s, self.step_off_s = step_on_s, step_off_s

    def roll_sp_rad(self, t_s):
        return self.step_rad if self.step_on_s <= t_s < self.step_off_s else 0.0

    def step(self, t_s, inputs):
        est = inputs["ESTIMATE"]
        delta_f, pitch = 0.0, 0.0
        if est is not None:
            phi, theta, _ = est.euler_rad
            p, q, _ = est.omega_body_radps
            v = est.velocity_body_mps[1]
            sp = self.roll_sp_rad(t_s)
            x = np.array([p, v, phi])
            delta_f = sp * self.u_per_rad - self.k @ (x - sp * self.x_per_rad)
            delta_f = float(np.clip(delta_f, -self.DELTA_F_MAX, self.DELTA_F_MAX))
            pitch = min(1.0, max(-1.0, -self.KP_PITCH * theta - self.KD_PITCH * q))
        cmd = command(delta_f, self.PITCH_TO_DIHEDRAL * pitch, "python_lqr")
        cmd.input_utime = est.utime if est is not None else -1
        return {"ACTUATOR_CMD": cmd}
