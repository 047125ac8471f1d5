"""Crack classification: pre-existing (inter/intra/trans) and post-test (tensile/shear/mixed).

Pre-existing (:func:`classify_pre`), He et al.'s rule against a grain map: a crack whose
skeleton lies > 86 % along grain boundaries is inter-granular; else > 80 % inside one grain is
intra-granular; else trans-granular. The fractions are reported per crack.

Post-test (:func:`classify_post`), from morphology. Per skeleton pixel, over a window of
radius :data:`WINDOW_PX`: local aperture (2 x distance to the wall), its variation, dark-pixel
density, skeleton density (parallel or en-echelon traces), endpoint density (steps, debris),
the excess dark area not explained by the local trace (debris in the band), the scatter of the
skeleton about its local line, and the dark fill (partial-volume dark width over the mask
aperture: ~1 for a clean opening, low where the mask bridges thin layered traces). A logistic
model turns these into P(tensile) per skeleton pixel; each crack pixel takes the smoothed
decision of its nearest skeleton pixel (debris within :data:`LINK_PX` of a crack belongs to
it), and a trace (skeleton branches continuing each other across junctions) holding long runs
of both types is mixed. The model is a small JSON-able dict; :func:`train_post` fits it from labelled cracks (``semkit classify
--train``).
"""
from __future__ import annotations

import json
import os

import numpy as np
import pandas as pd
from scipy import ndimage as ndi

from . import config
from .errors import InputError

__all__ = ["classify_pre", "post_features", "classify_post", "train_post", "save_model",
           "load_model", "apply_labels", "read_labels", "crack_clusters", "DEFAULT_POST_MODEL", "FEATURE_NAMES",
           "INTER_MIN_FRACTION", "INTRA_MIN_FRACTION"]

#: He et al.: share of the crack along grain boundaries above which it is inter-granular.
INTER_MIN_FRACTION = config.INTER_MIN_FRACTION
#: He et al.: share of the crack inside one grain above which it is intra-granular.
INTRA_MIN_FRACTION = config.INTRA_MIN_FRACTION
#: a skeleton pixel is "on a boundary" within this many px beyond the local half-aperture.
BOUNDARY_TOL_PX = config.BOUNDARY_TOL_PX
#: half-size of the feature window around each skeleton pixel, px.
WINDOW_PX = config.WINDOW_PX
#: a small object (debris, fragment) within this distance (px) of a large crack takes its type.
LINK_PX = config.LINK_PX
#: objects with fewer pixels than this are "small" (debris, fragments).
SMALL_OBJECT_PX = config.SMALL_OBJECT_PX
#: a trace is mixed when its long tensile runs and its long shear runs each make up at least
#: this share of its skeleton (runs of the smoothed per-pixel decision, >= MIN_RUN_PX long).
MIXED_SHARE = config.MIXED_SHARE
#: running-mean window (px) along a branch before runs are measured.
RUN_SMOOTH_PX = config.RUN_SMOOTH_PX
#: shortest run (px) of one type that counts as a segment of a mixed crack.
MIN_RUN_PX = config.MIN_RUN_PX
#: skeleton branches shorter than this (px) are spurs/steps: typed by their neighbours.
SHORT_BRANCH_PX = config.SHORT_BRANCH_PX
#: branches meeting at a junction within this angle of a straight continuation are one trace.
CONTINUE_DEG = config.CONTINUE_DEG
#: branch ends closer than this (px) meet at one junction.
JUNCTION_PX = config.JUNCTION_PX
#: branch ends of different objects up to this far apart (px), facing each other within
#: CONTINUE_DEG, continue one trace across the gap (a crack broken by the threshold).
GAP_PX = config.GAP_PX
#: feature names, in model order.
FEATURE_NAMES = ("log_aperture", "aperture_cv", "dark_density", "skeleton_density",
                 "endpoint_density", "excess_dark", "skeleton_scatter", "dark_fill")
#: default post-test model, fitted with :func:`train_post` on 12 synthetic post-test images
#: (``semkit.synth.make_sem_image((384, 512), stage="post", n_cracks=12, seed=100..111)``,
#: objects and smoothed grey image from ``semkit.pipeline.analyse_image``, labels = majority
#: true type per object); docs/semkit_science.md says how it scores on other seeds.
DEFAULT_POST_MODEL = {
    "features": list(FEATURE_NAMES),
    "mean": [1.5507, 0.2042, 0.2914, 1.2048, 0.0315, 0.003, 1.3537, 0.7189],
    "scale": [0.4394, 0.1414, 0.1291, 0.4184, 0.0402, 0.0424, 1.2248, 0.2011],
    "coef": [-0.1815, -0.7929, 0.5274, -0.0418, -0.5316, -0.5838, 0.0796, 1.6036],
    "intercept": 0.6546,
    "mixed_share": 0.1,
    "window_px": WINDOW_PX,
    "link_px": float(LINK_PX),
}


