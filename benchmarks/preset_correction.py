"""One correction step for a preset from its results pooled over many specimens.

A calibration searched on a few specimens lands its mean on the targets; a held-out check
(``benchmarks/preset_held_out.py``) may then show that those specimens were a low or high
draw. This script pools every specimen measured at the preset (the seed rows of the
calibration log and the held-out rows), takes the mean, and computes the calibration's own
seed-mean correction (:func:`sim.calibrate.correction_step`, scaling-law Jacobian), so that
the step rests on all the specimens rather than on the first few. The step is a prediction:
check the corrected set on specimens neither the calibration nor the pooled mean used.

Specimens measured at an earlier set of the same calibration join with ``--mapped
FILE:E=r1,UCS=r2,sigma_t=r3``: each response times its ratio to the preset (a paired run on
the same specimens, or the step's own prediction where there is none).

Writes into ``--out``: ``start_params.yaml`` (the preset as it was), ``correction.json``
(every response with its source, the mean, its errors, the multipliers) and
``corrected_params.yaml`` (the preset times the multipliers, 6 significant digits), and prints
a small table.

    python benchmarks/preset_correction.py --preset thesis-ch4-calibrated-25x50 \\
        --log benchmarks/ucs_results/calibration_25x50/mean_search/calibration_log.jsonl \\
        --held-out benchmarks/ucs_results/calibration_25x50/mean_search/held_out.json \\
        --out benchmarks/ucs_results/calibration_25x50/pooled_correction
"""
from __future__ import annotations

import argparse
import json
import os

import numpy as np

from gbmgen.params import load_params
from sim.calibrate import DEFAULT_KNOBS, DEFAULT_TARGETS, correction_step, scale_parameters
from sim.protocols.outputs import write_json_atomic
from sim.protocols.parameters import save_parameters


def log_rows(path):
    """Responses of the accepted seed round of a calibration log.

    :func:`sim.calibrate.calibrate` keeps the seed round whose mean has the smallest largest
    relative error (a correction round that made the mean worse is not kept); the same rule
    picks the round here.
    """
    with open(path, encoding="utf-8") as f:
        recs = [json.loads(line) for line in f if line.strip()]
    seeds = [r for r in recs if r["phase"] == "seed"]
    if not seeds:
        raise SystemExit(f"{path}: no 'seed' records (expected a calibration log with seeds)")
    rounds = sorted({r["iteration"] for r in seeds})

    def worst(it):
        rows = [r for r in seeds if r["iteration"] == it]
        return max(abs(np.mean([r["responses"][k] for r in rows]) / DEFAULT_TARGETS[k] - 1.0)
                   for k in DEFAULT_TARGETS)
    best = min(rounds, key=worst)
    return [{"source": f"{path} (seed round {best}, specimen {r['seed']})",
             **{k: r["responses"][k] for k in DEFAULT_TARGETS}}
            for r in seeds if r["iteration"] == best]


def held_out_rows(path):
    """Responses of a ``preset_held_out.py`` result file (SI units)."""
    with open(path, encoding="utf-8") as f:
        data = json.load(f)
    rows = []
    for r in data["held_out"]:
        if r["ucs_mpa"] is None or r["tensile_mpa"] is None:
            raise SystemExit(f"{path}: seed {r['seed']} lacks a UCS or tension result (a "
                             "--tests file?); expected both on every pooled specimen")
        if r["E_gpa"] is None:
            raise SystemExit(f"{path}: seed {r['seed']} has E flagged invalid (E_gpa null); "
                             "expected valid E on every pooled specimen: leave it out")
        rows.append({"source": f"{path} (seed {r['seed']})", "E": r["E_gpa"] * 1e9,
                     "UCS": r["ucs_mpa"] * 1e6, "sigma_t": r["tensile_mpa"] * 1e6})
    return rows


