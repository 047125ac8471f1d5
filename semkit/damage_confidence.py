"""How sure an image's P = A_T / A_S is: a band from the calibrated crack-type probabilities,
and the ``low_confidence`` flag.

Every crack group has calibrated probabilities of being tensile, shear or mixed
(:func:`semkit.classify.classify_post`). Drawing each group's type from them ``N_DRAWS`` times
(fixed seed) and recomputing P each time gives the spread of P that the typing uncertainty
alone causes; ``P_low``, ``P_high`` are its ``P_BAND`` quantiles.

The groups' probabilities are calibrated one by one, but on an image unlike the training
renderings their errors are not independent: the whole image's typing leans one way (a
microscope whose shear traces look tensile to the model shifts every group alike). Each draw
therefore also shifts the tensile-versus-shear log-odds of all the image's groups by one
amount drawn from a normal distribution of standard deviation ``shift_sd``: the spread of that
per-image bias, which the built-in model records as ``image_shift_sd`` (fitted on renderings
held out from its training, :func:`semkit.classify.model.fit_image_shift`) and the typing
passes on in ``cracks.csv`` (``type_shift_sd``). Without it (0) the draws are independent
and the band narrows as 1 / sqrt(number of groups), which on large images of another
rendering held the true P in about half of the images instead of 80 %.

P is reported with
``P_status = low_confidence`` (and a ``P_note`` saying why) when

* the band is wider than ``P_SPREAD_MAX`` (P_high / P_low), or P is undefined (no shear) in
  more than 10 % of the draws, or
* cracks whose morphology lies outside what the typing model was trained on
  (``type_post_ok = False``) hold more than ``UNTRUSTED_AREA_MAX`` of the typed area.

The areas themselves (detection) are taken as measured; the band is the typing's part of the
uncertainty only.
"""
from __future__ import annotations

import numpy as np

from . import config
from .errors import InputError

__all__ = ["p_confidence", "stage_band", "N_DRAWS", "P_BAND", "P_SPREAD_MAX", "UNTRUSTED_AREA_MAX"]

N_DRAWS = 400
P_BAND = (0.1, 0.9)
P_SPREAD_MAX = 2.0
UNTRUSTED_AREA_MAX = 0.25
_SEED = 0
_NO_SHEAR_DRAWS_MAX = 0.1


def _draw_areas(area, prob, mixed, tensile_fraction, rng, shift_sd=0.0, shift=None):
    """A_T and A_S of N_DRAWS type draws (groups x draws); each draw shifts the tensile-vs-shear
    log-odds of every group by one normal deviate of standard deviation ``shift_sd`` (or by
    the given ``shift``, one value per draw)."""
    u = rng.random((N_DRAWS, len(area)))
    p = np.broadcast_to(prob, (N_DRAWS, *prob.shape))
    if shift is None and shift_sd > 0:
        shift = rng.standard_normal(N_DRAWS) * shift_sd
    if shift is not None:
        p = p * np.exp(np.outer(shift, config.TYPE_SHIFT_DIRECTION))[:, None, :]
        p = p / np.maximum(p.sum(axis=2, keepdims=True), 1e-300)
    cum = np.cumsum(p, axis=2)
    k = (u[:, :, None] > cum[:, :, :-1]).sum(axis=2)   # 0 tensile, 1 shear, 2 mixed
    ft = {"exclude": 0.0, "tensile": 1.0, "shear": 0.0}.get(mixed)
    f_m_t = tensile_fraction if mixed == "split" else np.full(len(area), ft)
    f_m_s = 1 - tensile_fraction if mixed == "split" else np.full(
        len(area), 1.0 if mixed == "shear" else 0.0)
    a_t = ((k == 0) * area + (k == 2) * area * f_m_t).sum(axis=1)
    a_s = ((k == 1) * area + (k == 2) * area * f_m_s).sum(axis=1)
    return a_t, a_s


