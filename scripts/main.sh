#!/usr/bin/env bash
# The rig's main job: installs what is missing, builds, and prints the model
# report of identification set 1 with the published comparison of all five sets.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
export BUILD_DIR
"$ROOT/scripts/setup.sh"
RIG="$BUILD_DIR/bin/rig"

"$RIG" model "$ROOT/rig_configs/models/nimble_lateral_set1.yaml"
echo
echo "== identified sets 1-5 against thesis Table 9.5 =="
for k in 1 2 3 4 5; do
  "$RIG" model "$ROOT/rig_configs/models/nimble_lateral_set$k.yaml" \
    | awk -v k="$k" '/^eigenvalues/ {on=1; printf "set %s computed:", k; next}
                     on && NF == 0 {on=0; next}
                     on {printf "  %s", $0}
                     /largest difference/ {printf "\n         %s\n", $0}'
done
