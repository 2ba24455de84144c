#!/usr/bin/env bash
# Regenerate every benchmark table and figure of docs/benchmarks.md.
#
#   bash benchmarks/run_all.sh [--quick] [BUILD_DIR] [OUT_DIR]
#
# BUILD_DIR defaults to build (configured and built already), OUT_DIR to docs/benchmark-results
# (then docs/benchmarks.md is regenerated from the tables too).
# --quick runs the short sweep (seconds to a minute) instead of the full one.
set -euo pipefail
quick=""
if [ "${1:-}" = "--quick" ]; then quick="--quick"; shift; fi
build=${1:-build}
out=${2:-docs/benchmark-results}
mkdir -p "$out"
py=/usr/bin/python3; [ -x "$py" ] || py=python3
{
  echo "# machine: $(uname -m), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
  echo "# date: $(date -u +%Y-%m-%dT%H:%MZ)   commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
} > "$out/machine.txt"
cp "$out/machine.txt" "$out/vcref_machine.txt"  # the stamp of bench_vcref's run (also run on its own)
"$build/bin/bench_case_study" $quick --out "$out"
cp "$out/machine.txt" "$out/helical_machine.txt"  # the stamp of bench_helical's run (also run on its own)
"$build/bin/bench_helical" $quick --out "$out" | tee "$out/bench_helical.txt"
"$build/bin/bench_vcref" $quick --csv "$out/vcref.csv" | tee "$out/bench_vcref.txt"
"$build/bin/bench_vc" $quick | tee "$out/bench_vc.txt"
"$build/bin/bench_lumped" $quick | tee "$out/bench_lumped.txt"
"$build/bin/bench_loaded" $quick --out "$out"
"$build/bin/bench_soft" $quick --out "$out" | tee "$out/bench_soft.txt"
"$build/bin/bench_soft" $quick --out "$out" --rk4-tip-tol 1e-8 | tee "$out/bench_soft_tol.txt"
"$build/bin/bench_calibration" $quick --out "$out" | tee "$out/bench_calibration.txt"
"$py" benchmarks/plot_results.py "$out" "$out"
if [ "$out" = docs/benchmark-results ]; then
  "$py" benchmarks/make_report.py "$out" benchmarks/report_template.md docs/benchmarks.md --readme README.md
fi
echo "results and figures in $out"
