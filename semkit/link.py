"""Linking of faint, beaded cracks: an oriented line response joins the pieces a threshold
found along one crack.

A thin crack in a textured grain is often a row of dark beads (where it opens) joined by a
line only a few grey levels deep. The threshold finds the beads; each is too small or too
round to count as a crack, and the faint line between them is below the per-pixel ridge
response's noise (:mod:`semkit.ridge`). Averaged *along* the line, the faint segments and the
beads add up while texture, which is not collinear, does not: :func:`line_response` is a
steerable matched filter (second derivative across, Gaussian along, maximum over directions).

:func:`link_lines` keeps the pixels where that response passes ``LINK_SNR`` noise units
and that are connected to an accepted crack (hysteresis with the cracks as seeds: a line that
touches none seeds nothing), in sparse zones only (less than ``LINK_MAX_DENSITY`` of the
surroundings detected: among many dark pieces, which are one crack is not a line filter's
call) and not beside anything much brighter than the rock (``LINK_MAX_LIFT``: the dark halo of
a bright grain or particle is its rim). :func:`add_link_lines` adds the pieces that join two
objects or reach beyond one, except pieces closing a new loop (a ring of lines around a grain
is its rim) and links that leave the object shorter than ``LINK_MIN_CHAIN_PX`` (two specks
joined are no crack; a row of beads joined is).

The analysis (:class:`semkit.analysis.CrackAnalysis`) links after a first, unlinked pass has
judged the objects (:mod:`semkit.reject`): its cracks seed the lines; objects it rejected for
their own shape (a bead too round or short on its own) and pores may be passed through;
objects it rejected for their surroundings (``LINK_EXCLUDE_RULES``: dark phase, mottled zone,
grain rim) are kept ``LINK_EXCLUDE_PX`` away from, so a faint line never joins one (and is
not rejected with it).
"""
from __future__ import annotations

import numpy as np

from . import config

__all__ = ["line_response", "link_lines", "add_link_lines"]


def _line_kernels(sigma, length, theta):
    """Scale-normalised second and first derivative across direction ``theta`` of an
    anisotropic Gaussian (``sigma`` across, ``length`` along), as float32 kernels."""
    h = int(np.ceil(3.0 * max(sigma, length)))
    y, x = np.mgrid[-h:h + 1, -h:h + 1].astype(np.float64)
    u = x * np.cos(theta) + y * np.sin(theta)
    v = -x * np.sin(theta) + y * np.cos(theta)
    g = np.exp(-0.5 * (u / sigma) ** 2 - 0.5 * (v / length) ** 2)
    g /= g.sum()
    kuu = (u * u / sigma ** 4 - 1.0 / sigma ** 2) * g
    kuu -= g * kuu.sum()  # no response to a flat image
    ku = -u / sigma ** 2 * g
    return (sigma * sigma * kuu).astype(np.float32), (sigma * ku).astype(np.float32)


def line_response(image, *, sigma=config.LINK_SIGMA_PX, length=config.LINK_LENGTH_PX,
                  n_orient=config.LINK_ORIENTATIONS, kappa=config.LINK_EDGE_KAPPA,
                  region=None):
    """Oriented dark-line response: the valley strength averaged along the line.

    At each of ``n_orient`` directions the image is filtered (``cv2.filter2D``) with the
    scale-normalised second derivative across that direction of a Gaussian elongated along it
    (``sigma`` across, ``length`` along), less ``kappa`` times the first derivative across
    (the dark side of a step edge has one, the centre of a line has none); the response is
    the maximum over the directions, clipped at 0. A straight line's response does not depend
    on ``length``; that of uncorrelated texture falls about as ``sqrt(sigma / length)``.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image (flattened, denoised), cracks dark.
    sigma, length : float
        Gaussian scale across and along the line, px.
    n_orient : int
        Number of directions over 180 degrees.
    kappa : float
        Weight of the edge (first-derivative) term.
    region : (M, N) ndarray of bool, optional
        Sample region: the noise is measured inside it only (a filled surround is smooth).

    Returns
    -------
    response : (M, N) ndarray of float32
        Grey units.
    noise : float
        Robust std of the signed second-derivative output at one direction: the unit of
        :func:`link_lines`' level.

    Examples
    --------
    >>> img = np.full((40, 60), 100, np.float32); img[20, 5:55] = 60
    >>> r, _ = line_response(img)
    >>> int(np.argmax(r[:, 30])), bool(r[20, 30] > 10 * r[10, 30] + 1)
    (20, True)
    """
    import cv2
    a = np.ascontiguousarray(image, np.float32)
    out = np.zeros(a.shape, np.float32)
    noise = None
    for k in range(int(n_orient)):
        kuu, ku = _line_kernels(float(sigma), float(length), np.pi * k / n_orient)
        d2 = cv2.filter2D(a, cv2.CV_32F, kuu, borderType=cv2.BORDER_REFLECT)
        d1 = cv2.filter2D(a, cv2.CV_32F, ku, borderType=cv2.BORDER_REFLECT)
        if noise is None:
            v = d2[::2, ::2]
            if region is not None and np.asarray(region)[::2, ::2].any():
                v = v[np.asarray(region, bool)[::2, ::2]]
            v = v.ravel()
            noise = float(1.4826 * np.median(np.abs(v - np.median(v))))
        np.maximum(out, d2 - np.float32(kappa) * np.abs(d1), out=out)
    return out, max(noise or 0.0, 1e-6)


