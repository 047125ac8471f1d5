"""The post-test crack model: calibrated tensile / shear / mixed probabilities per crack group,
and the range of features it was trained on.

Two stages, both small and JSON-able (no pickle):

1. a logistic model of P(tensile) at each skeleton pixel from the morphology in the box around
   it (:data:`semkit.classify.morphology.LOCAL_NAMES`), fitted on the pixels of tensile and
   shear stretches;
2. a multinomial logistic model that types each crack group from its morphology
   (:data:`semkit.classify.morphology.FEATURE_NAMES`), the mean and the 20th / 80th
   percentiles of stage 1 along it and the share above 0.5 (:data:`STAGE2_NAMES`: a mixed
   crack has a tensile and a shear stretch), plus pairwise products of a few of them
   (:data:`PRODUCTS`). Each group is weighted by the square root of its labelled area.

The stage-2 scores are divided by a temperature fitted on a separate calibration set (minimum
log loss), so the probabilities are calibrated. The built-in model also records
``image_shift_sd``: how far the tensile-versus-shear log-odds of a whole image lean one way
on renderings unlike its training ones (:func:`fit_image_shift`), which widens the P band of
:mod:`semkit.damage_confidence`; a model without it (a user's own) gives independent draws.
The model stores, per stage-2 feature, the range of the training groups (0.5-99.5 % quantiles
widened by ``RANGE_PAD`` of their span): a group outside it is reported as untyped
(``type_post_ok = False``, the feature named).

:func:`train_post` fits it (``semkit classify --train``); :func:`save_model` /
:func:`load_model` write and read the JSON form.
"""
from __future__ import annotations

import json
import os

import numpy as np

from .. import config
from ..errors import InputError
from .morphology import FEATURE_NAMES, LOCAL_NAMES, crack_morphology, group_quantile

__all__ = ["DEFAULT_POST_MODEL", "train_post", "fit_post", "calibrate", "fit_image_shift",
           "shift_sd_mle", "save_model", "load_model", "check_model", "type_probabilities",
           "group_design", "out_of_range", "image_samples", "TYPE_CODES", "TYPES", "PRODUCTS",
           "STAGE2_NAMES", "VERSION"]

VERSION = 3
TYPES = ("tensile", "shear", "mixed")
TYPE_CODES = {"tensile": 1, "shear": 2, "mixed": 3}
#: stage-2 features: the group morphology and the summary of stage 1 along it.
STAGE2_NAMES = (*FEATURE_NAMES, "p_mean", "p_lo", "p_hi", "p_share")
#: stage-2 features whose pairwise products (with squares) enter the model.
PRODUCTS = ("p_lo", "p_hi", "log_aperture", "thin_share")
#: inverse L2 strengths of the two logistic models (standardised features).
C_PIXEL = 1.0
C_GROUP = 1.0
#: at most this many skeleton pixels (subsampled with the seed) fit stage 1.
MAX_PIXELS = 200_000
#: training-range quantiles and the padding (share of the span) of the out-of-range check.
RANGE_Q = (0.005, 0.995)
RANGE_PAD = 0.1
#: a group of at least this share of labelled pixels takes the majority label in training.
MIN_LABELLED = 0.5

#: default post-test model (``semkit/classify/model.json``), fitted by
#: ``benchmarks/typing_model.py train`` on the domain-randomised training family of
#: ``benchmarks/typing/render.py`` (docs/semkit_science.md).
DEFAULT_POST_MODEL = None  # filled below from _DEFAULT_JSON


def _expand(X, names, products):
    idx = [names.index(p) for p in products]
    cols = [X]
    for a in range(len(idx)):
        for b in range(a, len(idx)):
            cols.append((X[:, idx[a]] * X[:, idx[b]])[:, None])
    return np.hstack(cols)


def _z(X, mean, scale):
    z = (X - np.asarray(mean)) / np.asarray(scale)
    return np.where(np.isfinite(z), z, 0.0)  # a feature not measured: neutral


def _softmax(s):
    s = s - s.max(axis=1, keepdims=True)
    e = np.exp(s)
    return e / e.sum(axis=1, keepdims=True)


