"""Damage ratio P (Equ. 3-1) and the heterogeneity indices H (Equ. 4-1/4-2) and MHI (Equ. 4-3).

Pure functions on arrays and on grain-size tables in ``grains.csv`` form (DESIGN.md §4):
one row per (mineral, class) with ``mineral, class, d_min_um, d_max_um, frequency_pct,
volume_fraction_pct`` (optionally ``d_mean_um``, the measured mean diameter of the class).

Conventions (see docs/semkit_science.md):

* ``"N1"`` (default): the class mean is the class midpoint ``(d_min + d_max) / 2``; the mean
  size of mineral *i* is the frequency-weighted mean of its class means (frequencies normalised
  to sum to 1 within the mineral); ``R_a = sum_i w_i r_i`` with the volume fractions ``w``
  normalised to sum to 1. H uses the mineral means ``r_i``, MHI the class means.
* ``"geometric"``: as N1 but the class mean is ``sqrt(d_min * d_max)`` (log-scale midpoint).
* ``"measured"``: as N1 but the class mean is the table's ``d_mean_um`` column (semkit writes it).
"""
from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = [
    "damage_ratio",
    "heterogeneity_index",
    "mhi",
    "indices_from_table",
    "class_means_from_table",
    "split_range",
    "table_with_ranges",
    "CLASS_ORDER",
    "CONVENTIONS",
]

#: Order of the grain-size classes in every (M, 3) array of this module.
CLASS_ORDER = ("fine", "medium", "coarse")
#: Conventions understood by :func:`indices_from_table`.
CONVENTIONS = ("N1", "geometric", "measured")

_TABLE_COLUMNS = ("mineral", "class", "d_min_um", "d_max_um", "frequency_pct",
                  "volume_fraction_pct")


def _as_weights(weights, name="weights"):
    w = np.asarray(weights, dtype=np.float64)
    if w.ndim != 1 or w.size == 0:
        raise InputError(f"{name}: expected a non-empty 1-D array, got shape {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InputError(f"{name}: expected finite non-negative values, got {w.tolist()}")
    total = w.sum()
    if total <= 0:
        raise InputError(f"{name}: expected a positive sum, got {total}")
    return w / total


def _as_sizes(values, shape_hint, name):
    r = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(r)) or np.any(r <= 0):
        raise InputError(f"{name}: expected finite positive sizes, got {r.tolist()}")
    if shape_hint is not None and r.shape != shape_hint:
        raise InputError(f"{name}: expected shape {shape_hint}, got {r.shape}")
    return r


def damage_ratio(area_tensile, area_shear):
    """Damage ratio P = A_T / A_S of tensile to shear crack area (Equ. 3-1).

    Parameters
    ----------
    area_tensile : float or ndarray of float64
        Tensile crack area A_T (any area unit, e.g. um^2). Must be >= 0.
    area_shear : float or ndarray of float64
        Shear crack area A_S, same unit and broadcastable shape. Must be >= 0.

    Returns
    -------
    P : float or ndarray of float64
        The ratio; **NaN where A_S = 0** (no shear cracks: the ratio is undefined, never
        ``inf``). Callers that need to know why use :func:`semkit.damage.p_status`.

    Raises
    ------
    InputError
        If an area is negative or not finite.

    Notes
    -----
    P = D_T / D_S = A_T / A_S (thesis Equ. 3-1); P > 1 means tensile-dominated damage.
    A_S = 0 gives NaN without a warning; it is up to the aggregation (``damage.csv``) to
    count and report such images explicitly.

    Examples
    --------
    >>> float(damage_ratio(3.0, 1.5))
    2.0
    >>> damage_ratio([1.0, 2.0], [0.0, 4.0]).tolist()
    [nan, 0.5]
    """
    a_t = np.asarray(area_tensile, dtype=np.float64)
    a_s = np.asarray(area_shear, dtype=np.float64)
    for name, a in (("area_tensile", a_t), ("area_shear", a_s)):
        if not np.all(np.isfinite(a)) or np.any(a < 0):
            raise InputError(f"{name}: expected finite areas >= 0, got {a.tolist()}")
    a_t, a_s = np.broadcast_arrays(a_t, a_s)
    p = np.full(a_t.shape, np.nan)
    ok = a_s > 0
    p[ok] = a_t[ok] / a_s[ok]
    return p[()] if p.ndim == 0 else p


