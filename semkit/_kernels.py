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


def njit_exact(fn):
    """``numba.njit`` without fastmath: every float operation rounds as NumPy's does, so a
    kernel that fuses NumPy array expressions gives the same bits."""
    return numba.njit(cache=True, nogil=True, error_model="numpy")(fn)


@njit
def pixel_coords(mask):
    """Row and column (int64, raster order) of the nonzero pixels of a 2-D array: what
    ``np.nonzero`` returns, several times faster on a large image.

    Examples
    --------
    >>> m = np.zeros((3, 4), bool); m[1, 2] = m[2, 0] = True
    >>> [a.tolist() for a in pixel_coords(m)]
    [[1, 2], [2, 0]]
    """
    h, w = mask.shape
    n = 0
    for i in range(h):
        for j in range(w):
            if mask[i, j]:
                n += 1
    rr = np.empty(n, np.int64)
    cc = np.empty(n, np.int64)
    k = 0
    for i in range(h):
        for j in range(w):
            if mask[i, j]:
                rr[k] = i
                cc[k] = j
                k += 1
    return rr, cc


@njit
def lookup(table, labels):
    """``table[labels]`` for a 2-D label image: each pixel takes its label's entry (what
    NumPy's fancy indexing gives, about twice as fast on a large image).

    Examples
    --------
    >>> [r.tolist() for r in lookup(np.array([False, True]), np.array([[0, 1], [1, 0]]))]
    [[False, True], [True, False]]
    """
    h, w = labels.shape
    out = np.empty((h, w), table.dtype)
    for i in range(h):
        for j in range(w):
            out[i, j] = table[labels[i, j]]
    return out


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
def thin_pixels(skel, rows, cols, lut1, lut2):
    """Two-subiteration thinning (Lam, Lee & Suen 1992; scikit-image's ``thin``), in place.

    Parameters
    ----------
    skel : (H, W) uint8
        0/1 image, padded so that no foreground pixel touches the border. Thinned in place.
    rows, cols : (K,) int64
        Coordinates of the foreground pixels (only these are visited).
    lut1, lut2 : (256,) bool
        Deletion tables of the two subiterations, indexed by the 8-neighbour code
        (bit 0 = east, then counter-clockwise: NE, N, NW, W, SW, S, SE).

    Returns
    -------
    n_iter : int
        Full iterations done.

    Notes
    -----
    Each subiteration decides on all pixels first and deletes afterwards (parallel thinning).
    Cost is K x iterations (about half the widest crack), independent of the image size.
    """
    k = rows.shape[0]
    act = np.arange(k)
    dele = np.zeros(k, np.bool_)
    n_act = k
    n_iter = 0
    changed = True
    while changed:
        changed = False
        n_iter += 1
        for sub in range(2):
            for q in range(n_act):
                p = act[q]
                i = rows[p]
                j = cols[p]
                n = (skel[i, j + 1] | (skel[i - 1, j + 1] << 1) | (skel[i - 1, j] << 2)
                     | (skel[i - 1, j - 1] << 3) | (skel[i, j - 1] << 4)
                     | (skel[i + 1, j - 1] << 5) | (skel[i + 1, j] << 6)
                     | (skel[i + 1, j + 1] << 7))
                if sub == 0:
                    dele[q] = lut1[n]
                else:
                    dele[q] = lut2[n]
            keep = 0  # delete after deciding (parallel thinning), compact the active list
            for q in range(n_act):
                p = act[q]
                if dele[q]:
                    skel[rows[p], cols[p]] = 0
                    changed = True
                else:
                    act[keep] = p
                    keep += 1
            n_act = keep
    return n_iter


