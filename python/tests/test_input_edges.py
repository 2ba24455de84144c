"""Bad input at the edges of the Python front door: NaN and infinity in a scene dict, numpy values in
it, what tdcr.solve accepts, solver options out of their bounds, an interpreter without numpy, and
`tdcr plot`'s options (checked before any solve)."""
import copy
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import tdcr
import tdcr.plot
from conftest import EXAMPLES
from test_errors import BASE, edited


@pytest.mark.parametrize("path,value,field,text", [
    (["actuation", "tensions", 0], float("nan"), "actuation.tensions[0]", "nan"),
    (["robot", "segments", 1, "length"], float("inf"), "robot.segments[1].length", "inf"),
    (["loads"], {"tip_force": [0.0, -float("inf"), 0.0]}, "loads.tip_force[1]", "-inf"),
    (["robot", "backbone", "youngs_modulus"], np.float64("nan"), "robot.backbone.youngs_modulus", "nan"),
    (["actuation", "tensions"], np.array([1.0, np.nan, 0.0, 0.0]), "actuation.tensions[1]", "nan"),
    (["solver"], {"function_tolerance": np.float32("inf")}, "solver.function_tolerance", "inf"),
])
def test_non_finite_numbers_name_their_field(path, value, field, text):
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(edited(path, value))
    assert info.value.field == field
    assert info.value.value == text
    assert "malformed JSON" not in str(info.value)


def test_values_json_cannot_hold_name_their_field():
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(edited(["robot", "segments", 0, "length"], {0.05}))
    assert info.value.field == "robot.segments[0].length"
    assert "not set" in str(info.value)
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(edited(["loads"], {1: [0, 0, 0]}))
    assert info.value.field == "loads.1"
    assert "key must be a string" in str(info.value)
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict([BASE])
    assert info.value.field == "scene"


def test_numpy_scalars_and_arrays_are_numbers_and_lists():
    d = copy.deepcopy(BASE)
    d["robot"]["segments"][0]["disks"] = np.int64(10)
    d["robot"]["segments"][1]["length"] = np.float32(0.05)  # not a float subclass, unlike np.float64
    d["robot"]["backbone"]["youngs_modulus"] = np.float64(2.11e11)
    d["actuation"]["tensions"] = np.array([1.0, 0, 0, 0])
    d["loads"] = {"tip_force": np.array([0.0, 0.1, 0.0]), "gravity": (0, 0, np.float64(-9.81))}
    d["effects"] = {"shear_extension": np.bool_(False), "prb": {"gamma": np.array([0.1, 0.3, 0.4, 0.2])}}
    d["robot"]["segments"][0]["tendons"][0]["routing"] = {
        "type": "points", "positions": np.tile([0.0, 0.008], (10, 1))}
    scene = tdcr.Scene.from_dict(d)
    plain = json.loads(json.dumps(d, default=lambda v: v.tolist()))  # what the dict means
    assert scene.to_json() == tdcr.Scene.from_dict(plain).to_json()
    assert scene.robot.segments[0].disks == 10
    assert scene.robot.segments[1].length == pytest.approx(0.05, rel=1e-7)  # float32's precision
    assert list(scene.loads.tip_force) == [0.0, 0.1, 0.0]
    assert scene.effects.shear_extension is False
    assert scene.robot.segments[0].tendons[0].routing.positions.shape == (10, 2)
    assert tdcr.solve(d).converged


def test_solve_says_what_it_accepts():
    for bad in (None, 42, [BASE]):
        with pytest.raises(tdcr.InputError) as info:
            tdcr.solve(bad)
        assert info.value.field == "scene"
        text = repr(bad)
        assert info.value.value == (text if len(text) <= 80 else text[:77] + "...")
        assert "a Scene, a dict with the scene file's keys, or the path of a scene file" in str(info.value)
        assert "cannot be opened" not in str(info.value)
    path = EXAMPLES / "paper_robot_vc.json"
    for source in (path, str(path), os.fsencode(str(path))):  # os.PathLike, str and bytes paths
        assert tdcr.solve(source).converged


def test_solver_options_out_of_bounds_name_field_and_value():
    with pytest.raises(tdcr.InputError) as info:
        tdcr.Scene.from_dict(edited(["solver"], {"rk4_steps": 100000000}))
    assert (info.value.field, info.value.value) == ("solver.rk4_steps", "100000000")
    options = tdcr.SolverOptions()
    options.rk4_max_step = 1e-9
    with pytest.raises(tdcr.InputError) as info:
        options.validate()
    assert (info.value.field, info.value.value) == ("solver.rk4_max_step", "1e-09")


def test_without_numpy_the_import_error_says_so():
    """`python3 -S` leaves out site-packages and dist-packages, where numpy lives: an interpreter
    without numpy, as another python3 on PATH can be."""
    module_dir = pathlib.Path(tdcr.__file__).resolve().parents[1]
    probe = subprocess.run([sys.executable, "-S", "-c", "import numpy"], capture_output=True)
    if probe.returncode == 0:
        pytest.skip("numpy is importable without site-packages here")
    run = subprocess.run([sys.executable, "-S", "-c", "import sys; sys.path.insert(0, %r); import tdcr" % str(module_dir)],
                         capture_output=True, text=True)
    assert run.returncode != 0
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: tdcr needs numpy"), run.stderr
    assert sys.executable in last  # the interpreter that lacks numpy
    assert "This tdcr module was built for " in last and "(Python 3." in last
    assert "initialization failed" not in run.stderr


@pytest.mark.parametrize("args,option,value", [
    (["-o", "/nonexistent/dir/x.png"], "-o", "/nonexistent/dir/x.png"),
    (["-o", "x.png", "--dpi", "0"], "--dpi", "0"),
    (["-o", "x.png", "--dpi", "100000"], "--dpi", "100000"),
    (["-o", "x.bmp"], "-o", "x.bmp"),
])
def test_plot_options_are_checked_before_the_scene(tmp_path, capsys, monkeypatch, args, option, value):
    monkeypatch.chdir(tmp_path)
    # A scene that does not exist: the option is reported first, before any scene is read or solved.
    assert tdcr.plot.main([str(tmp_path / "no_such_scene.json")] + args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: %s: " % option) and err.endswith(" (got %s)\n" % value), err
    assert err.count("\n") == 1, err  # one line, no traceback
    assert not list(tmp_path.iterdir())


def test_plot_output_that_is_a_folder_or_under_a_file(tmp_path, capsys):
    scene = str(EXAMPLES / "paper_robot_vc.json")
    (tmp_path / "folder.png").mkdir()
    assert tdcr.plot.main([scene, "-o", str(tmp_path / "folder.png")]) == 2
    assert "-o: is a folder" in capsys.readouterr().err
    (tmp_path / "file").write_text("")
    assert tdcr.plot.main([scene, "-o", str(tmp_path / "file" / "x.png")]) == 2
    assert "is not a folder" in capsys.readouterr().err
