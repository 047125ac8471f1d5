"""All numba kernels of :mod:`gbmgen` (pure on arrays, SI units, they check nothing).

Compiled lazily with ``cache=True`` through :func:`sim._jit.njit` (importing compiles nothing).
"""
import numpy as np

from sim._jit import njit

#: Vertex capacity of one clipped cell (a Laguerre cell of a disk packing has ~6).
MAX_CELL_VERTICES = 128


@njit
def clip_cells(sx, sy, w, nbr_start, nbr_idx, box, eps, out_xy, out_lab, out_n):
    """Clip the box by the power bisectors of each seed's neighbours (Sutherland-Hodgman).

    sx, sy (S,) m seeds; w (S,) m^2 power weights (0 for Voronoi); nbr_start (S+1,),
    nbr_idx: neighbours of seed s are nbr_idx[nbr_start[s]:nbr_start[s+1]]; box (4,) m;
    eps: vertex-merge distance, m. Writes the counter-clockwise cell of seed s to
    out_xy[s, :out_n[s]] (out_xy (S, MAX_CELL_VERTICES, 2)) and, in out_lab[s, v], what the
    edge from vertex v to vertex v+1 lies on: the neighbour seed index, or -1..-4 for the box
    sides bottom, right, top, left. out_n[s] = -1 on overflow, 0 for an empty cell.
    """
    n_seeds = sx.size
    px = np.empty(MAX_CELL_VERTICES)
    py = np.empty(MAX_CELL_VERTICES)
    pl = np.empty(MAX_CELL_VERTICES, np.int64)
    qx = np.empty(MAX_CELL_VERTICES)
    qy = np.empty(MAX_CELL_VERTICES)
    ql = np.empty(MAX_CELL_VERTICES, np.int64)
    for s in range(n_seeds):
        px[0] = box[0]
        py[0] = box[2]
        px[1] = box[1]
        py[1] = box[2]
        px[2] = box[1]
        py[2] = box[3]
        px[3] = box[0]
        py[3] = box[3]
        pl[0] = -1
        pl[1] = -2
        pl[2] = -3
        pl[3] = -4
        m = 4
        cs = sx[s] * sx[s] + sy[s] * sy[s]
        overflow = False
        for k in range(nbr_start[s], nbr_start[s + 1]):
            j = nbr_idx[k]
            ax = sx[j] - sx[s]
            ay = sy[j] - sy[s]
            b = 0.5 * (sx[j] * sx[j] + sy[j] * sy[j] - cs - w[j] + w[s])
            # keep a.p <= b
            q = 0
            for v in range(m):
                if q + 2 > MAX_CELL_VERTICES:
                    overflow = True
                    break
                u = (v + 1) % m
                fv = ax * px[v] + ay * py[v] - b
                fu = ax * px[u] + ay * py[u] - b
                if fv <= 0.0:
                    qx[q] = px[v]
                    qy[q] = py[v]
                    if fu > 0.0:
                        if fv < 0.0:
                            ql[q] = pl[v]
                            q += 1
                            t = fv / (fv - fu)
                            qx[q] = px[v] + t * (px[u] - px[v])
                            qy[q] = py[v] + t * (py[u] - py[v])
                        ql[q] = j
                    else:
                        ql[q] = pl[v]
                    q += 1
                elif fu < 0.0:
                    t = fv / (fv - fu)
                    qx[q] = px[v] + t * (px[u] - px[v])
                    qy[q] = py[v] + t * (py[u] - py[v])
                    ql[q] = pl[v]
                    q += 1
            if overflow:
                break
            # merge near-duplicate consecutive vertices (the surviving edge keeps its label)
            m = 0
            for v in range(q):
                if m > 0 and abs(qx[v] - px[m - 1]) <= eps and abs(qy[v] - py[m - 1]) <= eps:
                    pl[m - 1] = ql[v]
                    continue
                px[m] = qx[v]
                py[m] = qy[v]
                pl[m] = ql[v]
                m += 1
            while m > 1 and abs(px[m - 1] - px[0]) <= eps and abs(py[m - 1] - py[0]) <= eps:
                m -= 1
            if m < 3:
                m = 0
                break
        if overflow:
            out_n[s] = -1
            continue
        out_n[s] = m
        for v in range(m):
            out_xy[s, v, 0] = px[v]
            out_xy[s, v, 1] = py[v]
            out_lab[s, v] = pl[v]


