"""Reader of LCM log files (lcm-logger's format) into numpy arrays per channel.

An LCM log is a sequence of events, each
    sync word 0xEDA1DA01 (uint32, big-endian), event number (int64), timestamp [us] (int64),
    channel length (int32), data length (int32), channel (UTF-8), data.
Each message's first 8 bytes are its type's fingerprint, which names the nimble type that
decodes it. A damaged log (a wrong sync word, a truncated event) is an error that names the
file, the byte offset and the event number; salvage=True keeps what precedes the damage.

A message with a value beyond the vehicle's physical bounds (garbage that decoded: the vehicle
file's data_bounds) is left out and named by a UserWarning and RigLog.beyond_bounds, by the rig's
own check (nimble_rig._rig.log_bounds), where the compiled module was built.
"""

import os
import stat
import struct
import warnings

import numpy as np

import nimble

_SYNC = 0xEDA1DA01
_HEADER = struct.Struct(">IqqII")
_MAX_CHANNEL = 256
#: The largest LCM log read (the rig's kMaxLcmLogBytes, core/input_file.h; docs/tool.md).
MAX_LOG_BYTES = 2_000_000_000


class LogError(Exception):
    """A log that cannot be read to its end (damaged or truncated), or not an LCM log at all."""


def _types_by_fingerprint():
    found = {}
    for name in dir(nimble):
        cls = getattr(nimble, name)
        if isinstance(cls, type) and hasattr(cls, "_get_packed_fingerprint"):
            found[cls._get_packed_fingerprint()] = cls
    return found


def _file_type(mode):
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a file"


def _read_bounded(path):
    """The bytes of `path`, refused before any is read unless it is a regular file within MAX_LOG_BYTES.

    Opened without blocking (a FIFO does not wait for a writer) and checked on the descriptor;
    a file that grows past the bound while it is read is refused too.
    """
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    st = os.fstat(fd)
    problem = None
    if not stat.S_ISREG(st.st_mode):
        problem = "is not a regular file (%s)" % _file_type(st.st_mode)
    elif st.st_size > MAX_LOG_BYTES:
        problem = "is %.1f GB, above the %.1f GB bound for an LCM log" % (st.st_size / 1e9, MAX_LOG_BYTES / 1e9)
    if problem is not None:
        os.close(fd)
        raise LogError("%s %s" % (path, problem))
    with os.fdopen(fd, "rb") as f:
        parts, total = [], 0
        while True:
            part = f.read(max(st.st_size - total, 1 << 20))
            if not part:
                return parts[0] if len(parts) == 1 else b"".join(parts)
            total += len(part)
            if total > MAX_LOG_BYTES:
                raise LogError("%s grew past the %.1f GB bound for an LCM log while it was read"
                               % (path, MAX_LOG_BYTES / 1e9))
            parts.append(part)


def _columns(messages):
    """Field name -> numpy array over the messages (fixed-size numeric fields as 2-D arrays)."""
    out = {}
    for field in messages[0].__slots__:
        values = [getattr(m, field) for m in messages]
        first = values[0]
        if isinstance(first, (bool, int, float)):
            out[field] = np.asarray(values)
        elif isinstance(first, (list, tuple)) and all(isinstance(v, (list, tuple)) and len(v) == len(first)
                                                      for v in values) and \
                all(isinstance(x, (bool, int, float)) for x in first):
            out[field] = np.asarray(values)
        else:
            out[field] = np.asarray(values, dtype=object)
    return out


class RigLog:
    """The messages of one log, decoded and grouped by channel.

    log[channel] is a dict of numpy arrays: every field of the channel's type, plus
    "log_utime", the event's timestamp in the log [us] (wall clock of the recording for a
    real-time run, simulated time for a lockstep or in-process run).
    """

    def __init__(self, path, channels, undecoded, events, damage, beyond_bounds=None):
        self.path = path
        self._channels = channels
        #: channel -> number of messages of no nimble type (or that did not decode)
        self.undecoded = undecoded
        #: number of events read
        self.events = events
        #: None, or what was wrong where (with salvage=True)
        self.damage = damage
        #: None (not checked: no compiled module), or the messages left out for a value beyond the
        #: vehicle's physical bounds: {"messages", "samples", "bounds", "text", "channels": [{"channel",
        #: "field", "quantity", "count", "bound", "first_t_s", "first_value", ...}]}
        self.beyond_bounds = beyond_bounds

    def channels(self):
        return sorted(self._channels)

    def __contains__(self, channel):
        return channel in self._channels

    def __getitem__(self, channel):
        if channel not in self._channels:
            raise KeyError("no decodable message on channel %r in %s (channels: %s)"
                           % (channel, self.path, ", ".join(self.channels())))
        return self._channels[channel]

    def frame(self, channel):
        """The channel as a pandas DataFrame: one row per message, indexed by its time t_s [s]
        (the message's utime, simulated time), one column per field ("euler_rad[0]" for an
        array field's elements); see channel_frame()."""
        return channel_frame(self[channel], channel)

    def __repr__(self):
        counts = ", ".join("%s: %d" % (c, len(v["log_utime"])) for c, v in sorted(self._channels.items()))
        return "RigLog(%r, %d events; %s)" % (self.path, self.events, counts)


