#!/bin/sh
# The dashboard page on a replayed log, in headless Chromium: `rig view LOG --foxglove 0 --web 0`
# serves a 12 s hover log and the page, and tests/dashboard/node/browser_dashboard.mjs opens it.
#
#   dashboard_replay.sh RIG NPM_DIR SOURCE_DIR live|late
#
# live: the log replayed at its pace, again and again (--loop: the page sees it move however late
#       the browser starts): the page connects, plots truth and estimate, moves, and its run line
#       shows the replay.
# late: the log replayed as fast as it reads and the page opened after the replay ended (rig view
#       holds the last state): the page plots truth and estimate over the last 10 s of rig time,
#       and its run line says the replay is done.
set -eu
rig=$1 npm=$2 src=$3 mode=$4
case $mode in
  live) view_args="--speed 1 --loop" ready="live view on" ;;
  late) view_args="--speed 0" ready="holding the last state" ;;
  *) echo "dashboard_replay: mode live or late, not '$mode'" >&2; exit 2 ;;
esac
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
"$rig" run "$src/rig_configs/hover.yaml" --clock inprocess --set duration_s=12 --no-progress \
  --log "$dir/hover.lcmlog" >"$dir/run.txt" 2>&1
# shellcheck disable=SC2086
"$rig" view "$dir/hover.lcmlog" --foxglove 127.0.0.1:0 --web 0 $view_args >"$dir/view.out" 2>"$dir/view.err" &
view=$!
url=
for _ in $(seq 100); do
  if grep -q "$ready" "$dir/view.err"; then
    url=$(sed -n 's/^rig view: dashboard on \(http[^ ]*\)$/\1/p' "$dir/view.err")
  fi
  [ -n "$url" ] && break
  sleep 0.1
done
if [ -z "$url" ]; then
  echo "dashboard_replay: rig view printed no page URL and '$ready':" >&2
  cat "$dir/view.err" >&2
  exit 1
fi
if [ "$mode" = live ]; then
  node "$npm/browser_dashboard.mjs" --url "$url" --expect-verdict replaying --timeout 20
else
  node "$npm/browser_dashboard.mjs" --url "$url" --still --expect-span 9.9 --expect-verdict replayed --timeout 20
fi