def heterogeneity_index(weights, radii):
    """Heterogeneity index H of Peng et al. (Equ. 4-1, 4-2).

    Parameters
    ----------
    weights : (M,) array_like of float
        Volume (area) fractions of the M minerals; normalised to sum to 1 (percent is fine).
    radii : (M,) array_like of float
        Mean grain size of each mineral (radius or diameter, any unit: H is dimensionless).

    Returns
    -------
    H : float
        Heterogeneity index.
    R_a : float
        Weighted mean size, in the unit of ``radii``.

    Raises
    ------
    InputError
        Wrong shapes, negative weights, non-positive sizes.

    Notes
    -----
    R_a = sum_i w_i r_i (Equ. 4-2) and H = sqrt(sum_i (r_i / R_a - 1)^2) (Equ. 4-1).
    Scaling every r_i by k leaves H unchanged.

    Examples
    --------
    >>> H, R_a = heterogeneity_index([0.5, 0.3, 0.2], [0.705, 0.473, 0.413])
    >>> round(R_a, 4), round(H, 4)
    (0.577, 0.4031)
    """
    w = _as_weights(weights)
    r = _as_sizes(radii, w.shape, "radii")
    r_a = float(np.dot(w, r))
    h = float(np.sqrt(np.sum((r / r_a - 1.0) ** 2)))
    return h, r_a


def mhi(weights, class_means, *, frequencies=None, r_a=None):
    """Modified heterogeneity index MHI (Equ. 4-3).

    Parameters
    ----------
    weights : (M,) array_like of float
        Volume fractions of the M minerals (normalised to sum to 1).
    class_means : (M, 3) array_like of float
        Mean size of the fine, medium and coarse class of each mineral (any unit).
    frequencies : (M, 3) array_like of float, optional
        Share of each class by grain count within its mineral (normalised per row). Used
        for the mineral mean size r_i = sum_c f_ic r_ic; without it r_i is the plain mean
        of the three class means.
    r_a : float, optional
        Use this R_a instead of computing it (for checks against published values).

    Returns
    -------
    MHI : float
        Modified heterogeneity index.
    R_a : float
        Weighted mean size used, in the unit of ``class_means``.

    Raises
    ------
    InputError
        Wrong shapes, negative weights or frequencies, non-positive sizes.

    Notes
    -----
    R_a = sum_i w_i r_i (Equ. 4-2) and
    MHI = sqrt(sum_i [(r_fi/R_a - 1)^2 + (r_mi/R_a - 1)^2 + (r_ci/R_a - 1)^2]) (Equ. 4-3).
    Scaling all sizes (and ``r_a``) by k leaves MHI unchanged.

    Examples
    --------
    >>> m, R_a = mhi([1.0], [[1.0, 2.0, 3.0]])
    >>> round(m, 4), R_a
    (0.7071, 2.0)
    """
    w = _as_weights(weights)
    rc = _as_sizes(class_means, (w.size, 3), "class_means")
    if frequencies is None:
        r_i = rc.mean(axis=1)
    else:
        f = np.asarray(frequencies, dtype=np.float64)
        if f.shape != rc.shape or not np.all(np.isfinite(f)) or np.any(f < 0):
            raise InputError(f"frequencies: expected finite values >= 0 of shape {rc.shape}")
        rows = f.sum(axis=1)
        if np.any(rows <= 0):
            raise InputError("frequencies: every mineral needs a positive total frequency")
        r_i = (f * rc).sum(axis=1) / rows
    if r_a is None:
        r_a = float(np.dot(w, r_i))
    else:
        r_a = float(r_a)
        if not np.isfinite(r_a) or r_a <= 0:
            raise InputError(f"r_a: expected a positive size, got {r_a}")
    value = float(np.sqrt(np.sum((rc / r_a - 1.0) ** 2)))
    return value, r_a


