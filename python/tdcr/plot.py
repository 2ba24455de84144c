"""Pictures of solved robots: a 3-D view, a side view and a top view, several models overlaid.

    python3 -m tdcr.plot SCENE.json [--model NAME[,NAME...]] -o FILE.png|svg     (also: tdcr plot)
    python3 -m tdcr.plot SCENE.json --animate OUT.gif|OUT.mp4 [--trajectory TIP.png] [--model NAME]
                         [--duration T] [--dt H] [--fps F]       (a simulation, docs/dynamics.md)

Draws the backbone, the disks as rings, the tendons through their holes, the base and tip frames
and the external tip force; axes in mm with equal aspect. From Python:

    import tdcr, tdcr.plot
    scene = tdcr.Scene.from_file("examples/paper_robot_vc.json")
    fig = tdcr.plot.figure(scene, [tdcr.solve(scene, model=m) for m in ("cc", "vc")])
    fig.savefig("robot.png")

Exit status of the command: 0 every model converged, 1 some did not (still drawn, dashed) or the
simulation stopped early (the steps up to there drawn), 2 bad input (also: an .mp4 without
ffmpeg), 3 matplotlib missing.
"""

import argparse
import math
import os
import sys

import numpy as np

import tdcr

_COLORS = {"cc": "#1f77b4", "ccsub": "#ff7f0e", "prb": "#2ca02c", "vc": "#d62728", "vcref": "#000000"}
_RING_POINTS = 40


def _pyplot():
    try:
        import matplotlib
    except ImportError:
        sys.stderr.write("error: tdcr plot needs matplotlib (Debian: apt-get install python3-matplotlib)\n")
        sys.exit(3)
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def disk_radius(robot):
    """Drawn disk radius (m): 1.25 times the farthest tendon hole (the robot has no disk size)."""
    r = [math.hypot(t.x, t.y) for seg in robot.segments for t in seg.tendons]
    return 1.25 * max(r) if r else 0.1 * robot.total_length() / max(1, len(robot.segments))


def tendon_end_disks(robot):
    """(x, y, last disk index) of every tendon in global order; disk 0 is the base disk."""
    out, last = [], 0
    for seg in robot.segments:
        last += seg.disks
        out += [(t.x, t.y, last) for t in seg.tendons]
    return out


def geometry(robot, solution):
    """Lines of one solved robot in mm: backbone (K, 3), rings [(P, 3)], tendons [(Q, 3)]."""
    frames = solution.disk_frames
    if len(frames) == 0:
        return None
    R, p = frames[:, :3, :3], frames[:, :3, 3]
    backbone = solution.backbone_positions if len(solution.backbone_s) else p
    t = np.linspace(0.0, 2.0 * np.pi, _RING_POINTS)
    circle = disk_radius(robot) * np.stack([np.cos(t), np.sin(t), np.zeros_like(t)])  # (3, P)
    rings = [(p[j][:, None] + R[j] @ circle).T for j in range(1, len(p))]
    tendons = []
    for x, y, end in tendon_end_disks(robot):
        hole = np.array([x, y, 0.0])
        tendons.append(np.array([p[j] + R[j] @ hole for j in range(min(end, len(p) - 1) + 1)]))
    mm = 1e3
    return {"backbone": backbone * mm, "rings": [r * mm for r in rings], "tendons": [q * mm for q in tendons],
            "tip": frames[-1]}


def _label(solution):
    if solution.converged:
        tip = solution.tip_position * 1e3
        return "%s: tip (%.2f, %.2f, %.2f) mm" % (solution.model, tip[0], tip[1], tip[2])
    return "%s: failed (%s)" % (solution.model, solution.termination)


def _views(horizontal):
    """(axis indices, labels) of the 3 panels: 3-D, side (horizontal-z), top (x-y)."""
    names = "xyz"
    return [(horizontal, 2), (0, 1)], ["side view (%s-z)" % names[horizontal], "top view (x-y)"]


def _draw_frame(draw3d, draw2d, T, length, alpha=1.0):
    for axis, color in zip(range(3), ("r", "g", "b")):
        a = np.array([T[:3, 3], T[:3, 3] + length * T[:3, axis]]) * 1e3
        draw3d(a, color, 1.5, "-", alpha)
        draw2d(a, color, 1.5, "-", alpha)


