"""Thesis studies as preset sweeps (``gbmsim study NAME --out DIR``), their tables, and how
they compare with the thesis's findings.

A study is a sweep document (:mod:`gbmgen.sweep_spec`) made by a preset from ``seeds`` and a
specimen size, plus what to tabulate and draw. Its cases (the runs of one seed):

* ``thesis-ch4-scenarios`` — Table 4-1 grains, Scenarios S1-S4 at x1.0 and S1 at x1.5;
  calibrated Ch. 4 parameters; UCS. Thesis: 7 seeds.
* ``thesis-ch4-grain-size`` — S1 at x1.0, x1.25, x1.5 and S4 at x0.75, x1.0, x1.25 (the
  thesis's Tables 4-6/4-7 scale ranges; the steps are this toolkit's choice).
* ``thesis-ch5-shapes`` — controlled hexagon, rectangle and shield grains of 1.78 mm² at 9
  slenderness ratios each over the thesis's ranges (minerals by Table 4-1 volume fractions,
  Ch. 5-7 parameters); UCS. Thesis: 12 seeds.
* ``thesis-ch6-holes`` — the one-mineral 4 mm-grain pyroxene model (``thesis-ch6-pyroxene``),
  particle radius 0.15 mm, one hole placed intra-grain (3 mm), inter-grain (2 mm), across 3
  and across 4 grains (3 mm); UCS; damaged area (:mod:`sim.hole_damage`).
* ``thesis-ch6-double-holes`` — the same model with two 3 mm holes, bridge 0.5R, R, 2R, 4R
  wall to wall, at 0, 30, 45, 60, 90, 120, 135, 150 degrees.

``size_mm`` changes the specimen. In the Ch. 6 studies the holes, bridges and grains shrink
with it (factor k = min(W / 25, H / 50), geometric similarity at the same particle size), so a
reduced study keeps the thesis's proportions; in Ch. 4 and 5 only the specimen changes (the
grains are what those studies vary).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .errors import InputError

__all__ = ["Study", "STUDIES", "study", "THESIS_CH4", "THESIS_CH5", "THESIS_CH6_BRIDGE_R",
           "THESIS_CH6_ANGLE", "THESIS_SIZE_MM", "case_summary"]

#: The thesis specimen, mm (REFERENCE.md).
THESIS_SIZE_MM = (25.0, 50.0)
#: Table 4-2 per scenario: MHI, UCS range (MPa) and E range (GPa) over 7 seeds.
THESIS_CH4 = {1: {"MHI": 3.01, "ucs_mpa": (133.9, 136.9), "E_gpa": (61.8, 65.5)},
              2: {"MHI": 1.78, "ucs_mpa": (189.1, 193.7), "E_gpa": (71.0, 73.4)},
              3: {"MHI": 1.37, "ucs_mpa": (237.0, 250.3), "E_gpa": (76.1, 78.5)},
              4: {"MHI": 0.85, "ucs_mpa": (295.6, 314.3), "E_gpa": (89.3, 93.4)}}
#: Ch. 5 findings: shape -> (extreme of the UCS, slenderness where it lies).
THESIS_CH5 = {"rectangle": ("strongest", 1.0), "hexagon": ("weakest", 1.0),
              "shield": ("weakest", 1.14)}
#: Ch. 5 slenderness ranges and the 9 ratios a study runs per shape.
CH5_RATIOS = {"hexagon": (0.47, 0.57, 0.69, 0.83, 1.0, 1.21, 1.46, 1.77, 2.13),
              "rectangle": (0.5, 0.67, 0.8, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0),
              "shield": (0.67, 0.75, 0.83, 0.91, 1.0, 1.07, 1.14, 1.25, 1.43)}
#: Ch. 6 mean damaged area (mm²) by bridge length in hole radii.
THESIS_CH6_BRIDGE_R = {0.5: 3.39, 1.0: 3.87, 2.0: 3.37, 4.0: 4.21}
#: Ch. 6 mean damaged area (mm²) at the angles the thesis names: largest and smallest.
THESIS_CH6_ANGLE = {60.0: 4.7, 150.0: 2.9}
CH6_ANGLES_DEG = (0, 30, 45, 60, 90, 120, 135, 150)
#: Ch. 6 hole diameters (mm at thesis size) by placement.
CH6_HOLES_MM = {"intra": 3.0, "inter": 2.0, "trans3": 3.0, "trans4": 3.0}
CH6_RADIUS_MM = 1.5


@dataclass(frozen=True)
class Study:
    """A preset sweep and how to read it.

    Attributes
    ----------
    name, title : str
    make : callable
        ``make(seeds, size_mm) -> sweep document``.
    case_keys : tuple of str
        results.csv columns that name a case (the runs of a case differ by seed only).
    metrics : tuple of str
        Columns averaged over the seeds of a case.
    default_seeds : int
    """

    name: str
    title: str
    make: object
    case_keys: tuple
    metrics: tuple = ("ucs_mpa", "E_gpa", "nu", "MHI_realised")
    default_seeds: int = 3
    notes: tuple = field(default_factory=tuple)


def _k(size_mm):
    return min(size_mm[0] / THESIS_SIZE_MM[0], size_mm[1] / THESIS_SIZE_MM[1])


def _fixed(size_mm, **more):
    return {"width_mm": float(size_mm[0]), "height_mm": float(size_mm[1]), "test": "ucs",
            **more}


def _seeds(n):
    return {"seed": list(range(1, int(n) + 1))}


def _ch4_scenarios(seeds, size_mm):
    cases = [{"scenario": s, "scale": 1.0} for s in (1, 2, 3, 4)] + [{"scenario": 1,
                                                                       "scale": 1.5}]
    return {"name": "thesis-ch4-scenarios",
            "fixed": _fixed(size_mm, table="table-4-1", params="thesis-ch4-calibrated"),
            "cases": cases, "grid": _seeds(seeds)}


def _ch4_grain_size(seeds, size_mm):
    cases = ([{"scenario": 1, "scale": s} for s in (1.0, 1.25, 1.5)]
             + [{"scenario": 4, "scale": s} for s in (0.75, 1.0, 1.25)])
    return {"name": "thesis-ch4-grain-size",
            "fixed": _fixed(size_mm, table="table-4-1", params="thesis-ch4-calibrated"),
            "cases": cases, "grid": _seeds(seeds)}


def _ch5_shapes(seeds, size_mm):
    cases = [{"shape": shape, "slenderness": s} for shape, ratios in CH5_RATIOS.items()
             for s in ratios]
    return {"name": "thesis-ch5-shapes",
            "fixed": _fixed(size_mm, table="table-4-1", params="thesis-ch5",
                            grain_area_mm2=1.78),
            "cases": cases, "grid": _seeds(seeds)}


def _ch6_fixed(size_mm):
    return _fixed(size_mm, table="thesis-ch6-pyroxene", params="thesis-ch5",
                  particle_radius_mm=0.15, scale=round(_k(size_mm), 6))


def _ch6_holes(seeds, size_mm):
    k = _k(size_mm)
    cases = [{"hole": kind, "hole_diameter_mm": round(d * k, 6)}
             for kind, d in CH6_HOLES_MM.items()]
    return {"name": "thesis-ch6-holes", "fixed": _ch6_fixed(size_mm), "cases": cases,
            "grid": _seeds(seeds)}


def _ch6_double(seeds, size_mm):
    k = _k(size_mm)
    r = CH6_RADIUS_MM * k
    cases = [{"bridge_mm": round(b * r, 6), "bridge_angle_deg": a}
             for b in THESIS_CH6_BRIDGE_R for a in CH6_ANGLES_DEG]
    return {"name": "thesis-ch6-double-holes",
            "fixed": {**_ch6_fixed(size_mm), "hole": "double",
                      "hole_diameter_mm": round(2 * r, 6)},
            "cases": cases, "grid": _seeds(seeds)}


_DAMAGE = ("hole_damage_damaged_area_mm2", "hole_damage_crack_joins_holes",
           "hole_damage_max_displacement_mm", "ucs_mpa", "E_gpa")

#: The studies by name.
STUDIES = {s.name: s for s in (
    Study("thesis-ch4-scenarios", "Grain-size scenarios S1-S4 and x1.5 (thesis Ch. 4)",
          _ch4_scenarios, ("scenario", "scale"), default_seeds=7),
    Study("thesis-ch4-grain-size", "Grain-size scale (thesis Ch. 4, Tables 4-6/4-7)",
          _ch4_grain_size, ("scenario", "scale"), default_seeds=7),
    Study("thesis-ch5-shapes", "Grain shape and slenderness (thesis Ch. 5)", _ch5_shapes,
          ("shape", "slenderness"), metrics=("ucs_mpa", "E_gpa", "nu"), default_seeds=12),
    Study("thesis-ch6-holes", "One hole by placement on the grains (thesis Ch. 6)",
          _ch6_holes, ("hole", "hole_diameter_mm"), metrics=_DAMAGE),
    Study("thesis-ch6-double-holes", "Double holes by bridge length and angle (thesis Ch. 6)",
          _ch6_double, ("bridge_mm", "bridge_angle_deg"), metrics=_DAMAGE),
)}


def study(name: str) -> Study:
    """The study ``name``.

    Raises
    ------
    InputError
        Unknown name (names the valid ones).
    """
    try:
        return STUDIES[name]
    except KeyError:
        raise InputError(f"study {name!r}: expected one of {', '.join(STUDIES)}") from None


def _number(x):
    """A table cell as a number: booleans (also as text, from a CSV) become 0/1."""
    if isinstance(x, str) and x in ("True", "False"):
        return float(x == "True")
    return float(x) if isinstance(x, bool) or type(x).__name__ == "bool_" else x


def case_summary(st: Study, frame):
    """Mean, sample standard deviation and count over the seeds of each case.

    Parameters
    ----------
    st : Study
    frame : pandas.DataFrame
        results.csv of the study.

    Returns
    -------
    summary : pandas.DataFrame
        One row per case (in sweep order): the case keys, ``runs``, ``ok`` (finished without
        failure), and ``<metric>_mean``, ``<metric>_sd`` (NaN with one seed), ``<metric>_n``
        over the ok runs with a value (a boolean metric becomes the fraction true).

    Examples
    --------
    >>> import pandas as pd
    >>> f = pd.DataFrame({"scenario": [1, 1, 2], "scale": [1.0] * 3, "status": ["ok"] * 3,
    ...                   "ucs_mpa": [100.0, 110.0, 150.0], "E_gpa": [60.0, 62.0, 70.0]})
    >>> s = case_summary(STUDIES["thesis-ch4-scenarios"], f)
    >>> s[["scenario", "runs", "ucs_mpa_mean", "ucs_mpa_n"]].to_dict("records")[0]
    {'scenario': 1, 'runs': 2, 'ucs_mpa_mean': 105.0, 'ucs_mpa_n': 2}
    """
    import pandas as pd
    rows = []
    if frame is None or len(frame) == 0:
        return pd.DataFrame(columns=list(st.case_keys) + ["runs", "ok"])
    keys = [k for k in st.case_keys if k in frame]
    for case, g in frame.groupby(keys, sort=False, dropna=False):
        case = case if isinstance(case, tuple) else (case,)
        ok = g[g["status"] == "ok"] if "status" in g else g
        row = dict(zip(keys, case), runs=len(g), ok=len(ok))
        for m in st.metrics:
            v = (pd.to_numeric(ok[m].map(_number), errors="coerce").dropna() if m in ok
                 else pd.Series(dtype=float))
            row[f"{m}_mean"] = float(v.mean()) if len(v) else float("nan")
            row[f"{m}_sd"] = float(v.std(ddof=1)) if len(v) > 1 else float("nan")
            row[f"{m}_n"] = int(len(v))
        rows.append(row)
    return pd.DataFrame(rows)
