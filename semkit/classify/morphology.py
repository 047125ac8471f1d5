"""Per-crack morphology, the evidence for tensile / shear / mixed typing (the thesis's criteria).

Tensile cracks open normal to their trace and keep complete, matching walls: a near-constant
aperture along one clean trace, dark across its whole width. Shear cracks slide: the walls no
longer match, so the aperture varies and closes (incomplete walls), the trace steps sideways
(en-echelon offsets), splits into parallel layers and sheds debris. Mixed cracks show both
along one crack.

The unit typed is a crack *group*: a crack object with the small fragments and debris within
``LINK_PX`` of it (:func:`crack_groups`). (Joining groups that continue each other across gaps
into longer traces was tried: on the training family it joined distinct cracks as often as the
pieces of one, and typing accuracy fell on every evaluation set.) :func:`crack_morphology`
measures the features of every group from an OpenCV distance transform (5 x 5 mask) and box
sums at skeleton pixels (numba), summed per group with ``bincount``: the cost grows with the
skeleton, not with the number of cracks.

Features (:data:`FEATURE_NAMES`), per group, over its skeleton pixels unless said otherwise:

- ``log_aperture`` — mean log of the aperture (2 x distance to the wall - 1, px);
- ``aperture_cv`` — SD / mean of the aperture along the whole group (matching walls: low;
  mixed: a wide and a thin part);
- ``local_cv`` — mean over the skeleton of the aperture's SD / mean in a ``WINDOW_PX`` box
  (walls that no longer match);
- ``scatter`` — mean RMS distance (px) of the skeleton from its local straight line in the box
  (steps, offsets, layers);
- ``layers`` — skeleton pixels per unit of trace length in the box (1 for one trace, 2 for a
  pair of layers);
- ``endpoints`` — skeleton end points per 100 px of skeleton (incomplete walls, steps, debris);
- ``pieces`` — log(1 + objects per 100 px of skeleton) (fragmented traces);
- ``excess`` — dark area in the box not explained by the trace's own aperture, over the
  trace's area (debris, parallel fragments);
- ``fill`` — mean partial-volume darkness (B - I)/(B - I_core) of the group's mask pixels (a
  clean opening reads about 1; thin, bridged or layered traces read lighter);
- ``thin_share``, ``wide_share`` — share of the skeleton with aperture <= 2 px and >= 4 px;
- ``log_length`` — log of the group's skeleton length, px.

The same quantities in the box around every skeleton pixel (:data:`LOCAL_NAMES`) tell a
tensile stretch from a shear stretch along one crack (``semkit.classify.model``, stage 1).
"""
from __future__ import annotations

import numpy as np

from .. import config

__all__ = ["crack_groups", "crack_morphology", "group_quantile", "FEATURE_NAMES",
           "LOCAL_NAMES", "WINDOW_PX", "LINK_PX", "SMALL_OBJECT_PX"]

#: side of the box of the local features, px.
WINDOW_PX = 15
#: a small object within this distance (px) of a large crack belongs to its group.
LINK_PX = config.LINK_PX
#: objects with fewer pixels than this are small (debris, fragments).
SMALL_OBJECT_PX = config.SMALL_OBJECT_PX
#: aperture limits of thin_share and wide_share, px.
THIN_PX, WIDE_PX = 2.0, 4.0
#: side of the grey closing that estimates the background when none is given, px.
BACKGROUND_PX = 11
FEATURE_NAMES = ("log_aperture", "aperture_cv", "local_cv", "scatter", "layers", "endpoints",
                 "pieces", "excess", "fill", "thin_share", "wide_share", "log_length")
#: features of each skeleton pixel, over the box around it.
LOCAL_NAMES = ("log_aperture", "local_cv", "scatter", "layers", "excess", "end_density",
               "fill")


