#!/usr/bin/env bash
# Time tdcr side by side with the paper's own code, in one run on this machine (bench_side_by_side,
# benchmarks/paper_code/bench_side_by_side.cpp says what it measures).
#
#   bash benchmarks/side_by_side.sh PAPER_CODE_DIR [OUT_DIR] [BENCH_ARGS...]
#
# PAPER_CODE_DIR: a checkout of the paper's code (MIT licence) at the commit of the reference data:
#   git clone https://github.com/SvenLilge/tdcr-modeling.git PAPER_CODE_DIR
#   git -C PAPER_CODE_DIR checkout 379d34a68c47d95629eb59e8d8ad9965f66947c0
# It is built from there; nothing of it is copied into tdcr. It needs GSL (Debian 12:
# apt-get install libgsl-dev) besides tdcr's own dependencies.
# OUT_DIR: default docs/benchmark-results; then docs/benchmarks.md is regenerated from the tables
# too (benchmarks/make_report.py), as benchmarks/run_all.sh does.
# BENCH_ARGS: passed on, e.g. --cases 4 --repeat 5 --models vc,ccsub or tdcr's options as a
# scene file's solver object: --solver '{"tip_tolerance": 1e-9}'.
# Environment: BUILD_DIR (default build; configured with -DTDCR_PAPER_CODE_DIR added, Release; the
# option stays in its cache until -DTDCR_PAPER_CODE_DIR= clears it),
# JOBS (default 2). Only bench_side_by_side and what it links are built. Paths other than
# PAPER_CODE_DIR are taken from the repository's root.
# The load average before and after goes to OUT_DIR/side_by_side_load.txt (and into the tables'
# first lines). The two codes' solves alternate, but other jobs preempt the paper code's long
# solves more than tdcr's short ones: compare the wall-time and CPU-time speed-ups, and prefer a
# run alone on the machine.
set -euo pipefail
if [ $# -lt 1 ] || [ ! -d "$1" ]; then
  sed -n '2,23p' "$0"
  exit 2
fi
paper=$(cd "$1" && pwd)
shift
cd "$(dirname "$0")/.."
out=docs/benchmark-results
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then out=$1; shift; fi
build=${BUILD_DIR:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DTDCR_PAPER_CODE_DIR="$paper" >/dev/null
cmake --build "$build" -j "${JOBS:-2}" --target bench_side_by_side
mkdir -p "$out"
snapshot() {
  echo "== $1: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  uptime
  # top's second frame: the CPU line of its first is not a measurement.
  top -bn2 -d 0.5 -o %CPU | awk '/^top -/ { n++ } n == 2' | sed -n '1,5p;7,12p'
}
snapshot before >"$out/side_by_side_load.txt"
"$build/bin/bench_side_by_side" --out "$out" "$@"
snapshot after >>"$out/side_by_side_load.txt"
cat "$out/side_by_side_load.txt"
if [ "$out" = docs/benchmark-results ]; then
  py=/usr/bin/python3; [ -x "$py" ] || py=python3
  "$py" benchmarks/make_report.py "$out" benchmarks/report_template.md docs/benchmarks.md
fi
echo "results in $out"
