"""Broad phase on a ring-graded field specimen: one grid (cell 2 r_max + skin) against one grid
per radius level (sim.neighbors), same pairs, time per contact-list build.

    python benchmarks/field_broad_phase.py [SPECIMEN.npz] [--repeat 7]

Default specimen: benchmarks/field_results/drive40_seed1.npz (``gbmgen field --opening drive
--seed 1``; built if missing). Both builders run alternately in one process on one thread
(medians of ``--repeat``); also reports how many particles the single grid's cells hold.
Writes benchmarks/field_results/broad_phase.{json,md}.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numba
import numpy as np


def main(argv=None):
    from sim import Specimen
    from sim.neighbors import (
        _build_contacts_levels,
        _build_contacts_single,
        partner_csr,
        radius_levels,
    )
    p = argparse.ArgumentParser()
    p.add_argument("specimen", nargs="?", default="benchmarks/field_results/drive40_seed1.npz")
    p.add_argument("--repeat", type=int, default=7)
    a = p.parse_args(argv)
    if not os.path.exists(a.specimen):
        subprocess.check_call([sys.executable, "-m", "gbmgen", "field", "--opening", "drive",
                               "--seed", "1", "--out", a.specimen, "--no-progress"])
    numba.set_num_threads(1)
    s = Specimen.load(a.specimen)
    x, y, r = s.x, s.y, s.r
    n = x.size
    skin = 0.5 * float(r.mean())
    sj = s.bond_kind == 1
    ptr, adj = partner_csr(n, s.bond_i[sj], s.bond_j[sj])
    level, nlev = radius_levels(r, spread=1.0)
    empty = (np.zeros(n + 1, np.int64), np.zeros(0, np.int32), np.zeros(0))

    def single(cap):
        cs = np.zeros(n + 1, np.int64)
        ci, cj, fs = np.zeros(cap, np.int32), np.zeros(cap, np.int32), np.zeros(cap)
        t = _build_contacts_single(x, y, r, skin, ptr, adj, *empty, cs, ci, cj, fs, 1)
        return t, ci[:t], cj[:t]

    def levels(cap):
        cs = np.zeros(n + 1, np.int64)
        ci, cj, fs = np.zeros(cap, np.int32), np.zeros(cap, np.int32), np.zeros(cap)
        t = _build_contacts_levels(x, y, r, level, nlev, skin, ptr, adj, *empty, cs, ci, cj,
                                   fs, 1)
        return t, ci[:t], cj[:t]

    cap = single(0)[0] + 16
    a1, a2 = single(cap), levels(cap)
    same = set(zip(a1[1].tolist(), a1[2].tolist())) == set(zip(a2[1].tolist(), a2[2].tolist()))
    ts, tl = [], []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        single(cap)
        ts.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        levels(cap)
        tl.append(time.perf_counter() - t0)
    h = 2 * r.max() + skin
    cx = np.floor((x - x.min()) / h).astype(np.int64)
    cy = np.floor((y - y.min()) / h).astype(np.int64)
    occ = np.bincount(cy * (cx.max() + 1) + cx)
    occ = occ[occ > 0]
    res = {"specimen": a.specimen, "particles": n, "radius_spread": float(r.max() / r.min()),
           "levels": nlev, "pairs": int(a1[0]), "same_pairs": bool(same),
           "single_grid_cell_m": float(h), "single_grid_max_per_cell": int(occ.max()),
           "single_grid_mean_per_occupied_cell": float(occ.mean()),
           "single_ms": 1e3 * float(np.median(ts)), "levels_ms": 1e3 * float(np.median(tl)),
           "load": os.getloadavg()}
    res["speedup"] = res["single_ms"] / res["levels_ms"]
    os.makedirs("benchmarks/field_results", exist_ok=True)
    with open("benchmarks/field_results/broad_phase.json", "w") as fh:
        json.dump(res, fh, indent=1)
    md = ("| particles | radius spread | levels | pairs | single grid: cell m, max / mean per "
          "cell | single ms | per-level ms | speed-up | load |\n|---|---|---|---|---|---|---|---|"
          f"---|\n| {n} | {res['radius_spread']:.1f} | {nlev} | {res['pairs']} | {h:.3f}, "
          f"{res['single_grid_max_per_cell']} / {res['single_grid_mean_per_occupied_cell']:.0f} "
          f"| {res['single_ms']:.1f} | {res['levels_ms']:.1f} | {res['speedup']:.1f} | "
          f"{res['load'][0]:.1f} |\n")
    with open("benchmarks/field_results/broad_phase.md", "w") as fh:
        fh.write(md)
    print(md)


if __name__ == "__main__":
    main()