@njit
def chain_links(skel, labels, n_labels, n_straight, n_diag, n_corner):
    """Count chain links and corners of a thin 8-connected skeleton per object, in place.

    Parameters
    ----------
    skel : (H, W) bool
        One-pixel-thin skeleton.
    labels : (H, W) int32
        Object label of each pixel (0 = background); read only where ``skel``.
    n_labels : int
        Number of labels + 1 (length of the output arrays).
    n_straight, n_diag, n_corner : (n_labels,) int64
        Incremented in place: horizontal/vertical neighbour pairs; diagonal pairs that are not
        short-cut corners (a diagonal pair with a common 4-neighbour in the skeleton is
        skipped); and corners (pixels with exactly two links that are not collinear).

    Notes
    -----
    With these rules each staircase is the 8-connected path a chain code would trace, so
    ``n_straight``, ``n_diag``, ``n_corner`` are the even, odd and corner counts of
    Vossepoel & Smeulders (1982).
    """
    h, w = skel.shape
    di = np.array([0, -1, -1, -1, 0, 1, 1, 1])
    dj = np.array([1, 1, 0, -1, -1, -1, 0, 1])
    for i in range(h):
        for j in range(w):
            if not skel[i, j]:
                continue
            lab = labels[i, j]
            nl = 0
            d0 = -1
            d1 = -1
            for d in range(8):
                ii = i + di[d]
                jj = j + dj[d]
                if ii < 0 or ii >= h or jj < 0 or jj >= w or not skel[ii, jj]:
                    continue
                if d % 2 == 1:  # diagonal: skipped when a 4-neighbour path exists
                    ia = i + di[d - 1]
                    ja = j + dj[d - 1]
                    ib = i + di[(d + 1) % 8]
                    jb = j + dj[(d + 1) % 8]
                    if skel[ia, ja] or skel[ib, jb]:
                        continue
                    if d == 7 or d == 5:  # count each diagonal pair once (from its upper pixel)
                        n_diag[lab] += 1
                else:
                    if d == 0 or d == 6:  # count each 4-pair once
                        n_straight[lab] += 1
                if nl == 0:
                    d0 = d
                elif nl == 1:
                    d1 = d
                nl += 1
            if nl == 2 and (d1 - d0) != 4:
                n_corner[lab] += 1


@njit
def _links(skel, i, j, nb_i, nb_j):
    """Effective 8-links of pixel (i, j): 4-neighbours, plus diagonals with no 4-path beside
    them. Writes up to 8 neighbours into nb_i, nb_j; returns their count. Assumes a 1-px
    zero border."""
    di = (0, -1, -1, -1, 0, 1, 1, 1)
    dj = (1, 1, 0, -1, -1, -1, 0, 1)
    n = 0
    for d in range(8):
        ii = i + di[d]
        jj = j + dj[d]
        if not skel[ii, jj]:
            continue
        if d % 2 == 1:
            if skel[i + di[d - 1], j + dj[d - 1]] or skel[i + di[(d + 1) % 8], j + dj[(d + 1) % 8]]:
                continue
        nb_i[n] = ii
        nb_j[n] = jj
        n += 1
    return n


@njit
def prune_spurs(skel, rows, cols, half_width, spur_half_widths, spur_extra_px):
    """Remove spurs (end-to-junction skeleton branches shorter than the local half-width
    rule) in place.

    Parameters
    ----------
    skel : (H, W) uint8
        0/1 thin skeleton with a 1-px zero border; pruned in place.
    rows, cols : (K,) int64
        Skeleton pixel coordinates.
    half_width : (H, W) float32
        Distance transform of the crack mask (local half-width at skeleton pixels), px.
    spur_half_widths, spur_extra_px : float
        A branch from an end point to a junction is a spur when its pixel count is at most
        ``spur_half_widths * half_width[junction] + spur_extra_px``.

    Returns
    -------
    n_removed : int
        Skeleton pixels removed.
    """
    k = rows.shape[0]
    nb_i = np.empty(8, np.int64)
    nb_j = np.empty(8, np.int64)
    path_i = np.empty(4096, np.int64)
    path_j = np.empty(4096, np.int64)
    removed = 0
    for p in range(k):
        i = rows[p]
        j = cols[p]
        if not skel[i, j]:
            continue
        if _links(skel, i, j, nb_i, nb_j) != 1:
            continue
        # walk from the end point until a junction, another end, or too far
        pi, pj = -1, -1
        ci, cj = i, j
        n = 0
        is_spur = False
        while n < 4096:
            path_i[n] = ci
            path_j[n] = cj
            n += 1
            m = _links(skel, ci, cj, nb_i, nb_j)
            if m >= 3:  # reached a junction: (ci, cj) is the junction itself
                n -= 1
                is_spur = n <= spur_half_widths * half_width[ci, cj] + spur_extra_px
                break
            if m == 1 and n > 1:
                break  # an isolated branch (end to end): keep
            nxt = -1
            for q in range(m):
                if nb_i[q] != pi or nb_j[q] != pj:
                    nxt = q
                    break
            if nxt < 0:
                break
            pi, pj = ci, cj
            ci, cj = nb_i[nxt], nb_j[nxt]
            if n > 64:  # no spur is this long
                break
        if is_spur:
            for q in range(n):
                skel[path_i[q], path_j[q]] = 0
            removed += n
    return removed


@njit
def label_counts(labels, out):
    """Pixel count of each label, added to ``out`` (int64, longer than the largest label;
    labels >= 0): ``np.bincount`` without its int64 copy of the image."""
    h, w = labels.shape
    for i in range(h):
        for j in range(w):
            out[labels[i, j]] += 1