# ----------------------------------------------------------------------------- pre-existing
def _fill_grains(grain_labels):
    g = np.asarray(grain_labels)
    if (g > 0).all():
        return g
    if not (g > 0).any():
        raise InputError("grain_labels: no grain pixels")
    _, idx = ndi.distance_transform_edt(g == 0, return_indices=True)
    return g[idx[0], idx[1]]


def _skeleton(mask):
    from skimage.morphology import skeletonize
    return skeletonize(mask)


def classify_pre(crack_labels, grain_labels, *, skeleton=None,
                 inter_min=INTER_MIN_FRACTION, intra_min=INTRA_MIN_FRACTION,
                 boundary_tol_px=BOUNDARY_TOL_PX):
    """Classify pre-existing cracks as inter-, intra- or trans-granular (He et al.'s rule).

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects, 0 = none.
    grain_labels : (M, N) ndarray of int
        Grain map, 1..G (0 where unknown, e.g. under cracks: filled by the nearest grain).
    skeleton : (M, N) ndarray of bool, optional
        Crack skeleton (computed when absent).
    inter_min, intra_min : float
        The rule's thresholds (0.86, 0.80).
    boundary_tol_px : float
        A skeleton pixel is on a boundary when its distance to the nearest grain boundary is
        at most its local half-aperture + this tolerance.

    Returns
    -------
    table : pandas.DataFrame
        One row per crack object: ``crack_id, boundary_fraction, max_grain_fraction,
        n_grains, type_pre, confidence``.
    type_image : (M, N) ndarray of int8
        Type per pixel (the object's): 0 none, 1 inter, 2 intra, 3 trans.

    Raises
    ------
    InputError
        Shapes disagree.

    Notes
    -----
    Per crack object: f_b = n(skeleton px on boundaries) / n(skeleton px); f_g = the largest share of skeleton px
    in one grain. inter if f_b > 0.86, else intra if f_g > 0.80, else trans. The confidence is
    the distance of the deciding fraction from its threshold, scaled to [0.5, 1].
    """
    lab = np.asarray(crack_labels)
    g = np.asarray(grain_labels)
    if lab.shape != g.shape or lab.ndim != 2:
        raise InputError(f"grain_labels: expected shape {lab.shape}, got {g.shape}")
    g = _fill_grains(g)
    mask = lab > 0
    skel = _skeleton(mask) if skeleton is None else (np.asarray(skeleton, bool) & mask)
    # pixels whose 4-neighbourhood has another grain: the boundary, both sides
    bnd = np.zeros(g.shape, bool)
    bnd[:, 1:] |= g[:, 1:] != g[:, :-1]
    bnd[:, :-1] |= g[:, 1:] != g[:, :-1]
    bnd[1:, :] |= g[1:, :] != g[:-1, :]
    bnd[:-1, :] |= g[1:, :] != g[:-1, :]
    d_bnd = ndi.distance_transform_edt(~bnd)
    half = ndi.distance_transform_edt(mask)
    rr, cc = np.nonzero(skel)
    on_img = np.zeros(lab.shape, bool)
    on_img[rr, cc] = d_bnd[rr, cc] <= half[rr, cc] + boundary_tol_px
    ids = lab[rr, cc]
    n = int(lab.max())
    rows = []
    code_of = np.zeros(n + 1, np.int8)
    names = {1: "inter", 2: "intra", 3: "trans"}
    for cid in np.unique(lab[mask]):
        sel = ids == cid
        if sel.any():
            on = on_img[rr[sel], cc[sel]]
            gg = g[rr[sel], cc[sel]]
        else:  # no skeleton pixel (cannot happen for a non-empty object): use all pixels
            pr, pc = np.nonzero(lab == cid)
            on = d_bnd[pr, pc] <= half[pr, pc] + boundary_tol_px
            gg = g[pr, pc]
        f_b = float(on.mean())
        counts = np.bincount(gg)
        f_g = float(counts.max() / counts.sum())
        if f_b > inter_min:
            k, conf = 1, 0.5 + 0.5 * (f_b - inter_min) / (1 - inter_min)
        elif f_g > intra_min:
            k, conf = 2, 0.5 + 0.5 * (f_g - intra_min) / (1 - intra_min)
        else:
            k = 3
            conf = 0.5 + 0.5 * min((inter_min - f_b) / inter_min, (intra_min - f_g) / intra_min)
        code_of[cid] = k
        rows.append(dict(crack_id=int(cid), boundary_fraction=f_b, max_grain_fraction=f_g,
                         n_grains=int((counts > 0).sum()), type_pre=names[k],
                         confidence=float(np.clip(conf, 0.5, 1.0))))
    cols = ["crack_id", "boundary_fraction", "max_grain_fraction", "n_grains", "type_pre",
            "confidence"]
    return pd.DataFrame(rows, columns=cols), code_of[lab]


