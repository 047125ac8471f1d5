"""Broad phase: cell grid + Verlet skin, fixed capacity with an overflow return.

The contact list holds every ball pair (i < j) closer than r_i + r_j + skin, except pairs joined
by a smooth joint (the joint replaces the ball–ball law, REFERENCE.md §4). Pairs joined by a
parallel bond stay in the list for the linear part of the bonded contact. Shear-force history
is carried across rebuilds by looking each new pair up among the old pairs of its owner i.
Radii spread widely (field models) are searched on one grid per radius level.
"""
import numpy as np

from . import config
from ._jit import njit, prange


@njit
def _bucket(cell, ncells):
    """CSR of particles by cell: items[head[c]:head[c+1]] are the particles of cell c, in
    index order."""
    head = np.zeros(ncells + 1, np.int64)
    for p in range(cell.size):
        head[cell[p] + 1] += 1
    for c in range(ncells):
        head[c + 1] += head[c]
    pos = head[:-1].copy()
    items = np.empty(cell.size, np.int64)
    for p in range(cell.size):
        c = cell[p]
        items[pos[c]] = p
        pos[c] += 1
    return head, items


@njit
def _grid(x, y, n, h):
    xmin = x[0]
    xmax = x[0]
    ymin = y[0]
    ymax = y[0]
    for p in range(n):
        if x[p] < xmin:
            xmin = x[p]
        if x[p] > xmax:
            xmax = x[p]
        if y[p] < ymin:
            ymin = y[p]
        if y[p] > ymax:
            ymax = y[p]
    # never more than ~4N cells, whatever the spread
    while ((xmax - xmin) / h + 1.0) * ((ymax - ymin) / h + 1.0) > 4.0 * n + 16.0:
        h *= 2.0
    ncx = int((xmax - xmin) / h) + 1
    ncy = int((ymax - ymin) / h) + 1
    cell = np.empty(n, np.int64)
    for p in range(n):
        cx = int((x[p] - xmin) / h)
        cy = int((y[p] - ymin) / h)
        cell[p] = cy * ncx + cx
    head, items = _bucket(cell, ncx * ncy)
    return cell, head, items, ncx, ncy


@njit(inline="always")
def _is_candidate(i, j, x, y, r, skin, sj_ptr, sj_adj):
    """True when ``i``–``j`` is within the Verlet skin and is not a smooth-joint pair.

    Inlined into both passes of :func:`build_contacts` (count, then fill), so the two passes
    cannot disagree about which pairs exist.
    """
    dx = x[j] - x[i]
    dy = y[j] - y[i]
    lim = r[i] + r[j] + skin
    if dx * dx + dy * dy >= lim * lim:
        return False
    for s in range(sj_ptr[i], sj_ptr[i + 1]):
        if sj_adj[s] == j:
            return False
    return True


@njit(inline="always")
def _owner_index(counts, cstart):
    """cstart = exclusive prefix sum of the per-owner counts; returns the total."""
    cstart[0] = 0
    for i in range(counts.size):
        cstart[i + 1] = cstart[i] + counts[i]
    return cstart[counts.size]


@njit(inline="always")
def _put(k, i, j, old_start, old_cj, old_fs, ci, cj, fs):
    """Write pair (i, j) into slot k with its shear force from the old list (0 if new)."""
    ci[k] = i
    cj[k] = j
    f = 0.0
    for o in range(old_start[i], old_start[i + 1]):
        if old_cj[o] == j:
            f = old_fs[o]
            break
    fs[k] = f


@njit(parallel=True)
def _build_contacts_single(x, y, r, skin, sj_ptr, sj_adj, old_start, old_cj, old_fs, cstart, ci,
                           cj, fs, nchunks):
    """Single-grid :func:`build_contacts` (cell 2 r_max + skin), same arguments and return."""
    n = x.size
    rmax = 0.0
    for p in range(n):
        if r[p] > rmax:
            rmax = r[p]
    h = 2.0 * rmax + skin
    cell, head, items, ncx, ncy = _grid(x, y, n, h)
    cnt = np.zeros(n, np.int64)
    for t in prange(nchunks):
        lo = (n * t) // nchunks
        hi = (n * (t + 1)) // nchunks
        for i in range(lo, hi):
            c = cell[i]
            cx = c % ncx
            cy = c // ncx
            k = 0
            for oy in range(-1, 2):
                yy = cy + oy
                if yy < 0 or yy >= ncy:
                    continue
                for ox in range(-1, 2):
                    xx = cx + ox
                    if xx < 0 or xx >= ncx:
                        continue
                    cc = yy * ncx + xx
                    for q in range(head[cc], head[cc + 1]):
                        j = items[q]
                        if j <= i:
                            continue
                        if _is_candidate(i, j, x, y, r, skin, sj_ptr, sj_adj):
                            k += 1
            cnt[i] = k
    total = _owner_index(cnt, cstart)
    if total > ci.size:
        return total
    for t in prange(nchunks):
        lo = (n * t) // nchunks
        hi = (n * (t + 1)) // nchunks
        for i in range(lo, hi):
            c = cell[i]
            cx = c % ncx
            cy = c // ncx
            k = cstart[i]
            for oy in range(-1, 2):
                yy = cy + oy
                if yy < 0 or yy >= ncy:
                    continue
                for ox in range(-1, 2):
                    xx = cx + ox
                    if xx < 0 or xx >= ncx:
                        continue
                    cc = yy * ncx + xx
                    for q in range(head[cc], head[cc + 1]):
                        j = items[q]
                        if j <= i:
                            continue
                        if _is_candidate(i, j, x, y, r, skin, sj_ptr, sj_adj):
                            _put(k, i, j, old_start, old_cj, old_fs, ci, cj, fs)
                            k += 1
    return total


