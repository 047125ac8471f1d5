"""Young's modulus and Poisson's ratio of a compression test, each with a validity flag.

Elastic constants are read where the specimen is still elastic: the **elastic window** is the
pre-peak records whose platen stress lies between 10 % and 60 % of the peak
(:data:`ELASTIC_STRESS`) while the crack count is at most :data:`ELASTIC_CRACKS` (5 %) of its
value at the peak. Later records carry the dilatancy of the cracks (each burst of bond breaks
widens the specimen) and no longer measure the elastic ν: on the 13 × 26 mm README specimens
ν read at 40-60 % of the peak (the ISRM tangent window) spread from 0.25 to 0.72 over five
seeds, read in the elastic window from 0.19 to 0.20 (docs/labtests.md). The window ends at
29-38 % of the peak on those specimens, where laboratory granite starts to crack (crack
initiation at 0.3-0.5 of the peak). Two readings:

- **gauge** (:mod:`sim.protocols.gauges`): the mean stress (σxx, σyy) and the affine strain of
  the central band of particles, fitted to the 2D elastic law (:func:`plane_stress_fit`).
  Stress and strain of one region obey that law at every instant, so the reading does not
  depend on the platen speed or its changes; it is valid while no crack crosses the gauge;
- **boundary**: the platen stress against the platen displacement (``E_platen``, the platen
  modulus of a laboratory: contact compliance included) and the lateral strain of the side
  layers against the axial strain of the end layers, the particles the platens touch
  (``nu_boundary``, over the whole height). These are specimen-scale readings of a dynamic
  loading, so they use only **steady** records: the platen speed unchanged over the last
  :data:`STEADY_RECORDS` chunks and the kinetic energy below :data:`KE_STEADY` × the strain
  energy.

``E_gpa`` is the gauge modulus while no crack crosses the gauge, else the platen modulus;
``nu`` is the boundary value (whole height) when the window holds steady records, else the
gauge value while no crack crosses the gauge. Flags (``E_ok``, ``nu_ok``, with a
``*_reason``): E needs both moduli and the two within :data:`E_AGREEMENT` of each other; ν
must lie in [0, 0.5). An invalid number is reported as null, its measured value kept in
``summary["elastic"]``.

2D convention: the moduli relate the in-plane stress and strain of a layer of unit thickness
with no out-of-plane stress (plane stress): they are the E and ν of a thin plate of the rock.
"""
from __future__ import annotations

import math

import numpy as np

from .. import analysis
from .gauges import crack_crosses

__all__ = ["E_AGREEMENT", "ELASTIC_STRESS", "ELASTIC_CRACKS", "STEADY_RECORDS", "KE_STEADY",
           "CONVENTION", "plane_stress_fit", "steady_records", "elastic_window",
           "elastic_constants"]

#: Platen stress range of the elastic window, fractions of the peak.
ELASTIC_STRESS = (0.1, 0.6)
#: The elastic window ends when the crack count passes this fraction of its value at the peak.
ELASTIC_CRACKS = 0.05
_WINDOW = (f"platen stress in {100 * ELASTIC_STRESS[0]:.0f}-{100 * ELASTIC_STRESS[1]:.0f} % of "
           f"the peak and at most {100 * ELASTIC_CRACKS:.0f} % of the peak's crack count")
#: Largest relative difference between the gauge and the platen modulus of a valid E.
E_AGREEMENT = 0.15
#: A record is steady when the platen speed was the same over this many chunks before it.
STEADY_RECORDS = 3
#: ... and the kinetic energy of the particles is below this fraction of the strain energy.
KE_STEADY = 1e-3
#: Minimum records in the window for a reading.
MIN_RECORDS = 3
#: What the 2D moduli mean (written into summary.json).
CONVENTION = ("plane stress: E and nu relate the in-plane stress and strain of a layer of unit "
              "thickness with no out-of-plane stress (sigma_zz = 0); plane-strain values "
              "E' = E / (1 - nu^2), nu' = nu / (1 - nu)")


