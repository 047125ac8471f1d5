"""The post-test crack model: per-pixel P(tensile), then a tensile/shear/mixed model per trace.

Two stages, both small and JSON-able (no pickles):

1. a logistic model of P(tensile) at each skeleton pixel from its morphology
   (:data:`semkit.classify.features.FEATURE_NAMES`), fitted by IRLS on the tensile and shear
   pixels of labelled cracks;
2. a multinomial logistic (softmax) model that types each trace as tensile, shear or mixed
   from the along-trace summary of stage 1 (:data:`semkit.classify.traces.TRACE_FEATURE_NAMES`)
   and the pairwise products of a few of them (``trace_products``: a mixed crack has both a
   tensile-looking and a shear-looking stretch, an interaction a linear model cannot express).
   It is fitted by L2-regularised gradient descent, each trace weighted by the square root of
   its labelled area.

:func:`train_post` fits both (``semkit classify --train``); :func:`save_model` and
:func:`load_model` write and read the JSON form.
"""
from __future__ import annotations

import json
import os

import numpy as np

from ..errors import InputError
from .features import FEATURE_NAMES, LINK_PX, WINDOW_PX, post_features, skeleton_of
from .traces import TRACE_FEATURE_NAMES, trace_features

__all__ = ["DEFAULT_POST_MODEL", "train_post", "save_model", "load_model", "p_tensile",
           "trace_probabilities", "TYPE_CODES"]

#: type codes of the per-pixel type images.
TYPE_CODES = {"tensile": 1, "shear": 2, "mixed": 3}
#: trace features whose pairwise products (with squares) enter the trace model.
TRACE_PRODUCTS = ("tensile_share", "chunk_p_min", "chunk_p_max", "log_aperture_mean")
#: L2 penalty of the per-pixel logistic model and of the trace model (standardised features).
PIXEL_L2 = 1e-3
TRACE_L2 = 1e-3
#: gradient-descent steps (step size 1) of the trace model.
TRACE_STEPS = 1500
#: at most this many skeleton pixels (subsampled with ``seed``) fit the per-pixel model.
MAX_PIXELS = 200_000

#: default post-test model, fitted with :func:`train_post` on 72 synthetic post-test images
#: (``semkit.synth.make_sem_image((384, 512), stage="post", n_cracks=12, seed=s)`` for
#: s = 100..111 and 1000..1059; objects and smoothed grey image from
#: ``semkit.analysis.analyse_image``; labels = the true type of each crack pixel).
#: docs/semkit_science.md says how it scores on the held-out seeds 200..211.
DEFAULT_POST_MODEL = None  # filled below from _DEFAULT_JSON


def _standardise(X, mean, scale):
    z = (X - np.asarray(mean)) / np.asarray(scale)
    return np.where(np.isfinite(z), z, 0.0)  # a feature not measured: neutral


def p_tensile(X, model):
    """P(tensile) of skeleton pixels with features ``X`` (stage 1)."""
    s = _standardise(X, model["mean"], model["scale"]) @ np.asarray(model["coef"])
    return 1.0 / (1.0 + np.exp(-np.clip(s + float(model["intercept"]), -50, 50)))


def _expand(F, products):
    """Trace features plus the pairwise products (i <= j) of the named ones."""
    idx = [TRACE_FEATURE_NAMES.index(n) for n in products]
    extra = [F[:, i] * F[:, j] for a, i in enumerate(idx) for j in idx[a:]]
    return np.column_stack([F, *extra]) if extra else F


def trace_probabilities(F, model):
    """(T, 3) probabilities of tensile, shear, mixed per trace (stage 2)."""
    Z = _standardise(_expand(F, model["trace_products"]), model["trace_mean"],
                     model["trace_scale"])
    S = Z @ np.asarray(model["trace_coef"]) + np.asarray(model["trace_intercept"])
    S -= S.max(axis=1, keepdims=True)
    e = np.exp(S)
    return e / e.sum(axis=1, keepdims=True)


