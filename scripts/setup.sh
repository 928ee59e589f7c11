#!/usr/bin/env bash
# Installs the Debian packages the rig needs (only those missing) and builds it.
# Used by scripts/main.sh and scripts/test.sh; safe to run again.
#   BUILD_DIR  build directory (default: build)
#   BUILD_TYPE CMake build type (default: RelWithDebInfo)
#   SANITIZE   1: the clang build with AddressSanitizer, UndefinedBehaviorSanitizer and the
#              libFuzzer targets of fuzz/ (cmake/Sanitizers.cmake); use its own BUILD_DIR
#   TARGETS    build only these targets (space separated; default: all)
#   PROFILE    all (default): every package the tests need; main: only what building and flying
#              the rig needs (scripts/main.sh): no browser, Slurm, qemu, gnuplot, numpy or npm
#              packages (the dashboard page is then left out with a note)
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
# nlohmann-json (JSON output and reading run reports), fmt (the run summary's formatting) and
# CLI11 (the command lines of the rig tool, its processes, benchmarks and tools);
# zstd and zlib (MCAP export: chunk compression and CRC-32), Debian's headless Chromium (the
# dashboard's browser test); Node.js and npm (below) for the viewers' assets and their readers;
# Slurm (slurm-wlm: slurmctld, slurmd and the client commands) with munge for `rig sweep
# --backend slurm` and the test that brings up a one-node cluster (tests/cluster).
# ccache: compiled objects reused across builds (CMakeLists.txt, RIG_CCACHE).
PROFILE="${PROFILE:-all}"
PACKAGES=(
  g++ make cmake pkg-config ccache
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev
  libeigen3-dev libyaml-cpp-dev catch2 libboost-dev nlohmann-json3-dev libfmt-dev libcli11-dev
  default-jdk-headless
  iproute2
  libzstd-dev zlib1g-dev
)
case "$PROFILE" in
  main) ;;
  all)
    PACKAGES+=(gnuplot-nox can-utils qemu-system-x86 xz-utils python3 python3-numpy chromium-headless-shell
               slurm-wlm munge
               # the layout check of every C++ source against .clang-format (meta.format)
               clang-format
               # the rig from Python: the compiled module (python/), its tests (scipy.signal checks the
               # loop analysis; a loop's discrete state space as scipy.signal.dlti; a channel as a
               # pandas DataFrame) and the notebook in docs/ (executed by nbconvert, plots by matplotlib)
               pybind11-dev python3-dev python3-pytest python3-scipy python3-pandas python3-matplotlib python3-yaml
               jupyter-nbconvert python3-ipykernel)
    # Node.js with npm: Debian's nodejs and npm, unless a Node.js with npm is already installed.
    command -v npm >/dev/null 2>&1 || PACKAGES+=(nodejs npm)
    ;;
  *) echo "setup: PROFILE must be main or all, not '$PROFILE'" >&2; exit 2 ;;
esac
CMAKE_ARGS=()
if [[ "${SANITIZE:-0}" == 1 ]]; then
  # clang, its sanitizer and libFuzzer runtimes, and llvm-symbolizer for readable reports.
  PACKAGES+=(clang-14 libclang-rt-14-dev llvm-14)
  # Unity builds of the libraries and programs (RIG_UNITY in CMakeLists.txt): a third less time.
  CMAKE_ARGS+=(-DCMAKE_CXX_COMPILER=clang++-14 -DRIG_SANITIZE=ON -DRIG_FUZZ=ON -DRIG_UNITY=ON)
fi

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

# The npm packages of tools/npm/package-lock.json in $BUILD_DIR/npm: the dashboard's plotting
# library (copied into the build's web assets) and, for the tests, the MCAP reader, the Foxglove
# WebSocket client and puppeteer-core. Installed again only when the lock file changed.
if [[ "${SANITIZE:-0}" != 1 && "$PROFILE" == all ]]; then
  NPM_DIR="$BUILD_DIR/npm"
  if ! cmp -s "$ROOT/tools/npm/package-lock.json" "$NPM_DIR/package-lock.json" || [[ ! -d "$NPM_DIR/node_modules" ]]; then
    mkdir -p "$NPM_DIR"
    cp "$ROOT/tools/npm/package.json" "$ROOT/tools/npm/package-lock.json" "$NPM_DIR/"
    echo "setup: npm ci in $NPM_DIR"
    (cd "$NPM_DIR" && npm ci --no-audit --no-fund --loglevel=error) || { echo "setup: npm ci failed in $NPM_DIR (the npm registry must be reachable)" >&2; exit 1; }
  fi
fi

# ccache (CMakeLists.txt, RIG_CCACHE): paths below the checkout are hashed relative to it and the
# build directory is left out of the hash, so a fresh clone of the rig in another folder of this
# machine (CI's) reuses the objects compiled here instead of compiling everything again. A reused
# object's debug information names the folder it was first compiled in.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$ROOT}"
export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"
cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" "${CMAKE_ARGS[@]}" >/dev/null
if [[ -n "${TARGETS:-}" ]]; then
  # shellcheck disable=SC2086  # a list of target names
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target ${TARGETS}
else
  cmake --build "$BUILD_DIR" -j "$(nproc)"
fi
