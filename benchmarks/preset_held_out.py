"""A calibrated preset on specimens it never saw: UCS, E, ν and σt per seed against the targets.

For each seed the specimen is built as a user builds it, then loaded with the defaults::

    gbmgen build --table table-4-1 --scenario 1 --width-mm W --height-mm H \\
        --particle-radius-mm R --seed S --params PRESET --out OUT/sS.npz
    gbmsim ucs OUT/sS.npz --out OUT/ucsS
    gbmsim tension OUT/sS.npz --out OUT/tenS

``--tests tension`` (or ``ucs``) runs one test per seed, for more specimens of one response
in the same time; the other's columns stay empty. A seed whose specimen or summaries already
exist is read back, not run again (an interrupted
run continues where it stopped). Writes ``held_out.json`` (per seed: particles, UCS, E gauge
and platen, ν, flags, σt, steps and wall time of each test) and prints a markdown table with
the mean, the sample sd and each mean's error against the calibration targets
(``sim.calibrate.DEFAULT_TARGETS``, REFERENCE.md: E 65 GPa, UCS 135 MPa, σt 18 MPa) with its
standard error (sd / √n, relative to the target); E and ν flagged invalid by the test are
shown as such and left out of the means.

    python benchmarks/preset_held_out.py --preset thesis-ch4-calibrated-25x50 --seeds 4,5,6 \\
        --width-mm 25 --height-mm 50 --particle-radius-mm 0.1 --out DIR
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import numpy as np

from sim.calibrate import DEFAULT_TARGETS

#: The calibration targets in the units of the summaries.
TARGETS = {"E_gpa": DEFAULT_TARGETS["E"] / 1e9, "ucs_mpa": DEFAULT_TARGETS["UCS"] / 1e6,
           "tensile_mpa": DEFAULT_TARGETS["sigma_t"] / 1e6}


def _run(args):
    subprocess.run([sys.executable, "-m", *args, "--no-progress"], check=True)


def _summary(folder):
    path = os.path.join(folder, "summary.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def run_seed(out, seed, *, preset, width_mm, height_mm, radius_mm, tests=("ucs", "tension")):
    """Build and test one seed (each step skipped when its output exists); its row (the
    fields of a test not in ``tests`` are None)."""
    spec = os.path.join(out, f"s{seed}.npz")
    if not os.path.exists(spec):
        _run(["gbmgen.cli", "build", "--table", "table-4-1", "--scenario", "1",
              "--width-mm", str(width_mm), "--height-mm", str(height_mm),
              "--particle-radius-mm", str(radius_mm), "--seed", str(seed),
              "--params", preset, "--out", spec])
    ucs_dir, ten_dir = os.path.join(out, f"ucs{seed}"), os.path.join(out, f"ten{seed}")
    if "ucs" in tests and _summary(ucs_dir) is None:
        _run(["sim", "ucs", spec, "--out", ucs_dir, "--no-figures"])
    if "tension" in tests and _summary(ten_dir) is None:
        _run(["sim", "tension", spec, "--out", ten_dir, "--no-figures"])
    u = _summary(ucs_dir) if "ucs" in tests else None
    t = _summary(ten_dir) if "tension" in tests else None
    u_, t_ = u or {}, t or {}
    e = u_.get("elastic", {})
    return {"seed": seed, "n_particles": (u_ or t_).get("n_particles"),
            "ucs_mpa": u_.get("ucs_mpa"), "E_gpa": u_.get("E_gpa"), "E_ok": u_.get("E_ok"),
            "E_gauge_gpa": e.get("E_gauge_gpa"), "E_platen_gpa": e.get("E_platen_gpa"),
            "nu": u_.get("nu"), "nu_ok": u_.get("nu_ok"), "tensile_mpa": t_.get("tensile_mpa"),
            "ucs_steps": u_.get("steps"), "ucs_wall_s": u_.get("wall_s"),
            "tension_steps": t_.get("steps"), "tension_wall_s": t_.get("wall_s"),
            "threads": (u_ or t_).get("threads")}


def summarise(rows):
    """Mean, sample sd and the mean's relative error per target (valid values only)."""
    out = {}
    for k, target in TARGETS.items():
        v = np.array([r[k] for r in rows if r[k] is not None], float)
        if len(v) == 0:
            out[k] = {"n": 0}
            continue
        m = float(v.mean())
        sd = float(v.std(ddof=1)) if len(v) > 1 else None
        out[k] = {"n": int(len(v)), "mean": m, "sd": sd, "error": m / target - 1.0,
                  "error_se": None if sd is None else sd / np.sqrt(len(v)) / target}
    return out