def crack_groups(crack_labels, *, link_px=LINK_PX, small_px=SMALL_OBJECT_PX, area=None):
    """Group id of every object: small objects join the nearest large object within link_px.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Objects 1..n.

    area : (n + 1,) ndarray of int, optional
        Pixel count of each label, when already at hand.

    Returns
    -------
    group_of : (n + 1,) ndarray of int64
        Group of each object id (0 -> 0): a large object is its own group (its id), a small
        object takes the id of the nearest large object within ``link_px``, or keeps its own.

    Examples
    --------
    >>> lab = np.zeros((20, 40), np.int32); lab[5:8, 2:30] = 1; lab[10, 10:12] = 2
    >>> lab[18, 35] = 3
    >>> crack_groups(lab).tolist()
    [0, 1, 1, 3]
    """
    import cv2
    lab = np.asarray(crack_labels)
    n = int(lab.max()) if area is None else len(area) - 1
    group_of = np.arange(n + 1, dtype=np.int64)
    if n == 0:
        return group_of
    if area is None:
        area = np.bincount(lab.ravel(), minlength=n + 1)
    big = area >= small_px
    big[0] = False
    small = (~big) & (area > 0)
    small[0] = False
    if not big.any() or not small.any():
        return group_of
    kind = big.astype(np.uint8)     # per label: 0 background, 1 large, 2 small
    kind[small] = 2
    kind_img = kind[lab]
    big_mask = kind_img == 1
    # each small object looks for large ones in its own box, grown by the link distance and a
    # margin: a large pixel outside lies more than link_px away in the chessboard metric, so
    # further in the chamfer one, and every distance up to link_px reads as on the whole image
    from .._kernels import pixel_coords
    rr, cc = pixel_coords(kind_img == 2)
    ids = lab[rr, cc]
    order = np.argsort(ids, kind="stable")          # each object's pixels in raster order
    ids, rr, cc = ids[order], rr[order], cc[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    ends = np.r_[starts[1:], ids.size]
    grow = int(np.ceil(link_px)) + 3
    h, w = lab.shape
    for a, b in zip(starts, ends):
        r, c = rr[a:b], cc[a:b]
        r0, c0 = max(int(r.min()) - grow, 0), max(int(c.min()) - grow, 0)
        r1, c1 = min(int(r.max()) + grow + 1, h), min(int(c.max()) + grow + 1, w)
        bm = big_mask[r0:r1, c0:c1]
        if not bm.any():
            continue
        dist, near = cv2.distanceTransformWithLabels(
            np.ascontiguousarray(~bm).view(np.uint8), cv2.DIST_L2, 5,
            labelType=cv2.DIST_LABEL_PIXEL)
        d = dist[r - r0, c - c0]
        k = int(np.argmin(d))                   # the first pixel at the least distance
        if d[k] <= link_px:
            src = np.zeros(int(near.max()) + 1, np.int64)
            src[near[bm]] = lab[r0:r1, c0:c1][bm]
            group_of[ids[a]] = src[near[r[k] - r0, c[k] - c0]]
    return group_of


def group_quantile(g, v, q, m):
    """q-quantile (lower) of the values v of each group id in g; NaN for empty groups."""
    order = np.lexsort((v, g))
    gs = g[order]
    start = np.searchsorted(gs, np.arange(m))
    count = np.bincount(g, minlength=m)
    out = np.full(m, np.nan)
    has = count > 0
    out[has] = v[order][start[has] + np.floor(q * (count[has] - 1)).astype(int)]
    return out


def crack_morphology(crack_labels, *, image=None, skeleton=None, background=None,
                     crack_level=None, window_px=WINDOW_PX, link_px=LINK_PX, area=None):
    """Morphology of every crack group, and of every skeleton pixel.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects 1..n.
    image : (M, N) ndarray, optional
        Flattened, denoised grey image; without it ``fill`` is NaN.
    skeleton : (M, N) ndarray of bool, optional
        Skeleton of the crack mask (computed when not given).
    background, crack_level : (M, N) ndarray and float, optional
        Local background and crack-core grey of the threshold stage (estimated when not
        given: a grey closing over ``BACKGROUND_PX`` and the 2nd percentile of the cracks).
    window_px : int
    link_px : float
    area : (n + 1,) ndarray of int, optional
        Pixel count of each label (index = label, n the largest), when already at hand.

    Returns
    -------
    group_of : (n + 1,) ndarray of int64
        Group of each object (:func:`crack_groups`).
    features : (n + 1, K) ndarray of float64
        Features of each group, indexed by group id (rows of ids that are not groups, and
        groups without skeleton, are NaN), columns :data:`FEATURE_NAMES`.
    local : dict
        ``rr, cc`` (skeleton pixels), ``group`` (their group ids) and ``X`` (their local
        features in the box, columns :data:`LOCAL_NAMES`).
    """
    import cv2

    from .._kernels import pixel_coords, skeleton_window_sums
    from ..skeleton import skeletonize
    lab = np.asarray(crack_labels)
    n = int(lab.max()) if area is None else len(area) - 1
    F = np.full((n + 1, len(FEATURE_NAMES)), np.nan)
    empty = dict(rr=np.zeros(0, int), cc=np.zeros(0, int), group=np.zeros(0, int),
                 X=np.zeros((0, len(LOCAL_NAMES))))
    if n == 0:
        return np.zeros(1, np.int64), F, empty
    mask = lab > 0
    skel = skeletonize(mask) if skeleton is None else (np.asarray(skeleton, bool) & mask)
    group_of = crack_groups(lab, link_px=link_px, area=area)
    rr, cc = pixel_coords(skel)
    g = group_of[lab[rr, cc]]
    mask8 = mask.view(np.uint8)
    at = np.flatnonzero(mask)        # the mask pixels, raster order
    dist = cv2.distanceTransform(mask8, cv2.DIST_L2, cv2.DIST_MASK_5)
    ap = np.maximum(2.0 * dist[rr, cc] - 1.0, 1.0).astype(np.float64)
    ap_img = np.zeros(lab.shape, np.float64)
    ap_img[rr, cc] = ap
    dark = np.zeros(lab.shape, np.float64)
    if image is not None:
        grey = np.asarray(image, np.float32)
        if background is None:
            k = cv2.getStructuringElement(cv2.MORPH_RECT, (BACKGROUND_PX, BACKGROUND_PX))
            background = cv2.morphologyEx(grey, cv2.MORPH_CLOSE, k)
        core = float(crack_level) if crack_level is not None and np.isfinite(crack_level) \
            else float(np.percentile(grey[mask], 2))
        bg = np.asarray(background, np.float32).ravel()[at]
        dark.ravel()[at] = np.clip((bg - grey.ravel()[at]) / np.maximum(bg - core, 1e-6), 0, 1)
    sk8 = skel.astype(np.uint8)
    nb = cv2.filter2D(sk8, cv2.CV_16S, np.ones((3, 3), np.float32),
                      borderType=cv2.BORDER_CONSTANT) - sk8
    ends = (skel & (nb <= 1)).astype(np.uint8)
    w = int(window_px)
    win = np.empty((rr.size, 11))
    skeleton_window_sums(sk8, ap_img, mask8, ends, dark, rr.astype(np.int64),
                         cc.astype(np.int64), w // 2, win)
    s0, sx, sy, sxx, syy, sxy, sa, saa, sm, se, sd = win.T
    mx, my = sx / s0, sy / s0
    cxx, cyy, cxy = sxx / s0 - mx * mx, syy / s0 - my * my, sxy / s0 - mx * my
    half = (cxx + cyy) / 2
    root = np.sqrt(np.maximum(((cxx - cyy) / 2) ** 2 + cxy ** 2, 0))
    lmin, lmax = np.maximum(half - root, 0), np.maximum(half + root, 1e-9)
    theta = 0.5 * np.arctan2(2 * cxy, cxx - cyy)
    step = np.maximum(np.abs(np.cos(theta)), np.abs(np.sin(theta)))   # px per unit length
    amean = sa / s0
    L = np.column_stack([
        np.log(amean),
        np.sqrt(np.maximum(saa / s0 - amean ** 2, 0)) / amean,
        np.sqrt(lmin),
        s0 * step / np.minimum(np.sqrt(12 * lmax), w * np.sqrt(2)),
        np.maximum(sm - sa, 0) / np.maximum(sa, 1),
        100 * se / s0,
        sd / np.maximum(sm, 1) if image is not None else np.full(rr.size, np.nan)])
    end = ends[rr, cc].astype(np.float64)
    gm = group_of[lab.ravel()[at]]
    dark_at = dark.ravel()[at] if image is not None else None
    F = group_features(n + 1, g, ap, end, L, np.bincount(group_of[1:], minlength=n + 1),
                       gm, dark_at)
    return group_of, F, dict(rr=rr, cc=cc, group=g, X=L, aperture=ap, end=end, at=at,
                             dark=dark_at)


def group_features(m, g, ap, end, L, n_obj, gm=None, dark=None):
    """Features (:data:`FEATURE_NAMES`) of groups 0..m-1 from their skeleton pixels' local
    measures.

    Parameters
    ----------
    m : int
        Number of group ids (rows of the result).
    g : (k,) ndarray of int
        Group of each skeleton pixel.
    ap, end : (k,) ndarray of float
        Local aperture (px) of each skeleton pixel and 1 where it is a skeleton end.
    L : (k, len(LOCAL_NAMES)) ndarray
        Local features of each skeleton pixel.
    n_obj : (m,) ndarray of int
        Objects in each group.
    gm, dark : (j,) ndarray, optional
        Group and darkness fraction of each mask pixel (the ``fill`` feature; NaN without).

    Returns
    -------
    features : (m, len(FEATURE_NAMES)) ndarray of float64
        NaN rows for groups without skeleton pixels.
    """
    F = np.full((m, len(FEATURE_NAMES)), np.nan)
    cnt = np.bincount(g, minlength=m).astype(np.float64)

    def gmean(v):
        return np.bincount(g, weights=v, minlength=m) / np.maximum(cnt, 1)

    a1, a2 = gmean(ap), gmean(ap * ap)
    F[:, 0] = gmean(np.log(ap))
    F[:, 1] = np.sqrt(np.maximum(a2 - a1 ** 2, 0)) / np.maximum(a1, 1e-9)
    for j, k in ((2, 1), (3, 2), (4, 3), (7, 4)):
        F[:, j] = gmean(L[:, k])
    F[:, 5] = 100 * np.bincount(g, weights=end, minlength=m) / np.maximum(cnt, 1)
    F[:, 6] = np.log1p(100 * np.asarray(n_obj, np.float64) / np.maximum(cnt, 1))
    F[:, 9] = gmean((ap <= THIN_PX).astype(float))
    F[:, 10] = gmean((ap >= WIDE_PX).astype(float))
    F[:, 11] = np.log(np.maximum(cnt, 1))
    if dark is not None:
        F[:, 8] = np.bincount(gm, weights=dark, minlength=m) / np.maximum(
            np.bincount(gm, minlength=m), 1)
    F[cnt == 0] = np.nan
    return F
