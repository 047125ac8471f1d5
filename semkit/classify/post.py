"""Post-test crack typing (tensile / shear / mixed) from morphology, in two stages.

1. At every skeleton pixel, :func:`semkit.classify.features.post_features` measures the local
   aperture and its variation, the dark and skeleton densities, endpoints, excess dark area
   (debris), the scatter of the skeleton about its local line, and from the grey image the
   dark fill of the mask and parallel dark layers across the trace. A logistic model gives
   P(tensile) per pixel.
2. :mod:`semkit.classify.traces` joins skeleton branches that continue each other into traces
   (ideally one crack each; a crossing crack is another trace) and summarises P(tensile)
   and the aperture along each trace; a softmax model types the whole trace tensile, shear
   or mixed (:mod:`semkit.classify.model`). Every crack pixel takes its trace's type.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import InputError
from .features import LINK_PX, WINDOW_PX, nearest_in_cluster, post_features, skeleton_of
from .model import DEFAULT_POST_MODEL, p_tensile, trace_probabilities
from .traces import RUN_SMOOTH_PX, TRACE_FEATURE_NAMES, trace_features

__all__ = ["classify_post", "MIN_TRACE_PX"]

#: traces with fewer skeleton pixels than this take the smoothed per-pixel decision (too
#: short to be typed from their along-trace features; never mixed).
MIN_TRACE_PX = 20
_TABLE_COLUMNS = ["crack_id", "type_post", "confidence", "frac_tensile", "frac_shear",
                  "frac_mixed", "tensile_fraction", "aperture_mean_px", "aperture_cv",
                  "dark_density", "skeleton_density", "endpoint_density", "excess_dark",
                  "skeleton_scatter", "dark_fill", "layer_lift", "layer_side", "tortuosity"]


def _pixel_decision(lab, rr, cc, p, *, link_px):
    """1 tensile / 2 shear per crack pixel: the decision p > 0.5 smoothed over RUN_SMOOTH_PX
    along the skeleton, taken from the nearest skeleton pixel of the pixel's cluster."""
    from scipy import ndimage as ndi
    sk = np.zeros(lab.shape)
    sk[rr, cc] = 1.0
    pv = np.zeros(lab.shape)
    pv[rr, cc] = p > 0.5
    num = ndi.uniform_filter(pv, RUN_SMOOTH_PX, mode="constant")[rr, cc]
    den = ndi.uniform_filter(sk, RUN_SMOOTH_PX, mode="constant")[rr, cc]
    seed = np.full(lab.shape, -1, np.int64)
    seed[rr, cc] = np.where(num / np.maximum(den, 1e-12) > 0.5, 1, 2)
    return nearest_in_cluster(lab, seed, link_px=link_px)


