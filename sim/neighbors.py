"""Broad phase: cell grid + Verlet skin, fixed capacity with an overflow return.

The contact list holds every ball pair (i < j) closer than r_i + r_j + skin, except pairs joined
by a smooth joint (the joint replaces the ball–ball law, REFERENCE.md §4). Pairs joined by a
parallel bond stay in the list for the linear part of the bonded contact. Shear-force history
is carried across rebuilds by looking each new pair up among the old pairs of its owner i.
"""
import numpy as np

from ._jit import njit, prange


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
    head = np.zeros(ncx * ncy + 1, np.int64)
    for p in range(n):
        cx = int((x[p] - xmin) / h)
        cy = int((y[p] - ymin) / h)
        c = cy * ncx + cx
        cell[p] = c
        head[c + 1] += 1
    for c in range(ncx * ncy):
        head[c + 1] += head[c]
    pos = head[:-1].copy()
    items = np.empty(n, np.int64)
    for p in range(n):
        c = cell[p]
        items[pos[c]] = p
        pos[c] += 1
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


@njit(parallel=True)
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
    """
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
    cstart[0] = 0
    for i in range(n):
        cstart[i + 1] = cstart[i] + cnt[i]
    total = cstart[n]
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
                            ci[k] = i
                            cj[k] = j
                            f = 0.0
                            for o in range(old_start[i], old_start[i + 1]):
                                if old_cj[o] == j:
                                    f = old_fs[o]
                                    break
                            fs[k] = f
                            k += 1
    return total


def partner_csr(n, pi, pj):
    """CSR (ptr, adj) of the partners of every particle for the pairs ``(pi, pj)`` (numpy)."""
    a = np.concatenate([pi, pj]).astype(np.int64)
    b = np.concatenate([pj, pi]).astype(np.int32)
    order = np.argsort(a, kind="stable")
    ptr = np.zeros(n + 1, np.int64)
    np.add.at(ptr, a + 1, 1)
    return np.cumsum(ptr), b[order]