def pixel_p_tensile(X_local, model):
    """Stage 1: P(tensile) of skeleton pixels from their local features."""
    s = _z(np.asarray(X_local, float), model["pixel_mean"], model["pixel_scale"]) @ \
        np.asarray(model["pixel_coef"]) + float(model["pixel_intercept"])
    return 1.0 / (1.0 + np.exp(-np.clip(s, -50, 50)))


def group_design(F, local, model):
    """Stage-2 features of every group (rows indexed like ``F``): :data:`STAGE2_NAMES`."""
    m = len(F)
    p = pixel_p_tensile(local["X"], model)
    g = local["group"]
    cnt = np.bincount(g, minlength=m)
    mean = np.bincount(g, weights=p, minlength=m) / np.maximum(cnt, 1)
    share = np.bincount(g, weights=(p > 0.5).astype(float), minlength=m) / np.maximum(cnt, 1)
    D = np.column_stack([F, mean, group_quantile(g, p, 0.2, m), group_quantile(g, p, 0.8, m),
                         share])
    D[cnt == 0, len(FEATURE_NAMES):] = np.nan
    return D


def _scores(D, model):
    E = _expand(np.asarray(D, float), list(STAGE2_NAMES), list(model["products"]))
    return _z(E, model["mean"], model["scale"]) @ np.asarray(model["coef"]).T + \
        np.asarray(model["intercept"])


def type_probabilities(D, model):
    """Calibrated P(tensile), P(shear), P(mixed) of groups with stage-2 features ``D``."""
    if len(D) == 0:
        return np.zeros((0, 3))
    return _softmax(_scores(D, model) / float(model["temperature"]))


def out_of_range(D, model):
    """For each row, "" when every stage-2 feature lies in the trained range, else a note
    naming the feature furthest outside it (in units of the range's span)."""
    D = np.asarray(D, float)
    lo, hi = np.asarray(model["range_lo"]), np.asarray(model["range_hi"])
    excess = np.maximum(lo - D, D - hi) / np.maximum(hi - lo, 1e-12)
    excess = np.where(np.isfinite(excess), excess, -1.0)
    notes = []
    for i, row in enumerate(excess):
        k = int(np.argmax(row)) if row.size else 0
        if row.size and row[k] > 0:
            notes.append(f"{STAGE2_NAMES[k]} {D[i, k]:.3g} outside the trained range "
                         f"{lo[k]:.3g}..{hi[k]:.3g}")
        else:
            notes.append("")
    return notes


def _pixel_codes(lab, labels):
    n = int(lab.max())
    if isinstance(labels, dict):
        code = np.zeros(n + 1, np.int64)
        for k, v in labels.items():
            if 0 < int(k) <= n and str(v) in TYPE_CODES:
                code[int(k)] = TYPE_CODES[str(v)]
        return code[lab]
    pix = np.asarray(labels).astype(np.int64)
    if pix.shape != lab.shape:
        raise InputError(f"label image: expected shape {lab.shape}, got {pix.shape}")
    return np.where(lab > 0, pix, 0)