@njit
def label_moments(labels, n_labels, out):
    """Raw moments of each label, one pass over the image, in place.

    Parameters
    ----------
    labels : (H, W) int32
    n_labels : int
        Highest label + 1.
    out : (n_labels, 10) float64, zeroed by the caller
        Columns: count, sum x, sum y, sum x², sum y², sum xy, the bounding box's width and
        height, and its first column and row (labels without pixels keep zeros there).
    """
    h, w = labels.shape
    bb = np.empty((n_labels, 4), np.int64)  # xmin, xmax, ymin, ymax
    for k in range(n_labels):
        bb[k, 0] = w
        bb[k, 1] = -1
        bb[k, 2] = h
        bb[k, 3] = -1
    for i in range(h):
        for j in range(w):
            k = labels[i, j]
            if k == 0:
                continue
            out[k, 0] += 1.0
            out[k, 1] += j
            out[k, 2] += i
            out[k, 3] += j * j
            out[k, 4] += i * i
            out[k, 5] += i * j
            if j < bb[k, 0]:
                bb[k, 0] = j
            if j > bb[k, 1]:
                bb[k, 1] = j
            if i < bb[k, 2]:
                bb[k, 2] = i
            if i > bb[k, 3]:
                bb[k, 3] = i
    for k in range(n_labels):
        if bb[k, 1] >= 0:
            out[k, 6] = bb[k, 1] - bb[k, 0] + 1
            out[k, 7] = bb[k, 3] - bb[k, 2] + 1
            out[k, 8] = bb[k, 0]
            out[k, 9] = bb[k, 2]


@njit
def label_extent(labels, n_labels, cos_t, sin_t, pmin, pmax):
    """Min and max of ``x cos_t + y sin_t`` over each label's pixels, in place.

    ``pmin``/``pmax`` (n_labels,) float64 are preset to +inf/-inf by the caller.
    """
    h, w = labels.shape
    for i in range(h):
        for j in range(w):
            k = labels[i, j]
            if k == 0:
                continue
            p = j * cos_t[k] + i * sin_t[k]
            if p < pmin[k]:
                pmin[k] = p
            if p > pmax[k]:
                pmax[k] = p


@njit
def band_owners(labels, di, dj):
    """Pixels near the objects and the object each is nearest to, from the object pixels out.

    Every object pixel stamps its label on the pixels at the offsets ``(di, dj)`` (sorted by
    distance); a pixel keeps the label of the stamp with the smallest offset index, the first
    such stamp in raster order of the object pixels. So an object pixel owns itself and a band
    pixel takes its nearest object; at equal distance the offset listed first decides.

    Parameters
    ----------
    labels : (M, N) int
        Objects 1..n, 0 background.
    di, dj : (K,) int64
        Offsets within the band (K < 255), sorted by length, ``(0, 0)`` first.

    Returns
    -------
    idx : (P,) int64
        Flat indices (raster order) of the pixels within the band of an object.
    owner : (P,) int64
        Their nearest object's label.
    """
    h, w = labels.shape
    k = di.size  # < 255: the offsets of a small disk
    best = np.full((h, w), 255, np.uint8)
    own = np.empty((h, w), np.int32)
    n = 0
    for i in range(h):
        for j in range(w):
            lab = labels[i, j]
            if lab <= 0:
                continue
            for t in range(k):
                a = i + di[t]
                b = j + dj[t]
                if a < 0 or a >= h or b < 0 or b >= w:
                    continue
                if t < best[a, b]:
                    if best[a, b] == 255:
                        n += 1
                    best[a, b] = t
                    own[a, b] = lab
    idx = np.empty(n, np.int64)
    owner = np.empty(n, np.int64)
    m = 0
    for i in range(h):
        for j in range(w):
            if best[i, j] != 255:
                idx[m] = i * w + j
                owner[m] = own[i, j]
                m += 1
    return idx, owner


