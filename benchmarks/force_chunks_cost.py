"""Benchmark: what a fixed force-chunk count costs on one thread (docs/sim.md).

The step loop sums one force buffer per chunk; the chunk count is fixed
(``sim.config.FORCE_CHUNKS`` = 2) so that results do not depend on the thread count. On one
thread that means summing two buffer rows where one would do. This runs the engine's own loop
(``Simulation._run_chunks``) with 1 and 2 chunks, alternating in one process so that machine
noise hits both alike, on a bonded random packing, and reports the medians (ns per
particle-step) and the relative cost. Accuracy is the same by construction: both sum the same
forces, in another order (rounding only; tests/sim/test_determinism.py).

    python benchmarks/force_chunks_cost.py [--sizes 5000 20000] [--alternations 30]
        [--out benchmarks/results]
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np


def measure(n, alternations, budget=2e6, seed=1):
    import numba

    from sim import Simulation, Specimen
    numba.set_num_threads(1)
    spec = Specimen.random_packing(n, seed=seed)
    sims = {k: Simulation(spec) for k in (1, 2)}
    for s in sims.values():
        s.state.ensure_rows(2)
        s._run_chunks(500, 1)             # same warm-up, then each keeps its own chunking
    steps = int(max(20, budget // n))
    ns = {1: [], 2: []}
    for rep in range(alternations):
        for k in ((1, 2) if rep % 2 else (2, 1)):
            t0 = time.perf_counter()
            sims[k]._run_chunks(steps, k)
            ns[k].append((time.perf_counter() - t0) / steps / n * 1e9)
    m1, m2 = float(np.median(ns[1])), float(np.median(ns[2]))
    return {"n_particles": n, "steps_per_call": steps, "alternations": alternations,
            "ns_per_particle_step_1_chunk": m1, "ns_per_particle_step_2_chunks": m2,
            "cost_of_2_chunks": m2 / m1 - 1.0,
            "load_1min": os.getloadavg()[0]}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[5000, 20000])
    p.add_argument("--alternations", type=int, default=30)
    p.add_argument("--out", default="benchmarks/results")
    a = p.parse_args(argv)
    rows = [measure(n, a.alternations) for n in a.sizes]
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "force_chunks_cost.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print("| N | 1 chunk ns/particle-step | 2 chunks | cost | load |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['n_particles']} | {r['ns_per_particle_step_1_chunk']:.1f} | "
              f"{r['ns_per_particle_step_2_chunks']:.1f} | {100 * r['cost_of_2_chunks']:+.1f} % | "
              f"{r['load_1min']:.1f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