def _groups(area, prob, group, tensile_fraction):
    """Area, area-weighted probabilities and tensile share of each group (one type draw per
    group); every crack its own group without ``group``."""
    area = np.asarray(area, float)
    prob = np.clip(np.nan_to_num(np.asarray(prob, float).reshape(-1, 3), nan=1 / 3), 0, 1)
    prob = prob / np.maximum(prob.sum(axis=1, keepdims=True), 1e-12)
    tf = np.full(len(area), 0.5) if tensile_fraction is None else np.nan_to_num(
        np.asarray(tensile_fraction, float), nan=0.5)
    if group is None or not len(area):
        return area, prob, tf
    _, inv = np.unique(np.asarray(group), return_inverse=True)
    t_area = np.bincount(inv, weights=area)
    t_prob = np.zeros((inv.max() + 1, 3))
    np.add.at(t_prob, inv, prob * area[:, None])
    t_prob /= np.maximum(t_area[:, None], 1e-12)
    t_tf = np.bincount(inv, weights=tf * area) / np.maximum(t_area, 1e-12)
    return t_area, t_prob, t_tf


def p_confidence(area, prob, *, trusted=None, group=None, mixed="exclude",
                 tensile_fraction=None, notes=None, shift_sd=0.0):
    """P band, status and note of one image from its cracks' areas and type probabilities.

    Parameters
    ----------
    area : (n,) array_like of float
        Crack areas (any unit).
    prob : (n, 3) array_like of float
        P(tensile), P(shear), P(mixed) of each crack (rows sum to 1; a crack typed by the
        user is one-hot).
    trusted : (n,) array_like of bool, optional
        ``type_post_ok`` of each crack.
    group : (n,) array_like of int, optional
        Group of each crack (``group_id``): the cracks of one group share one draw.
    mixed : str
        As :func:`semkit.damage.image_damage`.
    tensile_fraction : (n,) array_like of float, optional
        Tensile share of a mixed crack (``mixed="split"``).
    notes : (n,) array_like of str, optional
        ``type_note`` of each crack (that of the largest untrusted crack is quoted).
    shift_sd : float
        Standard deviation of the image's common tensile-versus-shear log-odds shift
        (``type_shift_sd``; 0: the groups' draws are independent).

    Returns
    -------
    result : dict
        ``P_low, P_high`` (NaN when the band is undefined), ``low_confidence`` (bool) and
        ``note`` (str, empty when confident).

    Examples
    --------
    >>> r = p_confidence([100, 50], [[0.99, 0.01, 0], [0.01, 0.99, 0]])
    >>> round(r["P_low"], 2), round(r["P_high"], 2), r["low_confidence"]
    (2.0, 2.0, False)
    >>> area, prob = [10] * 40, [[0.9, 0.1, 0]] * 20 + [[0.1, 0.9, 0]] * 20
    >>> r = p_confidence(area, prob)
    >>> round(r["P_low"], 2), round(r["P_high"], 2), r["low_confidence"]
    (0.82, 1.22, False)
    >>> r = p_confidence(area, prob, shift_sd=2.0)
    >>> round(r["P_low"], 2), round(r["P_high"], 2), r["low_confidence"]
    (0.29, 4.07, True)
    >>> p_confidence([100, 50], [[0.6, 0.4, 0], [0.4, 0.6, 0]])["low_confidence"]
    True
    """
    if not shift_sd >= 0:
        raise InputError(f"shift_sd: expected a standard deviation >= 0, got {shift_sd}")
    area = np.asarray(area, float)
    n = len(area)
    trusted = np.ones(n, bool) if trusted is None else np.asarray(trusted, bool)
    t_area, t_prob, t_tf = _groups(area, prob, group, tensile_fraction)
    out = dict(P_low=float("nan"), P_high=float("nan"), low_confidence=False, note="")
    if n == 0 or area.sum() <= 0:
        return out
    a_t, a_s = _draw_areas(t_area, t_prob, mixed, t_tf, np.random.default_rng(_SEED),
                           float(shift_sd))
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.where(a_s > 0, a_t / a_s, np.inf)
        # between two draws without shear the quantile is inf - inf: NaN, read as open below
        lo, hi = np.quantile(p, P_BAND)
    no_shear = float(np.mean(a_s <= 0))
    out.update(P_low=float(lo) if np.isfinite(lo) else float("nan"),
               P_high=float(hi) if np.isfinite(hi) else float("nan"))
    reasons = []
    untrusted = float(area[~trusted].sum() / area.sum())
    if untrusted > UNTRUSTED_AREA_MAX:
        main = ""
        if notes is not None:  # the reason of the largest untrusted crack
            bad = np.flatnonzero(~trusted & (np.asarray(notes, dtype=object) != ""))
            main = str(notes[bad[np.argmax(area[bad])]]) if bad.size else ""
        reasons.append(f"cracks untyped by the model hold {untrusted:.0%} of the typed area"
                       + (f" (largest: {main})" if main else ""))
    if no_shear > _NO_SHEAR_DRAWS_MAX:
        reasons.append(f"no shear area in {no_shear:.0%} of the type draws")
    elif lo > 0 and hi / lo > P_SPREAD_MAX:
        reasons.append(f"type uncertainty: P {P_BAND[0]:.0%}-{P_BAND[1]:.0%} band "
                       f"{lo:.3g}..{hi:.3g} ({hi / lo:.1f}x wide)")
    elif not lo > 0:
        reasons.append("type uncertainty: P may be 0")
    out["low_confidence"] = bool(reasons)
    out["note"] = "; ".join(reasons)
    return out


