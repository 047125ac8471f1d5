"""Crack traces: skeleton branches that continue each other, and their along-trace features.

A crack object's skeleton is split into branches at junctions (skan). Branches that continue
each other across a junction, or across a short gap between objects, within
:data:`CONTINUE_DEG` form one *trace*: ideally one crack, so that a crossing crack is another
trace. Every crack pixel belongs to the trace of its nearest skeleton pixel in its cluster
(small debris objects join the nearest large crack). :func:`trace_features` summarises the
per-pixel tensile probability and aperture along each trace (:data:`TRACE_FEATURE_NAMES`);
``semkit.classify.model`` types each trace from them.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

from .. import config
from .features import LINK_PX, nearest_in_cluster

__all__ = ["traces", "trace_features", "TRACE_FEATURE_NAMES"]

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
#: length (px) of the pieces a branch is cut into for the along-trace extremes.
CHUNK_PX = 24
#: running mean (px) of the log aperture along a branch.
APERTURE_SMOOTH_PX = 7
#: per-trace features, in model order (p = per-pixel P(tensile), a = log aperture).
TRACE_FEATURE_NAMES = ("tensile_share", "p_mean", "mixed_run_share", "log_aperture_mean",
                       "log_aperture_p10", "log_aperture_p90", "log_aperture_sd",
                       "chunk_p_min", "chunk_p_max", "chunk_tensile_share", "log_length",
                       "chunk_log_aperture_min", "chunk_log_aperture_max")


def traces(skel, *, short_px=SHORT_BRANCH_PX, angle_deg=CONTINUE_DEG, gap_px=GAP_PX):
    """Split a skeleton into branches (skan) and join branches that continue each other.

    Parameters
    ----------
    skel : (M, N) ndarray of bool
    short_px : int
        Branches shorter than this are not joined (spurs, steps).
    angle_deg : float
        Largest deviation from a straight continuation.
    gap_px : float
        Largest gap between the facing ends of two branches.

    Returns
    -------
    coords : list of (K, 2) ndarray of int64
        Pixels (row, col) of each branch, in order along it.
    trace : (n_branches,) ndarray of int
        Trace id (a branch index) of each branch.
    short : (n_branches,) ndarray of bool
    """
    from skan import Skeleton
    if not np.asarray(skel).any():
        return [], np.zeros(0, int), np.zeros(0, bool)
    sk = Skeleton(np.asarray(skel, bool))
    n = sk.n_paths
    coords = [np.asarray(sk.path_coordinates(i)).astype(np.int64) for i in range(n)]
    short = np.array([len(c) for c in coords]) < short_px
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
        for a_, b_ in cKDTree(pts).query_pairs(gap_px):
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
    return coords, np.array([find(i) for i in range(n)]), short


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


def _one_trace(paths, P, la_img):
    """Along-trace features of one trace from its branches' pixel lists."""
    pp, la, chunks, chla = [], [], [], []
    run_t = run_s = 0.0
    length = 0
    for c in paths:
        pv = P[c[:, 0], c[:, 1]]
        a = ndi.uniform_filter1d(la_img[c[:, 0], c[:, 1]], APERTURE_SMOOTH_PX, mode="nearest")
        pp.append(pv)
        la.append(a)
        lt, ls = _long_runs(_smooth_runs(pv > 0.5), MIN_RUN_PX)
        run_t += lt
        run_s += ls
        length += len(c)
        for q in np.array_split(np.arange(len(c)), max(int(round(len(c) / CHUNK_PX)), 1)):
            chunks.append(pv[q].mean())
            chla.append(a[q].mean())
    pp, la = np.concatenate(pp), np.concatenate(la)
    chunks, chla = np.array(chunks), np.array(chla)
    return [(pp > 0.5).mean(), pp.mean(), min(run_t, run_s) / max(length, 1), la.mean(),
            np.percentile(la, 10), np.percentile(la, 90), la.std(), chunks.min(),
            chunks.max(), (chunks > 0.5).mean(), np.log(length), chla.min(), chla.max()]


def trace_features(crack_labels, rr, cc, p, *, skeleton=None, link_px=LINK_PX):
    """Group the crack pixels into traces and measure each trace.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
    rr, cc : (K,) ndarray of int
        Skeleton pixels (as returned by :func:`semkit.classify.features.post_features`).
    p : (K,) ndarray of float
        P(tensile) of each skeleton pixel.
    skeleton : (M, N) ndarray of bool, optional
        The skeleton (default: the pixels rr, cc).
    link_px : float
        Small objects this close to a large crack belong to its traces.

    Returns
    -------
    pix : (M, N) ndarray of int64
        Trace id of every crack pixel (-1 for pixels of a cluster without a skeleton).
    F : (T, 13) ndarray of float64
        Features in :data:`TRACE_FEATURE_NAMES` order (NaN rows for ids without pixels).
    area : (T,) ndarray of float64
        Crack pixels per trace.

    Notes
    -----
    Branches shorter than ``SHORT_BRANCH_PX`` (spurs, steps) take the trace of the nearest
    long branch; an object whose skeleton is all short branches is one trace.
    """
    lab = np.asarray(crack_labels)
    mask = lab > 0
    if skeleton is None:
        skeleton = np.zeros(lab.shape, bool)
        skeleton[rr, cc] = True
    P = np.full(lab.shape, np.nan)
    P[rr, cc] = p
    la_img = np.log(np.maximum(2.0 * ndi.distance_transform_edt(mask), 0.5))
    coords, trace, short = traces(skeleton)
    n_tr = len(trace)
    seed_img = np.full(lab.shape, -1, np.int64)
    members = {}
    for i, c in enumerate(coords):
        if not short[i]:
            seed_img[c[:, 0], c[:, 1]] = trace[i]
            members.setdefault(int(trace[i]), []).append(c)
    has_long = np.zeros(int(lab.max()) + 1, bool)
    has_long[lab[seed_img >= 0]] = True
    extra = {}  # objects whose skeleton is all short branches: one trace per object
    for i, c in enumerate(coords):
        obj = int(lab[c[0, 0], c[0, 1]])
        if short[i] and not has_long[obj]:
            t = extra.setdefault(obj, n_tr + len(extra))
            seed_img[c[:, 0], c[:, 1]] = t
            members.setdefault(t, []).append(c)
    n_all = n_tr + len(extra)
    pix = nearest_in_cluster(lab, seed_img, link_px=link_px)
    pix[~mask] = -1
    F = np.full((n_all, len(TRACE_FEATURE_NAMES)), np.nan)
    for t, paths in members.items():
        F[t] = _one_trace(paths, P, la_img)
    area = np.bincount(pix[pix >= 0], minlength=n_all).astype(np.float64)
    return pix, F, area