@njit
def fill_excluded(img, exclude, n_rings, band):
    """Grey under the excluded pixels, filled ring by ring from their known neighbours.

    Ring 1 holds the excluded pixels with a known 8-neighbour, ring r + 1 the unvisited
    excluded neighbours of ring r: the chessboard distance to the known pixels, found by a
    breadth-first search over the excluded pixels (no distance transform, no pixel list).
    Each ring is decided as a whole, then applied: a pixel takes the mean of its known 3 x 3
    neighbours within ``band`` of the darkest of them, so at a phase boundary the rim of a
    crack takes the grey of one phase, never a mix. Each pixel is visited once.

    Parameters
    ----------
    img : (H, W) float32
    exclude : (H, W) bool
    n_rings : int
    band : float

    Returns
    -------
    val : (H, W) float32
        ``img`` with the filled pixels replaced.
    known : (H, W) uint8
        1 where ``val`` holds a grey (known or filled), 0 where still unfilled.
    n_left : int
        Excluded pixels still unfilled after ``n_rings`` rings.
    """
    h, w = img.shape
    out = np.zeros((h + 2, w + 2), np.float32)
    known = np.zeros((h + 2, w + 2), np.uint8)
    k = 0
    for i in range(h):
        for j in range(w):
            out[i + 1, j + 1] = img[i, j]
            if exclude[i, j]:
                k += 1
            else:
                known[i + 1, j + 1] = 1
    seen = known.copy()
    front_r = np.empty(k, np.int64)
    front_c = np.empty(k, np.int64)
    nf = 0
    for i in range(1, h + 1):
        for j in range(1, w + 1):
            if known[i, j]:
                continue
            hit = False
            for di in range(-1, 2):
                for dj in range(-1, 2):
                    if known[i + di, j + dj]:
                        hit = True
            if hit:
                front_r[nf] = i
                front_c[nf] = j
                seen[i, j] = 1
                nf += 1
    next_r = np.empty(k, np.int64)
    next_c = np.empty(k, np.int64)
    newv = np.empty(k, np.float32)
    n_done = 0
    for r in range(1, n_rings + 1):
        if nf == 0:
            break
        for q in range(nf):
            i = front_r[q]
            j = front_c[q]
            newv[q] = np.float32(np.nan)
            m = np.float32(1e30)
            for di in range(-1, 2):
                for dj in range(-1, 2):
                    if known[i + di, j + dj] and out[i + di, j + dj] < m:
                        m = out[i + di, j + dj]
            if m >= 1e30:
                continue
            sm = 0.0
            c = 0
            for di in range(-1, 2):
                for dj in range(-1, 2):
                    if known[i + di, j + dj] and out[i + di, j + dj] <= m + band:
                        sm += out[i + di, j + dj]
                        c += 1
            newv[q] = sm / c
        nn = 0
        for q in range(nf):  # apply after deciding the whole ring (parallel semantics)
            i = front_r[q]
            j = front_c[q]
            if newv[q] == newv[q]:
                out[i, j] = newv[q]
                known[i, j] = 1
                n_done += 1
            if r < n_rings:
                for di in range(-1, 2):
                    for dj in range(-1, 2):
                        ii = i + di
                        jj = j + dj
                        if ii >= 1 and ii <= h and jj >= 1 and jj <= w and not seen[ii, jj]:
                            seen[ii, jj] = 1
                            next_r[nn] = ii
                            next_c[nn] = jj
                            nn += 1
        front_r, next_r = next_r, front_r
        front_c, next_c = next_c, front_c
        nf = nn
    return out[1:-1, 1:-1].copy(), known[1:-1, 1:-1].copy(), k - n_done


@njit
def ridge_strength(dxx, dyy, dxy, gx, gy, s2, ks, out):
    """Dark-ridge strength from Hessian and gradient images, maxed into ``out`` in place.

    Parameters
    ----------
    dxx, dyy, dxy, gx, gy : (M, N) float32
        Second and first derivatives of the Gaussian-smoothed image.
    s2 : float
        sigma^2 (scale normalisation of the Hessian term).
    ks : float
        kappa * sigma (weight of the gradient term).
    out : (M, N) float32
        Running maximum over scales; ``max(out, s2 (l1 - |l2|) - ks |grad|, 0)`` is written.
    """
    h, w = dxx.shape
    for i in range(h):
        for j in range(w):
            a = dxx[i, j]
            b = dyy[i, j]
            c = dxy[i, j]
            half = 0.5 * (a + b)
            disc = math.sqrt(0.25 * (a - b) * (a - b) + c * c)
            l2 = half - disc
            r = s2 * (half + disc - abs(l2)) - ks * math.sqrt(gx[i, j] * gx[i, j]
                                                               + gy[i, j] * gy[i, j])
            if r > out[i, j]:
                out[i, j] = r


@njit_exact
def ridge_levels(a, bg, r, crack_level, noise, high_snr, low_snr, min_depth, low_depth, region,
                 depth, seed, low):
    """Depth below the background and the hysteresis masks of :func:`semkit.ridge.ridge_mask`,
    in one pass (float32 throughout, as the NumPy expressions it replaces).

    Parameters
    ----------
    a, bg, r : (M, N) float32
        Image, local background and ridge response.
    crack_level, noise, high_snr, low_snr, min_depth, low_depth : float32
    region : (M, N) bool
        Sample region (all True for none).
    depth : (M, N) float32
        Receives ``(bg - a) / max(bg - crack_level, 1e-3)``.
    seed, low : (M, N) bool
        Receive ``r / noise > high_snr and depth > min_depth`` and
        ``r / noise > low_snr and depth > low_depth``, inside the region.
    """
    h, w = a.shape
    eps = np.float32(1e-3)
    for i in range(h):
        for j in range(w):
            b = bg[i, j]
            c = b - crack_level
            if not c >= eps:    # np.maximum(c, 1e-3) (c is finite)
                c = eps
            d = (b - a[i, j]) / c
            depth[i, j] = d
            snr = r[i, j] / noise
            inside = region[i, j]
            seed[i, j] = inside and snr > high_snr and d > min_depth
            low[i, j] = inside and snr > low_snr and d > low_depth