def plane_stress_fit(sxx, syy, exx, eyy):
    """E and ν from increments of stress and strain of one region (2D, plane stress).

    Least squares on ``exx = (sxx − ν syy)/E`` and ``eyy = (syy − ν sxx)/E`` over the changes
    from the mean of the records (compression positive for both), so a lateral stress (waves,
    confinement) does not bias ν as the plain ratio −Δexx/Δeyy would.

    Returns
    -------
    E : float, Pa
    nu : float
        NaN when fewer than two records or no stress change.

    Examples
    --------
    >>> s = np.array([0.0, 1e6, 2e6])
    >>> E, nu = plane_stress_fit(0.1 * s, s, (0.1 - 0.25) * s / 50e9, (1 - 0.025) * s / 50e9)
    >>> round(E / 1e9, 9), round(nu, 9)
    (50.0, 0.25)
    """
    sxx, syy, exx, eyy = (np.asarray(v, float) for v in (sxx, syy, exx, eyy))
    if syy.size < 2:
        return math.nan, math.nan
    dsx, dsy = sxx - sxx.mean(), syy - syy.mean()
    a = np.r_[np.c_[dsx, -dsy], np.c_[dsy, -dsx]]
    b = np.r_[exx - exx.mean(), eyy - eyy.mean()]
    if not np.any(a):
        return math.nan, math.nan
    (inv_e, nu_e), *_ = np.linalg.lstsq(a, b, rcond=None)
    if not inv_e > 0:
        return math.nan, math.nan
    return float(1.0 / inv_e), float(nu_e / inv_e)


def steady_records(history, *, first: int = 0) -> np.ndarray:
    """Boolean mask of the steady records (see the module docstring); records before
    ``first`` (the start-up ramp) are never steady."""
    n = len(history)
    v = history["platen_velocity_m_per_s"].to_numpy(float) \
        if "platen_velocity_m_per_s" in history else np.zeros(n)
    ok = np.zeros(n, bool)
    for k in range(max(first, STEADY_RECORDS), n):
        ok[k] = bool(np.all(v[k - STEADY_RECORDS + 1:k + 1] == v[k - STEADY_RECORDS]))
    ke = history["kinetic_energy_j"].to_numpy(float)
    se = history["strain_energy_j"].to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        ok &= ~(ke > KE_STEADY * se)
    return ok


def elastic_window(history, stress_col="axial_stress_mpa") -> np.ndarray:
    """Indices of the elastic window (module docstring): pre-peak records with platen stress
    in :data:`ELASTIC_STRESS` of the peak and at most :data:`ELASTIC_CRACKS` of the peak's
    crack count (a history without ``cracks_total`` has none).

    Examples
    --------
    >>> import pandas as pd
    >>> h = pd.DataFrame({"axial_stress_mpa": [0, 5, 20, 40, 60, 80, 100, 90],
    ...                   "cracks_total": [0, 0, 0, 1, 8, 20, 100, 150]})
    >>> elastic_window(h).tolist()
    [2, 3]
    """
    s = history[stress_col].to_numpy(float)
    sel, _ = analysis._window(s, *ELASTIC_STRESS)
    if "cracks_total" in history and sel.size:
        c = history["cracks_total"].to_numpy(float)
        sel = sel[c[sel] <= ELASTIC_CRACKS * c[analysis.peak_index(s)]]
    return sel


def _boundary(hist, sel, stress):
    if sel.size < MIN_RECORDS:
        return math.nan, math.nan
    ep = hist["axial_strain"].to_numpy(float)[sel]
    ea = hist["end_axial_strain"].to_numpy(float)[sel]
    el = hist["lateral_strain"].to_numpy(float)[sel]
    return analysis._slope(ep, stress[sel]), -analysis._slope(ea, el)


