#!/usr/bin/env python3
"""Every model on one scene: tip position, error against VCref and solve time.

    PYTHONPATH=build/python python3 examples/python/compare_models.py examples/paper_robot_vc.json

Also prints which model `--model auto` would choose at 1 % and 0.1 % of the robot length.
"""
import sys

import numpy as np

import tdcr


def main(path):
    scene = tdcr.Scene.from_file(path)
    length = scene.robot.total_length()
    sols = {name: tdcr.solve(scene, model=name) for name in tdcr.model_names()}
    ref = sols["vcref"]
    print("%-6s %-10s %30s %14s %10s" % ("model", "status", "tip (mm)", "error (% L)", "time (ms)"))
    for name, s in sols.items():
        err = 100.0 * np.linalg.norm(s.tip_position - ref.tip_position) / length
        tip = s.tip_position * 1e3
        print("%-6s %-10s [%8.3f, %8.3f, %8.3f] %14.4f %10.3f"
              % (name, s.termination, *tip, err, 1e3 * s.solve_time_s))
    for tol in (0.01, 0.001):
        c = tdcr.choose_model(scene, tol)
        print("auto at %g %% of L: %s (%s)" % (100 * tol, c.kind, c.reason))
    return 0 if all(s.converged for s in sols.values()) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "examples/paper_robot_vc.json"))
