"""Failure-path scatter: UCS perturbation ensembles of given specimens beside their seed scatter.

For each specimen, ``sim.protocols.ensemble.run_ensemble`` runs the UCS ``--runs`` times
(member 0 as given, members 1.. with the particle centres moved by ``amplitude`` × mean radius).
The table gives, per specimen and amplitude, the members' mean ± sd of UCS, E, CI and CD and the
median cost; the last line compares the mean failure-path sd with the sd of the member-0 values
across the specimens (the seed scatter: microstructure plus failure path). Ensembles are kept in
``--out`` and resumed, so an interrupted benchmark continues where it stopped.

    P=benchmarks/ucs_results/calibration_10x20_dt06/calibrated_params.yaml
    python benchmarks/ucs_ensemble.py --specimens s1.npz s2.npz s3.npz --params $P --runs 8 \\
        --out benchmarks/ucs_results/ensemble_10x20
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

#: Numbers summarised (E as measured: an ensemble member's E may be flagged, see E_ok).
KEYS = ("ucs_mpa", "elastic.E_measured_gpa", "ci_mpa", "cd_mpa")


def summarise(name, amplitude, res):
    """One JSON row of an ensemble: stats of KEYS, cost medians, the member values."""
    m, st = res.members, res.stats
    steps, wall = m["steps"].to_numpy(float), m["wall_s"].to_numpy(float)
    n = res.summary["config"]["n_particles"]
    row = {"specimen": name, "amplitude_rel": amplitude, "runs": len(m),
           "n_particles": n, "median_wall_s": float(np.median(wall)),
           "median_steps": float(np.median(steps)),
           "median_particle_steps_per_s": float(np.median(n * steps / wall))}
    for k in KEYS:
        row[k] = {c: float(st.loc[k, c]) for c in ("mean", "sd", "sem", "ci95", "min", "max",
                                                   "cv_pct")}
        row[k]["members"] = m[k].tolist()
    return row


def table(rows):
    """Markdown table of the rows plus the seed-scatter line."""
    head = ("| specimen | amplitude | runs | UCS MPa mean ± sd (cv) | E GPa mean ± sd | "
            "CI MPa mean ± sd | CD MPa mean ± sd | median s/run | M particle-steps/s |\n"
            "|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        u, e, ci, cd = (r[k] for k in KEYS)
        lines.append(f"| {r['specimen']} | {r['amplitude_rel']:g} | {r['runs']} | "
                     f"{u['mean']:.1f} ± {u['sd']:.1f} ({u['cv_pct']:.1f} %) | "
                     f"{e['mean']:.2f} ± {e['sd']:.2f} | {ci['mean']:.1f} ± {ci['sd']:.1f} | "
                     f"{cd['mean']:.1f} ± {cd['sd']:.1f} | {r['median_wall_s']:.0f} | "
                     f"{r['median_particle_steps_per_s'] / 1e6:.1f} |")
    out = head + "\n".join(lines) + "\n"
    by_amp = {}
    for r in rows:
        by_amp.setdefault(r["amplitude_rel"], []).append(r)
    for amp, rs in by_amp.items():
        if len(rs) > 1:
            first = np.array([r["ucs_mpa"]["members"][0] for r in rs])
            means = np.array([r["ucs_mpa"]["mean"] for r in rs])
            sds = np.array([r["ucs_mpa"]["sd"] for r in rs])
            out += (f"\namplitude {amp:g}: UCS sd across specimens (member 0) "
                    f"{first.std(ddof=1):.1f} MPa, of the ensemble means {means.std(ddof=1):.1f}"
                    f" MPa; failure-path sd (rms over specimens) "
                    f"{np.sqrt(np.mean(sds ** 2)):.1f} MPa\n")
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--specimens", nargs="+", required=True, help="specimen .npz files")
    p.add_argument("--params", default=None, help="parameter YAML applied to each specimen")
    p.add_argument("--runs", type=int, default=8)
    p.add_argument("--amplitudes", default="1e-9",
                   help="comma-separated perturbation amplitudes (relative to the mean radius)")
    p.add_argument("--platen-velocity", type=float, default=None,
                   help="base speed of the adaptive rule (default: the protocol's)")
    p.add_argument("--f-max", type=float, default=None,
                   help="fast-phase factor of the adaptive rule (with --platen-velocity)")
    p.add_argument("--out", default="benchmarks/results/ucs_ensemble")
    p.add_argument("--no-progress", action="store_true")
    a = p.parse_args(argv)
    from sim import Specimen
    from sim.protocols.ensemble import run_ensemble
    from sim.protocols.parameters import apply_parameters, load_parameters
    params = load_parameters(a.params) if a.params else None
    kw = {}
    if a.platen_velocity is not None:
        kw["platen_velocity"] = a.platen_velocity
    if a.f_max is not None:
        kw["adaptive"] = {"f_max": a.f_max}
    rows = []
    t0 = time.perf_counter()
    for path in a.specimens:
        spec = Specimen.load(path)
        if params is not None:
            spec = apply_parameters(spec, params)
        name = os.path.splitext(os.path.basename(path))[0]
        for amp in (float(x) for x in a.amplitudes.split(",")):
            d = os.path.join(a.out, f"{name}_a{amp:g}")
            again = os.path.exists(os.path.join(d, "ensemble.json"))
            res = run_ensemble("ucs", spec, runs=a.runs, amplitude=amp, out=d, resume=again,
                               progress=not a.no_progress, figures=True, **kw)
            rows.append(summarise(name, amp, res))
    doc = {"benchmark": "ucs_ensemble", "params": a.params, "options": kw,
           "threads": int(__import__("numba").get_num_threads()),
           "wall_s_total": time.perf_counter() - t0, "rows": rows}
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "ucs_ensemble.json"), "w") as f:
        json.dump(doc, f, indent=2)
    text = table(rows)
    with open(os.path.join(a.out, "ucs_ensemble.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
