"""twinsim from Python: models, simulations stepped through the delay loop, and the
commands as functions returning NumPy arrays and dicts (docs/api.md).

    import twinsim
    sim = twinsim.OmniSim(twinsim.load_omni_model("models/omni4.yaml"), backend="ode")
    run = sim.run(commands=np.tile([1.0, 0.0, 0.5], (90, 1)))   # 3 s at 30 fps
    plt.plot(run["truth"][:, 0, 0], run["truth"][:, 0, 1])

Errors are twinsim.InputError (a ValueError) with the command line's
"path:line: what is wrong" messages, and twinsim.CheckFailed (a RuntimeError) when a
simulation diverges.
"""
import json as _json

from ._twinsim import (  # noqa: F401  (the public names)
    ArmModel,
    ArmPredictor,
    ArmSim,
    CheckFailed,
    InputError,
    OmniModel,
    OmniObserver,
    OmniPredictor,
    OmniSim,
    Scene,
    arm_model_from_urdf,
    arm_model_from_yaml,
    available_backends,
    load_arm_model,
    load_omni_model,
    load_scene,
    omni_model_from_yaml,
)
from . import _twinsim

__all__ = [
    "ArmModel", "ArmPredictor", "ArmSim", "CheckFailed", "InputError", "OmniModel", "OmniObserver", "OmniPredictor",
    "OmniSim", "Scene", "arm_model_from_urdf", "arm_model_from_yaml", "available_backends",
    "load_arm_model", "load_model", "load_omni_model", "load_scene", "omni_model_from_yaml",
    "replay", "training_data", "train", "identify", "diagnose", "compare", "tune_pid", "batch", "ilc", "run",
]


def load_model(path):
    """An arm (URDF or YAML with `robot: arm`, its own or from the file it extends) or omni
    model, as the file says."""
    if _twinsim._model_robot(str(path)) == "arm":
        return load_arm_model(path)
    return load_omni_model(path)


def replay(model, log, backend="analytic", horizon=4, predictor=None, state="observer"):
    """`twinsim replay` without files.

    Omni: `log` is an (N, 7) array t,x,y,theta,vx_cmd,vy_cmd,omega_cmd (or a CSV path);
    returns an (N, 4) array t,x,y,theta of the model's K-frame predictions, each from the
    state the model's Kalman filter estimated K frames earlier (state="tracker": from the
    open-loop tracker, as `replay --state tracker`).
    Arm: `log` is a dict of arrays t (N), q and tau (N, n), optionally qd, qdd (or a
    CSV path); returns the model's (N, n) torques for the logged motion.
    """
    if isinstance(model, ArmModel):
        return _twinsim._replay_arm(model, log)
    return _twinsim._replay_omni(model, log, backend, int(horizon), predictor, state)


def training_data(model, logs, horizon=1):
    """(X, Y) of the omni predictor: X (N, 42 + 3(H-1)) inputs, Y (N, 3) pose changes in
    the robot frame (docs/learning.md), from one log or a list of logs."""
    return _twinsim._training_data(model, logs, int(horizon))


def train(model, logs, kind="linear", horizon=1, residual=False, seed=1, epochs=400, hidden=(32, 32),
          nominal_engine="analytic", nominal_state="auto"):
    """`twinsim train` without files: an OmniPredictor or ArmPredictor (save() writes it).
    residual=True learns the correction to the model's own prediction (omni: the Newtonian
    robot on nominal_engine, carried along the log by its observer or the open-loop
    tracker, nominal_state "observer", "tracker" or "auto": both trained, the one whose
    held-out rollouts come nearer kept; docs/learning.md)."""
    if isinstance(model, ArmModel):
        return _twinsim._train_arm(model, logs, kind, bool(residual), int(seed), int(epochs), list(hidden))
    return _twinsim._train_omni(model, logs, kind, int(horizon), bool(residual), nominal_engine, nominal_state,
                                int(seed), int(epochs), list(hidden))


def identify(model, logs):
    """`twinsim identify` without files: the arm model with identified base parameters
    and friction."""
    return _twinsim._identify(model, logs)


def diagnose(model, logs, held_out=0.4, max_effects=3, backend="analytic", threads=0, refit_model=False):
    """`twinsim diagnose` without files: (report, repaired model); the report is the
    dict of report.json (CONTRACT.md). refit_model: re-identify the model's own
    parameters on the fit blocks first, as `--refit-model` (arms: inertia and friction;
    omni robots: the response, as `twinsim identify`)."""
    text, repaired = _twinsim._diagnose(model, logs, float(held_out), int(max_effects), backend, int(threads),
                                        bool(refit_model))
    return _json.loads(text), repaired


def compare(model, log, backends=(), predictor=None):
    """`twinsim compare` without files: {"rows": [one dict per source and horizon with
    position_rmse (m), position_max (m), heading_rmse (rad), ...], "free_runs": {source:
    (N, 4) array t,x,y,theta}, "frame_rate": Hz}. Default backends: every physics engine
    built, plus learned when a predictor is given."""
    return _twinsim._compare(model, log, list(backends), predictor)


def tune_pid(scene, iterations=0, backend="", threads=0, seed=None, start=""):
    """`twinsim tune-pid` without files: {"learning": rows of learning.csv as dicts,
    "parameters": (iterations, 18) array, "parameter_names", "best": {name: value},
    "best_score", "test_runs"}. `scene` is a Scene or a path; 0 / "" keep the scene's."""
    if isinstance(scene, str):
        scene = load_scene(scene)
    return _twinsim._tune_pid(scene, int(iterations), backend, int(threads), seed, start)


def batch(sweep, out, jobs=0, resume=False):
    """`twinsim batch`: runs the sweep file into the folder `out` (its job folders are
    the product) and returns summary.csv as {"columns": {name: array of numbers}, ...};
    text columns (status, error) are read with the csv module from "summary_csv"."""
    result = _twinsim._batch(str(sweep), str(out), int(jobs), bool(resume))
    import csv
    with open(result["summary_csv"], newline="") as f:
        rows = list(csv.DictReader(f))
    for name, values in result["columns"].items():
        if values is None:
            result["columns"][name] = [r[name] for r in rows]
    return result


def ilc(scene, trials=-1, backend=""):
    """`twinsim ilc` without files, for an arm scene file: {"rms", "max": (trials + 1, n)
    tracking errors per trial and joint (rad or m), "frequency" (Hz) and
    "process_sensitivity" (n, postures, lines, complex), "postures", "filters" (one line
    per joint), "reduction", "diverged", "backend"}. -1 / "" keep the scene's."""
    return _twinsim._ilc(str(scene), int(trials), backend)


def run(scene, backend="", predictor=None, seed=None):
    """`twinsim run` without files. Omni scene: the dict of OmniSim.run (t, truth,
    truth_velocity, observed, seen, command; frames x robots x 3). Arm scene: the task
    under the scene's controller: t, q, qd, q_ref, command, applied (N x n), error_rms,
    error_max. `predictor` is a file for the learned backend; "" keeps the scene's
    backend."""
    scene = str(scene)
    with open(scene, encoding="utf-8", errors="replace") as f:
        arm = any(line.split("#")[0].replace(" ", "").strip() == "robot:arm" for line in f)
    if arm:
        return _twinsim._run_arm_scene(scene, backend, predictor, seed)
    s = load_scene(scene)
    sim = OmniSim(s, backend=backend or s.backend, predictor=predictor, seed=seed, external=False)
    return sim.run(frames=s.frames)
