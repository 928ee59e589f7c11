#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan, in build-san/; installs clang if missing) and
# runs each for a time budget, then prints executions, time, crashes and exit status per target.
# Exits non-zero on any crash. Arguments go to tools/fuzz/fuzz.py:
#   scripts/fuzz.sh                          # every target, 60 s each
#   scripts/fuzz.sh --time 600 --jobs 2      # every target, 10 min each, two at a time
#   scripts/fuzz.sh --time 0 --runs 1000000  # every target, one million executions each
#   scripts/fuzz.sh --time 30 fuzz_candump   # one target
#   SAN_BUILD_DIR  build directory (default: build-san)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SAN_BUILD_DIR="${SAN_BUILD_DIR:-$ROOT/build-san}"
BUILD_DIR="$SAN_BUILD_DIR" SANITIZE=1 TARGETS=fuzz_targets "$ROOT/scripts/setup.sh"
export ASAN_SYMBOLIZER_PATH="${ASAN_SYMBOLIZER_PATH:-/usr/lib/llvm-14/bin/llvm-symbolizer}"
exec python3 "$ROOT/tools/fuzz/fuzz.py" --build-dir "$SAN_BUILD_DIR" "$@"