@njit
def _multigrid(x, y, r, level, nlev, skin):
    """One cell grid per radius level (cell = 2 r_max of the level + skin, over the level's own
    bounding box, never more than ~4 cells per particle of the level), stored back to back.

    Returns
    -------
    head, items : CSR over all levels' cells (cell ``off[l] + cy * ncx[l] + cx`` of level l)
    x0, y0, h, rmaxl : (L,) float64, m; ncx, ncy, off, cnt : (L,) int64
    """
    n = x.size
    cnt = np.zeros(nlev, np.int64)
    rmaxl = np.zeros(nlev)
    x0 = np.full(nlev, np.inf)
    y0 = np.full(nlev, np.inf)
    x1 = np.full(nlev, -np.inf)
    y1 = np.full(nlev, -np.inf)
    for p in range(n):
        lv = level[p]
        cnt[lv] += 1
        rmaxl[lv] = max(rmaxl[lv], r[p])
        x0[lv] = min(x0[lv], x[p])
        y0[lv] = min(y0[lv], y[p])
        x1[lv] = max(x1[lv], x[p])
        y1[lv] = max(y1[lv], y[p])
    h = np.ones(nlev)
    ncx = np.ones(nlev, np.int64)
    ncy = np.ones(nlev, np.int64)
    off = np.zeros(nlev + 1, np.int64)
    for lv in range(nlev):
        if cnt[lv] == 0:
            x0[lv] = 0.0
            y0[lv] = 0.0
            off[lv + 1] = off[lv]
            continue
        hl = 2.0 * rmaxl[lv] + skin
        while ((x1[lv] - x0[lv]) / hl + 1.0) * ((y1[lv] - y0[lv]) / hl + 1.0) \
                > 4.0 * cnt[lv] + 16.0:
            hl *= 2.0
        h[lv] = hl
        ncx[lv] = int((x1[lv] - x0[lv]) / hl) + 1
        ncy[lv] = int((y1[lv] - y0[lv]) / hl) + 1
        off[lv + 1] = off[lv] + ncx[lv] * ncy[lv]
    cell = np.empty(n, np.int64)
    for p in range(n):
        lv = level[p]
        cx = int((x[p] - x0[lv]) / h[lv])
        cy = int((y[p] - y0[lv]) / h[lv])
        cell[p] = off[lv] + cy * ncx[lv] + cx
    head, items = _bucket(cell, off[nlev])
    return head, items, x0, y0, h, rmaxl, ncx, ncy, off, cnt


@njit(inline="always")
def _scan_levels(i, fill, k, x, y, r, skin, sj_ptr, sj_adj, head, items, x0, y0, h, rmaxl, ncx,
                 ncy, off, cnt, old_start, old_cj, old_fs, ci, cj, fs):
    """Visit the candidates j > i of particle i in every level's grid; count them, and with
    ``fill`` write them from slot ``k`` on. Returns the slot after the last one."""
    for lv in range(rmaxl.size):
        if cnt[lv] == 0:
            continue
        reach = r[i] + rmaxl[lv] + skin
        cxa = max(int(np.floor((x[i] - reach - x0[lv]) / h[lv])), 0)
        cxb = min(int(np.floor((x[i] + reach - x0[lv]) / h[lv])), ncx[lv] - 1)
        cya = max(int(np.floor((y[i] - reach - y0[lv]) / h[lv])), 0)
        cyb = min(int(np.floor((y[i] + reach - y0[lv]) / h[lv])), ncy[lv] - 1)
        for yy in range(cya, cyb + 1):
            for xx in range(cxa, cxb + 1):
                cc = off[lv] + yy * ncx[lv] + xx
                for q in range(head[cc], head[cc + 1]):
                    j = items[q]
                    if j <= i:
                        continue
                    if _is_candidate(i, j, x, y, r, skin, sj_ptr, sj_adj):
                        if fill:
                            _put(k, i, j, old_start, old_cj, old_fs, ci, cj, fs)
                        k += 1
    return k


