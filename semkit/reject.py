"""Objects that are dark but not cracks, told apart by shape and by their surroundings.

Every cleaned object gets a few measures (:func:`object_evidence`):

* ``side_depth`` — how far the object's dark core (its 20th percentile grey) is below the
  *darker* side of its surroundings (the 25th percentile of a 2-px ring around it), as a share
  of that side's contrast to the crack core.
  A crack is darker than the rock on both of its sides; the dark rim at the edge of a bright
  grain (a halo, a boundary line) is darker only than the bright side.
* ``side_step`` — the ring's 75th minus its 25th percentile, in the same unit: small around
  an object inside one grain, large on a step between two phases. A short, shallow object on
  a step is the dark edge of a grain boundary (``phase_edge``), however thin; a crack along a
  phase boundary is deeper or longer. A shallow, short object whose ring's quartiles lie
  apart by less than a phase step but by at least ``REJECT_TEXTURE_STEP`` is no deeper than
  its surroundings vary (``faint_texture``, at any size): a bit of the dark rim of an
  inclusion or of a grain's texture, not a crack one can measure.
* ``encloses_px``, ``hole_lift`` — area of the holes the object closes around, and how much
  brighter they are than the darker side outside (share of the contrast): a ring around a
  brighter grain is that grain's rim (a halo), however long; a crack network closing around a
  grain of the same rock is not lifted. A ring of width w around an inclusion of radius r
  closes r^2 / (2 r w + w^2) of its own area (1/3 at r = w, 1/8 at r = w / 2): an object
  whose holes hold less than ``REJECT_RIM_HOLE_SHARE`` of its area is a network with a small
  loop somewhere, not a rim.
* ``rim_share`` — share of the object's pixels within its own width (+1.5 px) of the holes it
  closes (NaN unless the other ``grain_rim`` conditions hold, where it decides: a bright
  loop, ``REJECT_RIM_LOOP_PX`` and ``REJECT_RIM_HOLE_LIFT``, holding
  ``REJECT_RIM_HOLE_SHARE`` of the object, short of ``REJECT_ZONE_MAX_DEPTH``, judged by its
  size): ~1 for a ring, low for a crack network that closes one loop around a grain and runs
  on elsewhere (less than ``REJECT_RIM_MIN_SHARE``: not a rim, however bright the grain).
* ``elongation`` — sqrt of the ratio of the principal second moments (1 for a disc).
* ``width_px`` — mean width, area over skeleton length; ``slenderness`` — skeleton length
  over mean width (a curved crack is slender even when its moments are not elongated);
  ``winding`` — skeleton length over the diagonal of the object's bounding box (~1 for one
  path, bent or branched a little; 2.5 and more for a network of traces to and fro).
* ``background_rel`` — the object's median local background (a 21-px grey closing, on the
  image shrunk by 2, which fills every crack narrower than that) relative to the rock's (75th
  percentile of that closing), both measured from the crack core grey: ~1 for a crack in a
  clear grain, low inside a dark phase (biotite, opaque minerals), lowered in a mottled,
  altered grain.
* ``density`` — the object's median share of detected pixels in a 41 x 41 window around it: a
  mottled area is riddled with dark specks and squiggles, a crack is one line in clear rock.
* ``neighbours`` — other objects (>= 5 px) centred in the 81 x 81 window around the object's
  centre: a mottled area is many separate specks, a crack network (even with its debris) is
  one object with few around it.
* ``texture`` — grey standard deviation of the ring in noise sigmas (reported, not a rule).
* ``interior_share``, ``interior_depth``, ``interior_rough``, ``wall_depth`` — the share of
  the object's pixels at least ``REJECT_BAND_INTERIOR_PX`` inside it (a band wide enough to
  show its core grey through the blur); how far that interior's dark core (20th percentile)
  lies below the darker side of the ring, as a share of that side's contrast to the *void*
  grey (the grey areas are measured against); the interior's median 5 x 5 grey standard
  deviation in noise sigmas (a step where a band crosses two minerals moves the median
  little); and how far the whole object's dark core lies below its interior's, in the same
  unit. A lath of a darker mineral is wide, uniform, stops short of the void and is darkest
  inside (``dark_band``); a crack as wide reaches the void, or is rough inside (debris,
  merged layers) or has darker walls than its middle.
* ``depth_snr`` — the ``side_depth`` greys (the ring's 25th percentile minus the object's
  20th) in pixel-noise sigmas, times the square root of the skeleton length in px: how far
  the object stands out of the noise along its whole length. Under ``REJECT_NOISE_SNR`` it
  is ``noise`` at any size (a speck or a bit of a grain boundary on a noisy image), unless
  it is a long line on a step between phases (a thin crack along a boundary is shallow
  against the darker phase).

An object whose dark core reaches the crack core grey (``side_depth`` at least
``REJECT_ZONE_MAX_DEPTH``: an open, void- or epoxy-filled crack) is never rejected for its
zone: a crack through a dark or mottled grain stays a crack. Nor is a lone line
(:func:`kept_lone_lines`: straight or slender, deep for its zone, no other object around it)
rejected as ``dark_phase``: a crack in a darker mineral, not the grain's texture.

:func:`reject_objects` applies the rules (:data:`RULES`, thresholds in :mod:`semkit.config`)
and returns the reason per object (``""`` for a crack). Rejected objects stay in
``cracks.csv`` with ``rejected_as`` set and count in no sum.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from . import config

__all__ = ["object_evidence", "reject_objects", "split_zone_objects", "zone_relief",
           "kept_lone_lines", "RULES"]


def _lone_line(e):
    """A line (straight, or curved and slender along one path) with no other object around
    it, deep for its zone: a crack in a dark grain, not the grain's cleavage, boundaries or
    texture (which come many together, or joined into a network that winds to and fro)."""
    return ((e.neighbours <= config.LONE_LINE_MAX_NEIGHBOURS)
            & ((e.elongation >= config.LONE_LINE_ELONGATION)
               | ((e.slenderness >= config.LONE_LINE_SLENDERNESS)
                  & (e.winding <= config.LONE_LINE_MAX_WINDING)))
            & (e.side_depth >= config.LONE_LINE_DEPTH))


def _shallow_short(e):
    """Shallow against its surroundings and short: what ``phase_rim`` and ``faint_texture``
    judge (a grain's rim, a bit of texture), unless their other measures say otherwise."""
    return (e.side_depth < config.REJECT_SIDE_DEPTH) \
        & (e.slenderness < config.REJECT_RIM_MAX_SLENDERNESS)


def _rough_band(e):
    """A band wide enough to show its interior, rough inside (``interior_rough`` at least
    ``REJECT_BAND_MAX_ROUGH``): layered traces merged into one band, or a crack with debris;
    a grain's dark rim or halo is smooth across."""
    return (e.interior_share >= config.REJECT_BAND_INTERIOR_SHARE) \
        & (e.interior_rough >= config.REJECT_BAND_MAX_ROUGH)


def _clear_in_grain(e):
    """Elongated (``elongation`` at least ``REJECT_RIM_CLEAR_ELONGATION``), inside one grain
    (the ring's quartiles less than ``REJECT_TEXTURE_STEP`` apart) and far out of the noise
    along its length (``depth_snr`` at least ``REJECT_RIM_CLEAR_SNR``): a piece of crack,
    however shallow; a grain's rim lies on the step to the brighter grain, and a small pore
    or dark speck in the grain is not elongated."""
    return (e.side_step < config.REJECT_TEXTURE_STEP) \
        & (e.depth_snr >= config.REJECT_RIM_CLEAR_SNR) \
        & (e.elongation >= config.REJECT_RIM_CLEAR_ELONGATION)


def _dark_zone(e):
    """In a dark phase, and not reaching the crack core grey: what ``dark_phase`` judges."""
    return (e.background_rel < config.REJECT_DARK_BACKGROUND) \
        & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)


