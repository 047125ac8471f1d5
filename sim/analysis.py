"""Laboratory-test analytics: moduli, strengths, crack thresholds and the damage ratio P_sim.

Pure functions on recorded histories (numpy arrays, SI units). Nothing here runs a simulation;
the protocols in :mod:`sim.protocols` record the histories and call these functions.

Sign convention: **compression positive** for stresses and strains (rock mechanics). In a
uniaxial compression test the axial strain is positive (shortening) and the lateral strain is
negative (bulging); the 2D volumetric (area) strain is ``eps_v = eps_a + eps_l``, positive while
the specimen compacts.

Criteria (documented in ``docs/labtests.md``):

- **E**: tangent modulus at 50 % of the peak stress (ISRM suggested method), the least-squares
  slope of stress against axial strain over the pre-peak points with stress between 40 % and 60 %
  of the peak (``method="tangent"``); or the secant modulus, stress / strain at the first point
  where the stress reaches 50 % of the peak (``method="secant"``).
- **nu**: ``-d eps_l / d eps_a`` over the same window (least-squares slope).
- **UCS**: the peak axial stress.
- **CI** (crack initiation): the axial stress when the cumulative crack count first reaches
  ``max(1, ceil(ci_fraction * n_peak))`` with ``n_peak`` the count at the peak (default 1 %).
- **CD** (crack damage): the axial stress at the pre-peak maximum of the volumetric strain
  (volumetric-strain reversal, the onset of dilation).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = [
    "E_WINDOW", "CI_FRACTION", "CRACK_KINDS",
    "peak_index", "young_modulus", "poisson_ratio", "volumetric_strain",
    "crack_initiation", "crack_damage", "is_post_peak", "tensile_strength",
    "brazilian_strength", "crack_counts", "damage_ratio", "summarize_compression",
    "summarize_tension",
]

#: Stress window (fractions of the peak) of the tangent modulus and of Poisson's ratio.
E_WINDOW = (0.4, 0.6)
#: Crack-initiation threshold as a fraction of the crack count at the peak.
CI_FRACTION = 0.01
#: The four crack kinds, ``<bond kind>_<failure mode>``, in report order.
CRACK_KINDS = ("pb_tension", "pb_shear", "sj_tension", "sj_shear")


def _as_1d(name, a, n=None):
    a = np.asarray(a, dtype=float)
    if a.ndim != 1:
        raise ValueError(f"'{name}' must be 1-D, got shape {a.shape}")
    if n is not None and a.size != n:
        raise ValueError(f"'{name}' has {a.size} points, expected {n} like 'stress'")
    return a


def peak_index(stress) -> int:
    """Index of the (first) maximum of ``stress``.

    Parameters
    ----------
    stress : (T,) array_like of float
        Axial stress history, compression positive.

    Returns
    -------
    i : int

    Examples
    --------
    >>> peak_index([0.0, 2.0, 3.0, 1.0])
    2
    """
    s = _as_1d("stress", stress)
    if s.size == 0:
        raise ValueError("'stress' is empty: expected a recorded history")
    return int(np.nanargmax(s))


def _window(stress, lo, hi):
    """Pre-peak indices with lo*peak <= stress <= hi*peak."""
    ip = peak_index(stress)
    peak = stress[ip]
    pre = np.arange(ip + 1)
    sel = pre[(stress[: ip + 1] >= lo * peak) & (stress[: ip + 1] <= hi * peak)]
    return sel, peak


def _slope(x, y):
    xm, ym = x.mean(), y.mean()
    den = np.sum((x - xm) ** 2)
    return float(np.sum((x - xm) * (y - ym)) / den) if den > 0 else math.nan


def young_modulus(strain, stress, *, method: str = "tangent", fraction: float = 0.5,
                  window=E_WINDOW) -> float:
    """Young's modulus from an axial stress–strain curve.

    Parameters
    ----------
    strain, stress : (T,) array_like of float
        Axial strain (-) and stress (Pa), compression positive, in recording order.
    method : {"tangent", "secant"}
        ``tangent``: least-squares slope over the pre-peak points with stress inside
        ``window`` (fractions of the peak). ``secant``: stress / strain where the stress first
        reaches ``fraction`` of the peak (linear interpolation between records).
    fraction : float
        Secant level, default 0.5.
    window : (float, float)
        Tangent window, default (0.4, 0.6).

    Returns
    -------
    E : float, Pa
        NaN when fewer than two points fall inside the tangent window.

    Examples
    --------
    >>> eps = np.linspace(0, 3e-3, 11)
    >>> round(young_modulus(eps, 50e9 * eps) / 1e9, 6)
    50.0
    """
    s = _as_1d("stress", stress)
    e = _as_1d("strain", strain, s.size)
    if method == "tangent":
        sel, _ = _window(s, *window)
        if sel.size < 2:
            return math.nan
        return _slope(e[sel], s[sel])
    if method == "secant":
        if not 0.0 < fraction <= 1.0:
            raise ValueError(f"'fraction' = {fraction}, expected in (0, 1]")
        ip = peak_index(s)
        level = fraction * s[ip]
        k = int(np.argmax(s[: ip + 1] >= level))
        if k == 0:
            eps = e[0]
        else:
            t = (level - s[k - 1]) / (s[k] - s[k - 1])
            eps = e[k - 1] + t * (e[k] - e[k - 1])
        return float(level / eps) if eps > 0 else math.nan
    raise ValueError(f"'method' = {method!r}, expected 'tangent' or 'secant'")


def poisson_ratio(axial_strain, lateral_strain, stress, *, window=E_WINDOW) -> float:
    """Poisson's ratio ``-d eps_l / d eps_a`` over the pre-peak stress window.

    Parameters
    ----------
    axial_strain, lateral_strain, stress : (T,) array_like of float
        Compression positive (lateral strain is negative while the specimen bulges); stress
        in Pa selects the window.
    window : (float, float)
        Fractions of the peak stress, default (0.4, 0.6).

    Returns
    -------
    nu : float
        NaN when fewer than two points fall inside the window.

    Examples
    --------
    >>> poisson_ratio([0, 1, 2, 3, 4, 5], [0, -0.25, -0.5, -0.75, -1, -1.25], [0, 1, 2, 3, 4, 5])
    0.25
    """
    s = _as_1d("stress", stress)
    ea = _as_1d("axial_strain", axial_strain, s.size)
    el = _as_1d("lateral_strain", lateral_strain, s.size)
    sel, _ = _window(s, *window)
    if sel.size < 2:
        return math.nan
    return -_slope(ea[sel], el[sel])


def volumetric_strain(axial_strain, lateral_strain):
    """2D volumetric (area) strain ``eps_a + eps_l`` (small strain, compression positive).

    Examples
    --------
    >>> volumetric_strain([1e-3], [-2e-4]).tolist()
    [0.0008]
    """
    ea = np.asarray(axial_strain, dtype=float)
    return ea + np.asarray(lateral_strain, dtype=float)


def crack_initiation(stress, n_cracks, *, fraction: float = CI_FRACTION) -> float:
    """Crack-initiation stress CI from the onset of cracking.

    CI is the stress at the first record where the cumulative crack count reaches
    ``max(1, ceil(fraction * n_peak))``, with ``n_peak`` the count at the peak stress.

    Parameters
    ----------
    stress : (T,) array_like of float, Pa
    n_cracks : (T,) array_like of int
        Cumulative crack count at each record.
    fraction : float
        Default :data:`CI_FRACTION` (1 %).

    Returns
    -------
    ci : float, Pa
        NaN when no crack forms up to the peak.

    Examples
    --------
    >>> crack_initiation([0, 10, 20, 30, 5], [0, 0, 3, 300, 400])
    20.0
    """
    s = _as_1d("stress", stress)
    n = _as_1d("n_cracks", n_cracks, s.size)
    ip = peak_index(s)
    n_peak = n[ip]
    if n_peak <= 0:
        return math.nan
    need = max(1.0, math.ceil(fraction * n_peak))
    k = int(np.argmax(n[: ip + 1] >= need))
    return float(s[k])


def crack_damage(stress, volumetric) -> float:
    """Crack-damage stress CD at the volumetric-strain reversal.

    CD is the stress at the maximum of the volumetric strain (compression positive) over the
    records up to the peak stress: beyond it the specimen dilates.

    Parameters
    ----------
    stress, volumetric : (T,) array_like of float
        Pa and -, compression positive.

    Returns
    -------
    cd : float, Pa
        Equal to the peak stress when no reversal happens before the peak.

    Examples
    --------
    >>> crack_damage([0, 10, 20, 30, 25], [0, 1.0, 1.5, 1.2, 0.5])
    20.0
    """
    s = _as_1d("stress", stress)
    v = _as_1d("volumetric", volumetric, s.size)
    ip = peak_index(s)
    k = int(np.nanargmax(v[: ip + 1]))
    return float(s[k])


def is_post_peak(stress, *, fraction: float = 0.8, min_peak: float = 0.0) -> bool:
    """True once the stress has fallen below ``fraction`` of its peak after the peak.

    The stop rule of the compression and tension protocols: the last record lies after the
    maximum and ``stress[-1] < fraction * max(stress)``, with the peak above ``min_peak`` (so
    that noise at the start of loading does not stop a test).

    Examples
    --------
    >>> is_post_peak([0, 50, 100, 85], fraction=0.8)
    False
    >>> is_post_peak([0, 50, 100, 85, 79], fraction=0.8)
    True
    """
    if not 0.0 < fraction < 1.0:
        raise ValueError(f"'fraction' = {fraction}, expected in (0, 1)")
    s = _as_1d("stress", stress)
    if s.size < 2:
        return False
    ip = peak_index(s)
    peak = s[ip]
    return bool(peak > min_peak and ip < s.size - 1 and s[-1] < fraction * peak)


def tensile_strength(force, width: float, *, thickness: float = 1.0) -> float:
    """Direct-tension strength: peak pulling force / cross-section.

    Parameters
    ----------
    force : (T,) array_like of float, N
        Tensile force on the pulled grips (tension positive).
    width, thickness : float, m

    Returns
    -------
    sigma_t : float, Pa

    Examples
    --------
    >>> tensile_strength([0.0, 1e6, 2e6, 1e6], 0.1)
    20000000.0
    """
    f = _as_1d("force", force)
    if width <= 0 or thickness <= 0:
        raise ValueError(f"width = {width}, thickness = {thickness}: expected > 0 m")
    return float(np.nanmax(f) / (width * thickness))


def brazilian_strength(force, diameter: float, *, thickness: float = 1.0) -> float:
    """Brazilian (indirect) tensile strength ``2 P / (pi D t)`` at the peak load P.

    Parameters
    ----------
    force : (T,) array_like of float, N
        Diametral platen load (compression positive).
    diameter, thickness : float, m

    Returns
    -------
    sigma_t : float, Pa

    Examples
    --------
    >>> round(brazilian_strength([0.0, math.pi, 1.0], 1.0) / 1.0, 12)
    2.0
    """
    f = _as_1d("force", force)
    if diameter <= 0 or thickness <= 0:
        raise ValueError(f"diameter = {diameter}, thickness = {thickness}: expected > 0 m")
    return float(2.0 * np.nanmax(f) / (math.pi * diameter * thickness))


def _kind_column(kind, mode):
    kind = np.asarray(kind).astype(str)
    mode = np.asarray(mode).astype(str)
    return np.char.add(np.char.add(kind, "_"), mode)


def crack_counts(kind, mode, relation=None) -> dict:
    """Crack counts by kind (pb/sj × tension/shear) and, if given, by grain relation.

    Parameters
    ----------
    kind : (C,) array_like of str
        ``"pb"`` (parallel bond) or ``"sj"`` (smooth joint).
    mode : (C,) array_like of str
        ``"tension"`` or ``"shear"``.
    relation : (C,) array_like of str, optional
        ``"intra"`` or ``"inter"``.

    Returns
    -------
    counts : dict
        Keys of :data:`CRACK_KINDS`, ``total``, and ``intra``/``inter`` when ``relation`` is
        given.

    Examples
    --------
    >>> crack_counts(["pb", "sj", "pb"], ["tension", "shear", "tension"])["pb_tension"]
    2
    """
    kk = _kind_column(kind, mode)
    out = {k: int(np.sum(kk == k)) for k in CRACK_KINDS}
    out["total"] = int(kk.size)
    if relation is not None:
        rel = np.asarray(relation).astype(str)
        out["intra"] = int(np.sum(rel == "intra"))
        out["inter"] = int(np.sum(rel == "inter"))
    return out


def damage_ratio(mode, size, *, thickness: float = 1.0) -> dict:
    """Simulated damage ratio P_sim = tensile / shear, by crack area and by count.

    The crack area is the bond diameter × thickness (Equ. 3-1 applied to bond breaks, so that it
    can be set beside the SEM ratio P = A_T / A_S).

    Parameters
    ----------
    mode : (C,) array_like of str
        ``"tension"`` or ``"shear"``.
    size : (C,) array_like of float, m
        Bond diameter 2 R̄ of each broken bond.
    thickness : float, m

    Returns
    -------
    p : dict
        ``by_area``, ``by_count`` (``inf`` with tensile cracks only, NaN with none),
        ``area_tension_m2``, ``area_shear_m2``, ``n_tension``, ``n_shear``.

    Examples
    --------
    >>> d = damage_ratio(["tension", "tension", "shear"], [1e-4, 1e-4, 1e-4])
    >>> d["by_count"], round(d["by_area"], 12)
    (2.0, 2.0)
    """
    m = np.asarray(mode).astype(str)
    a = _as_1d("size", size, m.size) * thickness
    at, as_ = float(a[m == "tension"].sum()), float(a[m == "shear"].sum())
    nt, ns = int(np.sum(m == "tension")), int(np.sum(m == "shear"))

    def ratio(t, s):
        if s > 0:
            return t / s
        return math.inf if t > 0 else math.nan

    return {"by_area": ratio(at, as_), "by_count": ratio(float(nt), float(ns)),
            "area_tension_m2": at, "area_shear_m2": as_, "n_tension": nt, "n_shear": ns}


def summarize_compression(axial_strain, lateral_strain, stress, n_cracks, *,
                          e_method: str = "tangent", ci_fraction: float = CI_FRACTION) -> dict:
    """E, ν, peak, CI and CD of a compression test, in report units.

    Parameters
    ----------
    axial_strain, lateral_strain : (T,) array_like of float
        Compression positive.
    stress : (T,) array_like of float, Pa
        Axial stress (UCS) or deviatoric stress (biaxial), compression positive.
    n_cracks : (T,) array_like of int
        Cumulative crack count.
    e_method : {"tangent", "secant"}
    ci_fraction : float

    Returns
    -------
    summary : dict
        ``E_gpa, nu, ucs_mpa, ci_mpa, cd_mpa, peak_strain, e_method``.
    """
    s = _as_1d("stress", stress)
    ea = _as_1d("axial_strain", axial_strain, s.size)
    el = _as_1d("lateral_strain", lateral_strain, s.size)
    ip = peak_index(s)
    ev = volumetric_strain(ea, el)
    return {
        "E_gpa": young_modulus(ea, s, method=e_method) / 1e9,
        "nu": poisson_ratio(ea, el, s),
        "ucs_mpa": float(s[ip]) / 1e6,
        "ci_mpa": crack_initiation(s, n_cracks, fraction=ci_fraction) / 1e6,
        "cd_mpa": crack_damage(s, ev) / 1e6,
        "peak_strain": float(ea[ip]),
        "e_method": e_method,
    }


def summarize_tension(strain, force, *, width: float, thickness: float = 1.0) -> dict:
    """Direct-tension summary: σt (MPa), strain at peak and tensile modulus (GPa).

    Parameters
    ----------
    strain : (T,) array_like of float
        Tensile strain of the gauge (extension positive).
    force : (T,) array_like of float, N
        Pulling force, tension positive.
    width, thickness : float, m

    Returns
    -------
    summary : dict
        ``tensile_mpa, peak_strain, E_tension_gpa``.
    """
    f = _as_1d("force", force)
    e = _as_1d("strain", strain, f.size)
    stress = f / (width * thickness)
    ip = peak_index(stress)
    return {"tensile_mpa": tensile_strength(f, width, thickness=thickness) / 1e6,
            "peak_strain": float(e[ip]),
            "E_tension_gpa": young_modulus(e, stress) / 1e9}
