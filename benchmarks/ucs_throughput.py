"""Benchmark: throughput of a UCS test against the engine's own benchmark and against YADE.

One run measures, interleaved (so that a shared machine's load falls on all of them alike):

- **UCS**: ``run_ucs`` on a 10 x 20 mm Scenario-1 gbmgen specimen (seed 1, preset
  ``thesis-ch4-calibrated``, ~5 k particles), all defaults, stopped at ``--max-strain``
  (0.001); particle-steps/s over the loading loop (``summary["particle_steps_per_s"]``:
  recording, analysis, adaptive speed and neighbour rebuilds included);
- **engine**: what ``gbmsim bench --n N`` measures, at the UCS specimen's particle count:
  ``Simulation(Specimen.random_packing(N))`` cycled ``--bench-steps`` steps in one call (by
  default as many steps as the UCS row took, so that both rows sample the load over about the
  same time); the order of the two rows alternates between repeats;
- **YADE** (when the ``yade`` command exists, e.g. Debian's ``apt-get install yade``): a UCS
  of a bonded JCFpm sphere packing of about the same particle count between two moving
  platens, ``yade -j THREADS``; the script is written by this benchmark into the output
  folder (``yade_ucs.py``) and times ``O.run`` after a warm-up. Without YADE the row says so.

Prints and writes (``--out``) the medians, the ratios UCS / engine (of the medians, the median
of the per-repeat ratios, and per CPU-second, which a shared machine's load disturbs least) and
UCS / YADE, the thread count and the machine load; JSON and a markdown table. ``--profile``
first runs one UCS row under cProfile and reports the share of its loop spent in the compiled
step loop against the Python work between the calls::

    python benchmarks/ucs_throughput.py [--threads 2] [--repeat 3] [--max-strain 0.001]
        [--profile] [--out benchmarks/ucs_results/throughput]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

YADE_SCRIPT = r'''
# UCS of a JCFpm-bonded sphere packing between two rigid platens (written by
# benchmarks/ucs_throughput.py); prints one JSON line with the timing.
import json, time
from yade import pack, utils
from yade.wrapper import *
R = {radius!r}
W, H, D = {width!r}, {height!r}, {depth!r}
mat = O.materials.append(JCFpmMat(young=60e9, poisson=0.25, frictionAngle=0.52,
                                  density=2650.0, tensileStrength=50e6, cohesion=100e6))
sp = pack.SpherePack()
sp.makeCloud((0, 0, 0), (W, H, D), rMean=R, rRelFuzz=0.25, num={n!r}, seed=1)
ids = sp.toSimulation(material=mat)
wmat = O.materials.append(FrictMat(young=60e9, poisson=0.25, frictionAngle=0.0,
                                   density=2650.0))
lo = O.bodies.append(utils.wall(0.0, axis=1, sense=1, material=wmat))
hi = O.bodies.append(utils.wall(H, axis=1, sense=-1, material=wmat))
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(aabbEnlargeFactor=1.5), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(interactionDetectionFactor=1.5),
                     Ig2_Wall_Sphere_ScGeom()],
                    [Ip2_JCFpmMat_JCFpmMat_JCFpmPhys(cohesiveTresholdIteration=1),
                     Ip2_FrictMat_FrictMat_FrictPhys()],
                    [Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM(),
                     Law2_ScGeom_FrictPhys_CundallStrack()]),
    NewtonIntegrator(damping=0.7),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.step()                                    # bonds form at the first iteration
for e in O.engines:                         # then detect only touching pairs
    if isinstance(e, InsertionSortCollider):
        e.boundDispatcher.functors[0].aabbEnlargeFactor = 1.0
    if isinstance(e, InteractionLoop):
        e.geomDispatcher.functors[0].interactionDetectionFactor = 1.0
v = {velocity!r}
O.bodies[lo].state.vel = (0, v, 0)
O.bodies[hi].state.vel = (0, -v, 0)
O.run({warmup!r}, True)
t0 = time.perf_counter()
O.run({steps!r}, True)
t = time.perf_counter() - t0
n = len(ids)
print("YADE_RESULT " + json.dumps({{"particles": n, "steps": {steps!r}, "seconds": t,
      "particle_steps_per_s": n * {steps!r} / t, "dt": O.dt,
      "bonds": sum(1 for i in O.interactions if i.isReal and i.phys.isCohesive)}}))
'''


def load_avg() -> list:
    """The 1, 5 and 15 minute load averages."""
    return [round(v, 2) for v in os.getloadavg()]


def ucs_specimen(width_mm, height_mm, seed):
    """The Scenario-1 gbmgen specimen of the UCS row (preset thesis-ch4-calibrated)."""
    from gbmgen.build import build_specimen
    from gbmgen.table import example_table
    spec, _ = build_specimen(example_table("table-4-1"), width_mm=width_mm, height_mm=height_mm,
                             scenario=1, seed=seed, params="thesis-ch4-calibrated")
    return spec


def run_ucs_row(spec, max_strain):
    from sim.protocols.registry import run_test
    c0 = time.process_time()
    s = run_test("ucs", spec, max_strain=max_strain, post_peak=None, progress=False,
                 figures=False).summary
    cpu = time.process_time() - c0             # set-up and read-out included
    return {"particle_steps_per_s": s["particle_steps_per_s"], "steps": s["steps"],
            "seconds": s["wall_s"], "particles": s["n_particles"], "cpu_s": cpu,
            "particle_steps_per_cpu_s": s["n_particles"] * s["steps"] / cpu}


def profile_ucs_row(spec, max_strain):
    """One UCS row under cProfile: the share of the loading loop spent in the compiled step
    loop (``sim.integrate.run_steps``) and the Python work between its calls (records, the
    adaptive speed, the stop rule, crack harvesting, neighbour rebuilds), s."""
    import cProfile
    import pstats

    from sim.protocols.registry import run_test
    prof = cProfile.Profile()
    prof.enable()
    s = run_test("ucs", spec, max_strain=max_strain, post_peak=None, progress=False,
                 figures=False).summary
    prof.disable()
    stats = pstats.Stats(prof).stats
    kernel = sum(v[2] for k, v in stats.items() if k[2] == "run_steps")
    calls = sum(v[1] for k, v in stats.items() if k[2] == "run_steps")
    return {"loop_s": s["wall_s"], "kernel_s": kernel, "kernel_calls": calls,
            "between_s": s["wall_s"] - kernel, "kernel_share": kernel / s["wall_s"],
            "steps": s["steps"]}


def run_engine_row(n, steps, seed=1):
    """``gbmsim bench --n n --steps steps --repeat 1`` (the same code path)."""
    from sim import Simulation, Specimen
    s = Specimen.random_packing(n, seed=seed)
    sim = Simulation(s)
    sim.cycle(50)
    t0, c0 = time.perf_counter(), time.process_time()
    sim.cycle(steps)
    t, cpu = time.perf_counter() - t0, time.process_time() - c0
    return {"particle_steps_per_s": s.n_particles * steps / t, "steps": steps, "seconds": t,
            "particles": s.n_particles, "cpu_s": cpu,
            "particle_steps_per_cpu_s": s.n_particles * steps / cpu}


def run_yade_row(n_target, threads, steps, folder):
    """The YADE UCS on about ``n_target`` spheres, or None when YADE is absent."""
    exe = shutil.which("yade")
    if exe is None:
        return None
    r = 1e-4
    # n_target spheres in a slab 6 radii deep, at a solid fraction (0.3) a cloud can reach
    depth = 6 * r
    vol = n_target * (4 / 3) * np.pi * r ** 3 / 0.3
    width = float(np.sqrt(vol / depth / 2.0))
    script = YADE_SCRIPT.format(radius=r, width=width, height=2 * width, depth=depth,
                                n=int(n_target), velocity=0.05, warmup=200, steps=steps)
    path = os.path.join(folder, "yade_ucs.py")
    with open(path, "w", encoding="utf-8") as f:
        f.write(script)
    out = subprocess.run([exe, "-j", str(threads), "-n", "-x", path], capture_output=True,
                         text=True, timeout=3600)
    for line in out.stdout.splitlines():
        if line.startswith("YADE_RESULT "):
            res = json.loads(line[len("YADE_RESULT "):])
            res["version"] = _yade_version(exe)
            return res
    raise RuntimeError("YADE run failed: " + (out.stderr or out.stdout)[-800:])


def _yade_version(exe):
    out = subprocess.run([exe, "--version"], capture_output=True, text=True)
    return " ".join(out.stdout.split()[-1:]) or "unknown"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--max-strain", type=float, default=1e-3)
    ap.add_argument("--width-mm", type=float, default=10.0)
    ap.add_argument("--height-mm", type=float, default=20.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bench-steps", type=int, default=0,
                    help="steps of the engine row (default: as many as the UCS row took, so "
                         "that both sample the machine's load over the same time)")
    ap.add_argument("--yade-steps", type=int, default=2000)
    ap.add_argument("--no-yade", action="store_true", help="skip YADE even when installed")
    ap.add_argument("--profile", action="store_true",
                    help="first run one UCS row under cProfile and report the time in the "
                         "compiled step loop against the work between its calls")
    ap.add_argument("--out", default="benchmarks/ucs_results/throughput")
    a = ap.parse_args(argv)
    import numba  # sim picks the OpenMP threading layer)

    import sim  # noqa: F401  (before numba starts its threads:
    numba.set_num_threads(a.threads)
    os.makedirs(a.out, exist_ok=True)
    spec = ucs_specimen(a.width_mm, a.height_mm, a.seed)
    n = spec.n_particles
    run_ucs_row(spec, 2e-4)                 # compile (cached) before timing
    run_engine_row(n, 100)
    prof = profile_ucs_row(spec, a.max_strain) if a.profile else None
    if prof:
        print(f"profile: {100 * prof['kernel_share']:.2f} % of the UCS loop in the compiled "
              f"step loop ({prof['kernel_calls']} calls), {prof['between_s']:.2f} s between "
              f"them of {prof['loop_s']:.1f} s", flush=True)
    rows = {"ucs": [], "engine": [], "yade": []}
    yade_note = None
    loads = [load_avg()]
    for k in range(a.repeat):
        # alternate the order, so that a trend in the load favours neither
        if k % 2 == 0:
            rows["ucs"].append(run_ucs_row(spec, a.max_strain))
        rows["engine"].append(run_engine_row(n, a.bench_steps or rows["ucs"][-1]["steps"]))
        if k % 2 == 1:
            rows["ucs"].append(run_ucs_row(spec, a.max_strain))
        if a.no_yade:
            yade_note = "skipped (--no-yade)"
        else:
            with tempfile.TemporaryDirectory() as tmp:
                y = run_yade_row(n, a.threads, a.yade_steps, a.out if k == 0 else tmp)
            if y is None:
                yade_note = "YADE not installed (the yade command is missing): no comparison"
            else:
                rows["yade"].append(y)
        loads.append(load_avg())
        print(f"repeat {k + 1}/{a.repeat}: UCS {rows['ucs'][-1]['particle_steps_per_s'] / 1e6:.2f}"
              f" M, engine {rows['engine'][-1]['particle_steps_per_s'] / 1e6:.2f} M"
              + (f", YADE {rows['yade'][-1]['particle_steps_per_s'] / 1e6:.2f} M"
                 if rows["yade"] else "") + f" particle-steps/s; load {loads[-1]}", flush=True)
    med = {k: float(np.median([r["particle_steps_per_s"] for r in v])) if v else None
           for k, v in rows.items()}
    out = {"particles": n, "threads": a.threads, "threading_layer": numba.threading_layer(),
           "max_strain": a.max_strain,
           "median_particle_steps_per_s": med,
           "ucs_over_engine": med["ucs"] / med["engine"],
           "ucs_over_engine_paired": float(np.median(
               [u["particle_steps_per_s"] / e["particle_steps_per_s"]
                for u, e in zip(rows["ucs"], rows["engine"])])),
           "ucs_over_engine_cpu": float(
               np.median([r["particle_steps_per_cpu_s"] for r in rows["ucs"]])
               / np.median([r["particle_steps_per_cpu_s"] for r in rows["engine"]])),
           "ucs_over_yade": med["ucs"] / med["yade"] if med["yade"] else None,
           "yade": yade_note or f"yade {rows['yade'][0].get('version')}, "
                                f"{rows['yade'][0]['particles']} spheres",
           "profile": prof, "rows": rows, "load_avg": loads, "machine": platform.platform(),
           "command": "python benchmarks/ucs_throughput.py " + " ".join(sys.argv[1:])}
    with open(os.path.join(a.out, "ucs_throughput.json"), "w", encoding="utf-8") as f:
        json.dump(out, f, indent=1)
    lines = ["| run | particles | median M particle-steps/s | ratio |", "|---|---|---|---|",
             f"| UCS (defaults, to strain {a.max_strain:g}) | {n} | {med['ucs'] / 1e6:.2f} | — |",
             f"| engine (`gbmsim bench --n {n}`) | {n} | {med['engine'] / 1e6:.2f} | UCS / "
             f"engine {out['ucs_over_engine']:.2f} |"]
    if med["yade"]:
        lines.append(f"| YADE JCFpm UCS | {rows['yade'][0]['particles']} | "
                     f"{med['yade'] / 1e6:.2f} | UCS / YADE {out['ucs_over_yade']:.1f} |")
    else:
        lines.append(f"| YADE | — | — | {yade_note} |")
    lines += ["", "UCS / engine: median of the per-repeat ratios "
              f"{out['ucs_over_engine_paired']:.2f}, per CPU-second "
              f"{out['ucs_over_engine_cpu']:.2f}.",
              "", f"{a.threads} thread(s) ({out['threading_layer']}), median of {a.repeat} "
              "interleaved repeats; load average "
              f"before and after each repeat: {loads}"]
    with open(os.path.join(a.out, "ucs_throughput.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    if yade_note and not a.no_yade:
        print(yade_note, file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
