"""Overlap relaxation of a 2D disk packing in a rectangle (the packing step of ``ball distribute``).

A disk packing placed at random overlaps heavily. :func:`relax_overlaps` moves the disk centres
(radii fixed) until the largest overlap is a small fraction of the smaller radius. It is not a
dynamic simulation: it minimises the harmonic overlap energy

    E = 1/2 sum_contacts delta_ij^2 + 1/2 sum_walls delta_iw^2,   delta = max(0, r_i + r_j - d_ij)

by mass-weighted gradient steps with heavy-ball momentum, every step Jacobi style (all
displacements from the same old positions, serial loops), so the result is deterministic.
Candidate pairs come from a Verlet list with a skin, rebuilt when a disk has moved a quarter of
the skin; the list is built on a uniform cell grid in which a disk is entered in every cell its
bounding box touches, so that wide size distributions (grain seeds, size ratio ~25) stay cheap;
a pair is kept once, in the cell holding the lower-left corner of the two bounding boxes'
intersection. The kernels run serially: on the shared 2-core machine threaded ``prange``
loops were 10-25x slower under load.

The kernel ``_relax`` is pure on arrays and checks nothing; :func:`relax_overlaps` checks.
"""
from __future__ import annotations

import numpy as np

from ._jit import njit
from .errors import InputError

__all__ = ["relax_overlaps", "max_overlap"]

#: Fraction of a pair overlap removed per step (before momentum).
STEP = 0.5
#: Heavy-ball momentum of the relaxation.
MOMENTUM = 0.7
#: Cell size in units of the median diameter.
CELL_DIAMETERS = 1.5
#: Verlet skin in units of the median radius (pair list rebuilt after a move of skin/4).
SKIN_RADII = 0.5


@njit
def _build_cells(x, y, r, x0, y0, h, nx, ny, counts, start, items, cursor):
    """Fill the multi-cell grid. counts/start (nx*ny+1,), items (capacity,), cursor (nx*ny,).

    Returns the number of entries needed; if it exceeds ``items.size`` nothing is written
    after counting and the caller re-allocates.
    """
    n = x.size
    counts[:] = 0
    for i in range(n):
        cx0 = min(max(int((x[i] - r[i] - x0) / h), 0), nx - 1)
        cx1 = min(max(int((x[i] + r[i] - x0) / h), 0), nx - 1)
        cy0 = min(max(int((y[i] - r[i] - y0) / h), 0), ny - 1)
        cy1 = min(max(int((y[i] + r[i] - y0) / h), 0), ny - 1)
        for cy in range(cy0, cy1 + 1):
            for cx in range(cx0, cx1 + 1):
                counts[cy * nx + cx] += 1
    start[0] = 0
    for c in range(nx * ny):
        start[c + 1] = start[c] + counts[c]
    total = start[nx * ny]
    if total > items.size:
        return total
    for c in range(nx * ny):
        cursor[c] = start[c]
    for i in range(n):
        cx0 = min(max(int((x[i] - r[i] - x0) / h), 0), nx - 1)
        cx1 = min(max(int((x[i] + r[i] - x0) / h), 0), nx - 1)
        cy0 = min(max(int((y[i] - r[i] - y0) / h), 0), ny - 1)
        cy1 = min(max(int((y[i] + r[i] - y0) / h), 0), ny - 1)
        for cy in range(cy0, cy1 + 1):
            for cx in range(cx0, cx1 + 1):
                c = cy * nx + cx
                items[cursor[c]] = i
                cursor[c] += 1
    return total


@njit
def _build_pairs(x, y, r, skin, x0, y0, h, nx, ny, start, items, pi, pj):
    """Candidate pairs (i < j) with gap < skin into pi, pj. Returns the count (may exceed the
    capacity pi.size: then only the first pi.size are written and the caller re-allocates)."""
    n = x.size
    cap = pi.size
    k_out = 0
    for i in range(n):
        xi = x[i]
        yi = y[i]
        ri = r[i] + 0.5 * skin
        cx0 = min(max(int((xi - ri - x0) / h), 0), nx - 1)
        cx1 = min(max(int((xi + ri - x0) / h), 0), nx - 1)
        cy0 = min(max(int((yi - ri - y0) / h), 0), ny - 1)
        cy1 = min(max(int((yi + ri - y0) / h), 0), ny - 1)
        for cy in range(cy0, cy1 + 1):
            for cx in range(cx0, cx1 + 1):
                c = cy * nx + cx
                for k in range(start[c], start[c + 1]):
                    j = items[k]
                    if j <= i:
                        continue
                    rj = r[j] + 0.5 * skin
                    ex = x[j] - xi
                    ey = y[j] - yi
                    s = ri + rj
                    if ex * ex + ey * ey >= s * s:
                        continue
                    # count the pair once: in the cell of the lower-left corner of the overlap
                    px = max(xi - ri, x[j] - rj)
                    py = max(yi - ri, y[j] - rj)
                    qx = min(max(int((px - x0) / h), 0), nx - 1)
                    qy = min(max(int((py - y0) / h), 0), ny - 1)
                    if qx != cx or qy != cy:
                        continue
                    if k_out < cap:
                        pi[k_out] = i
                        pj[k_out] = j
                    k_out += 1
    return k_out


