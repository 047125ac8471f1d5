"""One run of a sweep, as a worker does it: build, defect, test, damage; a row of numbers and the
run's files back.

:func:`execute_run` takes plain data (:meth:`gbmgen.sweep_spec.Run.payload`) and returns plain
data, so that a process pool or a Dask worker on another machine (which needs only the
package installed, no shared folder) can run it. It works in a private temporary folder and
sends every file it wrote back as bytes; the caller writes them into the sweep's ``runs/``.
Numba runs on one thread: the engine's results do not depend on the thread count
(docs/sim.md), so this only keeps concurrent runs from competing for cores.
"""
from __future__ import annotations

import os
import pathlib
import platform
import tempfile
import time
import warnings

import numpy as np

__all__ = ["execute_run", "flatten_summary", "build_columns", "TIMING_COLUMNS"]

#: Columns that hold times or places (they differ between two runs of the same configuration).
TIMING_COLUMNS = ("wall_s", "build_s", "test_s", "test_wall_s", "particle_steps_per_s",
                  "worker")
#: Summary entries not copied into the row (the configuration and the specimen's meta are in
#: config.json and specimen.npz; texts that every row repeats are in summary.json).
_SKIP = ("specimen", "options", "test", "ci_criterion", "cd_criterion", "representative_rules")
#: Summary entries renamed in the row (the row's own wall_s is the whole run's).
_RENAME = {"wall_s": "test_wall_s", "status": "test_status"}
#: Sub-folder of the worker's folder for the input files (not sent back).
_INPUTS = "_inputs"


def flatten_summary(summary: dict, prefix: str = "") -> dict:
    """Scalar entries of a nested summary as flat columns (``cracks_pb_tension``,
    ``hole_damage_holes_0_damaged_area_mm2``); lists of numbers become JSON text.

    Examples
    --------
    >>> flatten_summary({"a": 1, "b": {"c": 2.5, "d": [1, 2]}, "e": [{"f": 3}]})
    {'a': 1, 'b_c': 2.5, 'b_d': '[1, 2]', 'e_0_f': 3}
    """
    import json
    out = {}
    for key, value in summary.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten_summary(value, name + "_"))
        elif isinstance(value, (list, tuple)):
            if value and all(isinstance(v, dict) for v in value):
                for i, v in enumerate(value):
                    out.update(flatten_summary(v, f"{name}_{i}_"))
            else:
                out[name] = json.dumps(value)
        elif isinstance(value, np.generic):
            out[name] = value.item()
        elif value is None or isinstance(value, (bool, int, float, str)):
            out[name] = value
    return out


def build_columns(spec) -> dict:
    """The build's realised statistics: counts, MHI and H, KS distance, particles per grain,
    defects."""
    m = spec.meta or {}
    fid = m.get("fidelity") or {}
    ppg = fid.get("particles_per_grain") or {}
    row = {"n_particles": int(spec.n_particles), "n_grains": int(spec.n_grains),
           "n_parallel_bonds": int((spec.bond_kind == 0).sum()),
           "n_smooth_joints": int((spec.bond_kind == 1).sum()),
           "MHI_target": m.get("MHI_target"), "MHI_realised": m.get("MHI_realised"),
           "H_target": m.get("H_target"), "H_realised": m.get("H_realised"),
           "ks_max": fid.get("ks_max"),
           "area_fraction_error_max": fid.get("area_fraction_error_max"),
           "particles_per_grain_min": ppg.get("min"),
           "particles_per_grain_median": ppg.get("median")}
    defects = m.get("defects") or []
    if defects:
        row["defect_particles_removed"] = int(sum(d.get("particles_removed", 0)
                                                  for d in defects))
        cut = [len(g) for d in defects for g in d.get("grains_cut", [])]
        row["defect_grains_cut"] = ";".join(str(c) for c in cut)
    return row


def _input_path(files, role, folder):
    (folder / _INPUTS).mkdir(exist_ok=True)
    path = folder / _INPUTS / f"{role}{files.get(role + '_suffix') or '.txt'}"
    path.write_text(files[role], encoding="utf-8")
    return str(path)


