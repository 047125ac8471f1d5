"""Controlled tessellations (thesis Ch. 5, Table 5-1): hexagon, rectangle and shield grains.

Every grain has the same area A and slenderness S = H / W (vertical over horizontal length
through the centroid, Equ. 5-2). The grains are built from node (vertex) lattices:

* rectangle: nodes aligned in x from row to row (x(N[i,j]) = x(N[i+1,j])): a W x H grid,
  W = sqrt(A / S), H = sqrt(A S); 4 vertices.
* hexagon: rows alternate in x (shifted by W/2, x(N[i,j]) = x(N[i+2,j])): a regular pointy-top
  hexagon stretched vertically; straight sides H/2, caps H/4, A = 0.75 W H; 6 vertices.
* shield: as hexagon, and the row spacings alternate: straight sides ``SHIELD_SIDE`` H, a long
  bottom cap ``SHIELD_BOTTOM`` H and a short top cap ``SHIELD_TOP`` H, every other row
  mirrored upside down so that the rows tile; A = W H (side + (top + bottom) / 2); 6 vertices.

Grains cut by the specimen boundary are clipped to it.
"""
from __future__ import annotations

import numpy as np

from . import config
from .errors import InputError

__all__ = ["controlled_tessellation", "measure_slenderness", "shape_dimensions", "SHAPES"]

SHAPES = ("hexagon", "rectangle", "shield")


def shape_dimensions(shape, slenderness, area):
    """Width W and height H (m) of a grain with slenderness H/W and area (m^2)."""
    if shape not in SHAPES:
        raise InputError(f"shape: expected one of {SHAPES}, got {shape!r}")
    if not (np.isfinite(slenderness) and slenderness > 0):
        raise InputError(f"slenderness: expected H/W > 0, got {slenderness!r}")
    if not (np.isfinite(area) and area > 0):
        raise InputError(f"grain area: expected > 0, got {area!r}")
    fill = {"rectangle": 1.0, "hexagon": 0.75,
            "shield": config.SHIELD_SIDE + 0.5 * (config.SHIELD_TOP + config.SHIELD_BOTTOM)}[shape]
    wh = area / fill
    return np.sqrt(wh / slenderness), np.sqrt(wh * slenderness)


def _template(shape, W, H, flip):
    """Counter-clockwise vertices of one grain centred on its lattice node."""
    if shape == "rectangle":
        return np.array([[-W / 2, -H / 2], [W / 2, -H / 2], [W / 2, H / 2], [-W / 2, H / 2]])
    if shape == "hexagon":
        side, top, bot = 0.5 * H, 0.25 * H, 0.25 * H
    else:
        side, top, bot = (config.SHIELD_SIDE * H, config.SHIELD_TOP * H, config.SHIELD_BOTTOM * H)
    p = np.array([[0.0, -side / 2 - bot], [W / 2, -side / 2], [W / 2, side / 2],
                  [0.0, side / 2 + top], [-W / 2, side / 2], [-W / 2, -side / 2]])
    if flip:
        p[:, 1] = -p[:, 1]
        p = p[::-1]
        p = np.roll(p, 1, axis=0)
    return p


def _lattice(shape, W, H, box):
    """Node positions and flip flags covering the box with a margin of one grain."""
    x0, x1, y0, y1 = box
    nodes, flips = [], []
    if shape == "rectangle":
        xs = np.arange(x0 + W / 2, x1 + W, W)
        ys = np.arange(y0 + H / 2, y1 + H, H)
        X, Y = np.meshgrid(xs, ys)
        return np.c_[X.ravel(), Y.ravel()], np.zeros(X.size, bool)
    if shape == "hexagon":
        side, top, bot = 0.5 * H, 0.25 * H, 0.25 * H
    else:
        side, top, bot = (config.SHIELD_SIDE * H, config.SHIELD_TOP * H, config.SHIELD_BOTTOM * H)
    # row A (not flipped): caps (top, bot); row B (flipped): caps (bot, top).
    # A -> B pitch: side + bot_B = side + top ... derived from shared edges.
    y = y0 - H
    row = 0
    while y < y1 + H:
        flip = (row % 2 == 1) and shape == "shield"
        shift = (row % 2) * W / 2
        xs = np.arange(x0 - W + shift, x1 + W, W)
        nodes.append(np.c_[xs, np.full(xs.size, y)])
        flips.append(np.full(xs.size, flip))
        # pitch to the next row: this row's top cap meets the next row's lower side vertex
        this_top = bot if flip else top
        y += side + this_top
        row += 1
    return np.concatenate(nodes), np.concatenate(flips)


