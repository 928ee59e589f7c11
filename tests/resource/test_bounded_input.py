"""Inputs bounded before they are read, from Python: /dev/zero and a FIFO given to nimble_rig's
readers (identify, validate, discrepancy, export_mcap, load_scenario and the pure-Python
read_log) are refused at once, naming the path, instead of read until memory runs out or waited
on for ever (core/input_file.h). Run by CTest as resource.bounded_input.python."""
import os
import tempfile

import pytest

import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
MODEL = os.path.join(SOURCE, "rig_configs", "models", "nimble_lateral_set1.yaml")


@pytest.fixture
def folder():
    path = tempfile.mkdtemp(prefix="rig_bounded_python_")
    yield path
    for name in os.listdir(path):
        os.remove(os.path.join(path, name))
    os.rmdir(path)


def bad_file(kind, folder):
    if kind == "/dev/zero":
        return "/dev/zero", "is not a regular file (a character device)"
    path = os.path.join(folder, "pipe.fifo")
    os.mkfifo(path)
    return path, "is not a regular file (a FIFO)"


@pytest.mark.parametrize("kind", ["/dev/zero", "fifo"])
def test_the_module_refuses_a_file_that_is_no_regular_file_naming_it(kind, folder):
    path, problem = bad_file(kind, folder)
    calls = {
        "identify": lambda: nimble_rig.identify(path),
        "validate": lambda: nimble_rig.validate(MODEL, path),
        "discrepancy": lambda: nimble_rig.discrepancy(path, model=MODEL),
        "export_mcap": lambda: nimble_rig.export_mcap(path, os.path.join(folder, "out.mcap")),
    }
    for name, call in calls.items():
        with pytest.raises(nimble_rig.DataError) as caught:
            call()
        assert caught.value.source == path, name
        assert problem in str(caught.value), name
    with pytest.raises(nimble_rig.ConfigError) as caught:
        nimble_rig.validate(path, os.path.join(SOURCE, "rig_configs", "hover.yaml"))
    assert caught.value.file == path and problem in str(caught.value)
    with pytest.raises(nimble_rig.ConfigError) as caught:
        nimble_rig.load_scenario(path)
    assert caught.value.file == path and problem in str(caught.value)
    with pytest.raises(nimble_rig.LogError) as caught:
        nimble_rig.read_log(path)
    assert str(caught.value) == path + " " + problem
    assert not os.path.exists(os.path.join(folder, "out.mcap"))
