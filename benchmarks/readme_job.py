"""The README's main job over seeds: E, ν and their validity flags, UCS, time per run.

Runs ``gbmgen run IMAGES --out OUT/seedK --width-mm 13 --height-mm 26 --particle-radius-mm 0.15
--seed K`` for each seed (a folder that already holds ``ucs/summary.json`` is read back, not
run again; its cost is then read from ``seedK.time``, a ``/usr/bin/time -v`` report, when
present), then writes ``readme_job.json`` and ``readme_job.md``: per seed E (gauge and
platen), ν (boundary and gauge), the flags, UCS and the wall and CPU time of the run; below,
whether the README's criteria hold: every E and ν valid, ν in [0, 0.5) and within ±0.05 of
the seeds' mean, gauge and platen E within 15 %.

    NUMBA_NUM_THREADS=1 python benchmarks/readme_job.py --seeds 1,2,3,4,5 --out DIR
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: The README's main job, less ``--out`` and ``--seed``.
JOB = ("--width-mm", "13", "--height-mm", "26", "--particle-radius-mm", "0.15")
#: Largest distance of a seed's ν from the seeds' mean for the README criterion.
NU_SPREAD = 0.05


def run_seed(images, out, seed):
    """Run the job for one seed unless ``out`` holds its summary; the run's cost or None."""
    if os.path.exists(os.path.join(out, "ucs", "summary.json")):
        return None
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "gbmgen.cli", "run", images, "--out", out, *JOB,
                    "--seed", str(seed), "--no-progress"], check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"wall_s": time.perf_counter() - t0,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)}


def time_file_cost(path):
    """Wall and CPU seconds from a GNU ``/usr/bin/time -v`` report, or None."""
    if not os.path.exists(path):
        return None
    got = {}
    with open(path) as f:
        for line in f:
            k, _, v = line.strip().partition(": ")
            if k in ("User time (seconds)", "System time (seconds)"):
                got[k] = float(v)
            elif k.startswith("Elapsed (wall clock) time"):
                parts = [float(x) for x in v.split(":")]
                got["wall"] = sum(x * 60 ** i for i, x in enumerate(reversed(parts)))
    if "wall" not in got:
        return None
    return {"wall_s": got["wall"], "cpu_s": got.get("User time (seconds)", 0.0)
            + got.get("System time (seconds)", 0.0)}


def _particles(out):
    with open(os.path.join(out, "run.json")) as f:
        return json.load(f)["particles"]


def row(out, seed, cost):
    """One seed's numbers from its ``ucs/summary.json``."""
    with open(os.path.join(out, "ucs", "summary.json")) as f:
        s = json.load(f)
    e = s["elastic"]
    r = {"seed": seed, "folder": out, "ucs_mpa": s["ucs_mpa"], "E_gpa": s["E_gpa"],
         "E_ok": s["E_ok"], "E_reason": s["E_reason"], "nu": s["nu"], "nu_ok": s["nu_ok"],
         "nu_reason": s["nu_reason"], "E_gauge_gpa": e["E_gauge_gpa"],
         "E_platen_gpa": e["E_platen_gpa"], "nu_boundary": e["nu_boundary"],
         "nu_gauge": e["nu_gauge"], "window_stress_fraction": e.get("window_stress_fraction"),
         "n_particles": _particles(out),
         "representative_ok": s.get("representative", {}).get("ok")}
    if cost:
        r.update(cost)
    return r


def criteria(rows):
    """The README criteria over the seeds."""
    nus = np.array([r["nu"] if r["nu"] is not None else np.nan for r in rows], float)
    ratio = np.array([r["E_gauge_gpa"] / r["E_platen_gpa"] for r in rows])
    all_valid = all(r["E_ok"] and r["nu_ok"] for r in rows)
    mean = float(np.nanmean(nus)) if np.isfinite(nus).any() else float("nan")
    spread = float(np.nanmax(np.abs(nus - mean))) if np.isfinite(nus).any() else float("nan")
    return {"all_valid": bool(all_valid), "nu_mean": mean, "nu_max_deviation": spread,
            "nu_within_spread": bool(all_valid and spread <= NU_SPREAD),
            "E_ratio_min": float(ratio.min()), "E_ratio_max": float(ratio.max()),
            "E_mean_gpa": float(np.mean([r["E_gpa"] for r in rows if r["E_gpa"] is not None]
                                        or [np.nan])),
            "ucs_mean_mpa": float(np.mean([r["ucs_mpa"] for r in rows])),
            "passes": bool(all_valid and spread <= NU_SPREAD
                           and np.all(np.abs(ratio - 1.0) <= 0.15))}


def markdown(rows, crit):
    def f(v, fmt):
        return "–" if v is None else format(v, fmt)
    lines = ["| seed | E GPa (gauge) | E platen GPa | ν (boundary) | ν gauge | E_ok | ν_ok | "
             "UCS MPa | wall s | CPU s |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['seed']} | {f(r['E_gpa'], '.1f')} | {r['E_platen_gpa']:.1f} | "
                     f"{f(r['nu'], '.3f')} | {r['nu_gauge']:.3f} | {r['E_ok']} | {r['nu_ok']} | "
                     f"{r['ucs_mpa']:.1f} | {f(r.get('wall_s'), '.0f')} | "
                     f"{f(r.get('cpu_s'), '.0f')} |")
    lines.append("")
    lines.append(f"ν mean {crit['nu_mean']:.3f}, largest distance from it "
                 f"{crit['nu_max_deviation']:.3f} (criterion ≤ {NU_SPREAD}); gauge/platen E "
                 f"{crit['E_ratio_min']:.3f}-{crit['E_ratio_max']:.3f} (criterion within 15 %); "
                 f"all flags true: {crit['all_valid']}; criteria met: {crit['passes']}")
    return "\n".join(lines) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", default="1,2,3,4,5")
    p.add_argument("--images", default=os.path.join(ROOT, "sample_images"))
    p.add_argument("--out", required=True, help="folder of the runs (seedK) and the tables")
    p.add_argument("--name", default="readme_job")
    a = p.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for k in (int(v) for v in a.seeds.split(",")):
        out = os.path.join(a.out, f"seed{k}")
        cost = run_seed(a.images, out, k) or time_file_cost(out + ".time")
        rows.append(row(out, k, cost))
        print(json.dumps(rows[-1]), flush=True)
    crit = criteria(rows)
    with open(os.path.join(a.out, a.name + ".json"), "w") as f:
        json.dump({"job": ["gbmgen", "run", "IMAGES", *JOB], "rows": rows, "criteria": crit},
                  f, indent=2)
    text = markdown(rows, crit)
    with open(os.path.join(a.out, a.name + ".md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
