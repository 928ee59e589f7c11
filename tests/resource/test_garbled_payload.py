"""Garbage that decodes is named, from Python: a log with one TRUTH event's values scrambled
(after its fingerprint and time) through nimble_rig's readers: read_log and export_mcap leave the
message out with a UserWarning naming its channel, field, time and count (export_mcap(strict=True)
raises), identify, validate and discrepancy raise DataError with the command line's message; a
record of zeros is refused by every analysis with one message (ident/data_check.h). Run by CTest
as resource.garbled.python; test_garbled_payload.cc holds the command line's readers."""
import os
import struct
import tempfile
import warnings

import numpy as np
import pytest

import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
MODEL = os.path.join(SOURCE, "rig_configs", "models", "nimble_lateral_set1.yaml")
VEHICLE = os.path.join(SOURCE, "rig_configs", "vehicles", "nimble_no_wifi.yaml")
HEADER = struct.Struct(">IqqII")


@pytest.fixture(scope="module")
def folder():
    path = tempfile.mkdtemp(prefix="rig_garbled_python_")
    yield path
    for name in os.listdir(path):
        os.remove(os.path.join(path, name))
    os.rmdir(path)


@pytest.fixture(scope="module")
def garbled(folder):
    """A 3 s hover flown in process, its middle TRUTH event's bytes after fingerprint and utime
    reversed: (log path, the event's time [s], TRUTH messages in the clean log)."""
    clean = os.path.join(folder, "hover.lcmlog")
    scenario = nimble_rig.load_scenario(os.path.join(SOURCE, "rig_configs", "hover.yaml"), {"duration_s": 3})
    nimble_rig.fly(scenario, log=clean)
    data = bytearray(open(clean, "rb").read())
    offset, truth = 0, []
    while offset < len(data):
        _sync, _number, _stamp, channel_len, data_len = HEADER.unpack_from(data, offset)
        start = offset + HEADER.size
        if data[start:start + channel_len] == b"TRUTH":
            truth.append((start + channel_len, data_len))
        offset = start + channel_len + data_len
    payload, size = truth[len(truth) // 2]
    data[payload + 16:payload + size] = bytes(reversed(data[payload + 16:payload + size]))
    path = os.path.join(folder, "garbled.lcmlog")
    open(path, "wb").write(data)
    return path, struct.unpack_from(">q", data, payload + 8)[0] * 1e-6, len(truth)


def named(text, t_s):
    assert "TRUTH " in text
    assert "beyond the physical bound" in text
    assert "at t = %.4f s" % t_s in text
    assert "vehicle file " + VEHICLE in text


def test_read_log_and_export_mcap_leave_the_message_out_naming_it(garbled, folder):
    path, t_s, messages = garbled
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        log = nimble_rig.read_log(path)
        result = nimble_rig.export_mcap(path, os.path.join(folder, "g.mcap"))
    texts = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert len(texts) == 2
    for text in texts:
        assert text.startswith(path + ": left out: 1 message with ")
        named(text, t_s)
    assert len(log["TRUTH"]["utime"]) == messages - 1
    assert log.beyond_bounds["messages"] == 1
    assert log.beyond_bounds["channels"][0]["channel"] == "TRUTH"
    assert all(abs(x) <= 50 for x in log["TRUTH"]["omega_body_radps"].ravel())
    assert result["beyond_bounds_messages"] == 1
    assert result["channels"]["TRUTH"]["beyond_bounds"] == 1
    assert result["channels"]["TRUTH"]["json"] == messages - 1
    with pytest.raises(nimble_rig.DataError) as e:
        nimble_rig.export_mcap(path, os.path.join(folder, "strict.mcap"), strict=True)
    named(str(e.value), t_s)
    assert not os.path.exists(os.path.join(folder, "strict.mcap"))


def test_the_analyses_refuse_the_log_with_the_command_lines_message(garbled):
    path, t_s, _ = garbled
    calls = [lambda: nimble_rig.identify(path, states="truth"),
             lambda: nimble_rig.validate(MODEL, path, states="truth"),
             lambda: nimble_rig.discrepancy(path, model=MODEL, states="truth")]
    messages = []
    for call in calls:
        with pytest.raises(nimble_rig.DataError) as e:
            call()
        named(str(e.value), t_s)
        messages.append(str(e.value))
    assert messages[0].startswith("refused: " + path + ": TRUTH ")
    assert len(set(messages)) == 1


def test_a_record_of_zeros_is_refused_by_every_analysis_with_one_message():
    t = np.arange(3072) / 512.0
    zeros = {"t": t, **{c: np.zeros_like(t) for c in ("p", "v", "phi", "delta_f", "delta_t")}}
    calls = [lambda: nimble_rig.identify(zeros), lambda: nimble_rig.validate(MODEL, zeros),
             lambda: nimble_rig.discrepancy(zeros, model=MODEL), lambda: nimble_rig.discrepancy([zeros, zeros], model=MODEL)]
    for call in calls:
        with pytest.raises(nimble_rig.DataError) as e:
            call()
        assert str(e.value) == ("refused: data (dict of arrays): no excitation: p is zero throughout (3072 samples); "
                                "nothing can be identified, validated or found in a record that does not move")