def _fit_logistic(X, y, *, l2=PIXEL_L2, n_iter=50):
    """Newton-IRLS logistic regression on standardised features; returns (coef, intercept)."""
    n, d = X.shape
    A = np.column_stack([X, np.ones(n)])
    beta = np.zeros(d + 1)
    reg = l2 * np.eye(d + 1)
    reg[-1, -1] = 0.0
    for _ in range(n_iter):
        p = 1.0 / (1.0 + np.exp(-np.clip(A @ beta, -50, 50)))
        wgt = np.maximum(p * (1 - p), 1e-9)
        g = A.T @ (p - y) + reg @ beta * n
        H = (A * wgt[:, None]).T @ A + reg * n
        step = np.linalg.solve(H, g)
        beta -= step
        if np.max(np.abs(step)) < 1e-8:
            break
    return beta[:-1], float(beta[-1])


def _fit_softmax(Z, y, w, *, l2=TRACE_L2, steps=TRACE_STEPS, k=3):
    """Weighted multinomial logistic regression by gradient descent (deterministic)."""
    n, d = Z.shape
    A = np.column_stack([Z, np.ones(n)])
    B = np.zeros((d + 1, k))
    Y = np.eye(k)[y]
    w = np.asarray(w, float) / max(float(np.sum(w)), 1e-12)
    reg = np.full(d + 1, l2)
    reg[-1] = 0.0
    for _ in range(steps):
        S = A @ B
        S -= S.max(axis=1, keepdims=True)
        P = np.exp(S)
        P /= P.sum(axis=1, keepdims=True)
        B -= A.T @ ((P - Y) * w[:, None]) + reg[:, None] * B
    return B[:-1], B[-1]


def _pixel_codes(lab, labels):
    """Type code (0 none) of every crack pixel from a {crack_id: type} dict or a label image;
    crack pixels a label image leaves at 0 take the nearest labelled pixel's code."""
    from scipy import ndimage as ndi
    n = int(lab.max())
    if isinstance(labels, dict):
        code = np.zeros(n + 1, np.int64)
        for k, v in labels.items():
            if int(k) <= n and str(v) in TYPE_CODES:
                code[int(k)] = TYPE_CODES[str(v)]
        return code[lab]
    pix = np.asarray(labels).astype(np.int64)
    if pix.shape != lab.shape:
        raise InputError(f"label image: expected shape {lab.shape}, got {pix.shape}")
    pix = np.where(lab > 0, pix, 0)
    if (pix > 0).any() and ((lab > 0) & (pix == 0)).any():
        _, (ir, ic) = ndi.distance_transform_edt(pix == 0, return_indices=True)
        pix = np.where(lab > 0, pix[ir, ic], 0)
    return pix