def kept_lone_lines(evidence, rejected_as):
    """Which objects are kept only as lone lines (:func:`_lone_line`): the dark-phase rule's
    zone test holds for them, and no rule rejected them (a boolean Series like
    ``rejected_as``)."""
    return _dark_zone(evidence) & _lone_line(evidence) & (np.asarray(rejected_as) == "")


#: the rules in the order they are tried: name, test on the evidence table
RULES = (
    ("phase_rim", lambda e: _shallow_short(e) & (e.width_px >= config.REJECT_RIM_MIN_WIDTH_PX)
     & ~_rough_band(e) & ~_clear_in_grain(e)),
    ("phase_edge", lambda e: (e.side_depth < config.REJECT_EDGE_DEPTH)
     & (e.side_step >= config.REJECT_EDGE_STEP)
     & (e.slenderness < config.REJECT_EDGE_MAX_SLENDERNESS)),
    ("grain_rim", lambda e: (e.encloses_px >= config.REJECT_RIM_LOOP_PX)
     & (e.encloses_px >= config.REJECT_RIM_HOLE_SHARE * e.area_px)
     & (e.hole_lift >= config.REJECT_RIM_HOLE_LIFT)
     & (e.rim_share >= config.REJECT_RIM_MIN_SHARE)
     & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)),
    ("compact_dark", lambda e: (e.slenderness < config.REJECT_COMPACT_SLENDERNESS)
     & (e.width_px >= config.REJECT_COMPACT_WIDTH_PX)
     & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)),
    ("dark_band", lambda e: (e.interior_share >= config.REJECT_BAND_INTERIOR_SHARE)
     & (e.interior_depth < config.REJECT_BAND_DEPTH)
     & (e.interior_rough < config.REJECT_BAND_MAX_ROUGH)
     & (e.wall_depth < config.REJECT_BAND_MAX_WALL)),
    ("dark_phase", lambda e: _dark_zone(e) & ~_lone_line(e)),
    ("mottled", lambda e: (e.background_rel < config.REJECT_MOTTLED_BACKGROUND)
     & (e.density >= config.REJECT_MOTTLED_DENSITY)
     & (e.neighbours >= config.REJECT_MOTTLED_NEIGHBOURS)
     & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)),
    ("noise", lambda e: (e.depth_snr < config.REJECT_NOISE_SNR)
     & ~((e.side_step >= config.REJECT_EDGE_STEP)
         & (e.slenderness >= config.REJECT_RIM_MAX_SLENDERNESS))),
    ("faint_texture", lambda e: _shallow_short(e) & (e.side_step >= config.REJECT_TEXTURE_STEP)
     & (e.side_step < config.REJECT_EDGE_STEP)),
)
#: the size (px) from which a rule judges an object: REJECT_MIN_AREA_PX, except where the
#: rule's evidence holds on smaller objects
RULE_MIN_AREA_PX = {"phase_edge": config.REJECT_EDGE_MIN_AREA_PX, "faint_texture": 0, "noise": 0}