@njit_exact
def crack_candidates(img, closed, dark_level, line_min, line_frac, crack_level, out):
    """Pixels that might be crack, as the NumPy expression ``(img < dark_level) | ((line >
    line_min) & (line > line_frac * (closed - crack_level)))`` with ``line = closed - img``.

    The scalars come typed as NumPy would use them against float32 arrays (float32 for a
    Python number, float64 for a float64 scalar), so the comparisons round alike.

    Parameters
    ----------
    img, closed : (M, N) float32
        Image and its grey closing.
    dark_level, line_min, line_frac, crack_level : float32 or float64
    out : (M, N) bool
        Receives the candidates.
    """
    h, w = img.shape
    for i in range(h):
        for j in range(w):
            a = img[i, j]
            c = closed[i, j]
            line = c - a
            out[i, j] = (a < dark_level) or (line > line_min
                                             and line > line_frac * (c - crack_level))


@njit_exact
def partial_volume_sums(labels, sel, near, img, bg, crack_level, rim, out):
    """Partial-volume coverage summed per object over its pixels and a ``rim``-px rim.

    A pixel belongs to its own label when that label is selected, else to the largest
    selected label in the (2 rim + 1)^2 box around it (a grey dilation of the selected
    labels); its coverage is ``clip((bg - img) / max(bg - crack_level, 1e-3), 0, 1)`` in
    float32, added in raster order to ``out`` (float64), as ``np.bincount`` would.

    Parameters
    ----------
    labels : (M, N) int32
    sel : (L,) bool
        Selected labels (``sel[0]`` False; L > every label).
    near : (M, N) uint8
        Nonzero within ``rim`` px of a selected pixel (the only pixels that can count).
    img, bg : (M, N) float32
    crack_level : float32
    rim : int
    out : (L,) float64
        Receives the sums (added to).
    """
    h, w = labels.shape
    eps = np.float32(1e-3)
    zero = np.float32(0.0)
    one = np.float32(1.0)
    for i in range(h):
        for j in range(w):
            if not near[i, j]:
                continue
            v = labels[i, j]
            lab = v if sel[v] else 0
            if lab == 0:
                for a in range(max(i - rim, 0), min(i + rim + 1, h)):
                    for b in range(max(j - rim, 0), min(j + rim + 1, w)):
                        u = labels[a, b]
                        if sel[u] and u > lab:
                            lab = u
            if lab == 0:
                continue
            g = bg[i, j]
            d = g - crack_level
            if not d >= eps:
                d = eps
            c = (g - img[i, j]) / d
            if c < zero:
                c = zero
            elif c > one:
                c = one
            out[lab] += c


