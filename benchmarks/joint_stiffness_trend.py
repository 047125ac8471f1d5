"""Which way E moves with the grain-boundary share, for joint stiffnesses below and above the bonds.

The thesis has E rising both from Scenario 1 to 4 and when every grain size is scaled ×1.5.
In this model's specimens S2-S4 carry more smooth joints than S1 (joint share of the bonds
0.43-0.46 against 0.27) and ×1.5 carries fewer (0.18). This benchmark measures E against the
joint share for several joint stiffnesses: ``sj_kn`` and ``sj_ks`` of the parameter file times
a factor f, every bond and joint made unbreakable, UCS loading to ``--max-strain`` (elastic).
E then depends on the structure and the stiffnesses only, with no cracking and no failure path.

    python benchmarks/joint_stiffness_trend.py --seeds 1,2,3 --out DIR

Prints E (mean ± sd over the seeds) per case and factor, the relative change S1 → S4 and
S1 → S1 ×1.5 beside the thesis's sign, and the median throughput (particle-steps/s).
"""
from __future__ import annotations

import argparse
import copy
import json
import os
import time

from ucs_scenarios import add_specimen_options, read_rows, write_rows

PRESET = os.path.join(os.path.dirname(__file__), "ucs_results", "calibration_10x20_dt06",
                      "calibrated_params.yaml")
# (scenario, grain-size factor, label); 1.357 puts S4 at S1's grain count (the control)
CASES = [(1, 1.0, "S1"), (2, 1.0, "S2"), (3, 1.0, "S3"), (4, 1.0, "S4"),
         (4, 1.357, "S4 ×1.357"), (1, 1.5, "S1 ×1.5")]
THESIS_E = {"S1": 63.65, "S2": 72.2, "S3": 77.3, "S4": 91.35}   # mid-ranges of Table 4-2, GPa


def elastic_params(params, factor):
    """``params`` with the joint stiffnesses times ``factor`` and nothing able to break."""
    p = copy.deepcopy(params)
    p["joint"]["sj_kn"] *= factor
    p["joint"]["sj_ks"] *= factor
    p["joint"]["sj_ten"] = p["joint"]["sj_coh"] = 1e15
    for m in p["minerals"].values():
        m["pb_ten"] = m["pb_coh"] = 1e15
    return p


def markdown_table(rows):
    """E per case (columns) and joint-stiffness factor (rows), with S1 → S4 and S1 → ×1.5."""
    import numpy as np
    labels = [c[2] for c in CASES if any(r["case"] == c[2] for r in rows)]
    factors = sorted({r["f"] for r in rows})

    def e_of(label, f):
        return np.array([r["E_gpa"] for r in rows if r["case"] == label and r["f"] == f])

    share = {lab: np.mean([r["joint_fraction"] for r in rows if r["case"] == lab])
             for lab in labels}
    head = " | ".join(f"{lab} E GPa (J {share[lab]:.2f})" for lab in labels)
    lines = [f"| sj_kn factor | {head} | S1 → S4 | S1 → S1 ×1.5 |",
             "|---" * (len(labels) + 3) + "|"]
    for f in factors:
        cells = []
        for lab in labels:
            e = e_of(lab, f)
            cells.append(f"{e.mean():.1f} ± {e.std(ddof=1) if e.size > 1 else 0:.1f}")
        d = []
        for lab in ("S4", "S1 ×1.5"):
            ok = lab in labels and "S1" in labels
            d.append(f"{100 * (e_of(lab, f).mean() / e_of('S1', f).mean() - 1):+.0f} %"
                     if ok else "–")
        lines.append(f"| {f:g} | " + " | ".join(cells) + f" | {d[0]} | {d[1]} |")
    th = " | ".join(f"{THESIS_E[lab]:.1f}" if lab in THESIS_E else "rises" if lab == "S1 ×1.5"
                    else "–" for lab in labels)
    rise = 100 * (THESIS_E["S4"] / THESIS_E["S1"] - 1)
    lines.append(f"| thesis | {th} | {rise:+.0f} % | rises |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--params", default=PRESET, help="parameter YAML (default: the calibrated "
                   "preset, thesis-ch4-calibrated)")
    p.add_argument("--factors", default="0.1,0.3,1,2,3,10", help="sj_kn, sj_ks multipliers")
    p.add_argument("--seeds", default="1,2,3")
    p.add_argument("--cases", default=",".join(c[2] for c in CASES),
                   help="subset of: " + ", ".join(c[2] for c in CASES))
    add_specimen_options(p, width_mm=10.0, height_mm=20.0)
    p.add_argument("--max-strain", type=float, default=1e-3)
    p.add_argument("--out", default="benchmarks/results/joint_stiffness")
    p.add_argument("--merge", default=None,
                   help="comma-separated joint_stiffness.json files: only print their table")
    a = p.parse_args(argv)
    if a.merge:
        print(markdown_table(read_rows(a.merge)))
        return 0
    import numpy as np

    from gbmgen.build import build_specimen
    from gbmgen.table import example_table
    from sim.protocols.parameters import apply_parameters, load_parameters
    from sim.protocols.ucs import run_ucs
    table = example_table("table-4-1")
    params = load_parameters(a.params)
    wanted = [c.strip() for c in a.cases.split(",")]
    unknown = sorted(set(wanted) - {c[2] for c in CASES})
    if unknown:
        p.error(f"--cases: unknown {unknown}, expected some of {[c[2] for c in CASES]}")
    cases = [c for c in CASES if c[2] in wanted]
    factors = [float(x) for x in a.factors.split(",")]
    rows = []
    for sc, scale, label in cases:
        for seed in map(int, a.seeds.split(",")):
            spec0, _ = build_specimen(table, width_mm=a.width_mm, height_mm=a.height_mm,
                                      scenario=sc, scale=scale,
                                      particle_radius_mm=a.particle_radius_mm, seed=seed,
                                      seat_faces=a.seat_faces)
            for f in factors:
                spec = apply_parameters(spec0, elastic_params(params, f))
                t0 = time.perf_counter()
                s = run_ucs(spec, progress=False, figures=False, post_peak=None,
                            max_strain=a.max_strain).summary
                wall = time.perf_counter() - t0
                rows.append({"case": label, "scenario": sc, "scale": scale, "seed": seed,
                             "f": f, "n_particles": spec.n_particles,
                             "n_grains": spec.n_grains,
                             "joint_fraction": float(np.mean(spec.bond_kind == 1)),
                             "E_gpa": s["elastic"]["E_measured_gpa"], "E_ok": s["E_ok"],
                             "nu": s["elastic"]["nu_measured"], "steps": s["steps"],
                             "wall_s": wall,
                             "particle_steps_per_s": spec.n_particles * s["steps"] / wall,
                             "threads": s["threads"], "params": a.params})
                print(json.dumps(rows[-1]), flush=True)
    text = markdown_table(rows)
    rate = np.median([r["particle_steps_per_s"] for r in rows])
    text += (f"\nmedian throughput {rate / 1e6:.1f} M particle-steps/s over {len(rows)} elastic "
             f"runs to strain {a.max_strain:g}\n")
    write_rows(a.out, "joint_stiffness", rows, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
