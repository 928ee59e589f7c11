"""nimble_rig.subscribe (python/nimble_rig/live.py, python/py_subscribe.cc): a real-time `rig run`
read live from Python, as lcm-spy reads it. The run and the reader share a private network
namespace made here (unshare -n, its loopback given multicast), so that parallel tests do not hear
each other; the run is told to stay in it (run.network_namespace: never)."""
import ast
import os
import subprocess
import sys
import textwrap

import nimble_rig

SOURCE = os.environ["RIG_SOURCE_DIR"]
RIG = os.environ["RIG_BIN"]
URL = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"  # the rig's own, kernel buffer and all
READER = textwrap.dedent("""
    import subprocess, sys
    import nimble_rig
    rig, scenario, url = sys.argv[1:4]
    run = subprocess.Popen([rig, "run", scenario, "--clock", "realtime", "--no-progress", "--set", "duration_s=2",
                            "--set", "run.network_namespace=never", "--set", "run.lcm_url=" + url],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    seen = {}
    for channel, message in nimble_rig.subscribe(["TRUTH", "ACTUATOR_CMD"], url=url, timeout_s=5):
        seen.setdefault(channel, []).append(message.utime)
    _, err = run.communicate()
    assert run.returncode == 0, err
    print(repr({c: (len(u), u[0], u[-1], all(b > a for a, b in zip(u, u[1:]))) for c, u in seen.items()}))
""")


def test_subscribe_reads_a_real_time_run_as_it_flies():
    setup = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"
    done = subprocess.run(["unshare", "-n", "sh", "-c", setup + ' && exec "$0" -c "$1" "$2" "$3" "$4"',
                           sys.executable, READER, RIG, os.path.join(SOURCE, "rig_configs", "hover.yaml"), URL],
                          capture_output=True, text=True, timeout=120, env=os.environ)
    assert done.returncode == 0, "needs root for unshare -n (CI runs as root): " + done.stderr[-2000:]
    seen = ast.literal_eval(done.stdout.strip().splitlines()[-1])
    assert set(seen) == {"TRUTH", "ACTUATOR_CMD"}  # the channels asked for, nothing else
    truth, cmd = seen["TRUTH"], seen["ACTUATOR_CMD"]
    assert truth[3] and cmd[3]  # each in the order it was stamped
    assert truth[0] >= 1990 and truth[2] >= 1_990_000  # the whole run: 1 kHz for 2 s
    assert cmd[0] >= 1000  # 512 Hz


def test_subscribe_stops_when_nothing_comes_and_names_a_bad_url():
    assert list(nimble_rig.subscribe(["TRUTH"], url="memq://", timeout_s=0.1)) == []
    try:
        list(nimble_rig.subscribe(["TRUTH"], url="nonesuch://x", timeout_s=0.1))
    except RuntimeError as e:
        assert "nonesuch://x" in str(e)
    else:
        raise AssertionError("a bad URL was taken")
