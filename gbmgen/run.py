"""``gbmgen run IMAGES_DIR``: SEM images -> semkit -> grains.csv -> specimen -> laboratory test.

The end-to-end job of DESIGN.md §1 in one call. Writes to ``out``:

* ``semkit/`` — semkit's outputs: ``images.csv``, ``cracks.csv`` (and ``damage.csv`` where
  semkit writes it) from the crack pipeline (skipped with ``cracks=False``), ``grains.csv``
  (the measured grain-size table), ``grains_per_grain.csv``, grain maps and histograms;
* ``specimen.npz`` — built from the measured table at model scale (thesis: 10 x SEM scale);
* ``specimen.png`` — preview;
* ``<test>/`` — the laboratory test run on the specimen by :mod:`sim.protocols` (default ``ucs``:
  ``summary.json``, ``history.csv``, ``cracks.csv``, figures), skipped with ``test="none"``;
* ``run.json`` — a summary (semkit tables used, specimen counts, MHI target/realised, the test's
  E / strength / crack counts, the SEM damage ratio P beside the simulated P_sim, seconds per
  stage);
* ``report.html`` (self-contained) and ``report.md`` with ``report_files/`` — the run in one
  page (:mod:`gbmgen.run_report`).
"""
from __future__ import annotations

import json
import os
import pathlib
import time

from .errors import InputError

__all__ = ["run"]

#: Thesis minerals, brightest first in BSE images.
DEFAULT_MINERALS = "pyroxene,plagioclase,biotite"

#: Summary keys of the test copied into run.json.
_TEST_KEYS = ("E_gpa", "nu", "E_ok", "E_reason", "nu_ok", "nu_reason", "elastic", "ucs_mpa",
              "ci_mpa", "cd_mpa", "tensile_mpa", "cracks", "P_sim", "steps", "wall_s",
              "particle_steps_per_s", "stop_reason", "representative")


def test_names() -> tuple:
    """Laboratory tests ``run`` can finish with: those of
    :data:`sim.protocols.registry.TESTS`, and ``none`` (stop at the specimen)."""
    from sim.protocols.registry import test_names as names
    return (*names(), "none")


def resolve_seed(seed):
    """``(seed, source)``: None -> :data:`gbmgen.config.DEFAULT_SEED` ("default"), an integer
    as given ("given"), ``"random"`` -> a fresh draw ("random").

    Raises
    ------
    InputError
        Neither an integer >= 0 nor "random".

    Examples
    --------
    >>> resolve_seed(None)
    (1, 'default')
    >>> resolve_seed("7")
    (7, 'given')
    """
    from . import config
    if seed is None:
        return config.DEFAULT_SEED, "default"
    if isinstance(seed, str) and seed.strip().lower() == "random":
        import numpy as np
        return int(np.random.SeedSequence().entropy % 2**32), "random"
    try:
        value = int(seed)
    except (TypeError, ValueError):
        value = -1
    if value < 0 or (isinstance(seed, float) and seed != value):
        raise InputError(f"seed = {seed!r}: expected a whole number >= 0 or 'random'")
    return value, "given"


def run_test(spec, test, out, *, progress=True, **options):
    """Run the laboratory ``test`` of :mod:`sim.protocols` on ``spec``; write into ``out``.

    Parameters
    ----------
    spec : sim.Specimen
    test : str
        A name of :data:`sim.protocols.registry.TESTS`.
    out : path
        Results folder of the test.
    progress : bool
    **options
        Options of :func:`sim.protocols.registry.run_test` (e.g. ``post_peak``).

    Returns
    -------
    summary : dict
        The protocol's ``summary.json`` content.
    """
    from sim.protocols.registry import run_test as run_protocol
    if test not in test_names()[:-1]:
        raise InputError(f"test = {test!r}: expected one of {', '.join(test_names())}")
    return run_protocol(test, spec, out=str(out), progress=progress, **options).summary


