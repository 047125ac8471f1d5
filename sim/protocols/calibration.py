"""The DEM black box of :func:`sim.calibrate.calibrate`: UCS + tension runs on specimens.

``calibrate_specimens`` loads the specimens, builds ``evaluate(params) -> {E, UCS, sigma_t}``
(a UCS test for E and UCS, a direct-tension or Brazilian test for σt, on the first specimen) and
``evaluate_seeds`` (the same on every specimen), runs the calibration, and writes

- ``calibrated_params.yaml`` — the parameter file (load with ``--params``);
- ``calibration_report.json`` — every evaluation, multipliers, Jacobian, seed summary;
- ``calibration_report.md`` — the same as tables (iterations, evaluations, wall time, final
  errors, seed spread);
- ``calibration_log.jsonl`` — one line per evaluation as it happens (survives Ctrl-C).
"""
from __future__ import annotations

import hashlib
import json
import os
import time

from ..calibrate import DEFAULT_TARGETS, calibrate
from ..errors import InputError, InstabilityError
from .outputs import json_ready, write_json_atomic, write_text_atomic
from .parameters import apply_parameters, load_parameters, save_parameters, start_parameters
from .speed import DEFAULT_TIMESTEP_FACTOR

__all__ = ["make_evaluator", "calibrate_specimens", "report_markdown"]


def _finished(out):
    """The summary of a finished test in ``out`` (None when there is none)."""
    path = os.path.join(out, "summary.json")
    try:
        with open(path, encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, ValueError):
        return None
    return summary if summary.get("status") == "complete" else None


def make_evaluator(specimen, *, platen_velocity=None, tension_test="direct", progress=False,
                   runs_dir=None):
    """``evaluate(params) -> {"E", "UCS", "sigma_t"}`` (Pa) on one specimen.

    E is the UCS test's modulus (:func:`sim.protocols.elastic.elastic_constants`; its measured
    value when flagged, with ``E_ok`` in the response), UCS its peak, σt the peak of a
    direct-tension test (or a Brazilian test on the disc cut from the specimen).

    With ``runs_dir`` every test writes its results into ``runs_dir/<parameter hash>/<test>``
    (no figures), and a finished test found there is read instead of run again (the runs are
    deterministic): an interrupted calibration resumes from its finished runs.
    """
    from .brazilian import run_brazilian
    from .tension import run_tension
    from .ucs import run_ucs
    if tension_test not in ("direct", "brazilian"):
        raise ValueError(f"'tension_test' = {tension_test!r}, expected 'direct' or 'brazilian'")
    kw = {} if platen_velocity is None else {"platen_velocity": platen_velocity}

    def robust(fn, spec, out):
        # an InstabilityError after the peak must not end a long calibration: rerun once at
        # 0.6 x the time-step factor (the rerun is recorded in the summary options)
        if out is not None:
            done = _finished(out)
            if done is not None:
                return done
            kw_out = {"out": out, "figures": False}
        else:
            kw_out = {}
        try:
            return fn(spec, progress=progress, **kw, **kw_out).summary
        except InstabilityError:
            f = 0.6 * (kw.get("timestep_factor") or DEFAULT_TIMESTEP_FACTOR)
            return fn(spec, progress=progress, **{**kw, "timestep_factor": f}, **kw_out).summary

    def evaluate(params):
        spec = apply_parameters(specimen, params)
        base = None
        if runs_dir is not None:
            key = json.dumps(json_ready(params), sort_keys=True)
            base = os.path.join(runs_dir, hashlib.sha1(key.encode()).hexdigest()[:12])
        u = robust(run_ucs, spec, None if base is None else os.path.join(base, "ucs"))
        t = robust(run_tension if tension_test == "direct" else run_brazilian, spec,
                   None if base is None else os.path.join(base, "tension"))
        e = u["E_gpa"] if u.get("E_gpa") is not None else u["elastic"]["E_measured_gpa"]
        return {"E": e * 1e9, "UCS": u["ucs_mpa"] * 1e6,
                "sigma_t": t["tensile_mpa"] * 1e6, "nu": u["nu"], "E_ok": u.get("E_ok"),
                "wall_s": u["wall_s"] + t["wall_s"]}

    return evaluate