def _label_percentiles(values, lab, n, qs, bins=256, std=True):
    """Per label 0..n: the ``qs`` percentiles (to 1/``bins`` of the value range) and the std
    of ``values`` (None with ``std=False``), from per-label histograms (one ``bincount``; no
    sort).

    ``values`` and ``lab`` are 1-D, over the pixels concerned only."""
    out = np.full((len(qs), n + 1), np.nan)
    sd = np.full(n + 1, np.nan)
    if lab.size == 0:
        return out, sd
    v = np.asarray(values, np.float32)
    lo, hi = float(v.min()), float(v.max())
    step = (hi - lo) / bins if hi > lo else 1.0
    b = np.minimum(((v - lo) * np.float32(1.0 / step)).astype(np.int32), bins - 1)
    hist = np.bincount(lab * bins + b, minlength=(n + 1) * bins).reshape(n + 1, bins)
    cum = np.cumsum(hist, axis=1)
    cnt = cum[:, -1]
    has = cnt > 0
    for k, q in enumerate(qs):
        rank = np.floor((cnt - 1) * q / 100.0) + 1
        idx = np.argmax(cum >= rank[:, None], axis=1)
        out[k, has] = lo + (idx[has] + 0.5) * step
    if not std:
        return out, None
    c = np.maximum(cnt, 1)
    s1 = np.bincount(lab, weights=v, minlength=n + 1)
    s2 = np.bincount(lab, weights=np.square(v, dtype=np.float64), minlength=n + 1)
    sd[has] = np.sqrt(np.maximum(s2[has] / c[has] - (s1[has] / c[has]) ** 2, 0.0))
    return out, sd