# ----------------------------------------------------------------------------- post-test
def crack_clusters(crack_labels, *, link_px=LINK_PX, small_px=SMALL_OBJECT_PX):
    """Attach small objects (debris, en-echelon fragments) to the nearest large crack.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
    link_px : float
        A small object joins the large object nearest to it when closer than this (px).
    small_px : int
        Objects with fewer pixels are "small".

    Returns
    -------
    cluster_of : (n + 1,) ndarray of int64
        Cluster id of each object id (0 -> 0), n = crack_labels.max(). A large object is its
        own cluster (its id); an isolated small object too.
    """
    lab = np.asarray(crack_labels)
    n = int(lab.max())
    cluster_of = np.arange(n + 1, dtype=np.int64)
    if n == 0:
        return cluster_of
    area = np.bincount(lab.ravel(), minlength=n + 1)
    big = area >= small_px
    big[0] = False
    big_mask = big[lab]
    if not big_mask.any():
        return cluster_of
    dist, (ir, ic) = ndi.distance_transform_edt(~big_mask, return_indices=True)
    small_ids = np.flatnonzero(~big & (area > 0))
    small_ids = small_ids[small_ids > 0]
    if small_ids.size:
        rr, cc = np.nonzero(np.isin(lab, small_ids))
        ids = lab[rr, cc]
        d = dist[rr, cc]
        order = np.lexsort((d, ids))  # nearest pixel of each small object first
        first = order[np.r_[True, ids[order][1:] != ids[order][:-1]]]
        near = d[first] <= link_px
        tgt = lab[ir[rr[first], cc[first]], ic[rr[first], cc[first]]]
        cluster_of[ids[first][near]] = tgt[near]
    return cluster_of


def post_features(crack_labels, *, image=None, skeleton=None, window_px=WINDOW_PX):
    """Morphological features at each skeleton pixel of the cracks.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects (and debris specks: keep them, they are evidence of shear).
    skeleton : (M, N) ndarray of bool, optional
    window_px : int
        Half-size of the square window.

    Returns
    -------
    rows, cols : (K,) ndarray of int
        Skeleton pixel positions.
    X : (K, 8) ndarray of float64
        Features in :data:`FEATURE_NAMES` order: log local aperture (px), aperture coefficient
        of variation, dark-pixel density, skeleton density (px of skeleton per px of window
        side: ~1 for one trace, ~2 for layered traces), endpoint density (per window side),
        excess dark density (dark area not explained by the skeleton x aperture: debris),
        skeleton scatter (px, RMS distance of the window's skeleton from its best line) and
        dark fill (partial-volume dark width / aperture; NaN without ``image``).
    """
    lab = np.asarray(crack_labels)
    mask = lab > 0
    skel = _skeleton(mask) if skeleton is None else (np.asarray(skeleton, bool) & mask)
    w = 2.0 * ndi.distance_transform_edt(mask)
    size = 2 * int(window_px) + 1
    sk = skel.astype(np.float64)
    nb = ndi.convolve(sk, np.ones((3, 3)), mode="constant") - sk
    endpoints = skel & (nb <= 1)

    def box(a):
        return ndi.uniform_filter(a, size, mode="constant")

    n_s = box(sk)
    s_w = box(sk * w)
    s_w2 = box(sk * w * w)
    dark = box(mask.astype(np.float64))
    ends = box(endpoints.astype(np.float64))
    rr, cc = np.nonzero(skel)
    ns = np.maximum(n_s[rr, cc], 1e-12)
    wm = s_w[rr, cc] / ns
    var = np.maximum(s_w2[rr, cc] / ns - wm ** 2, 0.0)
    cv = np.sqrt(var) / np.maximum(wm, 1e-9)
    skel_dens = n_s[rr, cc] * size
    end_dens = ends[rr, cc] * size
    dk = dark[rr, cc]
    excess = dk - n_s[rr, cc] * np.maximum(wm, 1.0)
    # scatter of the skeleton about its local best line: smallest eigenvalue of the
    # covariance of skeleton coordinates in the window (zigzag steps, layered traces)
    yy, xx = np.mgrid[0:lab.shape[0], 0:lab.shape[1]].astype(np.float64)
    yy -= yy.mean()
    xx -= xx.mean()
    mx, my = box(sk * xx)[rr, cc] / ns, box(sk * yy)[rr, cc] / ns
    sxx = box(sk * xx * xx)[rr, cc] / ns - mx * mx
    syy = box(sk * yy * yy)[rr, cc] / ns - my * my
    sxy = box(sk * xx * yy)[rr, cc] / ns - mx * my
    lam = 0.5 * (sxx + syy) - np.sqrt(np.maximum(0.25 * (sxx - syy) ** 2 + sxy ** 2, 0.0))
    scatter = np.sqrt(np.maximum(lam, 0.0))
    # dark (partial-volume) width per skeleton px over the mask aperture: ~1 for an open
    # crack, well below 1 where the mask bridges or fills between thin dark traces
    if image is not None:
        from .damage import darkness_fraction
        f, _ = darkness_fraction(image, lab)
        pv_w = box(f)[rr, cc] / ns
        fill = pv_w / np.maximum(wm, 1.0)
    else:
        fill = np.full(rr.shape, np.nan)
    X = np.column_stack([np.log(np.maximum(wm, 0.5)), cv, dk, skel_dens, end_dens, excess,
                         scatter, fill])
    return rr, cc, X