def _check_table(table):
    missing = [c for c in _TABLE_COLUMNS if c not in getattr(table, "columns", ())]
    if missing:
        raise InputError(f"grain-size table: missing column(s) {missing}; "
                         f"expected {list(_TABLE_COLUMNS)}")
    bad = set(table["class"]) - set(CLASS_ORDER)
    if bad:
        raise InputError(f"grain-size table: column 'class' has {sorted(bad)}; "
                         f"expected fine|medium|coarse")
    d_min = table["d_min_um"].to_numpy(float)
    d_max = table["d_max_um"].to_numpy(float)
    if np.any(~np.isfinite(d_min)) or np.any(d_min <= 0) or np.any(d_max < d_min):
        raise InputError("grain-size table: expected 0 < d_min_um <= d_max_um on every row")


def class_means_from_table(table, *, convention="N1"):
    """Class mean sizes, frequencies and volume fractions from a grain-size table.

    Parameters
    ----------
    table : pandas.DataFrame
        ``grains.csv`` form (DESIGN.md §4). Each mineral needs all three classes; a class
        missing from a measured table is an error (give it a zero frequency instead).
    convention : {"N1", "geometric", "measured"}
        How a class mean is taken (module docstring).

    Returns
    -------
    minerals : list of str
        Mineral names in order of first appearance.
    weights : (M,) ndarray of float64
        Volume fractions (normalised to sum to 1).
    class_means : (M, 3) ndarray of float64, um
        Fine, medium, coarse class means.
    frequencies : (M, 3) ndarray of float64
        Frequencies normalised per mineral.

    Raises
    ------
    InputError
        Missing columns, unknown class or convention, a missing class, bad sizes.
    """
    if convention not in CONVENTIONS:
        raise InputError(f"convention: expected one of {CONVENTIONS}, got {convention!r}")
    _check_table(table)
    if convention == "measured" and "d_mean_um" not in table.columns:
        raise InputError("grain-size table: convention 'measured' needs column d_mean_um")
    minerals = list(dict.fromkeys(table["mineral"].astype(str)))
    m = len(minerals)
    means = np.zeros((m, 3))
    freqs = np.zeros((m, 3))
    weights = np.zeros(m)
    for i, name in enumerate(minerals):
        rows = table[table["mineral"].astype(str) == name]
        weights[i] = float(rows["volume_fraction_pct"].iloc[0])
        for c, cls in enumerate(CLASS_ORDER):
            row = rows[rows["class"] == cls]
            if len(row) != 1:
                raise InputError(f"grain-size table: mineral {name!r} needs exactly one "
                                 f"{cls!r} row, found {len(row)}")
            lo, hi = float(row["d_min_um"].iloc[0]), float(row["d_max_um"].iloc[0])
            if convention == "N1":
                means[i, c] = 0.5 * (lo + hi)
            elif convention == "geometric":
                means[i, c] = np.sqrt(lo * hi)
            else:
                dm = float(row["d_mean_um"].iloc[0])
                means[i, c] = dm if np.isfinite(dm) and dm > 0 else 0.5 * (lo + hi)
            freqs[i, c] = float(row["frequency_pct"].iloc[0])
    if np.any(freqs.sum(axis=1) <= 0):
        raise InputError("grain-size table: every mineral needs a positive total frequency_pct")
    freqs = freqs / freqs.sum(axis=1, keepdims=True)
    return minerals, _as_weights(weights, "volume_fraction_pct"), means, freqs