def link_lines(image, seeds, *, crack_level, passable=None, exclude=None, region=None,
               snr=config.LINK_SNR,
               detected=None, max_density=config.LINK_MAX_DENSITY,
               max_lift=config.LINK_MAX_LIFT, min_depth_sigmas=config.LINK_DEPTH_SIGMAS):
    """Line pixels that continue or join the ``seeds`` objects.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image (flattened, denoised).
    seeds : (M, N) ndarray of bool
        Accepted crack objects: a line counts only when it touches one.
    crack_level : float
        Crack core grey.
    passable : (M, N) ndarray of bool, optional
        Objects a line may pass through but not start from (a bead too short or round to be
        accepted as a crack on its own).
    exclude : (M, N) ndarray of bool, optional
        Pixels no line may pass (objects rejected for their surroundings, and a margin).
    region : (M, N) ndarray of bool, optional
        Sample region.
    snr : float
        Least oriented line response, in its noise units.
    detected : (M, N) ndarray of bool, optional
        Everything the first pass detected; lines are drawn only where its share of a
        ``ZONE_WINDOW_PX`` window is below ``max_density`` (among many dark pieces, which of
        them are one crack is not decided by a line filter).
    max_density : float
    max_lift : float
        Lines are drawn only where their brighter side (the grey maximum within
        ``2 LINK_SIGMA_PX``) is brighter than the rock (the 75th percentile of that maximum)
        by less than this share of the contrast: the dark halo around a brighter grain or
        particle is its rim (as in the ``grain_rim`` rule of :mod:`semkit.reject`).
    min_depth_sigmas : float
        Line pixels lie at least this many pixel-noise sigmas below their local background
        (a ``RIDGE_CLOSING_PX`` grey closing): the elongated filter's response runs on past
        a crack's tip, where the grey is the background's.

    Returns
    -------
    lines : (M, N) ndarray of bool
        The line pixels (about one pixel wide) connected to a seed, outside the seeds and
        the passable objects.

    Examples
    --------
    >>> img = np.full((40, 80), 100, np.float32); img[20, 5:75] = 94; img[19:22, 10:14] = 40
    >>> img += np.random.default_rng(0).normal(0, 1, img.shape).astype(np.float32)
    >>> seeds = np.zeros(img.shape, bool); seeds[19:22, 10:14] = True
    >>> bool(link_lines(img, seeds, crack_level=40.0)[20, 60])
    True
    """
    import cv2
    a = np.ascontiguousarray(image, np.float32)
    r, noise = line_response(a, region=region)
    low = r > snr * noise
    side = 2 * int(np.ceil(2 * config.LINK_SIGMA_PX)) + 1
    bg = cv2.dilate(a, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (side, side)))
    ref = float(np.percentile(bg if region is None or not np.any(region)
                              else bg[np.asarray(region, bool)], 75))
    low &= (bg - ref) < max_lift * max(ref - float(crack_level), 1e-3)
    from .threshold import noise_sigma
    closed = cv2.morphologyEx(a, cv2.MORPH_CLOSE, cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (config.RIDGE_CLOSING_PX,) * 2))
    low &= (closed - a) > min_depth_sigmas * noise_sigma(a)
    if exclude is not None:
        low &= ~np.asarray(exclude, bool)
    if region is not None:
        low &= np.asarray(region, bool)
    if detected is not None:
        w = (config.ZONE_WINDOW_PX,) * 2
        low &= cv2.boxFilter(np.asarray(detected, np.float32), -1, w) < max_density
    seeds = np.asarray(seeds, bool)
    near = cv2.dilate(seeds.view(np.uint8), np.ones((3, 3), np.uint8)).view(bool)
    low |= seeds
    if passable is not None:
        low |= np.asarray(passable, bool)
    n, lab = cv2.connectedComponents(low.view(np.uint8), connectivity=8)
    keep = np.zeros(n, bool)
    keep[lab[near & low]] = True
    keep[0] = False
    out = keep[lab] & ~seeds
    return out if passable is None else out & ~np.asarray(passable, bool)