def image_samples(crack_labels, labels, *, modes=None, image=None, skeleton=None,
                  background=None, crack_level=None):
    """The training material of one image.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
    labels : dict or (M, N) ndarray
        ``{crack_id: "tensile"|"shear"|"mixed"}`` or a per-pixel type-code image (0 none,
        1 tensile, 2 shear, 3 mixed).
    modes : (M, N) ndarray, optional
        Per-pixel local mode (1 tensile, 2 shear stretch; 0 unknown) for stage 1; default the
        tensile and shear cracks of ``labels``.
    image, skeleton, background, crack_level
        As :func:`semkit.classify.morphology.crack_morphology`.

    Returns
    -------
    sample : dict
        ``F, local`` (morphology), ``pixel_y`` (stage-1 label per skeleton pixel: 1 tensile,
        0 shear, -1 unknown), ``group_ids, group_y, group_area`` (groups with at least
        ``MIN_LABELLED`` labelled pixels, their majority type 0/1/2 and labelled area).
    """
    lab = np.asarray(crack_labels)
    n = int(lab.max())
    pix = _pixel_codes(lab, labels)
    mode = np.where(pix <= 2, pix, 0) if modes is None else np.asarray(modes)
    group_of, F, local = crack_morphology(lab, image=image, skeleton=skeleton,
                                          background=background, crack_level=crack_level)
    md = mode[local["rr"], local["cc"]]
    pixel_y = np.where(md == 1, 1, np.where(md == 2, 0, -1))
    grp = group_of[lab]
    M = np.zeros((n + 1, 4))
    np.add.at(M, (grp[lab > 0], pix[lab > 0]), 1.0)
    tot = M.sum(axis=1)
    ok = (M[:, 1:].sum(axis=1) >= MIN_LABELLED * np.maximum(tot, 1)) & (tot > 0)
    ok &= np.isfinite(F[:, 0])
    ids = np.flatnonzero(ok)
    return dict(F=F, local=local, pixel_y=pixel_y, group_ids=ids,
                group_y=M[ids, 1:].argmax(axis=1), group_area=M[ids, 1:].sum(axis=1))


def _logistic(X, y, w, c, seed):
    from sklearn.linear_model import LogisticRegression
    return LogisticRegression(C=c, max_iter=5000, random_state=seed).fit(X, y,
                                                                         sample_weight=w)


def fit_post(samples, *, c_pixel=C_PIXEL, c_group=C_GROUP, seed=0, products=PRODUCTS):
    """Fit both stages and the trained ranges from :func:`image_samples` dicts (temperature 1;
    see :func:`calibrate`)."""
    Xp = np.concatenate([s["local"]["X"] for s in samples])
    yp = np.concatenate([s["pixel_y"] for s in samples])
    keep = yp >= 0
    Xp, yp = Xp[keep], yp[keep]
    if not ((yp == 1).any() and (yp == 0).any()):
        raise InputError("labels: training needs both tensile and shear cracks")
    rng = np.random.default_rng(seed)
    if len(yp) > MAX_PIXELS:
        sel = np.sort(rng.choice(len(yp), MAX_PIXELS, replace=False))
        Xp, yp = Xp[sel], yp[sel]
    pm = np.nanmean(Xp, axis=0)
    ps = np.nanstd(Xp, axis=0)
    pm, ps = np.nan_to_num(pm), np.where(np.nan_to_num(ps) > 0, np.nan_to_num(ps), 1.0)
    lr = _logistic(_z(Xp, pm, ps), yp, None, c_pixel, seed)
    model = {"version": VERSION, "types": list(TYPES), "local_features": list(LOCAL_NAMES),
             "features": list(STAGE2_NAMES), "products": list(products),
             "pixel_mean": pm.tolist(), "pixel_scale": ps.tolist(),
             "pixel_coef": lr.coef_[0].tolist(), "pixel_intercept": float(lr.intercept_[0])}
    D, y, area = _group_rows(samples, model)
    if len(set(y.tolist())) < 2:
        raise InputError("labels: training needs at least two crack types")
    fill = np.nanmean(D, axis=0)
    E = _expand(np.where(np.isfinite(D), D, fill), list(STAGE2_NAMES), list(products))
    mean, scale = E.mean(axis=0), E.std(axis=0)
    scale[scale == 0] = 1.0
    lr = _logistic((E - mean) / scale, y, np.sqrt(area), c_group, seed)
    coef = np.zeros((3, E.shape[1]))
    icpt = np.full(3, -30.0)  # a type never seen in training gets no probability
    present = lr.classes_.astype(int)
    if len(present) == 2:  # binary: sklearn keeps one score column
        coef[present[1]], icpt[present[1]] = lr.coef_[0], lr.intercept_[0]
        icpt[present[0]] = 0.0
    else:
        coef[present], icpt[present] = lr.coef_, lr.intercept_
    q_lo, q_hi = np.nanquantile(D, RANGE_Q[0], axis=0), np.nanquantile(D, RANGE_Q[1], axis=0)
    pad = RANGE_PAD * (q_hi - q_lo)
    model.update({"mean": mean.tolist(), "scale": scale.tolist(), "coef": coef.tolist(),
                  "intercept": icpt.tolist(), "temperature": 1.0,
                  "range_lo": (q_lo - pad).tolist(), "range_hi": (q_hi + pad).tolist(),
                  "c_pixel": float(c_pixel), "c_group": float(c_group), "seed": int(seed),
                  "n_pixels": int(len(yp)), "n_groups": int(len(y)),
                  "n_per_type": np.bincount(y, minlength=3).tolist()})
    return model


