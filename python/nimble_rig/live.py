"""A live run from Python: the rig's channels as they arrive, as lcm-spy shows them.

    for channel, message in nimble_rig.subscribe(["TRUTH", "ACTUATOR_CMD"], url=URL, timeout_s=2):
        print(channel, message.utime)

`rig run` flies a real-time or lockstep run in a private network namespace of its own unless the
scenario says otherwise (run.network_namespace, run.lcm_url: docs/running.md): listen from inside
it (`nsenter -t <rig run's pid> -n`, as rig run prints for an external process) on its URL
(udpm://239.255.76.67:7667?ttl=0), or fly it in this network with run.network_namespace: never
and a run.lcm_url of your choosing. The messages come through the rig's own transport (Debian has
no Python bindings of LCM), decoded as lcm-gen's nimble types.
"""

from .log import _types_by_fingerprint

__all__ = ["subscribe"]


def subscribe(channels, url="", timeout_s=1.0, count=None):
    """Yields (channel, message) for each message of `channels` (names; empty: every channel)
    received on the LCM URL `url` ("": LCM_DEFAULT_URL or LCM's default), in the order they come,
    each decoded as its nimble type (bytes for a message of no rig type). Stops when none has come
    for timeout_s [s], or after `count` messages. Raises RuntimeError naming the URL if LCM cannot
    start on it (the loopback needs multicast: `rig check` says how)."""
    from . import _rig

    if isinstance(channels, str):
        raise TypeError("channels must be a list of channel names, not a str")
    sub = _rig._Subscription(list(channels), url)
    types = _types_by_fingerprint()
    received = 0
    while count is None or received < count:
        got = sub.next(float(timeout_s))
        if got is None:
            return
        channel, data = got
        cls = types.get(data[:8])
        yield channel, (cls.decode(data) if cls is not None else data)
        received += 1
