"""Solution arrays: shapes, units (m, N, N m) and consistency with each other."""
import math

import numpy as np
import pytest

import tdcr

MODELS = ["cc", "ccsub", "prb", "vc", "vcref"]


@pytest.mark.parametrize("kind", MODELS)
def test_shapes_and_frames(paper_scene, kind):
    sol = tdcr.solve(paper_scene, model=kind)
    assert sol.converged and sol.model == kind
    n = paper_scene.robot.total_disks() + 1  # base disk included
    m = paper_scene.robot.tendon_count()
    assert sol.disk_frames.shape == (n, 4, 4)
    assert sol.disk_positions.shape == (n, 3)
    np.testing.assert_array_equal(sol.disk_frames[:, 3, :], np.tile([0, 0, 0, 1.0], (n, 1)))
    np.testing.assert_array_equal(sol.disk_frames[0], np.eye(4))  # base disk at the base frame
    R = sol.disk_frames[:, :3, :3]
    np.testing.assert_allclose(np.einsum("kij,kil->kjl", R, R), np.tile(np.eye(3), (n, 1, 1)), atol=1e-12)
    assert sol.tip.shape == (4, 4) and sol.tip_position.shape == (3,) and sol.tip_rotation.shape == (3, 3)
    np.testing.assert_array_equal(sol.tip[:3, 3], sol.tip_position)
    assert sol.tensions.shape == (m,) and sol.tendon_displacements.shape == (m,)
    np.testing.assert_allclose(sol.tensions, paper_scene.actuation.values, rtol=0, atol=1e-12)
    # metres: a 0.1 m robot bent by ~30 deg in its first segment; the tip is below 0.1 m high
    length = paper_scene.robot.total_length()
    assert 0.08 < sol.tip_position[2] < length
    chord = np.linalg.norm(np.diff(sol.disk_positions, axis=0), axis=1)
    np.testing.assert_allclose(chord, 0.005, rtol=2e-3)  # 5 mm disk spacing (arc ~ chord)
    # tendon 1 is pulled (positive displacement, mm scale), tendon 2 released
    assert 1e-4 < sol.tendon_displacements[0] < 5e-3
    assert sol.tendon_displacements[1] < 0
    # not requested: empty arrays, not None
    assert sol.tip_jacobian.shape == (0, 0) and sol.tip_compliance.shape == (0, 0)
    s = sol.summary
    assert s.termination == sol.termination == "converged"
    assert s.iterations == sol.iterations >= 0 and s.residual_norm == sol.residual_norm
    assert s.solve_time_s == sol.solve_time_s > 0
    # tendons only, a direct solve: the automatic stability rule does not test it
    assert isinstance(sol.message, str) and sol.stability.status == "undetermined"
    assert sol.stability.method == ("kinematic model" if kind == "cc" else "not checked")
    assert sol.path_events == [] and sol.geometry_warnings == []


@pytest.mark.parametrize("kind", ["vc", "vcref"])
def test_backbone_samples(paper_scene, kind):
    sol = tdcr.solve(paper_scene, model=kind)
    M = len(sol.backbone_s)
    assert M > paper_scene.robot.total_disks()
    assert sol.backbone_positions.shape == (M, 3) and sol.backbone_frames.shape == (M, 4, 4)
    assert sol.backbone_n.shape == (M, 3) and sol.backbone_m.shape == (M, 3)
    assert sol.backbone_s[0] == 0.0 and math.isclose(sol.backbone_s[-1], 0.1, abs_tol=1e-15)
    np.testing.assert_allclose(sol.backbone_positions[-1], sol.tip_position, atol=1e-12)
    # no external load: the moment at the base balances the pulled tendon, T * r_d (N m) about x
    # (VC exactly; VCref's discrete disk forces of Eq. 58 within 0.1 %)
    T, r = paper_scene.actuation.values[0], 0.008
    np.testing.assert_allclose(sol.backbone_m[0], [-T * r, 0, 0], rtol=1e-6 if kind == "vc" else 1e-3, atol=1e-9)


def test_jacobian_and_compliance_shapes(paper_scene):
    scene = paper_scene.copy()
    scene.solver.differential_kinematics = True
    sol = tdcr.solve(scene, model="vc")
    assert sol.tip_jacobian.shape == (6, 4) and sol.tip_compliance.shape == (6, 6)
    # stiffening by a tip force along +y moves the tip along +y (m/N, positive)
    assert sol.tip_compliance[1, 1] > 0


def test_effects_and_options_reach_the_solver(paper_scene):
    scene = paper_scene.copy()
    scene.solver.integrator = "cvode"
    scene.solver.stability = True
    scene.effects.shear_extension = False
    scene.effects.disk_normal_force = "kept"
    sol = tdcr.solve(scene, model="vc")
    assert sol.converged and sol.summary.integrator == "cvode"
    assert sol.stability.status == "stable"
    d = scene.to_dict()
    assert d["solver"]["integrator"] == "cvode" and d["effects"]["shear_extension"] is False
    base = tdcr.solve(paper_scene, model="vc")
    assert np.linalg.norm(sol.tip_position - base.tip_position) < 1e-4  # same robot, small changes
    assert not np.array_equal(sol.tip_position, base.tip_position)


def test_stability_rule_is_auto_true_or_false(paper_scene):
    scene = paper_scene.copy()
    assert scene.solver.stability == "auto"
    scene.loads.tip_force = [0.05, 0.0, 0.0]
    # a loaded direct solve is not tested under "auto" (answers of a loading path are)
    assert tdcr.solve(scene, model="vc").stability.method == "not checked"
    scene.solver.stability = False
    assert tdcr.solve(scene, model="vc").stability.method == "not checked"
    assert scene.to_dict()["solver"]["stability"] is False
    scene.solver.stability = True
    assert scene.solver.stability is True and scene.to_dict()["solver"]["stability"] is True
    assert tdcr.solve(scene, model="vc").stability.status == "stable"
    scene.solver.stability = "auto"
    assert scene.to_dict()["solver"]["stability"] == "auto"
    with pytest.raises(tdcr.InputError, match="solver.stability"):
        scene.solver.stability = "always"
