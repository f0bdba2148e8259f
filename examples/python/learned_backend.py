"""Record a plant, learn its motion with a least-squares fit written here in NumPy, and
run the fit as twinsim's learned backend, next to the physical model that knows neither
the plant's motor lag nor its slipping wheels (docs/api.md).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/learned_backend.py --out out/example

Prints both models' 4-frame prediction errors on a held-out log (learned about 9 mm,
physics about 59 mm with --quick) and writes OUT/paths.csv (t, then x and y of the plant, the learned model and the physical
model driven by the same commands) and, when matplotlib is installed, OUT/paths.png.
"""
import argparse
import os

import numpy as np

import twinsim

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def drive(frames, seed):
    """Random piecewise-constant commands (vx, vy m/s, omega rad/s), half a second each."""
    rng = np.random.default_rng(seed)
    steps = rng.uniform([-1.0, -1.0, -2.5], [1.0, 1.0, 2.5], size=(frames // 15 + 1, 3))
    return np.repeat(steps, 15, axis=0)[:frames]


def record(model, commands, seed):
    """The contract's log (t, x, y, theta, vx_cmd, vy_cmd, omega_cmd) of one run."""
    run = twinsim.OmniSim(model, backend="analytic", seed=seed).run(commands)
    log = np.column_stack([run["t"], run["observed"][:, 0], run["command"][:, 0]])
    return log[run["seen"][:, 0]]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out/python_example")
    parser.add_argument("--quick", action="store_true", help="two minutes of data instead of ten")
    args = parser.parse_args()

    nominal = twinsim.load_omni_model(os.path.join(ROOT, "models/omni4.yaml"))
    plant = nominal.copy()
    plant["effects.motor_lag.time_constant"] = 0.1    # s: what the physical model misses ...
    plant["effects.traction_limit.a_max"] = 1.2       # m/s^2: ... and the wheels slip
    minutes = 2 if args.quick else 10
    logs = [record(plant, drive(minutes * 60 * 30 // 4, seed), seed) for seed in range(1, 5)]

    # The fit: pose change one frame ahead from the last six frames (42 numbers).
    x, y = twinsim.training_data(nominal, logs, horizon=1)
    ridge = 1e-6 * np.eye(x.shape[1])
    weights = np.linalg.solve(x.T @ x + ridge, x.T @ y)          # (42, 3)
    predictor = twinsim.OmniPredictor.linear(nominal, weights.T, np.zeros(3), horizon=1, frame_rate=30.0)
    print(f"fitted {weights.size} weights on {len(x)} frames of {len(logs)} logs")

    # On a held-out log of the plant: each frame predicted 4 frames ahead (the contract's
    # replay) by the learned backend and by the physical model, which misses the lag.
    held_out = record(plant, drive(1800, 99), 99)
    for name, backend, p in (("learned", "learned", predictor), ("physics", "analytic", None)):
        r = twinsim.replay(nominal, held_out, backend=backend, predictor=p, horizon=4)
        error = np.sqrt(np.mean(np.sum((r[:, 1:3] - held_out[:, 1:3]) ** 2, axis=1)))
        print(f"{name:8s} 4-frame prediction error on the held-out log: {1000 * error:.1f} mm")

    # Ten seconds of new commands: the plant, the learned backend and the physical model.
    commands = drive(300, 98)
    paths = {}
    for name, model, backend, p in (("plant", plant, "analytic", None),
                                    ("learned", nominal, "learned", predictor),
                                    ("physics", nominal, "analytic", None)):
        run = twinsim.OmniSim(model, backend=backend, predictor=p, seed=7).run(commands)
        paths[name] = run["truth"][:, 0, :2]
    t = np.arange(len(commands)) / 30.0

    os.makedirs(args.out, exist_ok=True)
    table = np.column_stack([t] + [paths[n] for n in ("plant", "learned", "physics")])
    np.savetxt(os.path.join(args.out, "paths.csv"), table, delimiter=",", comments="",
               header="t,plant_x,plant_y,learned_x,learned_y,physics_x,physics_y")
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"wrote {args.out}/paths.csv (install python3-matplotlib for the plot)")
        return
    for name, style in (("plant", "k-"), ("learned", "b--"), ("physics", "r:")):
        plt.plot(paths[name][:, 0], paths[name][:, 1], style, label=name)
    plt.axis("equal")
    plt.legend()
    plt.savefig(os.path.join(args.out, "paths.png"), dpi=120)
    print(f"wrote {args.out}/paths.csv and {args.out}/paths.png")


if __name__ == "__main__":
    main()
