"""Per-pixel morphology of crack skeletons, the evidence for tensile / shear typing.

At every skeleton pixel of the crack objects, :func:`post_features` measures the local
opening and its regularity, the darkness of the mask, parallel layers across the trace and
debris alongside it (:data:`FEATURE_NAMES`). :func:`crack_clusters` attaches small objects
(debris, en-echelon fragments) to the nearest large crack. ``semkit.classify.traces`` groups the
skeleton pixels into traces and ``semkit.classify.model`` turns the features into types.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

from .. import config

__all__ = ["post_features", "crack_clusters", "nearest_in_cluster", "skeleton_of",
           "FEATURE_NAMES", "WINDOW_PX", "LINK_PX", "SMALL_OBJECT_PX"]

#: half-size of the feature window around each skeleton pixel, px.
WINDOW_PX = config.WINDOW_PX
#: a small object (debris, fragment) within this distance (px) of a large crack takes its type.
LINK_PX = config.LINK_PX
#: objects with fewer pixels than this are "small" (debris, fragments).
SMALL_OBJECT_PX = config.SMALL_OBJECT_PX
#: half-length (px) of the grey profile sampled across the trace at each skeleton pixel.
PROFILE_HALF_PX = 7.0
#: side (px) of the square window over which the trace direction is estimated.
ORIENT_WINDOW_PX = 11
#: sides (px) of the small windows of the local dark fill (mean darkness of the mask pixels).
FILL_WINDOWS_PX = (5, 9)
#: running mean (px) of the local dark fill along the skeleton.
FILL_SMOOTH_PX = 11
#: feature names, in model order.
FEATURE_NAMES = ("log_aperture", "aperture_cv", "dark_density", "skeleton_density",
                 "endpoint_density", "excess_dark", "skeleton_scatter", "dark_fill",
                 "layer_lift", "layer_side", "fill_5", "fill_9", "fill_9_smooth")


def skeleton_of(mask):
    """Skeleton (scikit-image ``skeletonize``) of a boolean mask."""
    from skimage.morphology import skeletonize
    return skeletonize(np.asarray(mask, bool))


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


def nearest_in_cluster(lab, seed, *, link_px=LINK_PX):
    """Value of the nearest ``seed >= 0`` pixel of the same cluster, for every crack pixel.

    Parameters
    ----------
    lab : (M, N) ndarray of int
        Crack objects.
    seed : (M, N) ndarray of int
        Values to spread; negative = no value. Pixels of a cluster without a seed get -1.
    link_px : float
        See :func:`crack_clusters`.

    Returns
    -------
    out : (M, N) ndarray of int64
    """
    mask = lab > 0
    out = np.full(lab.shape, -1, np.int64)
    clus = crack_clusters(lab, link_px=link_px)[lab]
    for cid in np.unique(clus[mask]):
        sel = clus == cid
        rows = np.flatnonzero(sel.any(axis=1))
        cols = np.flatnonzero(sel.any(axis=0))
        win = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
        seeds = sel[win] & (seed[win] >= 0)
        if not seeds.any():
            continue
        _, (ir, ic) = ndi.distance_transform_edt(~seeds, return_indices=True)
        v = seed[win][ir, ic]
        out[win][sel[win]] = v[sel[win]]
    return out


def _window_means(rr, cc, shape, size, *values):
    """Mean of each per-skeleton-pixel value over the skeleton pixels of a size x size window."""
    sk = np.zeros(shape)
    sk[rr, cc] = 1.0
    ns = np.maximum(ndi.uniform_filter(sk, size, mode="constant")[rr, cc], 1e-12)
    out = []
    for v in values:
        im = np.zeros(shape)
        im[rr, cc] = v
        out.append(ndi.uniform_filter(im, size, mode="constant")[rr, cc] / ns)
    return out


def _layer_profile(image, rr, cc, shape):
    """Parallel dark layers across the trace, from the grey profile normal to it.

    Returns (lift, side) per skeleton pixel, in units of the local crack depth: ``lift`` is
    how much lighter the centre is than the darkest point on each side (two layers with the
    mask filled between them), ``side`` a second dark layer 3-7 px to one side behind a
    lighter ridge (a thin trace beside another).
    """
    img = ndi.gaussian_filter(np.asarray(image, np.float64), 0.5)
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float64)
    mx, my, sxx, syy, sxy = _window_means(rr, cc, shape, ORIENT_WINDOW_PX, cc, rr, cc * cc,
                                          rr * rr, cc * rr)
    th = 0.5 * np.arctan2(2 * (sxy - mx * my), (sxx - mx * mx) - (syy - my * my))
    nx, ny = -np.sin(th), np.cos(th)
    t = np.arange(-PROFILE_HALF_PX, PROFILE_HALF_PX + 0.01, 0.5)
    ys = rr[:, None] + ny[:, None] * t[None]
    xs = cc[:, None] + nx[:, None] * t[None]
    prof = ndi.map_coordinates(img, [ys.ravel(), xs.ravel()], order=1,
                               mode="nearest").reshape(ys.shape)
    bg = prof[:, [0, 1, -2, -1]].max(axis=1)
    depth = np.maximum(bg - prof.min(axis=1), 1.0)
    c = len(t) // 2
    centre = prof[:, c - 1:c + 2].min(axis=1)
    left = prof[:, :c - 1].min(axis=1)
    right = prof[:, c + 2:].min(axis=1)
    lift = (centre - np.maximum(left, right)) / depth
    side = np.zeros(len(rr))
    for sgn in (-1.0, 1.0):
        far = (sgn * t >= 3) & (sgn * t <= 7)
        mid = (sgn * t > 0.5) & (sgn * t < 3)
        fmin = prof[:, far].min(axis=1)
        ridge = prof[:, mid].max(axis=1)
        s = (ridge - np.maximum(fmin, centre)) / depth * (bg - fmin) / depth
        side = np.maximum(side, s)
    return np.clip(lift, -1.0, 1.0), np.clip(side, 0.0, 1.0)


def post_features(crack_labels, *, image=None, skeleton=None, window_px=WINDOW_PX):
    """Morphological features at each skeleton pixel of the cracks.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects (and debris specks: keep them, they are evidence of shear).
    image : (M, N) ndarray, optional
        Flattened, denoised grey image (cracks dark). Without it the grey-level features are
        NaN (a model treats them as neutral).
    skeleton : (M, N) ndarray of bool, optional
    window_px : int
        Half-size of the square window.

    Returns
    -------
    rows, cols : (K,) ndarray of int
        Skeleton pixel positions.
    X : (K, 13) ndarray of float64
        Features in :data:`FEATURE_NAMES` order:

        - log local aperture (px; aperture = 2 x distance to the wall), aperture coefficient
          of variation, dark-pixel density, skeleton density (px of skeleton per px of window
          side: ~1 for one trace, ~2 for layered traces), endpoint density (per window side),
          excess dark density (dark area not explained by the skeleton x aperture: debris),
          skeleton scatter (px, RMS distance of the window's skeleton from its best line);
        - from the grey image: dark fill (partial-volume dark width / aperture over the
          window), layer lift and layer side (window means of :func:`_layer_profile`: two
          parallel dark layers), and the mean darkness of the mask pixels in 5 x 5 and 9 x 9
          windows, the latter also smoothed along the skeleton (low where the mask fills the
          lighter gap between layered traces).
    """
    lab = np.asarray(crack_labels)
    mask = lab > 0
    skel = skeleton_of(mask) if skeleton is None else (np.asarray(skeleton, bool) & mask)
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
    grey = np.full((len(rr), 6), np.nan)
    if image is not None and len(rr):
        from ..damage_areas import darkness_fraction
        f, _ = darkness_fraction(image, lab)
        # dark (partial-volume) width per skeleton px over the mask aperture: ~1 for an
        # open crack, well below 1 where the mask bridges or fills between thin traces
        grey[:, 0] = box(f)[rr, cc] / ns / np.maximum(wm, 1.0)
        lift, side = _layer_profile(image, rr, cc, lab.shape)
        grey[:, 1], grey[:, 2] = _window_means(rr, cc, lab.shape, size,
                                               np.maximum(lift, 0.0), side)
        fm = f * mask
        for k, s in enumerate(FILL_WINDOWS_PX):
            num = ndi.uniform_filter(fm, s, mode="constant")[rr, cc]
            den = ndi.uniform_filter(mask.astype(np.float64), s, mode="constant")[rr, cc]
            grey[:, 3 + k] = num / np.maximum(den, 1e-9)
        grey[:, 5] = _window_means(rr, cc, lab.shape, FILL_SMOOTH_PX, grey[:, 4])[0]
    X = np.column_stack([np.log(np.maximum(wm, 0.5)), cv, dk, skel_dens, end_dens, excess,
                         scatter, grey])
    return rr, cc, X
