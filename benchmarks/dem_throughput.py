"""Benchmark: DEM throughput on bonded random packings, 1 and 2 threads (issue #5).

For N in 5k, 20k, 50k, 200k particles (``Specimen.random_packing``: ~4.3 parallel bonds per
particle, polydisperse, a few % overlaps) and 1 and 2 numba threads, runs the engine with its
defaults (local damping 0.7, time-step factor 0.5) and reports the median over repeats of:
particle-steps/s, pair-steps/s (bonds + Verlet-list pairs), the time split (broad phase =
list rebuilds; pair laws; particle pass) and memory (engine arrays; peak RSS). Accuracy is
read beside speed: the analytic checks of ``gbmsim verify`` are run once and their largest
relative error is recorded.

    /work/venv/bin/python benchmarks/dem_throughput.py [--sizes 5000 20000 50000 200000]
        [--threads 1 2] [--budget 1e7] [--repeat 3] [--out benchmarks/dem_throughput_results]

Target (issue #5): >= 25 M particle-steps/s at 20k on 2 threads, flat cost per particle-step
from 5k to 200k. The 2-core machine was shared with other jobs: wall times are indicative
and the load average is recorded with every run.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import sys
import time

import numpy as np

import sim as _sim  # noqa: F401  (sets the OpenMP wait policy before the thread pool starts)


def _split(sim, reps=20):
    """Seconds per step of the pair pass and of the particle pass (single call each, all
    threads), timed with the engine's own kernels on the current state."""
    from sim.integrate import run_steps
    st = sim.state
    nch = sim.force_chunks
    info = np.zeros(8)
    # full steps without rebuild checks are what run_steps does; time it, then time a
    # refresh-only call (one pair pass, no motion) to split pairs from particles
    pf_copy = st.pf.copy()
    acc_copy = st.acc.copy()
    bf_copy, cf_copy, bstate_copy = st.bf.copy(), st.cf.copy(), st.bstate.copy()
    args = lambda n, refresh: (n, sim.step, sim.dt, sim.damping, nch, 1e30, 1e30, 1e30, 1.0,  # noqa
                               0.5, st.pf, st.fix, st.bi, st.bj, st.bstate, st.bf, st.npb, st.ci,
                               st.cj, st.cf, st.nc, False, st.wf, st.qp, st.qw, st.qf, st.nq,
                               st.acc, refresh, False, 0.0, 0.0, 1, st.quiet, info)
    t0 = time.perf_counter()
    for _ in range(reps):
        run_steps(*args(0, True))
    t_pairs = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    run_steps(*args(reps, False))
    t_step = (time.perf_counter() - t0) / reps
    st.pf[:], st.acc[:], st.bf[:], st.cf[:], st.bstate[:] = (pf_copy, acc_copy, bf_copy,
                                                             cf_copy, bstate_copy)
    return t_pairs, max(t_step - t_pairs, 0.0)


def _engine_bytes(st):
    return int(sum(getattr(st, k).nbytes for k in st.ARRAYS) + st.acc.nbytes)


