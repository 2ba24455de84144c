#!/usr/bin/env python3
"""`mpirun -np 2 tdcr-sweep-mpi` writes the file of a single `tdcr sweep` run: same header, same
rows (samples, inputs, models, statuses), tips within 1e-9 m / 1e-9 rad."""
import argparse
import csv
import os
import subprocess
import sys


def rows(path):
    with open(path, newline="") as f:
        lines = f.read().splitlines()
    return lines[:2], list(csv.reader(lines[2:]))


def main():
    p = argparse.ArgumentParser()
    for k in ("tdcr", "mpi", "mpirun", "sweep", "work"):
        p.add_argument("--" + k, required=True)
    a = p.parse_args()
    os.makedirs(a.work, exist_ok=True)
    single, mpi = os.path.join(a.work, "single.csv"), os.path.join(a.work, "mpi.csv")
    for f in (single, mpi):
        if os.path.exists(f):
            os.remove(f)
    subprocess.run([a.tdcr, "sweep", a.sweep, "-o", single, "--quiet"], check=True)
    subprocess.run([a.mpirun, "--allow-run-as-root", "--oversubscribe", "-np", "2", a.mpi, a.sweep, "-o", mpi],
                   check=True)
    (h1, r1), (h2, r2) = rows(single), rows(mpi)
    ok = h1 == h2 and len(r1) == len(r2) and len(r1) > 0
    for x, y in zip(r1, r2):
        n = len(x)
        ok = ok and len(y) == n and x[: n - 9] == y[: n - 9]  # sample, inputs, model, status
        ok = ok and all(abs(float(x[c]) - float(y[c])) <= 1e-9 for c in range(n - 8, n - 2))
    print(f"single run {len(r1)} rows, mpirun -np 2 {len(r2)} rows: {'equal' if ok else 'DIFFERENT'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
