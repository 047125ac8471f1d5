"""Score a crack mask against a hand-drawn one by centrelines.

Hand-painted crack masks are usually wider than the dark crack (a brush), so pixel overlap
punishes a detector that follows the dark pixels. Centrelines are compared instead: both masks
are skeletonised, a predicted skeleton pixel is correct when it lies within ``tol_px`` of the
true mask, and a true skeleton pixel is found when it lies within ``tol_px`` of the predicted
mask.
"""
from __future__ import annotations

import numpy as np

__all__ = ["centreline_scores", "chain_length_px"]


def chain_length_px(skel):
    """Length of a one-pixel skeleton: 4-neighbour steps 1, diagonal steps sqrt(2).

    A diagonal step is not counted where both pixels are already joined through a shared
    4-neighbour (a staircase corner).

    Examples
    --------
    >>> s = np.zeros((5, 5), bool); s[2, :] = True
    >>> float(chain_length_px(s))
    4.0
    >>> float(chain_length_px(np.eye(4, dtype=bool)))  # doctest: +ELLIPSIS
    4.24...
    """
    s = np.asarray(skel, bool)
    straight = (s[:, 1:] & s[:, :-1]).sum() + (s[1:] & s[:-1]).sum()
    d1 = s[1:, 1:] & s[:-1, :-1] & ~s[:-1, 1:] & ~s[1:, :-1]
    d2 = s[1:, :-1] & s[:-1, 1:] & ~s[:-1, :-1] & ~s[1:, 1:]
    return float(straight + np.sqrt(2) * (d1.sum() + d2.sum()))


def centreline_scores(pred_mask, true_mask, *, tol_px=2.0, valid_mask=None):
    """Centreline precision, recall, F1 and length ratio of a crack mask.

    Parameters
    ----------
    pred_mask, true_mask : (M, N) bool
    tol_px : float
        A skeleton pixel counts when it lies within this distance of the other mask.
    valid_mask : (M, N) bool, optional
        Only skeleton pixels inside it are counted (e.g. the imaged sample).

    Returns
    -------
    scores : dict
        ``precision, recall, f1`` of centreline pixels, ``length_ratio`` (predicted over true
        skeleton length, :func:`chain_length_px`), ``n_pred_px, n_true_px``. Precision is 1
        and F1 follows from recall when nothing is predicted and nothing is true.

    Examples
    --------
    >>> t = np.zeros((20, 20), bool); t[8:12, 2:18] = True
    >>> p = np.zeros((20, 20), bool); p[9:11, 2:18] = True
    >>> s = centreline_scores(p, t); (s["precision"], s["recall"], s["f1"])
    (1.0, 1.0, 1.0)
    """
    from scipy import ndimage as ndi

    from .skeleton import skeletonize
    p = np.asarray(pred_mask, bool)
    t = np.asarray(true_mask, bool)
    sp, st = skeletonize(p), skeletonize(t)
    if valid_mask is not None:
        sp &= valid_mask
        st &= valid_mask
    near_t = ndi.distance_transform_edt(~t) <= tol_px if t.any() else np.zeros_like(t)
    near_p = ndi.distance_transform_edt(~p) <= tol_px if p.any() else np.zeros_like(p)
    n_p, n_t = int(sp.sum()), int(st.sum())
    precision = float(near_t[sp].mean()) if n_p else 1.0
    recall = float(near_p[st].mean()) if n_t else 1.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    lt = chain_length_px(st)
    return {"precision": precision, "recall": recall, "f1": float(f1),
            "length_ratio": chain_length_px(sp) / lt if lt > 0 else float("nan"),
            "n_pred_px": n_p, "n_true_px": n_t}