def run_case(n, threads, budget, repeat, seed, args_prerun=500):
    import numba

    from sim import Simulation, Specimen
    from sim.state import C_FN
    numba.set_num_threads(threads)
    spec = Specimen.random_packing(n, seed=seed)
    sim = Simulation(spec)
    sim.cycle(args_prerun)  # let the initial-overlap transient (frequent rebuilds) die down
    steps = int(max(20, budget // n))
    n_rebuild = [0]
    t_rebuild = [0.0]
    orig = sim.rebuild

    def timed_rebuild():
        t0 = time.perf_counter()
        orig()
        t_rebuild[0] += time.perf_counter() - t0
        n_rebuild[0] += 1
    sim.rebuild = timed_rebuild
    walls, cpus = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        sim.cycle(steps)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    med = float(np.median(walls))
    total = float(np.sum(walls))
    t_pairs, t_part = _split(sim)
    broad = t_rebuild[0] / total
    rest = 1.0 - broad
    pp = t_pairs + t_part
    st = sim.state
    pairs = st.n_bonds + st.nc
    return {
        "particles": n, "threads": threads, "bonds": st.n_bonds,
        "bonds_per_particle": 2.0 * st.n_bonds / n, "verlet_pairs": st.nc,
        "touching_contacts": int(np.count_nonzero(st.cf[C_FN, :st.nc])),
        "steps_per_repeat": steps, "repeats": repeat, "median_s": med,
        "particle_steps_per_s": n * steps / med, "pair_steps_per_s": pairs * steps / med,
        "ns_per_particle_step": med / (n * steps) * 1e9,
        "cpu_ns_per_particle_step": float(np.median(cpus)) / (n * steps) * 1e9,
        "prerun_steps": args_prerun, "rebuilds": n_rebuild[0], "split_broad_phase": broad,
        "split_pairs": rest * t_pairs / pp if pp else float("nan"),
        "split_particles": rest * t_part / pp if pp else float("nan"),
        "engine_mb": _engine_bytes(st) / 2 ** 20, "dt_s": sim.dt,
        "load_avg_1min": os.getloadavg()[0],
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[5000, 20000, 50000, 200000])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--budget", type=float, default=1e7, help="particle-steps per repeat")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--prerun", type=int, default=500,
                    help="steps run before timing (the packing's initial overlaps relax)")
    ap.add_argument("--no-verify", action="store_true")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__),
                                                  "dem_throughput_results"))
    a = ap.parse_args(argv)
    import numba

    from sim.verify import verification_cases
    rows = []
    for n in a.sizes:
        for t in a.threads:
            r = run_case(n, t, a.budget, a.repeat, a.seed, a.prerun)
            rows.append(r)
            print(f"N={n:>7d} threads={t}: "
                  f"{r['particle_steps_per_s'] / 1e6:6.2f} M particle-steps/s  "
                  f"{r['ns_per_particle_step']:6.1f} ns/particle-step  "
                  f"(load {r['load_avg_1min']:.1f})",
                  flush=True)
    checks = [] if a.no_verify else verification_cases()
    result = {
        "benchmark": "dem_throughput", "machine": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(), "numba": numba.__version__,
        "threading_layer": numba.threading_layer(), "python": sys.version.split()[0],
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "rows": rows, "accuracy": checks,
        "max_rel_error": max((c["rel_error"] for c in checks), default=None),
        "note": "shared 2-core machine: other jobs load the CPU (see load_avg_1min)",
    }
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "dem_throughput.json"), "w") as f:
        json.dump(result, f, indent=2)
    lines = ["| N | threads | M particle-steps/s | M pair-steps/s | ns/particle-step "
             "| CPU ns/particle-step | bonds/particle | rebuilds | broad phase | pairs | particles "
             "| engine MB "
             "| load avg |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['particles']} | {r['threads']} | {r['particle_steps_per_s'] / 1e6:.2f} | "
            f"{r['pair_steps_per_s'] / 1e6:.2f} | {r['ns_per_particle_step']:.1f} | "
            f"{r['cpu_ns_per_particle_step']:.1f} | "
            f"{r['bonds_per_particle']:.2f} | {r['rebuilds']} | "
            f"{100 * r['split_broad_phase']:.0f} % | "
            f"{100 * r['split_pairs']:.0f} % | {100 * r['split_particles']:.0f} % | "
            f"{r['engine_mb']:.1f} | {r['load_avg_1min']:.1f} |")
    if checks:
        lines.append("")
        lines.append(f"Accuracy beside speed (gbmsim verify): largest relative error "
                     f"{100 * result['max_rel_error']:.3f} % over {len(checks)} analytic checks.")
    table = "\n".join(lines)
    with open(os.path.join(a.out, "dem_throughput.md"), "w") as f:
        f.write(table + "\n")
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