def report_markdown(result, targets, *, specimens=(), extra="") -> str:
    """The calibration report as markdown tables."""
    names = list(targets)
    unit = {"E": ("GPa", 1e9), "UCS": ("MPa", 1e6), "sigma_t": ("MPa", 1e6)}
    lines = ["# Calibration report", "",
             f"- converged (every target within acceptance): **{result.converged}**",
             f"- iterations (search evaluations): {result.n_iterations}; evaluations in all: "
             f"{result.n_evaluations}; wall time: {result.wall_s:.1f} s",
             "- multipliers on the starting set: " + ", ".join(
                 f"{k} × {v:.4g}" for k, v in result.multipliers.items()),
             "- specimens: " + ", ".join(str(s) for s in specimens), ""]
    if extra:
        lines += [extra, ""]
    head = "| phase | it | seed | " + " | ".join(
        f"{k} ({unit.get(k, ('', 1))[0]}) | err {k}" for k in names) + " | s |"
    lines += ["## Evaluations", "", head, "|" + "---|" * (4 + 2 * len(names))]
    for e in result.evaluations:
        cells = []
        for k in names:
            u, f = unit.get(k, ("", 1.0))
            cells += [f"{e['responses'][k] / f:.4g}", f"{100 * e['errors'][k]:+.2f} %"]
        seed = "" if e["seed"] is None else str(e["seed"])
        lines.append(f"| {e['phase']} | {e['iteration']} | {seed} | " + " | ".join(cells)
                     + (" | reused |" if e["phase"] == "seed" and e["seconds"] == 0.0
                        else f" | {e['seconds']:.1f} |"))
    if any(e["phase"] == "seed" and e["seconds"] == 0.0 for e in result.evaluations):
        lines += ["", "reused: the point was already run on that specimen (a search on the "
                  "seed mean); the runs are deterministic, so the result is reused."]
    lines += ["", "## Final", "", "| target | value | final error | seed mean | seed std | "
              "seed min | seed max |", "|---|---|---|---|---|---|---|"]
    for k in names:
        u, f = unit.get(k, ("", 1.0))
        s = result.seed_summary.get(k)
        row = f"| {k} | {targets[k] / f:.4g} {u} | {100 * result.final_errors[k]:+.2f} % |"
        row += (f" {s['mean'] / f:.4g} | {s['std'] / f:.3g} | {s['min'] / f:.4g} | "
                f"{s['max'] / f:.4g} |" if s else " | | | |")
        lines.append(row)
    return "\n".join(lines) + "\n"


