"""UCS convergence: UCS and E against platen speed and time-step factor, with the cost of each.

For one fixed specimen, runs the UCS protocol (post-peak stop at 80 %) at a ladder of platen
speeds (>= 4 speeds spanning >= 10x) at the default time-step factor, then at a ladder of
time-step factors at a fixed speed. Each row gives wall seconds, particle-steps/s, UCS, E and
their relative errors against the most expensive run of the ladder (slowest speed / smallest
factor) — speed is always read beside the error it buys. Writes JSON and a markdown table.

    python benchmarks/ucs_convergence.py --specimen S.npz --out benchmarks/results

Without ``--specimen`` a Scenario-1 specimen 5 x 10 mm (particle radius 0.1 mm, seed 1) is
built with gbmgen. The CPU of the 2-core machine may be shared: wall times are indicative.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time


def _specimen(path, seed):
    from sim import Specimen
    if path:
        return Specimen.load(path), path
    import gbmgen
    from gbmgen.build import build_specimen
    from gbmgen.table import read_table
    table = read_table(os.path.join(os.path.dirname(gbmgen.__file__), "presets",
                                    "table_4_1.csv"))
    spec, _ = build_specimen(table, width_mm=5.0, height_mm=10.0, scenario=1,
                             particle_radius_mm=0.1, seed=seed)
    return spec, f"gbmgen S1 5x10 mm r=0.1 mm seed {seed}"


def _run(spec, v, factor, post_peak):
    from sim.protocols.ucs import run_ucs
    t0 = time.perf_counter()
    r = run_ucs(spec, platen_velocity=v, timestep_factor=factor, post_peak=post_peak,
                progress=False)
    wall = time.perf_counter() - t0
    s = r.summary
    return {"platen_velocity_m_per_s": v, "timestep_factor": factor,
            "strain_rate_per_s": s["options"]["strain_rate_per_s"], "steps": s["steps"],
            "dt_s": s["dt_s"], "wall_s": wall,
            "particle_steps_per_s": s["n_particles"] * s["steps"] / wall,
            "ucs_mpa": s["ucs_mpa"], "E_gpa": s["E_gpa"], "nu": s["nu"],
            "cracks": s["cracks"]["total"], "stop_reason": s["stop_reason"]}


def _errors(rows):
    ref = rows[-1]
    for r in rows:
        r["err_ucs"] = r["ucs_mpa"] / ref["ucs_mpa"] - 1.0
        r["err_E"] = r["E_gpa"] / ref["E_gpa"] - 1.0
    return rows


def _table(rows, title):
    out = [f"### {title}", "",
           "| v (m/s) | rate (1/s) | dt factor | steps | wall s | Mpart-steps/s | UCS MPa | "
           "err UCS | E GPa | err E | cracks |", "|" + "---|" * 11]
    for r in rows:
        out.append(f"| {r['platen_velocity_m_per_s']:.4g} | {r['strain_rate_per_s']:.3g} | "
                   f"{r['timestep_factor']} | {r['steps']} | {r['wall_s']:.1f} | "
                   f"{r['particle_steps_per_s'] / 1e6:.2f} | {r['ucs_mpa']:.2f} | "
                   f"{100 * r['err_ucs']:+.2f} % | {r['E_gpa']:.2f} | {100 * r['err_E']:+.2f} % | "
                   f"{r['cracks']} |")
    return "\n".join(out) + "\n"


def _choose(rows, tol):
    """Cheapest row (fewest steps) within tol of the reference on UCS and E."""
    ok = [r for r in rows if abs(r["err_ucs"]) <= tol and abs(r["err_E"]) <= tol]
    return min(ok, key=lambda r: r["steps"]) if ok else None


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--specimen", default=None)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--velocities", default="0.4,0.2,0.1,0.05,0.025",
                   help="platen speeds, m/s, fastest first (the last is the reference)")
    p.add_argument("--ladder-factor", type=float, default=None,
                   help="time-step factor of the speed ladder (default: engine default)")
    p.add_argument("--factors", default="0.8,0.5,0.3",
                   help="time-step factors, largest first (the last is the reference)")
    p.add_argument("--factor-velocity", type=float, default=None,
                   help="platen speed of the time-step ladder (default: the chosen speed)")
    p.add_argument("--post-peak", type=float, default=0.8)
    p.add_argument("--tol", type=float, default=0.02)
    p.add_argument("--out", default="benchmarks/results")
    p.add_argument("--keep-params", action="store_true",
                   help="use the specimen's own micro-parameters (default: start_parameters)")
    a = p.parse_args(argv)
    from sim.protocols.speed import DEFAULT_PLATEN_VELOCITY  # noqa: F401 (import check)
    spec, source = _specimen(a.specimen, a.seed)
    if not a.keep_params:
        from sim.protocols.parameters import apply_parameters, start_parameters
        spec = apply_parameters(spec, start_parameters(spec))
        source += " (thesis Ch. 4 parameters, joint stiffness = bond stiffness)"
    print(f"specimen: {source}: {spec.n_particles} particles, {spec.n_bonds} bonds", flush=True)
    _run(spec, 0.4, None, a.post_peak)     # compile once, not timed in the table
    vel = [float(v) for v in a.velocities.split(",")]
    rows_v = []
    for v in vel:
        rows_v.append(_run(spec, v, a.ladder_factor, a.post_peak))
        print(json.dumps(rows_v[-1]), flush=True)
    _errors(rows_v)
    best_v = _choose(rows_v, a.tol)
    fv = a.factor_velocity or (best_v["platen_velocity_m_per_s"] if best_v else vel[-1])
    rows_f = []
    for f in [float(x) for x in a.factors.split(",") if x]:
        rows_f.append(_run(spec, fv, f, a.post_peak))
        print(json.dumps(rows_f[-1]), flush=True)
    _errors(rows_f) if rows_f else None
    best_f = _choose(rows_f, a.tol) if rows_f else None
    os.makedirs(a.out, exist_ok=True)
    res = {"specimen": source, "n_particles": spec.n_particles, "tol": a.tol,
           "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                       "note": "2-core machine shared with other jobs; wall times indicative"},
           "velocity_ladder": rows_v, "factor_ladder": rows_f,
           "chosen_velocity": best_v, "chosen_factor": best_f}
    with open(os.path.join(a.out, "ucs_convergence.json"), "w") as f:
        json.dump(res, f, indent=2)
    md = [f"# UCS convergence ({source}, {spec.n_particles} particles)", "",
          _table(rows_v, "Platen speed (time-step factor: "
                 f"{a.ladder_factor or 'engine default'})"),
          _table(rows_f, f"Time-step factor (platen speed {fv} m/s)")]
    if not rows_f:
        md.pop()
    if best_v:
        md.append(f"Cheapest speed within {100 * a.tol:.0f} % of the slowest run: "
                  f"{best_v['platen_velocity_m_per_s']} m/s.")
    if best_f:
        md.append(f"Largest time-step factor within {100 * a.tol:.0f} %: "
                  f"{best_f['timestep_factor']}.")
    text = "\n".join(md) + "\n"
    with open(os.path.join(a.out, "ucs_convergence.md"), "w") as f:
        f.write(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
