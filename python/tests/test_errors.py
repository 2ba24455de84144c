"""Bad input raises tdcr.InputError (a ValueError) naming the field and the value, as the C++ API
and the command line do (cases from tests/bad_scene_inputs.hpp, same field names)."""
import copy
import json

import pytest

import tdcr
from conftest import EXAMPLES

BASE = {
    "robot": {
        "backbone": {"youngs_modulus": 2.11e11, "poisson_ratio": 0.3, "outer_radius": 0.0004},
        "segments": [
            {"length": 0.05, "disks": 10, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
            {"length": 0.05, "disks": 10, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
        ],
    },
    "actuation": {"tensions": [1.0, 0.0, 0.0, 0.0]},
    "model": "vc",
}


def edited(path, value):
    d = copy.deepcopy(BASE)
    *parents, last = path
    node = d
    for p in parents:
        node = node[p]
    node[last] = value
    return d


# (name, scene dict, field, text the message contains): a subset of bad_scene_inputs.hpp.
CASES = [
    ("LengthNegative", edited(["robot", "segments", 1, "length"], -0.05), "robot.segments[1].length", "-0.05"),
    ("LengthString", edited(["robot", "segments", 1, "length"], "0.05"), "robot.segments[1].length", '"0.05"'),
    ("DisksZero", edited(["robot", "segments", 0, "disks"], 0), "robot.segments[0].disks", "0"),
    ("DisksFloat", edited(["robot", "segments", 0, "disks"], 2.5), "robot.segments[0].disks", "2.5"),
    ("TendonOnAxis", edited(["robot", "segments", 0, "tendons", 1], {"x": 0, "y": 0}),
     "robot.segments[0].tendons[1]", "(0, 0)"),
    ("InnerRadiusTooLarge", edited(["robot", "backbone", "inner_radius"], 0.0005), "robot.backbone.inner_radius",
     "0.0005"),
    ("TensionNegative", edited(["actuation", "tensions", 2], -1.0), "actuation.tensions[2]", "-1"),
    ("TensionsTooFew", edited(["actuation", "tensions"], [1.0, 0.0, 0.0]), "actuation.tensions", "3 values"),
    ("TipForceTwoValues", edited(["loads"], {"tip_force": [0, 0.5]}), "loads.tip_force", "[0,0.5]"),
    ("UnknownSegmentKey", edited(["robot", "segments", 0, "lenght"], 0.05), "robot.segments[0].lenght",
     'did you mean "length"'),
    ("PrbKThetaNegative", edited(["effects"], {"prb": {"k_theta": [3.25, -2.84, 2.95]}}), "effects.prb.k_theta[1]",
     "-2.84"),
    ("IntegratorUnknown", edited(["solver"], {"integrator": "euler"}), "solver.integrator", '"euler"'),
    ("Rk4StepsZero", edited(["solver"], {"rk4_steps": 0}), "solver.rk4_steps", "0"),
    ("ModelUnknown", edited(["model"], "cosserat"), "model", '"cosserat"'),
]


@pytest.mark.parametrize("name,data,field,text", CASES, ids=[c[0] for c in CASES])
def test_bad_scene_dict(name, data, field, text):
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(data).validate()  # the parser, then the models layer (model name)
    assert info.value.field == field
    assert text in str(info.value)
    assert isinstance(info.value, ValueError)
    # the same text through the JSON parser and through solve
    with pytest.raises(tdcr.InputError) as again:
        tdcr.solve(tdcr.Scene.from_json(json.dumps(data)))
    assert again.value.field == field


def test_missing_file():
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_file(str(EXAMPLES / "no_such_scene.json"))
    assert info.value.field.endswith("no_such_scene.json")


def test_field_by_field_values_are_validated(paper_scene):
    scene = paper_scene.copy()
    scene.robot.segments[1].length = -0.05  # segments are mutable in place
    with pytest.raises(tdcr.InputError) as info:
        tdcr.solve(scene)
    assert info.value.field == "robot.segments[1].length"
    assert info.value.value == "-0.05"
    with pytest.raises(tdcr.InputError) as info:
        tdcr.make_model("vc", scene)
    assert info.value.field == "robot.segments[1].length"


def test_enum_strings_are_checked(paper_scene):
    with pytest.raises(tdcr.InputError) as info:
        paper_scene.solver.integrator = "euler"
    assert info.value.field == "solver.integrator" and info.value.value == '"euler"'
    with pytest.raises(tdcr.InputError) as info:
        paper_scene.effects.disk_normal_force = "ignored"
    assert info.value.field == "effects.disk_normal_force"
    with pytest.raises(tdcr.InputError):
        tdcr.make_model("cosserat", paper_scene)


def test_model_input_and_workspace_checks(paper_scene):
    vc = tdcr.make_model("vc", paper_scene)
    cc = tdcr.make_model("cc", paper_scene)
    ws = vc.make_workspace()
    bad = paper_scene.input()
    bad.actuation.values = [1.0, 0.0, -2.0, 0.0]
    with pytest.raises(tdcr.InputError) as info:
        tdcr.solve_with(vc, ws, bad, paper_scene.solver)
    assert info.value.field == "actuation.tensions[2]"
    with pytest.raises(tdcr.InputError):  # a workspace of another model
        tdcr.solve_with(cc, ws, paper_scene.input(), paper_scene.solver)
    cc_sol = cc.solve(cc.make_workspace(), paper_scene.input())
    with pytest.raises(tdcr.InputError):  # a warm start of another model
        vc.solve(ws, paper_scene.input(), paper_scene.solver, warm_start=cc_sol)


def test_models_and_solutions_are_not_changed_through_their_views(paper_scene):
    m = tdcr.make_model("vc", paper_scene)
    m.robot.segments[0].length = 1.0
    assert m.robot.segments[0].length == 0.05
    sol = tdcr.solve(paper_scene)
    loads = sol.loads
    loads.tip_force = [5.0, 0.0, 0.0]
    assert sol.loads.tip_force[0] == 0.0
    with pytest.raises(ValueError):  # vectors are assigned whole, never changed silently in place
        sol.loads.tip_force[0] = 5.0
    with pytest.raises(ValueError):
        paper_scene.actuation.values[0] = 1.0
    paper_scene.actuation.values = [1.0, 0.0, 0.0, 0.0]
    assert paper_scene.actuation.values[0] == 1.0
