#!/usr/bin/env bash
# The rig's main job: installs what is missing, builds, and flies the identification
# doublet train (7 and 4 Hz, fast gains, set-1 model) in real time: plant and attitude
# controller as separate processes over LCM, in a private network namespace, recorded
# to an LCM log, with the run summary at the end. Extra arguments go to `rig run`
# (for example --clock lockstep, --set plant.effects.lateral_gust.enabled=true).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
export BUILD_DIR
# Only what the main job needs: its packages (PROFILE=main) and the rig with its processes (the
# target rig depends on them), not the tests and benchmarks.
PROFILE=main TARGETS=rig "$ROOT/scripts/setup.sh"
cd "$ROOT"
exec "$BUILD_DIR/bin/rig" run rig_configs/id_doublet_train_fast.yaml "$@"