def _num(v, fmt):
    return "–" if v is None else f"{v:{fmt}}"


def table(rows, summary):
    lines = ["| seed | particles | UCS MPa | E GPa (gauge; platen) | ν | σt MPa |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        ran = r["ucs_mpa"] is not None
        e = "–" if not ran else "invalid" if r["E_gpa"] is None else f"{r['E_gpa']:.1f}"
        nu = "–" if not ran else "invalid" if r["nu"] is None else f"{r['nu']:.3f}"
        gauge = f"{_num(r['E_gauge_gpa'], '.1f')}; {_num(r['E_platen_gpa'], '.1f')}"
        lines.append(f"| {r['seed']} | {r['n_particles']} | {_num(r['ucs_mpa'], '.1f')} | {e} "
                     f"({gauge}) | {nu} | {_num(r['tensile_mpa'], '.2f')} |")

    def cell(k, fmt):
        s = summary[k]
        if s["n"] == 0:
            return "no valid value"
        sd = "" if s["sd"] is None else f" ± {s['sd']:{fmt}}"
        se = "" if s.get("error_se") is None else f" ± {100 * s['error_se']:.1f}"
        ran = sum(r["ucs_mpa" if k == "E_gpa" else k] is not None for r in rows)
        n = f", {s['n']} valid of {ran}" if s["n"] < ran else ""
        return f"{s['mean']:{fmt}}{sd} ({100 * s['error']:+.1f}{se} %{n})"
    lines.append(f"| **mean ± sd** | | {cell('ucs_mpa', '.1f')} | {cell('E_gpa', '.1f')} | | "
                 f"{cell('tensile_mpa', '.2f')} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", required=True)
    ap.add_argument("--seeds", required=True, help="comma-separated seeds, e.g. 4,5,6")
    ap.add_argument("--width-mm", type=float, default=25.0)
    ap.add_argument("--height-mm", type=float, default=50.0)
    ap.add_argument("--particle-radius-mm", type=float, default=0.1)
    ap.add_argument("--out", required=True, help="working folder (specimens, test outputs)")
    ap.add_argument("--json", default=None, help="result file (default OUT/held_out.json)")
    ap.add_argument("--tests", default="ucs,tension",
                    help="tests to run per seed: ucs, tension or both (default)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    seeds = [int(s) for s in args.seeds.split(",")]
    tests = tuple(t.strip() for t in args.tests.split(","))
    if not tests or set(tests) - {"ucs", "tension"}:
        raise SystemExit(f"--tests {args.tests!r}: expected ucs, tension or ucs,tension")
    rows = [run_seed(args.out, s, preset=args.preset, width_mm=args.width_mm,
                     height_mm=args.height_mm, radius_mm=args.particle_radius_mm, tests=tests)
            for s in seeds]
    summary = summarise(rows)
    build = (f"gbmgen build --table table-4-1 --scenario 1 --width-mm {args.width_mm:g} "
             f"--height-mm {args.height_mm:g} --particle-radius-mm {args.particle_radius_mm:g} "
             f"--seed S --params {args.preset} --out sS.npz")
    cmd = {"ucs": "gbmsim ucs sS.npz --out ucsS", "tension": "gbmsim tension sS.npz --out tenS"}
    result = {"preset": args.preset, "targets": TARGETS, "build": build,
              "tests": [cmd[t] for t in tests],
              "load": os.getloadavg(), "held_out": rows, "summary": summary}
    path = args.json or os.path.join(args.out, "held_out.json")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, path)
    print(table(rows, summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