def indices_from_table(table, *, convention="N1"):
    """H, MHI and R_a of a grain-size table (``grains.csv`` form).

    Parameters
    ----------
    table : pandas.DataFrame
        Columns ``mineral, class, d_min_um, d_max_um, frequency_pct, volume_fraction_pct``.
    convention : {"N1", "geometric", "measured"}
        Class-mean convention (module docstring). N1 reproduces REFERENCE.md's documented
        values 2.69, 1.84, 1.34, 0.88 for scenarios S1..S4.

    Returns
    -------
    result : dict
        ``H``, ``MHI``, ``R_a_um`` and ``R_a_mm`` (the same R_a in both units, the table's
        sizes being in um), ``mineral_mean_um`` ({mineral: r_i}), ``convention``.

    Raises
    ------
    InputError
        Bad table (see :func:`class_means_from_table`).

    Notes
    -----
    r_i = sum_c f_ic r_ic, R_a = sum_i w_i r_i (Equ. 4-2), H from r_i (Equ. 4-1),
    MHI from the class means r_ic (Equ. 4-3).
    """
    minerals, w, means, freqs = class_means_from_table(table, convention=convention)
    r_i = (freqs * means).sum(axis=1)
    h, r_a = heterogeneity_index(w, r_i)
    m, _ = mhi(w, means, r_a=r_a)
    return {"H": h, "MHI": m, "R_a_um": r_a, "R_a_mm": r_a / 1000.0,
            "mineral_mean_um": {k: float(v) for k, v in zip(minerals, r_i)},
            "convention": convention}


def split_range(edges, d_min, d_max):
    """Map class edges linearly onto a new size range (the N1 scenario split).

    Parameters
    ----------
    edges : (4,) array_like of float
        Increasing class edges of the full range: fine lower, fine/medium, medium/coarse,
        coarse upper.
    d_min, d_max : float
        The new range (same unit), d_min < d_max.

    Returns
    -------
    new_edges : (4,) ndarray of float64
        ``d_min + (edges - edges[0]) * (d_max - d_min) / (edges[-1] - edges[0])``.

    Examples
    --------
    >>> split_range([1.0, 2.0, 14.0, 24.0], 2.2, 12.4).round(3).tolist()
    [2.2, 2.643, 7.965, 12.4]
    """
    e = np.asarray(edges, dtype=np.float64)
    if e.shape != (4,) or np.any(np.diff(e) <= 0):
        raise InputError(f"edges: expected 4 increasing values, got {e.tolist()}")
    if not (0 < d_min < d_max):
        raise InputError(f"range: expected 0 < d_min < d_max, got {d_min}, {d_max}")
    return d_min + (e - e[0]) * (d_max - d_min) / (e[-1] - e[0])


def table_with_ranges(table, ranges_um):
    """A grain-size table whose class edges are remapped onto new per-mineral ranges.

    Parameters
    ----------
    table : pandas.DataFrame
        ``grains.csv`` form with the full-range class edges (e.g. Table 4-1 / Appendix A bins).
    ranges_um : dict
        {mineral: (d_min_um, d_max_um)}, e.g. a Table 4-2 scenario range.

    Returns
    -------
    new_table : pandas.DataFrame
        Copy with ``d_min_um, d_max_um`` replaced by :func:`split_range`; frequencies and
        volume fractions unchanged.
    """
    _check_table(table)
    out = table.copy()
    out["d_min_um"] = out["d_min_um"].astype(np.float64)
    out["d_max_um"] = out["d_max_um"].astype(np.float64)
    for name, (lo, hi) in ranges_um.items():
        sel = out["mineral"].astype(str) == str(name)
        if not sel.any():
            raise InputError(f"ranges_um: mineral {name!r} is not in the table")
        rows = out[sel].set_index("class").loc[list(CLASS_ORDER)]
        edges = [rows["d_min_um"].iloc[0], rows["d_max_um"].iloc[0],
                 rows["d_max_um"].iloc[1], rows["d_max_um"].iloc[2]]
        new = split_range(edges, float(lo), float(hi))
        for c, cls in enumerate(CLASS_ORDER):
            idx = out.index[sel & (out["class"] == cls)]
            out.loc[idx, "d_min_um"] = new[c]
            out.loc[idx, "d_max_um"] = new[c + 1]
    return out
