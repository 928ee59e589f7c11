#!/usr/bin/env bash
# The dashboard in headless Chromium during a real run: `rig run` of the hover scenario in real
# time with its live view (--foxglove) and an injected fault, `rig view --web` serving the page,
# and node/browser_dashboard.mjs checking that the page loads, live data arrives, the plots move
# (their canvases drawn differently a second apart), and the injected fault appears on the page.
#
#   browser_run.sh RIG_BIN SOURCE_DIR BUILD_DIR WORK_DIR
#
# Exits non-zero (with what failed) if any step fails: a missing npm package or browser is a
# failure too, never a skip.
set -euo pipefail
RIG="$1"
SRC="$2"
BUILD="$3"
WORK="$4"
rm -rf "$WORK"
mkdir -p "$WORK"

[[ -d "$BUILD/npm/node_modules/puppeteer-core" ]] || { echo "FAIL: $BUILD/npm/node_modules has no puppeteer-core: run scripts/setup.sh" >&2; exit 1; }
[[ -x /usr/bin/chromium-headless-shell ]] || { echo "FAIL: /usr/bin/chromium-headless-shell is missing: run scripts/setup.sh" >&2; exit 1; }

# Two free ports on the loopback, let go before the servers start.
read -r WS_PORT WEB_PORT <<<"$(/usr/bin/python3 "$SRC/tests/support/free_ports.py" 2)"

pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
}
trap cleanup EXIT

# The page first, so that the browser's first connection finds it.
"$RIG" view --web "127.0.0.1:$WEB_PORT" >"$WORK/view.out" 2>&1 &
pids+=($!)

# 14 s of hover in real time; a garbage fault on the motion capture from 6 s (after the page has
# subscribed), announced on FAULT as "injected ... began".
"$RIG" run "$SRC/rig_configs/hover.yaml" --clock realtime --no-progress --log "$WORK/run.lcmlog" \
  --json "$WORK/summary.json" --foxglove "127.0.0.1:$WS_PORT" \
  --set duration_s=14 \
  --set 'faults=[{target: MOCAP_POSE, kind: garbage, start_s: 6.0, duration_s: 0.5}]' \
  >"$WORK/run.out" 2>&1 &
run_pid=$!
pids+=("$run_pid")

# Both servers listening before the browser starts (a refused connection is a console error).
for port in "$WEB_PORT" "$WS_PORT"; do
  for _ in $(seq 1 100); do
    (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && break
    sleep 0.1
  done
  (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null || {
    echo "FAIL: nothing listens on 127.0.0.1:$port" >&2
    cat "$WORK/run.out" "$WORK/view.out" >&2
    exit 1
  }
done

status=0
node "$BUILD/npm/browser_dashboard.mjs" \
  --url "http://127.0.0.1:$WEB_PORT/?ws=ws://127.0.0.1:$WS_PORT" \
  --expect-fault "began" --timeout 30 --screenshots "$WORK/screenshots" >"$WORK/browser.json" || status=$?
cat "$WORK/browser.json"
if [[ $status -ne 0 ]]; then
  echo "FAIL: the browser check failed (exit $status)" >&2
  cat "$WORK/run.out" >&2
  exit 1
fi

# The run line's rig time is the run's (garbage on the bus must not move it).
python3 - "$WORK/browser.json" <<'PY' || exit 1
import json, re, sys
report = json.load(open(sys.argv[1]))
text = report["verdict"]["text"]
times = [float(x) for x in re.findall(r"([0-9]+(?:\.[0-9]+)?) s", text)]
if not times or not all(0 <= t <= 15 for t in times):
    sys.exit("FAIL: the run line %r does not hold the run's rig time (0-15 s)" % text)
PY

run_status=0
wait "$run_pid" || run_status=$?
cat "$WORK/run.out"
if [[ $run_status -ne 0 ]]; then
  echo "FAIL: rig run exited $run_status" >&2
  exit 1
fi
echo "PASS: the page showed the live run and its injected fault"