def _p_tensile(X, model):
    z = (X - np.asarray(model["mean"])) / np.asarray(model["scale"])
    z = np.where(np.isfinite(z), z, 0.0)  # a feature not measured (no grey image): neutral
    s = z @ np.asarray(model["coef"]) + float(model["intercept"])
    return 1.0 / (1.0 + np.exp(-np.clip(s, -50, 50)))


def _traces(skel, p, *, short_px, angle_deg):
    """Split the skeleton into branches (skan), join collinear branches across junctions.

    Returns (path pixel lists, trace id per path, short flag per path).
    """
    from skan import Skeleton
    sk = Skeleton(skel)
    n = sk.n_paths
    coords = [np.asarray(sk.path_coordinates(i)).astype(np.int64) for i in range(n)]
    lengths = np.array([len(c) for c in coords])
    short = lengths < short_px
    parent = np.arange(n)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    ends = []  # (path, end point, inward direction)
    k = 6
    for i, c in enumerate(coords):
        if short[i] or len(c) < 2:
            continue
        for e, q in ((c[0], c[min(k, len(c) - 1)]), (c[-1], c[max(len(c) - 1 - k, 0)])):
            d = (q - e).astype(float)
            nd = np.hypot(*d)
            if nd > 0:
                ends.append((i, e.astype(float), d / nd))
    if len(ends) > 1:
        from scipy.spatial import cKDTree
        pts = np.array([e[1] for e in ends])
        dirs = np.array([e[2] for e in ends])
        owner = np.array([e[0] for e in ends])
        cos_lim = np.cos(np.radians(angle_deg))
        best = {}
        for a_, b_ in cKDTree(pts).query_pairs(GAP_PX):
            if owner[a_] == owner[b_]:
                continue
            c = -float(dirs[a_] @ dirs[b_])  # 1 = perfectly continuing
            if c < cos_lim:
                continue
            v = pts[b_] - pts[a_]
            dv = np.hypot(*v)
            if dv > JUNCTION_PX:  # across a gap: the gap must lie along both branches
                v = v / dv
                if -float(dirs[a_] @ v) < cos_lim or float(dirs[b_] @ v) < cos_lim:
                    continue
            for x, y in ((a_, b_), (b_, a_)):
                if c > best.get(x, (-2.0, -1))[0]:
                    best[x] = (c, y)
        for x, (c, y) in best.items():
            if best.get(y, (None, -1))[1] == x:  # mutual best partners only
                parent[find(owner[x])] = find(owner[y])
    trace = np.array([find(i) for i in range(n)])
    return coords, trace, short


