#!/bin/sh
# The dashboard page on a replayed log, in headless Chromium: `rig view LOG --foxglove 0 --web 0`
# serves the log and the page, tests/dashboard/node/browser_dashboard.mjs opens the page and checks
# that it connects, plots truth and estimate, moves and shows the replay on its run line.
#
#   dashboard_replay.sh RIG NPM_DIR SOURCE_DIR
set -eu
rig=$1 npm=$2 src=$3
if [ ! -d "$npm/node_modules/puppeteer-core" ] || [ ! -f "$npm/browser_dashboard.mjs" ]; then
  echo "dashboard_replay: no npm packages or browser_dashboard.mjs in $npm: run scripts/setup.sh" >&2
  exit 1
fi
dir=$(mktemp -d "${TMPDIR:-/tmp}/rig_dashboard_replay.XXXXXX")
view=
cleanup() {
  [ -n "$view" ] && kill "$view" 2>/dev/null && wait "$view" 2>/dev/null
  rm -rf "$dir"
}
trap cleanup EXIT
"$rig" run "$src/rig_configs/hover.yaml" --clock inprocess --set duration_s=20 --no-progress \
  --log "$dir/hover.lcmlog" >"$dir/run.txt" 2>&1
"$rig" view "$dir/hover.lcmlog" --foxglove 127.0.0.1:0 --web 0 --speed 1 >"$dir/view.out" 2>"$dir/view.err" &
view=$!
url=
for _ in $(seq 100); do
  url=$(sed -n 's/^rig view: dashboard on \(http[^ ]*\)$/\1/p' "$dir/view.err")
  [ -n "$url" ] && break
  sleep 0.1
done
if [ -z "$url" ]; then
  echo "dashboard_replay: rig view printed no page URL:" >&2
  cat "$dir/view.err" >&2
  exit 1
fi
node "$npm/browser_dashboard.mjs" --url "$url" --expect-verdict replaying --timeout 20