def channel_frame(fields, channel="channel"):
    """A channel's fields (name -> numpy array, one row per message, with "utime" [us]) as a pandas
    DataFrame indexed by t_s = utime * 1e-6 [s]: a field of one value per message is a column, an
    array field one column per element, named "field[i]" ("field[i][j]" for a matrix); the units
    are those of the field names (docs/python.md: _rad, _radps, _mps, _us, ...).

    Needs pandas (Debian: python3-pandas). Raises ModuleNotFoundError naming the package without it,
    KeyError if the channel has no utime."""
    try:
        import pandas
    except ModuleNotFoundError as e:
        raise ModuleNotFoundError("frame() needs pandas: install Debian's python3-pandas") from e
    if "utime" not in fields:
        raise KeyError("%s has no utime field to index its frame by" % channel)
    columns = {}
    for name, values in fields.items():
        a = np.asarray(values)
        if a.ndim <= 1:
            columns[name] = a
        else:
            flat = a.reshape(a.shape[0], -1)
            for k, index in enumerate(np.ndindex(*a.shape[1:])):
                columns[name + "".join("[%d]" % i for i in index)] = flat[:, k]
    t_s = np.asarray(fields["utime"], dtype=np.int64) * 1e-6
    return pandas.DataFrame(columns, index=pandas.Index(t_s, name="t_s"))


def _beyond_bounds(path, vehicle, salvage):
    """The rig's check of the log against the vehicle's bounds (None without the compiled module)."""
    try:
        from . import _rig
    except ModuleNotFoundError:
        return None
    try:
        return _rig.log_bounds(path, vehicle=vehicle, salvage=salvage)
    except _rig.DataError:
        return None  # a damaged log: named by the reader below


def read_log(path, channels=None, salvage=False, vehicle=None):
    """Reads the LCM log at `path`; `channels` (a collection of names) keeps only those.

    A message with a value beyond the physical bounds of `vehicle` (a vehicle file; default the
    rig's) is left out, named by a UserWarning and RigLog.beyond_bounds (with the compiled module).

    Raises LogError naming the byte offset and event number of any damage, unless `salvage`,
    which keeps the events before it and records what was wrong in RigLog.damage; and, before
    reading a byte, naming the file if it is no regular file (a FIFO, /dev/zero) or is above
    MAX_LOG_BYTES.
    """
    types = _types_by_fingerprint()
    data = _read_bounded(os.fspath(path))
    bounds = _beyond_bounds(os.fspath(path), vehicle, salvage)
    beyond = set(bounds["offsets"]) if bounds else set()
    offset, events, damage = 0, 0, None
    messages, stamps, undecoded = {}, {}, {}
    while offset < len(data):
        problem = None
        if len(data) - offset < _HEADER.size:
            problem = "a truncated event header (%d bytes left)" % (len(data) - offset)
        else:
            sync, _number, utime, channel_len, data_len = _HEADER.unpack_from(data, offset)
            if sync != _SYNC:
                problem = "no sync word (0x%08X instead of 0xEDA1DA01)" % sync
            elif channel_len == 0 or channel_len > _MAX_CHANNEL:
                problem = "a channel name of %d bytes" % channel_len
            elif offset + _HEADER.size + channel_len + data_len > len(data):
                problem = "a truncated event (%d bytes announced, %d left)" % (
                    channel_len + data_len, len(data) - offset - _HEADER.size)
        if problem is not None:
            message = "%s: damaged at byte %d (event %d): %s" % (path, offset, events, problem)
            if not salvage:
                raise LogError(message + "; read_log(..., salvage=True) keeps the events before it")
            damage = message
            break
        event_offset = offset
        start = offset + _HEADER.size
        channel = data[start:start + channel_len].decode("utf-8", "replace")
        payload = data[start + channel_len:start + channel_len + data_len]
        offset = start + channel_len + data_len
        events += 1
        if channels is not None and channel not in channels:
            continue
        if event_offset in beyond:
            continue
        cls = types.get(payload[:8])
        msg = None
        if cls is not None:
            try:
                msg = cls.decode(payload)
            except Exception:  # a malformed payload is counted, like the rig's own readers do
                msg = None
        if msg is None:
            undecoded[channel] = undecoded.get(channel, 0) + 1
            continue
        messages.setdefault(channel, []).append(msg)
        stamps.setdefault(channel, []).append(utime)
    if events == 0 and damage is None and len(data) > 0:
        raise LogError("%s: not an LCM log" % path)
    decoded = {}
    for channel, msgs in messages.items():
        columns = _columns(msgs)
        columns["log_utime"] = np.asarray(stamps[channel], dtype=np.int64)
        decoded[channel] = columns
    if bounds and bounds["text"]:
        warnings.warn("%s: left out: %s" % (path, bounds["text"]), UserWarning, stacklevel=2)
    if bounds is not None:
        bounds = dict(bounds.pop("beyond_bounds"), text=bounds["text"])
    return RigLog(path, decoded, undecoded, events, damage, bounds)
