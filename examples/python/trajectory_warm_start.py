#!/usr/bin/env python3
"""A trajectory with one model and one workspace, each solve warm-started from the previous answer.

    PYTHONPATH=build/python python3 examples/python/trajectory_warm_start.py examples/paper_robot_vc.json

Raises the first tendon's tension from half the scene's value to the full one under a 1 N tip
force across the bending plane and prints the tip and the Newton iterations of each warm solve
against a cold one (which loads the robot from rest).
"""
import sys

import numpy as np

import tdcr


def main(path, steps=11):
    scene = tdcr.Scene.from_file(path)
    model = tdcr.make_model("vc", scene)  # immutable: robot and effects
    ws = model.make_workspace()           # reused along the trajectory
    top = max(scene.actuation.values)
    previous = None
    warm_total = cold_total = 0
    print("%8s  %28s  %5s %5s" % ("T1 (N)", "tip (mm)", "warm", "cold"))
    for t in np.linspace(0.5 * top, top, steps):
        u = scene.input()
        u.actuation.values = [t] + [0.0] * (len(u.actuation.values) - 1)
        u.loads.tip_force = [1.0, 0.0, 0.0]
        sol = tdcr.solve_with(model, ws, u, scene.solver, warm_start=previous)
        cold = tdcr.solve_with(model, model.make_workspace(), u, scene.solver)
        if not (sol.converged and cold.converged):
            print("not converged at T1 = %g N: %s" % (t, sol.message))
            return 1
        # A warm start changes the work, not the accuracy: both tips are within the tip
        # tolerance of the exact one (a warm step may stop on a coarser RK4 mesh within it).
        gap = np.linalg.norm(sol.tip_position - cold.tip_position)
        assert gap <= 2.0 * sol.summary.tip_tolerance, gap
        tip = sol.tip_position * 1e3
        print("%8.3f  [%8.3f, %8.3f, %8.3f]  %5d %5d" % (t, *tip, sol.iterations, cold.iterations))
        warm_total += sol.iterations
        cold_total += cold.iterations
        previous = sol
    print("Newton iterations: warm %d, cold %d" % (warm_total, cold_total))
    return 0 if warm_total < cold_total else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "examples/paper_robot_vc.json"))
