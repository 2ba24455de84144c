#!/usr/bin/env python3
"""Write docs/benchmarks.md from the benchmark tables (benchmarks/run_all.sh output) and the
narrative template benchmarks/report_template.md, so that every number in the page comes from a
measured table and none is copied by hand.

usage: make_report.py RESULTS_DIR TEMPLATE OUTPUT [--readme README.md]
"""
import csv
import math
import os
import sys
import textwrap

res, template, output = sys.argv[1:4]
HERE = os.path.dirname(os.path.abspath(__file__))
LABEL = {"cc": "CC", "ccsub": "CCsub", "prb": "PRB", "vc": "VC", "vcref": "VCref"}


def read(name, base=res):
    path = os.path.join(base, name)
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def f(x, digits=3):
    try:
        v = float(x)
    except (TypeError, ValueError):
        return "-"
    if math.isnan(v):
        return "-"
    if v == 0:
        return "0"
    if abs(v) >= 1000:
        return f"{v:,.0f}"
    return f"{v:.{digits}g}"


def time_us(x):
    v = float(x)
    if v >= 1000:
        return f"{v / 1000:.3g} ms"
    return f"{v:.3g} us"


s1 = read("scenario1.csv")
s2 = read("scenario2.csv")
paper = read("paper_code_fig10.csv", os.path.join(HERE, "data"))
vcref = read("vcref.csv")
effects = read("effects.csv")
warm = read("warmstart.csv")


def s1_row(n, model):
    for r in s1:
        if r["n"] == str(n) and r["model"] == model:
            return r
    return None


def paper_row(n, model):
    for r in paper:
        if r["n"] == str(n) and r["model"].lower() == model and r["initial_guess"] == "straight":
            return r
    return None


tables = {}

# Published text values, the paper's own code, tdcr.
rows = ["| quantity | paper (text) | paper's code (ref. data) | tdcr |", "| --- | --- | --- | --- |"]
for n, model, pub in [(1, "vc", "9.12 %"), (10, "vc", "0.16 %")]:
    t, p = s1_row(n, model), paper_row(n, model)
    rows.append(f"| {LABEL[model]} vs VCref, n = {n}, e_p | {pub} | "
                f"{f(p['e_p_pct_vs_VCref_straight'])} % (vs its straight-guess VCref) / "
                f"{f(p['e_p_pct_vs_VCref_best'])} % (vs converged VCref) | {f(t['e_p_pct'])} % |")
t, p = s1_row(1, "prb"), paper_row(1, "prb")
rows.append(f"| PRB vs VCref, n = 1, e_p / e_R | at most 0.47 % / 0.43 deg | {f(p['e_p_pct_vs_VCref_best'])} % / "
            f"{f(p['e_R_deg_vs_VCref_best'])} deg | {f(t['e_p_pct'])} % / {f(t['e_R_deg'])} deg |")
tables["published"] = "\n".join(rows)

# Speed at n = 10.
rows = ["| model | tdcr median | tdcr min | paper's code median | speed-up |", "| --- | --- | --- | --- | --- |"]
for m in ["cc", "ccsub", "prb", "vc", "vcref"]:
    r = s1_row(10, m)
    if r:
        rows.append(f"| {LABEL[m]} | {time_us(r['median_us'])} | {time_us(r['min_us'])} | "
                    f"{time_us(r['paper_code_median_us'])} | {f(r['speedup'])}x |")
tables["speed10"] = "\n".join(rows)

# Scenario 1 errors and times.
ns = [r["n"] for r in s1 if r["model"] == "vc"]
rows = ["| n | " + " | ".join(f"{LABEL[m]} e_p (%)" for m in ["cc", "ccsub", "prb", "vc"]) + " | "
        + " | ".join(f"{LABEL[m]} time" for m in ["cc", "ccsub", "prb", "vc", "vcref"]) + " |",
        "| --- " * 10 + "|"]
