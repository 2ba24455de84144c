"""Tendon stiffness and routing, mixed actuation, tendon friction, the friction and slack outputs of a
Solution and the inverse solve: each reaches the solver and round-trips through Scene.to_dict()."""
import copy
import json
import subprocess

import numpy as np
import pytest

import tdcr
from conftest import EXAMPLES

PAPER = {
    "robot": {
        "backbone": {"youngs_modulus": 2.11e11, "poisson_ratio": 0.3, "outer_radius": 0.0004},
        "segments": [
            {"length": 0.05, "disks": 10, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
            {"length": 0.05, "disks": 10, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
        ],
    },
    "actuation": {"tensions": [1.0, 0.0, 0.5, 0.0]},
    "model": "ccsub",
}


def paper(**changes):
    d = copy.deepcopy(PAPER)
    d.update(changes)
    return d


def test_tendon_spec_keywords_and_positional():
    t = tdcr.TendonSpec(0.008, 0.0)
    assert t.stiffness is None and t.routing.type == "straight"
    t = tdcr.TendonSpec(0.008, 0.0, stiffness=2000.0, routing=tdcr.TendonRoutingSpec("helical", turns=0.5))
    assert t.stiffness == 2000.0 and t.routing.type == "helical" and t.routing.turns == 0.5
    t.routing.positions = [[0.001, 0.008], [0.002, 0.0079]]  # a list of pairs
    assert t.routing.positions.shape == (2, 2)
    t.routing.positions = np.array([[0.001, 0.008]])
    np.testing.assert_array_equal(t.routing.positions, [[0.001, 0.008]])
    with pytest.raises(tdcr.InputError) as info:
        t.routing.positions = [0.001, 0.008, 0.003]
    assert info.value.field == "routing.positions"


def test_helical_tendon_matches_cli(cli):
    path = EXAMPLES / "helical_tendon.json"
    scene = tdcr.Scene.from_file(str(path))
    tendons = scene.robot.segments[0].tendons
    assert tendons[0].routing.type == "helical" and tendons[0].routing.turns == 0.5
    assert tendons[1].routing.type == "points" and tendons[1].routing.positions.shape == (20, 2)
    again = tdcr.Scene.from_dict(scene.to_dict())
    assert again.to_dict() == scene.to_dict()
    sol = tdcr.solve(again)
    ref = json.loads(subprocess.run([cli, "solve", str(path), "--json"], check=True, capture_output=True,
                                    text=True).stdout)
    np.testing.assert_allclose(sol.tip_position, ref["tip"]["position"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.tip_rotation, ref["tip"]["rotation"], rtol=0, atol=1e-12)
    # The helix twists the tip: its x axis turns about z, which a straight tendon in the y-z plane
    # of bending would not do.
    assert abs(sol.tip_rotation[1, 0]) > 1e-2


def test_routing_built_in_python_reaches_the_solver():
    scene = tdcr.Scene.from_dict(paper(model="vc"))
    straight = tdcr.solve(scene)
    scene.robot.segments[1].tendons[0].routing = tdcr.TendonRoutingSpec("helical", turns=0.25)
    d = scene.to_dict()
    assert d["robot"]["segments"][1]["tendons"][0]["routing"] == {"type": "helical", "turns": 0.25}
    helical = tdcr.solve(scene)
    assert straight.converged and helical.converged
    assert np.linalg.norm(helical.tip_position - straight.tip_position) > 1e-3


def test_mixed_displacements_give_slack_flags():
    scene = tdcr.Scene.from_file(str(EXAMPLES / "paper_robot_displacements.json"))
    a = scene.actuation
    assert a.mixed and a.kind == "displacements"
    assert a.kinds == ["displacements", "displacements", "displacements", "tensions"]
    assert scene.robot.segments[1].tendons[0].stiffness == 2000.0
    again = tdcr.Scene.from_dict(scene.to_dict())
    assert again.to_dict() == scene.to_dict() and again.actuation.kinds == a.kinds
    sol = tdcr.solve(again)
    assert sol.converged
    assert sol.tendon_slack.dtype == bool and sol.tendon_slack.shape == (4,)
    assert sol.tendon_slack[1] and not sol.tendon_slack[0]  # the example's T2 is let out past slack
    assert sol.tensions[1] == 0.0 and sol.tensions[3] == pytest.approx(0.2)
    assert tdcr.solve(tdcr.Scene.from_dict(PAPER)).tendon_slack.size == 0  # tension input


def test_actuation_kinds_property():
    a = tdcr.Actuation([0.001, 0.5], kinds=["displacements", "tensions"])
    assert a.mixed and a.kind == "displacements" and a.kinds == ["displacements", "tensions"]
    a.kinds = ["tensions", "tensions"]  # one kind: stored as that kind, as the scene parser does
    assert not a.mixed and a.kind == "tensions" and a.kinds == []
    with pytest.raises(tdcr.InputError) as info:
        a.kinds = ["tensions", "forces"]
    assert info.value.field == "actuation.kinds[1]"
    scene = tdcr.Scene.from_dict(paper(model="vc"))
    scene.actuation = tdcr.Actuation([0.002, 0.0, 0.5, 0.0],
                                     kinds=["displacements", "tensions", "tensions", "tensions"])
    d = scene.to_dict()["actuation"]
    assert d["displacements"] == [0.002, None, None, None] and d["tensions"] == [None, 0.0, 0.5, 0.0]
    sol = tdcr.solve(scene)
    assert sol.converged and sol.tendon_displacements[0] == pytest.approx(0.002, abs=1e-9)


def test_friction_lowers_end_tensions_when_pulling():
    scene = tdcr.Scene.from_dict(paper())
    assert tdcr.solve(scene).tendon_end_tensions.size == 0  # no friction
    scene.effects.tendon_friction = tdcr.TendonFriction(coefficient=0.2, motion="pulling")
    d = scene.to_dict()
    assert d["effects"]["tendon_friction"] == {"coefficient": 0.2, "motion": "pulling"}
    again = tdcr.Scene.from_dict(d)
    assert again.effects.tendon_friction.coefficient == 0.2 and again.effects.tendon_friction.on
    sol = tdcr.solve(again)
    end = sol.tendon_end_tensions
    assert sol.converged and end.shape == (4,)
    assert end[0] < 1.0 and end[2] < 0.5 and end[0] > 0.5
    scene.effects.tendon_friction.motion = "releasing"
    assert tdcr.solve(scene).tendon_end_tensions[0] > 1.0


@pytest.mark.parametrize("kind", ["cc", "vc"])
def test_inverse_solve_reaches_a_forward_target(kind):
    scene = tdcr.Scene.from_dict(paper(model=kind))
    model = tdcr.make_model(kind, scene)
    ws = model.make_workspace()
    target = tdcr.solve_with(model, ws, scene.input()).tip_position
    start = scene.input()
    start.actuation.values = [0.0] * 4
    r = tdcr.inverse_solve(model, ws, start, target)
    assert r.converged and r.status == "converged", r.brief_report()
    assert r.position_error < 1e-6 and r.rotation_error == 0.0
    assert np.linalg.norm(r.solution.tip_position - target) < 1e-6
    assert r.tensions.shape == (4,) and np.all(r.tensions >= 0.0) and r.iterations >= 1
    assert "converged" in r.brief_report()
    # The same through an InverseTarget object.
    r2 = tdcr.inverse_solve(model, ws, start, tdcr.InverseTarget(position=target), options=scene.solver,
                            inverse_options=tdcr.InverseOptions())
    assert r2.converged and r2.position_error < 1e-6


def test_inverse_solve_bad_input():
    scene = tdcr.Scene.from_dict(paper(model="cc"))
    model = tdcr.make_model("cc", scene)
    ws = model.make_workspace()
    opts = tdcr.InverseOptions()
    opts.max_iterations = 0
    with pytest.raises(tdcr.InputError) as info:
        tdcr.inverse_solve(model, ws, scene.input(), [0.0, 0.01, 0.09], inverse_options=opts)
    assert info.value.field == "inverse.max_iterations"
    with pytest.raises(tdcr.InputError) as info:
        tdcr.inverse_solve(model, ws, scene.input(), [0.0, 0.01, 0.09], rotation=[1.0, 2.0])
    assert info.value.field == "target.rotation"


BAD = [
    ("FrictionNegative", {"effects": {"tendon_friction": {"coefficient": -0.1}}},
     "effects.tendon_friction.coefficient"),
    ("FrictionMotion", {"effects": {"tendon_friction": {"coefficient": 0.1, "motion": "sliding"}}},
     "effects.tendon_friction.motion"),
]


@pytest.mark.parametrize("name,change,field", BAD, ids=[b[0] for b in BAD])
def test_bad_effects_dict(name, change, field):
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(paper(**change)).validate()
    assert info.value.field == field


def test_bad_values_name_the_field():
    d = paper()
    d["robot"]["segments"][0]["tendons"][1]["stiffness"] = 0
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(d)
    assert info.value.field == "robot.segments[0].tendons[1].stiffness"
    d = paper()
    d["robot"]["segments"][0]["tendons"][0]["routing"] = {"type": "spiral"}
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(d)
    assert info.value.field == "robot.segments[0].tendons[0].routing.type"

    # The same values set field by field: the setters and validate() name them too.
    scene = tdcr.Scene.from_dict(paper())
    with pytest.raises(tdcr.InputError) as info:
        scene.robot.segments[0].tendons[0].routing.type = "spiral"
    assert info.value.field == "routing.type" and "spiral" in info.value.value
    scene.robot.segments[0].tendons[1].stiffness = 0.0
    with pytest.raises(tdcr.InputError) as info:
        scene.robot.validate()
    assert info.value.field == "robot.segments[0].tendons[1].stiffness"
    scene = tdcr.Scene.from_dict(paper())
    scene.effects.tendon_friction.coefficient = -0.1
    with pytest.raises(tdcr.InputError) as info:
        scene.effects.validate()
    assert info.value.field == "effects.tendon_friction.coefficient"
    scene.effects.tendon_friction = tdcr.TendonFriction(coefficients=[0.1, 0.1])
    scene.effects.validate()
    with pytest.raises(tdcr.InputError) as info:
        scene.effects.validate(scene.robot)
    assert info.value.field == "effects.tendon_friction.coefficients"
    with pytest.raises(tdcr.InputError) as info:
        tdcr.TendonFriction(motion="sliding")
    assert info.value.field == "effects.tendon_friction.motion"
