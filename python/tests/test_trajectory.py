"""A trajectory with one model and one workspace: warm starts take fewer Newton iterations and
give the cold answers. Under a 1 N tip force across the bending plane a cold solve loads the
robot from rest (16-41 iterations), a warm one continues from the previous answer (2-4)."""
import threading

import numpy as np
import pytest

import tdcr


@pytest.mark.parametrize("kind", ["vc", "vcref", "ccsub"])
def test_warm_started_trajectory(paper_scene, kind):
    model = tdcr.make_model(kind, paper_scene)
    ws = model.make_workspace()
    options = paper_scene.solver
    tensions = np.arange(3.0, 3.5, 0.05)
    warm_iters = cold_iters = 0
    previous = None
    for t in tensions:
        u = paper_scene.input()
        u.actuation.values = [t, 0.0, 0.5 * t, 0.0]
        u.loads.tip_force = [1.0, 0.0, 0.0]
        warm = model.solve(ws, u, options, warm_start=previous)
        cold = tdcr.solve_with(model, model.make_workspace(), u, options)
        assert warm.converged and cold.converged
        np.testing.assert_allclose(warm.disk_positions, cold.disk_positions, rtol=0, atol=1e-9)
        if previous is not None:
            warm_iters += warm.iterations
            cold_iters += cold.iterations
        previous = warm
    assert 2 * warm_iters < cold_iters, (warm_iters, cold_iters)


def test_solves_release_the_gil(paper_scene):
    """Threads, each with its own workspace of one model, give the serial answers."""
    model = tdcr.make_model("vc", paper_scene)
    inputs = []
    for t in (1.0, 2.0, 3.0, 4.0):
        u = paper_scene.input()
        u.actuation.values = [t, 0.0, 0.0, 0.0]
        inputs.append(u)
    serial = [tdcr.solve_with(model, model.make_workspace(), u).tip_position for u in inputs]
    results = [None] * len(inputs)

    def work(i):
        results[i] = tdcr.solve_with(model, model.make_workspace(), inputs[i]).tip_position

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(inputs))]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for a, b in zip(serial, results):
        np.testing.assert_array_equal(a, b)