def _circle(center, normal, radius, n=48):
    """A circle (n + 1 points closing it) about `center` in the plane of `normal`."""
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    a = np.cross(normal, [1.0, 0.0, 0.0])
    if np.linalg.norm(a) < 1e-6:
        a = np.cross(normal, [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(normal, a)
    t = np.linspace(0.0, 2.0 * np.pi, n + 1)[:, None]
    return np.asarray(center, float) + radius * (np.cos(t) * a + np.sin(t) * b)


def obstacle_curves(obstacle, near, size):
    """Wire-frame polylines (m) of an obstacle of the scene file's `environment.obstacles`: a
    square of side `size` of a plane about the point nearest `near`, great circles of a sphere,
    rings and generators of a cylinder or capsule, rings along a lumen's centreline."""
    kind = obstacle["type"]
    if kind == "plane":
        n = np.asarray(obstacle["normal"], float)
        n /= np.linalg.norm(n)
        c = np.asarray(near, float) - np.dot(np.asarray(near, float) - obstacle["point"], n) * n
        a = np.cross(n, [1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.cross(n, [0.0, 1.0, 0.0])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        h = 0.5 * size
        corners = [c + h * (sa * a + sb * b) for sa, sb in ((1, 1), (-1, 1), (-1, -1), (1, -1), (1, 1))]
        grid = [np.array([c - h * a + t * b, c + h * a + t * b]) for t in np.linspace(-h, h, 5)]
        return [np.array(corners)] + grid
    if kind == "sphere":
        return [_circle(obstacle["center"], axis, obstacle["radius"]) for axis in np.eye(3)]
    if kind in ("cylinder", "capsule"):
        p0, p1 = (np.asarray(e, float) for e in obstacle["ends"])
        axis = p1 - p0
        r = obstacle["radius"]
        curves = [_circle(p, axis, r) for p in (p0, p1)]
        ring = _circle(p0, axis, r, n=8)
        curves += [np.array([q, q + axis]) for q in ring[:-1]]
        if kind == "capsule":  # the end caps' half circles through the axis
            u = axis / np.linalg.norm(axis)
            for q in ring[:-1:2]:
                d = (q - p0) / r
                for p, sign in ((p0, -1.0), (p1, 1.0)):
                    t = np.linspace(0.0, 0.5 * np.pi, 12)[:, None]
                    curves.append(p + r * (np.cos(t) * d + sign * np.sin(t) * u))
        return curves
    if kind == "lumen":
        c = np.asarray(obstacle["centreline"], float)
        curves = [c]
        for k in range(len(c)):
            tangent = c[min(k + 1, len(c) - 1)] - c[max(k - 1, 0)]
            curves.append(_circle(c[k], tangent, obstacle["radius"]))
        return curves
    return []


def _cube_3d(ax3, pts):
    """Equal aspect in mm: a cube around the points `pts`, and the 3-D view's labels. Returns the
    cube's centre and half side (the 2-D views use the same)."""
    center = 0.5 * (pts.max(axis=0) + pts.min(axis=0))
    half = 0.55 * max(np.ptp(pts, axis=0).max(), 1e-9)
    for k, setlim in enumerate((ax3.set_xlim, ax3.set_ylim, ax3.set_zlim)):
        setlim(center[k] - half, center[k] + half)
    ax3.set_box_aspect((1, 1, 1))
    ax3.set_xlabel("x (mm)")
    ax3.set_ylabel("y (mm)")
    ax3.set_zlabel("z (mm)")
    ax3.set_title("3-D view")
    return center, half


def figure(scene, solutions, title=None):
    """A matplotlib Figure of `solutions` (one per model) of `scene`'s robot."""
    plt = _pyplot()
    robot, loads = scene.robot, scene.loads
    fig = plt.figure(figsize=(15, 6))
    ax3 = fig.add_subplot(1, 3, 1, projection="3d")
    geoms = [(s, geometry(robot, s)) for s in solutions]
    pts = np.vstack([np.zeros((1, 3))] + [g["backbone"] for _, g in geoms if g is not None])
    spread = np.ptp(pts, axis=0)
    horizontal = 0 if spread[0] >= spread[1] else 1
    pairs, view_titles = _views(horizontal)
    ax2 = [fig.add_subplot(1, 3, k + 2) for k in range(2)]

    def draw3d(P, color, lw, ls, alpha):
        ax3.plot(P[:, 0], P[:, 1], P[:, 2], color=color, lw=lw, ls=ls, alpha=alpha)

    def draw2d(P, color, lw, ls, alpha, label=None):
        for ax, (i, j) in zip(ax2, pairs):
            ax.plot(P[:, i], P[:, j], color=color, lw=lw, ls=ls, alpha=alpha, label=label)

    L = robot.total_length()
    base = np.eye(4)
    for k, (sol, g) in enumerate(geoms):
        if g is None:
            continue
        color = _COLORS.get(sol.model, None)
        ls = "-" if sol.converged else "--"
        for ring in g["rings"]:
            draw3d(ring, color, 0.6, ls, 0.4)
            draw2d(ring, color, 0.6, ls, 0.4)
        for q in g["tendons"]:
            draw3d(q, color, 0.6, ":", 0.8)
            draw2d(q, color, 0.6, ":", 0.8)
        lw = 1.5 + 3.0 * (len(geoms) - 1 - k) / max(1, len(geoms) - 1)  # first widest: overlays stay visible
        ax3.plot(*g["backbone"].T, color=color, lw=lw, ls=ls, label=_label(sol))
        draw2d(g["backbone"], color, lw, ls, 1.0)
        _draw_frame(draw3d, draw2d, g["tip"], 0.12 * L)
    _draw_frame(draw3d, draw2d, base, 0.12 * L)

    force = np.asarray(loads.tip_force)
    fnorm = float(np.linalg.norm(force))
    drawn = [g for _, g in geoms if g is not None]
    if fnorm > 0 and drawn:
        for g in drawn[-1:]:  # at the last model's tip
            start = g["tip"][:3, 3] * 1e3
            arrow = np.array([start, start + 0.25 * L * 1e3 * force / fnorm])
            draw3d(arrow, "m", 2.0, "-", 1.0)
            draw2d(arrow, "m", 2.0, "-", 1.0)
            for ax, (i, j) in zip(ax2, pairs):
                ax.annotate("", xy=arrow[1, [i, j]], xytext=arrow[0, [i, j]],
                            arrowprops=dict(arrowstyle="->", color="m", lw=2))
        ax3.plot([], [], color="m", lw=2, label="tip force %.3g N" % fnorm)
    # Obstacles (grey wire frames) and the contact forces of the last model (red arrows, the
    # largest a quarter of the robot's length).
    obstacles = scene.to_dict().get("environment", {}).get("obstacles", [])
    middle = pts.mean(axis=0) * 1e-3
    for o in obstacles:
        for q in obstacle_curves(o, middle, 1.2 * L):
            draw3d(q * 1e3, "0.5", 0.7, "-", 0.6)
            draw2d(q * 1e3, "0.5", 0.7, "-", 0.6)
    if obstacles:
        ax3.plot([], [], color="0.5", lw=0.7, label="obstacles (%d)" % len(obstacles))
    contacts = [c for s in solutions[-1:] for c in s.contacts]
    if contacts:
        fmax = max(c.force for c in contacts)
        for c in contacts:
            start = np.asarray(c.point) * 1e3
            arrow = np.array([start, start + 0.25 * L * 1e3 * (c.force / fmax) * np.asarray(c.normal)])
            draw3d(arrow, "r", 2.0, "-", 1.0)
            for ax, (i, j) in zip(ax2, pairs):
                ax.annotate("", xy=arrow[1, [i, j]], xytext=arrow[0, [i, j]],
                            arrowprops=dict(arrowstyle="->", color="r", lw=2))
        ax3.plot([], [], color="r", lw=2, label="contact forces (largest %.3g N)" % fmax)
    mnorm = float(np.linalg.norm(np.asarray(loads.tip_moment)))
    if mnorm > 0:  # listed, not drawn: an arrow of a moment reads as a force
        ax3.plot([], [], ls="none", label="tip moment %.3g N m" % mnorm)

    # Equal aspect in mm: a cube around everything drawn.
    allpts = np.vstack([pts] + [g["rings"][k] for _, g in geoms if g is not None for k in range(len(g["rings"]))])
    center, half = _cube_3d(ax3, allpts)
    names = "xyz"
    for ax, (i, j), t in zip(ax2, pairs, view_titles):
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("%s (mm)" % names[i])
        ax.set_ylabel("%s (mm)" % names[j])
        ax.set_title(t)
        ax.grid(True, lw=0.3)
    fig.legend(*ax3.get_legend_handles_labels(), loc="lower center", ncol=min(3, len(solutions) + 1), fontsize=9)
    if title:
        fig.suptitle(title)
    fig.tight_layout(rect=(0, 0.1, 1, 0.95))
    return fig


# Largest --dpi: the figure is 15 x 6 inches, so 600 dpi is a 9000 x 3600 picture, print quality.
# The paper robot (`tdcr plot examples/paper_robot_vc.json --model vc --dpi N`, 2-core AMD EPYC
# with a build running, 2026-11-26) took 10.5 s and 320 MB at 600 dpi, 31 s and 1.1 GB at 1200;
# Agg refuses more than 2^16 pixels a side (4369 dpi).
MAX_DPI = 600


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors, as the tdcr program writes them (exit status 2)."""

    def error(self, message):
        self.exit(2, "error: %s (tdcr plot --help)\n" % message)


def _bad(option, value, reason):
    """One line naming the option and its value; the exit status of bad input."""
    sys.stderr.write("error: %s: %s (got %s)\n" % (option, reason, value))
    return 2


def _output_problem(path):
    """Why the picture cannot be written to `path` (None if it can): checked before any solve."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".png", ".svg", ".pdf"):
        return "the file must end in .png, .svg or .pdf"
    return _folder_problem(path)


# Longest simulation drawn: frames are drawn one per output step.
MAX_FRAMES = 5000


def _animation_problem(path):
    """Why the animation cannot be written to `path` (None if it can)."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".gif", ".mp4"):
        return "the file must end in .gif or .mp4"
    return _folder_problem(path)


def _folder_problem(path):
    if os.path.isdir(path):
        return "is a folder, not a picture file"
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.exists(folder):
        return "the folder %s does not exist" % folder
    if not os.path.isdir(folder):
        return "%s is not a folder" % folder
    if not os.access(folder, os.W_OK | os.X_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        return "cannot be written (no permission)"
    return None


def simulate_shapes(scene, duration, dt=1.0 / 60.0, model=None):
    """tdcr.simulate with the disk positions of every step (`disks`, steps x disks x 3, m)."""
    return tdcr.simulate(scene, duration, dt=dt, model=model, shapes=True)


def _tip_panel(ax, r):
    t, tip = r["t"], r["tip"] * 1e3
    for i, (name, color) in enumerate(zip("xyz", ("r", "g", "b"))):
        ax.plot(t, tip[:, i], color=color, lw=1.5, label="tip %s" % name)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("tip position (mm)")
    ax.set_title("tip trajectory")
    ax.grid(True, lw=0.3)
    ax.legend(loc="best", fontsize=8)
    if len(t) > 1:
        ax.set_xlim(t[0], t[-1])


def trajectory_figure(r, title=None):
    """A matplotlib Figure of a simulation's tip trajectory: tip x, y, z (mm) against t, and the
    tip's path in the side and top views. `r` is a dict of tdcr.simulate."""
    plt = _pyplot()
    fig = plt.figure(figsize=(12, 4.5))
    _tip_panel(fig.add_subplot(1, 3, 1), r)
    tip = r["tip"] * 1e3
    spread = np.ptp(tip, axis=0) if len(tip) else np.zeros(3)
    pairs, titles = _views(0 if spread[0] >= spread[1] else 1)
    names = "xyz"
    for k, ((i, j), name) in enumerate(zip(pairs, titles)):
        ax = fig.add_subplot(1, 3, k + 2)
        ax.plot(tip[:, i], tip[:, j], color="k", lw=1.2)
        if len(tip):
            ax.plot(tip[0, i], tip[0, j], "o", color="0.4", label="t = 0")
            ax.plot(tip[-1, i], tip[-1, j], "s", color="m", label="t = %.3g s" % r["t"][-1])
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("tip %s (mm)" % names[i])
        ax.set_ylabel("tip %s (mm)" % names[j])
        ax.set_title("tip path, " + name)
        ax.grid(True, lw=0.3)
        ax.legend(loc="best", fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def write_animation(r, path, fps, title=None, dpi=80):
    """Write the simulation `r` (tdcr.simulate(..., shapes=True)) as a GIF (PillowWriter) or an
    MP4 (FFMpegWriter, needs ffmpeg), one frame per step: the backbone through the disk centres in
    a 3-D, a side and a top view, the time, and the tip trajectory with a cursor at that time."""
    plt = _pyplot()
    from matplotlib import animation
    if path.lower().endswith(".mp4"):
        writer = animation.FFMpegWriter(fps=fps)
    else:
        writer = animation.PillowWriter(fps=fps)
    disks = r["disks"] * 1e3  # steps x disks x 3, mm
    t = r["t"]
    fig = plt.figure(figsize=(12, 7))
    grid = fig.add_gridspec(2, 3, height_ratios=(3, 2))
    ax3 = fig.add_subplot(grid[0, 0], projection="3d")
    pts = disks.reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    pts = np.vstack([np.zeros((1, 3)), pts])
    spread = np.ptp(pts, axis=0)
    pairs, view_titles = _views(0 if spread[0] >= spread[1] else 1)
    ax2 = [fig.add_subplot(grid[0, k + 1]) for k in range(2)]
    axt = fig.add_subplot(grid[1, :])
    _tip_panel(axt, r)
    cursor = axt.axvline(t[0], color="k", lw=1.0)
    center, half = _cube_3d(ax3, pts)
    names = "xyz"
    for ax, (i, j), vt in zip(ax2, pairs, view_titles):
        ax.set_xlim(center[i] - half, center[i] + half)
        ax.set_ylim(center[j] - half, center[j] + half)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("%s (mm)" % names[i])
        ax.set_ylabel("%s (mm)" % names[j])
        ax.set_title(vt)
        ax.grid(True, lw=0.3)
    # The tip's path so far (thin) under the robot (backbone through the disks, disks as dots).
    line3, = ax3.plot([], [], [], color="#1f77b4", lw=2.5, marker="o", ms=3)
    path3, = ax3.plot([], [], [], color="m", lw=0.8)
    lines2 = [ax.plot([], [], color="#1f77b4", lw=2.5, marker="o", ms=3)[0] for ax in ax2]
    paths2 = [ax.plot([], [], color="m", lw=0.8)[0] for ax in ax2]
    label = fig.text(0.01, 0.97, "", fontsize=12, family="monospace", va="top")
    if title:
        fig.suptitle(title)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    with writer.saving(fig, path, dpi):
        for k in range(len(t)):
            P = disks[k]
            P = P[np.all(np.isfinite(P), axis=1)]
            tip = disks[: k + 1, -1]
            line3.set_data_3d(P[:, 0], P[:, 1], P[:, 2])
            path3.set_data_3d(tip[:, 0], tip[:, 1], tip[:, 2])
            for line, tpath, (i, j) in zip(lines2, paths2, pairs):
                line.set_data(P[:, i], P[:, j])
                tpath.set_data(tip[:, i], tip[:, j])
            cursor.set_xdata([t[k], t[k]])
            label.set_text("t = %.3f s  (%s)" % (t[k], r["status"][k]))
            writer.grab_frame()
    plt.close(fig)
    return len(t)


def _scene_problem(path):
    """(field, value, reason) if the scene file cannot be simulated (None if it can, or if the
    file is not JSON: the scene reader then names the problem)."""
    import json
    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, ValueError):
        return None
    if not isinstance(doc, dict):
        return None
    if "timeline" not in doc:
        return ("timeline", "missing", "a scene to animate gives a \"timeline\" of inputs over time "
                "(docs/scene-file.md)")
    if "dynamics" not in doc:
        return ("dynamics", "missing", "a scene to animate gives a \"dynamics\" object (docs/dynamics.md)")
    return None


def _run_simulation(args, plt):
    """`tdcr plot --animate/--trajectory`: the exit status."""
    if args.animate:
        problem = _animation_problem(args.animate)
        if problem:
            return _bad("--animate", args.animate, problem)
        if args.animate.lower().endswith(".mp4"):
            from matplotlib import animation
            if not animation.FFMpegWriter.isAvailable():
                return _bad("--animate", args.animate, "an .mp4 needs ffmpeg, which is missing (Debian: apt-get "
                            "install ffmpeg); write a .gif instead")
    if args.trajectory:
        problem = _output_problem(args.trajectory)
        if problem:
            return _bad("--trajectory", args.trajectory, problem)
    if not (args.duration > 0 and math.isfinite(args.duration)):
        return _bad("--duration", args.duration, "must be a positive number of seconds")
    if not (args.dt > 0 and math.isfinite(args.dt)):
        return _bad("--dt", args.dt, "must be a positive number of seconds")
    if args.fps is not None and not (args.fps > 0 and math.isfinite(args.fps)):
        return _bad("--fps", args.fps, "must be a positive number of frames per second")
    frames = math.ceil(args.duration / args.dt - 1e-9) + 1
    if args.animate and frames > MAX_FRAMES:
        return _bad("--dt", args.dt, "gives %d frames over --duration %g; at most %d (a larger --dt)"
                    % (frames, args.duration, MAX_FRAMES))
    if args.model and "," in args.model:
        return _bad("--model", args.model, "an animation shows one model")
    bad = _scene_problem(args.scene)
    if bad:
        sys.stderr.write("error: %s: %s (got %s)\n" % (bad[0], bad[2], bad[1]))
        return 2
    try:
        scene = tdcr.Scene.from_file(args.scene)
        r = simulate_shapes(scene, args.duration, dt=args.dt, model=args.model.strip() if args.model else None)
    except tdcr.InputError as e:
        sys.stderr.write("error: %s\n" % e)
        return 2
    if not r["completed"]:
        sys.stderr.write("warning: the simulation stopped early: %s (the steps up to there are drawn)\n"
                         % r["message"])
    title = args.title or "%s, %s" % (os.path.basename(args.scene), (args.model or scene.model).strip())
    fps = args.fps if args.fps is not None else min(50.0, max(1.0, round(1.0 / args.dt)))
    try:
        if args.animate:
            n = write_animation(r, args.animate, fps, title, dpi=args.dpi if args.dpi_given else 80)
            print("%d frames (t = 0 to %.4g s, %g fps) -> %s" % (n, r["t"][-1], fps, args.animate))
        if args.trajectory:
            fig = trajectory_figure(r, title)
            try:
                fig.savefig(args.trajectory, dpi=args.dpi)
            finally:
                plt.close(fig)
            print("tip trajectory (t = 0 to %.4g s) -> %s" % (r["t"][-1], args.trajectory))
    except OSError as e:
        return _bad("--animate" if args.animate else "--trajectory", args.animate or args.trajectory,
                    "cannot be written (%s)" % (e.strerror or e))
    return 0 if r["completed"] else 1


def main(argv=None):
    parser = _Parser(prog="tdcr plot", description="Draw the solved robot of a scene file, or animate its "
                     "simulation (--animate, --trajectory).")
    parser.add_argument("scene", help="scene file (JSON)")
    parser.add_argument("--model", help="model name(s), comma separated (default: the scene's model)")
    parser.add_argument("-o", "--output", help="picture file: .png, .svg or .pdf, in a writable folder")
    parser.add_argument("--title", help="figure title (default: the scene file name)")
    parser.add_argument("--dpi", type=int, default=None, help="resolution of a .png, 1 to %d (default 120; "
                        "an animation's frames 80)" % MAX_DPI)
    parser.add_argument("--animate", metavar="OUT.gif|OUT.mp4", help="simulate the scene (its timeline and "
                        "dynamics) and write the motion as a GIF or an MP4 (needs ffmpeg)")
    parser.add_argument("--trajectory", metavar="OUT.png", help="simulate the scene and draw the tip "
                        "trajectory over time (.png, .svg or .pdf)")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated time, s (default 1)")
    parser.add_argument("--dt", type=float, default=1.0 / 60.0, help="output step = one frame, s (default 1/60)")
    parser.add_argument("--fps", type=float, default=None, help="frames per second of the animation "
                        "(default 1/dt, real time, at most 50)")
    args = parser.parse_args(argv)
    args.dpi_given = args.dpi is not None
    if args.dpi is None:
        args.dpi = 120
    if not (args.output or args.animate or args.trajectory):
        parser.error("one of -o, --animate or --trajectory is required")
    if args.output and (args.animate or args.trajectory):
        parser.error("-o draws the static answer; give it alone or --animate/--trajectory without it")
    # The options first: a bad one is reported before any solve.
    problem = _output_problem(args.output) if args.output else None
    if problem:
        return _bad("-o", args.output, problem)
    if not 1 <= args.dpi <= MAX_DPI:
        return _bad("--dpi", args.dpi, "must be a whole number from 1 to %d" % MAX_DPI)
    if args.animate or args.trajectory:
        return _run_simulation(args, _pyplot())
    plt = _pyplot()
    try:
        scene = tdcr.Scene.from_file(args.scene)
        models = args.model.split(",") if args.model else [scene.model]
        solutions = [tdcr.solve(scene, model=m.strip()) for m in models]
    except tdcr.InputError as e:
        sys.stderr.write("error: %s\n" % e)
        return 2
    fig = figure(scene, solutions, args.title or os.path.basename(args.scene))
    try:
        fig.savefig(args.output, dpi=args.dpi)
    except OSError as e:  # the folder changed since the check, or a full disk
        return _bad("-o", args.output, "cannot be written (%s)" % (e.strerror or e))
    finally:
        plt.close(fig)
    for s in solutions:
        print("%s -> %s" % (_label(s), args.output))
    return 0 if all(s.converged for s in solutions) else 1


if __name__ == "__main__":
    sys.exit(main())