for n in ns:
    e = [f(s1_row(n, m)["e_p_pct"]) for m in ["cc", "ccsub", "prb", "vc"]]
    t = [time_us(s1_row(n, m)["median_us"]) for m in ["cc", "ccsub", "prb", "vc", "vcref"]]
    rows.append(f"| {n} | " + " | ".join(e) + " | " + " | ".join(t) + " |")
tables["scenario1"] = "\n".join(rows)

# Scenario 2.
rows = ["| stiffness factor | force | CCsub e_p / e_R | PRB e_p / e_R | VC e_p / e_R | failures (CCsub, PRB, VC) | "
        "time at half load: CCsub, PRB, VC, VCref |", "| --- | --- | --- | --- | --- | --- | --- |"]
keys = []
for r in s2:
    k = (r["stiffness_factor"], r["force_case"])
    if k not in keys:
        keys.append(k)
for sf, fc in keys:
    by = {r["model"]: r for r in s2 if r["stiffness_factor"] == sf and r["force_case"] == fc}
    cell = lambda m: f"{f(by[m]['e_p_pct'])} % / {f(by[m]['e_R_deg'])} deg" if m in by else "-"
    fails = ", ".join(by[m]["failures"] if m in by else "-" for m in ["ccsub", "prb", "vc"])
    times = ", ".join(time_us(by[m]["median_us"]) if m in by else "-" for m in ["ccsub", "prb", "vc", "vcref"])
    rows.append(f"| {f(sf)} | {fc} | {cell('ccsub')} | {cell('prb')} | {cell('vc')} | {fails} | {times} |")
tables["scenario2"] = "\n".join(rows)

# VCref: accuracy and time at n = 10, and scaling.
rows = ["| initial guess | RK4 steps per interval | median | tip error vs CVODE 1e-12 | speed-up vs paper's code |",
        "| --- | --- | --- | --- | --- |"]
for r in vcref:
    if r["part"] == "a":
        rows.append(f"| {r['initial_guess']} | {r['rk4_steps']} | {f(r['median_ms'])} ms | {f(r['tip_error_m'])} m | "
                    f"{f(r['speedup_vs_paper'])}x |")
tables["vcref_a"] = "\n".join(rows)
# Scaling (part b): per scene, wall and CPU time and peak RSS against the disk count, CPU time
# and added RSS per disk; the log-log slope of CPU time against n from n = 30 on, per scene.
def duration(ms):
    return f"{f(ms / 1000)} s" if ms >= 1000 else f"{f(ms)} ms"