def _assign_traces(lab, skel, rr, cc, p, *, link_px):
    """Trace id of every crack pixel (-1 none) and the tensile share f_T of each trace."""
    mask = lab > 0
    p_img = np.full(lab.shape, np.nan)
    p_img[rr, cc] = p
    coords, trace, short = _traces(skel, p_img, short_px=SHORT_BRANCH_PX,
                                   angle_deg=CONTINUE_DEG)
    n_tr = len(trace)
    tsum = np.zeros(n_tr)
    tcnt = np.zeros(n_tr)
    run_t = np.zeros(n_tr)
    run_s = np.zeros(n_tr)
    for i, c in enumerate(coords):
        if not short[i]:
            b = _smooth_runs(p_img[c[:, 0], c[:, 1]] > 0.5)
            tsum[trace[i]] += b.sum()
            tcnt[trace[i]] += len(c)
            lt, ls = _long_runs(b, MIN_RUN_PX)
            run_t[trace[i]] += lt
            run_s[trace[i]] += ls
    seed_img = np.full(lab.shape, -1, np.int64)
    for i, c in enumerate(coords):
        if not short[i]:
            seed_img[c[:, 0], c[:, 1]] = trace[i]
    # objects whose skeleton is all short branches: one trace per object
    extra = []
    for i, c in enumerate(coords):
        if short[i]:
            extra.append(i)
    obj_has = np.zeros(int(lab.max()) + 1, bool)
    obj_has[lab[seed_img >= 0]] = True
    new_tr = {}
    for i in extra:
        c = coords[i]
        obj = int(lab[c[0, 0], c[0, 1]])
        if obj_has[obj]:
            continue
        t = new_tr.setdefault(obj, n_tr + len(new_tr))
        seed_img[c[:, 0], c[:, 1]] = t
    if new_tr:
        tsum = np.r_[tsum, np.zeros(len(new_tr))]
        tcnt = np.r_[tcnt, np.zeros(len(new_tr))]
        for i in extra:
            c = coords[i]
            obj = int(lab[c[0, 0], c[0, 1]])
            if obj in new_tr:
                tsum[new_tr[obj]] += (p_img[c[:, 0], c[:, 1]] > 0.5).sum()
                tcnt[new_tr[obj]] += len(c)
    ft = np.where(tcnt > 0, tsum / np.maximum(tcnt, 1), np.nan)
    n_all = len(ft)
    run_t = np.r_[run_t, np.zeros(n_all - len(run_t))]
    run_s = np.r_[run_s, np.zeros(n_all - len(run_s))]
    mixed_share = np.minimum(run_t, run_s) / np.maximum(tcnt, 1)
    pix = np.full(lab.shape, -1, np.int64)
    cluster_of = crack_clusters(lab, link_px=link_px)
    clus = cluster_of[lab]
    for cid in np.unique(clus[mask]):
        sel = clus == cid
        seeds = sel & (seed_img >= 0)
        if not seeds.any():
            continue
        rows = np.flatnonzero(sel.any(axis=1))
        cols = np.flatnonzero(sel.any(axis=0))
        win = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
        _, (ir, ic) = ndi.distance_transform_edt(~seeds[win], return_indices=True)
        t = seed_img[win][ir, ic]
        pix[win][sel[win]] = t[sel[win]]
    ft = np.where(np.isfinite(ft), ft, 0.5)
    return pix, ft, mixed_share


def _nearest_in_cluster(lab, seed, *, link_px):
    """Value of the nearest non-zero ``seed`` pixel of the same cluster, for every crack pixel."""
    mask = lab > 0
    out = np.zeros(lab.shape, seed.dtype)
    clus = crack_clusters(lab, link_px=link_px)[lab]
    for cid in np.unique(clus[mask]):
        sel = clus == cid
        rows = np.flatnonzero(sel.any(axis=1))
        cols = np.flatnonzero(sel.any(axis=0))
        win = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
        seeds = sel[win] & (seed[win] > 0)
        if not seeds.any():
            continue
        _, (ir, ic) = ndi.distance_transform_edt(~seeds, return_indices=True)
        v = seed[win][ir, ic]
        out[win][sel[win]] = v[sel[win]]
    return out


def _smooth_runs(b):
    """Running mean of a boolean sequence over RUN_SMOOTH_PX, thresholded at 0.5."""
    if len(b) < 3:
        return b.astype(bool)
    return ndi.uniform_filter1d(b.astype(float), RUN_SMOOTH_PX, mode="nearest") > 0.5


