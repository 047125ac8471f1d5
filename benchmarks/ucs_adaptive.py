"""UCS cost vs accuracy: adaptive platen speed against constant speeds (issue #6).

Runs the UCS protocol (80 % post-peak stop, default time-step factor) on each specimen with
each loading mode and prints one JSON line per run (wall s, steps, UCS, E, errors against the
reference mode = the last one given). Modes: ``const:V`` (constant platen speed V m/s) and
``adaptive`` (the default adaptive rule, :data:`sim.protocols.speed.ADAPTIVE_DEFAULT`),
``adaptive:VBASE[:FMAX[:FPEAK]]`` (same rule, another base speed, largest factor and factor
near the peak).

    python benchmarks/ucs_adaptive.py --specimens s1_4x8_seed1.npz,s1_4x8_seed2.npz,... \
        --modes adaptive,const:0.0125,const:0.00625 --out benchmarks/ucs_results/adaptive.json

Specimens: ``gbmgen build --table table-4-1 --scenario 1 --width-mm 4 --height-mm 8
--particle-radius-mm 0.1 --seed K`` with the thesis Ch. 4 start parameters (as
benchmarks/ucs_convergence.py). The 2-core machine is shared: wall times are indicative.
"""
from __future__ import annotations

import argparse
import json
import os
import time


def mode_options(mode):
    """``run_ucs`` keywords of a loading mode: ``const:V``,
    ``adaptive[:VBASE[:FMAX[:FPEAK]]]`` (FPEAK: the rule's ``f_peak``, the largest factor
    near the peak and after it; 1, the default, unless given)."""
    if mode.startswith("const:"):
        return dict(platen_velocity=float(mode.split(":")[1]), adaptive=False)
    parts = mode.split(":")
    if parts[0] != "adaptive":
        raise ValueError(f"mode {mode!r}: expected adaptive[:VBASE[:FMAX[:FPEAK]]] or const:V")
    kw = dict(adaptive=True)
    if len(parts) > 1:
        kw["platen_velocity"] = float(parts[1])
    if len(parts) > 2:
        kw["adaptive"] = {"f_max": float(parts[2])}
    if len(parts) > 3:
        kw["adaptive"]["f_peak"] = float(parts[3])
    return kw


def run_mode(spec, mode, factor=None):
    from sim.protocols import speed as ld
    from sim.protocols.ucs import run_ucs
    kw = mode_options(mode)
    if factor is not None:
        kw["timestep_factor"] = factor
    t0 = time.perf_counter()
    r = run_ucs(spec, progress=False, figures=False, **kw)
    wall = time.perf_counter() - t0
    s = r.summary
    return {"mode": mode, "steps": s["steps"], "wall_s": round(wall, 2),
            "n_particles": s["n_particles"], "ucs_mpa": s["ucs_mpa"], "E_gpa": s["E_gpa"],
            "nu": s["nu"], "E_ok": s["E_ok"], "elastic": s["elastic"],
            "cracks": s["cracks"]["total"], "stop_reason": s["stop_reason"],
            "peak_axial_strain": s.get("peak_axial_strain"),
            "timestep_factor": ld.DEFAULT_TIMESTEP_FACTOR if factor is None else factor}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--specimens", required=True, help="comma-separated specimen.npz paths")
    p.add_argument("--modes", default="adaptive,const:0.0125,const:0.00625",
                   help="loading modes; the last one is the reference")
    p.add_argument("--factor", type=float, default=None,
                   help="time-step factor (default: the protocol's)")
    p.add_argument("--keep-params", action="store_true")
    p.add_argument("--out", default=None, help="append JSON lines here")
    a = p.parse_args(argv)
    from sim import Specimen
    from sim.protocols.parameters import apply_parameters, start_parameters
    modes = a.modes.split(",")
    rows = []
    for path in a.specimens.split(","):
        spec = Specimen.load(path)
        if not a.keep_params:
            spec = apply_parameters(spec, start_parameters(spec))
        for m in modes:
            row = run_mode(spec, m, a.factor)
            row["specimen"] = os.path.basename(path)
            rows.append(row)
            print(json.dumps(row), flush=True)
            if a.out:
                with open(a.out, "a") as f:
                    f.write(json.dumps(row) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