rows = ["| scene | disks per segment | unknowns | Jacobian nonzeros | Newton iterations | median (wall) | "
        "median (CPU) | CPU per disk | peak RSS | added RSS per disk |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
pts = {}
for r in vcref:
    if r["part"] == "b":
        cpu = float(r["cpu_ms"])
        rows.append(f"| {r['scene']} | {r['n']} | {r['unknowns']} | {r['nnz']} | {r['iterations']} | "
                    f"{duration(float(r['median_ms']))} | {duration(cpu)} | {f(r['us_per_disk'])} us | "
                    f"{f(r['peak_rss_mb'])} MB | {f(r['kb_per_disk'])} KB |")
        if int(r["n"]) >= 30:
            pts.setdefault(r["scene"], []).append((math.log(float(r["n"])), math.log(cpu)))
tables["vcref_b"] = "\n".join(rows)
slopes = []
for scene, p in pts.items():
    if len(p) >= 2:
        mx = sum(x for x, _ in p) / len(p)
        my = sum(y for _, y in p) / len(p)
        slope = sum((x - mx) * (y - my) for x, y in p) / sum((x - mx) ** 2 for x, _ in p)
        slopes.append(f"{slope:.2f} ({scene})")
tables["vcref_slope"] = ", ".join(slopes) if slopes else "-"
# The stamp of bench_vcref's own run (vcref_machine.txt beside vcref.csv), else run_all's.
stamp = os.path.join(res, "vcref_machine.txt")
if not os.path.exists(stamp):
    stamp = os.path.join(res, "machine.txt")
with open(stamp) as fh:
    tables["vcref_run"] = "; ".join(line.lstrip("# ").rstrip() for line in fh if line.strip())

# Effects.
names = []
for r in effects:
    if r["effect"] not in names:
        names.append(r["effect"])
rows = ["| model | " + " | ".join(names) + " |", "| --- " * (len(names) + 1) + "|"]
for m in ["ccsub", "prb", "vc", "vcref"]:
    cells = []
    for n in names:
        r = [x for x in effects if x["model"] == m and x["effect"] == n]
        cells.append(f"{time_us(r[0]['median_us'])} ({r[0]['iterations']} it.)" if r else "-")
    rows.append(f"| {LABEL[m]} | " + " | ".join(cells) + " |")
tables["effects"] = "\n".join(rows)

# Warm start.
rows = ["| model | cold: total | cold: iterations per step | warm: total | warm: iterations per step |",
        "| --- | --- | --- | --- | --- |"]
for m in ["ccsub", "prb", "vc", "vcref"]:
    c = [r for r in warm if r["model"] == m and r["mode"] == "cold"]
    w = [r for r in warm if r["model"] == m and r["mode"] == "warm"]
    if c and w:
        rows.append(f"| {LABEL[m]} | {f(c[0]['total_ms'])} ms | {f(c[0]['mean_iterations'])} | {f(w[0]['total_ms'])} ms | "
                    f"{f(w[0]['mean_iterations'])} |")
tables["warmstart"] = "\n".join(rows)

# Loaded cases and the loaded trajectory (bench_loaded).
def metres(x):
    v = float(x)
    return "-" if math.isnan(v) else f"{v:.1e} m"


loaded_sum = read("loaded_summary.csv")
loaded_opt = read("loaded_options.csv")
traj = read("trajectory.csv")
rows = ["| model | options | converged / cases | tdcr failed | paper's code failed | tdcr median | "
        "speed-up median | speed-up min | max tip error vs tight reference | max tip diff vs paper's code "
        "(cases over 1e-6 m) |", "| --- " * 10 + "|"]
for r in loaded_sum:
    rows.append(f"| {LABEL[r['model']]} | {r['options']} | {r['converged']} / {r['cases']} | {r['failed']} | "
                f"{r['paper_failed']} | {time_us(r['median_us'])} | {f(r['speedup_median'])}x | "
                f"{f(r['speedup_min'])}x | {metres(r['max_tip_err_ref_m'])}"
                + (f" ({r['reference_failed']} references failed)" if r["reference_failed"] != "0" else "")
                + f" | {metres(r['max_tip_diff_paper_m'])} ({r['tip_diff_paper_over_1e-6']}) |")
tables["loaded_summary"] = "\n".join(rows)
# Consistency with the paper code's tips, per n (default options; its rows with a squared residual < 1e-12).
loaded_rows = [r for r in read("loaded.csv") if r["options"] == "default"]
ns = sorted({int(r["n"]) for r in loaded_rows})
rows = ["| n | " + " | ".join(f"{LABEL[m]}" for m in ["ccsub", "prb", "vc", "vcref"])
        + " | VC without kink forces (paper code's formulation) |", "| --- " * 6 + "|"]
for n in ns:
    def worst(m, col="tip_diff_paper_m"):
        v = [float(r[col]) for r in loaded_rows if r["model"] == m and int(r["n"]) == n
             and r["converged"] == "1" and r["paper_converged"] == "1" and float(r["paper_residual"]) < 1e-12]
        v = [x for x in v if not math.isnan(x)]
        return metres(max(v)) if v else "-"
    rows.append(f"| {n} | " + " | ".join(worst(m) for m in ["ccsub", "prb", "vc", "vcref"])
                + f" | {worst('vc', 'paper_form_tip_diff_paper_m')} |")
tables["loaded_consistency"] = "\n".join(rows)

rows = ["| model | options | converged / cases | max tip error vs tight reference | median (min of 3) | within tolerance | chosen |",
        "| --- " * 7 + "|"]
for r in loaded_opt:
    if r["options"] == "default" or r["chosen"] == "1" or r["options"].startswith("cvode"):
        rows.append(f"| {LABEL[r['model']]} | {r['options']} | {r['converged']} / {r['cases']} | "
                    f"{metres(r['max_tip_err_ref_m'])} | {time_us(r['median_us'])} | "
                    f"{'yes' if r['within_tol'] == '1' else 'no'} | {'**yes**' if r['chosen'] == '1' else ''} |")
tables["loaded_options"] = "\n".join(rows)
# The largest tip error of a trajectory's checked steps (nan, shown as "-", if a check failed):
# max_tip_err_m over 20 steps; results written before that column existed: the 4 quarter steps.
def traj_error(r):
    if r.get("max_tip_err_m") not in (None, ""):
        return float(r["max_tip_err_m"])
    errs = [float(r[k]) for k in ("tip_err_quarter_m", "tip_err_half_m", "tip_err_three_quarter_m", "tip_err_end_m")]
    return float("nan") if any(math.isnan(e) for e in errs) else max(errs)


rows = ["| model | options | steps | rate | per step | Newton iterations per step (max) | failed | "
        "max tip error vs tight reference (checked steps) |", "| --- " * 8 + "|"]
for r in traj:
    rows.append(f"| {LABEL[r['model']]} | {r['options']} | {r['steps']} | {f(r['rate_hz'])} Hz | "
                f"{time_us(r['mean_us_per_step'])} | {f(r['mean_iterations'])} ({r['max_iterations']}) | {r['failed']} | "
                f"{metres(traj_error(r))} |")
tables["trajectory"] = "\n".join(rows)
stamp = ""
if os.path.exists(os.path.join(res, "loaded_summary.csv")):
    with open(os.path.join(res, "loaded_summary.csv")) as fh:
        stamp = fh.readline().lstrip("# ").rstrip()
tables["loaded_machine"] = stamp

# Soft robots under tip forces (bench_soft); left empty if the results hold no soft.csv.
tables["soft_summary"] = tables["soft_table"] = tables["soft_machine"] = ""
tables["soft_tol_summary"] = tables["soft_tol_machine"] = ""


def soft_summary(rows_in):
    # Ratios on the soft scenes (E < 1: the target's) and on the stiff control (E = 1) apart.
    rows = ["| model | converged / scenes | soft scenes (E < 1): ratio to the fastest, median | max | "
            "control (E = 1): max ratio | soft scenes: median CPU time | max |",
            "| --- " * 7 + "|"]
    med = lambda v: v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])
    show = lambda v, g: f"{f(g(v))}x" if v else "-"
    for m in ["ccsub", "prb", "vc", "vcref"]:
        mine = [r for r in rows_in if r["model"] == m]
        ok = [r for r in mine if r["status"] == "converged"]
        soft = sorted(float(r["ratio_to_fastest"]) for r in ok if float(r["e_factor"]) < 1)
        control = sorted(float(r["ratio_to_fastest"]) for r in ok if float(r["e_factor"]) >= 1)
        cpu = sorted(float(r["median_cpu_us"]) for r in ok if float(r["e_factor"]) < 1)
        rows.append(f"| {LABEL[m]} | {len(ok)} / {len(mine)} | {show(soft, med)} | {show(soft, max)} | "
                    f"{show(control, max)} | {time_us(med(cpu)) if cpu else '-'} | {time_us(cpu[-1]) if cpu else '-'} |")
    return "\n".join(rows)


