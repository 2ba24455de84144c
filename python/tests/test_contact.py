"""Contact with obstacles from Python: a scene dict with `environment`, the Solution's contacts,
and the error naming an obstacle through the base."""
import copy

import pytest

import tdcr

WALL = {
    "robot": {
        "backbone": {"youngs_modulus": 2.11e11, "poisson_ratio": 0.3, "outer_radius": 0.0004},
        "segments": [
            {"length": 0.05, "disks": 10, "disk_radius": 0.01, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
            {"length": 0.05, "disks": 10, "disk_radius": 0.01, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
        ],
    },
    "actuation": {"tensions": [2.0, 0.0, 1.0, 0.0]},
    "environment": {"obstacles": [{"type": "plane", "point": [0, 0.025, 0], "normal": [0, -1, 0]}]},
    "model": "ccsub",
}


@pytest.mark.parametrize("model", ["ccsub", "prb"])
def test_contacts_reach_python(model):
    d = copy.deepcopy(WALL)
    d["model"] = model
    sol = tdcr.solve(tdcr.Scene.from_dict(d))
    assert sol.converged, sol.message
    assert len(sol.contacts) == 1
    c = sol.contacts[0]
    assert c.body == "disk" and c.disk == 20 and c.obstacle == 0
    assert c.force > 0.05
    assert abs(c.gap) < 1e-9
    assert abs(c.point[1] - 0.025) < 1e-9
    assert c.normal[1] == pytest.approx(-1.0)
    back = tdcr.Scene.from_dict(d).to_dict()
    assert back["environment"]["obstacles"][0]["type"] == "plane"


def test_obstacle_through_the_base_is_named():
    d = copy.deepcopy(WALL)
    d["environment"]["obstacles"][0]["point"] = [0, 0.005, 0]
    with pytest.raises(tdcr.InputError) as e:
        tdcr.solve(tdcr.Scene.from_dict(d))
    assert "environment.obstacles[0]" in str(e.value)


def test_models_without_contact_refuse_obstacles():
    d = copy.deepcopy(WALL)
    d["model"] = "cc"
    with pytest.raises(tdcr.InputError) as e:
        tdcr.solve(tdcr.Scene.from_dict(d))
    assert "environment.obstacles" in str(e.value)
