"""Calibration through Python: tdcr.calibrate fits E back from data its own model made, and bad
data or parameters raise tdcr.InputError naming the line and column or the entry."""
import numpy as np
import pytest

import tdcr

E = 2.11e11


def write_data(path, scene, rows=8):
    """Tip positions of CCsub at random tensions and transverse tip forces, as a data file."""
    model = tdcr.make_model("ccsub", scene)
    ws = model.make_workspace()
    options = scene.solver
    options.function_tolerance = 1e-12
    rng = np.random.default_rng(7)
    lines = ["actuation.tensions[0],actuation.tensions[1],actuation.tensions[2],actuation.tensions[3],"
             "loads.tip_force[0],tip_x,tip_y,tip_z"]
    for _ in range(rows):
        t = rng.uniform(0.0, 2.0, 4)
        f = rng.uniform(-0.1, 0.1)
        inp = scene.input()
        inp.actuation.values = list(t)
        inp.loads.tip_force = [f, 0.0, 0.0]
        sol = tdcr.solve_with(model, ws, inp, options)
        assert sol.converged
        p = sol.tip_position
        lines.append(",".join("%.17g" % v for v in [*t, f, *p]))
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_calibrate_recovers_youngs_modulus(paper_scene, tmp_path):
    data = write_data(tmp_path / "data.csv", paper_scene)
    start = paper_scene.copy()
    start.robot.backbone.youngs_modulus = 1.3 * E
    r = tdcr.calibrate(start, data, model="ccsub", fit=["youngs_modulus"])
    assert r.converged, r.summary.brief_report()
    assert abs(r.values["youngs_modulus"] / E - 1.0) < 1e-6
    assert r.parameters[0].name == "youngs_modulus" and r.parameters[0].identifiable
    assert np.isfinite(r.parameters[0].std_error)
    assert r.summary.before.rms_position > 1e-3 and r.summary.after.rms_position < 1e-9
    assert abs(r.scene.robot.backbone.youngs_modulus / E - 1.0) < 1e-6
    assert r.correlation.shape == (1, 1) and r.base.shape == (4, 4)
    assert len(r.residuals_after) == 8 and r.residuals_after[0].line == 2
    assert r.summary.linearised_answers > 0
    d = tdcr.calibrate(start, data, model="ccsub", fit=["youngs_modulus"], differences=True)
    assert d.summary.linearised_answers == 0
    assert abs(d.values["youngs_modulus"] / r.values["youngs_modulus"] - 1.0) < 1e-9


def test_bad_row_names_line_and_column(paper_scene, tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("actuation.tensions[0],tip_x,tip_y,tip_z\n1,0,0,0.1\n1,0,abc,0.1\n")
    with pytest.raises(tdcr.InputError) as info:
        tdcr.calibrate(paper_scene, str(path), model="ccsub", fit="youngs_modulus")
    assert "line 3, column tip_y: not a number (got abc)" in str(info.value)
    assert info.value.value == "abc"


def test_unknown_parameter_and_negative_bound(paper_scene, tmp_path):
    data = write_data(tmp_path / "data.csv", paper_scene, rows=2)
    with pytest.raises(tdcr.InputError) as info:
        tdcr.calibrate(paper_scene, data, model="ccsub", fit="stiffness")
    assert info.value.field == "--fit"
    with pytest.raises(tdcr.InputError, match="must not be negative"):
        tdcr.calibrate(paper_scene, data, model="ccsub", fit="youngs_modulus:-1:")
    with pytest.raises(tdcr.InputError, match="cannot read the data file"):
        tdcr.calibrate(paper_scene, str(tmp_path / "missing.csv"), model="ccsub")