if os.path.exists(os.path.join(res, "soft_tol.csv")):
    with open(os.path.join(res, "soft_tol.csv")) as fh:
        tables["soft_tol_machine"] = "Run: " + fh.readline().lstrip("# ").rstrip() + "."
    tables["soft_tol_summary"] = soft_summary(read("soft_tol.csv"))
if os.path.exists(os.path.join(res, "soft.csv")):
    soft = read("soft.csv")
    with open(os.path.join(res, "soft.csv")) as fh:
        tables["soft_machine"] = "Run: " + fh.readline().lstrip("# ").rstrip() + "."
    tables["soft_summary"] = soft_summary(soft)
    rows = ["| scene | force | model | status | continuation steps | iterations | median time (CPU) | "
            "ratio to the fastest | tip distance to VCref |", "| --- " * 9 + "|"]
    for r in soft:
        dist = float(r["tip_dist_vcref_m"]) if r["tip_dist_vcref_m"] not in ("", "nan") else float("nan")
        rows.append(f"| {r['scene']} | {float(r['force_n']):.2f} N | {LABEL[r['model']]} | {r['status']} | "
                    f"{r['continuation_steps']} | {r['iterations']} | {time_us(r['median_cpu_us'])} | "
                    f"{f(r['ratio_to_fastest'])}x | {'-' if r['model'] == 'vcref' else metres(dist)} |")
    tables["soft_table"] = "\n".join(rows)

