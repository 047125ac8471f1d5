"""Thesis-scale UCS: 25 x 50 mm Scenario-1 specimen, particle radius 0.1 mm (~31 k particles).

Runs the UCS protocol with the default loading speed to the 80 % post-peak stop and reports the
wall time (the issue's target: <= 10 minutes on the 2-core machine; PFC took 1-2 hours). With
``--max-strain`` it stops early and extrapolates the full time from the measured cost per unit
strain and the strain at the stop measured on small specimens (``--stop-strain``).

    python benchmarks/ucs_thesis_scale.py --specimen S.npz --out benchmarks/results

``--mode`` as benchmarks/ucs_adaptive.py (``adaptive``: the default size-aware rule;
``adaptive:VBASE:FMAX``; ``const:V``), e.g. a reference at half the default cracking rate on a
25 x 50 mm specimen: ``--mode adaptive:0.01953125:5.12 --name half``. The machine load (1-min
average) before and after the run is recorded beside the wall time.
"""
from __future__ import annotations

import argparse
import json
import os
import time


def _probe(spec, a):
    """Time ``a.probe_steps`` steps of the UCS set-up and extrapolate the full run."""
    from sim.protocols import rig
    from sim.protocols.speed import DEFAULT_PLATEN_VELOCITY, DEFAULT_TIMESTEP_FACTOR
    factor = a.timestep_factor or DEFAULT_TIMESTEP_FACTOR
    v = a.platen_velocity or DEFAULT_PLATEN_VELOCITY
    spec, _ = rig.relieve_overlaps(spec)
    t0 = time.perf_counter()
    sim = rig.make_simulation(spec, timestep_factor=factor)
    lo, hi = rig.add_platens(sim, spec.box)
    setup = time.perf_counter() - t0
    sim.set_wall_velocity(lo, 0.0, v)
    sim.set_wall_velocity(hi, 0.0, -v)
    sim.cycle(200)                       # compile / warm caches
    t0 = time.perf_counter()
    sim.cycle(a.probe_steps)
    wall = time.perf_counter() - t0
    pps = spec.n_particles * a.probe_steps / wall
    rate = 2.0 * v / (spec.box[3] - spec.box[2])
    steps = a.stop_strain / (rate * sim.dt)
    res = {"n_particles": spec.n_particles, "probe_steps": a.probe_steps, "probe_wall_s": wall,
           "setup_s": setup, "dt_s": sim.dt, "particle_steps_per_s": pps,
           "platen_velocity_m_per_s": v, "timestep_factor": factor,
           "stop_strain_assumed": a.stop_strain, "steps_needed_estimate": steps,
           "full_run_wall_s_estimate": steps * spec.n_particles / pps,
           "note": "2-core machine shared with other engineers' jobs (load ~5) during the probe"}
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "ucs_thesis_scale.json"), "w") as f:
        json.dump(res, f, indent=2)
    print(json.dumps(res, indent=2))
    return 0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--specimen", default=None, help="default: built with gbmgen (seed 1)")
    p.add_argument("--max-strain", type=float, default=None,
                   help="stop at this axial strain and extrapolate (default: full run)")
    p.add_argument("--stop-strain", type=float, default=4.5e-3,
                   help="axial strain at the 80 %% post-peak stop, for the extrapolation")
    p.add_argument("--platen-velocity", type=float, default=None)
    p.add_argument("--timestep-factor", type=float, default=None)
    p.add_argument("--probe-steps", type=int, default=0,
                   help="only time this many loading steps (platens moving) and extrapolate "
                        "the full run from the steps it needs at the default speed")
    p.add_argument("--params", default=None,
                   help="parameter YAML applied to the specimen (default: the specimen's own)")
    p.add_argument("--mode", default=None, help="loading mode (default: the protocol's)")
    p.add_argument("--name", default="ucs_thesis_scale", help="output file stem")
    p.add_argument("--out", default="benchmarks/results")
    p.add_argument("--run-out", default=None,
                   help="also write the test's outputs (summary.json, history.csv, ...) there; "
                        "Ctrl-C (SIGINT) then leaves partial outputs and a checkpoint, and the "
                        "JSON reports the partial run")
    a = p.parse_args(argv)
    from sim import Specimen
    from sim.protocols.parameters import apply_parameters, load_parameters
    from sim.protocols.ucs import run_ucs
    if a.specimen:
        spec = Specimen.load(a.specimen)
    else:
        import gbmgen
        from gbmgen.build import build_specimen
        from gbmgen.table import read_table
        table = read_table(os.path.join(os.path.dirname(gbmgen.__file__), "presets",
                                        "table_4_1.csv"))
        spec, _ = build_specimen(table, width_mm=25.0, height_mm=50.0, scenario=1,
                                 particle_radius_mm=0.1, seed=1)
    if a.params:
        spec = apply_parameters(spec, load_parameters(a.params))
    kw = {}
    if a.mode:
        from ucs_adaptive import mode_options  # this folder is on sys.path (a script)
        kw.update(mode_options(a.mode))
    if a.platen_velocity:
        kw["platen_velocity"] = a.platen_velocity
    if a.timestep_factor:
        kw["timestep_factor"] = a.timestep_factor
    if a.max_strain:
        kw.update(max_strain=a.max_strain, post_peak=None)
    if a.probe_steps:
        return _probe(spec, a)
    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    if a.run_out:
        kw["out"] = a.run_out
        kw["figures"] = False
    try:
        r = run_ucs(spec, progress=True, **kw)
    except KeyboardInterrupt:
        if not a.run_out:
            raise
        import pandas as pd
        wall = time.perf_counter() - t0
        with open(os.path.join(a.run_out, "summary.json")) as f:
            s = json.load(f)
        h = pd.read_csv(os.path.join(a.run_out, "history.csv"))
        res = {"n_particles": spec.n_particles, "steps": s["steps"], "dt_s": s["dt_s"],
               "wall_s": wall, "loop_wall_s": s["wall_s"],
               "particle_steps_per_s": s["particle_steps_per_s"],
               "strain_reached": float(h["axial_strain"].iloc[-1]),
               "stress_reached_mpa": float(h["axial_stress_mpa"].iloc[-1]),
               "peak_so_far_mpa": float(h["axial_stress_mpa"].max()),
               "cracks_so_far": int(h["cracks_total"].iloc[-1]),
               "stop_reason": "interrupted", "options": s["options"],
               "note": "partial run (interrupted); 2-core machine shared"}
        os.makedirs(a.out, exist_ok=True)
        with open(os.path.join(a.out, "ucs_thesis_scale.json"), "w") as f:
            json.dump(res, f, indent=2, default=str)
        print(json.dumps(res, indent=2, default=str))
        return 1
    wall = time.perf_counter() - t0
    s = r.summary
    strain = float(r.history["axial_strain"].iloc[-1])
    full = wall if not a.max_strain else wall * a.stop_strain / strain
    res = {"n_particles": spec.n_particles, "steps": s["steps"], "dt_s": s["dt_s"],
           "wall_s": wall, "loop_wall_s": s["wall_s"],
           "particle_steps_per_s": s["particle_steps_per_s"], "strain_reached": strain,
           "stop_reason": s["stop_reason"], "ucs_mpa": s.get("ucs_mpa"),
           "E_gpa": s.get("E_gpa"), "nu": s.get("nu"), "E_ok": s.get("E_ok"),
           "nu_ok": s.get("nu_ok"), "elastic": s.get("elastic"), "ci_mpa": s.get("ci_mpa"),
           "cd_mpa": s.get("cd_mpa"), "peak_axial_strain": s.get("peak_axial_strain"),
           "cracks": s.get("cracks"), "options": s["options"], "mode": a.mode or "default",
           "params": a.params or "specimen's own", "full_run_wall_s_estimate": full,
           "load_1min_before_after": [load_before, os.getloadavg()[0]],
           "numba_threads": int(os.environ.get("NUMBA_NUM_THREADS", os.cpu_count()))}
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, f"{a.name}.json"), "w") as f:
        json.dump(res, f, indent=2, default=str)
    print(json.dumps(res, indent=2, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