@njit
def mixed_area_sums(labels, skel, near, area, img, bg, crack_level, resolved, out, n_pv, n_own):
    """Per-object area: pixel count where the crack core is resolved, partial volume elsewhere.

    Each centreline pixel (``skel``) of an object is *resolved* when a pixel of that object
    in its 3 x 3 box lies at least ``resolved`` of the way from its background to the crack
    grey. Every other pixel of the object and of its 1-px rim (``near``) takes the decision of
    the centreline pixel that reaches it first in a breadth-first search through ``near``
    (its cross-section), so a resolved cross-section is measured whole by its midpoint count
    and a thin one whole by partial volume, with no pixel counted both ways. A resolved
    pixel adds 1 when it is its object's own and in ``area``; an unresolved one adds its
    coverage ``clip((bg - img) / max(bg - crack_level, 1e-3), 0, 1)``. Object pixels that no
    centreline reaches count as resolved.

    Parameters
    ----------
    labels : (M, N) int32
    skel : (M, N) uint8
        Centreline pixels.
    near : (M, N) uint8
        The objects and their 1-px rim.
    area : (M, N) bool
        Pixels past the midpoint.
    img, bg : (M, N) float32
    crack_level, resolved : float32
    out : (L,) float64
        Receives the areas (added to); L > every label.
    n_pv, n_own : (L,) int64
        Receive the object's own pixels measured by partial volume, and all its own pixels.
    """
    h, w = labels.shape
    eps = np.float32(1e-3)
    zero = np.float32(0.0)
    one = np.float32(1.0)
    owner = np.zeros((h, w), np.int32)
    state = np.zeros((h, w), np.int8)  # 0 unreached, 1 resolved, 2 unresolved, -1 outside
    n = 0
    for i in range(h):
        for j in range(w):
            if skel[i, j] and labels[i, j] > 0:
                n += 1
    qr = np.empty(max(n, 1), np.int64)
    qc = np.empty(max(n, 1), np.int64)
    k = 0
    for i in range(h):
        for j in range(w):
            lab = labels[i, j]
            if not (skel[i, j] and lab > 0):
                continue
            core = False
            for a in range(max(i - 1, 0), min(i + 2, h)):
                for b in range(max(j - 1, 0), min(j + 2, w)):
                    if labels[a, b] == lab:
                        d = bg[a, b] - crack_level
                        if not d >= eps:
                            d = eps
                        if (bg[a, b] - img[a, b]) / d >= resolved:
                            core = True
            owner[i, j] = lab
            state[i, j] = 1 if core else 2
            qr[k] = i
            qc[k] = j
            k += 1
    # breadth-first search from the centrelines through the objects and their rims
    head = 0
    tail = k
    cap = k
    while head < tail:
        i = qr[head]
        j = qc[head]
        head += 1
        lab = owner[i, j]
        st0 = state[i, j]
        for a in range(max(i - 1, 0), min(i + 2, h)):
            for b in range(max(j - 1, 0), min(j + 2, w)):
                if state[a, b] != 0:
                    continue
                if not near[a, b]:
                    state[a, b] = -1  # outside: read once, not at every neighbour
                    continue
                v = labels[a, b]
                if v != lab and v != 0:
                    continue
                owner[a, b] = lab
                state[a, b] = st0
                if v == lab:  # rim pixels take a decision but pass none on
                    if tail == cap:
                        cap = 2 * cap + 16
                        nr = np.empty(cap, np.int64)
                        nc = np.empty(cap, np.int64)
                        nr[:tail] = qr[:tail]
                        nc[:tail] = qc[:tail]
                        qr = nr
                        qc = nc
                    qr[tail] = a
                    qc[tail] = b
                    tail += 1
    for i in range(h):
        for j in range(w):
            v = labels[i, j]
            st = state[i, j]
            if st < 0:
                continue
            lab = owner[i, j]
            if st == 0:
                if v == 0:
                    continue
                lab = v
                st = 1
            own = v == lab
            if own:
                n_own[lab] += 1
            if st == 1:
                if own and area[i, j]:
                    out[lab] += 1.0
                continue
            if own:
                n_pv[lab] += 1
            d = bg[i, j] - crack_level
            if not d >= eps:
                d = eps
            c = (bg[i, j] - img[i, j]) / d
            if c < zero:
                c = zero
            elif c > one:
                c = one
            out[lab] += c


@njit
def skeleton_window_sums(skel, aperture, mask, ends, dark, rr, cc, half, out):
    """Sums over the (2 half + 1)^2 box around each skeleton pixel, written in place.

    Parameters
    ----------
    skel : (M, N) uint8
        Skeleton (1) of the crack mask.
    aperture : (M, N) float64
        Aperture at skeleton pixels (anything elsewhere).
    mask : (M, N) uint8
        Crack mask (1).
    ends : (M, N) uint8
        Skeleton end points (1).
    dark : (M, N) float64
        Partial-volume darkness at mask pixels (anything elsewhere).
    rr, cc : (K,) int64
        The skeleton pixels.
    half : int
    out : (K, 11) float64
        Per skeleton pixel: number of skeleton pixels in the box, sums of their dx, dy,
        dx^2, dy^2, dx dy (offsets from the centre pixel, px), of their aperture and squared
        aperture, the number of mask pixels, the number of end points and the summed
        darkness of the mask pixels in the box.

    Notes
    -----
    Checks nothing; the box is clipped at the image edge.
    """
    h, w = skel.shape
    for k in range(rr.shape[0]):
        i, j = rr[k], cc[k]
        s0 = sx = sy = sxx = syy = sxy = sa = saa = sm = se = sd = 0.0
        for di in range(-half, half + 1):
            ii = i + di
            if ii < 0 or ii >= h:
                continue
            for dj in range(-half, half + 1):
                jj = j + dj
                if jj < 0 or jj >= w:
                    continue
                if mask[ii, jj]:
                    sm += 1.0
                    sd += dark[ii, jj]
                if skel[ii, jj]:
                    a = aperture[ii, jj]
                    s0 += 1.0
                    sx += dj
                    sy += di
                    sxx += dj * dj
                    syy += di * di
                    sxy += di * dj
                    sa += a
                    saa += a * a
                    se += ends[ii, jj]
        out[k, 0] = s0
        out[k, 1] = sx
        out[k, 2] = sy
        out[k, 3] = sxx
        out[k, 4] = syy
        out[k, 5] = sxy
        out[k, 6] = sa
        out[k, 7] = saa
        out[k, 8] = sm
        out[k, 9] = se
        out[k, 10] = sd


