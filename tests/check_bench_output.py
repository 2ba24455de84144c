#!/usr/bin/env python3
"""Smoke test of bench_case_study: run it with --quick, check every CSV is well formed (a header,
rows of the same width, finite errors for converged comparisons), then draw the plots.

usage: check_bench_output.py BENCH_EXE OUT_DIR PLOT_SCRIPT
"""
import csv
import math
import os
import subprocess
import sys

exe, out, plot = sys.argv[1:4]
subprocess.run([exe, "--quick", "--out", out], check=True)
expected = ["scenario1.csv", "scenario1_configs.csv", "scenario2.csv", "tradeoff.csv", "effects.csv", "warmstart.csv"]
for name in expected:
    path = os.path.join(out, name)
    with open(path) as f:
        rows = list(csv.reader(f))
    assert len(rows) >= 2, f"{name}: no data rows"
    width = len(rows[0])
    for r in rows[1:]:
        assert len(r) == width, f"{name}: row of {len(r)} fields, header has {width}: {r}"
    header = rows[0]
    for col in ("e_p_pct", "e_R_deg"):
        if col in header:
            i = header.index(col)
            for r in rows[1:]:
                v = float(r[i])
                assert not math.isinf(v), f"{name}: infinite {col} in {r}"
    print(f"{name}: {len(rows) - 1} rows ok")
# Scenario 1 must compare every model it has against VCref with finite errors.
with open(os.path.join(out, "scenario1.csv")) as f:
    s1 = list(csv.DictReader(f))
for r in s1:
    if r["model"] != "vcref" and int(r["n_compared"]) > 0:
        assert math.isfinite(float(r["e_p_pct"])), r
subprocess.run([sys.executable, plot, out], check=True)
print("bench_case_study smoke: ok")