def elastic_constants(history, cracks=None, *, gauge_box=None, link=None,
                      stress_col="axial_stress_mpa", first_steady: int = 0) -> dict:
    """E, ν and their validity from a compression history (report units).

    Parameters
    ----------
    history : pandas.DataFrame
        Columns ``stress_col`` (MPa, the platen stress the window is set on),
        ``gauge_stress_xx_mpa``, ``gauge_stress_yy_mpa``, ``gauge_lateral_strain``,
        ``gauge_axial_strain``, ``end_axial_strain``, ``lateral_strain``,
        ``platen_velocity_m_per_s``, ``kinetic_energy_j``, ``strain_energy_j``, ``step``.
    cracks : pandas.DataFrame, optional
        Crack log (``step``, ``x``, ``y``): whether a crack crosses the gauge by the end of the
        window (:func:`sim.protocols.gauges.crack_crosses`).
    gauge_box : (4,) array, m
        The gauge region.
    link : float, m
        Distance within which two cracks are connected (about one particle diameter).
    first_steady : int
        Records before this index are never steady (the start-up ramp).

    Returns
    -------
    dict
        ``E_gpa``, ``nu`` (None when invalid), ``E_ok``, ``E_reason``, ``nu_ok``,
        ``nu_reason`` and ``elastic`` (every reading, its source, record counts, convention).
    """
    s = history[stress_col].to_numpy(float) * 1e6
    peak = s[analysis.peak_index(s)]
    sel = elastic_window(history, stress_col)
    steady = steady_records(history, first=first_steady)[sel]
    g = {k: history[c].to_numpy(float)[sel] for k, c in (
        ("sxx", "gauge_stress_xx_mpa"), ("syy", "gauge_stress_yy_mpa"),
        ("exx", "gauge_lateral_strain"), ("eyy", "gauge_axial_strain"))}
    e_g, nu_g = (plane_stress_fit(g["sxx"] * 1e6, g["syy"] * 1e6, g["exx"], g["eyy"])
                 if sel.size >= MIN_RECORDS else (math.nan, math.nan))
    st = sel[steady]
    platen_steady = st.size >= MIN_RECORDS
    e_p, nu_b = _boundary(history, st if platen_steady else sel, s)
    crossed = False
    if cracks is not None and len(cracks) and sel.size and gauge_box is not None:
        last = history["step"].to_numpy()[sel[-1]]
        c = cracks[cracks["step"].to_numpy() <= last]
        crossed = crack_crosses(c["x"].to_numpy(float), c["y"].to_numpy(float), gauge_box,
                                link)
    gauge_ok = not crossed and math.isfinite(e_g)
    E, e_src = (e_g, "gauge") if gauge_ok else (e_p, "platen")
    if platen_steady or not gauge_ok:
        nu, nu_src = nu_b, "boundary"
    else:
        nu, nu_src = nu_g, "gauge"
    if sel.size < MIN_RECORDS:
        e_why = nu_why = (f"{sel.size} records in the elastic window ({_WINDOW}), expected "
                          f">= {MIN_RECORDS}")
    else:
        e_why = nu_why = ""
        if not gauge_ok and not platen_steady:
            e_why = nu_why = (f"a crack crosses the gauge and only {st.size} steady records "
                              "(constant platen speed, small kinetic energy) lie in the window")
        if not e_why:
            if not (math.isfinite(e_g) and math.isfinite(e_p)):
                e_why = "gauge or platen modulus not measured"
            elif abs(e_g / e_p - 1.0) > E_AGREEMENT:
                e_why = (f"gauge and platen moduli {e_g / 1e9:.4g} and {e_p / 1e9:.4g} GPa "
                         f"differ by more than {100 * E_AGREEMENT:.0f} %")
        if not nu_why and not (math.isfinite(nu) and 0.0 <= nu < 0.5):
            nu_why = f"nu = {nu:.4g} ({nu_src}) outside [0, 0.5)"
    e_ok, nu_ok = not e_why, not nu_why
    return {
        "E_gpa": E / 1e9 if e_ok else None, "nu": nu if nu_ok else None,
        "E_ok": e_ok, "E_reason": e_why or f"{e_src}; gauge and platen within "
                                           f"{100 * E_AGREEMENT:.0f} %",
        "nu_ok": nu_ok, "nu_reason": nu_why or f"{nu_src}, in [0, 0.5)",
        "elastic": {
            "E_measured_gpa": E / 1e9, "nu_measured": nu, "E_source": e_src,
            "nu_source": nu_src,
            "E_gauge_gpa": e_g / 1e9, "nu_gauge": nu_g, "E_platen_gpa": e_p / 1e9,
            "nu_boundary": nu_b, "gauge_crossed_by_crack": bool(crossed),
            "window_records": int(sel.size), "steady_window_records": int(st.size),
            "boundary_on_steady_records": bool(platen_steady),
            "window_stress_fraction": [float(s[sel[0]] / peak), float(s[sel[-1]] / peak)]
            if sel.size else None,
            "window": "pre-peak records with " + _WINDOW,
            "convention": CONVENTION},
    }
