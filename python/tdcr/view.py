"""`tdcr view SCENE.json [--port P] [--models m1,m2] [--open]`: the interactive viewer.

A local HTTP server (loopback only: it binds 127.0.0.1 and answers nothing else) serves a page
that draws the robot with three.js and has a slider per tendon and per tip-load component. Every
slider move is one warm-started solve per shown model, here, in the server: each model keeps its
model, workspace and last answer, so that a move is a trajectory step (docs/viewer.md).

The server speaks JSON:
  GET  /api/scene  the robot, the inputs and their slider ranges, the models, or the scene's error
  POST /api/solve  {"models": [...], "values": [...], "tip_force": [3], "tip_moment": [3]}
                   -> {"results": [{model, ok, report, stability, tip, disks, backbone, holes}]}
"""

import argparse
import json
import math
import os
import sys
import threading
import time
import webbrowser
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np

import tdcr

_HERE = os.path.dirname(os.path.abspath(__file__))
STATIC_DIR = os.path.join(_HERE, "viewer_static")


def three_dir():
    """The npm package three: beside the module (copied by the build), or the source tree's
    viewer/node_modules (installed by .ci/deps), or TDCR_THREE_DIR."""
    candidates = [os.environ.get("TDCR_THREE_DIR", ""), os.path.join(_HERE, "vendor", "three")]
    src = os.environ.get("TDCR_SOURCE_DIR")
    if src:
        candidates.append(os.path.join(src, "viewer", "node_modules", "three"))
    for c in candidates:
        if c and os.path.isfile(os.path.join(c, "build", "three.module.js")):
            return c
    return None


def _finite_list(v, n, field):
    if not isinstance(v, list) or len(v) != n:
        raise tdcr.InputError(f"{field}: expected a list of {n} numbers, got {v!r}")
    out = []
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            raise tdcr.InputError(f"{field}[{i}]: {x!r} is not a finite number")
        out.append(float(x))
    return out