@njit(parallel=True)
def _build_contacts_levels(x, y, r, level, nlev, skin, sj_ptr, sj_adj, old_start, old_cj,
                           old_fs, cstart, ci, cj, fs, nchunks):
    """:func:`build_contacts` on one grid per radius level (``level`` (N,) int64 in 0..nlev-1).

    A particle searches every level's grid over the cells within r_i + r_max(level) + skin,
    so each pair is found once, from its lower index, whatever the two radii. Partners of a
    particle come level by level, then cell by cell (an order that differs from the single
    grid's: sums over contacts then differ in the last bits).
    """
    n = x.size
    head, items, x0, y0, h, rmaxl, ncx, ncy, off, cnt = _multigrid(x, y, r, level, nlev, skin)
    counts = np.zeros(n, np.int64)
    for t in prange(nchunks):
        lo = (n * t) // nchunks
        hi = (n * (t + 1)) // nchunks
        for i in range(lo, hi):
            counts[i] = _scan_levels(i, False, 0, x, y, r, skin, sj_ptr, sj_adj, head, items,
                                     x0, y0, h, rmaxl, ncx, ncy, off, cnt, old_start, old_cj,
                                     old_fs, ci, cj, fs)
    total = _owner_index(counts, cstart)
    if total > ci.size:
        return total
    for t in prange(nchunks):
        lo = (n * t) // nchunks
        hi = (n * (t + 1)) // nchunks
        for i in range(lo, hi):
            _scan_levels(i, True, cstart[i], x, y, r, skin, sj_ptr, sj_adj, head, items, x0,
                         y0, h, rmaxl, ncx, ncy, off, cnt, old_start, old_cj, old_fs, ci, cj, fs)
    return total


def radius_levels(r, spread=config.MULTILEVEL_SPREAD):
    """Radius level of every particle for the multi-level grid, or None for a single grid.

    Level l holds radii in (r_max / 2^(l+1), r_max / 2^l]; a single grid is used when
    r_max / r_min <= ``spread`` (lab specimens: 1.66).

    Returns
    -------
    level : (N,) ndarray of int64 or None
    n_levels : int
    """
    r = np.asarray(r, float)
    if r.size == 0:
        return None, 1
    rmax, rmin = float(r.max()), float(r.min())
    if rmax <= spread * rmin:
        return None, 1
    level = np.floor(np.log2(rmax / r)).astype(np.int64)
    level = np.clip(level, 0, None)
    return level, int(level.max()) + 1


def build_contacts(x, y, r, skin, sj_ptr, sj_adj, old_start, old_cj, old_fs, cstart, ci, cj,
                   fs, nchunks):
    """Fill the contact list; return the number of pairs (> capacity means nothing was filled).

    Parameters
    ----------
    x, y, r : (N,) float64, m
    skin : float, m
    sj_ptr, sj_adj : CSR (N+1,), (2S,) of smooth-joint partners, excluded from the list.
    old_start, old_cj, old_fs : previous owner index (N+1,), partners and shear forces.
    cstart : (N+1,) int64, written: owner index of the new list.
    ci, cj, fs : (C,) int32, int32, float64, written up to the returned count.
    nchunks : int
        Static work split (threads).

    Returns
    -------
    total : int
        Number of pairs; if it exceeds ``ci.size`` only ``cstart`` was written.

    Notes
    -----
    With radii spread by more than ``config.MULTILEVEL_SPREAD`` (r_max / r_min) the search runs
    on one grid per radius level (:func:`radius_levels`), so cells sized for the largest
    particles do not fill up with hundreds of small ones (field models: 17-397 mm).
    Otherwise one grid of cell 2 r_max + skin, as before.
    """
    level, nlev = radius_levels(r)
    if level is None:
        return _build_contacts_single(x, y, r, skin, sj_ptr, sj_adj, old_start, old_cj,
                                      old_fs, cstart, ci, cj, fs, nchunks)
    return _build_contacts_levels(x, y, r, level, nlev, skin, sj_ptr, sj_adj, old_start, old_cj,
                                  old_fs, cstart, ci, cj, fs, nchunks)


def partner_csr(n, pi, pj):
    """CSR (ptr, adj) of the partners of every particle for the pairs ``(pi, pj)`` (numpy)."""
    a = np.concatenate([pi, pj]).astype(np.int64)
    b = np.concatenate([pj, pi]).astype(np.int32)
    order = np.argsort(a, kind="stable")
    ptr = np.zeros(n + 1, np.int64)
    np.add.at(ptr, a + 1, 1)
    return np.cumsum(ptr), b[order]
