"""The inverse solve through Python: a target orientation given as a matrix must be a rotation
(orthonormal to 1e-9, det +1), else tdcr.InputError naming target.rotation and the matrix; a
rotation matrix is read as its rotation vector; the round trip of a forward solve's tip reaches it
to 1e-9 m with a verified minimum norm, and the result carries its diagnostics."""
import numpy as np
import pytest

import tdcr


@pytest.fixture
def paper_vc(paper_scene):
    model = tdcr.make_model("vc", paper_scene)
    ws = model.make_workspace()
    start = paper_scene.input()
    start.actuation.values = [0.0] * 4
    return paper_scene, model, ws, start


def rotation(axis, angle):
    """Rodrigues: the rotation matrix of a rotation vector angle * axis / |axis|."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K


# Matrices that are not rotations: they were read as the identity and "converged" at 1487 N.
NOT_ROTATIONS = [
    ("ones", np.ones((3, 3))),
    ("twice_identity", 2.0 * np.eye(3)),
    ("reflection", np.diag([1.0, 1.0, -1.0])),
    ("skewed", rotation([0, 1, 0], 0.3) + 1e-7),
    ("nan", np.full((3, 3), np.nan)),
]


@pytest.mark.parametrize("name,matrix", NOT_ROTATIONS, ids=[n for n, _ in NOT_ROTATIONS])
def test_a_rotation_matrix_must_be_a_rotation(paper_vc, name, matrix):
    scene, model, ws, start = paper_vc
    with pytest.raises(tdcr.InputError) as info:
        tdcr.inverse_solve(model, ws, start, [0.0, 0.01, 0.095], rotation=matrix)
    assert info.value.field == "target.rotation"
    assert info.value.value.startswith("[[")  # the matrix itself
    with pytest.raises(tdcr.InputError) as info:
        tdcr.InverseTarget(position=[0.0, 0.01, 0.095], rotation=matrix)
    assert info.value.field == "target.rotation"
    target = tdcr.InverseTarget(position=[0.0, 0.01, 0.095])
    with pytest.raises(tdcr.InputError):
        target.rotation = matrix


def test_a_rotation_matrix_is_read_as_its_rotation_vector():
    R = rotation([1.0, -2.0, 0.5], 0.7)
    t = tdcr.InverseTarget(position=[0.0, 0.0, 0.1], rotation=R)
    w = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5]) * 0.7
    assert np.linalg.norm(np.asarray(t.rotation) - w) < 1e-12
    # Orthonormal to 1e-9 (the tolerance) is accepted: a rotation rounded to ~12 digits.
    tdcr.InverseTarget(position=[0.0, 0.0, 0.1], rotation=np.round(R, 12))
    assert np.asarray(tdcr.InverseTarget(position=[0, 0, 0.1], rotation=np.eye(3)).rotation).tolist() == [0, 0, 0]


def test_pose_target_from_a_forward_solve_given_as_a_matrix(paper_vc):
    """The example's tip pose (tendon 1 at T_M), position and orientation as a matrix: reached
    by T_M on tendon 1 alone."""
    scene, model, ws, start = paper_vc
    f = tdcr.solve_with(model, ws, scene.input())
    r = tdcr.inverse_solve(model, ws, start, f.tip_position, rotation=f.tip_rotation)
    assert r.converged, r.brief_report()
    assert r.position_error <= 1e-9 and r.rotation_error <= 1e-8
    assert r.tensions[0] == pytest.approx(scene.input().actuation.values[0], abs=1e-6)


def test_round_trip_reaches_the_tip_with_verified_minimum_norm(paper_scene):
    """PRB at 20 disks per segment (a reported failure: 'unreachable'), from zero tensions."""
    d = paper_scene.to_dict()
    for seg in d["robot"]["segments"]:
        seg["disks"] = 20
    scene = tdcr.Scene.from_dict(d)
    model = tdcr.make_model("prb", scene)
    ws = model.make_workspace()
    forward = scene.input()
    forward.actuation.values = [2.493, 2.331, 0.3203, 2.498]
    tip = tdcr.solve_with(model, ws, forward).tip_position
    start = scene.input()
    start.actuation.values = [0.0] * 4
    r = tdcr.inverse_solve(model, ws, start, tip)
    assert r.converged and r.status == "converged", r.brief_report()
    assert r.position_error <= 1e-9
    assert np.linalg.norm(r.solution.tip_position - tip) <= 1e-9
    assert r.minimum_norm and r.optimality <= tdcr.InverseOptions().tension_tolerance
    assert r.tension_resolution > 0.0 and r.forward_solves > r.iterations
    assert np.all(r.tensions >= 0.0) and np.linalg.norm(r.tensions) < np.linalg.norm(forward.actuation.values)