@njit
def _step(x, y, r, box, pi, pj, n_pairs, dx, dy):
    """Overlap-removal displacement of every disk into dx, dy; returns the worst relative
    overlap. Pure; checks nothing."""
    n = x.size
    worst = 0.0
    for i in range(n):
        dx[i] = 0.0
        dy[i] = 0.0
    for k in range(n_pairs):
        i = pi[k]
        j = pj[k]
        ri = r[i]
        rj = r[j]
        ex = x[j] - x[i]
        ey = y[j] - y[i]
        s = ri + rj
        d2 = ex * ex + ey * ey
        if d2 >= s * s:
            continue
        d = np.sqrt(d2)
        delta = s - d
        if d > 1e-300:
            ux = ex / d
            uy = ey / d
        else:
            ux = 1.0
            uy = 0.0
        mi = ri * ri
        mj = rj * rj
        fi = delta * mj / (mi + mj)
        fj = delta - fi
        dx[i] -= fi * ux
        dy[i] -= fi * uy
        dx[j] += fj * ux
        dy[j] += fj * uy
        rel = delta / min(ri, rj)
        if rel > worst:
            worst = rel
    for i in range(n):
        ri = r[i]
        p = box[0] + ri - x[i]
        if p > 0.0:
            dx[i] += p
            worst = max(worst, p / ri)
        p = x[i] + ri - box[1]
        if p > 0.0:
            dx[i] -= p
            worst = max(worst, p / ri)
        p = box[2] + ri - y[i]
        if p > 0.0:
            dy[i] += p
            worst = max(worst, p / ri)
        p = y[i] + ri - box[3]
        if p > 0.0:
            dy[i] -= p
            worst = max(worst, p / ri)
    return worst


@njit
def _relax(x, y, r, box, tol, max_iter, step, momentum, h, skin, items, pi, pj):
    """Relax overlaps in place. x, y (N,) m (modified); r (N,) m; box (4,) m.

    Verlet pair list with a skin, rebuilt when a disk has moved more than skin/2.
    Returns (iterations, worst relative overlap, status): status 0 done, 1 the cell buffer
    ``items`` is too small, 2 the pair buffers are too small (the caller re-allocates and
    calls again; positions so far are kept). Pure on arrays; checks nothing.
    """
    n = x.size
    x0 = box[0]
    y0 = box[2]
    nx = max(int((box[1] - box[0]) / h) + 1, 1)
    ny = max(int((box[3] - box[2]) / h) + 1, 1)
    counts = np.zeros(nx * ny + 1, np.int64)
    start = np.zeros(nx * ny + 1, np.int64)
    cursor = np.zeros(nx * ny, np.int64)
    dx = np.zeros(n)
    dy = np.zeros(n)
    vx = np.zeros(n)
    vy = np.zeros(n)
    ax = np.zeros(n)
    ay = np.zeros(n)
    it = 0
    w = np.inf
    n_pairs = 0
    fresh = False
    while it < max_iter:
        if not fresh:
            rs = r + 0.5 * skin
            need = _build_cells(x, y, rs, x0, y0, h, nx, ny, counts, start, items, cursor)
            if need > items.size:
                return it, w, 1
            n_pairs = _build_pairs(x, y, r, skin, x0, y0, h, nx, ny, start, items, pi, pj)
            if n_pairs > pi.size:
                return it, w, 2
            for i in range(n):
                ax[i] = x[i]
                ay[i] = y[i]
            fresh = True
        w = _step(x, y, r, box, pi, pj, n_pairs, dx, dy)
        if w <= tol:
            break
        lim = 0.25 * skin * 0.25 * skin
        for i in range(n):
            vx[i] = momentum * vx[i] + step * dx[i]
            vy[i] = momentum * vy[i] + step * dy[i]
            x[i] += vx[i]
            y[i] += vy[i]
            ex = x[i] - ax[i]
            ey = y[i] - ay[i]
            if ex * ex + ey * ey > lim:
                fresh = False
        it += 1
    return it, w, 0


