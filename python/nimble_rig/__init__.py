"""Python access to the Delfly Nimble rig: its LCM logs, and (compiled module) its scenarios and
flights.

    import nimble_rig
    s = nimble_rig.load_scenario("rig_configs/id_doublet_train_fast.yaml")
    f = nimble_rig.fly(s, seed=1)               # in process, at the C++ speed
    f.report["result"], f.channels["TRUTH"]["euler_rad"][:, 0]

    from nimble_rig import read_log
    log = read_log("rig_logs/hover.lcmlog")
    truth = log["TRUTH"]                      # field name -> numpy array, one row per message
    t = truth["utime"] * 1e-6                 # simulated time [s]
    phi = truth["euler_rad"][:, 0]            # roll [rad]

Pure Python and numpy: the message types come from the `nimble` package that lcm-gen made from
lcmtypes/*.lcm (installed next to this one); LCM's own Python module is not needed.
"""

from .live import subscribe
from .log import LogError, RigLog, channel_frame, read_log
from .participant import Participant

__all__ = ["LogError", "Participant", "RigLog", "channel_frame", "read_log", "subscribe"]

try:  # the compiled module (python/rig_module.cc), where the build had pybind11
    from ._rig import (ConfigError, DataError, Flight, Scenario, discrepancy, export_mcap, fly, identify,
                       load_scenario, loop, sweep, validate)

    __all__ += ["ConfigError", "DataError", "Flight", "Scenario", "discrepancy", "export_mcap", "fly", "identify",
                "load_scenario", "loop", "sweep", "validate"]

    def _flight_frame(self, channel):
        """The channel as a pandas DataFrame indexed by t_s [s] (nimble_rig.channel_frame)."""
        if channel not in self.channels:
            raise KeyError("no message on channel %r in this flight (channels: %s)"
                           % (channel, ", ".join(sorted(self.channels))))
        return channel_frame(self.channels[channel], channel)

    Flight.frame = _flight_frame
except ModuleNotFoundError:  # built without pybind11: the log reader alone (a module that fails to load raises)
    pass
__version__ = "@PROJECT_VERSION@"