def _holes(mask):
    """Background not connected to the image border (4-connected)."""
    import cv2
    back = np.pad((~mask).view(np.uint8), 1, constant_values=1)
    cv2.floodFill(back, None, (0, 0), 2)
    return back[1:-1, 1:-1] == 1


def _axis(ys, xs):
    """Principal direction (radians, mod pi) and elongation (sqrt of the moment ratio)."""
    if len(xs) < 3:
        return 0.0, 1.0
    x = xs - xs.mean()
    y = ys - ys.mean()
    mxx, myy, mxy = (x * x).mean() + 1 / 12, (y * y).mean() + 1 / 12, (x * y).mean()
    half = 0.5 * (mxx + myy)
    disc = np.sqrt(0.25 * (mxx - myy) ** 2 + mxy ** 2)
    return 0.5 * np.arctan2(2 * mxy, mxx - myy), float(np.sqrt((half + disc) / (half - disc)))


def _useful_pieces(detect, new, reach_px, min_px):
    """Pieces (8-connected) of ``new`` that join two objects of ``detect``, or continue one:
    reach more than ``reach_px`` from it, hold at least ``min_px`` pixels and, where the
    object is elongated near the contact, run within ``CONTINUE_DEG`` of its direction. The
    others run along one object's edge, are the line filter's overshoot past a tip, or
    branch off (a grain boundary leaving a crack at a junction)."""
    import cv2
    n, lab = cv2.connectedComponents(new.view(np.uint8), connectivity=8)
    if n <= 1:
        return new
    nd, dlab = cv2.connectedComponents(detect.view(np.uint8), connectivity=8)
    dist = cv2.distanceTransform((~detect).view(np.uint8), cv2.DIST_L2, 3)
    reach = np.zeros(n, bool)
    reach[lab[new & (dist > reach_px)]] = True
    reach &= np.bincount(lab.ravel(), minlength=n) >= min_px
    grown = cv2.dilate(lab.astype(np.float32), np.ones((3, 3), np.uint8)).astype(np.int64)
    at = (grown > 0) & (dlab > 0)
    pairs = np.unique(grown[at] * nd + dlab[at])
    joins = np.bincount(pairs // nd, minlength=n)
    keep = joins >= 2
    r = int(np.ceil(2 * min_px))
    h, w = detect.shape
    ay, ax = np.nonzero(at)  # contact pixels (on an object), grouped by piece
    al = grown[ay, ax]
    order = np.argsort(al, kind="stable")
    ay, ax, al = ay[order], ax[order], al[order]
    for i in np.flatnonzero(reach & ~keep):
        lo, hi = np.searchsorted(al, i), np.searchsorted(al, i, side="right")
        cy, cx = ay[lo:hi], ax[lo:hi]
        if not len(cy):
            continue
        obj = dlab[cy[0], cx[0]]
        y0, x0 = int(cy.mean()), int(cx.mean())
        win = np.s_[max(y0 - r, 0):min(y0 + r + 1, h), max(x0 - r, 0):min(x0 + r + 1, w)]
        oy, ox = np.nonzero(dlab[win] == obj)
        py, px = np.nonzero(lab[win] == i)
        t_obj, e_obj = _axis(oy, ox)
        t_new, _ = _axis(py, px)
        turn = np.degrees(abs((t_new - t_obj + np.pi / 2) % np.pi - np.pi / 2))
        keep[i] = e_obj < 2.0 or turn <= config.CONTINUE_DEG
    keep[0] = False
    return keep[lab]


def _short_chains(detect, new, min_px):
    """``new`` pixels of the objects of ``detect | new`` shorter than ``min_px`` (the length of
    a segment with the object's largest principal second moment)."""
    import cv2

    from .measure import object_moments
    n, lab = cv2.connectedComponents((detect | new).view(np.uint8), connectivity=8)
    _, _, _, mxx, myy, mxy, _, _ = object_moments(lab, n - 1)
    big = 0.5 * (mxx + myy) + np.sqrt(0.25 * (mxx - myy) ** 2 + mxy ** 2)
    short = np.sqrt(12.0 * np.maximum(big, 0.0)) < min_px
    short[0] = False
    return new & short[lab]


def _label_quantile(values, labels, n, q):
    """Per label 1..n-1: the ``q`` quantile of ``values`` (the lower one; NaN when empty)."""
    order = np.lexsort((values, labels))  # by label, then value
    lv, vv = labels[order], values[order]
    idx = np.arange(1, n)
    lo, hi = np.searchsorted(lv, idx), np.searchsorted(lv, idx, side="right")
    out = np.full(len(idx), np.nan)
    has = hi > lo
    out[has] = vv[lo[has] + np.floor(q * (hi[has] - lo[has] - 1)).astype(np.int64)]
    return out


def _shallow_pieces(new, detect, grey, crack_level, min_depth):
    """``new`` pieces (8-connected) whose median grey is less than ``min_depth`` of the
    contrast below the *darker* side around them (the 25th percentile of a ring 2-3 px out,
    away from the objects; a piece with no such ring is kept): a crack is darker than the
    rock on both sides; a faint boundary line, or the dark side of a step between two grains,
    is not (as ``side_depth`` in :mod:`semkit.reject`)."""
    import cv2
    n, lab = cv2.connectedComponents(new.view(np.uint8), connectivity=8)
    if n <= 1:
        return np.zeros(new.shape, bool)
    g = np.asarray(grey, np.float32)
    labf = lab.astype(np.float32)
    outer = cv2.dilate(labf, np.ones((7, 7), np.uint8))
    inner = cv2.dilate(labf, np.ones((3, 3), np.uint8))
    near = cv2.dilate(detect.view(np.uint8), np.ones((5, 5), np.uint8)).view(bool)
    ring = (outer > 0) & (inner == 0) & ~near  # the objects' own blurred rims left out
    side = _label_quantile(g[ring], outer[ring].astype(np.int64), n, 0.25)
    on = lab > 0
    core = _label_quantile(g[on], lab[on].astype(np.int64), n, 0.5)
    depth = (side - core) / np.maximum(side - float(crack_level), 1e-3)
    return np.concatenate([[False], depth < min_depth])[lab]  # NaN (no ring): kept


def add_link_lines(detect, area, lines, grey, depth, *, crack_level,
                   loop_px=config.REJECT_RIM_LOOP_PX,
                   reach_px=config.LINK_EXCLUDE_PX, min_chain_px=config.LINK_MIN_CHAIN_PX,
                   min_depth=config.LINK_MIN_DEPTH_FRACTION):
    """Add line pixels to a detection: pieces that join objects or continue one, except
    pieces closing a new loop.

    Parameters
    ----------
    detect, area : (M, N) ndarray of bool
        Detect and area masks (before cleaning).
    lines : (M, N) ndarray of bool
        :func:`link_lines` output.
    grey : (M, N) ndarray
        Grey image (flattened, denoised).
    depth : (M, N) ndarray of float32
        Depth below the local background as a share of the contrast
        (:func:`semkit.ridge.ridge_mask`); line pixels at least ``AUTO_AREA_FRACTION`` deep
        join the area mask too (the others are measured by partial volume).
    loop_px : int
        A piece of line (a connected set of added pixels) next to a hole of at least this many
        px that the detection did not enclose before is left out.
    crack_level : float
        Crack core grey.
    min_depth : float
        Pieces less than this share of the contrast below the darker side around them are
        left out (a faint grain boundary, the dark side of a step between grains).
    min_chain_px : float
        Pieces are left out of objects (once linked) shorter than this: two specks joined
        into a short squiggle are no evidence of a crack, a row of beads joined is.
    reach_px : float
        A piece that touches one object only and stays within this distance of the detection
        (a line along the edge of a wide crack, or between two of its branches), or is
        shorter than ``LINK_LENGTH_PX`` px (the filter's overshoot past a tip), is left out.

    Returns
    -------
    detect, area : (M, N) ndarray of bool

    Examples
    --------
    >>> d = np.zeros((20, 20), bool); d[5, 5:15] = d[15, 5:15] = d[5:16, 5] = True
    >>> ring = d.copy(); ring[5:16, 14] = True
    >>> g = np.where(ring, 20.0, 100.0).astype(np.float32)
    >>> out, _ = add_link_lines(d, d, ring, g, np.zeros((20, 20), np.float32), crack_level=0.0)
    >>> bool(out[10, 14])
    False
    """
    import cv2
    detect = np.asarray(detect, bool)
    new = np.asarray(lines, bool) & ~detect
    new &= ~_shallow_pieces(new, detect, grey, crack_level, min_depth)
    new = _useful_pieces(detect, new, reach_px, config.LINK_LENGTH_PX)
    if new.any():
        created = _holes(detect | new) & ~_holes(detect)
        if created.any():
            nh, hl = cv2.connectedComponents(created.view(np.uint8), connectivity=4)
            size = np.bincount(hl.ravel(), minlength=nh)
            size[0] = 0
            big = (size >= loop_px)[hl]
            if big.any():
                n, lab = cv2.connectedComponents(new.view(np.uint8), connectivity=8)
                touch = cv2.dilate(big.view(np.uint8), np.ones((3, 3), np.uint8)).view(bool)
                drop = np.zeros(n, bool)
                drop[lab[touch & new]] = True
                drop[0] = False
                new &= ~drop[lab]
    if new.any() and min_chain_px:
        new &= ~_short_chains(detect, new, min_chain_px)
    return detect | new, np.asarray(area, bool) | (new & (depth >= config.AUTO_AREA_FRACTION))
