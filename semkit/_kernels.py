"""All numba kernels of :mod:`semkit`.

Kernels are pure functions on arrays: they check nothing (the public wrappers do), print nothing
and use no global random state. Each is compiled lazily on first call with ``cache=True``;
importing this module compiles nothing.
"""
import math

import numba
import numpy as np

_OPTS = dict(cache=True, nogil=True, fastmath={"nsz", "arcp", "contract", "afn", "reassoc"},
             error_model="numpy")


def njit(fn):
    """``numba.njit`` with the semkit options (cache, nogil, fastmath without nnan/ninf)."""
    return numba.njit(**_OPTS)(fn)


@njit
def polyline_excess(xs, ys, ws, ox, oy, out):
    """Distance excess of each pixel over a polyline of varying width, written in place.

    Parameters
    ----------
    xs, ys : (K,) float64, px
        Polyline vertices; pixel (i, j) has its centre at (x=j, y=i). K = 1 draws a disk.
    ws : (K,) float64, px
        Full width at each vertex, linearly interpolated along each segment.
    ox, oy : int
        Column and row of ``out[0, 0]`` in the image.
    out : (H, W) float32
        Updated in place with ``min(out, d - w/2)`` where d is the distance to the polyline
        and w the width at the nearest point. Pixels further than ``max(ws)/2 + 2`` px from
        the polyline are left untouched.

    Notes
    -----
    A pixel is inside the crack when its excess is <= 0 and its partial-volume coverage is
    ``clip(0.5 - excess, 0, 1)``.
    """
    h, w = out.shape
    k = xs.shape[0]
    n_seg = max(k - 1, 1)
    for s in range(n_seg):
        ax = xs[s]
        ay = ys[s]
        wa = ws[s]
        if k > 1:
            bx = xs[s + 1]
            by = ys[s + 1]
            wb = ws[s + 1]
        else:
            bx = ax
            by = ay
            wb = wa
        dx = bx - ax
        dy = by - ay
        l2 = dx * dx + dy * dy
        r = 0.5 * max(wa, wb) + 2.0
        i0 = max(int(math.floor(min(ay, by) - r)) - oy, 0)
        i1 = min(int(math.ceil(max(ay, by) + r)) - oy + 1, h)
        j0 = max(int(math.floor(min(ax, bx) - r)) - ox, 0)
        j1 = min(int(math.ceil(max(ax, bx) + r)) - ox + 1, w)
        for i in range(i0, i1):
            py = i + oy
            for j in range(j0, j1):
                px = j + ox
                if l2 > 0.0:
                    t = ((px - ax) * dx + (py - ay) * dy) / l2
                    if t < 0.0:
                        t = 0.0
                    elif t > 1.0:
                        t = 1.0
                else:
                    t = 0.0
                ex = px - ax - t * dx
                ey = py - ay - t * dy
                e = math.sqrt(ex * ex + ey * ey) - 0.5 * (wa + t * (wb - wa))
                if e < out[i, j]:
                    out[i, j] = e


@njit
def chain_links(skel, labels, n_labels, n_straight, n_diag):
    """Count 4- and 8-links of a thin 8-connected skeleton per object, in place.

    Parameters
    ----------
    skel : (H, W) bool
        One-pixel-thin skeleton.
    labels : (H, W) int32
        Object label of each pixel (0 = background); read only where ``skel``.
    n_labels : int
        Number of labels + 1 (length of the output arrays).
    n_straight, n_diag : (n_labels,) int64
        Incremented in place: horizontal/vertical neighbour pairs, and diagonal pairs that are
        not short-cut corners (a diagonal pair whose two common 4-neighbours are both empty).

    Notes
    -----
    Dropping a diagonal link beside which a 4-neighbour path exists counts each staircase
    corner once, so the chain is the 8-connected path a chain code would trace.
    """
    h, w = skel.shape
    for i in range(h):
        for j in range(w):
            if not skel[i, j]:
                continue
            lab = labels[i, j]
            if j + 1 < w and skel[i, j + 1]:
                n_straight[lab] += 1
            if i + 1 < h:
                if skel[i + 1, j]:
                    n_straight[lab] += 1
                if j + 1 < w and skel[i + 1, j + 1]:
                    if not skel[i, j + 1] and not skel[i + 1, j]:
                        n_diag[lab] += 1
                if j >= 1 and skel[i + 1, j - 1]:
                    if not skel[i, j - 1] and not skel[i + 1, j]:
                        n_diag[lab] += 1
    return n_straight, n_diag
