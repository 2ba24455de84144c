#!/usr/bin/env bash
# The viewer's latency, measured in the browser: from a slider move (an input event on the first
# tendon's slider) to the new picture (the animation frame after the answer was drawn), one move at
# a time, per model, on the paper robot at n = 10 (examples/paper_robot_vc.json), each move a
# warm-started solve with the scene's (default) solver options.
#   bash benchmarks/bench_viewer.sh BUILD_DIR [MOVES]
set -euo pipefail
build=${1:?usage: bench_viewer.sh BUILD_DIR [MOVES]}
moves=${2:-100}
here=$(cd "$(dirname "$0")/.." && pwd)
node "$here/viewer/tests/check_viewer.mjs" --cli "$build/bin/tdcr" --scene "$here/examples/paper_robot_vc.json" \
  --out "$build/viewer_bench" --bench ccsub,prb,vc,vcref --moves "$moves"
