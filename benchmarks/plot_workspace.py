#!/usr/bin/env python3
"""Workspace figure from a sweep CSV (tdcr sweep): the reachable tip positions of one model,
coloured by its tip distance from a reference model (same sample) and by the total tension.

Usage: plot_workspace.py SWEEP.csv OUT.png [--model vc] [--reference vcref]
(docs/sweeps.md: docs/images/workspace.png is made from examples/sweeps/workspace_random.json.)
"""
import argparse
import csv
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_rows(path):
    with open(path, newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    return list(csv.DictReader(lines))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("csv")
    p.add_argument("out")
    p.add_argument("--model", default="vc")
    p.add_argument("--reference", default="vcref")
    a = p.parse_args()
    rows = read_rows(a.csv)
    tension_cols = [k for k in rows[0] if k.startswith("actuation.tensions[")]
    tips = {}
    for r in rows:
        if r["status"] == "converged":
            tips[(r["sample"], r["model"])] = (
                [float(r["tip_x"]), float(r["tip_y"]), float(r["tip_z"])],
                sum(float(r[k]) for k in tension_cols),
            )
    ys, zs, err, tension = [], [], [], []
    for (sample, model), (tip, total) in tips.items():
        if model != a.model or (sample, a.reference) not in tips:
            continue
        ref = tips[(sample, a.reference)][0]
        ys.append(tip[1] * 1e3)
        zs.append(tip[2] * 1e3)
        err.append(math.dist(tip, ref) * 1e3)
        tension.append(total)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True, constrained_layout=True)
    for ax, c, label, cmap in ((axes[0], err, f"|tip {a.model} - tip {a.reference}| (mm)", "viridis"),
                                (axes[1], tension, "total tendon tension (N)", "plasma")):
        sc = ax.scatter(ys, zs, c=c, s=6, cmap=cmap)
        fig.colorbar(sc, ax=ax, label=label, orientation="horizontal", shrink=0.8)
        ax.set_xlabel("tip y (mm)")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("tip z (mm)")
    axes[0].set_title(f"{a.model} vs {a.reference}: {len(err)} samples, max {max(err):.2f} mm")
    axes[1].set_title(f"reachable tip positions ({a.model})")
    fig.savefig(a.out, dpi=120)
    print(f"{a.out}: {len(err)} samples, {a.model} vs {a.reference} tip distance median "
          f"{sorted(err)[len(err) // 2]:.3f} mm, max {max(err):.3f} mm")


if __name__ == "__main__":
    main()
