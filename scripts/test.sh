#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test through CTest; then the sanitizer pass:
# builds the clang build with AddressSanitizer, UndefinedBehaviorSanitizer and the libFuzzer
# targets (build-san/, cmake/Sanitizers.cmake), only what the pass runs (target sanitizer_pass),
# and runs the unit, functional and fuzz tests there, less those labelled heavy (over 15 s each
# under the sanitizers; the first pass runs them).
# Exits non-zero on any failure in either pass. Extra arguments go to the first pass's ctest
# (e.g. -L unit); with arguments the sanitizer pass is left out unless SANITIZE_PASS=1.
#   BUILD_DIR      build directory of the first pass (default: build)
#   SAN_BUILD_DIR  build directory of the sanitizer pass (default: build-san)
#   SANITIZE_PASS  1: always run the sanitizer pass, 0: never (default: only without arguments)
# Each pass's tests write their files under <build dir>/test-tmp (TMPDIR), emptied when the pass
# starts: a test removes its files when it passes and keeps them when it fails (the path is in its
# output), so what is left there after a pass is what failed tests wrote, until the next run.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
SAN_BUILD_DIR="${SAN_BUILD_DIR:-$ROOT/build-san}"
SANITIZE_PASS="${SANITIZE_PASS:-$([[ $# -eq 0 ]] && echo 1 || echo 0)}"
export BUILD_DIR
"$ROOT/scripts/setup.sh"

# Runs ctest in build directory $1 with the other arguments, TMPDIR a fresh <$1>/test-tmp.
run_ctest() {
  local dir="$1"
  shift
  rm -rf "$dir/test-tmp"
  mkdir -p "$dir/test-tmp"
  local rc=0
  TMPDIR="$dir/test-tmp" ctest --test-dir "$dir" --output-on-failure -j "$(nproc)" "$@" || rc=$?
  local left
  left="$(du -sh "$dir/test-tmp" 2>/dev/null | cut -f1)"
  if [[ -n "$(ls -A "$dir/test-tmp")" ]]; then
    echo "== files left in $dir/test-tmp by failed tests or by processes the tests killed: $left"
  fi
  leftover_processes "$dir" || rc=1
  return "$rc"
}

# After a pass, no process of the rig's own executables (<build dir>/bin) may still run: each test
# ends what it started (tests/catch_main.cc reaps what a case left). Names, kills and fails on any.
leftover_processes() {
  local bin
  bin="$(cd "$1" && pwd)/bin/"
  local found=0 pid exe
  for pid in $(ls /proc | grep -E '^[0-9]+$'); do
    exe="$(readlink "/proc/$pid/exe" 2>/dev/null)" || continue
    [[ "$exe" == "$bin"* ]] || continue
    echo "== a process outlived the tests: pid $pid: $(tr '\0' ' ' < "/proc/$pid/cmdline" 2>/dev/null)"
    kill -9 "$pid" 2>/dev/null || true
    found=1
  done
  return "$found"
}

# The tests a pass failed, named again at the very end of the run: the first pass's list would
# otherwise scroll away under the sanitizer pass's output.
failed_list() {
  local file="$1/Testing/Temporary/LastTestsFailed.log"
  [[ -s "$file" ]] || return 0
  echo "== $2 failed:"
  sed 's/^/==   /' "$file"
}

status=0
first_status=0
run_ctest "$BUILD_DIR" "$@" || first_status=$?
status=$first_status

if [[ "$SANITIZE_PASS" == 1 ]]; then
  start=$(date +%s)
  echo "== sanitizer pass: ASan + UBSan build in $SAN_BUILD_DIR, ctest -L 'unit|functional|fuzz' -LE heavy"
  BUILD_DIR="$SAN_BUILD_DIR" SANITIZE=1 TARGETS=sanitizer_pass "$ROOT/scripts/setup.sh"
  # Leaks and undefined behaviour fail the test that shows them; reports name file and line.
  export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1}"
  export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
  export ASAN_SYMBOLIZER_PATH="${ASAN_SYMBOLIZER_PATH:-/usr/lib/llvm-14/bin/llvm-symbolizer}"
  san_status=0
  run_ctest "$SAN_BUILD_DIR" -L 'unit|functional|fuzz' -LE heavy || san_status=$?
  echo "== sanitizer pass took $(( $(date +%s) - start )) s"
  [[ "$san_status" == 0 ]] || status=$san_status
  [[ "$first_status" == 0 ]] || failed_list "$BUILD_DIR" "the first pass (exit $first_status)"
  [[ "$san_status" == 0 ]] || failed_list "$SAN_BUILD_DIR" "the sanitizer pass (exit $san_status)"
fi
exit "$status"
