"""Sleeping particles: error against the awake run and steps saved, by sleep threshold.

    python benchmarks/field_sleep_threshold.py [--thresholds 1e-8,1e-7,1e-6]

The small elastic model of tests/field (a = 0.75 m circle in an 8 m domain of the test's
three-ring plan, seed 3, 400 m) excavated awake and with each ``--sleep-disp``; writes
benchmarks/field_results/sleep_threshold.json: excavation steps, mean asleep fraction, largest
displacement difference / largest displacement, largest relative σθθ difference (r/a >= 1.5).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile

import numpy as np
import pandas as pd


def main(argv=None):
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests", "field"))
    from conftest import MINI_PLAN

    from gbmgen.field import openings as op
    from gbmgen.field.build import build_field
    from gbmgen.field.plan import plan_from_dict
    from sim.protocols.excavate import run_excavate
    p = argparse.ArgumentParser()
    p.add_argument("--thresholds", default="1e-8,1e-7,1e-6")
    a = p.parse_args(argv)
    spec, _ = build_field(plan=plan_from_dict(MINI_PLAN), openings=[op.circle(radius_m=0.75)],
                          domain_m=8.0, seed=3)
    tmp = tempfile.mkdtemp()

    def run(sd):
        d = os.path.join(tmp, f"s{sd}")
        s = run_excavate(spec, depth_m=400, out=d, elastic=True, sleep=sd > 0,
                         sleep_disp=max(sd, 1e-12), progress=False, figures=False)
        return s, d

    s0, d0 = run(0.0)
    u0 = pd.read_csv(os.path.join(d0, "displacement.csv"))
    p0 = pd.read_csv(os.path.join(d0, "stress_profile.csv"))
    rows = [{"sleep_disp": 0.0, "excavation_steps": s0["phases"]["excavate_1"]["steps"]}]
    for sd in (float(v) for v in a.thresholds.split(",")):
        s, d = run(sd)
        u = pd.read_csv(os.path.join(d, "displacement.csv"))
        pr = pd.read_csv(os.path.join(d, "stress_profile.csv"))
        h = pd.read_csv(os.path.join(d, "history.csv"))
        du = np.hypot(u["ux_mm"] - u0["ux_mm"], u["uy_mm"] - u0["uy_mm"]).max()
        sel = p0["r_over_a"] >= 1.5
        ds = ((pr["sigma_tt_mpa"] - p0["sigma_tt_mpa"]).abs() / p0["sigma_tt_mpa"].abs())[sel]
        rows.append({"sleep_disp": sd, "excavation_steps": s["phases"]["excavate_1"]["steps"],
                     "asleep_mean": float(h.loc[h["phase"] != "insitu",
                                                "asleep_fraction"].mean()),
                     "displacement_rel_error": float(du / np.hypot(u0["ux_mm"],
                                                                   u0["uy_mm"]).max()),
                     "stress_rel_error": float(ds.max())})
    os.makedirs("benchmarks/field_results", exist_ok=True)
    with open("benchmarks/field_results/sleep_threshold.json", "w") as fh:
        json.dump({"particles": spec.n_particles, "rows": rows}, fh, indent=1)
    print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