def _long_runs(b, min_len):
    """Total length of True runs and of False runs that are at least ``min_len`` long."""
    if len(b) == 0:
        return 0.0, 0.0
    edges = np.flatnonzero(np.diff(b.astype(np.int8))) + 1
    starts = np.r_[0, edges]
    lens = np.diff(np.r_[starts, len(b)])
    vals = b[starts]
    keep = lens >= min_len
    return float(lens[keep & vals].sum()), float(lens[keep & ~vals].sum())


def _trace_codes(ft, mixed_share, model):
    """1 tensile / 2 shear / 3 mixed per trace (the decision rule of classify_post)."""
    return np.where(mixed_share >= float(model["mixed_share"]), 3,
                    np.where(ft >= 0.5, 1, 2)).astype(np.int8)


def classify_post(crack_labels, *, image=None, skeleton=None, model=None):
    """Classify post-test cracks as tensile, shear or mixed from their morphology.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects 1..n.
    skeleton : (M, N) ndarray of bool, optional
    model : dict, optional
        :data:`DEFAULT_POST_MODEL` form (from :func:`train_post` / :func:`load_model`).

    Returns
    -------
    table : pandas.DataFrame
        One row per object: ``crack_id, type_post`` (area-majority type of its pixels),
        ``confidence, frac_tensile, frac_shear, frac_mixed`` (shares of the object's pixels
        typed so: an object where a tensile and a shear crack cross is split, not averaged),
        ``tensile_fraction`` (share of tensile skeleton), the object means of the features
        ``aperture_mean_px, aperture_cv, dark_density, skeleton_density, endpoint_density,
        excess_dark, skeleton_scatter, dark_fill`` and ``tortuosity``.
    type_image : (M, N) ndarray of int8
        Type per pixel: 0 none, 1 tensile, 2 shear, 3 mixed.

    Notes
    -----
    p_T = 1 / (1 + exp(-(beta . z + beta_0))), z the standardised features of a skeleton
    pixel. The skeleton is split into branches at junctions; branches continuing each other
    within :data:`CONTINUE_DEG` across a junction form one trace (a crossing crack is a
    different trace). Along each branch the decision p_T > 0.5 is smoothed over
    :data:`RUN_SMOOTH_PX`; a trace whose runs of tensile and of shear (each >= MIN_RUN_PX)
    both exceed ``mixed_share`` of its length is mixed. Otherwise each crack pixel takes the
    smoothed decision of its nearest skeleton pixel (small objects within :data:`LINK_PX` of
    a crack belong to it). The object's ``type_post`` is its area-majority type;
    confidence = mean |2 p_T - 1| over its skeleton x the majority share.
    """
    model = DEFAULT_POST_MODEL if model is None else model
    lab = np.asarray(crack_labels)
    if lab.ndim != 2:
        raise InputError(f"crack_labels: expected a 2-D array, got shape {lab.shape}")
    n = int(lab.max())
    cols = ["crack_id", "type_post", "confidence", "frac_tensile", "frac_shear", "frac_mixed",
            "tensile_fraction", "aperture_mean_px", "aperture_cv", "dark_density",
            "skeleton_density", "endpoint_density", "excess_dark", "skeleton_scatter",
            "dark_fill", "tortuosity"]
    type_img = np.zeros(lab.shape, np.int8)
    if n == 0:
        return pd.DataFrame(columns=cols), type_img
    mask = lab > 0
    skel = _skeleton(mask) if skeleton is None else (np.asarray(skeleton, bool) & mask)
    rr, cc, X = post_features(lab, image=image, skeleton=skel,
                              window_px=int(model.get("window_px", WINDOW_PX)))
    p = _p_tensile(X, model)
    pix_trace, ft_trace, ms_trace = _assign_traces(lab, skel, rr, cc, p,
                                                   link_px=float(model.get("link_px", LINK_PX)))
    code_trace = _trace_codes(ft_trace, ms_trace, model)
    # tensile/shear per pixel: the nearest skeleton pixel's decision, smoothed along the
    # skeleton over RUN_SMOOTH_PX; mixed where the pixel's trace is mixed
    sk = np.zeros(lab.shape)
    sk[rr, cc] = 1.0
    pv = np.zeros(lab.shape)
    pv[rr, cc] = (p > 0.5)
    num = ndi.uniform_filter(pv, RUN_SMOOTH_PX, mode="constant")
    den = ndi.uniform_filter(sk, RUN_SMOOTH_PX, mode="constant")
    seed = np.zeros(lab.shape, np.int64)
    seed[rr, cc] = np.where(num[rr, cc] / np.maximum(den[rr, cc], 1e-12) > 0.5, 1, 2)
    type_img[:] = _nearest_in_cluster(lab, seed, link_px=float(model.get("link_px", LINK_PX)))
    is_mixed = (pix_trace >= 0) & (code_trace[np.maximum(pix_trace, 0)] == 3)
    type_img[is_mixed] = 3
    # objects left untyped (isolated specks without a skeleton branch): their own f_T
    left = mask & (type_img == 0)
    if left.any():
        ids_sk = lab[rr, cc]
        cnt_o = np.bincount(ids_sk, minlength=n + 1)
        ft_o = np.bincount(ids_sk, weights=(p > 0.5).astype(float), minlength=n + 1) / \
            np.maximum(cnt_o, 1)
        code_o = np.where(ft_o >= 0.5, 1, 2).astype(np.int8)
        type_img[left] = code_o[lab[left]]
    # per-object table
    area = np.bincount(lab.ravel(), minlength=n + 1).astype(float)
    fr = [np.bincount(lab[type_img == k], minlength=n + 1) / np.maximum(area, 1)
          for k in (1, 2, 3)]
    ids_sk = lab[rr, cc]
    cnt = np.bincount(ids_sk, minlength=n + 1).astype(float)
    ft_obj = np.bincount(ids_sk, weights=(p > 0.5).astype(float), minlength=n + 1) / \
        np.maximum(cnt, 1)
    margin = np.bincount(ids_sk, weights=np.abs(2 * p - 1), minlength=n + 1) / \
        np.maximum(cnt, 1)
    feats = np.column_stack([np.exp(X[:, 0]), X[:, 1:]])
    fmean = np.stack([np.bincount(ids_sk, weights=feats[:, k], minlength=n + 1)
                      / np.maximum(cnt, 1) for k in range(feats.shape[1])], axis=1)
    tort = _tortuosity(lab, skel, n)
    names = np.array(["unknown", "tensile", "shear", "mixed"])
    rows = []
    for cid in np.unique(lab[mask]):
        f = np.array([fr[0][cid], fr[1][cid], fr[2][cid]])
        k = int(np.argmax(f)) + 1 if f.sum() > 0 else 0
        if k in (1, 2, 3):
            conf = margin[cid] if cnt[cid] > 0 else 0.5
        else:
            conf = 0.0
        rows.append([int(cid), names[k], float(np.clip(conf, 0, 1)) * f.max() if k else 0.0,
                     *f.tolist(), float(ft_obj[cid]) if cnt[cid] else np.nan,
                     *fmean[cid].tolist(), float(tort[cid])])
    return pd.DataFrame(rows, columns=cols), type_img