class Session:
    """The scene and, per model, its model, workspace and last converged answer (warm starts)."""

    def __init__(self, scene_path):
        self.scene_path = scene_path
        self.error = None
        self.scene = None
        self.lock = threading.Lock()
        self.models = {}
        try:
            self.scene = tdcr.Scene.from_file(scene_path)
            tdcr.validate_scene(self.scene)
        except Exception as e:  # shown on the page: the field and value
            self.error = str(e)

    # --- the scene, for the page ---------------------------------------------------------------
    def describe(self):
        if self.error:
            return {"ok": False, "error": self.error, "scene": self.scene_path}
        s = self.scene
        robot = s.robot
        EI = robot.backbone.effective_stiffness().EI
        L = sum(seg.length for seg in robot.segments)
        r_max = max((math.hypot(t.x, t.y) for seg in robot.segments for t in seg.tendons), default=0.0)
        # Slider ranges: tensions up to the one that bends the robot by about two radians
        # (2 EI / (r L)) or twice the scene's; displacements to +-r times two radians; tip loads
        # to the force (moment) that bends it by about a radian, EI / L^2 (EI / L).
        t_scale = 2.0 * EI / (r_max * L) if r_max > 0 and L > 0 else 10.0
        kinds = list(s.actuation.kinds) or [s.actuation.kind] * len(s.actuation.values)
        tendons, k = [], 0
        for i, seg in enumerate(robot.segments):
            for j, t in enumerate(seg.tendons):
                v = float(s.actuation.values[k])
                if kinds[k] == "displacements":
                    hi = max(2.0 * r_max, 2.0 * abs(v))
                    lo = -hi
                else:
                    hi, lo = max(t_scale, 2.0 * v), 0.0
                tendons.append({"label": f"segment {i + 1} tendon {j + 1}", "kind": kinds[k], "value": v,
                                "min": lo, "max": hi, "segment": i, "x": t.x, "y": t.y})
                k += 1
        f_scale = EI / (L * L) if L > 0 else 1.0
        chosen = s.model.lower()
        names = list(tdcr.model_names())
        selected = [chosen] if chosen in names else [str(tdcr.choose_model(s).kind)]
        return {
            "ok": True, "scene": self.scene_path, "models": names, "selected": selected,
            "tendons": tendons, "length": L, "tendon_radius": r_max,
            "tip_force": [float(x) for x in s.loads.tip_force], "force_max": max(f_scale, 2.0 * float(np.max(np.abs(s.loads.tip_force)))),
            "tip_moment": [float(x) for x in s.loads.tip_moment], "moment_max": max(EI / L if L > 0 else 1.0, 2.0 * float(np.max(np.abs(s.loads.tip_moment)))),
            "segments": [{"length": seg.length, "disks": seg.disks} for seg in robot.segments],
        }

    # --- one solve per shown model ----------------------------------------------------------------
    def _model(self, name):
        m = self.models.get(name)
        if m is None:
            model = tdcr.make_model(name, self.scene)
            m = self.models[name] = {"model": model, "workspace": model.make_workspace(), "previous": None}
        return m

    def solve(self, request):
        if self.error:
            raise tdcr.InputError(self.error)
        n = len(self.scene.actuation.values)
        names = request.get("models")
        if not isinstance(names, list) or not names or not all(isinstance(x, str) for x in names):
            raise tdcr.InputError(f"models: expected a non-empty list of model names, got {names!r}")
        values = _finite_list(request.get("values"), n, "values")
        force = _finite_list(request.get("tip_force", [0, 0, 0]), 3, "tip_force")
        moment = _finite_list(request.get("tip_moment", [0, 0, 0]), 3, "tip_moment")
        inp = self.scene.input()
        inp.actuation.values = np.array(values)
        inp.loads.tip_force = np.array(force)
        inp.loads.tip_moment = np.array(moment)
        results = []
        with self.lock:
            for name in names:
                results.append(self._solve_one(name, inp))
        return {"results": results}

    def _solve_one(self, name, inp):
        out = {"model": name}
        try:
            m = self._model(name)
            t0 = time.perf_counter()
            sol = m["model"].solve(m["workspace"], inp, self.scene.solver, m["previous"])
            out["solve_ms"] = 1e3 * (time.perf_counter() - t0)
        except Exception as e:  # an input this model cannot take: shown on the page
            out.update(ok=False, error=str(e))
            return out
        m["previous"] = sol if sol.converged else None
        out["ok"] = bool(sol.converged)
        out["report"] = sol.summary.brief_report()
        if not sol.converged:
            out["error"] = sol.summary.message
        st = sol.stability
        out["stability"] = {"status": str(st.status), "margin": float(st.margin) if math.isfinite(st.margin) else None,
                            "method": st.method}
        frames = sol.disk_frames
        if len(frames):
            out["disks"] = [[float(x) for x in f[:3, 3]] + [float(x) for x in f[:3, :3].reshape(-1)] for f in frames]
            out["tip"] = [float(x) for x in frames[-1][:3, 3]]
        pts = sol.backbone_positions
        out["backbone"] = [[float(x) for x in p] for p in pts] if len(pts) else [d[:3] for d in out.get("disks", [])]
        out["tensions"] = [float(x) for x in sol.tensions]
        return out


