"""Python access to the Delfly Nimble rig's LCM logs.

    from nimble_rig import read_log
    log = read_log("rig_logs/hover.lcmlog")
    truth = log["TRUTH"]                      # field name -> numpy array, one row per message
    t = truth["utime"] * 1e-6                 # simulated time [s]
    phi = truth["euler_rad"][:, 0]            # roll [rad]

Pure Python and numpy: the message types come from the `nimble` package that lcm-gen made from
lcmtypes/*.lcm (installed next to this one); LCM's own Python module is not needed.
"""

from .log import LogError, RigLog, read_log

__all__ = ["LogError", "RigLog", "read_log"]
__version__ = "@PROJECT_VERSION@"
