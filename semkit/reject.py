"""Objects that are dark but not cracks, told apart by shape and by their surroundings.

Every cleaned object gets a few measures (:func:`object_evidence`):

* ``side_depth`` — how far the object's dark core (its 20th percentile grey) is below the
  *darker* side of its surroundings (the 25th percentile of a 2-px ring around it), as a share
  of that side's contrast to the crack core.
  A crack is darker than the rock on both of its sides; the dark rim at the edge of a bright
  grain (a halo, a boundary line) is darker only than the bright side.
* ``encloses_px``, ``hole_lift`` — area of the holes the object closes around, and how much
  brighter they are than the darker side outside (share of the contrast): a ring around a
  brighter grain is that grain's rim (a halo), however long; a crack network closing around a
  grain of the same rock is not lifted.
* ``elongation`` — sqrt of the ratio of the principal second moments (1 for a disc).
* ``width_px`` — mean width, area over skeleton length; ``slenderness`` — skeleton length
  over mean width (a curved crack is slender even when its moments are not elongated).
* ``background_rel`` — the object's median local background (a 21-px grey closing, which fills
  every crack narrower than that) relative to the rock's (75th percentile of that closing),
  both measured from the crack core grey: ~1 for a crack in a clear grain, low inside a dark
  phase (biotite, opaque minerals), lowered in a mottled, altered grain.
* ``density`` — the object's median share of detected pixels in a 41 x 41 window around it: a
  mottled area is riddled with dark specks and squiggles, a crack is one line in clear rock.
* ``neighbours`` — other objects (>= 5 px) centred in the 81 x 81 window around the object's
  centre: a mottled area is many separate specks, a crack network (even with its debris) is
  one object with few around it.
* ``texture`` — grey standard deviation of the ring in noise sigmas (reported, not a rule).

An object whose dark core reaches the crack core grey (``side_depth`` at least
``REJECT_ZONE_MAX_DEPTH``: an open, void- or epoxy-filled crack) is never rejected for its
zone: a crack through a dark or mottled grain stays a crack.

:func:`reject_objects` applies the rules (:data:`RULES`, thresholds in :mod:`semkit.config`)
and returns the reason per object (``""`` for a crack). Rejected objects stay in
``cracks.csv`` with ``rejected_as`` set and count in no sum.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from . import config

__all__ = ["object_evidence", "reject_objects", "RULES"]

#: the rules in the order they are tried: name, test on the evidence table
RULES = (
    ("phase_rim", lambda e: (e.side_depth < config.REJECT_SIDE_DEPTH)
     & (e.slenderness < config.REJECT_RIM_MAX_SLENDERNESS)
     & (e.width_px >= config.REJECT_RIM_MIN_WIDTH_PX)),
    ("grain_rim", lambda e: (e.encloses_px >= config.REJECT_RIM_LOOP_PX)
     & (e.hole_lift >= config.REJECT_RIM_HOLE_LIFT)
     & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)),
    ("compact_dark", lambda e: (e.slenderness < config.REJECT_COMPACT_SLENDERNESS)
     & (e.width_px >= config.REJECT_COMPACT_WIDTH_PX)
     & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)),
    ("dark_phase", lambda e: (e.background_rel < config.REJECT_DARK_BACKGROUND)
     & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)),
    ("mottled", lambda e: (e.background_rel < config.REJECT_MOTTLED_BACKGROUND)
     & (e.density >= config.REJECT_MOTTLED_DENSITY)
     & (e.neighbours >= config.REJECT_MOTTLED_NEIGHBOURS)
     & (e.side_depth < config.REJECT_ZONE_MAX_DEPTH)),
)


def _label_percentiles(values, lab, n, qs):
    """Per label 0..n: the ``qs`` percentiles (lower-nearest rank) and the std of ``values``.

    ``values`` and ``lab`` are 1-D, over the pixels concerned only (sorting them is all)."""
    out = np.full((len(qs), n + 1), np.nan)
    sd = np.full(n + 1, np.nan)
    if lab.size == 0:
        return out, sd
    order = np.lexsort((values, lab))
    lab, val = lab[order], values[order]
    start = np.searchsorted(lab, np.arange(n + 1), "left")
    cnt = np.searchsorted(lab, np.arange(n + 1), "right") - start
    has = cnt > 0
    for k, q in enumerate(qs):
        idx = start + np.floor((cnt - 1) * q / 100.0).astype(np.int64)
        out[k, has] = val[idx[has]]
    c = np.maximum(cnt, 1)
    s1 = np.bincount(lab, weights=val, minlength=n + 1)
    s2 = np.bincount(lab, weights=val.astype(np.float64) ** 2, minlength=n + 1)
    sd[has] = np.sqrt(np.maximum(s2[has] / c[has] - (s1[has] / c[has]) ** 2, 0.0))
    return out, sd


def _ring(labels, width=2):
    """``(ring_mask, label_of_ring_pixel)``: pixels within ``width`` of an object, outside all."""
    import cv2
    k = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * width + 1, 2 * width + 1))
    grown = cv2.dilate(labels.astype(np.float32), k).astype(np.int64)
    ring = (labels == 0) & (grown > 0)
    return ring, grown[ring]


def object_evidence(labels, n, grey, *, crack_level, noise, skeleton=None, region=None):
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

    Returns
    -------
    evidence : pandas.DataFrame
        Index 1..n: ``area_px, side_depth, encloses_px, hole_lift, elongation, width_px,
        slenderness, background_rel, density, neighbours, texture``.
    """
    import cv2
    from scipy import ndimage as ndi

    from .measure import object_moments
    lab = np.asarray(labels)
    g = np.asarray(grey, np.float32)
    on = lab > 0
    lab_on = lab[on].astype(np.int64)
    # the object's dark core: its 20th percentile (a thin crack is mostly partial-volume rim)
    core = _label_percentiles(g[on], lab_on, n, (20.0,))[0][0]
    ring, ring_lab = _ring(lab)
    (ring_lo,), ring_sd = _label_percentiles(g[ring], ring_lab, n, (25.0,))
    side_depth = (ring_lo - core) / np.maximum(ring_lo - float(crack_level), 1e-3)
    area, cx, cy, mxx, myy, mxy, _, _ = object_moments(lab, n)
    half = 0.5 * (mxx + myy)
    disc = np.sqrt(0.25 * (mxx - myy) ** 2 + mxy ** 2)
    elong = np.sqrt(np.maximum(half + disc, 1e-9) / np.maximum(half - disc, 1e-2))
    if skeleton is None:
        from .skeleton import skeletonize
        skeleton = skeletonize(lab > 0)
    sk = np.bincount(lab[np.asarray(skeleton, bool)], minlength=n + 1).astype(float)
    width = area / np.maximum(sk, 1.0)
    # the zone around the object: local background and detection density
    bg = cv2.morphologyEx(g, cv2.MORPH_CLOSE, cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (config.ZONE_CLOSING_PX, config.ZONE_CLOSING_PX)))
    inside = bg if region is None else bg[np.asarray(region, bool)]
    ref = float(np.percentile(inside, 75)) if inside.size else float(bg.max())
    rel = (bg - float(crack_level)) / max(ref - float(crack_level), 1e-3)
    dens = cv2.blur((lab > 0).astype(np.float32), (config.ZONE_WINDOW_PX,) * 2)
    background_rel = _label_percentiles(rel[on], lab_on, n, (50.0,))[0][0]
    density = _label_percentiles(dens[on], lab_on, n, (50.0,))[0][0]
    # holes closed by an object (owner: the largest label next to the hole)
    holes = ndi.binary_fill_holes(lab > 0) & (lab == 0)
    encloses = np.zeros(n + 1)
    hole_grey = np.full(n + 1, np.nan)
    if holes.any():
        nh, hl = cv2.connectedComponents(holes.view(np.uint8), connectivity=4)
        grown = cv2.dilate(lab.astype(np.float32), np.ones((3, 3), np.uint8)).astype(np.int64)
        owner = np.zeros(nh, np.int64)
        np.maximum.at(owner, hl[holes], grown[holes])
        encloses = np.bincount(owner[1:], weights=np.bincount(hl[holes], minlength=nh)[1:],
                               minlength=n + 1)[:n + 1]
        hole_grey = _label_percentiles(g[holes], owner[hl[holes]], n, (50.0,))[0][0]
    hole_lift = (hole_grey - ring_lo) / np.maximum(ring_lo - float(crack_level), 1e-3)
    # other objects (>= 5 px) whose centre lies in the window around this one's centre
    counts = np.zeros(lab.shape, np.float32)
    big = np.flatnonzero(area[1:] >= 5) + 1
    ri = np.clip(np.rint(cy[big]).astype(int), 0, lab.shape[0] - 1)
    ci = np.clip(np.rint(cx[big]).astype(int), 0, lab.shape[1] - 1)
    np.add.at(counts, (ri, ci), 1.0)
    w = config.ZONE_NEIGHBOUR_WINDOW_PX
    counts = cv2.boxFilter(counts, -1, (w, w), normalize=False, borderType=cv2.BORDER_CONSTANT)
    neighbours = counts[np.clip(np.rint(cy).astype(int), 0, lab.shape[0] - 1),
                        np.clip(np.rint(cx).astype(int), 0, lab.shape[1] - 1)] - (area >= 5)
    texture = ring_sd / max(float(noise), 1e-6)
    ev = pd.DataFrame(dict(area_px=area, side_depth=side_depth, encloses_px=encloses,
                           hole_lift=hole_lift,
                           elongation=elong, width_px=width,
                           slenderness=sk / np.maximum(width, 1e-9),
                           background_rel=background_rel, density=density,
                           neighbours=neighbours, texture=texture),
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
    out = pd.Series("", index=evidence.index, dtype=object)
    judged = (evidence["area_px"] >= config.REJECT_MIN_AREA_PX).to_numpy(bool)
    for name, rule in RULES:
        hit = rule(evidence).fillna(False).to_numpy(bool) & judged
        out[(out == "") & hit] = name
    return out