def sem_damage(sem_dir, manifest=None):
    """SEM damage ratio P = A_T/A_S (Equ. 3-1) from semkit's ``damage.csv``, per stage and pooled.

    Parameters
    ----------
    sem_dir : path
        semkit's output folder.
    manifest : path, optional
        The images' ``manifest.csv`` (their stages, for the pooled band).

    Returns
    -------
    damage : dict
        ``{"by_stage": [{specimen, test, stage, P_mean, P_mean_low, P_mean_high, P_pooled,
        P_status}, ...], "P_pooled": float, "P_pooled_low": float, "P_pooled_high": float,
        "P_status": str, "P_note": str}``; empty when semkit wrote no ``damage.csv``.

        * ``P_pooled`` pools A_T and A_S over every loaded (not pre-test) stage;
          ``P_pooled_low, P_pooled_high`` is its 10-90 % typing band (one common lean for all
          the images; None without the ``manifest`` or semkit's ``images.csv`` and
          ``cracks.csv``).
        * ``P_status`` is ``low_confidence`` when any loaded stage is (semkit's
          ``damage.csv`` ``P_status``, which names the images).
        * ``P_mean_low, P_mean_high`` are the typing's 10-90 % band of the stage's ``P_mean``
          (absent from a ``damage.csv`` written without it).
    """
    import pandas as pd

    path = pathlib.Path(sem_dir) / "damage.csv"
    if not path.exists():
        return {}
    d = pd.read_csv(path)
    if "P_status" not in d.columns:  # written by a semkit without stage statuses
        d["P_status"] = "unchecked"
    loaded = d[d["stage"].astype(str) != "pre-test"]
    a_t, a_s = float(loaded["area_T_um2"].sum()), float(loaded["area_S_um2"].sum())
    keys = ("specimen", "test", "stage", "P_mean", "P_mean_low", "P_mean_high", "P_pooled",
            "P_status")
    rows = [{k: (None if pd.isna(r[k]) else r[k]) for k in keys if k in d.columns}
            for _, r in d.iterrows()]
    band = _pooled_band(pathlib.Path(sem_dir), loaded, manifest)
    statuses = loaded["P_status"].astype(str)
    low = loaded[statuses == "low_confidence"]
    status, note = "ok", ""
    if len(low):
        status = "low_confidence"
        where = dict.fromkeys(f"{r.specimen} {r.test} {r.stage}" for r in low.itertuples())
        note = (f"low_confidence P at {', '.join(where)} "
                "(damage.csv P_note names the images)")
    elif (statuses == "unchecked").any():
        status = "unchecked"
    return {"by_stage": rows, "P_pooled": a_t / a_s if a_s > 0 else None,
            "P_pooled_low": band[0], "P_pooled_high": band[1], "P_status": status,
            "P_note": note}


def _pooled_band(sem_dir, loaded, manifest):
    """The typing's 10-90 % band of the pooled SEM P: semkit's ``cracks.csv`` over the images
    of the loaded stages that ``P_pooled`` sums (``manifest.csv`` gives their stages; images
    semkit flagged ``P_outlier`` left out); (None, None) without them."""
    import numpy as np
    import pandas as pd

    from semkit.damage import p_band
    ipath, cpath = sem_dir / "images.csv", sem_dir / "cracks.csv"
    if manifest is None or not (pathlib.Path(manifest).is_file() and ipath.exists()
                                and cpath.exists()):
        return None, None
    keys = ["specimen", "test", "stage"]
    man = pd.read_csv(manifest)
    imgs = pd.read_csv(ipath)
    if not {"image", *keys} <= set(man.columns) or "image" not in imgs.columns:
        return None, None
    imgs = imgs.merge(man[["image", *keys]].astype(str), on="image", how="inner")
    stages = set(loaded[keys].astype(str).apply(tuple, axis=1))
    mine = imgs[keys].apply(tuple, axis=1).isin(stages)
    if "P_outlier" in imgs.columns:
        mine &= ~imgs["P_outlier"].fillna(False).astype(bool)
    lo, hi = p_band(pd.read_csv(cpath), imgs.loc[mine, "image"].astype(str),
                    statistic="pooled")
    return (float(lo) if np.isfinite(lo) else None), (float(hi) if np.isfinite(hi) else None)