# Side by side with the paper's code (bench_side_by_side, benchmarks/side_by_side.sh): its own
# markdown summary, table and run line; the load before and after from side_by_side_load.txt.
tables["side_by_side"] = "Not run for these results: see the command above."
tables["side_by_side_note"] = ""
if os.path.exists(os.path.join(res, "side_by_side_summary.md")):
    with open(os.path.join(res, "side_by_side_summary.md")) as fh:
        table, _, run = fh.read().strip().rpartition("\n\n")
    tables["side_by_side"] = table + "\n\nRun: " + run
    load = os.path.join(res, "side_by_side_load.txt")
    notes = []
    cpu = run.split(";")[0].replace("machine: ", "").strip()
    if "EPYC" not in cpu:
        notes.append("The paper code's stored times were recorded on a 2 vCPU AMD EPYC "
                     "(`benchmarks/data/paper_code_cases_timing.csv`); this run's machine has another CPU "
                     f"({cpu}), so \"paper's code / its stored times\" compares the machines as well as their load.")
    if os.path.exists(load):
        with open(load) as fh:
            lines = [line.strip() for line in fh if "load average" in line and not line.startswith("top")]
        sbs_rows = read("side_by_side.csv")

        def ratio(code):  # wall over CPU time of a case's solves (medians of R), mean over the rows
            v = [float(r[f"{code}_median_us"]) / float(r[f"{code}_cpu_median_us"]) for r in sbs_rows]
            return sum(v) / len(v)

        # 1-minute load averages before and after; the benchmark itself keeps one core busy.
        ones = [float(x.split("load average:")[1].split(",")[0]) for x in lines]
        busy = bool(ones) and (ones[0] > 0.5 or max(ones) > 1.5)
        text = ("The machine (2 cores) is shared with other engineers' jobs. `uptime` before and after the run: "
                + "; ".join(f"`{x}`" for x in lines) + ". The benchmark itself keeps one core busy; "
                + ("other jobs ran beside it for some or all of the run (the busiest processes are in "
                   "`side_by_side_load.txt`)." if busy else "the load shows no other job beside it."))
        if sbs_rows:
            paper, tdcr = ratio("paper"), ratio("tdcr")
            text += (f" Wall time over CPU time of a case, mean over the cases and models: the paper's code "
                     f"{f(paper)}, tdcr {f(tdcr)}"
                     + (": the paper code's long solves lost more wall time to other jobs than tdcr's short ones, "
                        "so the wall-time speed-ups lean above the CPU-time ones." if paper > 1.05 * tdcr else "."))
        notes.append(text)
    notes.append("Raw tables: `docs/benchmark-results/side_by_side.csv` (every case and model), "
                 "`side_by_side_summary.csv`, `side_by_side_load.txt` (uptime and the busiest processes before "
                 "and after).")
    tables["side_by_side_note"] = "\n\n".join(notes)

