"""Per-grain shape (:func:`grain_table`, slenderness H/W) and the grain-size table
(:func:`grain_size_table`, ``grains.csv``).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .. import config
from ..errors import InputError

__all__ = ["slenderness", "grain_table", "grain_size_table", "parse_classes"]

AUTO_CLASS_PERCENTILES = config.AUTO_CLASS_PERCENTILES


def slenderness(grain_mask):
    """Slenderness ratio H/W of one grain (Equ. 5-2).

    Parameters
    ----------
    grain_mask : (M, N) ndarray of bool
        The grain (a crop is fine).

    Returns
    -------
    ratio : float
        Vertical chord length / horizontal chord length, both through the centroid (the
        contiguous run of grain pixels through the centroid pixel), NaN for an empty mask.

    Examples
    --------
    >>> m = np.zeros((9, 9), bool); m[1:8, 3:6] = True
    >>> float(slenderness(m))
    2.3333333333333335
    """
    m = np.asarray(grain_mask, bool)
    if not m.any():
        return float("nan")
    rr, cc = np.nonzero(m)
    r0, c0 = int(round(rr.mean())), int(round(cc.mean()))
    if not m[r0, c0]:  # non-convex grain: nearest grain pixel to the centroid
        k = np.argmin((rr - rr.mean()) ** 2 + (cc - cc.mean()) ** 2)
        r0, c0 = rr[k], cc[k]

    def run(line, i):
        lo = i
        while lo > 0 and line[lo - 1]:
            lo -= 1
        hi = i
        while hi < len(line) - 1 and line[hi + 1]:
            hi += 1
        return hi - lo + 1

    return run(m[:, c0], r0) / run(m[r0, :], c0)


def grain_table(grain_labels, phase_labels=None, *, pixel_size_um=1.0, names=None):
    """Per-grain measurements.

    Parameters
    ----------
    grain_labels : (M, N) ndarray of int
        0 = none, 1..G grains.
    phase_labels : (M, N) ndarray of int, optional
        Phase map (1 = brightest); the grain's mineral is its majority phase.
    pixel_size_um : float
        Pixel size, um.
    names : sequence of str, optional
        Mineral names brightest-first (phase k -> names[k-1]); default ``phase1``...

    Returns
    -------
    grains : pandas.DataFrame
        ``grain_id, mineral, phase, area_um2, eq_diameter_um, aspect_ratio, orientation_deg,
        slenderness, centroid_x_um, centroid_y_um``. ``orientation_deg`` is the major axis
        angle from the image x axis, anticlockwise as displayed, in [0, 180).

    Notes
    -----
    d_eq = sqrt(4 A / pi); aspect = major / minor axis of the inertia ellipse; slenderness =
    vertical / horizontal chord through the centroid (Equ. 5-2).
    """
    from skimage.measure import regionprops

    lab = np.asarray(grain_labels)
    if lab.ndim != 2:
        raise InputError(f"grain_labels: expected a 2-D array, got shape {lab.shape}")
    if not (pixel_size_um > 0):
        raise InputError(f"pixel_size_um: expected > 0, got {pixel_size_um}")
    ph = None if phase_labels is None else np.asarray(phase_labels)
    if ph is not None and ph.shape != lab.shape:
        raise InputError(f"phase_labels: expected shape {lab.shape}, got {ph.shape}")
    rows = []
    for rp in regionprops(lab.astype(np.int32)):
        if ph is not None:
            vals = ph[rp.slice][rp.image]
            vals = vals[vals > 0]
            phase = int(np.bincount(vals).argmax()) if vals.size else 0
        else:
            phase = 1
        if names is not None and 1 <= phase <= len(names):
            mineral = str(names[phase - 1])
        else:
            mineral = f"phase{phase}"
        major, minor = rp.axis_major_length, rp.axis_minor_length
        ang = (np.degrees(rp.orientation) + 90.0) % 180.0
        rows.append(dict(grain_id=rp.label, mineral=mineral, phase=phase,
                         area_um2=rp.area * pixel_size_um ** 2,
                         eq_diameter_um=np.sqrt(4 * rp.area / np.pi) * pixel_size_um,
                         aspect_ratio=major / minor if minor > 0 else np.inf,
                         orientation_deg=ang, slenderness=slenderness(rp.image),
                         centroid_x_um=rp.centroid[1] * pixel_size_um,
                         centroid_y_um=rp.centroid[0] * pixel_size_um))
    cols = ["grain_id", "mineral", "phase", "area_um2", "eq_diameter_um", "aspect_ratio",
            "orientation_deg", "slenderness", "centroid_x_um", "centroid_y_um"]
    return pd.DataFrame(rows, columns=cols)


def _edges(value, what):
    if isinstance(value, str):
        try:
            value = [float(v) for v in value.split(",")]
        except ValueError:
            raise InputError(f"{what}: expected 'e1,e2' in um, got {value!r}") from None
    e = tuple(float(v) for v in value)
    if len(e) != 2 or not (0 < e[0] < e[1]):
        raise InputError(f"{what}: expected two increasing edges 'fine/medium,medium/coarse' "
                         f"in um, got {value}")
    return e


def parse_classes(classes):
    if classes is None:
        return None
    if isinstance(classes, dict):
        return {str(k): _edges(v, f"classes[{k!r}]") for k, v in classes.items()}
    return {None: _edges(classes, "classes")}


def grain_size_table(grains, *, classes=None, volume_fractions=None):
    """Build the grain-size table (``grains.csv``, DESIGN.md §4) from per-grain measurements.

    Parameters
    ----------
    grains : pandas.DataFrame
        Output of :func:`grain_table` (``mineral, area_um2, eq_diameter_um``).
    classes : (2,) sequence, "20,140" string, or dict {mineral: (e1, e2)}, optional
        Class edges in um: fine < e1 <= medium < e2 <= coarse. Default: the automatic rule,
        per mineral e1, e2 = the 10th and 90th count percentiles of its equivalent diameters.
    volume_fractions : dict {mineral: fraction}, optional
        Use these (e.g. phase-map pixel fractions) instead of the grain-area fractions.

    Returns
    -------
    table : pandas.DataFrame
        One row per (mineral, class): ``mineral, class, d_min_um, d_max_um, frequency_pct,
        volume_fraction_pct, d_mean_um, n_grains``. Minerals in order of decreasing volume.
        ``d_min_um``/``d_max_um`` are the class edges, closed by the smallest and largest grain
        measured; ``frequency_pct`` the share of the mineral's grains by count.

    Raises
    ------
    InputError
        Missing columns, no grains, bad class edges.

    Notes
    -----
    Volume fraction = area fraction in 2-D (Delesse principle).
    """
    for col in ("mineral", "area_um2", "eq_diameter_um"):
        if col not in grains.columns:
            raise InputError(f"grains table: missing column {col!r}")
    if len(grains) == 0:
        raise InputError("grains table: no grains")
    minerals = list(grains.groupby("mineral")["area_um2"].sum().sort_values(
        ascending=False).index)
    edges_cfg = parse_classes(classes)
    total = grains["area_um2"].sum()
    rows = []
    for name in minerals:
        g = grains[grains["mineral"] == name]
        d = g["eq_diameter_um"].to_numpy(float)
        if edges_cfg is None:
            e1, e2 = np.percentile(d, AUTO_CLASS_PERCENTILES)
            if not e1 < e2:
                e2 = e1 * (1 + 1e-9) + 1e-12
        elif None in edges_cfg:
            e1, e2 = edges_cfg[None]
        elif str(name) in edges_cfg:
            e1, e2 = edges_cfg[str(name)]
        else:
            raise InputError(f"classes: no class edges given for mineral {name!r}")
        lo, hi = min(d.min(), e1), max(d.max(), e2)
        bounds = [(lo, e1), (e1, e2), (e2, hi)]
        cls_idx = np.digitize(d, [e1, e2])
        if volume_fractions is not None:
            vf = 100.0 * float(volume_fractions.get(name, 0.0))
        else:
            vf = 100.0 * g["area_um2"].sum() / total
        for c, cls in enumerate(("fine", "medium", "coarse")):
            sel = cls_idx == c
            rows.append(dict(mineral=name, **{"class": cls}, d_min_um=bounds[c][0],
                             d_max_um=bounds[c][1], frequency_pct=100.0 * sel.mean(),
                             volume_fraction_pct=vf,
                             d_mean_um=float(d[sel].mean()) if sel.any() else np.nan,
                             n_grains=int(sel.sum())))
    return pd.DataFrame(rows)