def _grow(labels, width):
    """Grey dilation of a label image (uint16 when the labels fit, else float32)."""
    import cv2
    k = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * width + 1, 2 * width + 1))
    a = labels.astype(np.uint16) if labels.max(initial=0) < 65536 else \
        labels.astype(np.float32)
    return cv2.dilate(a, k)


def _window_counts(ri, ci, qr, qc, w):
    """How many points ``(ri, ci)`` lie in the w x w box centred on each query ``(qr, qc)``,
    as float32 (what an unnormalised box filter of the point counts reads there)."""
    half = w // 2
    out = np.zeros(qr.size, np.float32)
    if ri.size == 0 or qr.size == 0:
        return out
    order = np.argsort(ri, kind="stable")
    rs, cs = ri[order], ci[order]
    lo = np.searchsorted(rs, qr - half, side="left")
    cnt = np.searchsorted(rs, qr - half + w - 1, side="right") - lo
    q = np.repeat(np.arange(qr.size), cnt)         # (query, point) pairs in the row band
    start = np.cumsum(cnt) - cnt
    pos = np.arange(q.size) - start[q] + lo[q]
    c = cs[pos]
    inside = (c >= qc[q] - half) & (c <= qc[q] - half + w - 1)
    out[:] = np.bincount(q, weights=inside, minlength=qr.size)
    return out


def _ring(labels, width=2):
    """``(ring_mask, label_of_ring_pixel)``: pixels within ``width`` of an object, outside all."""
    grown = _grow(labels, width)
    ring = (labels == 0) & (grown > 0)
    return ring, grown[ring].astype(np.int64)