def _group_rows(samples, model):
    D = [group_design(s["F"], s["local"], model)[s["group_ids"]] for s in samples]
    return (np.concatenate(D), np.concatenate([s["group_y"] for s in samples]).astype(int),
            np.concatenate([s["group_area"] for s in samples]))


def calibrate(model, samples):
    """Fit the temperature on calibration samples (minimum log loss); returns the model."""
    from scipy.optimize import minimize_scalar
    D, y, _ = _group_rows(samples, model)
    s = _scores(D, model)

    def nll(log_t):
        p = _softmax(s / np.exp(log_t))
        return -np.mean(np.log(np.clip(p[np.arange(len(y)), y], 1e-12, 1)))
    r = minimize_scalar(nll, bounds=(-3, 3), method="bounded")
    model["temperature"] = float(np.exp(r.x))
    model["n_calibration"] = int(len(y))
    return model


#: Gauss-Hermite nodes of the marginal likelihood in :func:`fit_image_shift`.
_SHIFT_NODES = 41
#: the tensile-versus-shear direction of an image's log-odds shift (tensile, shear, mixed).
SHIFT_DIRECTION = config.TYPE_SHIFT_DIRECTION


def _shift_nll(sd, per_image):
    """Negative log marginal likelihood of the images' group labels when each image's
    scores are shifted by ``sd * z * SHIFT_DIRECTION``, z ~ N(0, 1)."""
    x, w = np.polynomial.hermite_e.hermegauss(_SHIFT_NODES)
    logw = np.log(w / w.sum())
    u = np.asarray(SHIFT_DIRECTION)
    total = 0.0
    for s, y in per_image:
        z = s[None, :, :] + (sd * x)[:, None, None] * u          # nodes x groups x types
        z = z - z.max(axis=2, keepdims=True)
        lp = z - np.log(np.exp(z).sum(axis=2, keepdims=True))
        ll = lp[:, np.arange(len(y)), y].sum(axis=1) + logw
        m = ll.max()
        total += m + np.log(np.exp(ll - m).sum())
    return -total


def fit_image_shift(samples, model, *, max_sd=6.0):
    """Spread of the per-image bias of the typing: a random-effects fit on labelled images.

    Every image's calibrated stage-2 scores are shifted along :data:`SHIFT_DIRECTION` (the
    tensile-versus-shear log-odds) by ``sd * z_i`` with one ``z_i ~ N(0, 1)`` per image, and
    ``sd`` is chosen by maximum marginal likelihood of the images' group labels (``z_i``
    integrated out by Gauss-Hermite quadrature). 0 means the groups' errors are independent
    between images as well as within; images from another rendering than the training one
    typically share a lean, which independent draws of the groups' types do not cover.

    Parameters
    ----------
    samples : list of dict
        One per image, from :func:`image_samples` (images with no labelled group are skipped).
    model : dict
        The post-test model whose probabilities are examined.
    max_sd : float
        Upper end of the search.

    Returns
    -------
    result : dict
        ``sd`` (the estimate), ``sd_low, sd_high`` (its 95 % profile-likelihood interval),
        ``n_images``, ``n_groups``.
    """
    per_image = []
    for smp in samples:
        D = group_design(smp["F"], smp["local"], model)[smp["group_ids"]]
        if len(D):
            per_image.append((_scores(D, model) / float(model["temperature"]),
                              np.asarray(smp["group_y"], int)))
    return shift_sd_mle(per_image, max_sd=max_sd)