def run(images_dir="sample_images", out="gbmgen_run", *, minerals=DEFAULT_MINERALS,
        classes=None, pixel_size_um=None, cracks=True, jobs=None, progress=True,
        seed=None, test="ucs", test_options=None, report=True, **build_options):
    """Analyse a folder of SEM images with semkit and build a specimen from the measured table.

    Parameters
    ----------
    images_dir : path
        SEM images (``manifest.csv`` beside them is used by semkit when present).
    out : path
        Output folder (created).
    minerals : str
        Mineral names brightest-first (semkit ``--minerals``); they must have properties in the
        parameter set (``params``, default thesis-ch4).
    classes : str, optional
        Class edges in um (semkit ``--classes``, e.g. ``"20,140"``); default semkit's rule.
    pixel_size_um : float, optional
        Fallback pixel size for semkit.
    cracks : bool
        Also run semkit's crack pipeline (images.csv, cracks.csv, damage.csv).
    jobs : int, optional
        semkit worker processes.
    progress : bool
        tqdm bars in semkit.
    seed : int or "random", optional
        Seed of semkit's grain analysis and of the specimen; default
        :data:`gbmgen.config.DEFAULT_SEED` (two runs give identical numbers); ``"random"``
        draws one. Written to run.json with its source.
    test : {"ucs", "tension", "brazilian", "biaxial", "none"}
        Laboratory test run on the built specimen (:func:`run_test`); ``"none"`` stops at the
        specimen.
    test_options : dict, optional
        Keywords of the test's protocol function (e.g. ``{"post_peak": 0.8}``).
    report : bool
        Also write ``report.html`` and ``report.md`` (:mod:`gbmgen.run_report`).
    **build_options
        Keywords of :func:`gbmgen.build.build_specimen` (scenario, width_mm, height_mm,
        model_scale, tessellation, particle_radius_mm, porosity, params, ...).

    Returns
    -------
    summary : dict
        What ``run.json`` holds.

    Raises
    ------
    InputError
        The folder is missing or empty, a bad seed or test, or semkit wrote no usable
        grain-size table (semkit's and sim's own input errors pass through; the command line
        reports all of them as bad input).
    sim.errors.InstabilityError
        The test's engine became unstable before the peak.
    """
    from .build import build_specimen
    from .plot import plot_specimen
    from .table import read_table

    images_dir = pathlib.Path(images_dir)
    out = pathlib.Path(out)
    if not images_dir.is_dir():
        raise InputError(f"{images_dir}: not a folder of SEM images")
    if test not in test_names():
        raise InputError(f"test = {test!r}: expected one of {', '.join(test_names())}")
    seed, seed_source = resolve_seed(seed)
    sem = out / "semkit"
    sem.mkdir(parents=True, exist_ok=True)
    timing = {}
    t0 = time.perf_counter()
    from semkit.workflow import analyse_folder  # one semkit pass per image: cracks and grains
    images, _ = analyse_folder(images_dir, sem, jobs=jobs, progress=progress,
                               pixel_size_um=pixel_size_um, classes=classes, seed=seed,
                               grains=True, minerals=minerals, crack_tables=cracks)
    timing["semkit"] = time.perf_counter() - t0
    table_path = sem / "grains.csv"
    if not table_path.exists():
        failed = images[images["error"].notna()] if "error" in images else images.iloc[:0]
        why = "; ".join(f"{r.image}: {r.error}" for r in failed.head(3).itertuples())
        raise InputError(f"{why}; semkit wrote no grain-size table" if why
                         else f"{table_path}: semkit wrote no grain-size table")
    table = read_table(table_path)
    t0 = time.perf_counter()
    build_options.setdefault("width_mm", 25.0)
    build_options.setdefault("height_mm", 50.0)
    spec, stages = build_specimen(table, seed=seed, **build_options)
    spec_path = out / "specimen.npz"
    spec.save(spec_path)
    plot_specimen(spec, out / "specimen.png")
    timing["build"] = time.perf_counter() - t0
    timing.update({f"build_{k}": v for k, v in stages.items()})
    test_summary = None
    if test != "none":
        t0 = time.perf_counter()
        full = run_test(spec, test, out / test, progress=progress, **(test_options or {}))
        test_summary = {k: full[k] for k in _TEST_KEYS if k in full}
        timing[f"test_{test}"] = time.perf_counter() - t0
    summary = {
        "images": str(images_dir), "out": str(out), "grains_csv": str(table_path),
        "specimen": str(spec_path), "minerals": list(table.minerals),
        "measured_range_um": {n: [float(v) for v in table.range_um()[k]]
                              for k, n in enumerate(table.minerals)},
        "volume_fractions": {n: float(table.volume_fractions[k])
                             for k, n in enumerate(table.minerals)},
        "particles": spec.n_particles, "grains": spec.n_grains,
        "parallel_bonds": int((spec.bond_kind == 0).sum()),
        "smooth_joints": int((spec.bond_kind == 1).sum()),
        "seed": spec.meta["seed"], "seed_source": seed_source,
        "scenario": spec.meta["scenario"],
        "MHI_target": spec.meta["MHI_target"], "MHI_realised": spec.meta["MHI_realised"],
        "test": test, "test_summary": test_summary,
        "P_sem": sem_damage(sem, images_dir / "manifest.csv") if cracks else {},
        "semkit_files": sorted(os.listdir(sem)),
        "timing_s": {k: round(v, 3) for k, v in timing.items()},
    }
    tmp = out / "run.json.tmp"
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(summary, fh, indent=1, default=_json_default)
    os.replace(tmp, out / "run.json")
    if report:                                 # report.html (self-contained) and report.md
        from .run_report import write_run_report
        write_run_report(out)
    return summary


def _json_default(o):
    import numpy as np
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")
