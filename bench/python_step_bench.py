"""Overhead of stepping a simulation from Python (issue 15: at most 2 us per step over
C++ on the analytic backend).

    PYTHONPATH=build/python /usr/bin/python3 bench/python_step_bench.py

Both loops run the same C++ Simulation::Step on the analytic backend with one robot:
`run(commands)` steps N frames inside C++ (one call), `step(command)` is called N times
from Python. The difference per frame is what Python costs. Prints the best of 5 runs.
"""
import time

import numpy as np

import twinsim

FRAMES = 20000


def best(f, repeat=5):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    model = twinsim.load_omni_model("models/omni4.yaml")
    commands = np.tile([0.5, 0.0, 0.2], (FRAMES, 1))
    sim = twinsim.OmniSim(model, backend="analytic")

    def in_cpp():
        sim.reset(seed=1)
        sim.run(commands)

    def from_python():
        sim.reset(seed=1)
        step = sim.step
        for c in commands:
            step(c)

    def from_python_reading():
        sim.reset(seed=1)
        for c in commands:
            sim.step(c)
            sim.truth

    cpp = best(in_cpp) / FRAMES
    py = best(from_python) / FRAMES
    py_read = best(from_python_reading) / FRAMES
    print(f"C++ loop (run):                {1e6 * cpp:7.3f} us per frame")
    print(f"Python loop (step):            {1e6 * py:7.3f} us per frame, overhead {1e6 * (py - cpp):6.3f} us")
    print(f"Python loop (step + truth):    {1e6 * py_read:7.3f} us per frame, overhead {1e6 * (py_read - cpp):6.3f} us")


if __name__ == "__main__":
    main()