def _tortuosity(lab, skel, n):
    """Skeleton pixel count over the maximum Feret diameter, per object (1 = straight)."""
    from skimage.measure import regionprops
    out = np.full(n + 1, np.nan)
    sk_count = np.bincount(lab[skel], minlength=n + 1)
    for rp in regionprops(lab):
        out[rp.label] = sk_count[rp.label] / max(rp.feret_diameter_max, 1.0)
    return out


# ----------------------------------------------------------------------------- training
def _fit_logistic(X, y, *, l2=1e-3, n_iter=50):
    """Newton-IRLS logistic regression on standardised features; returns (coef, intercept)."""
    n, d = X.shape
    A = np.column_stack([X, np.ones(n)])
    beta = np.zeros(d + 1)
    reg = l2 * np.eye(d + 1)
    reg[-1, -1] = 0.0
    for _ in range(n_iter):
        s = np.clip(A @ beta, -50, 50)
        p = 1.0 / (1.0 + np.exp(-s))
        wgt = np.maximum(p * (1 - p), 1e-9)
        g = A.T @ (p - y) + reg @ beta * n
        H = (A * wgt[:, None]).T @ A + reg * n
        step = np.linalg.solve(H, g)
        beta -= step
        if np.max(np.abs(step)) < 1e-8:
            break
    return beta[:-1], float(beta[-1])