def shift_sd_mle(per_image, *, max_sd=6.0):
    """Maximum marginal likelihood ``sd`` of :func:`fit_image_shift` from scores and labels.

    Parameters
    ----------
    per_image : list of (scores, labels)
        Per image: ``(n, 3)`` calibrated log-odds scores of its groups (tensile, shear,
        mixed) and their ``(n,)`` true type indices.
    max_sd : float
        Upper end of the search.

    Returns
    -------
    result : dict
        As :func:`fit_image_shift`.
    """
    from scipy.optimize import minimize_scalar
    per_image = [(np.asarray(s, float).reshape(-1, 3), np.asarray(y, int))
                 for s, y in per_image if len(y)]
    if not per_image:
        raise InputError("fit_image_shift: no labelled crack groups in the samples")
    r = minimize_scalar(lambda v: _shift_nll(v, per_image), bounds=(0.0, max_sd),
                        method="bounded", options={"xatol": 1e-3})
    grid = np.linspace(0.0, max_sd, 121)
    inside = grid[[_shift_nll(v, per_image) <= r.fun + 1.92 for v in grid]]
    return dict(sd=float(r.x), sd_low=float(min(inside.min(), r.x)),
                sd_high=float(max(inside.max(), r.x)), n_images=len(per_image),
                n_groups=int(sum(len(y) for _, y in per_image)))


def train_post(samples, *, seed=None, calibration=None):
    """Fit the post-test model from labelled cracks.

    Parameters
    ----------
    samples : iterable of (crack_labels, labels) or (crack_labels, labels, image)
        ``labels`` as in :func:`image_samples`.
    seed : int, optional
    calibration : iterable, optional
        Samples of the same form kept apart for the temperature; without them the
        temperature is 1 (the logistic model's own probabilities).

    Returns
    -------
    model : dict

    Raises
    ------
    InputError
        No tensile or no shear cracks, or fewer than two types of group, among the labels.
    """
    def collect(ss):
        return [image_samples(s[0], s[1], image=s[2] if len(s) > 2 else None) for s in ss]
    model = fit_post(collect(samples), seed=0 if seed is None else seed)
    if calibration is not None:
        cal = collect(calibration)
        if cal:
            calibrate(model, cal)
    return model


def save_model(model, path):
    """Write a post-test model as JSON (temporary file, then rename)."""
    path = str(path)
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(model, fh, indent=1)
    os.replace(tmp, path)


def check_model(model, where="crack model"):
    """Check a post-test model's version, fields and sizes; returns it."""
    if model.get("version") != VERSION:
        raise InputError(f"{where}: crack model version {model.get('version')!r}, this semkit "
                         f"reads version {VERSION} (retrain it with `semkit classify --train`)")
    need = ("features", "products", "mean", "scale", "coef", "intercept", "temperature",
            "range_lo", "range_hi", "pixel_mean", "pixel_scale", "pixel_coef",
            "pixel_intercept")
    miss = [k for k in need if k not in model]
    if miss:
        raise InputError(f"{where} lacks field(s) {miss}")
    if list(model["features"]) != list(STAGE2_NAMES) or len(model["pixel_coef"]) != len(
            LOCAL_NAMES):
        raise InputError(f"{where}: features {model['features']} differ from this semkit's "
                         f"{list(STAGE2_NAMES)}")
    k = len(STAGE2_NAMES) + sum(range(len(model["products"]) + 1))
    if np.shape(model["coef"]) != (3, k) or len(model["mean"]) != k:
        raise InputError(f"{where}: coefficients of shape {np.shape(model['coef'])}, "
                         f"expected (3, {k})")
    if not float(model["temperature"]) > 0:
        raise InputError(f"{where}: temperature must be > 0")
    if not float(model.get("image_shift_sd", 0.0)) >= 0:
        raise InputError(f"{where}: image_shift_sd must be >= 0")
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
DEFAULT_POST_MODEL = load_model(_DEFAULT_JSON) if os.path.exists(_DEFAULT_JSON) else None