def zone_relief(grey, crack_level, region=None):
    """Local background of every pixel relative to the rock's, from the crack core grey.

    The local background is a ``ZONE_CLOSING_PX`` grey closing (on the image shrunk by 2,
    resized back), which fills every crack narrower than that; the rock's is the 75th
    percentile of that closing inside ``region``. ~1 in a clear grain, low inside a dark
    phase: ``background_rel`` of :func:`object_evidence` is its median over an object.

    Parameters
    ----------
    grey : (M, N) ndarray
        Flattened, denoised grey image.
    crack_level : float
    region : (M, N) ndarray of bool, optional

    Returns
    -------
    relief : (M, N) ndarray of float32
    """
    import cv2
    g = np.asarray(grey, np.float32)
    h, w = g.shape
    half = cv2.resize(g, (max(w // 2, 1), max(h // 2, 1)), interpolation=cv2.INTER_AREA)
    k = config.ZONE_CLOSING_PX // 2 | 1
    bg_half = cv2.morphologyEx(half, cv2.MORPH_CLOSE, cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (k, k)))
    bg = cv2.resize(bg_half, (w, h), interpolation=cv2.INTER_LINEAR)
    inside = bg_half if region is None else bg_half[cv2.resize(
        np.asarray(region, np.uint8), bg_half.shape[::-1],
        interpolation=cv2.INTER_NEAREST).view(bool)]
    ref = float(np.percentile(inside, 75)) if inside.size else float(bg.max())
    return (bg - float(crack_level)) / max(ref - float(crack_level), 1e-3)


def object_evidence(labels, n, grey, *, crack_level, noise, skeleton=None, region=None,
                    relief=None, void_level=None):
    """Shape and surroundings of every object (see the module docstring).

    Parameters
    ----------
    labels : (M, N) ndarray of int
        Objects 1..n.
    n : int
    grey : (M, N) ndarray
        Flattened, denoised grey image.
    crack_level : float
        Crack core grey.
    noise : float
        Pixel-noise sigma.
    skeleton : (M, N) ndarray of bool, optional
    region : (M, N) ndarray of bool, optional
        Sample region (the rock's background level is read inside it).
    relief : (M, N) ndarray, optional
        :func:`zone_relief` of ``grey`` (computed when not given).
    void_level : float, optional
        Void grey (``interior_depth`` is read against it); ``crack_level`` when not given.

    Returns
    -------
    evidence : pandas.DataFrame
        Index 1..n: ``area_px, side_depth, side_step, encloses_px, hole_lift, rim_share,
        elongation, width_px, slenderness, winding, background_rel, density, neighbours,
        texture, interior_share, interior_depth, interior_rough, wall_depth, depth_snr``.
    """
    import cv2

    from ._kernels import pixel_coords
    from .measure import object_moments
    lab = np.asarray(labels)
    g = np.asarray(grey, np.float32)
    on = lab > 0
    lab_on = lab[on].astype(np.int64)
    # the object's dark core: its 20th percentile (a thin crack is mostly partial-volume rim)
    core = _label_percentiles(g[on], lab_on, n, (20.0,), std=False)[0][0]
    ring, ring_lab = _ring(lab)
    (ring_lo, ring_hi), ring_sd = _label_percentiles(g[ring], ring_lab, n, (25.0, 75.0))
    side_depth = (ring_lo - core) / np.maximum(ring_lo - float(crack_level), 1e-3)
    side_step = (ring_hi - ring_lo) / np.maximum(ring_lo - float(crack_level), 1e-3)
    area, cx, cy, mxx, myy, mxy, bw, bh, bx, by = object_moments(lab, n, origin=True)
    half = 0.5 * (mxx + myy)
    disc = np.sqrt(0.25 * (mxx - myy) ** 2 + mxy ** 2)
    elong = np.sqrt(np.maximum(half + disc, 1e-9) / np.maximum(half - disc, 1e-2))
    if skeleton is None:
        from .skeleton import skeletonize
        skeleton = skeletonize(lab > 0)
    sk = np.bincount(lab[np.asarray(skeleton, bool)], minlength=n + 1).astype(float)
    width = area / np.maximum(sk, 1.0)
    winding = sk / np.maximum(np.hypot(bw, bh), 1.0)
    # the zone around the object: local background and detection density
    h, w = g.shape
    if relief is None:
        relief = zone_relief(g, crack_level, region)
    rel_on = relief[on]
    dens = cv2.boxFilter(on.view(np.uint8), cv2.CV_32F, (config.ZONE_WINDOW_PX,) * 2)
    background_rel = _label_percentiles(rel_on, lab_on, n, (50.0,), std=False)[0][0]
    density = _label_percentiles(dens[on], lab_on, n, (50.0,), std=False)[0][0]
    # holes closed by an object (background not connected to the image border; owner: the
    # largest label next to the hole)
    back = np.pad((~on).view(np.uint8), 1, constant_values=1)
    cv2.floodFill(back, None, (0, 0), 2)
    holes = back[1:-1, 1:-1] == 1
    encloses = np.zeros(n + 1)
    hole_grey = np.full(n + 1, np.nan)
    rim_share = np.full(n + 1, np.nan)
    if holes.any():
        nh, hl = cv2.connectedComponents(holes.view(np.uint8), connectivity=4)
        at = np.flatnonzero(holes)
        hole_of = hl.ravel()[at]
        owner = np.zeros(nh, np.int64)
        nxt = _grow(lab, 1).ravel()[at]   # only the hole's rim touches an object
        rim = nxt > 0
        np.maximum.at(owner, hole_of[rim], nxt[rim].astype(np.int64))
        encloses = np.bincount(owner[1:], weights=np.bincount(hole_of, minlength=nh)[1:],
                               minlength=n + 1)[:n + 1]
        hole_grey = _label_percentiles(g.ravel()[at], owner[hole_of], n, (50.0,), std=False)[0][0]
    hole_lift = (hole_grey - ring_lo) / np.maximum(ring_lo - float(crack_level), 1e-3)
    # objects whose grain-rim verdict rests on rim_share: a bright loop, large for the
    # object, not reaching the void, judged
    loop = (encloses >= config.REJECT_RIM_LOOP_PX) & (hole_lift >= config.REJECT_RIM_HOLE_LIFT) \
        & (encloses >= config.REJECT_RIM_HOLE_SHARE * area) \
        & (side_depth < config.REJECT_ZONE_MAX_DEPTH) & (area >= config.REJECT_MIN_AREA_PX)
    if loop.any():
        # share of the object that hugs a hole: within its own width (+1.5 px) of one (only
        # for those objects: the other rules never read it). The
        # distance is read in the object's box widened by its reach: a chamfer path of k
        # steps is >= 0.955 k long, so that box holds every path short enough to pass (the
        # same verdicts as distances over the whole image)
        hugging = np.zeros(n + 1)
        for k in np.flatnonzero(loop):
            reach = width[k] + 1.5
            m = int(np.ceil(reach / 0.955)) + 2
            r0, c0 = max(int(by[k]) - m, 0), max(int(bx[k]) - m, 0)
            r1, c1 = min(int(by[k] + bh[k]) + m, h), min(int(bx[k] + bw[k]) + m, w)
            d = cv2.distanceTransform(
                np.ascontiguousarray(~holes[r0:r1, c0:c1]).view(np.uint8), cv2.DIST_L2, 3)
            hugging[k] = np.count_nonzero(d[lab[r0:r1, c0:c1] == k] <= reach)
        rim_share = np.where(loop, hugging / np.maximum(area, 1.0), np.nan)
    # other objects (>= 5 px) whose centre lies in the window around this one's centre
    big = np.flatnonzero(area[1:] >= 5) + 1
    ri = np.clip(np.rint(cy[big]).astype(int), 0, lab.shape[0] - 1)
    ci = np.clip(np.rint(cx[big]).astype(int), 0, lab.shape[1] - 1)
    neighbours = _window_counts(ri, ci, np.clip(np.rint(cy).astype(int), 0, lab.shape[0] - 1),
                                np.clip(np.rint(cx).astype(int), 0, lab.shape[1] - 1),
                                config.ZONE_NEIGHBOUR_WINDOW_PX) - (area >= 5)
    texture = ring_sd / max(float(noise), 1e-6)
    depth_snr = (ring_lo - core) / max(float(noise), 1e-6) * np.sqrt(np.maximum(sk, 1.0))
    # the interior: pixels at least REJECT_BAND_INTERIOR_PX inside the object (where a band
    # wide enough shows its core grey, whatever the blur); depths are read against the void
    # grey the areas use (the crack grey is a guess when no crack shows a plateau)
    dist = cv2.distanceTransform(on.view(np.uint8), cv2.DIST_L2, 3)
    rr, cc = pixel_coords(dist >= config.REJECT_BAND_INTERIOR_PX)
    lab_in = lab.ravel()[rr * w + cc].astype(np.int64)
    interior_share = np.bincount(lab_in, minlength=n + 1)[:n + 1] / np.maximum(area, 1.0)
    gf = g.ravel()
    in_core = _label_percentiles(gf[rr * w + cc], lab_in, n, (20.0,), std=False)[0][0]
    # the grey standard deviation of each interior pixel's 5 x 5 window (read there only)
    at = np.clip(rr, 2, h - 3) * w + np.clip(cc, 2, w - 3)
    centre = gf[at]   # sums of differences from it: no cancellation in float32
    s1 = np.zeros(at.size, np.float32)
    s2 = np.zeros(at.size, np.float32)
    for off in (np.arange(-2, 3)[:, None] * w + np.arange(-2, 3)).ravel():
        v = gf[at + off] - centre
        s1 += v
        s2 += v * v
    local_sd = np.sqrt(np.maximum(s2 / 25 - (s1 / 25) ** 2, 0.0))
    interior_rough = _label_percentiles(local_sd, lab_in, n, (50.0,),
                                        std=False)[0][0] / max(float(noise), 1e-6)
    void = float(crack_level if void_level is None or not np.isfinite(void_level)
                 else void_level)
    to_void = np.maximum(ring_lo - void, 1e-3)
    interior_depth = (ring_lo - in_core) / to_void
    wall_depth = (in_core - core) / to_void
    ev = pd.DataFrame(dict(area_px=area, side_depth=side_depth, side_step=side_step,
                           encloses_px=encloses, hole_lift=hole_lift, rim_share=rim_share,
                           elongation=elong, width_px=width,
                           slenderness=sk / np.maximum(width, 1e-9), winding=winding,
                           background_rel=background_rel, density=density,
                           neighbours=neighbours, texture=texture,
                           interior_share=interior_share, interior_depth=interior_depth,
                           interior_rough=interior_rough, wall_depth=wall_depth,
                           depth_snr=depth_snr),
                      index=np.arange(n + 1))
    return ev.iloc[1:]


def reject_objects(evidence):
    """The first rule of :data:`RULES` each object meets (``""``: kept as a crack).

    Parameters
    ----------
    evidence : pandas.DataFrame
        :func:`object_evidence` output.

    Returns
    -------
    rejected_as : pandas.Series of str
    """
    import types

    # the rules read the columns as arrays (a NaN measure meets no test)
    e = types.SimpleNamespace(**{c: evidence[c].to_numpy(float) for c in evidence.columns})
    why = np.full(len(evidence), "", dtype=object)
    for name, rule in RULES:
        judged = e.area_px >= RULE_MIN_AREA_PX.get(name, config.REJECT_MIN_AREA_PX)
        with np.errstate(invalid="ignore"):
            hit = np.asarray(rule(e), bool) & judged
        why[(why == "") & hit] = name
    return pd.Series(why, index=evidence.index, dtype=object)


def split_zone_objects(labels, n, rejected_as, relief, *, level=config.REJECT_MOTTLED_BACKGROUND,
                       min_px=config.REJECT_MIN_AREA_PX):
    """Cut the objects rejected as ``dark_phase`` where they leave the dark phase.

    A crack that runs out of a dark grain into clear rock is one object with the grain's rim
    or cleavage; judged whole, its median zone is dark and all of it is rejected. Its pixels
    whose zone is clear rock (``relief`` at least ``level``, the level from which the
    ``mottled`` rule calls a zone clear) are cut off; every 8-connected piece of at least
    ``min_px`` becomes an object of its own, to be judged again, and the rest stays with the
    original object and its verdict.

    Parameters
    ----------
    labels : (M, N) ndarray of int32
        Objects 1..n (connected components).
    n : int
    rejected_as : sequence of str
        The rules' verdict per object 1..n (:func:`reject_objects`).
    relief : (M, N) ndarray
        :func:`zone_relief`.
    level, min_px : float, int

    Returns
    -------
    None when nothing is cut, else ``(labels, n, origin)``: the new labels 1..n (compact)
    and, per new label, the old label of an object left unchanged, minus the old label of
    the rest of a cut object (still in the dark phase: it keeps its verdict), 0 for a
    piece.

    Examples
    --------
    >>> lab = np.zeros((5, 80), np.int32); lab[2, 5:75] = 1
    >>> relief = np.zeros((5, 80), np.float32); relief[:, 40:] = 1.0
    >>> new, n, origin = split_zone_objects(lab, 1, ["dark_phase"], relief)
    >>> n, int((new == 2).sum()), origin.tolist()
    (2, 35, [0, -1, 0])
    """
    import cv2

    from ._kernels import lookup
    dark = np.zeros(n + 1, bool)
    dark[1:] = np.asarray(rejected_as, dtype=object) == "dark_phase"
    if not dark.any():
        return None
    clear = lookup(dark, labels) & (np.asarray(relief) >= level)
    k, piece = cv2.connectedComponents(clear.view(np.uint8), connectivity=8)
    big = np.bincount(piece.ravel(), minlength=k) >= min_px
    big[0] = False
    if not big.any():
        return None
    cut = np.zeros(n + 1, bool)
    cut[np.unique(labels[lookup(big, piece)])] = True
    new_id = np.zeros(k, np.int32)
    new_id[big] = n + 1 + np.arange(int(big.sum()), dtype=np.int32)
    lab = np.where(lookup(big, piece), new_id[piece], labels)
    # compact ids (an object may be cut into pieces whole)
    used = np.flatnonzero(np.bincount(lab.ravel(), minlength=n + 1 + int(big.sum())))
    used = used[used > 0]
    remap = np.zeros(n + 2 + int(big.sum()), np.int32)
    remap[used] = np.arange(1, used.size + 1, dtype=np.int32)
    old = np.where(used <= n, used, 0)
    origin = np.concatenate([[0], np.where(cut[np.minimum(old, n)], -old, old)])
    return remap[lab].astype(np.int32, copy=False), int(used.size), origin.astype(np.int64)
