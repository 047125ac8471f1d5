"""Cost of one step with sleeping particles against the same state awake.

    python benchmarks/field_sleep_cost.py [CHECKPOINT] [--steps 200] [--repeat 5]

Default checkpoint: benchmarks/field_results/d400/checkpoint.npz (the 400 m drive at the end
of its excavation with sleeping, written by ``benchmarks/field_excavation.py``). Loads it twice,
wakes every particle of one copy, and alternates ``cycle(steps)`` on the two on one thread;
prints the median CPU ms per step of each and the asleep fraction, and writes
benchmarks/field_results/sleep_cost.json.
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numba
import numpy as np


def main(argv=None):
    from sim import Simulation
    p = argparse.ArgumentParser()
    p.add_argument("checkpoint", nargs="?",
                   default="benchmarks/field_results/d400/checkpoint.npz")
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--repeat", type=int, default=5)
    a = p.parse_args(argv)
    numba.set_num_threads(1)
    asleep = Simulation.load(a.checkpoint)
    asleep.sleep = True
    awake = Simulation.load(a.checkpoint)
    awake.sleep = False
    awake.free(np.arange(awake.n_particles))
    f0 = float(asleep.asleep.mean())
    asleep.cycle(10)
    awake.cycle(10)
    ta, tb = [], []
    for _ in range(a.repeat):
        t0 = time.process_time()
        asleep.cycle(a.steps)
        ta.append(time.process_time() - t0)
        t0 = time.process_time()
        awake.cycle(a.steps)
        tb.append(time.process_time() - t0)
    res = {"checkpoint": a.checkpoint, "particles": asleep.n_particles,
           "asleep_fraction_start": f0, "asleep_fraction_end": float(asleep.asleep.mean()),
           "cpu_ms_per_step_sleep": 1e3 * float(np.median(ta)) / a.steps,
           "cpu_ms_per_step_awake": 1e3 * float(np.median(tb)) / a.steps,
           "load": os.getloadavg()}
    res["ratio"] = res["cpu_ms_per_step_awake"] / res["cpu_ms_per_step_sleep"]
    with open("benchmarks/field_results/sleep_cost.json", "w") as fh:
        json.dump(res, fh, indent=1)
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
