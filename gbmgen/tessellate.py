"""Voronoi and Laguerre (power) tessellations of seed disks, clipped to the specimen rectangle.

The Laguerre cell of seed i is {p : |p - c_i|^2 - w_i <= |p - c_j|^2 - w_j for all j} with
w_i = r_i^2 (the seed radius squared); Voronoi is the same with w = 0. Neighbours come from the
regular triangulation (lower convex hull of the lifted points (x, y, x^2 + y^2 - w), Qhull), each
cell is the box clipped by the bisectors of its neighbours (exact, convex, counter-clockwise).
For a non-overlapping disk packing every disk lies inside its own Laguerre cell, so a cell's
area follows its disk's area: that is why Laguerre keeps wide size distributions that Voronoi
(which moves the boundaries to the middle between centres) loses.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import config
from ._kernels import MAX_CELL_VERTICES, clip_cells
from .errors import InputError

__all__ = ["Grains", "tessellate", "polygon_areas", "polygon_centroids"]


@dataclass
class Grains:
    """Grain polygons of a tessellation.

    Notation: G grains, K vertices in all.

    Attributes
    ----------
    xy : (K, 2) ndarray of float64, m
        Vertices, counter-clockwise per grain.
    offsets : (G+1,) ndarray of int64
        Grain g has vertices ``xy[offsets[g]:offsets[g+1]]``.
    mineral : (G,) ndarray of int32
        Mineral index of each grain (its seed's mineral).
    klass : (G,) ndarray of int8
        Size class of the seed: 0 fine, 1 medium, 2 coarse (-1 when not from a table).
    seed : (G,) ndarray of int64
        Index of the seed that made the grain (-1 for controlled lattices).
    """

    xy: np.ndarray
    offsets: np.ndarray
    mineral: np.ndarray
    klass: np.ndarray
    seed: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def n_grains(self) -> int:
        return int(self.offsets.size - 1)

    def polygon(self, g: int) -> np.ndarray:
        return self.xy[self.offsets[g]:self.offsets[g + 1]]

    def areas(self) -> np.ndarray:
        """(G,) polygon areas, m^2."""
        return polygon_areas(self.xy, self.offsets)

    def centroids(self) -> np.ndarray:
        """(G, 2) polygon centroids, m."""
        return polygon_centroids(self.xy, self.offsets)

    def eq_diameters(self) -> np.ndarray:
        """(G,) equivalent-circle diameters sqrt(4 A / pi), m."""
        return np.sqrt(4.0 * self.areas() / np.pi)

    def n_vertices(self) -> np.ndarray:
        return np.diff(self.offsets)


def _shoelace_terms(xy, offsets):
    n = np.diff(offsets)
    g = np.repeat(np.arange(n.size), n)
    nxt = np.arange(xy.shape[0]) + 1
    full = n > 0
    nxt[offsets[1:][full] - 1] = offsets[:-1][full]
    x0, y0 = xy[:, 0], xy[:, 1]
    x1, y1 = xy[nxt, 0], xy[nxt, 1]
    cross = x0 * y1 - x1 * y0
    return g, cross, x0 + x1, y0 + y1, n.size


def polygon_areas(xy, offsets) -> np.ndarray:
    """(G,) signed areas (positive counter-clockwise) of packed polygons, m^2 (shoelace)."""
    g, cross, _, _, n = _shoelace_terms(np.asarray(xy, float), np.asarray(offsets, np.int64))
    return 0.5 * np.bincount(g, weights=cross, minlength=n)


def polygon_centroids(xy, offsets) -> np.ndarray:
    """(G, 2) centroids of packed polygons, m."""
    g, cross, sx, sy, n = _shoelace_terms(np.asarray(xy, float), np.asarray(offsets, np.int64))
    a = 0.5 * np.bincount(g, weights=cross, minlength=n)
    cx = np.bincount(g, weights=cross * sx, minlength=n) / (6.0 * a)
    cy = np.bincount(g, weights=cross * sy, minlength=n) / (6.0 * a)
    return np.c_[cx, cy]


def _neighbours(sx, sy, w):
    """CSR neighbour lists from the regular triangulation (lower hull of the lifted points)."""
    from scipy.spatial import ConvexHull, QhullError

    n = sx.size
    if n == 1:
        return np.zeros(2, np.int64), np.zeros(0, np.int64)
    if n <= 3:
        i, j = np.triu_indices(n, 1)
    else:
        # centre and scale for conditioning
        cx, cy = sx.mean(), sy.mean()
        L = max(np.ptp(sx), np.ptp(sy), 1e-300)
        X = (sx - cx) / L
        Y = (sy - cy) / L
        Z = X * X + Y * Y - w / (L * L)
        try:
            hull = ConvexHull(np.c_[X, Y, Z], qhull_options="Qt")
        except QhullError:  # all seeds collinear
            o = np.lexsort((sy, sx))
            i, j = o[:-1], o[1:]
        else:
            low = hull.equations[:, 2] < 0
            simp = hull.simplices[low]
            i = np.r_[simp[:, 0], simp[:, 1], simp[:, 2]]
            j = np.r_[simp[:, 1], simp[:, 2], simp[:, 0]]
    a = np.r_[i, j]
    b = np.r_[j, i]
    key = np.unique(a.astype(np.int64) * n + b)
    a, b = key // n, key % n
    start = np.zeros(n + 1, np.int64)
    np.add.at(start, a + 1, 1)
    return np.cumsum(start), b.astype(np.int64)


def tessellate(sx, sy, box, *, weights=None):
    """Voronoi (``weights=None``) or Laguerre tessellation of seeds, clipped to ``box``.

    Parameters
    ----------
    sx, sy : (S,) array_like of float64, m
        Seed positions (inside the box).
    box : (4,) array_like of float64, m
        xmin, xmax, ymin, ymax.
    weights : (S,) array_like of float64, m^2, optional
        Power weights (seed radius squared for Laguerre).

    Returns
    -------
    xy : (K, 2) ndarray of float64, m
        Cell vertices, counter-clockwise.
    offsets : (G+1,) ndarray of int64
    seed : (G,) ndarray of int64
        Seed of each cell (seeds with an empty cell, possible only for a Laguerre
        diagram of strongly overlapping disks, are left out).

    Raises
    ------
    InputError
        Bad shapes or a seed outside the box.

    Examples
    --------
    >>> xy, off, seed = tessellate([0.25, 0.75], [0.5, 0.5], [0, 1, 0, 1])
    >>> polygon_areas(xy, off).round(3).tolist()
    [0.5, 0.5]
    """
    xy, offsets, seed, _ = _tessellate(sx, sy, box, weights)
    return xy, offsets, seed


def _tessellate(sx, sy, box, weights):
    """tessellate() plus the edge labels of clip_cells (neighbour seed or -1..-4 box side)."""
    sx = np.ascontiguousarray(sx, dtype=np.float64)
    sy = np.ascontiguousarray(sy, dtype=np.float64)
    box = np.asarray(box, dtype=np.float64)
    if sx.ndim != 1 or sx.size == 0 or sy.shape != sx.shape:
        raise InputError(f"seeds: expected two 1-D arrays of one shape, got {sx.shape}, {sy.shape}")
    if box.shape != (4,) or not (box[0] < box[1] and box[2] < box[3]):
        raise InputError(f"box: expected [xmin, xmax, ymin, ymax], got {box.tolist()}")
    if np.any((sx < box[0]) | (sx > box[1]) | (sy < box[2]) | (sy > box[3])):
        raise InputError("seeds: every seed must lie inside the box")
    w = np.zeros_like(sx) if weights is None else np.ascontiguousarray(weights, dtype=np.float64)
    if w.shape != sx.shape or not np.all(np.isfinite(w)):
        raise InputError(f"weights: expected {sx.shape} finite values")
    start, nbr = _neighbours(sx, sy, w)
    eps = config.GEOM_EPS * max(box[1] - box[0], box[3] - box[2])
    out_xy = np.empty((sx.size, MAX_CELL_VERTICES, 2))
    out_n = np.zeros(sx.size, np.int64)
    out_lab = np.empty((sx.size, MAX_CELL_VERTICES), np.int64)
    clip_cells(sx, sy, w, start, nbr, box, eps, out_xy, out_lab, out_n)
    if sx.size > 1:
        out_n[np.diff(start) == 0] = 0  # hidden in the regular triangulation: empty cell
    if np.any(out_n < 0):
        raise InputError("seeds: a cell has more than "
                         f"{MAX_CELL_VERTICES} vertices (degenerate seeds?)")
    keep = np.flatnonzero(out_n >= 3)
    counts = out_n[keep]
    offsets = np.zeros(keep.size + 1, np.int64)
    offsets[1:] = np.cumsum(counts)
    mask = np.arange(MAX_CELL_VERTICES)[None, :] < counts[:, None]
    xy = out_xy[keep][mask]
    lab = out_lab[keep][mask]
    area = polygon_areas(xy, offsets)
    good = area > config.MIN_CELL_AREA_FRACTION * (box[1] - box[0]) * (box[3] - box[2]) / sx.size
    if not np.all(good):
        sel = np.flatnonzero(good)
        counts = counts[sel]
        idx = np.concatenate([np.arange(offsets[g], offsets[g + 1]) for g in sel])
        xy, lab = xy[idx], lab[idx]
        offsets = np.zeros(sel.size + 1, np.int64)
        offsets[1:] = np.cumsum(counts)
        keep = keep[sel]
    return xy, offsets, keep.astype(np.int64), lab


def _hessian(sx, sy, xy, offsets, seed, lab, n):
    """Sparse (S, S) matrix of d(area_i)/d(w_j): off-diagonal -l_ij / (2 d_ij), diagonal
    sum_j l_ij / (2 d_ij), over the cell edges shared by seeds i and j."""
    from scipy.sparse import coo_matrix

    nxt = np.arange(xy.shape[0]) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    length = np.hypot(*(xy[nxt] - xy).T)
    owner = seed[np.repeat(np.arange(offsets.size - 1), np.diff(offsets))]
    ok = lab >= 0
    i, j = owner[ok], lab[ok]
    c = length[ok] / (2.0 * np.hypot(sx[j] - sx[i], sy[j] - sy[i]))
    diag = np.bincount(i, weights=c, minlength=n)
    return coo_matrix((np.r_[-c, diag], (np.r_[i, np.arange(n)], np.r_[j, np.arange(n)])),
                      shape=(n, n)).tocsr()


def _areas(sx, sy, box, w):
    xy, off, seed, lab = _tessellate(sx, sy, box, w)
    a = np.zeros(sx.size)
    a[seed] = polygon_areas(xy, off)
    return a, (xy, off, seed, lab)


def fit_power_weights(sx, sy, box, target_area, *, weights, n_iter=30, rtol=0.01):
    """Laguerre weights that give every cell its target area (capacity-constrained diagram).

    Parameters
    ----------
    sx, sy : (S,) ndarray of float64, m
        Seeds (fixed).
    box : (4,) array_like of float64, m
    target_area : (S,) ndarray of float64, m^2
        Wanted cell areas (their sum is scaled to the box area).
    weights : (S,) ndarray of float64, m^2
        Starting weights (seed radius squared: for non-overlapping seed disks every cell is
        then non-empty, which the method needs; if a cell is empty the weights are halved
        towards Voronoi, w = 0, until none is).
    n_iter : int
        Newton-step limit.
    rtol : float
        Stop when every cell area is within ``rtol`` (relative) of its target.

    Returns
    -------
    weights : (S,) ndarray of float64, m^2
    info : dict
        ``iterations``, ``max_rel_error`` (largest |A - A_target| / A_target) and
        ``rms_rel_error`` (root mean square of sqrt(A / A_target) - 1, the relative error of
        the equivalent diameter).

    Notes
    -----
    The areas are the gradient of a concave function of the weights (semi-discrete optimal
    transport), whose Hessian is the graph Laplacian with weights l_ij / (2 d_ij) (l_ij the
    shared edge, d_ij the seed distance). Damped Newton (Kitagawa, Merigot and Thibert 2019):
    solve H dw = A_target - A, halve the step until every cell keeps at least half of
    min(its area, its target) and the error has fallen. Converges in a few steps.
    """
    from scipy.sparse import identity
    from scipy.sparse.linalg import spsolve

    box = np.asarray(box, float)
    t = np.asarray(target_area, float)
    t = t * (box[1] - box[0]) * (box[3] - box[2]) / t.sum()
    w = np.array(weights, dtype=float)
    n = sx.size
    a, geo = _areas(sx, sy, box, w)
    lam = 1.0
    while np.any(a <= 0) and lam > 1e-3:  # empty cells (overlapping seed disks): shrink the
        lam *= 0.5                         # weights towards Voronoi (w = 0, every cell live)
        a, geo = _areas(sx, sy, box, lam * w)
    if np.any(a <= 0):
        lam = 0.0
        a, geo = _areas(sx, sy, box, 0.0 * w)
    w = lam * w
    err = float(np.max(np.abs(a - t) / t))
    it = 0
    for it in range(1, n_iter + 1):
        if err <= rtol or np.any(a <= 0):
            it -= 1
            break
        H = _hessian(sx, sy, *geo, n)
        eps = 1e-9 * float(H.diagonal().mean())
        dw = spsolve((H + eps * identity(n, format="csr")).tocsc(), t - a)
        dw -= dw.mean()
        g0 = float(np.linalg.norm(t - a))
        floor = 0.5 * np.minimum(a, t)
        tau = 1.0
        accepted = False
        while tau > 1e-4:
            a2, geo2 = _areas(sx, sy, box, w + tau * dw)
            if np.all(a2 >= floor) and np.linalg.norm(t - a2) <= (1.0 - 0.5 * tau) * g0:
                accepted = True
                break
            tau *= 0.5
        if not accepted:
            break
        w = w + tau * dw
        a, geo = a2, geo2
        err = float(np.max(np.abs(a - t) / t))
    rms = float(np.sqrt(np.mean((np.sqrt(a / t) - 1.0) ** 2)))
    return w, {"iterations": it, "max_rel_error": err, "rms_rel_error": rms}


def fit_with_centroid_steps(sx, sy, box, target_area, *, weights, steps):
    """:func:`fit_power_weights`, then ``steps`` times: seeds to their cell centroids and fit
    again (the seeds then lie in their own cells; areas stay within the fit's tolerance).

    Returns
    -------
    sx, sy : (S,) ndarray of float64, m
        Seeds (moved; copies).
    weights : (S,) ndarray of float64, m^2
    info : dict
        Of the last fit.
    """
    w, fit = fit_power_weights(sx, sy, box, target_area, weights=weights)
    for _ in range(steps):
        xy, off, sidx = tessellate(sx, sy, box, weights=w)
        c = polygon_centroids(xy, off)
        sx, sy = sx.copy(), sy.copy()
        sx[sidx], sy[sidx] = c[:, 0], c[:, 1]
        w, fit = fit_power_weights(sx, sy, box, target_area, weights=w)
    return sx, sy, w, fit