with open(os.path.join(res, "machine.txt")) as fh:
    tables["machine"] = "; ".join(line.lstrip("# ").rstrip() for line in fh if line.strip())

# README's speed sentence: the default options' rows first (what a user who asks for nothing
# gets: unloaded, loaded and trajectory speed-ups with their tip errors), then the fastest options
# the benchmark found within the tip tolerance where they differ; from the same tables, written
# between the markers of README.md when --readme is given.
def readme_speed():
    parts, faster = [], []
    for m in ["ccsub", "prb", "vc", "vcref"]:
        r = s1_row(10, m)
        ls = [x for x in loaded_sum if x["model"] == m]
        if not r or not ls:
            return None
        d = [x for x in ls if x["options"] == "default"] or ls[:1]
        td = [x for x in traj if x["model"] == m and x["options"] == "default"]
        parts.append(f"{LABEL[m]} {f(r['speedup'])}x unloaded, {f(d[0]['speedup_median'])}x median / "
                     f"{f(d[0]['speedup_min'])}x min loaded at tip error <= {metres(float(d[0]['max_tip_err_ref_m']))}"
                     + (f", trajectory {f(td[0]['rate_hz'])} Hz at tip error {metres(traj_error(td[0]))}" if td else ""))
        # The fastest options within the tip tolerance, if the benchmark chose other ones.
        chosen = [x for x in loaded_opt if x["model"] == m and x["chosen"] == "1" and x["options"] != "default"]
        pick = [x for x in ls if chosen and x["options"] == chosen[0]["options"]]
        t = [x for x in traj if x["model"] == m and x["options"].startswith("fastest within")
             and not x["options"].endswith(": default")]
        extra = []
        if pick:
            extra.append(f"{f(pick[0]['speedup_median'])}x / {f(pick[0]['speedup_min'])}x loaded with {pick[0]['options']}")
        if t:
            extra.append(f"trajectory {f(t[0]['rate_hz'])} Hz at {metres(traj_error(t[0]))} with "
                         f"{t[0]['options'].split(': ', 1)[1]}")
        if extra:
            faster.append(f"{LABEL[m]} " + ", ".join(extra))
    side = ""
    if os.path.exists(os.path.join(res, "side_by_side_summary.csv")):
        sb = read("side_by_side_summary.csv")
        cells = [f"{LABEL[x['model']]} {f(x['speedup_median'])}x median / {f(x['speedup_min'])}x min "
                 f"(CPU time {f(x['cpu_speedup_median'])}x / {f(x['cpu_speedup_min'])}x)"
                 for x in sb if x["options"] == "default"]
        if cells:
            side = (" Timed side by side with the paper's code in one run on the same 60 loaded cases "
                    "(`benchmarks/side_by_side.sh`, wall time, default options): " + "; ".join(cells) + ".")
    text = ("Speed-ups against the paper's own code with tdcr's default options (tip tolerance 1e-7 of "
            "the robot's length, 1e-8 m here), generated from the tables of docs/benchmarks.md "
            "(unloaded: n = 10, configuration (T_M, 0, 0, 0); loaded: its 60 random cases with tip forces, "
            "n = 3-20, median and minimum over the cases, against the paper code's stored timings; "
            "trajectory: n = 10, 0.05 N tip force, 1000 warm-started steps): " + "; ".join(parts) + "."
            + side
            + (" Options the benchmark found faster at the same accuracy: " + "; ".join(faster) + "." if faster else ""))
    return textwrap.fill(text, width=100, initial_indent="  ", subsequent_indent="  ", break_on_hyphens=False)


