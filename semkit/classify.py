"""Crack classification, public API: pre-existing and post-test types, training, user labels.

Pre-existing (:func:`classify_pre`, in ``semkit.classify_pre``): He et al.'s rule against a
grain map (inter / intra / trans-granular).

Post-test (:func:`classify_post`): tensile / shear / mixed from morphology, in two stages.

1. At every skeleton pixel, ``semkit.classify_features.post_features`` measures the local
   aperture and its variation, the dark and skeleton densities, endpoints, excess dark area
   (debris), the scatter of the skeleton about its local line, and from the grey image the
   dark fill of the mask and parallel dark layers across the trace. A logistic model gives
   P(tensile) per pixel.
2. ``semkit.classify_traces`` joins skeleton branches that continue each other into traces
   (ideally one crack each; a crossing crack is another trace) and summarises P(tensile)
   and the aperture along each trace; a softmax model types the whole trace tensile, shear
   or mixed (``semkit.classify_model``). Every crack pixel takes its trace's type.

The model is a small JSON dict; :func:`train_post` fits it from labelled cracks (``semkit
classify --train``).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .classify_features import (
    FEATURE_NAMES,
    LINK_PX,
    WINDOW_PX,
    crack_clusters,
    nearest_in_cluster,
    post_features,
    skeleton_of,
)
from .classify_model import (
    DEFAULT_POST_MODEL,
    load_model,
    p_tensile,
    save_model,
    trace_probabilities,
    train_post,
)
from .classify_pre import INTER_MIN_FRACTION, INTRA_MIN_FRACTION, classify_pre
from .classify_traces import RUN_SMOOTH_PX, TRACE_FEATURE_NAMES, trace_features
from .errors import InputError

__all__ = ["classify_pre", "post_features", "classify_post", "train_post", "save_model",
           "load_model", "apply_labels", "read_labels", "crack_clusters", "classify_stage",
           "train_from_folder", "DEFAULT_POST_MODEL", "FEATURE_NAMES", "INTER_MIN_FRACTION",
           "INTRA_MIN_FRACTION"]

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
    features. Traces (``semkit.classify_traces``) are typed by the softmax model on their
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


def read_labels(path):
    """Read user crack labels ``image, crack_id, type`` (CSV); checks columns and types."""
    try:
        df = pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot read labels ({exc})") from None
    miss = [c for c in ("image", "crack_id", "type") if c not in df.columns]
    if miss:
        raise InputError(f"{path}: missing column(s) {miss}; expected image, crack_id, type")
    bad = sorted(set(df["type"].astype(str)) - {"tensile", "shear", "mixed", "inter", "intra",
                                                 "trans"})
    if bad:
        raise InputError(f"{path}: column 'type' has {bad}; expected tensile|shear|mixed or "
                         f"inter|intra|trans")
    return df


def apply_labels(cracks, labels):
    """Override classified types with user labels (user labels win, confidence 1).

    Parameters
    ----------
    cracks : pandas.DataFrame
        ``cracks.csv`` rows with ``image, crack_id`` and ``type_post``/``type_pre``.
    labels : pandas.DataFrame
        ``image, crack_id, type``; a post-test type overrides ``type_post``, a pre-existing one
        ``type_pre``.

    Returns
    -------
    cracks : pandas.DataFrame
        Copy with overridden types, ``confidence`` 1 and ``type_source`` "user" on those rows
        (``model`` elsewhere). Per-pixel fractions of an overridden post type are set to it.
    """
    out = cracks.copy()
    if "type_source" not in out.columns:
        out["type_source"] = "model"
    key = out["image"].astype(str) + "\x00" + out["crack_id"].astype(int).astype(str)
    lk = labels["image"].astype(str) + "\x00" + labels["crack_id"].astype(int).astype(str)
    lab = dict(zip(lk, labels["type"].astype(str)))
    for i, k in zip(out.index, key):
        t = lab.get(k)
        if t is None:
            continue
        col = "type_post" if t in ("tensile", "shear", "mixed") else "type_pre"
        out.loc[i, col] = t
        out.loc[i, "confidence"] = 1.0
        out.loc[i, "type_source"] = "user"
        if col == "type_post" and "frac_tensile" in out.columns:
            for name, c in (("tensile", "frac_tensile"), ("shear", "frac_shear"),
                            ("mixed", "frac_mixed")):
                out.loc[i, c] = 1.0 if t == name else 0.0
    return out


# ----------------------------------------------------------------------------- pipeline stage
_POST_COLUMNS = ("frac_tensile", "frac_shear", "frac_mixed", "tensile_fraction",
                 "aperture_mean_px", "aperture_cv", "dark_density", "skeleton_density",
                 "endpoint_density", "excess_dark", "skeleton_scatter", "dark_fill",
                 "layer_lift", "layer_side")


def classify_stage(cracks, crack_labels, *, grey=None, pixel_size_um=1.0, model=None,
                   post=True, grain_labels=None):
    """Add crack types, confidences, features and partial-volume areas to ``cracks.csv`` rows.

    Parameters
    ----------
    cracks : pandas.DataFrame
        Rows of one image (``crack_id`` matches ``crack_labels``).
    crack_labels : (M, N) ndarray of int
    grey : (M, N) ndarray, optional
        Flattened, denoised grey image: gives ``area_pv_um2`` (partial-volume area), which
        :func:`semkit.damage.image_damage` uses for A_T and A_S.
    pixel_size_um : float
    model : dict, optional
        Post-test model (default :data:`DEFAULT_POST_MODEL`).
    post : bool
        Classify tensile/shear/mixed (False for pre-test images: ``type_post`` "unknown").
    grain_labels : (M, N) ndarray of int, optional
        Grain map: classify inter/intra/trans (``type_pre``).

    Returns
    -------
    cracks : pandas.DataFrame
        Copy with ``type_pre, type_post, confidence`` (post-test confidence, or the pre-existing
        one when only that was classified), ``confidence_pre``, the post features,
        ``frac_tensile, frac_shear, frac_mixed`` and ``area_pv_um2``.
    """
    from .damage import typed_areas
    out = cracks.copy()
    lab = np.asarray(crack_labels)
    ids = out["crack_id"].to_numpy() if len(out) else np.zeros(0, int)
    if grey is not None and len(out):
        a = typed_areas(grey, lab).set_index("crack_id")
        out["area_pv_um2"] = a["area_pv_px"].reindex(ids).to_numpy() * pixel_size_um ** 2
    if grain_labels is not None and len(out):
        t, _ = classify_pre(lab, grain_labels)
        t = t.set_index("crack_id").reindex(ids)
        out["type_pre"] = t["type_pre"].fillna("unknown").to_numpy()
        out["confidence_pre"] = t["confidence"].to_numpy()
        out["confidence"] = out["confidence_pre"]
    if post and len(out):
        t, _ = classify_post(lab, image=grey, model=model)
        t = t.set_index("crack_id").reindex(ids)
        out["type_post"] = t["type_post"].fillna("unknown").to_numpy()
        out["confidence"] = t["confidence"].to_numpy()
        for c in _POST_COLUMNS:
            out[c] = t[c].to_numpy()
    elif len(out):
        out["type_post"] = "unknown"
    return out


def train_from_folder(folder, labels, *, pixel_size_um=None, seed=None, **options):
    """Fit a post-test model from ``labels.csv`` rows referring to a ``semkit analyse`` run.

    The images named in ``labels`` are re-analysed with the same pipeline options (crack ids
    are deterministic), and :func:`train_post` fits the model on the labelled cracks.

    Parameters
    ----------
    folder : path
        The images (with ``manifest.csv`` if the analysis had one).
    labels : pandas.DataFrame
        ``image, crack_id, type`` (post-test types are used).
    pixel_size_um : float, optional
    seed : int, optional
    **options
        Pipeline options (:class:`semkit.pipeline.AnalysisOptions` fields).

    Returns
    -------
    model : dict
    """
    import pathlib

    from .io import load_image, read_manifest
    from .pipeline import AnalysisOptions, CrackAnalysis
    folder = pathlib.Path(folder)
    post = labels[labels["type"].astype(str).isin(["tensile", "shear", "mixed"])]
    if post.empty:
        raise InputError("labels: no tensile/shear/mixed rows to train on")
    man = read_manifest(folder)
    mrows = {} if man is None else {str(r["image"]): r for r in man.to_dict("records")}
    opts = AnalysisOptions(**options)
    samples = []
    for name, g in post.groupby("image"):
        path = folder / str(name)
        if not path.is_file():
            raise InputError(f"labels: image {name!r} not found in {folder}")
        li = load_image(path, manifest_row=mrows.get(str(name)), pixel_size_um=pixel_size_um)
        a = CrackAnalysis(li.image, pixel_size_um=li.pixel_size_um, name=str(name), options=opts)
        samples.append((a.crack_labels, dict(zip(g["crack_id"].astype(int), g["type"])),
                        a.smooth))
    return train_post(samples, seed=seed)