def train_post(samples, *, window_px=WINDOW_PX, link_px=LINK_PX, seed=None):
    """Fit the post-test model from labelled cracks.

    Parameters
    ----------
    samples : iterable of (crack_labels, labels) or (crack_labels, labels, image)
        ``crack_labels`` an (M, N) int array of crack objects and ``labels`` a dict
        {crack_id: "tensile"|"shear"|"mixed"} (unlabelled objects are ignored), or an (M, N)
        label image of type codes (0 none, 1 tensile, 2 shear, 3 mixed) per pixel (crack
        pixels left at 0 take the nearest labelled pixel's type); ``image`` the flattened,
        denoised grey image (for the grey-level features).
    window_px, link_px : int, float
        Feature window and cluster link distance stored in the model.
    seed : int, optional
        Seed of the subsampling of skeleton pixels (at most 200 000 are used).

    Returns
    -------
    model : dict
        :data:`DEFAULT_POST_MODEL` form.

    Raises
    ------
    InputError
        No tensile or no shear pixels among the labels.
    """
    Xs, ys, per_sample = [], [], []
    for sample in samples:
        lab = np.asarray(sample[0])
        image = sample[2] if len(sample) > 2 else None
        pix_code = _pixel_codes(lab, sample[1])
        skel = skeleton_of(lab > 0)
        rr, cc, X = post_features(lab, image=image, skeleton=skel, window_px=window_px)
        y = pix_code[rr, cc]
        sel = (y == 1) | (y == 2)
        Xs.append(X[sel])
        ys.append((y[sel] == 1).astype(float))
        per_sample.append((lab, skel, rr, cc, X, pix_code))
    X = np.concatenate(Xs) if Xs else np.zeros((0, len(FEATURE_NAMES)))
    y = np.concatenate(ys) if ys else np.zeros(0)
    if (y == 1).sum() == 0 or (y == 0).sum() == 0:
        raise InputError("labels: training needs both tensile and shear cracks")
    if len(y) > MAX_PIXELS:
        keep = np.random.default_rng(seed).choice(len(y), MAX_PIXELS, replace=False)
        X, y = X[keep], y[keep]
    mean = np.nan_to_num(np.nanmean(X, axis=0))
    scale = np.nan_to_num(np.nanstd(X, axis=0))
    scale[scale == 0] = 1.0
    coef, intercept = _fit_logistic(np.nan_to_num((X - mean) / scale), y)
    model = {"version": 2, "features": list(FEATURE_NAMES), "mean": mean.tolist(),
             "scale": scale.tolist(), "coef": coef.tolist(), "intercept": intercept,
             "window_px": int(window_px), "link_px": float(link_px)}
    # stage 2: one row per trace with labelled pixels; label = its majority type
    Fs, ts, ws = [], [], []
    for lab, skel, rr, cc, Xi, pix_code in per_sample:
        pix, F, _ = trace_features(lab, rr, cc, p_tensile(Xi, model), skeleton=skel,
                                   link_px=link_px)
        sel = (pix >= 0) & (pix_code > 0)
        M = np.zeros((len(F), 4))
        np.add.at(M, (pix[sel], pix_code[sel]), 1.0)
        ok = (M[:, 1:].sum(axis=1) > 0) & np.isfinite(F).all(axis=1)
        Fs.append(F[ok])
        ts.append(M[ok, 1:].argmax(axis=1))
        ws.append(np.sqrt(M[ok, 1:].sum(axis=1)))
    products = list(TRACE_PRODUCTS)
    E = _expand(np.concatenate(Fs), products)
    t_mean = E.mean(axis=0)
    t_scale = E.std(axis=0)
    t_scale[t_scale == 0] = 1.0
    tc, ti = _fit_softmax((E - t_mean) / t_scale, np.concatenate(ts), np.concatenate(ws))
    model.update(trace_features=list(TRACE_FEATURE_NAMES), trace_products=products,
                 trace_mean=t_mean.tolist(), trace_scale=t_scale.tolist(),
                 trace_coef=tc.tolist(), trace_intercept=ti.tolist())
    return model


def save_model(model, path):
    """Write a post-test model as JSON (temporary file, then rename)."""
    path = str(path)
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(model, fh, indent=1)
    os.replace(tmp, path)


def check_model(model, where="crack model"):
    """Check a post-test model's fields and sizes; returns it."""
    need = ("mean", "scale", "coef", "intercept", "trace_products", "trace_mean",
            "trace_scale", "trace_coef", "trace_intercept")
    miss = [k for k in need if k not in model]
    if miss:
        raise InputError(f"{where} lacks field(s) {miss} (a model of an older semkit: "
                         f"retrain it with `semkit classify --train`)")
    if len(model["coef"]) != len(FEATURE_NAMES):
        raise InputError(f"{where} has {len(model['coef'])} coefficients, "
                         f"expected {len(FEATURE_NAMES)}")
    n_t = len(TRACE_FEATURE_NAMES) + sum(range(len(model["trace_products"]) + 1))
    if np.shape(model["trace_coef"]) != (n_t, 3) or len(model["trace_mean"]) != n_t:
        raise InputError(f"{where}: trace model has shape {np.shape(model['trace_coef'])}, "
                         f"expected ({n_t}, 3)")
    return model


def load_model(path):
    """Read a post-test model JSON written by :func:`save_model`; checks its fields."""
    try:
        with open(path) as fh:
            model = json.load(fh)
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot read crack model ({exc})") from None
    if not isinstance(model, dict):
        raise InputError(f"{path}: crack model is not a JSON object")
    return check_model(model, where=str(path))


_DEFAULT_JSON = os.path.join(os.path.dirname(__file__), "model.json")
DEFAULT_POST_MODEL = (load_model(_DEFAULT_JSON) if os.path.exists(_DEFAULT_JSON)
                      else None)