# Scenario 3 (bench_helical): helical routing, the disk force, disk counts.
s3 = read("scenario3.csv")
S3_MODELS = ["ccsub", "prb", "vc", "vcref_eq58", "vcref"]
S3_LABEL = dict(LABEL, vcref_eq58="VCref Eq. 58")


def s3_get(part, n, sf, turns, pairs, load, model, ref):
    for r in s3:
        if (r["part"], r["n"], float(r["stiffness_factor"]), float(r["turns"]), r["pairs"], r["tip_force"], r["model"],
                r["reference"]) == (part, str(n), sf, turns, pairs, load, model, ref):
            return r
    return None


def s3_cell(r):
    if not r or r["e_p_pct"] in ("nan", ""):
        return "-"
    fails = f", {r['failures']} failed" if r["failures"] not in ("0", "") else ""
    return f"{f(r['e_p_pct'])} % / {f(r['e_R_deg'])} deg{fails}"


tables["scenario3"] = tables["scenario3_n"] = tables["scenario3_stiffness"] = tables["scenario3_time"] = ""
tables["scenario3_cc"] = tables["helical_run"] = tables["disk_force"] = tables["disks"] = ""
if s3:
    turns = sorted({float(r["turns"]) for r in s3})
    cols = [m for m in S3_MODELS if m != "vcref"]
    rows = ["| turns / segment | pairs | tip force | " + " | ".join(f"{S3_LABEL[m]} vs VCref" for m in cols) +
            " | VCref vs VC | VCref Eq. 58 vs VC |", "| --- | --- | --- |" + " --- |" * (len(cols) + 2)]
    for t in turns:
        for pairs in ["antagonistic", "adjacent"]:
            for load in ["0", "1"]:
                cells = [s3_cell(s3_get("n", 10, 1.0, t, pairs, load, m, "vcref")) for m in cols]
                cells.append(s3_cell(s3_get("n", 10, 1.0, t, pairs, load, "vcref", "vc")))
                cells.append(s3_cell(s3_get("n", 10, 1.0, t, pairs, load, "vcref_eq58", "vc")))
                rows.append(f"| {f(t)} | {pairs} | {'0.25 N' if load == '1' else '-'} | " + " | ".join(cells) + " |")
    tables["scenario3"] = "\n".join(rows)
    ns = sorted({int(r["n"]) for r in s3 if r["part"] == "n"})
    rows = ["| n | " + " | ".join(f"{S3_LABEL[m]} vs VCref" for m in cols) + " | " +
            " | ".join(f"{S3_LABEL[m]} vs VC" for m in ["ccsub", "prb", "vcref_eq58", "vcref"]) + " |",
            "| --- |" + " --- |" * (len(cols) + 4)]
    for n in ns:
        cells = [s3_cell(s3_get("n", n, 1.0, 0.5, "adjacent", "1", m, "vcref")) for m in cols]
        cells += [s3_cell(s3_get("n", n, 1.0, 0.5, "adjacent", "1", m, "vc")) for m in ["ccsub", "prb", "vcref_eq58", "vcref"]]
        rows.append(f"| {n} | " + " | ".join(cells) + " |")
    tables["scenario3_n"] = "\n".join(rows)
    sfs = sorted({float(r["stiffness_factor"]) for r in s3 if r["part"] == "stiffness"})
    rows = ["| stiffness factor | turns / segment | pairs | " + " | ".join(f"{S3_LABEL[m]} vs VCref" for m in cols) +
            " | VCref vs VC |", "| --- | --- | --- |" + " --- |" * (len(cols) + 1)]
    for sf in sfs:
        for t in turns:
            for pairs in ["antagonistic", "adjacent"]:
                cells = [s3_cell(s3_get("stiffness", 10, sf, t, pairs, "1", m, "vcref")) for m in cols]
                cells.append(s3_cell(s3_get("stiffness", 10, sf, t, pairs, "1", "vcref", "vc")))
                rows.append(f"| {f(sf)} | {f(t)} | {pairs} | " + " | ".join(cells) + " |")
    tables["scenario3_stiffness"] = "\n".join(rows)
    rows = ["| n | " + " | ".join(S3_LABEL[m] for m in S3_MODELS) + " |", "| --- |" + " --- |" * len(S3_MODELS)]
    for n in ns:
        cells = []
        for m in S3_MODELS:
            r = s3_get("n", n, 1.0, 0.5, "antagonistic", "0", m, "vc" if m != "vc" else "vcref")
            cells.append(f"{time_us(r['median_cpu_us'])} ({time_us(r['median_us'])})" if r and r["median_us"] != "nan" else "-")
        rows.append(f"| {n} | " + " | ".join(cells) + " |")
    tables["scenario3_time"] = "\n".join(rows)
    cc = [r for r in s3 if r["model"] == "cc" and r["note"]]
    if cc:
        tables["scenario3_cc"] = ("CC has no row: it refuses these robots (" +
                                  cc[0]["note"].replace("refuses: ", "").replace(";", ",") +
                                  "): constant curvature needs tendons parallel to the backbone.")