@njit
def _inside(px, py, xy, a, b):
    """Crossing-number test of point (px, py) in polygon xy[a:b]."""
    c = False
    m = b - a
    for v in range(m):
        x1 = xy[a + v, 0]
        y1 = xy[a + v, 1]
        x2 = xy[a + (v + 1) % m, 0]
        y2 = xy[a + (v + 1) % m, 1]
        if (y1 > py) != (y2 > py):
            xc = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
            if px < xc:
                c = not c
    return c


@njit
def _dist_to_polygon(px, py, xy, a, b):
    m = b - a
    best = np.inf
    for v in range(m):
        w = a + (v + 1) % m
        d = _seg_dist(px, py, xy[a + v, 0], xy[a + v, 1], xy[w, 0], xy[w, 1])
        if d < best:
            best = d
    return best


@njit
def points_in_polygons(x, y, xy, offsets, cell_start, cell_items, x0, y0, h, nx, ny, out):
    """Index of the polygon containing each point (crossing number), -1 if none.

    x, y (N,) m; polygons xy (K, 2), offsets (G+1,); a grid of polygon bounding boxes
    (cell_start (nx*ny+1,), cell_items) with origin (x0, y0) and cell size h. A point outside
    every candidate polygon (on a boundary, within rounding) takes the nearest candidate.
    Writes out (N,) int32.
    """
    for i in range(x.size):
        cx = min(max(int((x[i] - x0) / h), 0), nx - 1)
        cy = min(max(int((y[i] - y0) / h), 0), ny - 1)
        c = cy * nx + cx
        found = -1
        for k in range(cell_start[c], cell_start[c + 1]):
            g = cell_items[k]
            if _inside(x[i], y[i], xy, offsets[g], offsets[g + 1]):
                found = g
                break
        if found < 0:
            best = np.inf
            for k in range(cell_start[c], cell_start[c + 1]):
                g = cell_items[k]
                d = _dist_to_polygon(x[i], y[i], xy, offsets[g], offsets[g + 1])
                if d < best:
                    best = d
                    found = g
        out[i] = found