def _clip_box(p, box):
    """Clip a convex counter-clockwise polygon to the box (Sutherland-Hodgman)."""
    for axis, bound, sign in ((0, box[0], -1), (0, box[1], 1), (1, box[2], -1), (1, box[3], 1)):
        if p.shape[0] == 0:
            break
        f = sign * (p[:, axis] - bound)  # keep f <= 0
        out = []
        m = p.shape[0]
        for v in range(m):
            u = (v + 1) % m
            if f[v] <= 0:
                out.append(p[v])
            if (f[v] < 0 < f[u]) or (f[u] < 0 < f[v]):
                t = f[v] / (f[v] - f[u])
                out.append(p[v] + t * (p[u] - p[v]))
        p = np.array(out).reshape(-1, 2)
    return p


def controlled_tessellation(shape, box, *, slenderness, grain_area_m2):
    """Tile the box with grains of one shape, slenderness and area.

    Parameters
    ----------
    shape : {"hexagon", "rectangle", "shield"}
    box : (4,) array_like of float64, m
    slenderness : float
        H / W through the centroid (thesis ranges: hexagon 0.47-2.13, rectangle 0.5-3,
        shield 0.67-1.43).
    grain_area_m2 : float
        Area of every (unclipped) grain, m^2 (thesis 1.78 mm^2).

    Returns
    -------
    xy : (K, 2) ndarray of float64, m
    offsets : (G+1,) ndarray of int64
    interior : (G,) ndarray of bool
        True for grains not cut by the box.

    Examples
    --------
    >>> xy, off, inner = controlled_tessellation("rectangle", [0, 4, 0, 2], slenderness=1.0,
    ...                                          grain_area_m2=1.0)
    >>> off.size - 1, int(inner.sum())
    (8, 8)
    """
    box = np.asarray(box, float)
    W, H = shape_dimensions(shape, float(slenderness), float(grain_area_m2))
    nodes, flips = _lattice(shape, W, H, box)
    eps = config.GEOM_EPS * max(box[1] - box[0], box[3] - box[2])
    polys, inner = [], []
    full = float(grain_area_m2)
    for (cx, cy), fl in zip(nodes, flips):
        p = _template(shape, W, H, fl) + (cx, cy)
        if p[:, 0].max() <= box[0] + eps or p[:, 0].min() >= box[1] - eps \
                or p[:, 1].max() <= box[2] + eps or p[:, 1].min() >= box[3] - eps:
            continue
        inside = (p[:, 0].min() >= box[0] - eps and p[:, 0].max() <= box[1] + eps
                  and p[:, 1].min() >= box[2] - eps and p[:, 1].max() <= box[3] + eps)
        if not inside:
            p = _clip_box(p, box)
            # drop repeated vertices left by the clipping
            keep = np.ones(p.shape[0], bool)
            keep[1:] = np.any(np.abs(np.diff(p, axis=0)) > eps, axis=1)
            p = p[keep]
            if p.shape[0] > 1 and np.all(np.abs(p[-1] - p[0]) <= eps):
                p = p[:-1]
            if p.shape[0] < 3:
                continue
            a = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
            if a <= 1e-9 * full:
                continue
        polys.append(p)
        inner.append(inside)
    offsets = np.zeros(len(polys) + 1, np.int64)
    offsets[1:] = np.cumsum([p.shape[0] for p in polys])
    return np.concatenate(polys), offsets, np.array(inner, bool)


def _chord(p, axis, at):
    """Length of the chord of a convex polygon along the line {coord[axis] = at}."""
    other = 1 - axis
    q = np.roll(p, -1, axis=0)
    a, b = p[:, axis], q[:, axis]
    hits = []
    for k in range(p.shape[0]):
        if (a[k] - at) * (b[k] - at) <= 0 and a[k] != b[k]:
            t = (at - a[k]) / (b[k] - a[k])
            hits.append(p[k, other] + t * (q[k, other] - p[k, other]))
    return max(hits) - min(hits) if hits else 0.0


def measure_slenderness(p):
    """Slenderness H/W of a polygon: vertical over horizontal chord through its centroid.

    Parameters
    ----------
    p : (K, 2) array_like of float64
        Convex polygon, counter-clockwise.

    Returns
    -------
    slenderness : float

    Examples
    --------
    >>> measure_slenderness([[0, 0], [2, 0], [2, 1], [0, 1]])
    0.5
    """
    p = np.asarray(p, float)
    q = np.roll(p, -1, axis=0)
    cr = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    a = 0.5 * cr.sum()
    cx = np.sum((p[:, 0] + q[:, 0]) * cr) / (6 * a)
    cy = np.sum((p[:, 1] + q[:, 1]) * cr) / (6 * a)
    return float(_chord(p, 0, cx) / _chord(p, 1, cy))