def stage_band(images, *, mixed="exclude", shift_sd=0.0, statistic="mean"):
    """Band of a stage's mean P (``P_mean`` of ``damage.csv``) from its images' typing, or of
    the pooled ratio of their summed areas.

    Each of ``N_DRAWS`` draws types every group of every image from its calibrated
    probabilities, as :func:`p_confidence` does, with one tensile-versus-shear log-odds shift
    for the whole stage in that draw: a stage's images come from one microscope and rock, so
    their leans are not independent either and averaging images does not remove it. Each
    draw's mean is taken over the images with a finite P in that draw (as ``P_mean`` is);
    with ``statistic="pooled"`` each draw's sum A_T over sum A_S is taken instead (as
    ``P_pooled`` is).

    Parameters
    ----------
    images : list of dict
        One per image in the stage's mean: ``area``, ``prob`` and optionally ``group`` and
        ``tensile_fraction``, as for :func:`p_confidence`.
    mixed : str
        As :func:`semkit.damage.image_damage`.
    shift_sd : float
        Standard deviation of the common lean (``type_shift_sd``).
    statistic : {"mean", "pooled"}
        The mean of the images' P, or the ratio of their summed areas.

    Returns
    -------
    low, high : float
        The ``P_BAND`` quantiles of the statistic over the draws; NaN where undefined (no image
        with cracks, or more than 10 % of the draws without a finite P in any image for
        ``high``).

    Examples
    --------
    >>> one = dict(area=[10] * 40, prob=[[0.9, 0.1, 0]] * 20 + [[0.1, 0.9, 0]] * 20)
    >>> [round(v, 2) for v in stage_band([one])]                # one image
    [0.82, 1.22]
    >>> [round(v, 2) for v in stage_band([one] * 5)]            # independent: averaging narrows
    [0.91, 1.15]
    >>> [round(v, 2) for v in stage_band([one] * 5, shift_sd=2.0)]  # one lean: it does not
    [0.28, 2.61]
    """
    if not shift_sd >= 0:
        raise InputError(f"shift_sd: expected a standard deviation >= 0, got {shift_sd}")
    if statistic not in ("mean", "pooled"):
        raise InputError(f"statistic: expected 'mean' or 'pooled', got {statistic!r}")
    shift = np.random.default_rng(_SEED + 1).standard_normal(N_DRAWS) * float(shift_sd)
    rng = np.random.default_rng(_SEED)
    draws = []
    for im in images:
        t_area, t_prob, t_tf = _groups(im["area"], im["prob"], im.get("group"),
                                       im.get("tensile_fraction"))
        if not len(t_area) or t_area.sum() <= 0:
            continue
        draws.append(_draw_areas(t_area, t_prob, mixed, t_tf, rng, shift=shift))
    if not draws:
        return float("nan"), float("nan")
    a_t, a_s = (np.array(x) for x in zip(*draws))          # images x draws
    with np.errstate(divide="ignore", invalid="ignore"):
        if statistic == "pooled":
            stat = np.where(a_s.sum(axis=0) > 0, a_t.sum(axis=0) / a_s.sum(axis=0), np.inf)
        else:
            p = np.where(a_s > 0, a_t / a_s, np.inf)
            fin = np.isfinite(p)
            n_fin = fin.sum(axis=0)
            stat = np.where(n_fin > 0, np.where(fin, p, 0.0).sum(axis=0)
                            / np.maximum(n_fin, 1), np.inf)
    lo, hi = np.quantile(stat, P_BAND)
    return (float(lo) if np.isfinite(lo) else float("nan"),
            float(hi) if np.isfinite(hi) else float("nan"))