@njit
def crossing_normals(xi, yi, xj, yj, gi, gj, xy, offsets, nx_out, ny_out, edge_out):
    """Unit normal of the grain-boundary edge crossed by each segment (x_i, y_i)->(x_j, y_j).

    The segment starts in grain gi; the crossed edge is the first edge of gi it meets (else the
    last edge of gj; else the edge of gi nearest the segment midpoint). The normal is oriented so
    that n.(x_j - x_i) > 0. Writes nx_out, ny_out (B,) and edge_out (B,) = vertex index k of the
    edge xy[k] -> next vertex of the same polygon.
    """
    for b in range(xi.size):
        px = xi[b]
        py = yi[b]
        dx = xj[b] - px
        dy = yj[b] - py
        best_t = np.inf
        best_k = -1
        for pas in range(2):
            g = gi[b] if pas == 0 else gj[b]
            a0 = offsets[g]
            m = offsets[g + 1] - a0
            for v in range(m):
                x1 = xy[a0 + v, 0]
                y1 = xy[a0 + v, 1]
                x2 = xy[a0 + (v + 1) % m, 0]
                y2 = xy[a0 + (v + 1) % m, 1]
                ex = x2 - x1
                ey = y2 - y1
                den = dx * ey - dy * ex
                if den == 0.0:
                    continue
                t = ((x1 - px) * ey - (y1 - py) * ex) / den
                u = ((x1 - px) * dy - (y1 - py) * dx) / den
                if 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0:
                    key = t if pas == 0 else 1.0 - t
                    if key < best_t:
                        best_t = key
                        best_k = a0 + v
            if best_k >= 0:
                break
        if best_k < 0:
            g = gi[b]
            a0 = offsets[g]
            m = offsets[g + 1] - a0
            mx = px + 0.5 * dx
            my = py + 0.5 * dy
            best = np.inf
            for v in range(m):
                d = _dist_to_polygon(mx, my, xy, a0 + v, a0 + v + 2) if v < m - 1 else \
                    _seg_dist(mx, my, xy[a0 + v, 0], xy[a0 + v, 1], xy[a0, 0], xy[a0, 1])
                if d < best:
                    best = d
                    best_k = a0 + v
        g = gi[b] if offsets[gi[b]] <= best_k < offsets[gi[b] + 1] else gj[b]
        a0 = offsets[g]
        m = offsets[g + 1] - a0
        v = best_k - a0
        ex = xy[a0 + (v + 1) % m, 0] - xy[best_k, 0]
        ey = xy[a0 + (v + 1) % m, 1] - xy[best_k, 1]
        ll = np.sqrt(ex * ex + ey * ey)
        nx = ey / ll
        ny = -ex / ll
        if nx * dx + ny * dy < 0.0:
            nx = -nx
            ny = -ny
        nx_out[b] = nx
        ny_out[b] = ny
        edge_out[b] = best_k


@njit
def _seg_dist(px, py, x1, y1, x2, y2):
    ex = x2 - x1
    ey = y2 - y1
    ll = ex * ex + ey * ey
    t = 0.0
    if ll > 0:
        t = min(max(((px - x1) * ex + (py - y1) * ey) / ll, 0.0), 1.0)
    dx = x1 + t * ex - px
    dy = y1 + t * ey - py
    return np.sqrt(dx * dx + dy * dy)


@njit
def bbox_grid(xy, offsets, x0, y0, h, nx, ny):
    """Multi-cell grid of polygon bounding boxes -> (cell_start (nx*ny+1,), cell_items)."""
    g_n = offsets.size - 1
    counts = np.zeros(nx * ny, np.int64)
    lo = np.empty((g_n, 4), np.int64)
    for g in range(g_n):
        xmin = np.inf
        xmax = -np.inf
        ymin = np.inf
        ymax = -np.inf
        for k in range(offsets[g], offsets[g + 1]):
            xmin = min(xmin, xy[k, 0])
            xmax = max(xmax, xy[k, 0])
            ymin = min(ymin, xy[k, 1])
            ymax = max(ymax, xy[k, 1])
        lo[g, 0] = min(max(int((xmin - x0) / h), 0), nx - 1)
        lo[g, 1] = min(max(int((xmax - x0) / h), 0), nx - 1)
        lo[g, 2] = min(max(int((ymin - y0) / h), 0), ny - 1)
        lo[g, 3] = min(max(int((ymax - y0) / h), 0), ny - 1)
        if offsets[g + 1] == offsets[g]:
            continue
        for cy in range(lo[g, 2], lo[g, 3] + 1):
            for cx in range(lo[g, 0], lo[g, 1] + 1):
                counts[cy * nx + cx] += 1
    start = np.zeros(nx * ny + 1, np.int64)
    for c in range(nx * ny):
        start[c + 1] = start[c] + counts[c]
    items = np.empty(start[nx * ny], np.int64)
    cur = start[:-1].copy()
    for g in range(g_n):
        if offsets[g + 1] == offsets[g]:
            continue
        for cy in range(lo[g, 2], lo[g, 3] + 1):
            for cx in range(lo[g, 0], lo[g, 1] + 1):
                c = cy * nx + cx
                items[cur[c]] = g
                cur[c] += 1
    return start, items
