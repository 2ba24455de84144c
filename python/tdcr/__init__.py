"""tdcr: kineto-static models of tendon-driven continuum robots (CC, CCsub, PRB, VC, VCref).

The classes and functions map 1:1 to the C++ library (docs/python.md):

    import tdcr
    scene = tdcr.Scene.from_file("examples/paper_robot_vc.json")
    sol = tdcr.solve(scene)                      # one-shot, scene.model or model="vcref"/"auto"
    m = tdcr.make_model("vc", scene)             # immutable model
    ws = m.make_workspace()                      # reusable memory
    sol2 = tdcr.solve_with(m, ws, scene.input(), scene.solver, warm_start=sol)

Units are SI (m, N, N m); arrays are numpy. Bad input raises tdcr.InputError (a ValueError with
`.field` and `.value`).
"""

from ._tdcr import (  # noqa: F401
    Actuation,
    CalibrationData,
    CalibrationResult,
    FittedParameter,
    Backbone,
    BackboneStiffness,
    Effects,
    GeometryWarning,
    InputError,
    InverseOptions,
    InverseResult,
    InverseTarget,
    Loads,
    ModelChoice,
    ModelInput,
    ModelWorkspace,
    PathEvent,
    PrbParameters,
    Robot,
    Scene,
    Segment,
    Solution,
    SolverOptions,
    SolverSummary,
    Stability,
    StaticModel,
    TendonFriction,
    TendonRoutingSpec,
    TendonSpec,
    choose_model,
    expected_model_error,
    inverse_solve,
    load_scene,
    make_model,
    model_names,
    parse_calibration_data,
    parse_scene,
    read_calibration_data,
    scene_to_json,
    simulate,
    solution_to_json,
    solve_with,
    validate_scene,
)
from ._tdcr import solve_scene as _solve_scene
from ._tdcr import _calibrate

import os as _os

__all__ = [name for name in dir() if not name.startswith("_")] + ["solve", "scene_from", "calibrate"]


def _input_error(field, value, reason):
    """An InputError as the C++ library raises it: "<field>: <reason> (got <value>)"."""
    error = InputError("%s: %s (got %s)" % (field, reason, value))
    error.field, error.value = field, value
    return error


def scene_from(source):
    """A Scene from a Scene (copied), a dict with the scene file's keys, or a path to a scene file
    (str, bytes or os.PathLike). Anything else raises InputError (field "scene") saying what is accepted."""
    if isinstance(source, Scene):
        return source.copy()
    if isinstance(source, dict):
        return Scene.from_dict(source)
    if isinstance(source, (str, bytes, _os.PathLike)):
        return Scene.from_file(_os.fsdecode(source))
    text = repr(source)
    raise _input_error("scene", text if len(text) <= 80 else text[:77] + "...",
                       "must be a Scene, a dict with the scene file's keys, or the path of a scene file "
                       "(str or os.PathLike), not %s" % type(source).__name__)


def solve(scene, model=None, warm_start=None, accuracy=0.01):
    """Solve a scene once (a fresh model and workspace), as `tdcr solve SCENE --model MODEL`.

    scene: a Scene, a dict or a path. model: a model name ("cc", "ccsub", "prb", "vc", "vcref") or
    "auto" (the cheapest model expected to meet `accuracy`, a fraction of the robot length);
    None keeps scene.model. warm_start: a converged Solution of the same model and robot.
    Raises InputError on bad input; a solve that does not converge returns a Solution whose
    `converged` is False.
    """
    s = scene_from(scene)
    if model is not None:
        s.model = model.lower() if model.lower() == "auto" else model
    return _solve_scene(s, accuracy, warm_start)


def calibrate(scene, data, model=None, fit="youngs_modulus", loss="huber", loss_scale=3.0, position_std=1e-4,
              rotation_std=1e-3, max_iterations=100, warm_start=True, differences=False):
    """Fit a model's parameters to measured shapes, as `tdcr calibrate SCENE DATA --model M --fit ...`
    (docs/calibration.md).

    scene: a Scene, a dict or a path. data: the path of a data file (CSV in the sweep CSV's columns)
    or a CalibrationData. model: a model name (None keeps scene.model). fit: parameter names
    separated by commas (or a list), each optionally with bounds as name:LOWER:UPPER, e.g.
    "youngs_modulus,segment_offset_scale,base_offset". loss: "huber", "cauchy" or "none", with
    loss_scale in standard deviations. position_std (m) and rotation_std (rad): standard
    deviations where the data give none. warm_start=False solves every measurement cold;
    differences=True makes the Jacobian by re-solving instead of the implicit function theorem
    (`--cold`, `--differences`). Returns a CalibrationResult (fitted values with standard
    errors, correlation, residuals before and after, the calibrated scene); bad input (a bad row,
    an unknown parameter, a negative bound) raises InputError naming the line and column or the
    entry.
    """
    s = scene_from(scene)
    if model is not None:
        s.model = model
    if not isinstance(fit, str):
        fit = ",".join(fit)
    if not isinstance(data, CalibrationData):
        if not isinstance(data, (str, bytes, _os.PathLike)):
            raise _input_error("data", repr(data)[:80], "must be the path of a data file or a CalibrationData")
        data = read_calibration_data(_os.fsdecode(data), s)
    return _calibrate(s, data, s.model, fit, loss, float(loss_scale), float(position_std), float(rotation_std),
                      int(max_iterations), bool(warm_start), bool(differences))
