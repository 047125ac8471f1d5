"""Thesis trend check: UCS and E for grain-size Scenarios 1-4 and for grain sizes x1.5.

Builds gbmgen specimens (Table 4-1, Laguerre grains) for each scenario and seed, applies one
parameter file (e.g. the calibrated one), runs the UCS protocol, and prints a table beside the
thesis's Table 4-2 ranges (UCS 133.9-136.9 / 189.1-193.7 / 237.0-250.3 / 295.6-314.3 MPa;
E 61.8-65.5 / 71.0-73.4 / 76.1-78.5 / 89.3-93.4 GPa for S1..S4).

    python benchmarks/ucs_scenarios.py --params calib/calibrated_params.yaml --out results
"""
from __future__ import annotations

import argparse
import json
import os
import time

THESIS = {1: ((133.9, 136.9), (61.8, 65.5)), 2: ((189.1, 193.7), (71.0, 73.4)),
          3: ((237.0, 250.3), (76.1, 78.5)), 4: ((295.6, 314.3), (89.3, 93.4))}


def markdown_table(rows):
    """Markdown table of the runs, one line per (scenario, scale), beside the thesis ranges."""
    import numpy as np
    cases = list(dict.fromkeys((x["scenario"], x["scale"]) for x in rows))
    cases.sort(key=lambda c: (c[1] != 1.0, c[0], c[1]))
    lines = ["| scenario | scale | MHI (realised) | grains | joint share of bonds | "
             "UCS MPa (mean ± sd) | E GPa (mean ± sd) | thesis UCS MPa | thesis E GPa | n |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for sc, scale in cases:
        r = [x for x in rows if x["scenario"] == sc and x["scale"] == scale]
        u = np.array([x["ucs_mpa"] for x in r])
        e = np.array([x["E_gpa"] for x in r if x["E_gpa"] is not None])
        m = [x["mhi_realised"] for x in r if x["mhi_realised"] is not None]
        g = np.mean([x["n_grains"] for x in r])
        jf = [x["joint_fraction"] for x in r if "joint_fraction" in x]
        th = THESIS.get(sc) if scale == 1.0 else None
        lines.append(f"| S{sc} | ×{scale:g} | {np.mean(m) if m else float('nan'):.2f} | "
                     f"{g:.0f} | {np.mean(jf) if jf else float('nan'):.2f} | "
                     f"{_mean_sd(u)} | " + (_mean_sd(e) if len(e) else "–")
                     + (f" ({len(r) - len(e)} invalid)" if len(e) < len(r) else "") + " | "
                     + (f"{th[0][0]}–{th[0][1]} | {th[1][0]}–{th[1][1]}" if th else "– | –")
                     + f" | {len(r)} |")
    return "\n".join(lines) + "\n"


def _mean_sd(v):
    """``"mean ± sd"`` over the seeds; the mean alone for one value (no sd to show)."""
    return f"{v.mean():.1f} ± {v.std(ddof=1):.1f}" if len(v) > 1 else f"{v.mean():.1f}"


def read_rows(paths):
    """The rows of comma-separated result JSON files (lists of dicts), joined."""
    rows = []
    for path in paths.split(","):
        with open(path) as f:
            rows += json.load(f)
    return rows


def write_rows(out, name, rows, text):
    """Write ``rows`` to ``out/name.json`` and the table ``text`` to ``out/name.md``; print it."""
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, f"{name}.json"), "w") as f:
        json.dump(rows, f, indent=2)
    with open(os.path.join(out, f"{name}.md"), "w") as f:
        f.write(text)
    print(text)


def add_specimen_options(p, *, width_mm, height_mm):
    """The specimen options shared by the scenario benchmarks (size, particles, seating)."""
    p.add_argument("--width-mm", type=float, default=width_mm)
    p.add_argument("--height-mm", type=float, default=height_mm)
    p.add_argument("--particle-radius-mm", type=float, default=0.1)
    p.add_argument("--no-seat-faces", dest="seat_faces", action="store_false",
                   help="specimens without face seating (the results of 2026-11-21)")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--params", default=None, help="parameter YAML (default start_parameters)")
    add_specimen_options(p, width_mm=4.0, height_mm=8.0)
    p.add_argument("--seeds", default="1,2")
    p.add_argument("--scenarios", default="1,2,3,4")
    p.add_argument("--scales", default="1.0,1.5",
                   help="grain-size factors run for the --scale-scenarios")
    p.add_argument("--scale-scenarios", default="1",
                   help="scenarios run with the --scales (default 1)")
    p.add_argument("--platen-velocity", type=float, default=None)
    p.add_argument("--timestep-factor", type=float, default=None)
    p.add_argument("--out", default="benchmarks/results")
    p.add_argument("--merge", default=None,
                   help="comma-separated ucs_scenarios.json files: only print their joint table")
    a = p.parse_args(argv)
    if a.merge:
        print(markdown_table(read_rows(a.merge)))
        return 0
    import numpy as np

    import gbmgen
    from gbmgen.build import build_specimen
    from gbmgen.table import read_table
    from sim.protocols.parameters import apply_parameters, load_parameters, start_parameters
    from sim.protocols.ucs import run_ucs
    table = read_table(os.path.join(os.path.dirname(gbmgen.__file__), "presets",
                                    "table_4_1.csv"))
    kw = {}
    if a.platen_velocity:
        kw["platen_velocity"] = a.platen_velocity
    if a.timestep_factor:
        kw["timestep_factor"] = a.timestep_factor
    cases = [(sc, 1.0) for sc in map(int, a.scenarios.split(",")) if sc]
    cases += [(sc, float(s)) for sc in map(int, a.scale_scenarios.split(","))
              for s in a.scales.split(",") if float(s) != 1.0]
    rows = []
    for sc, scale in cases:
        for seed in map(int, a.seeds.split(",")):
            spec, _ = build_specimen(table, width_mm=a.width_mm, height_mm=a.height_mm,
                                     scenario=sc, scale=scale,
                                     particle_radius_mm=a.particle_radius_mm, seed=seed,
                                     seat_faces=a.seat_faces)
            prm = load_parameters(a.params) if a.params else start_parameters(spec)
            spec = apply_parameters(spec, prm)
            t0 = time.perf_counter()
            s = run_ucs(spec, progress=False, **kw).summary
            mhi = spec.meta.get("MHI_realised", spec.meta.get("mhi_realised"))
            rows.append({"scenario": sc, "scale": scale, "seed": seed,
                         "width_mm": a.width_mm, "height_mm": a.height_mm,
                         "n_particles": spec.n_particles, "n_grains": spec.n_grains,
                         "joint_fraction": float(np.mean(spec.bond_kind == 1)),
                         "mhi_realised": mhi, "ucs_mpa": s["ucs_mpa"], "E_gpa": s["E_gpa"],
                         "nu": s["nu"], "E_ok": s["E_ok"], "nu_ok": s["nu_ok"],
                         "E_reason": s["E_reason"], "elastic": s["elastic"],
                         "cracks": s["cracks"]["total"],
                         "wall_s": time.perf_counter() - t0, "steps": s["steps"],
                         "force_chunks": s["force_chunks"], "threads": s["threads"],
                         "params": a.params, "seat_faces": a.seat_faces})
            print(json.dumps(rows[-1]), flush=True)
    write_rows(a.out, "ucs_scenarios", rows, markdown_table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
