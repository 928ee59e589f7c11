#!/usr/bin/env bash
# Installs the build into a fresh prefix and uses it as a lab would: flies a scenario with the
# installed rig and its installed configs, builds a consumer project with find_package and
# another with pkg-config, and reads the flight's log from Python with the installed packages.
#   check_install.sh <build dir> <source dir>
set -euo pipefail
BUILD="$1"
SRC="$2"
WORK="$(mktemp -d /tmp/rig_install_XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
PREFIX="$WORK/prefix"

cmake --install "$BUILD" --prefix "$PREFIX" > "$WORK/install.log"
for f in bin/rig bin/nimble_plant lib/libnimble_ident.a include/nimble_rig/nimble/truth_state_t.hpp \
         include/nimble_rig/nimble/rig_message_list.hpp \
         include/nimble_rig/ident/identify.h lib/cmake/nimble_rig/nimble_rigConfig.cmake \
         lib/pkgconfig/nimble_rig.pc share/java/nimble_lcmtypes.jar share/nimble_rig/nimble_rig.dbc \
         share/nimble_rig/lcmtypes/truth_state_t.lcm share/nimble_rig/rig_configs/hover.yaml \
         lib/python3/dist-packages/nimble/truth_state_t.py lib/python3/dist-packages/nimble_rig/log.py; do
  [[ -e "$PREFIX/$f" ]] || { echo "install: $f is missing from the prefix"; exit 1; }
done
echo "install: every expected file is in $PREFIX"

# The installed rig flies an installed scenario (in process: no network needed).
"$PREFIX/bin/rig" run "$PREFIX/share/nimble_rig/rig_configs/hover.yaml" --clock inprocess --set duration_s=1 \
  --log "$WORK/hover.lcmlog" --no-progress > "$WORK/run.out"
echo "install: the installed rig flew hover"
MODEL="$PREFIX/share/nimble_rig/rig_configs/models/nimble_lateral_set1.yaml"

# find_package(nimble_rig)
cmake -S "$SRC/tests/install/consumer" -B "$WORK/consumer" -DCMAKE_PREFIX_PATH="$PREFIX" > "$WORK/consumer.log"
cmake --build "$WORK/consumer" -j 2 >> "$WORK/consumer.log"
"$WORK/consumer/consumer" "$WORK/hover.lcmlog" "$MODEL"

# pkg-config
PKG_CONFIG_PATH="$PREFIX/lib/pkgconfig" g++ -std=c++17 -o "$WORK/consumer_pc" "$SRC/tests/install/consumer/main.cc" \
  $(PKG_CONFIG_PATH="$PREFIX/lib/pkgconfig" pkg-config --cflags --libs nimble_rig)
"$WORK/consumer_pc" "$WORK/hover.lcmlog" "$MODEL"
echo "install: pkg-config consumer built and ran"

# Python: Debian's interpreter (python3-numpy is installed for it), the installed packages.
PYTHONPATH="$PREFIX/lib/python3/dist-packages" /usr/bin/python3 - "$WORK/hover.lcmlog" <<'PY'
import sys
from nimble_rig import read_log, LogError
log = read_log(sys.argv[1])
truth = log["TRUTH"]
n = len(truth["utime"])
assert n == 1001, n
assert truth["euler_rad"].shape == (n, 3), truth["euler_rad"].shape
assert abs(truth["utime"][-1] - 1000000) <= 1000, truth["utime"][-1]
assert abs(truth["euler_rad"][:, 0]).max() < 0.2
assert "ESTIMATE" in log and "IMU" in log
# A damaged log names where; salvage keeps what precedes.
data = open(sys.argv[1], "rb").read()
cut = sys.argv[1] + ".cut"
open(cut, "wb").write(data[: len(data) // 2])
try:
    read_log(cut)
    raise SystemExit("a truncated log was read without an error")
except LogError as e:
    assert "damaged at byte" in str(e), e
half = read_log(cut, salvage=True)
assert 0 < len(half["TRUTH"]["utime"]) < n and half.damage
print("install: Python read %d TRUTH samples, phi max %.4f rad; a cut log is refused and salvaged"
      % (n, abs(truth["euler_rad"][:, 0]).max()))
PY

# The compiled module, where the build had pybind11: the installed package flies the installed
# scenario in process and gives the installed rig's TRUTH.
if compgen -G "$BUILD/python/nimble_rig/_rig*.so" > /dev/null; then
  PYTHONPATH="$PREFIX/lib/python3/dist-packages" /usr/bin/python3 - "$PREFIX" "$WORK/hover.lcmlog" <<'PY'
import sys
import numpy as np
import nimble_rig
from nimble_rig import _rig
prefix, log = sys.argv[1], sys.argv[2]
assert _rig.__file__.startswith(prefix), _rig.__file__
flight = nimble_rig.fly(nimble_rig.load_scenario(prefix + "/share/nimble_rig/rig_configs/hover.yaml", {"duration_s": 1}))
np.testing.assert_array_equal(flight.channels["TRUTH"]["euler_rad"], nimble_rig.read_log(log)["TRUTH"]["euler_rad"])
print("install: the installed nimble_rig._rig flew hover with the installed rig's TRUTH")
PY
else
  echo "install: nimble_rig._rig was not built here (no pybind11): its installed copy is not checked"
fi
