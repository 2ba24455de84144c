"""`tdcr plot --animate OUT.gif|mp4` and `--trajectory OUT.png`: a simulation's pictures
(docs/dynamics.md, docs/python.md), and tdcr.simulate(..., shapes=True) under them."""
import copy
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import tdcr
import tdcr.plot

pytest.importorskip("matplotlib")
Image = pytest.importorskip("PIL.Image")

from dynamics_scene import SCENE  # a small CCsub robot, tendon 1 stepped to 2 N within 10 ms


def _write(tmp_path, doc, name="scene.json"):
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return str(path)


def test_simulate_shapes_gives_the_disks_of_every_step():
    scene = tdcr.parse_scene(json.dumps(SCENE))
    plain = tdcr.simulate(scene, 0.1, dt=0.01)
    r = tdcr.simulate(scene, 0.1, dt=0.01, shapes=True)
    assert "disks" not in plain
    assert r["completed"], r["message"]
    assert r["disks"].shape == (11, 7, 3)  # 11 steps; the base disk and 6 disks
    np.testing.assert_allclose(r["disks"][:, 0], 0.0, atol=1e-15)  # the base disk stays
    np.testing.assert_allclose(r["disks"][:, -1], r["tip"], atol=1e-12)  # the last disk is the tip
    np.testing.assert_allclose(r["tip"], plain["tip"], atol=1e-12)  # the same steps as tdcr::simulate
    np.testing.assert_allclose(r["t"], plain["t"])


def test_animate_gif_has_a_frame_per_step_and_trajectory_png(tmp_path, capsys):
    scene = _write(tmp_path, SCENE)
    gif, png = tmp_path / "robot.gif", tmp_path / "tip.png"
    rc = tdcr.plot.main([scene, "--animate", str(gif), "--trajectory", str(png), "--duration", "0.2", "--dt", "0.01"])
    assert rc == 0, capsys.readouterr().err
    with Image.open(gif) as im:
        assert im.format == "GIF"
        assert im.n_frames == 21  # t = 0, 0.01, ..., 0.2
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10000
    assert "21 frames" in capsys.readouterr().out


def test_trajectory_alone(tmp_path):
    png = tmp_path / "tip.png"
    assert tdcr.plot.main([_write(tmp_path, SCENE), "--trajectory", str(png), "--duration", "0.05",
                           "--dt", "0.01"]) == 0
    assert png.stat().st_size > 10000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.json", "tip.png"]


@pytest.mark.parametrize("args,option,value", [
    (["--animate", "/nonexistent/dir/x.gif"], "--animate", "/nonexistent/dir/x.gif"),
    (["--animate", "x.avi"], "--animate", "x.avi"),
    (["--animate", "x.gif", "--fps", "0"], "--fps", "0.0"),
    (["--animate", "x.gif", "--fps", "-3"], "--fps", "-3.0"),
    (["--animate", "x.gif", "--duration", "0"], "--duration", "0.0"),
    (["--animate", "x.gif", "--dt", "-1"], "--dt", "-1.0"),
    (["--animate", "x.gif", "--dt", "1e-6"], "--dt", "1e-06"),
    (["--trajectory", "x.gif"], "--trajectory", "x.gif"),
    (["--trajectory", "/nonexistent/dir/x.png"], "--trajectory", "/nonexistent/dir/x.png"),
    (["--animate", "x.gif", "--model", "ccsub,prb"], "--model", "ccsub,prb"),
])
def test_bad_options_exit_2_naming_them(tmp_path, capsys, monkeypatch, args, option, value):
    monkeypatch.chdir(tmp_path)
    scene = _write(tmp_path, SCENE)
    assert tdcr.plot.main([scene] + args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: %s: " % option) and err.endswith(" (got %s)\n" % value), err
    assert err.count("\n") == 1, err  # one line, no traceback
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.json"]


@pytest.mark.parametrize("drop,field", [("timeline", "timeline"), ("dynamics", "dynamics")])
def test_scene_without_timeline_or_dynamics(tmp_path, capsys, drop, field):
    doc = copy.deepcopy(SCENE)
    del doc[drop]
    assert tdcr.plot.main([_write(tmp_path, doc), "--animate", str(tmp_path / "x.gif")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: %s: " % field) and err.count("\n") == 1, err
    assert not (tmp_path / "x.gif").exists()


def test_scene_without_mass(tmp_path, capsys):
    doc = copy.deepcopy(SCENE)
    del doc["robot"]["backbone"]["density"]
    assert tdcr.plot.main([_write(tmp_path, doc), "--animate", str(tmp_path / "x.gif")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "robot.backbone.density" in err and err.count("\n") == 1, err
    assert not (tmp_path / "x.gif").exists()


def test_output_and_animate_are_not_mixed(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        tdcr.plot.main([_write(tmp_path, SCENE), "-o", "x.png", "--animate", "x.gif"])
    assert info.value.code == 2
    assert "--animate" in capsys.readouterr().err


def test_mp4_without_ffmpeg_exits_2_naming_animate(tmp_path):
    # A matplotlibrc that points FFMpegWriter at no program: ffmpeg is missing.
    config = tmp_path / "mpl"
    config.mkdir()
    (config / "matplotlibrc").write_text("animation.ffmpeg_path: %s\n" % (tmp_path / "no-ffmpeg"))
    env = dict(os.environ, MPLCONFIGDIR=str(config), MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, "-m", "tdcr.plot", _write(tmp_path, SCENE), "--animate",
                          str(tmp_path / "x.mp4"), "--duration", "0.05", "--dt", "0.01"],
                         capture_output=True, text=True, env=env)
    assert run.returncode == 2, run.stderr
    assert run.stderr.startswith("error: --animate: ") and "ffmpeg" in run.stderr, run.stderr
    assert "Traceback" not in run.stderr
    assert not (tmp_path / "x.mp4").exists()


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed (Debian: ffmpeg)")
def test_mp4_with_ffmpeg(tmp_path):
    mp4 = tmp_path / "robot.mp4"
    assert tdcr.plot.main([_write(tmp_path, SCENE), "--animate", str(mp4), "--duration", "0.05",
                           "--dt", "0.01", "--fps", "10"]) == 0
    assert mp4.read_bytes()[4:8] == b"ftyp"


def test_through_the_tdcr_program(tmp_path, cli):
    # `tdcr plot` forwards to python3 -m tdcr.plot (apps/plot_command.cpp): the GIF and a bad --fps.
    scene, gif = _write(tmp_path, SCENE), tmp_path / "robot.gif"
    run = subprocess.run([cli, "plot", scene, "--animate", str(gif), "--duration", "0.05", "--dt", "0.01"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    with Image.open(gif) as im:
        assert im.n_frames == 6
    run = subprocess.run([cli, "plot", scene, "--animate", str(gif), "--fps", "0"], capture_output=True, text=True)
    assert run.returncode == 2 and run.stderr == "error: --fps: must be a positive number of frames per second (got 0.0)\n"