def mapped_rows(spec):
    """Held-out rows measured at an earlier set, mapped to the preset by response ratios.

    ``spec`` is ``FILE:E=r1,UCS=r2,sigma_t=r3``: each response of ``FILE`` (a
    ``preset_held_out.py`` result) is multiplied by its ratio, the preset's response over the
    earlier set's response on the same specimens (measured by a paired run, or the step's
    prediction where no paired run exists). The source names the file and the ratios.
    """
    path, sep, ratios = spec.rpartition(":")
    try:
        r = {k: float(v) for k, v in (item.split("=") for item in ratios.split(","))}
    except ValueError:
        r = {}
    if not sep or set(r) != set(DEFAULT_TARGETS):
        raise SystemExit(f"--mapped {spec!r}: expected FILE:E=r1,UCS=r2,sigma_t=r3")
    note = ", ".join(f"{k} x {v:.6g}" for k, v in r.items())
    return [{**row, **{k: row[k] * r[k] for k in DEFAULT_TARGETS},
             "source": f"{row['source']}, mapped by {note}"} for row in held_out_rows(path)]


def _six_digits(params):
    """Every number of the mineral and joint tables to 6 significant digits."""
    def r(t):
        return {k: float(f"{v:.6g}") if isinstance(v, float) else v for k, v in t.items()}
    return {**params, "minerals": {m: r(t) for m, t in params["minerals"].items()},
            "joint": r(params["joint"])}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", required=True, help="preset name the responses were measured at")
    ap.add_argument("--log", action="append", default=[], help="calibration_log.jsonl (repeat)")
    ap.add_argument("--held-out", action="append", default=[], help="held_out.json (repeat)")
    ap.add_argument("--mapped", action="append", default=[],
                    help="FILE:E=r1,UCS=r2,sigma_t=r3: held_out.json measured at an earlier "
                         "set, each response times its ratio to the preset (repeat)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    rows = [r for p in a.log for r in log_rows(p)] + [r for p in a.held_out
                                                      for r in held_out_rows(p)]
    rows += [r for spec in a.mapped for r in mapped_rows(spec)]
    if not rows:
        raise SystemExit("no responses: give --log, --held-out and/or --mapped")
    p = load_params(a.preset)
    start = {"minerals": p.minerals, "joint": p.joint}
    mult = correction_step(rows)
    names = list(DEFAULT_TARGETS)
    vals = np.array([[r[k] for k in names] for r in rows])
    mean = vals.mean(axis=0)
    os.makedirs(a.out, exist_ok=True)
    save_parameters(os.path.join(a.out, "start_params.yaml"), start,
                    header=f"The preset {a.preset} as it was before the correction step.")
    corrected = _six_digits(scale_parameters(start, DEFAULT_KNOBS,
                                             [mult[k.name] for k in DEFAULT_KNOBS]))
    save_parameters(os.path.join(a.out, "corrected_params.yaml"), corrected,
                    header=f"{a.preset} times the correction multipliers "
                           + ", ".join(f"{k} {v:.6g}" for k, v in mult.items()))
    report = {"preset": a.preset, "targets": DEFAULT_TARGETS, "responses": rows,
              "n": len(rows), "mean": dict(zip(names, mean.tolist())),
              "sd": dict(zip(names, vals.std(axis=0, ddof=1).tolist() if len(rows) > 1
                             else [0.0] * len(names))),
              "rel_error_of_mean": {k: float(m / DEFAULT_TARGETS[k] - 1.0)
                                    for k, m in zip(names, mean)},
              "jacobian": "scaling laws (sim.calibrate.initial_jacobian)",
              "multipliers": mult}
    write_json_atomic(os.path.join(a.out, "correction.json"), report)
    print(f"| {a.preset}, {len(rows)} specimens | mean | sd | error of mean |")
    print("|---|---|---|---|")
    for k, m, s in zip(names, mean, report["sd"].values()):
        print(f"| {k} | {m:.4g} | {s:.3g} | {100 * (m / DEFAULT_TARGETS[k] - 1):+.1f} % |")
    print("multipliers: " + ", ".join(f"{k} x {v:.6g}" for k, v in mult.items()))


if __name__ == "__main__":
    main()
