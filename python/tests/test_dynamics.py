"""tdcr.simulate: the robot in motion (docs/dynamics.md) as numpy arrays."""
import json

import numpy as np
import pytest

import tdcr

SCENE = {
    "model": "ccsub",
    "robot": {
        "backbone": {"density": 6450},
        "segments": [
            {"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
            {"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
        ],
    },
    "actuation": {"tensions": [0, 0, 0, 0]},
    "dynamics": {"bending_damping_time": 0.004},
    "timeline": [{"t": 0}, {"t": 0.01, "actuation": {"tensions": [2, 0, 0, 0]}}],
}


def test_simulate_settles_on_the_static_answer():
    scene = tdcr.parse_scene(json.dumps(SCENE))
    r = tdcr.simulate(scene, 0.3, dt=0.01)
    assert r["completed"], r["message"]
    assert r["t"].shape == (31,) and r["tip"].shape == (31, 3) and r["rot"].shape == (31, 3)
    assert r["status"][-1] == "converged"
    static = dict(SCENE, actuation={"tensions": [2, 0, 0, 0]})
    del static["timeline"]
    sol = tdcr.solve(tdcr.parse_scene(json.dumps(static)))
    assert np.linalg.norm(r["tip"][-1] - np.asarray(sol.tip_position)) < 1e-6


def test_simulate_names_bad_input():
    scene = tdcr.parse_scene(json.dumps(SCENE))
    with pytest.raises(tdcr.InputError, match="dt"):
        tdcr.simulate(scene, 0.1, dt=0.0)
    with pytest.raises(tdcr.InputError, match="has no dynamics"):
        tdcr.simulate(scene, 0.1, model="cc")