if os.path.exists(os.path.join(res, "helical_machine.txt")):
    with open(os.path.join(res, "helical_machine.txt")) as fh:
        tables["helical_run"] = "; ".join(line.lstrip("# ").rstrip() for line in fh if line.strip())
df = read("disk_force.csv")
if df:
    rows = ["| robot (one 100 mm segment) | n | VCref kept vs VC | VCref removed (Eq. 58) vs VC | removed vs kept | "
            "force Eq. 58 drops |", "| --- | --- | --- | --- | --- | --- |"]
    for r in df:
        rows.append(f"| {r['case']} | {r['n']} | {f(1e3 * float(r['kept_vs_vc_m']))} mm | "
                    f"{f(1e3 * float(r['removed_vs_vc_m']))} mm | {f(1e3 * float(r['removed_vs_kept_m']))} mm | "
                    f"{f(r['eq58_net_force_N'])} N |")
    tables["disk_force"] = "\n".join(rows)
dk = read("disks.csv")
if dk:
    accs = []
    for r in dk:
        if r["accuracy_fraction"] not in accs:
            accs.append(r["accuracy_fraction"])
    rows = ["| robot | model | " + " | ".join(f"within {f(100 * float(a))} % of L" for a in accs) + " | observed order |",
            "| --- | --- |" + " --- |" * (len(accs) + 1)]
    keys = []
    for r in dk:
        if (r["robot"], r["model"]) not in keys:
            keys.append((r["robot"], r["model"]))
    for rb, m in keys:
        by = {r["accuracy_fraction"]: r for r in dk if r["robot"] == rb and r["model"] == m}
        cells = [(by[a]["n_min"] if by[a]["n_min"] != "-1" else "not resolved") if a in by else "-" for a in accs]
        order = next(iter(by.values()))["order"]
        rows.append(f"| {rb} | {LABEL.get(m, m)} | " + " | ".join(cells) + f" | {f(order, 2)} |")
    tables["disks"] = "\n".join(rows)


if "--readme" in sys.argv:
    readme = sys.argv[sys.argv.index("--readme") + 1]
    sentence = readme_speed()
    body = open(readme).read()
    begin, end = "<!-- speed:begin (benchmarks/make_report.py) -->", "<!-- speed:end -->"
    if sentence and begin in body and end in body:
        head, rest = body.split(begin, 1)
        body = head + begin + "\n" + sentence + "\n" + end + rest.split(end, 1)[1]
        with open(readme, "w") as fh:
            fh.write(body)
        print(f"updated {readme}")

text = open(template).read()
for k, v in tables.items():
    text = text.replace("{{" + k + "}}", v)
with open(output, "w") as fh:
    fh.write(text)
print(f"wrote {output}")
