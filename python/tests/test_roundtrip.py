"""The module against the command line: every example scene gives the same answer both ways."""
import json
import subprocess

import numpy as np
import pytest

import tdcr
from conftest import EXAMPLES

SCENES = sorted(EXAMPLES.glob("*.json"))


def test_every_example_is_listed():
    assert len(SCENES) >= 8


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_same_answer_as_cli(path, cli):
    run = subprocess.run([cli, "solve", str(path), "--json"], capture_output=True, text=True, timeout=120)
    assert run.returncode in (0, 1), run.stderr
    ref = json.loads(run.stdout)
    sol = tdcr.solve(tdcr.Scene.from_file(str(path)))
    mine = sol.to_dict()
    assert mine["status"] == ref["status"]
    assert mine["model"] == ref["model"]
    assert mine["summary"]["termination"] == ref["summary"]["termination"]
    assert sol.converged == (ref["status"] == "converged")
    np.testing.assert_allclose(sol.tip_position, ref["tip"]["position"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.tip_rotation, ref["tip"]["rotation"], rtol=0, atol=1e-12)
    disks = np.array([d["position"] for d in ref["disks"]])
    np.testing.assert_allclose(sol.disk_positions, disks, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.tensions, ref["tensions"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.tendon_displacements, ref["tendon_displacements"], rtol=0, atol=1e-12)


def test_dict_scene_equals_file_scene(paper_scene):
    path = EXAMPLES / "paper_robot_vc.json"
    with open(path) as f:
        data = json.load(f)
    from_dict = tdcr.Scene.from_dict(data)
    assert from_dict.to_json() == paper_scene.to_json()
    # and back: a scene's dict parses to the same scene
    assert tdcr.Scene.from_dict(paper_scene.to_dict()).to_json() == paper_scene.to_json()


def test_field_by_field_equals_file(paper_scene):
    seg = lambda: tdcr.Segment(length=0.05, disks=10,
                               tendons=[tdcr.TendonSpec(0.0, 0.008), tdcr.TendonSpec(0.0, -0.008)])
    backbone = tdcr.Backbone()
    backbone.youngs_modulus = 2.11e11
    backbone.poisson_ratio = 0.3
    backbone.outer_radius = 0.0004
    scene = tdcr.Scene()
    scene.robot = tdcr.Robot(backbone, [seg(), seg()])
    scene.actuation = tdcr.Actuation(list(paper_scene.actuation.values))
    scene.model = "vc"
    a = tdcr.solve(scene)
    b = tdcr.solve(paper_scene)
    assert a.converged and b.converged
    np.testing.assert_array_equal(a.disk_frames, b.disk_frames)


def test_model_auto_matches_cli(paper_scene, cli):
    path = EXAMPLES / "paper_robot_vc.json"
    run = subprocess.run([cli, "solve", str(path), "--json", "--model", "auto", "--accuracy", "0.05"],
                         capture_output=True, text=True, timeout=120)
    ref = json.loads(run.stdout)
    choice = tdcr.choose_model(paper_scene, 0.05)
    sol = tdcr.solve(paper_scene, model="auto", accuracy=0.05)
    assert sol.model == choice.kind == ref["model"]
    assert sol.model_selection == ref["model_selection"] == "auto: " + choice.reason
    np.testing.assert_allclose(sol.tip_position, ref["tip"]["position"], rtol=0, atol=1e-12)
