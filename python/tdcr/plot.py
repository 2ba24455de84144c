"""Pictures of solved robots: a 3-D view, a side view and a top view, several models overlaid.

    python3 -m tdcr.plot SCENE.json [--model NAME[,NAME...]] -o FILE.png|svg     (also: tdcr plot)

Draws the backbone, the disks as rings, the tendons through their holes, the base and tip frames
and the external tip force; axes in mm with equal aspect. From Python:

    import tdcr, tdcr.plot
    scene = tdcr.Scene.from_file("examples/paper_robot_vc.json")
    fig = tdcr.plot.figure(scene, [tdcr.solve(scene, model=m) for m in ("cc", "vc")])
    fig.savefig("robot.png")

Exit status of the command: 0 every model converged, 1 some did not (still drawn, dashed),
2 bad input, 3 matplotlib missing.
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
    center = 0.5 * (allpts.max(axis=0) + allpts.min(axis=0))
    half = 0.55 * max(np.ptp(allpts, axis=0).max(), 1e-9)
    for k, setlim in enumerate((ax3.set_xlim, ax3.set_ylim, ax3.set_zlim)):
        setlim(center[k] - half, center[k] + half)
    ax3.set_box_aspect((1, 1, 1))
    ax3.set_xlabel("x (mm)")
    ax3.set_ylabel("y (mm)")
    ax3.set_zlabel("z (mm)")
    ax3.set_title("3-D view")
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


def main(argv=None):
    parser = _Parser(prog="tdcr plot", description="Draw the solved robot of a scene file.")
    parser.add_argument("scene", help="scene file (JSON)")
    parser.add_argument("--model", help="model name(s), comma separated (default: the scene's model)")
    parser.add_argument("-o", "--output", required=True, help="picture file: .png, .svg or .pdf, in a writable folder")
    parser.add_argument("--title", help="figure title (default: the scene file name)")
    parser.add_argument("--dpi", type=int, default=120, help="resolution of a .png, 1 to %d (default 120)" % MAX_DPI)
    args = parser.parse_args(argv)
    # The options first: a bad one is reported before any solve.
    problem = _output_problem(args.output)
    if problem:
        return _bad("-o", args.output, problem)
    if not 1 <= args.dpi <= MAX_DPI:
        return _bad("--dpi", args.dpi, "must be a whole number from 1 to %d" % MAX_DPI)
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