def _build(config, files, folder):
    from .build import build_specimen
    from .table import EXAMPLE_TABLES, example_table, read_table
    opts = dict(config["build"])
    table = opts.pop("table")
    if table in EXAMPLE_TABLES:
        table = example_table(table)
    elif table is not None:
        table = read_table(_input_path(files, "table", folder))
    if str(opts["params"]).startswith("file:"):
        opts["params"] = _input_path(files, "params", folder)
    if opts.get("ranges_mm"):
        opts["ranges_mm"] = {k: tuple(v) for k, v in opts["ranges_mm"].items()}
    spec, _ = build_specimen(table, **opts)
    return spec


def cut_defects(spec, defect: dict):
    """The specimen with the sweep's defect options applied (:data:`DEFECT_KEYS`)."""
    from . import defects
    box = spec.box
    at = (np.asarray(defect["hole_at_mm"], float) * 1e-3 if defect.get("hole_at_mm") else
          np.array([0.5 * (box[0] + box[1]), 0.5 * (box[2] + box[3])]))
    r = 0.5 * float(defect["hole_diameter_mm"]) * 1e-3
    kind = defect["hole"]
    if kind == "double":
        spec = defects.cut_holes(spec, defects.double_hole_centres(
            at, r, float(defect["bridge_mm"]) * 1e-3, float(defect["bridge_angle_deg"])), r,
            kind="double")
    elif kind != "none":
        c = at if defect.get("hole_at_mm") else defects.place_hole(spec, kind, r)
        spec = defects.cut_holes(spec, [c], r, kind=kind)
    if float(defect.get("flaw_length_mm") or 0) > 0:
        spec = defects.cut_flaw(spec, at, float(defect["flaw_length_mm"]) * 1e-3,
                                float(defect["flaw_width_mm"]) * 1e-3,
                                float(defect["flaw_angle_deg"]))
    return spec


def _one_line(exc) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


def execute_run(payload: dict) -> dict:
    """Build, cut and test one run of a sweep; return its row and files.

    Parameters
    ----------
    payload : dict
        ``run_id``, ``config`` (build, defect, test, test_options), ``files`` (texts of the
        table and parameter files).

    Returns
    -------
    outcome : dict
        ``row`` (``run_id``, ``status`` ok or failed, ``error``, the build's statistics, the
        test's summary numbers, ``wall_s``, ``build_s``, ``test_s``, ``worker``) and ``files``
        (path relative to the run folder -> bytes: ``specimen.npz``, ``<test>/summary.json``,
        ``history.csv``, ``cracks.csv``, figures). A failure of the run itself (bad geometry,
        numerical failure) is recorded in the row, not raised.
    """
    import numba

    from sim.protocols.registry import run_test
    from sim.protocols.skeleton import RepresentativenessWarning
    numba.set_num_threads(1)
    config, files = payload["config"], payload.get("files") or {}
    row = {"run_id": payload["run_id"], "status": "ok", "error": ""}
    t_start = time.perf_counter()
    stage = "build"
    with tempfile.TemporaryDirectory(prefix="rockkit-run-") as tmp:
        folder = pathlib.Path(tmp)
        try:
            t0 = time.perf_counter()
            spec = _build(config, files, folder)
            stage = "defect"
            spec = cut_defects(spec, config["defect"])
            spec.save(folder / "specimen.npz")
            row.update(build_columns(spec))
            row["build_s"] = time.perf_counter() - t0
            stage = "test"
            t0 = time.perf_counter()
            with warnings.catch_warnings():          # recorded in summary.json instead
                warnings.simplefilter("ignore", RepresentativenessWarning)
                result = run_test(config["test"], spec, out=str(folder / config["test"]),
                                  progress=False, **config["test_options"])
            row["test_s"] = time.perf_counter() - t0
            row.update({_RENAME.get(k, k): v for k, v in flatten_summary(result.summary).items()
                        if k not in _SKIP and not k.startswith(("specimen_", "options_"))})
        except Exception as exc:                      # recorded; the sweep goes on
            row.update(status="failed", error=f"{stage}: {_one_line(exc)}")
        row["wall_s"] = time.perf_counter() - t_start
        row["worker"] = f"{platform.node()}:{os.getpid()}"
        out_files = {}
        for path in sorted(folder.rglob("*")):
            rel = path.relative_to(folder).as_posix()
            if path.is_file() and not rel.startswith(_INPUTS + "/"):
                out_files[rel] = path.read_bytes()
    return {"row": row, "files": out_files}
