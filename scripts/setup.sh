#!/usr/bin/env bash
# Installs the Debian packages the rig needs (only those missing) and builds it.
# Used by scripts/main.sh and scripts/test.sh; safe to run again.
#   BUILD_DIR  build directory (default: build)
#   BUILD_TYPE CMake build type (default: RelWithDebInfo)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
BUILD_TYPE="${BUILD_TYPE:-RelWithDebInfo}"

# Debian bookworm packages: toolchain, LCM (library, tools, Java for lcm-spy),
# jchart2d (lcm-spy's detail plots), glib headers (lcm.pc requires them), Eigen, yaml-cpp,
# Catch2, a JDK for the type jar,
# gnuplot for identification plots, and for real SocketCAN tests: can-utils, iproute2,
# and qemu with xz (tools/canvm/canvm boots Debian's kernel when the host has no vcan);
# python3 for the check that every CTest entry runs one test case (tests/meta), python3-numpy for
# the Python log reader (python/nimble_rig);
# Boost (header-only Boost.Math) for the F and chi-square distributions of the significance tests;
# nlohmann-json (JSON output and reading run reports) and fmt (the run summary's formatting).
PACKAGES=(
  g++ make cmake pkg-config
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev
  libeigen3-dev libyaml-cpp-dev catch2 libboost-dev nlohmann-json3-dev libfmt-dev
  default-jdk-headless
  gnuplot-nox
  can-utils iproute2 qemu-system-x86 xz-utils
  python3 python3-numpy
)

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null || { echo "setup: need root or sudo to install ${missing[*]}" >&2; exit 1; }
    SUDO="sudo"
  fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"
