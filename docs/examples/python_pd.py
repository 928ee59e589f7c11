"""A roll and pitch PD in Python, flying in place of the rig's attitude controller
(nimble_rig.Participant; docs/python.md, "Python in the loop").

    import nimble_rig
    from python_pd import PythonPD
    scenario = nimble_rig.load_scenario("rig_configs/hover.yaml")
    flight = nimble_rig.fly(scenario, participants={"controller": PythonPD()})

It holds hover on the plant's TRUTH with the rig controller's law and numbers
(rig_configs/controller/nimble_attitude.yaml, controller/attitude_controller.cc), without its
low-pass, reference generator, yaw loop or manoeuvres: each step it reads the newest TRUTH and
commands the left and right flapping frequencies and the dihedral servo.
"""
import nimble
import nimble_rig

F_TRIM = 102.49738145337824  # the hover flapping frequency at trim throttle [rad/s]
TRIM_THROTTLE = 60.0  # trim_throttle_pct [%]


def command(delta_f_radps, dihedral_rad, source):
    """The actuator command of a roll command delta_f [rad/s] (left minus right flapping frequency
    about the trim) and a dihedral [rad] at trim throttle, as the rig controller's mixing makes it."""
    cmd = nimble.actuator_command_t()
    cmd.mode = nimble.actuator_command_t.MODE_LEFT_RIGHT
    cmd.flap_freq_left_radps = F_TRIM + 0.5 * delta_f_radps
    cmd.flap_freq_right_radps = F_TRIM - 0.5 * delta_f_radps
    cmd.delta_f_radps = delta_f_radps
    cmd.flap_freq_collective_radps = F_TRIM
    cmd.throttle_pct = TRIM_THROTTLE
    cmd.dihedral_rad = dihedral_rad
    cmd.source = source
    return cmd


class PythonPD(nimble_rig.Participant):
    inputs = ("TRUTH",)
    outputs = ("ACTUATOR_CMD",)
    rate_hz = 512.0  # the onboard loop's rate, the IMU's (controller.rate_hz) [Hz]

    KP_ROLL = 1.406  # roll_gain_sets.fast.kp_per_rad: roll command per rad of roll error [1/rad]
    KD_ROLL = 0.200  # roll_gain_sets.fast.kd_per_radps: per rad/s of roll-rate error [s/rad]
    KP_PITCH = 0.115  # pitch_gains.kp_per_rad [1/rad]
    KD_PITCH = 0.011  # pitch_gains.kd_per_radps [s/rad]
    ROLL_TO_DELTA_F = 125.0  # mixing.roll_cmd_to_delta_f_radps: delta_f per unit roll command [rad/s]
    PITCH_TO_DIHEDRAL = 0.35  # mixing.pitch_cmd_to_dihedral_rad: dihedral per unit pitch command [rad]

    def __init__(self, roll_sp_rad=0.0):
        self.roll_sp_rad = roll_sp_rad  # the roll to hold [rad]

    def step(self, t_s, inputs):
        truth = inputs["TRUTH"]
        phi = theta = p = q = 0.0
        if truth is not None:
            phi, theta, _ = truth.euler_rad
            p, q, _ = truth.omega_body_radps
        roll = min(1.0, max(-1.0, self.KP_ROLL * (self.roll_sp_rad - phi) - self.KD_ROLL * p))
        pitch = min(1.0, max(-1.0, -self.KP_PITCH * theta - self.KD_PITCH * q))
        cmd = command(self.ROLL_TO_DELTA_F * roll, self.PITCH_TO_DIHEDRAL * pitch, "python_pd")
        cmd.input_utime = truth.utime if truth is not None else -1
        return {"ACTUATOR_CMD": cmd}