def max_overlap(x, y, r, box):
    """Largest overlap of a packing as a fraction of the smaller radius (walls included).

    Parameters
    ----------
    x, y, r : (N,) array_like of float64, m
    box : (4,) array_like of float64, m
        xmin, xmax, ymin, ymax.

    Returns
    -------
    worst : float
        max over contacts of (r_i + r_j - d_ij) / min(r_i, r_j), and over walls of the
        penetration / r_i; 0 when nothing overlaps.
    """
    x, y, r, box = _check(x, y, r, box)
    from scipy.spatial import cKDTree
    tree = cKDTree(np.c_[x, y])
    pairs = tree.query_pairs(2.0 * r.max(), output_type="ndarray")
    worst = 0.0
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        d = np.hypot(x[j] - x[i], y[j] - y[i])
        rel = (r[i] + r[j] - d) / np.minimum(r[i], r[j])
        worst = max(worst, float(rel.max()))
    pen = np.max(np.c_[box[0] + r - x, x + r - box[1], box[2] + r - y, y + r - box[3]], axis=1)
    return max(worst, float(np.max(pen / r)), 0.0)


def _check(x, y, r, box):
    x = np.ascontiguousarray(x, dtype=np.float64)
    y = np.ascontiguousarray(y, dtype=np.float64)
    r = np.ascontiguousarray(r, dtype=np.float64)
    box = np.ascontiguousarray(box, dtype=np.float64)
    if x.ndim != 1 or x.size == 0:
        raise InputError(f"x: expected a non-empty 1-D array, got shape {x.shape}")
    for name, a in (("y", y), ("r", r)):
        if a.shape != x.shape:
            raise InputError(f"{name}: expected shape {x.shape} like x, got {a.shape}")
    for name, a in (("x", x), ("y", y), ("r", r), ("box", box)):
        if not np.all(np.isfinite(a)):
            raise InputError(f"{name}: has NaN or inf values, expected finite numbers")
    if np.any(r <= 0):
        raise InputError("r: expected radii > 0 m")
    if box.shape != (4,) or not (box[0] < box[1] and box[2] < box[3]):
        raise InputError(f"box: expected [xmin, xmax, ymin, ymax] with min < max, got {box}")
    if np.any(2 * r > min(box[1] - box[0], box[3] - box[2])):
        raise InputError("r: a disk is wider than the box")
    return x, y, r, box


def relax_overlaps(x, y, r, box, *, tol=0.01, max_iter=20000):
    """Move disk centres until the largest overlap is at most ``tol`` of the smaller radius.

    Parameters
    ----------
    x, y : (N,) array_like of float64, m
        Initial centres (not modified).
    r : (N,) array_like of float64, m
        Radii (fixed).
    box : (4,) array_like of float64, m
        xmin, xmax, ymin, ymax; disks are pushed inside.
    tol : float
        Target largest overlap / min(r_i, r_j) (walls: penetration / r_i).
    max_iter : int
        Step limit.

    Returns
    -------
    x, y : (N,) ndarray of float64, m
        Relaxed centres.
    info : dict
        ``iterations``, ``max_overlap`` (relative, as ``tol``), ``converged``.

    Raises
    ------
    InputError
        Bad shapes, non-finite values, non-positive radii, a bad box or ``tol``.

    Notes
    -----
    Each step moves disk i by the momentum-filtered sum over its overlaps of
    ``-STEP * delta_ij * r_j^2 / (r_i^2 + r_j^2) * n_ij`` (so a large disk moves little against a
    small one) plus the wall penetrations. The result is deterministic (Jacobi update).
    A packing denser than jamming (2D random packings jam near a solid fraction of 0.84) cannot
    reach a small ``tol``: ``converged`` is then False and ``max_overlap`` says how close it got.

    Examples
    --------
    >>> x, y, info = relax_overlaps([0.0, 0.5], [0.0, 0.0], [1.0, 1.0], [-5, 5, -5, 5])
    >>> info["converged"], round(float(abs(x[1] - x[0])), 2) >= 1.98
    (True, True)
    """
    x, y, r, box = _check(x, y, r, box)
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol: expected a positive fraction of a radius, got {tol}")
    x = x.copy()
    y = y.copy()
    rmed = float(np.median(r))
    h = CELL_DIAMETERS * 2.0 * rmed
    h = max(h, 1e-9 * max(box[1] - box[0], box[3] - box[2]))
    skin = SKIN_RADII * rmed
    cap = max(4 * x.size, 1024)
    pcap = max(8 * x.size, 1024)
    total = 0
    while True:
        items = np.empty(cap, np.int64)
        pi = np.empty(pcap, np.int64)
        pj = np.empty(pcap, np.int64)
        it, worst, status = _relax(x, y, r, box, float(tol), int(max_iter) - total, STEP, MOMENTUM,
                                   h, skin, items, pi, pj)
        total += it
        if status == 0:
            break
        if status == 1:
            cap *= 2
        else:
            pcap *= 2
    it = total
    return x, y, {"iterations": int(it), "max_overlap": float(worst),
                  "converged": bool(worst <= tol)}