def train_post(samples, *, window_px=WINDOW_PX, link_px=LINK_PX, seed=None):
    """Fit the post-test model from labelled cracks.

    Parameters
    ----------
    samples : iterable of (crack_labels, labels) or (crack_labels, labels, image)
        ``crack_labels`` an (M, N) int array of crack objects and ``labels`` a dict
        {crack_id: "tensile"|"shear"|"mixed"} (unlabelled objects are ignored), or an (M, N)
        label image of type codes (0 none, 1 tensile, 2 shear, 3 mixed) per pixel; ``image``
        the (flattened, denoised) grey image, for the ``dark_fill`` feature.
    window_px, link_px : int, float
        Feature window and cluster link distance stored in the model.
    seed : int, optional
        Seed of the subsampling of skeleton pixels (at most 200 000 are used).

    Returns
    -------
    model : dict
        :data:`DEFAULT_POST_MODEL` form; ``mixed_share`` chosen (when mixed labels exist)
        to maximise the correctly typed labelled crack area.

    Raises
    ------
    InputError
        No tensile or no shear pixels among the labels.
    """
    codes = {"tensile": 1, "shear": 2, "mixed": 3}
    Xs, ys, per_sample = [], [], []
    for sample in samples:
        crack_labels, labels = sample[0], sample[1]
        image = sample[2] if len(sample) > 2 else None
        lab = np.asarray(crack_labels)
        n = int(lab.max())
        if isinstance(labels, dict):
            code = np.zeros(n + 1, np.int64)
            for k, v in labels.items():
                if int(k) <= n and str(v) in codes:
                    code[int(k)] = codes[str(v)]
            pix_code = code[lab]
        else:
            pix_code = np.asarray(labels).astype(np.int64)
            if pix_code.shape != lab.shape:
                raise InputError(f"label image: expected shape {lab.shape}, "
                                 f"got {pix_code.shape}")
        skel = _skeleton(lab > 0)
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
    rng = np.random.default_rng(seed)
    if len(y) > 200_000:
        keep = rng.choice(len(y), 200_000, replace=False)
        X, y = X[keep], y[keep]
    mean = np.nan_to_num(np.nanmean(X, axis=0))
    scale = np.nan_to_num(np.nanstd(X, axis=0))
    scale[scale == 0] = 1.0
    coef, intercept = _fit_logistic(np.nan_to_num((X - mean) / scale), y)
    model = {"features": list(FEATURE_NAMES), "mean": mean.tolist(), "scale": scale.tolist(),
             "coef": coef.tolist(), "intercept": intercept, "mixed_share": MIXED_SHARE,
             "window_px": int(window_px), "link_px": float(link_px)}
    # mixed share: maximise the correctly typed labelled crack area (rule of classify_post)
    stats = []  # per sample: traces' f_T, mixed share, labelled area of each code per trace
    for lab, skel, rr, cc, Xi, pix_code in per_sample:
        pix, ft, ms = _assign_traces(lab, skel, rr, cc, _p_tensile(Xi, model),
                                     link_px=link_px)
        sel = (pix >= 0) & (pix_code > 0)
        area = np.zeros((len(ft), 4))
        np.add.at(area, (pix[sel], pix_code[sel]), 1.0)
        stats.append((ft, ms, area))
    if any(a[:, 3].sum() > 0 for _, _, a in stats):  # only with mixed labels
        best = (-1.0, MIXED_SHARE)
        for share in np.arange(0.05, 0.51, 0.05):
            m = dict(model, mixed_share=float(share))
            good = sum(a[np.arange(len(f)), _trace_codes(f, s, m)].sum() for f, s, a in stats)
            if good > best[0] + 1e-9:
                best = (good, round(float(share), 2))
        model["mixed_share"] = best[1]
    return model


def save_model(model, path):
    """Write a post-test model as JSON (temporary file, then rename)."""
    path = str(path)
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(model, fh, indent=1)
    os.replace(tmp, path)


def load_model(path):
    """Read a post-test model JSON written by :func:`save_model`; checks its fields."""
    try:
        with open(path) as fh:
            model = json.load(fh)
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot read crack model ({exc})") from None
    need = ("mean", "scale", "coef", "intercept", "mixed_share")
    miss = [k for k in need if k not in model]
    if miss:
        raise InputError(f"{path}: crack model lacks field(s) {miss}")
    if len(model["coef"]) != len(FEATURE_NAMES):
        raise InputError(f"{path}: crack model has {len(model['coef'])} coefficients, "
                         f"expected {len(FEATURE_NAMES)}")
    return model


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
                 "endpoint_density", "excess_dark", "skeleton_scatter", "dark_fill")


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
    from .pipeline import CrackAnalysis, AnalysisOptions
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