def make_handler(session):
    class Handler(BaseHTTPRequestHandler):
        server_version = "tdcr-view"

        def log_message(self, fmt, *args):  # quiet: the terminal shows the address only
            pass

        def _loopback(self):
            host = self.client_address[0]
            if host.startswith("127.") or host == "::1":
                return True
            self.send_error(HTTPStatus.FORBIDDEN, "tdcr view answers the loopback only")
            return False

        def _send(self, code, body, ctype):
            data = body if isinstance(body, bytes) else body.encode()
            self.send_response(code)
            self.send_header("Content-Type", ctype)
            self.send_header("Content-Length", str(len(data)))
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            self.wfile.write(data)

        def _json(self, code, obj):
            self._send(code, json.dumps(obj), "application/json")

        def _file(self, root, rel):
            path = os.path.realpath(os.path.join(root, rel))
            if not path.startswith(os.path.realpath(root) + os.sep) or not os.path.isfile(path):
                self.send_error(HTTPStatus.NOT_FOUND)
                return
            ctype = {".html": "text/html", ".js": "text/javascript", ".css": "text/css"}.get(
                os.path.splitext(path)[1], "application/octet-stream")
            with open(path, "rb") as f:
                self._send(HTTPStatus.OK, f.read(), ctype)

        def do_GET(self):
            if not self._loopback():
                return
            p = self.path.split("?")[0]
            if p == "/api/scene":
                self._json(HTTPStatus.OK, session.describe())
            elif p in ("/", "/index.html"):
                self._file(STATIC_DIR, "index.html")
            elif p.startswith("/static/"):
                self._file(STATIC_DIR, p[len("/static/"):])
            elif p.startswith("/vendor/three/"):
                root = three_dir()
                if root is None:
                    self.send_error(HTTPStatus.NOT_FOUND, "three.js is not installed (bash .ci/deps installs it)")
                    return
                self._file(root, p[len("/vendor/three/"):])
            else:
                self.send_error(HTTPStatus.NOT_FOUND)

        def do_POST(self):
            if not self._loopback():
                return
            if self.path != "/api/solve":
                self.send_error(HTTPStatus.NOT_FOUND)
                return
            try:
                n = int(self.headers.get("Content-Length", "0"))
                request = json.loads(self.rfile.read(n) or b"{}")
                if not isinstance(request, dict):
                    raise tdcr.InputError("request: expected a JSON object")
                t0 = time.perf_counter()
                reply = session.solve(request)
                reply["server_ms"] = 1e3 * (time.perf_counter() - t0)
                self._json(HTTPStatus.OK, reply)
            except (tdcr.InputError, ValueError) as e:
                self._json(HTTPStatus.BAD_REQUEST, {"error": str(e)})
            except Exception as e:  # never a dropped connection: the page shows what failed
                self._json(HTTPStatus.INTERNAL_SERVER_ERROR, {"error": f"internal error: {type(e).__name__}: {e}"})

    return Handler


def main(argv=None):
    ap = argparse.ArgumentParser(prog="tdcr view", description="Interactive viewer in the browser (loopback only).")
    ap.add_argument("scene", help="scene file (JSON)")
    ap.add_argument("--port", type=int, default=8765, help="port on 127.0.0.1 (0: any free port; default 8765)")
    ap.add_argument("--open", action="store_true", help="open the page in the default browser")
    args = ap.parse_args(argv)
    if not 0 <= args.port <= 65535:
        print(f"error: --port: {args.port} is not a port number (0-65535)", file=sys.stderr)
        return 2
    if not os.path.isfile(args.scene):
        print(f"error: {args.scene}: cannot be opened (no such file)", file=sys.stderr)
        return 2
    if three_dir() is None:
        print("error: three.js is not installed: run `bash .ci/deps` (npm install in viewer/) and rebuild",
              file=sys.stderr)
        return 3
    session = Session(args.scene)
    try:
        server = ThreadingHTTPServer(("127.0.0.1", args.port), make_handler(session))
    except OSError as e:
        print(f"error: --port: {args.port}: {e.strerror}", file=sys.stderr)
        return 2
    url = f"http://127.0.0.1:{server.server_address[1]}/"
    print(f"tdcr view: {url} (loopback only; Ctrl-C stops)", flush=True)
    if session.error:
        print(f"tdcr view: the scene has an error, shown on the page: {session.error}", flush=True)
    if args.open:
        webbrowser.open(url)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