@njit
def _bilinear(img, y, x):
    """Bilinear grey of ``img`` at ``(y, x)``, the point clamped into the image."""
    h, w = img.shape
    if y < 0.0:
        y = 0.0
    elif y > h - 1.0:
        y = h - 1.0
    if x < 0.0:
        x = 0.0
    elif x > w - 1.0:
        x = w - 1.0
    y0 = min(int(y), h - 2) if h > 1 else 0
    x0 = min(int(x), w - 2) if w > 1 else 0
    fy = y - y0
    fx = x - x0
    y1 = min(y0 + 1, h - 1)
    x1 = min(x0 + 1, w - 1)
    return ((1 - fy) * ((1 - fx) * img[y0, x0] + fx * img[y0, x1])
            + fy * ((1 - fx) * img[y1, x0] + fx * img[y1, x1]))


@njit
def cross_section_valleys(img, bg, labels, skel, rr, cc, crack_level, depth, rise, min_half,
                          max_reach, along, min_rise_grey, out):
    """Resolved parallel traces across each centreline pixel of an object.

    At centreline pixel ``(rr[k], cc[k])`` the line's direction is the principal axis of the
    object's centreline pixels in the 7 x 7 box around it; along the normal the object's
    extent is walked on each side (0.5-px steps, at most ``max_reach``), and the grey is
    sampled (bilinear, 0.5-px steps) from 1.5 px beyond one side to 1.5 px beyond the other,
    each sample the mean of ``2 * int(along) + 1`` points 1 px apart along the line.
    With ``d = (bg - grey) / (bg - crack_level)`` (``bg`` at the centreline pixel), a
    *valley* is a local maximum of ``d`` at least ``depth``; two valleys count apart when
    ``d`` between them falls ``rise`` x the shallower one's ``d`` below it, and by at least
    ``min_rise_grey`` in grey, else the deeper stands for both. Cross-sections of
    half-width under ``min_half`` (one thin trace) read 1.

    Parameters
    ----------
    img, bg : (M, N) float32
    labels : (M, N) int32
    skel : (M, N) bool
        The centreline pixels.
    rr, cc : (K,) int64
        The centreline pixels to read (all inside labelled objects).
    crack_level, depth, rise, min_half, max_reach, along, min_rise_grey : float
    out : (K,) int32
        Receives the number of valleys (at least 1).
    """
    h, w = img.shape
    nmax = int(4 * (max_reach + 2.0)) + 3
    n_along = int(along)
    d = np.empty(nmax, np.float32)
    keep = np.empty(nmax, np.int64)
    for k in range(rr.size):
        i = rr[k]
        j = cc[k]
        lab = labels[i, j]
        out[k] = 1
        # direction: principal axis of the centreline pixels nearby (one pass: raw moments
        # of the offsets from (i, j), small integers, so the centring loses nothing)
        n = 0
        sx = 0.0
        sy = 0.0
        sxx = 0.0
        syy = 0.0
        sxy = 0.0
        for a in range(max(i - 3, 0), min(i + 4, h)):
            for b in range(max(j - 3, 0), min(j + 4, w)):
                if skel[a, b] and labels[a, b] == lab:
                    dx = float(b - j)
                    dy = float(a - i)
                    n += 1
                    sx += dx
                    sy += dy
                    sxx += dx * dx
                    syy += dy * dy
                    sxy += dx * dy
        if n < 3:
            continue
        cxx = sxx - sx * sx / n
        cyy = syy - sy * sy / n
        cxy = sxy - sx * sy / n
        th = 0.5 * math.atan2(2.0 * cxy, cxx - cyy)
        nx = -math.sin(th)
        ny = math.cos(th)
        nx_t = math.cos(th)  # along the line: the grey is averaged over 2 * n_along + 1 px
        ny_t = math.sin(th)
        # the object's extent along the normal, each side
        e_pos = 0.0
        e_neg = 0.0
        for s in range(2):
            sg = 1.0 if s == 0 else -1.0
            t = 0.5
            while t <= max_reach:
                y = int(round(i + sg * t * ny))
                x = int(round(j + sg * t * nx))
                if y < 0 or y >= h or x < 0 or x >= w or labels[y, x] != lab:
                    break
                t += 0.5
            if s == 0:
                e_pos = t - 0.5
            else:
                e_neg = t - 0.5
        if 0.5 * (e_pos + e_neg) < min_half:
            continue
        g0 = bg[i, j]
        den = g0 - crack_level
        if not den >= 1e-3:
            den = 1e-3
        m = 0
        t = -(e_neg + 1.5)
        while t <= e_pos + 1.5 + 1e-9 and m < nmax:
            y = i + t * ny
            x = j + t * nx
            v = 0.0
            for u in range(-n_along, n_along + 1):
                v += _bilinear(img, y + u * ny_t, x + u * nx_t)
            d[m] = (g0 - v / (2 * n_along + 1)) / den
            m += 1
            t += 0.5
        nk = 0
        for q in range(1, m - 1):
            if d[q] > d[q - 1] and d[q] >= d[q + 1] and d[q] >= depth:
                if nk == 0:
                    keep[0] = q
                    nk = 1
                    continue
                p = keep[nk - 1]
                low = d[p]
                for u in range(p, q + 1):
                    if d[u] < low:
                        low = d[u]
                shallow = min(d[p], d[q])
                if shallow - low >= rise * shallow and shallow - low >= min_rise_grey / den:
                    keep[nk] = q
                    nk += 1
                elif d[q] > d[p]:
                    keep[nk - 1] = q
        if nk > 1:
            out[k] = nk


