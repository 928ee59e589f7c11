#!/usr/bin/env bash
# canvm run --out DIR: what the command writes under DIR inside the VM lands on the host, and
# nothing else it writes does (the host is read-only to the guest).
#   check_canvm_out.sh <canvm>
set -euo pipefail
CANVM="$1"
OUT="$(mktemp -d /tmp/canvm_out_XXXXXX)"
trap 'rm -rf "$OUT"' EXIT
"$CANVM" run --timeout 120 --out "$OUT" -- sh -c \
  "echo written-in-the-guest > $OUT/result.txt && ip -o link show vcan0 > $OUT/vcan0.txt && echo lost > $OUT.elsewhere"
grep -qx written-in-the-guest "$OUT/result.txt" || { echo "canvm --out: result.txt did not reach the host"; exit 1; }
grep -q "vcan0" "$OUT/vcan0.txt" || { echo "canvm --out: the guest's vcan0 listing did not reach the host"; exit 1; }
[[ ! -e "$OUT.elsewhere" ]] || { echo "canvm --out: a file outside DIR reached the host"; rm -f "$OUT.elsewhere"; exit 1; }
echo "canvm --out: the guest's files under $OUT are on the host; a file outside it is not"
