"""Participants of one's own in the rig's loop: a controller, an estimator, a filter or a
disturbance written in Python, flown in place of one of the scenario's processes.

    class MyController(nimble_rig.Participant):
        inputs = ("ESTIMATE",)          # channels it reads
        outputs = ("ACTUATOR_CMD",)     # channels it publishes
        rate_hz = 512.0                 # how often step() runs [Hz, simulated time]

        def step(self, t_s, inputs):
            est = inputs["ESTIMATE"]    # the newest nimble.estimator_state_t, or None before the first
            cmd = nimble.actuator_command_t()
            ...
            return {"ACTUATOR_CMD": cmd}

    flight = nimble_rig.fly(scenario, participants={"controller": MyController()})

It flies in every clock. In process, nimble_rig.fly() calls it from the run's own loop; in lockstep
and real time it is a process of its own over LCM, named in the scenario and started by the launcher
like the rig's processes (python -m nimble_rig.node):

    participants:
      controller: {python: my_controller.py, class: MyController, arguments: {kp: 0.5}}

(the file relative to the scenario; `arguments`: the class's keyword arguments). nimble_rig.fly()
flies the same section in process.

step(t_s, inputs) gets the simulated time [s] and, per input channel, the newest message received
before this step (the message types of lcmtypes/, as `import nimble` has them: the fields in the
units their names say), or None while none has come. In lockstep and in process a message another
participant published at a step counts from the next step on, as the rig's own processes take
theirs, so that both clocks fly the same flight; the plant's (TRUTH, IMU, ...) count at once: it
publishes them before the step that uses them. It returns {channel: message} for any of its
outputs (or None: nothing this step). Each message's utime is set to the step's time [us] and its
seq to the channel's count, as the rig's own processes stamp theirs; anything else is the
participant's. The participant takes the process's place on the bus: its heartbeat and health are
the process's, and the scenario's faults on its outputs apply.

An exception step() raises ends the flight with result failed, naming the process, the exception
and the simulated time; the log keeps everything until then.
"""

import importlib.util
import math
import os
import sys

from .log import _types_by_fingerprint

__all__ = ["Participant", "stepper", "load"]


class Participant:
    """Base of a participant: set inputs, outputs and rate_hz, and define step(t_s, inputs)."""

    #: channels it reads: step() gets the newest message of each
    inputs = ()
    #: channels it publishes: step() may return a message for each
    outputs = ()
    #: how often step() runs [Hz of simulated time]; the period must be a whole number of ns
    rate_hz = None

    def step(self, t_s, inputs):
        raise NotImplementedError("a participant defines step(t_s, inputs)")


def _channel_list(process, what, value, channels):
    if isinstance(value, str) or not all(isinstance(c, str) and c for c in value):
        raise TypeError("participant in place of %s: %s must be a list of channel names, not %r" % (process, what, value))
    unknown = [c for c in value if c not in channels]
    if unknown:
        raise ValueError("participant in place of %s: %s %s: no such channel in the rig's contract (lcmtypes/README.md)"
                         % (process, what, ", ".join(unknown)))
    return list(value)


def _publishes(process, publishers):
    """The contract lets `process` publish a channel whose publishers name it (with or without a
    condition: "controller (pilot.enabled)")."""
    return any(p == process or p.startswith(process + " ") for p in publishers)


def load(process, path, class_name, arguments):
    """The participant a scenario names: an instance of class `class_name` of the Python file `path`,
    made with `arguments` ({name: value}) as keyword arguments. Raises ImportError, TypeError or what
    the file raises, naming the process and the file."""
    name = "nimble_rig_participant_%s_%s" % (process, os.path.splitext(os.path.basename(path))[0])
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None:
        raise ImportError("participants.%s: %s cannot be imported as a Python file" % (process, path))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    cls = getattr(module, class_name, None)
    if not isinstance(cls, type):
        raise ImportError("participants.%s: %s defines no class %s" % (process, path, class_name))
    try:
        return cls(**(arguments or {}))
    except TypeError as e:
        raise TypeError("participants.%s: %s(**arguments) of %s: %s" % (process, class_name, path, e)) from e