@njit
def tip_reach(skel, labels, rr, cc, back_px, max_radius, out):
    """How far each skeleton end's object reaches beyond the circle inscribed at the end.

    At end pixel ``(rr[k], cc[k])`` the direction is the chord from the skeleton pixel
    ``back_px`` links back along the branch (:func:`_links`; fewer where a junction comes
    first; none, and ``out[k] = 0``, under 2) to the end. Along it the object (same label) is
    sampled in 0.25-px steps to its edge: reach ``t`` (to within 0.125 px). The inscribed
    radius ``r`` is the distance to the nearest pixel outside the object, less half a pixel
    (at most ``max_radius``).
    ``out[k] = max(t - r + 0.5, 0)``: the half of the end pixel the chain code leaves out, and
    the stretch of object the skeleton stops short of beyond the inscribed circle (none at a
    round or flat end, which the circle touches). An end whose object runs into the image
    border gets ``out[k] = t``: the crack goes on beyond the frame.

    Parameters
    ----------
    skel : (M + 2, N + 2) uint8
        0/1 thin skeleton with a 1-px zero border (as :func:`prune_spurs` takes it).
    labels : (M, N) int32
    rr, cc : (K,) int64
        The skeleton's end pixels, in ``labels``' coordinates.
    back_px : int
    max_radius : float
    out : (K,) float64
    """
    h, w = labels.shape
    nb_i = np.empty(8, np.int64)
    nb_j = np.empty(8, np.int64)
    rad = int(max_radius) + 1
    for k in range(rr.size):
        i0 = rr[k]
        j0 = cc[k]
        lab = labels[i0, j0]
        out[k] = 0.0
        # walk back along the branch (padded coordinates) while it runs on as one path
        pi, pj = -1, -1
        ci, cj = i0 + 1, j0 + 1
        n = 0
        while n < back_px:
            m = _links(skel, ci, cj, nb_i, nb_j)
            if m != (1 if n == 0 else 2):
                break
            q = 0 if nb_i[0] != pi or nb_j[0] != pj else 1
            pi, pj = ci, cj
            ci, cj = nb_i[q], nb_j[q]
            n += 1
        if n < 2:
            continue
        vy = float(i0 + 1 - ci)
        vx = float(j0 + 1 - cj)
        nv = math.sqrt(vy * vy + vx * vx)
        vy /= nv
        vx /= nv
        t = 0.125  # samples between pixel edges: no sample rounds on an edge
        framed = False
        while True:
            y = int(math.floor(i0 + t * vy + 0.5))
            x = int(math.floor(j0 + t * vx + 0.5))
            if y < 0 or y >= h or x < 0 or x >= w:
                framed = True
                break
            if labels[y, x] != lab:
                break
            t += 0.25
        reach = t - 0.125
        if framed:  # the crack runs on beyond the frame: its length here ends at the edge
            out[k] = reach
            continue
        r2 = max_radius * max_radius + max_radius + 0.25
        for a in range(max(i0 - rad, 0), min(i0 + rad + 1, h)):
            for b in range(max(j0 - rad, 0), min(j0 + rad + 1, w)):
                if labels[a, b] != lab:
                    d2 = float((a - i0) * (a - i0) + (b - j0) * (b - j0))
                    if d2 < r2:
                        r2 = d2
        r = min(math.sqrt(r2) - 0.5, max_radius)
        out[k] = max(reach - r + 0.5, 0.0)
