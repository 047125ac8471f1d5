"""Fidelity of a generated grain structure to its grain-size table.

Per mineral: the Kolmogorov-Smirnov distance between the equivalent diameters of the generated
grains and the table's size distribution (piecewise uniform in the classes, by count); realised
area fractions; realised H and MHI with semkit's functions and convention (class means of the
generated grains seeded by each class, R_a = sum_i w_i r_i, REFERENCE.md "How to check" 5).
"""
from __future__ import annotations

import numpy as np

from semkit.indices import heterogeneity_index, indices_from_table, mhi

from . import config
from .table import GrainSizeTable

__all__ = ["ks_distance", "fidelity_report"]


def ks_distance(d_um, table: GrainSizeTable, k: int) -> float:
    """One-sample Kolmogorov-Smirnov distance sup |F_n(d) - F(d)| of diameters ``d_um``
    against the table's distribution of mineral ``k`` (NaN for an empty sample).

    Examples
    --------
    >>> import pandas as pd
    >>> t = GrainSizeTable.from_frame(pd.DataFrame({"mineral": ["a"] * 3,
    ...     "class": ["fine", "medium", "coarse"], "d_min_um": [1, 2, 3],
    ...     "d_max_um": [2, 3, 4], "frequency_pct": [25, 50, 25],
    ...     "volume_fraction_pct": [100] * 3}))
    >>> round(ks_distance([1.5, 2.25, 2.75, 3.5], t, 0), 3)
    0.125
    """
    d = np.sort(np.asarray(d_um, float))
    n = d.size
    if n == 0:
        return float("nan")
    F = table.cdf(k, d)
    return float(max(np.max(np.arange(1, n + 1) / n - F), np.max(F - np.arange(n) / n)))


def fidelity_report(table: GrainSizeTable, areas_m2, mineral, klass, *, grain_particles=None):
    """Generated vs target statistics of a grain structure.

    Parameters
    ----------
    table : GrainSizeTable
        Scenario table at model scale (um).
    areas_m2 : (G,) ndarray of float64
        Grain areas, m^2.
    mineral : (G,) ndarray of int
        Mineral index of each grain.
    klass : (G,) ndarray of int
        Size class of the seed of each grain (0, 1, 2).
    grain_particles : (G,) ndarray of int, optional
        Particles in each grain.

    Returns
    -------
    report : dict
        ``n_grains``; ``minerals`` {name: {n_grains, ks, area_fraction, area_fraction_target,
        class_mean_um, class_mean_target_um}}; ``ks_max``; ``area_fraction_error_max``;
        ``H_target``, ``MHI_target``, ``H``, ``MHI``, ``R_a_mm``; ``particles_per_grain``
        {min, median} when given. Plain JSON types.

    Notes
    -----
    Realised class mean r_ic = mean equivalent diameter of the grains seeded by class c of
    mineral i (the target midpoint when a class has no grain, listed under
    ``classes_without_grains``); realised frequencies and area fractions are the weights.
    """
    areas = np.asarray(areas_m2, float)
    mineral = np.asarray(mineral)
    klass = np.asarray(klass)
    d_um = np.sqrt(4.0 * areas / np.pi) * 1e6
    total = areas.sum()
    tgt = indices_from_table(table.to_frame())
    m = table.n_minerals
    means = 0.5 * (table.lo_um + table.hi_um)
    real_means = means.copy()
    freqs = np.zeros((m, 3))
    w = np.zeros(m)
    missing = []
    per = {}
    for k, name in enumerate(table.minerals):
        sel = mineral == k
        w[k] = areas[sel].sum() / total
        for c in range(3):
            sc = sel & (klass == c)
            freqs[k, c] = sc.sum()
            if sc.any():
                real_means[k, c] = d_um[sc].mean()
            elif table.frequencies[k, c] > 0:
                missing.append(f"{name}/{config.CLASSES[c]}")
        per[name] = {
            "n_grains": int(sel.sum()),
            "ks": ks_distance(d_um[sel], table, k),
            "area_fraction": float(w[k]),
            "area_fraction_target": float(table.volume_fractions[k]),
            "class_mean_um": [float(v) for v in real_means[k]],
            "class_mean_target_um": [float(v) for v in means[k]],
        }
    use = freqs.sum(axis=1) > 0
    fr = np.where(use[:, None], freqs, table.frequencies)
    r_i = (fr * real_means).sum(axis=1) / fr.sum(axis=1)
    H, r_a = heterogeneity_index(np.maximum(w, 1e-12), r_i)
    MHI, _ = mhi(np.maximum(w, 1e-12), real_means, r_a=r_a)
    ks = [v["ks"] for v in per.values() if np.isfinite(v["ks"])]
    out = {
        "n_grains": int(areas.size),
        "minerals": per,
        "ks_max": float(max(ks)) if ks else float("nan"),
        "area_fraction_error_max": float(np.max(np.abs(w - table.volume_fractions))),
        "H_target": float(tgt["H"]), "MHI_target": float(tgt["MHI"]),
        "H": float(H), "MHI": float(MHI), "R_a_mm": float(r_a / 1000.0),
        "R_a_target_mm": float(tgt["R_a_mm"]),
        "index_convention": "semkit N1 (class means; R_a = sum w_i r_i)",
        "classes_without_grains": missing,
    }
    if grain_particles is not None:
        gp = np.asarray(grain_particles)
        out["particles_per_grain"] = {"min": int(gp.min()) if gp.size else 0,
                                      "median": float(np.median(gp)) if gp.size else 0.0,
                                      "grains_without_particles": int(np.sum(gp == 0))}
    return out
