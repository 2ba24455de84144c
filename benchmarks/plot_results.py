#!/usr/bin/env python3
"""Draw the benchmark results of bench_case_study (and bench_vcref --csv DIR/vcref.csv) as PNG and SVG.

usage: plot_results.py RESULTS_DIR [FIGURES_DIR]

Reads the CSV tables the benchmark executables wrote into RESULTS_DIR and writes the figures
into FIGURES_DIR (default: RESULTS_DIR). Tables that are missing are skipped. Uses only the
standard library and matplotlib (Debian's python3-matplotlib).
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
COLORS = {"cc": "tab:gray", "ccsub": "tab:blue", "prb": "tab:orange", "vc": "tab:green", "vcref": "tab:red"}
LABELS = {"cc": "CC", "ccsub": "CCsub", "prb": "PRB", "vc": "VC", "vcref": "VCref"}


def read(path):
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def save(fig, out, name):
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(out, f"{name}.{ext}"), dpi=130, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {name}.png/.svg")


def by_model(rows):
    out = {}
    for r in rows:
        out.setdefault(r["model"].lower(), []).append(r)
    return out


def scenario1(res, out):
    rows = read(os.path.join(res, "scenario1.csv"))
    if not rows:
        return
    paper = read(os.path.join(HERE, "data", "paper_code_fig10.csv")) or []
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    for model, rs in sorted(by_model(rows).items()):
        n = [num(r["n"]) for r in rs]
        c = COLORS.get(model)
        if model != "vcref":
            ax[0].plot(n, [num(r["e_p_pct"]) for r in rs], "o-", color=c, label=f"tdcr {LABELS[model]}")
            ax[1].plot(n, [num(r["e_R_deg"]) for r in rs], "o-", color=c, label=f"tdcr {LABELS[model]}")
        ax[2].plot(n, [num(r["median_us"]) / 1e3 for r in rs], "o-", color=c, label=f"tdcr {LABELS[model]}")
    for model, rs in sorted(by_model(paper).items()):
        rs = [r for r in rs if r.get("initial_guess") == "straight"]
        n = [num(r["n"]) for r in rs]
        c = COLORS.get(model)
        if model != "vcref":
            ax[0].plot(n, [num(r["e_p_pct_vs_VCref_best"]) for r in rs], "x--", color=c, alpha=0.6,
                       label=f"paper code {LABELS[model]}")
            ax[1].plot(n, [num(r["e_R_deg_vs_VCref_best"]) for r in rs], "x--", color=c, alpha=0.6)
        ax[2].plot(n, [num(r["time_config2_median_us"]) / 1e3 for r in rs], "x--", color=c, alpha=0.6,
                   label=f"paper code {LABELS[model]}")
    ax[0].set_ylabel("e_p (% of robot length)")
    ax[1].set_ylabel("e_R (deg)")
    ax[2].set_ylabel("solve time, configuration 2 (ms)")
    ax[2].set_yscale("log")
    for a in ax:
        a.set_xlabel("disks per segment n")
        a.set_xscale("log")
        a.grid(True, which="both", alpha=0.3)
    ax[0].legend(fontsize=7)
    ax[2].legend(fontsize=7)
    fig.suptitle("Scenario 1 (paper Fig. 10): errors against VCref and solve time")
    save(fig, out, "fig10_scenario1")


def scenario2(res, out):
    rows = read(os.path.join(res, "scenario2.csv"))
    if not rows:
        return
    fig, ax = plt.subplots(2, 3, figsize=(15, 8))
    for i, case in enumerate(["planar", "transverse"]):
        for model, rs in sorted(by_model([r for r in rows if r["force_case"] == case]).items()):
            f = [num(r["stiffness_factor"]) for r in rs]
            c = COLORS.get(model)
            if model != "vcref":
                ax[i][0].plot(f, [num(r["e_p_pct"]) for r in rs], "o-", color=c, label=LABELS[model])
                ax[i][1].plot(f, [num(r["e_R_deg"]) for r in rs], "o-", color=c, label=LABELS[model])
            ax[i][2].plot(f, [num(r["median_us"]) / 1e3 for r in rs], "o-", color=c, label=LABELS[model])
        ax[i][0].set_ylabel(f"{case}: e_p (%)")
        ax[i][1].set_ylabel(f"{case}: e_R (deg)")
        ax[i][2].set_ylabel(f"{case}: time at half load (ms)")
        ax[i][2].set_yscale("log")
        for a in ax[i]:
            a.set_xscale("log")
            a.set_xlabel("stiffness factor (EI / EI_paper)")
            a.grid(True, which="both", alpha=0.3)
        ax[i][0].legend(fontsize=8)
        ax[i][2].legend(fontsize=8)
    fig.suptitle("Scenario 2 (paper Fig. 11): tip force 0.5 N, n = 10")
    save(fig, out, "fig11_scenario2")


def pareto(points):
    """Indices of the points not dominated in (time, error), both minimised."""
    idx = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in idx:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def tradeoff(res, out):
    rows = read(os.path.join(res, "tradeoff.csv"))
    if not rows:
        return
    cases = sorted({r["case"] for r in rows})
    fig, ax = plt.subplots(1, len(cases), figsize=(7 * len(cases), 5), squeeze=False)
    for a, case in zip(ax[0], cases):
        rs = [r for r in rows if r["case"] == case and r["converged"] == "1"]
        pts = [(num(r["median_us"]) / 1e3, max(num(r["e_p_pct"]), 1e-9)) for r in rs]
        seen = set()
        for r, (t, e) in zip(rs, pts):
            m = r["model"].lower()
            a.scatter(t, e, color=COLORS.get(m), s=30, label=None if m in seen else LABELS.get(m, m))
            seen.add(m)
        front = pareto(pts)
        for i in front:  # name the settings on the front only, the others by colour
            a.annotate(rs[i]["setting"], pts[i], fontsize=7, xytext=(4, 2), textcoords="offset points")
        a.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "k--", lw=1, label="Pareto front")
        a.set_xscale("log")
        a.set_yscale("log")
        a.set_xlabel("median solve time (ms)")
        a.set_ylabel("tip error vs converged VCref (% of length)")
        a.set_title(case.replace("_", " "))
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle("What accuracy costs in time (paper robot, configuration 2)")
    save(fig, out, "tradeoff")


def effects(res, out):
    rows = read(os.path.join(res, "effects.csv"))
    if not rows:
        return
    models = sorted({r["model"] for r in rows})
    names = []
    for r in rows:
        if r["effect"] not in names:
            names.append(r["effect"])
    fig, ax = plt.subplots(figsize=(10, 4.5))
    w = 0.8 / len(names)
    for j, name in enumerate(names):
        vals = []
        for m in models:
            v = [num(r["median_us"]) for r in rows if r["model"] == m and r["effect"] == name]
            vals.append(v[0] / 1e3 if v else math.nan)
        ax.bar([i + j * w for i in range(len(models))], vals, w, label=name)
    ax.set_xticks([i + 0.4 - w / 2 for i in range(len(models))])
    ax.set_xticklabels([LABELS.get(m, m) for m in models])
    ax.set_ylabel("median solve time (ms)")
    ax.set_yscale("log")
    ax.legend(fontsize=8)
    ax.set_title("Cost of each effect (paper robot, n = 10, configuration 2)")
    save(fig, out, "effects")


def warmstart(res, out):
    rows = read(os.path.join(res, "warmstart.csv"))
    if not rows:
        return
    models = sorted({r["model"] for r in rows})
    fig, ax = plt.subplots(figsize=(8, 4))
    for j, mode in enumerate(["cold", "warm"]):
        vals = []
        for m in models:
            v = [num(r["total_ms"]) for r in rows if r["model"] == m and r["mode"] == mode]
            vals.append(v[0] if v else math.nan)
        ax.bar([i + 0.4 * j for i in range(len(models))], vals, 0.4, label=mode)
    ax.set_xticks([i + 0.2 for i in range(len(models))])
    ax.set_xticklabels([LABELS.get(m, m) for m in models])
    ax.set_ylabel("total time of the trajectory (ms)")
    ax.set_yscale("log")
    ax.legend()
    ax.set_title("A 100-step tension trajectory: warm against cold starts")
    save(fig, out, "warmstart")


def vcref_scaling(res, out):
    """Part (b) of bench_vcref --csv RESULTS_DIR/vcref.csv: cost and memory per disk against disks per segment."""
    rows = read(os.path.join(res, "vcref.csv"))
    if not rows:
        return
    rows = [r for r in rows if r["part"] == "b"]
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4.2))
    for scene, style in zip(scenes, ["o-", "s--", "^:"]):
        sel = [r for r in rows if r["scene"] == scene]
        n = [num(r["n"]) for r in sel]
        ax.semilogx(n, [num(r["us_per_disk"]) for r in sel], style, color=COLORS["vcref"], label=scene)
        bx.semilogx(n, [num(r["kb_per_disk"]) for r in sel], style, color=COLORS["vcref"], label=scene)
    for a in (ax, bx):
        a.set_xlabel("disks per segment n")
        a.set_ylim(bottom=0)
        a.grid(True, which="both", alpha=0.3)
        a.legend()
    ax.set_ylabel("CPU time of a cold solve per disk (us)")
    bx.set_ylabel("RSS added by the solve, per disk (KB)")
    fig.suptitle("VCref (multiple shooting + KLU), default options: cost per disk against the disk count")
    save(fig, out, "vcref_scaling")


def scenario3(res, out):
    """bench_helical's scenario3.csv: e_p against n (stiffness 1) per turn count, against VCref and
    against VC, unloaded (solid) and with the tip force (dashed); solve time of configuration 2."""
    rows = read(os.path.join(res, "scenario3.csv"))
    if not rows:
        return
    rows = [r for r in rows if r["part"] == "n" and r["reference"] != "-"]
    turns = sorted({r["turns"] for r in rows}, key=float)
    colors = dict(COLORS, vcref_eq58="tab:purple")
    labels = dict(LABELS, vcref_eq58="VCref Eq. 58")
    fig, ax = plt.subplots(len(turns), 3, figsize=(15, 3.6 * len(turns)), squeeze=False)
    for i, t in enumerate(turns):
        for j, ref in enumerate(["vcref", "vc"]):
            for loaded, style in (("0", "o-"), ("1", "x--")):
                sel = [r for r in rows if r["turns"] == t and r["reference"] == ref and r["tip_force"] == loaded
                       and r["pairs"] == "antagonistic"]
                for model, rs in sorted(by_model(sel).items()):
                    ax[i][j].plot([num(r["n"]) for r in rs], [num(r["e_p_pct"]) for r in rs], style,
                                  color=colors.get(model), label=f"{labels.get(model, model)}" + (" + F" if loaded == "1" else ""))
            ax[i][j].set_ylabel(f"{t} turn/segment: e_p vs {LABELS[ref]} (%)")
            ax[i][j].set_yscale("log")
        # One row per model for its time: VC's rows are those against VCref, the others' against VC.
        sel = [r for r in rows if r["turns"] == t and r["reference"] == ("vcref" if r["model"] == "vc" else "vc")
               and r["tip_force"] == "0" and r["pairs"] == "antagonistic"]
        for model, rs in sorted(by_model(sel).items()):
            ax[i][2].plot([num(r["n"]) for r in rs], [num(r["median_cpu_us"]) / 1e3 for r in rs], "o-",
                          color=colors.get(model), label=labels.get(model, model))
        ax[i][2].set_ylabel("thread CPU time, configuration 2 (ms)")
        ax[i][2].set_yscale("log")
        for a in ax[i]:
            a.set_xlabel("disks per segment n")
            a.set_xscale("log")
            a.grid(True, which="both", alpha=0.3)
    ax[0][0].legend(fontsize=6, ncol=2)
    ax[0][2].legend(fontsize=7)
    fig.suptitle("Scenario 3: helical routing (antagonistic pairs; solid: tendons only, dashed: 0.25 N tip force)")
    save(fig, out, "fig_scenario3")


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    res = sys.argv[1]
    out = sys.argv[2] if len(sys.argv) > 2 else res
    os.makedirs(out, exist_ok=True)
    for f in (scenario1, scenario2, scenario3, tradeoff, effects, warmstart, vcref_scaling):
        f(res, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