def classify_post(crack_labels, *, image=None, skeleton=None, model=None):
    """Classify post-test cracks as tensile, shear or mixed from their morphology.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects 1..n.
    image : (M, N) ndarray, optional
        Flattened, denoised grey image (``CrackAnalysis.smooth``). Without it the grey-level
        features are neutral and the typing is less accurate.
    skeleton : (M, N) ndarray of bool, optional
    model : dict, optional
        :data:`DEFAULT_POST_MODEL` form (from :func:`train_post` / :func:`load_model`).

    Returns
    -------
    table : pandas.DataFrame
        One row per object: ``crack_id, type_post`` (area-majority type of its pixels),
        ``confidence, frac_tensile, frac_shear, frac_mixed`` (shares of the object's pixels
        typed so: an object where a tensile and a shear crack cross is split, not averaged),
        ``tensile_fraction`` (share of skeleton with P(tensile) > 0.5), the object means of
        the features ``aperture_mean_px, aperture_cv, dark_density, skeleton_density,
        endpoint_density, excess_dark, skeleton_scatter, dark_fill, layer_lift,
        layer_side`` and ``tortuosity``.
    type_image : (M, N) ndarray of int8
        Type per pixel: 0 none, 1 tensile, 2 shear, 3 mixed.

    Notes
    -----
    p_T = 1 / (1 + exp(-(beta . z + beta_0))) per skeleton pixel, z its standardised
    features. Traces (``semkit.classify.traces``) are typed by the softmax model on their
    along-trace features; each crack pixel takes the type of the trace of its nearest
    skeleton pixel (small objects within ``link_px`` of a crack belong to it). Pixels of a
    cluster without a trace take the smoothed per-pixel decision. ``type_post`` is the
    object's area-majority type; confidence = the mean, over the object's pixels, of the
    probability of its trace's type x the majority share.
    """
    model = DEFAULT_POST_MODEL if model is None else model
    lab = np.asarray(crack_labels)
    if lab.ndim != 2:
        raise InputError(f"crack_labels: expected a 2-D array, got shape {lab.shape}")
    n = int(lab.max())
    type_img = np.zeros(lab.shape, np.int8)
    if n == 0:
        return pd.DataFrame(columns=_TABLE_COLUMNS), type_img
    mask = lab > 0
    link_px = float(model.get("link_px", LINK_PX))
    skel = skeleton_of(mask) if skeleton is None else (np.asarray(skeleton, bool) & mask)
    rr, cc, X = post_features(lab, image=image, skeleton=skel,
                              window_px=int(model.get("window_px", WINDOW_PX)))
    p = p_tensile(X, model)
    pix, F, _ = trace_features(lab, rr, cc, p, skeleton=skel, link_px=link_px)
    prob = trace_probabilities(F, model) if len(F) else np.zeros((0, 3))
    code_tr = (prob.argmax(axis=1) + 1).astype(np.int8)
    # too short a trace to read its morphology along it: the per-pixel decision instead
    short_tr = ~(np.nan_to_num(F[:, TRACE_FEATURE_NAMES.index("log_length")], nan=0.0)
                 >= np.log(MIN_TRACE_PX)) if len(F) else np.zeros(0, bool)
    has = (pix >= 0) & ~short_tr[np.maximum(pix, 0)]
    type_img[has] = code_tr[pix[has]]
    pconf = np.zeros(lab.shape)
    pconf[has] = prob.max(axis=1)[pix[has]]
    left = mask & ~has
    if left.any():  # clusters without a trace: the smoothed per-pixel decision
        dec = _pixel_decision(lab, rr, cc, p, link_px=link_px)
        type_img[left] = np.maximum(dec[left], 0)
        pconf[left] = 0.5
    ids_sk = lab[rr, cc]
    cnt = np.bincount(ids_sk, minlength=n + 1).astype(float)
    ft_obj = np.bincount(ids_sk, weights=(p > 0.5).astype(float), minlength=n + 1) / \
        np.maximum(cnt, 1)
    left = mask & (type_img == 0)  # objects without any skeleton pixel: their own f_T
    if left.any():
        type_img[left] = np.where(ft_obj >= 0.5, 1, 2).astype(np.int8)[lab[left]]
    area = np.bincount(lab.ravel(), minlength=n + 1).astype(float)
    fr = np.stack([np.bincount(lab[type_img == k], minlength=n + 1) / np.maximum(area, 1)
                   for k in (1, 2, 3)], axis=1)
    conf_obj = np.bincount(lab.ravel(), weights=pconf.ravel(), minlength=n + 1) / \
        np.maximum(area, 1)
    feats = np.column_stack([np.exp(X[:, 0]), X[:, 1:10]])
    fmean = np.stack([np.bincount(ids_sk, weights=np.nan_to_num(feats[:, k]), minlength=n + 1)
                      / np.maximum(cnt, 1) for k in range(feats.shape[1])], axis=1)
    if image is None:
        fmean[:, 7:] = np.nan
    tort = _tortuosity(lab, skel, n)
    names = np.array(["unknown", "tensile", "shear", "mixed"])
    rows = []
    for cid in np.unique(lab[mask]):
        f = fr[cid]
        k = int(np.argmax(f)) + 1 if f.sum() > 0 else 0
        conf = float(np.clip(conf_obj[cid], 0, 1)) * f.max() if k else 0.0
        rows.append([int(cid), names[k], conf, *f.tolist(),
                     float(ft_obj[cid]) if cnt[cid] else np.nan, *fmean[cid].tolist(),
                     float(tort[cid])])
    return pd.DataFrame(rows, columns=_TABLE_COLUMNS), type_img


def _tortuosity(lab, skel, n):
    """Skeleton pixel count over the maximum Feret diameter, per object (1 = straight)."""
    from skimage.measure import regionprops
    out = np.full(n + 1, np.nan)
    sk_count = np.bincount(lab[skel], minlength=n + 1)
    for rp in regionprops(lab):
        out[rp.label] = sk_count[rp.label] / max(rp.feret_diameter_max, 1.0)
    return out