def _plausible_sim_utime(utime):
    """A rig-time stamp [us], not a wall-clock one (the health channels are stamped with the epoch)."""
    return isinstance(utime, int) and 0 <= utime <= 10 ** 12  # transport/clock.h kMaxSimUtime


def stepper(process, participant, channels):
    """Checks `participant` and returns (call, inputs, rate_hz, label, outputs) for the flight: call(t_s,
    fresh, lockstep) takes the inputs' bytes that came since the last call ([(channel, bytes)] in the
    order they came) and returns [(channel, bytes)] to publish; outputs: {channel: type}. lockstep:
    a message of another participant stamped at or after t_s is held for a later step. `channels`: the contract's {channel: (type, publishers)}. Its
    outputs must be channels the contract lets `process` publish, each message of the channel's
    type. Raises TypeError or ValueError naming the process."""
    label = "%s (Python %s)" % (process, type(participant).__name__)
    step = getattr(participant, "step", None)
    if not callable(step):
        raise TypeError("participant in place of %s: %r has no step(t_s, inputs)" % (process, participant))
    inputs = _channel_list(process, "inputs", getattr(participant, "inputs", ()), channels)
    outputs = _channel_list(process, "outputs", getattr(participant, "outputs", ()), channels)
    foreign = [c for c in outputs if not _publishes(process, channels[c][1])]
    if foreign:
        raise ValueError("participant in place of %s: outputs %s: the contract does not let %s publish them "
                         "(lcmtypes/README.md)" % (process, ", ".join(foreign), process))
    expected = {c: channels[c][0] for c in outputs}
    rate_hz = getattr(participant, "rate_hz", None)
    if not isinstance(rate_hz, (int, float)) or not math.isfinite(rate_hz) or not 0 < rate_hz <= 1e5:
        raise ValueError("participant in place of %s: rate_hz must be a number in (0, 1e5] Hz, not %r"
                         % (process, rate_hz))
    types = _types_by_fingerprint()
    latest = {channel: None for channel in inputs}
    seqs = {channel: 0 for channel in outputs}
    # The plant's channels count at once: the lockstep master publishes them before its tick.
    at_once = {c for c in inputs if _publishes("plant", channels[c][1])}
    held = []  # lockstep: (stamp [us], channel, message) of other participants, in arrival order

    def call(t_s, fresh, lockstep=False):
        t_us = int(round(t_s * 1e6))
        for channel, data in fresh:
            cls = types.get(data[:8])
            message = cls.decode(data) if cls is not None else None
            stamp = getattr(message, "utime", None)
            if lockstep and channel not in at_once and _plausible_sim_utime(stamp):
                held.append((stamp, channel, message))
            else:
                latest[channel] = message
        if held:
            kept = []
            for stamp, channel, message in held:
                if stamp < t_us:
                    latest[channel] = message
                else:
                    kept.append((stamp, channel, message))
            held[:] = kept
        out = step(t_s, latest)
        if out is None:
            return []
        if not isinstance(out, dict):
            raise TypeError("step() returned %s, not {channel: message}" % type(out).__name__)
        published = []
        for channel, message in out.items():
            if channel not in seqs:
                raise ValueError("step() returned a message on %s, which is not among its outputs %s"
                                 % (channel, outputs))
            if type(message).__name__ != expected[channel] or not hasattr(message, "encode"):
                raise TypeError("step() returned a %s on %s, whose messages are nimble.%s"
                                % (type(message).__name__, channel, expected[channel]))
            message.utime = t_us
            message.seq = seqs[channel]
            seqs[channel] += 1
            published.append((channel, message.encode()))
        return published

    return call, inputs, float(rate_hz), label, expected
