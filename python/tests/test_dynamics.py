"""tdcr.simulate: the robot in motion (docs/dynamics.md) as numpy arrays."""
import json

import numpy as np
import pytest

import tdcr

from dynamics_scene import SCENE


def test_simulate_settles_on_the_static_answer():
    scene = tdcr.parse_scene(json.dumps(SCENE))
    r = tdcr.simulate(scene, 0.3, dt=0.01)
    assert r["completed"], r["message"]
    assert r["t"].shape == (31,) and r["tip"].shape == (31, 3) and r["rot"].shape == (31, 3)
    assert r["status"][-1] == "converged"
    static = dict(SCENE, actuation={"tensions": [2, 0, 0, 0]})
    del static["timeline"]
    sol = tdcr.solve(tdcr.parse_scene(json.dumps(static)))
    assert np.linalg.norm(r["tip"][-1] - np.asarray(sol.tip_position)) < 1e-6


def test_simulate_names_bad_input():
    scene = tdcr.parse_scene(json.dumps(SCENE))
    with pytest.raises(tdcr.InputError, match="dt"):
        tdcr.simulate(scene, 0.1, dt=0.0)
    with pytest.raises(tdcr.InputError, match="has no dynamics"):
        tdcr.simulate(scene, 0.1, model="cc")


def _vc_pull_scene():
    # VC, tendon 1 pulled by 1 mm within 20 ms (displacement), the others by tension 0.
    scene = dict(SCENE, model="vc")
    scene["dynamics"] = {"bending_damping_time": 0.01, "shear_damping_time": 0.01}
    rest = {"displacements": [0, None, None, None], "tensions": [None, 0, 0, 0]}
    pulled = {"displacements": [0.001, None, None, None], "tensions": [None, 0, 0, 0]}
    scene["actuation"] = rest
    scene["timeline"] = [{"t": 0, "actuation": rest}, {"t": 0.02, "actuation": pulled}]
    return scene


def test_cli_simulate_writes_npz_that_numpy_reads(cli, tmp_path):
    import subprocess
    import zipfile

    path = tmp_path / "scene.json"
    path.write_text(json.dumps(_vc_pull_scene()))
    npz, csv = tmp_path / "out.npz", tmp_path / "out.csv"
    for out in (npz, csv):
        r = subprocess.run([cli, "simulate", str(path), "--duration", "0.1", "--dt", "0.01", "-o", str(out)],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert r.stderr == ""  # no progress bar: standard error is no terminal
    with zipfile.ZipFile(npz) as z:
        assert z.testzip() is None  # every member's CRC-32 checks
        assert all(i.compress_type == zipfile.ZIP_STORED for i in z.infolist())
    d = np.load(npz)
    n = 11
    assert d["t"].shape == (n,) and d["tip"].shape == (n, 3) and d["rot"].shape == (n, 3)
    assert d["tensions"].shape == (n, 4) and d["tendon_displacements"].shape == (n, 4)
    assert d["disks"].shape == (n, 7, 3)  # 2 x 3 disks and the base
    assert d["iterations"].dtype == np.int64 and list(d["status"]) == ["converged"] * n
    # The same numbers as the CSV (printed with 12 digits).
    rows = np.genfromtxt(csv, delimiter=",", names=True, dtype=None, encoding=None)
    assert np.allclose(d["t"], rows["t"], rtol=0, atol=1e-12)
    assert np.allclose(d["tip"][:, 1], rows["tip_y"], rtol=1e-10, atol=1e-14)
    assert np.allclose(d["tensions"][:, 0], rows["T_1"], rtol=1e-10, atol=1e-14)
    # Physics: the tip is the last disk; the pulled tendon meets its command once the ramp is
    # done and carries tension; the others, given by tension 0, carry exactly none.
    assert np.array_equal(d["disks"][:, -1, :], d["tip"])
    assert abs(d["tendon_displacements"][-1, 0] - 0.001) < 1e-9
    assert d["tensions"][-1, 0] > 0.1
    assert np.all(d["tensions"][:, 1:] == 0.0)
    assert d["potential_energy"][-1] > 0 and d["kinetic_energy"][0] == 0


def test_simulate_displacement_input_reports_tensions():
    # The Python front end: VC under a displacement timeline returns each step's solved tensions
    # and pulls; the static displacement solve of the held command is where it settles.
    scene = _vc_pull_scene()
    r = tdcr.simulate(tdcr.parse_scene(json.dumps(scene)), 0.3, dt=0.01)
    assert r["completed"], r["message"]
    assert r["tensions"].shape == (31, 4) and r["tendon_displacements"].shape == (31, 4)
    assert np.all(r["tensions"][:, 1:] == 0.0)
    static = dict(scene, actuation=scene["timeline"][1]["actuation"])
    del static["timeline"]
    sol = tdcr.solve(tdcr.parse_scene(json.dumps(static)))
    # The statics on their own mesh, the dynamics on theirs (2 RK4 steps per disk interval):
    # measured 7.7e-11 m, 7e-12 N apart.
    assert np.linalg.norm(r["tip"][-1] - np.asarray(sol.tip_position)) < 1e-8
    assert abs(r["tensions"][-1, 0] - sol.tensions[0]) < 1e-8 * sol.tensions[0]
    # CCsub's dynamics refuse its inextensible driven tendon, naming the tendon's stiffness field
    # (they take elastic ones: docs/dynamics.md, "Displacement input").
    with pytest.raises(tdcr.InputError, match=r"robot\.segments\[0\]\.tendons\[0\]\.stiffness"):
        tdcr.simulate(tdcr.parse_scene(json.dumps(dict(scene, model="ccsub"))), 0.1)
