"""Scores of a crack mask against a hand-drawn truth: centrelines, lengths, polylines.

Hand-painted crack labels are usually wider than the dark crack and stop where the painter
stopped, so pixel-wise scores mostly measure the brush. These scores compare centrelines:

* :func:`centreline_scores` — both masks are skeletonised; a skeleton pixel counts as found when
  it lies within ``tol_px`` of the *other mask* (precision: predicted skeleton near the truth;
  recall: truth skeleton near the prediction), and F1 of the two. Lengths are the skeleton
  lengths of both masks measured the same way as a crack's
  (:func:`semkit.skeleton.skeleton_length` plus :func:`semkit.skeleton.tip_extension`).
* :func:`polyline_coverage` — the share of a hand-drawn polyline's length lying within
  ``tol_px`` of a detected crack (a crack traced by hand as a line, not painted).
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

__all__ = ["centreline_scores", "polyline_coverage", "rasterise_polyline"]


def _skeleton(mask):
    from .skeleton import prune_spurs, skeletonize
    m = np.asarray(mask, bool)
    return prune_spurs(skeletonize(m), m)


def _length(skel, mask):
    """Total length (px) of a mask's skeleton, measured as :func:`semkit.measure.crack_table`
    measures a crack's: chain code plus what the skeleton leaves out at the ends."""
    from .measure import label_cracks
    from .skeleton import skeleton_length, tip_extension
    lab, n = label_cracks(mask)
    return float((skeleton_length(skel, lab, n + 1) + tip_extension(skel, lab, n + 1)).sum())


def _near(mask, tol_px):
    """Pixels within ``tol_px`` (Euclidean) of ``mask``."""
    if not mask.any():
        return np.zeros(mask.shape, bool)
    return ndi.distance_transform_edt(~mask) <= tol_px


def centreline_scores(pred_mask, truth_mask, *, tol_px=2.0, valid_mask=None):
    """Centreline precision, recall, F1 and length ratio of a crack mask against the truth.

    Parameters
    ----------
    pred_mask, truth_mask : (M, N) array_like of bool
        Detected cracks and the hand-drawn truth.
    tol_px : float
        Match distance, px.
    valid_mask : (M, N) array_like of bool, optional
        Only skeleton pixels inside count (e.g. the sample region).

    Returns
    -------
    scores : dict
        ``precision, recall, f1`` (NaN when undefined), ``length_pred_px, length_truth_px``
        (skeleton lengths with their ends, as :func:`semkit.measure.crack_table` measures a
        crack), ``length_ratio``,
        ``area_pred_px, area_truth_px, area_ratio``.

    Examples
    --------
    >>> t = np.zeros((20, 40), bool); t[8:13, 5:35] = True
    >>> p = np.zeros_like(t); p[10, 5:35] = True
    >>> s = centreline_scores(p, t)
    >>> round(s["precision"], 2), round(s["recall"], 2)
    (1.0, 1.0)
    """
    p = np.asarray(pred_mask, bool)
    t = np.asarray(truth_mask, bool)
    if p.shape != t.shape:
        raise ValueError(f"pred_mask: expected shape {t.shape}, got {p.shape}")
    sp, st = _skeleton(p), _skeleton(t)
    if valid_mask is not None:
        v = np.asarray(valid_mask, bool)
        sp, st = sp & v, st & v
    n_sp, n_st = int(sp.sum()), int(st.sum())
    prec = float((sp & _near(t, tol_px)).sum() / n_sp) if n_sp else float("nan")
    rec = float((st & _near(p, tol_px)).sum() / n_st) if n_st else float("nan")
    f1 = 2 * prec * rec / (prec + rec) if prec + rec > 0 else float("nan")
    lp = _length(sp, p if valid_mask is None else p & v) if n_sp else 0.0
    lt = _length(st, t if valid_mask is None else t & v) if n_st else 0.0
    ap, at = int(p.sum()), int(t.sum())
    return dict(precision=prec, recall=rec, f1=f1, length_pred_px=lp, length_truth_px=lt,
                length_ratio=lp / lt if lt else float("nan"), area_pred_px=ap,
                area_truth_px=at, area_ratio=ap / at if at else float("nan"))


def rasterise_polyline(points_xy, shape):
    """Boolean image of a polyline drawn 1 px wide (8-connected).

    Parameters
    ----------
    points_xy : (K, 2) array_like of float
        Vertices, x (column) then y (row), px.
    shape : tuple of int

    Returns
    -------
    line : (M, N) ndarray of bool
    """
    from skimage.draw import line
    pts = np.rint(np.asarray(points_xy, float)).astype(int)
    out = np.zeros(shape, bool)
    for (x0, y0), (x1, y1) in zip(pts[:-1], pts[1:]):
        rr, cc = line(y0, x0, y1, x1)
        ok = (rr >= 0) & (rr < shape[0]) & (cc >= 0) & (cc < shape[1])
        out[rr[ok], cc[ok]] = True
    return out


def polyline_coverage(points_xy, detected_mask, *, tol_px=3.0):
    """Share of a polyline's pixels lying within ``tol_px`` of a detected crack.

    Parameters
    ----------
    points_xy : (K, 2) array_like of float
        Polyline vertices, x then y, px.
    detected_mask : (M, N) array_like of bool
    tol_px : float

    Returns
    -------
    coverage : float
        In [0, 1].

    Examples
    --------
    >>> m = np.zeros((10, 30), bool); m[5, 0:15] = True
    >>> round(polyline_coverage([(0, 4), (29, 4)], m, tol_px=1.5), 3)  # x = 0 .. 15 of 30
    0.533
    """
    d = np.asarray(detected_mask, bool)
    line = rasterise_polyline(points_xy, d.shape)
    n = int(line.sum())
    return float((line & _near(d, tol_px)).sum() / n) if n else float("nan")