def calibrate_specimens(paths, *, out, params=None, targets=None, tol=0.03, accept=0.05,
                        max_evaluations=10, platen_velocity=None, tension_test="direct",
                        progress=True, knobs=None, search_on="first", extra=(),
                        resume=False):
    """Calibrate on specimen files and write the parameter file and the report into ``out``.

    Parameters
    ----------
    paths : sequence of path
        ``specimen.npz`` files; the first for the search, all for the seed average.
    out : path
    params : path or dict, optional
        Starting parameters (default: thesis Ch. 4 with a bond-like joint stiffness,
        :func:`sim.protocols.parameters.start_parameters`).
    targets : dict, optional
        ``{"E", "UCS", "sigma_t"}`` in Pa (default thesis lab 65 GPa, 135 MPa, 18 MPa).
    tol, accept, max_evaluations, knobs :
        See :func:`sim.calibrate.calibrate`.
    platen_velocity : float, optional
        Loading speed of the tests, m/s (default: the protocols' default).
    tension_test : {"direct", "brazilian"}
    search_on : {"first", "mean"}
        ``first``: search on the first specimen, seeds at the end (the issue's sketch).
        ``mean``: every search evaluation is the mean over all specimens (costs one run per
        specimen, but targets the seed mean directly; use it when the seed spread is large).
    extra : sequence of path
        More ``specimen.npz`` files used only in the seed rounds at the end: a held-out check
        of the searched set, whose mean over all specimens then drives the correction step.
    resume : bool
        Continue an interrupted calibration in ``out``: every test writes its results into
        ``out/runs/specimen_K/<parameter hash>/`` and a finished one is read back instead of
        run again (same specimens and options, so the search retraces its steps).

    Returns
    -------
    result : sim.calibrate.CalibrationResult
    """
    from ..specimen import Specimen
    if not paths:
        raise InputError("calibrate: expected at least one specimen file")
    n_search = len(paths)
    paths = list(paths) + list(extra)
    specs = [Specimen.load(p) for p in paths]
    start = (start_parameters(specs[0]) if params is None else
             load_parameters(params) if isinstance(params, (str, os.PathLike)) else params)
    for p, s in zip(paths, specs):   # fail early on a name mismatch
        apply_parameters(s, start)
    targets = dict(DEFAULT_TARGETS if targets is None else targets)
    os.makedirs(out, exist_ok=True)
    log_path = os.path.join(out, "calibration_log.jsonl")
    if not resume:
        open(log_path, "w").close()

    def log(rec):
        with open(log_path, "a", encoding="utf-8") as f:
            f.write(json.dumps(json_ready(rec)) + "\n")
        if progress and rec["phase"] == "seed-failed":
            print(f"[calibrate] seed {rec['seed']} failed: {rec['error'][:200]}", flush=True)
        elif progress:
            errs = ", ".join(f"{k} {100 * v:+.1f}%" for k, v in rec["errors"].items())
            print(f"[calibrate] {rec['phase']} {rec['iteration']}"
                  f"{'' if rec['seed'] is None else ' seed ' + str(rec['seed'])}: {errs} "
                  f"({rec['seconds']:.0f} s)", flush=True)

    evals = [make_evaluator(s, platen_velocity=platen_velocity, tension_test=tension_test,
                            runs_dir=os.path.join(out, "runs", f"specimen_{k}"))
             for k, s in enumerate(specs)]
    t0 = time.perf_counter()
    kw = {} if knobs is None else {"knobs": knobs}
    failures = []

    done = {}        # the runs are deterministic: (point, specimen) already run is reused

    def run_seeds(p, ks=range(len(evals))):
        # a seed whose test the engine cannot finish (InstabilityError before the peak, even
        # after the time-step retry) is left out of the mean and listed in the report
        key = json.dumps(json_ready(p), sort_keys=True)
        out = []
        for k in ks:
            if (key, k) in done:
                if done[key, k] is not None:
                    out.append({**done[key, k], "seconds": 0.0})     # reused
                continue
            ts = time.perf_counter()
            try:
                done[key, k] = {**evals[k](p), "specimen_index": k}
                done[key, k]["seconds"] = time.perf_counter() - ts
            except InstabilityError as exc:
                done[key, k] = None
                failures.append({"specimen": str(paths[k]), "error": str(exc)})
                log({"phase": "seed-failed", "iteration": len(failures) - 1, "seed": k,
                     "errors": {}, "seconds": 0.0, "error": str(exc)})
                continue
            out.append(done[key, k])
        if not out:
            raise InstabilityError("every seed specimen failed: " + failures[-1]["error"])
        return out

    seeds = run_seeds if len(evals) > 1 else None
    if search_on not in ("first", "mean"):
        raise ValueError(f"'search_on' = {search_on!r}, expected 'first' or 'mean'")
    search = evals[0]
    if search_on == "mean" and n_search > 1:
        def search(p):
            rs = run_seeds(p, range(n_search))
            return {k: sum(r[k] for r in rs) / len(rs) for k in targets}
    res = calibrate(search, start, targets=targets, tol=tol, accept=accept,
                    max_evaluations=max_evaluations, evaluate_seeds=seeds, progress=log, **kw)
    wall = time.perf_counter() - t0
    header = (f"Calibrated by gbmsim calibrate on {len(specs)} specimen(s); targets "
              + ", ".join(f"{k}={v:.4g} Pa" for k, v in targets.items())
              + f"; converged={res.converged}; multipliers "
              + ", ".join(f"{k}={v:.4g}" for k, v in res.multipliers.items()))
    save_parameters(os.path.join(out, "calibrated_params.yaml"), res.params, header=header)
    rep = res.to_dict()
    rep.update(targets=targets, specimens=[str(p) for p in paths], wall_s=wall,
               failed_seed_runs=failures, search_on=search_on,
               extra_specimens=[str(p) for p in paths[n_search:]],
               tension_test=tension_test, platen_velocity=platen_velocity)
    write_json_atomic(os.path.join(out, "calibration_report.json"), rep)
    write_text_atomic(os.path.join(out, "calibration_report.md"),
                      report_markdown(res, targets, specimens=paths, extra="\n".join(
                          f"- seed run left out (engine instability): {f['specimen']}: "
                          f"{f['error'][:160]}" for f in failures)))
    return res
