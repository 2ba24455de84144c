"""The viewer's server side (tdcr.view.Session), without a browser: what a slider move asks and
what it answers. The page itself is tested in headless chromium (ctest viewer_browser)."""
import json
import os

import numpy as np
import pytest

import tdcr
from tdcr.view import Session

SCENE = os.path.join(os.environ.get("TDCR_SOURCE_DIR", "."), "examples", "paper_robot_vc.json")


def test_a_move_is_a_warm_step_with_the_answer_of_a_cold_solve():
    s = Session(SCENE)
    d = s.describe()
    assert d["ok"] and len(d["tendons"]) == 4 and "vc" in d["models"] and d["selected"] == ["vc"]
    assert all(t["min"] <= t["value"] <= t["max"] for t in d["tendons"])
    values = [t["value"] for t in d["tendons"]]
    first = s.solve({"models": ["vc", "ccsub"], "values": values})["results"]
    values[1] = 1.0
    moved = s.solve({"models": ["vc", "ccsub"], "values": values, "tip_force": [0.0, 0.05, 0.0]})["results"]
    scene = tdcr.Scene.from_file(SCENE)
    scene.actuation.values = np.array(values)
    scene.loads.tip_force = np.array([0.0, 0.05, 0.0])
    for a, b in zip(first, moved):
        assert a["ok"] and b["ok"], b
        cold = tdcr.solve(scene, model=b["model"])
        # The warm step's tip is the cold solve's within the default tip tolerance (1e-8 m).
        assert np.linalg.norm(np.array(b["tip"]) - cold.tip_position) < 1e-8
        assert np.linalg.norm(np.array(b["tip"]) - np.array(a["tip"])) > 1e-4
        json.dumps(b)  # what the page receives is JSON


@pytest.mark.parametrize("request_, field", [
    ({"models": ["vc"], "values": [1.0, float("nan"), 0.0, 0.0]}, "values[1]"),
    ({"models": ["vc"], "values": [1.0, 0.0]}, "values"),
    ({"models": [], "values": [0.0] * 4}, "models"),
    ({"models": ["vc"], "values": [0.0] * 4, "tip_force": [0.0, "x", 0.0]}, "tip_force[1]"),
])
def test_a_bad_request_names_the_field(request_, field):
    with pytest.raises(tdcr.InputError, match=field.replace("[", r"\[").replace("]", r"\]")):
        Session(SCENE).solve(request_)


def test_a_model_that_cannot_take_the_input_says_so_in_its_answer():
    r = Session(SCENE).solve({"models": ["cc", "vc"], "values": [1.0, 0, 0, 0], "tip_force": [0.1, 0, 0]})["results"]
    assert not r[0]["ok"] and "loads.tip_force" in r[0]["error"]
    assert r[1]["ok"]


def test_a_bad_scene_is_described_with_its_field_and_value(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps({"robot": {"backbone": {"youngs_modulus": 54e9, "outer_radius": 5e-4},
                                       "segments": [{"length": -0.1, "disks": 10, "tendons": [{"x": 0.008, "y": 0}]}]},
                             "actuation": {"tensions": [1]}}))
    d = Session(str(p)).describe()
    assert not d["ok"] and "robot.segments[0].length" in d["error"] and "-0.1" in d["error"]
