"""Seeded synthetic BSE-like SEM images of cracked rock, with exact ground truth.

The image is built from a Voronoi grain map (2-3 minerals with distinct grey levels), faint grain
boundaries (not cracks), grain texture, dark cracks drawn from known centrelines with partial-
volume edges, isolated dark speckles, optional pores, a Gaussian point-spread blur, an optional
smooth illumination gradient and detector noise. Everything random comes from one ``seed``.

Ground truth (see :class:`SynthImage`): the crack mask is the set of pixels whose centre lies
within half the local width of a crack centreline (partial-volume coverage >= 0.5); the length
of a crack is the length of its path (main centreline plus branches). A shear crack is drawn as
en-echelon steps or two thin layers along that path; the total length of everything drawn is
``trace_length_px`` (equal to ``length_px`` for pre-test and tensile cracks).

Run ``python -m semkit.synth OUT_DIR`` to (re)write the bundled ``sample_images/`` set.
"""
from __future__ import annotations

import dataclasses
import math
import pathlib
import sys

import numpy as np
import pandas as pd
from scipy import ndimage as ndi
from scipy.spatial import Voronoi, cKDTree

from . import _kernels

__all__ = ["SynthImage", "make_sem_image", "write_sample_set", "MINERALS"]

#: default minerals: name, BSE grey level (8-bit scale), volume share (REFERENCE.md).
MINERALS = (("pyroxene", 200.0, 0.5), ("plagioclase", 100.0, 0.3), ("biotite", 150.0, 0.2))
CRACK_GREY = 30.0
PRE_TYPES = (("inter", 0.37), ("intra", 0.36), ("trans", 0.27))
POST_TYPES = (("tensile", 0.53), ("shear", 0.29), ("mixed", 0.18))


@dataclasses.dataclass
class SynthImage:
    """A synthetic SEM image and its ground truth.

    Notation: H x W pixels, C cracks (ids 1..C), G grains (ids 1..G), M minerals.

    Attributes
    ----------
    image : (H, W) ndarray of uint8 or uint16
        The grey image (cracks dark).
    crack_mask : (H, W) ndarray of bool
        True crack pixels (centre within half the local width of a centreline, or debris).
    crack_labels : (H, W) ndarray of int32
        Crack id per pixel, 0 = none (where cracks overlap, the first drawn keeps the pixel).
    grain_labels : (H, W) ndarray of int32
        Grain id per pixel, 1..G (the polygonal grains, cracks ignored).
    mineral_labels : (H, W) ndarray of int32
        Mineral index per pixel, 0..M-1, into ``mineral_names``.
    pixel_size_um : float
        Pixel size, µm.
    cracks : DataFrame
        One row per crack: ``crack_id, type_pre`` (inter|intra|trans), ``type_post``
        (tensile|shear|mixed, or unknown for ``stage="pre"``), ``area_px`` (pixel count of the
        mask), ``area_cov_px`` (partial-volume area: sum of the anti-aliased coverage; for
        1-px cracks the physically meaningful area), ``length_px`` (path length: main centreline +
        branches), ``trace_length_px`` (all drawn traces: layers and overlapping en-echelon
        steps count each), ``width_px`` (nominal width), ``n_traces, n_branches,
        debris_px, n_grains, orientation_deg``.
    grains : DataFrame
        One row per grain: ``grain_id, mineral`` (name), ``mineral_idx, area_px, eq_diameter_px``.
    mineral_names : tuple of str
    stage : str
        ``"pre"`` or ``"post"``.
    seed : int or None
    illumination : (H, W) ndarray of float32
        Multiplicative illumination field (1 = full brightness).
    speckle_mask, pore_mask, boundary_mask, lens_mask : (H, W) ndarray of bool
        Where the isolated speckles, the pores, the (faint) grain boundaries and the dark
        lenses are.
    traces : list of list of (K, 3) ndarray
        Per crack, the polylines drawn (columns x, y, width; px).
    """

    image: np.ndarray
    crack_mask: np.ndarray
    crack_labels: np.ndarray
    grain_labels: np.ndarray
    mineral_labels: np.ndarray
    pixel_size_um: float
    cracks: pd.DataFrame
    grains: pd.DataFrame
    mineral_names: tuple
    stage: str
    seed: int | None
    illumination: np.ndarray
    speckle_mask: np.ndarray
    pore_mask: np.ndarray
    boundary_mask: np.ndarray
    traces: list
    lens_mask: np.ndarray

    @property
    def crack_area_px(self) -> int:
        """Total true crack area, px."""
        return int(self.crack_mask.sum())

    @property
    def crack_length_px(self) -> float:
        """Total true centreline length, px."""
        return float(self.cracks["length_px"].sum())


# --------------------------------------------------------------------------- grains
def _grain_map(shape, mean_grain_px, rng):
    h, w = shape
    margin = 2.0 * mean_grain_px
    area = (h + 2 * margin) * (w + 2 * margin)
    n = max(int(area / (0.9 * mean_grain_px ** 2)), 4)
    seeds = np.column_stack([rng.uniform(-margin, w + margin, n),
                             rng.uniform(-margin, h + margin, n)])
    yy, xx = np.mgrid[0:h, 0:w]
    tree = cKDTree(seeds)
    _, idx = tree.query(np.column_stack([xx.ravel(), yy.ravel()]).astype(np.float64), workers=-1)
    idx = idx.reshape(h, w)
    present, inv = np.unique(idx, return_inverse=True)
    labels = (inv.reshape(h, w) + 1).astype(np.int32)
    return labels, seeds, present


def _boundary_mask(labels):
    b = np.zeros(labels.shape, bool)
    dx = labels[:, 1:] != labels[:, :-1]
    dy = labels[1:, :] != labels[:-1, :]
    b[:, 1:] |= dx
    b[:, :-1] |= dx
    b[1:, :] |= dy
    b[:-1, :] |= dy
    return b


def _resample(pts, step=2.0):
    """Resample a polyline (K, 2) at about ``step`` px spacing, keeping the end points."""
    seg = np.hypot(*np.diff(pts, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        return pts[:1].copy()
    n = max(int(math.ceil(s[-1] / step)), 1)
    t = np.linspace(0.0, s[-1], n + 1)
    return np.column_stack([np.interp(t, s, pts[:, 0]), np.interp(t, s, pts[:, 1])])


def _polylen(pts):
    return float(np.hypot(*np.diff(pts[:, :2], axis=0).T).sum()) if len(pts) > 1 else 0.0


def _smooth_noise(n, rng, corr):
    """A smooth 1-D random sequence with unit std and correlation length ``corr`` samples."""
    x = rng.standard_normal(n + 4 * int(corr) + 4)
    x = ndi.gaussian_filter1d(x, max(corr, 0.5))
    x = x[2 * int(corr) + 2: 2 * int(corr) + 2 + n]
    # std of Gaussian-filtered white noise (not the sample std: short runs would blow up)
    return x * math.sqrt(2.0 * math.sqrt(math.pi) * max(corr, 0.5))


# --------------------------------------------------------------------------- centrelines
def _walk(start, angle, length, curvature, rng, inside):
    """Random-walk centreline from ``start``; stops at ``length`` or when ``inside`` fails."""
    pts = [np.asarray(start, float)]
    step = 2.0
    turn = _smooth_noise(int(length / step) + 2, rng, 6.0) * curvature
    for k in range(int(length / step)):
        angle += turn[k]
        p = pts[-1] + step * np.array([math.cos(angle), math.sin(angle)])
        if not inside(p):
            break
        pts.append(p)
    return np.array(pts)


def _inter_path(vor, shape, margin, rng, n_edges):
    """A path along Voronoi edges (grain boundaries), as vertex coordinates."""
    h, w = shape
    v = vor.vertices
    ok = (v[:, 0] > margin) & (v[:, 0] < w - margin) & (v[:, 1] > margin) & (v[:, 1] < h - margin)
    adj = {}
    for a, b in vor.ridge_vertices:
        if a < 0 or b < 0 or not (ok[a] and ok[b]):
            continue
        adj.setdefault(a, []).append(b)
        adj.setdefault(b, []).append(a)
    if not adj:
        return None
    keys = np.array(sorted(adj))
    cur = int(rng.choice(keys))
    path = [cur]
    prev_dir = None
    for _ in range(n_edges):
        cand = [c for c in adj[cur] if c not in path]
        if not cand:
            break
        if prev_dir is None:
            nxt = int(rng.choice(cand))
        else:  # prefer going straight on, as a crack would
            d = [(v[c] - v[cur]) / max(np.hypot(*(v[c] - v[cur])), 1e-9) for c in cand]
            score = np.array([np.dot(prev_dir, di) for di in d])
            nxt = cand[int(np.argmax(score + 0.3 * rng.standard_normal(len(cand))))]
        prev_dir = (v[nxt] - v[cur]) / max(np.hypot(*(v[nxt] - v[cur])), 1e-9)
        path.append(nxt)
        cur = nxt
    if len(path) < 2:
        return None
    return v[path]


def _grains_on(pts, grain_labels):
    h, w = grain_labels.shape
    ij = np.round(pts[:, ::-1]).astype(int)
    ij[:, 0] = np.clip(ij[:, 0], 0, h - 1)
    ij[:, 1] = np.clip(ij[:, 1], 0, w - 1)
    return set(np.unique(grain_labels[ij[:, 0], ij[:, 1]]).tolist())


# --------------------------------------------------------------------------- morphologies
def _with_width(pts, width, rng, variation):
    pts = _resample(pts)
    wv = width * (1.0 + variation * _smooth_noise(len(pts), rng, 8.0))
    return np.column_stack([pts, np.clip(wv, 0.8 * min(width, 1.0), None)])


def _normals(pts):
    d = np.gradient(pts, axis=0)
    n = np.column_stack([-d[:, 1], d[:, 0]])
    return n / np.maximum(np.hypot(n[:, 0], n[:, 1]), 1e-9)[:, None]


def _shear_traces(pts, rng):
    """Narrow en-echelon pieces, or two parallel layered traces, plus debris blobs."""
    pts = _resample(pts)
    nrm = _normals(pts)
    traces = []
    if rng.random() < 0.5 or len(pts) < 12:  # en echelon
        i = 0
        sign = 1.0
        while i < len(pts) - 2:
            n_seg = int(rng.integers(8, 18))
            j = min(i + n_seg + 2, len(pts))  # +2: overlapping steps
            off = sign * rng.uniform(1.2, 2.5)
            piece = pts[i:j] + off * nrm[i:j]
            wv = rng.uniform(1.0, 2.2)
            traces.append(np.column_stack([piece, np.full(len(piece), wv)]))
            sign = -sign
            i = j - 2
    else:  # layered: two thin parallel traces
        gap = rng.uniform(2.0, 3.0)
        for s in (-1.0, 1.0):
            piece = pts + s * gap * nrm
            traces.append(np.column_stack([piece, np.full(len(piece), rng.uniform(1.0, 1.8))]))
    debris = []
    n_deb = max(int(_polylen(pts) / 14.0), 1)
    for _ in range(n_deb):
        k = int(rng.integers(0, len(pts)))
        off = rng.choice([-1.0, 1.0]) * rng.uniform(4.0, 7.0)
        c = pts[k] + off * nrm[k]
        debris.append(np.array([[c[0], c[1], rng.uniform(1.6, 3.0)]]))
    return traces, debris


def _satellite(path, traces, rng):
    """A thin trace parallel to ``path`` 1-4 px beyond the outer wall of the traces drawn
    along it (a tensile opening, steps or layers), over 40-80 % of its length; None where
    the path is too short."""
    pts = _resample(path)
    if len(pts) < 12:
        return None
    tree = cKDTree(_resample(path, 0.5))
    half = 0.0
    for t in traces:
        d = tree.query(t[:, :2])[0]
        if np.median(d) < 6.0:  # drawn along this path (not a branch or another path)
            half = max(half, float(np.max(d + t[:, 2] / 2)))
    nrm = _normals(pts)
    n = len(pts)
    run = int(n * rng.uniform(0.4, 0.8))
    a = int(rng.integers(0, n - run + 1))
    wv = rng.uniform(0.9, 1.6)
    off = rng.choice([-1.0, 1.0]) * (half + rng.uniform(1.0, 4.0) + wv / 2)
    piece = pts[a:a + run] + off * nrm[a:a + run]
    return np.column_stack([piece, np.full(len(piece), wv)])


def _lens(c, rng):
    """A lens-shaped grain at ``c`` (8-40 px long, aspect 2-6, pointed at both ends) as a
    (K, 3) polyline of widths."""
    length = rng.uniform(8.0, 40.0)
    width = max(length / rng.uniform(2.0, 6.0), 2.0)
    ang = rng.uniform(0, math.pi)
    u = np.array([math.cos(ang), math.sin(ang)])
    s = np.linspace(-0.5, 0.5, max(int(length / 2), 3))
    wv = np.maximum(width * np.sqrt(np.clip(1.0 - (2.0 * s) ** 2, 0.0, 1.0)), 0.6)
    return np.column_stack([c + np.outer(s * length, u), wv])


def _place_isolated(n, crack_labels, margin, rng, shape):
    """``n`` dark objects, each the polyline ``shape(centre)`` at a random centre, kept 4 px
    clear of the cracks (a centre is redrawn up to 4 n times) -> (mask, coverage)."""
    h, w = crack_labels.shape
    mask = np.zeros((h, w), bool)
    cov = np.zeros((h, w), np.float32)
    placed = 0
    for _ in range(4 * n):
        if placed >= n:
            break
        c = np.array([rng.uniform(margin, w - margin), rng.uniform(margin, h - margin)])
        ex, (y0, x0) = _render_traces([shape(c)], (h, w))
        win = (slice(y0, y0 + ex.shape[0]), slice(x0, x0 + ex.shape[1]))
        near = ndi.binary_dilation(crack_labels[win] > 0, iterations=4)
        if (near & (ex <= 2)).any():
            continue
        mask[win] |= ex <= 0
        np.maximum(cov[win], np.clip(0.5 - ex, 0.0, 1.0), out=cov[win])
        placed += 1
    return mask, cov


def _render_traces(traces, shape):
    """Excess field of a set of traces over their joint bounding box -> (excess, (y0, x0))."""
    h, w = shape
    allp = np.vstack(traces)
    r = allp[:, 2].max() / 2 + 3
    x0 = max(int(allp[:, 0].min() - r), 0)
    x1 = min(int(allp[:, 0].max() + r) + 1, w)
    y0 = max(int(allp[:, 1].min() - r), 0)
    y1 = min(int(allp[:, 1].max() + r) + 1, h)
    out = np.full((max(y1 - y0, 1), max(x1 - x0, 1)), np.float32(1e9), np.float32)
    for t in traces:
        t = np.ascontiguousarray(t, np.float64)
        _kernels.polyline_excess(t[:, 0].copy(), t[:, 1].copy(), t[:, 2].copy(), x0, y0, out)
    return out, (y0, x0)


# --------------------------------------------------------------------------- main entry
def make_sem_image(shape=(768, 1024), *, stage="pre", n_cracks=None, widths=(1.0, 8.0),
                   mean_grain_px=None, minerals=MINERALS, gradient=1.0, n_speckles=None,
                   n_pores=0, noise_sigma=5.0, blur_sigma=0.6, boundary_depth=0.12,
                   pixel_size_um=1.43, bit_depth=8, type_mix=None, max_overlap=0.05,
                   crack_grey=CRACK_GREY, satellite=0.0, n_lenses=0,
                   seed=None) -> SynthImage:
    """Make a synthetic BSE-like SEM image of cracked rock with exact ground truth.

    Parameters
    ----------
    shape : (int, int)
        Image rows, columns (H, W).
    stage : {"pre", "post"}
        ``"pre"``: pre-existing cracks, smooth openings, ``type_post = "unknown"``.
        ``"post"``: loading cracks rendered by ``type_post``: tensile = clean opening of
        smooth, near-uniform width with matching walls; shear = narrow en-echelon or layered
        trace with small debris fragments alongside; mixed = segments of both along one crack.
    n_cracks : int, optional
        Number of cracks; default about one per 25 000 px.
    widths : (float, float)
        Range of nominal crack widths, px (1-8 in the issue).
    mean_grain_px : float, optional
        Mean grain spacing, px; default ``min(shape) / 8``.
    minerals : sequence of (name, grey, share)
        Mineral name, grey level on the 8-bit scale and area share.
    gradient : float
        Illumination ratio between the brightest and the darkest side (1 = uniform; 2.5 =
        2.5x darker on one side); direction drawn from the seed.
    n_speckles : int, optional
        Isolated dark specks (1-3 px); default one per 10 000 px.
    n_pores : int
        Round dark pores (radius 3-9 px); they are not cracks.
    crack_grey : float
        Grey of the crack void (8-bit scale; jittered by 3 per image): 30, a void or dark
        epoxy in BSE; lighter for epoxy-filled cracks.
    noise_sigma : float
        Detector noise, grey levels (8-bit scale).
    blur_sigma : float
        Point-spread Gaussian sigma, px.
    boundary_depth : float
        Relative darkening of grain boundaries (faint: far above the crack grey).
    pixel_size_um : float
    bit_depth : {8, 16}
    type_mix : sequence of (name, share), optional
        Crack-type shares; default thesis shares (pre: inter/intra/trans 37/36/27 %, post:
        tensile/shear/mixed 53/29/18 %).
    max_overlap : float
        A new crack is redrawn when more than this share of its pixels already belong to
        other cracks (crossings are allowed; running along another crack is not).
    satellite : float
        ``stage="post"`` only: the chance that a crack path (of 24 px or more) carries a
        satellite, a thin (0.9-1.6 px) parallel trace 1-4 px from the crack's wall over
        40-80 % of the path (a second microcrack of a crack array, or a layer of a layered
        shear crack). The
        satellite belongs to its crack: it counts in ``area_cov_px``, ``trace_length_px``
        and ``n_traces``.
    n_lenses : int
        Dark lens-shaped grains (organic matter or void-filled lenses, 8-40 px long, aspect
        2-6) as dark as the cracks (crack grey + 0-20); they are not cracks
        (``lens_mask``).
    seed : int, optional
        Same seed -> identical output.

    Returns
    -------
    synth : SynthImage

    Examples
    --------
    >>> s = make_sem_image((96, 128), n_cracks=2, widths=(3, 4), seed=1)
    >>> s.image.shape, s.image.dtype.name, len(s.cracks)
    ((96, 128), 'uint8', 2)
    """
    if stage not in ("pre", "post"):
        raise ValueError(f"stage: expected 'pre' or 'post', got {stage!r}")
    if bit_depth not in (8, 16):
        raise ValueError(f"bit_depth: expected 8 or 16, got {bit_depth!r}")
    h, w = (int(shape[0]), int(shape[1]))
    if h < 32 or w < 32:
        raise ValueError(f"shape: expected at least 32 x 32, got {shape}")
    rng = np.random.default_rng(seed)
    # the optional scene elements draw from their own stream: without them an image is
    # bit-identical to one made before they existed
    extra = np.random.default_rng(None if seed is None else [int(seed), 7])
    mean_grain_px = float(mean_grain_px or min(h, w) / 8.0)
    n_cracks = int(n_cracks if n_cracks is not None else max(h * w // 25000, 3))
    n_speckles = int(n_speckles if n_speckles is not None else h * w // 10000)

    # grains and minerals
    grain_labels, seeds, present = _grain_map((h, w), mean_grain_px, rng)
    n_grains = int(grain_labels.max())
    names = tuple(m[0] for m in minerals)
    greys = np.array([m[1] for m in minerals], float)
    share = np.array([m[2] for m in minerals], float)
    grain_mineral = rng.choice(len(minerals), size=n_grains + 1,
                               p=share / share.sum()).astype(np.int32)
    grain_mineral[0] = 0
    mineral_labels = grain_mineral[grain_labels]
    boundary = _boundary_mask(grain_labels)
    dist_b = ndi.distance_transform_edt(~boundary)
    vor = Voronoi(seeds)

    # cracks
    if type_mix is None:
        type_mix = PRE_TYPES if stage == "pre" else POST_TYPES
    tnames = [t[0] for t in type_mix]
    tp = np.array([t[1] for t in type_mix], float)
    margin = 6.0 + widths[1]

    def inside_img(p):
        return margin <= p[0] <= w - 1 - margin and margin <= p[1] <= h - 1 - margin

    crack_labels = np.zeros((h, w), np.int32)
    cover = np.zeros((h, w), np.float32)
    rows, all_traces = [], []
    cid = 0
    attempts = 0
    while cid < n_cracks and attempts < 50 * n_cracks:
        attempts += 1
        width = float(rng.uniform(*widths))
        ttype = tnames[int(rng.choice(len(tnames), p=tp / tp.sum()))]
        if stage == "pre":
            type_pre, type_post = ttype, "unknown"
        else:
            type_post = ttype
            type_pre = PRE_TYPES[int(rng.choice(3, p=[0.37, 0.36, 0.27]))][0]
        # centreline(s) by pre type
        mains, n_branches = [], 0
        if type_pre == "inter":
            path = _inter_path(vor, (h, w), margin, rng, int(rng.integers(2, 6)))
            if path is None or _polylen(path) < 20:
                continue
            mains.append(path)
        elif type_pre == "intra":
            cand = np.flatnonzero(dist_b.ravel() > width / 2 + 8)
            if cand.size == 0:
                continue
            p0 = np.array(np.unravel_index(int(rng.choice(cand)), (h, w))[::-1], float)
            g0 = grain_labels[int(p0[1]), int(p0[0])]

            def inside_grain(p, g0=g0, width=width):
                if not inside_img(p):
                    return False
                i, j = int(round(p[1])), int(round(p[0]))
                return grain_labels[i, j] == g0 and dist_b[i, j] > width / 2 + 2

            ang = rng.uniform(0, 2 * math.pi)
            ln = rng.uniform(0.4, 1.2) * mean_grain_px
            a = _walk(p0, ang, ln / 2, 0.015, rng, inside_grain)
            b = _walk(p0, ang + math.pi, ln / 2, 0.015, rng, inside_grain)
            path = np.vstack([b[::-1], a[1:]])
            if _polylen(path) < 15:
                continue
            mains.append(path)
        else:  # trans
            p0 = np.array([rng.uniform(margin, w - margin), rng.uniform(margin, h - margin)])
            ang = rng.uniform(0, 2 * math.pi)
            ln = rng.uniform(0.25, 0.6) * min(h, w)
            a = _walk(p0, ang, ln / 2, 0.015, rng, inside_img)
            b = _walk(p0, ang + math.pi, ln / 2, 0.015, rng, inside_img)
            path = np.vstack([b[::-1], a[1:]])
            if _polylen(path) < 30 or len(_grains_on(_resample(path, 1.0), grain_labels)) < 2:
                continue
            mains.append(path)
            if rng.random() < 0.4:  # a branch
                rp = _resample(path)
                k = int(rng.integers(len(rp) // 3, max(2 * len(rp) // 3, len(rp) // 3 + 1)))
                d = rp[min(k + 1, len(rp) - 1)] - rp[max(k - 1, 0)]
                ang_b = math.atan2(d[1], d[0]) + rng.choice([-1, 1]) * rng.uniform(0.45, 1.0)
                br = _walk(rp[k], ang_b, rng.uniform(0.2, 0.5) * _polylen(path), 0.015, rng,
                           inside_img)
                if _polylen(br) >= 15:
                    mains.append(br)
                    n_branches = 1
        # morphology
        traces, debris = [], []
        for m in mains:
            if stage == "pre" or type_post == "tensile":
                traces.append(_with_width(m, width, rng, 0.08 if type_post == "tensile" else 0.15))
            elif type_post == "shear":
                t, d = _shear_traces(m, rng)
                traces += t
                debris += d
            else:  # mixed: alternate tensile and shear segments along the crack
                rp = _resample(m)
                n_part = int(rng.integers(2, 5))
                cuts = np.linspace(0, len(rp) - 1, n_part + 1).astype(int)
                first_shear = rng.random() < 0.5
                for q in range(n_part):
                    seg = rp[cuts[q]: cuts[q + 1] + 1]
                    if len(seg) < 3:
                        continue
                    if (q % 2 == 1) == first_shear:
                        traces.append(_with_width(seg, max(width, 2.5), rng, 0.08))
                    else:
                        t, d = _shear_traces(seg, rng)
                        traces += t
                        debris += d
        if stage == "post" and satellite > 0:
            sats = [_satellite(m, traces, extra) for m in mains if extra.random() < satellite]
            traces += [t for t in sats if t is not None]
        if not traces:
            continue
        ex, (y0, x0) = _render_traces(traces + debris, (h, w))
        win = (slice(y0, y0 + ex.shape[0]), slice(x0, x0 + ex.shape[1]))
        inside = ex <= 0
        taken = inside & (crack_labels[win] > 0)
        if taken.sum() > max_overlap * inside.sum():
            continue  # cracks may cross but not run along each other (ambiguous truth)
        cid += 1
        free = inside & ~taken
        crack_labels[win][free] = cid
        np.maximum(cover[win], np.clip(0.5 - ex, 0.0, 1.0), out=cover[win])
        debris_px = 0
        if debris:
            exd, _ = _render_traces(debris, (h, w))
            debris_px = int((exd <= 0).sum())
        area_cov = float(np.clip(0.5 - ex, 0.0, 1.0).sum())
        length = sum(_polylen(m) for m in mains)       # the crack's path (main + branches)
        trace_length = sum(_polylen(t) for t in traces)  # every drawn trace (layers, steps)
        chord = mains[0][-1, :2] - mains[0][0, :2]
        all_pts = np.vstack([_resample(m, 1.0) for m in mains])
        rows.append(dict(crack_id=cid, type_pre=type_pre, type_post=type_post,
                         area_px=int(free.sum()), area_cov_px=area_cov, length_px=length,
                         trace_length_px=trace_length, width_px=width,
                         n_traces=len(traces), n_branches=n_branches, debris_px=debris_px,
                         n_grains=len(_grains_on(all_pts, grain_labels)),
                         orientation_deg=float(np.degrees(np.arctan2(-chord[1], chord[0]))
                                               % 180.0)))
        all_traces.append(traces + debris)
    cracks = pd.DataFrame(rows, columns=["crack_id", "type_pre", "type_post", "area_px",
                                         "area_cov_px", "length_px", "trace_length_px",
                                         "width_px", "n_traces", "n_branches", "debris_px",
                                         "n_grains", "orientation_deg"])

    # speckles and pores (dark, not cracks)
    def blobs(n, rmin, rmax):
        return _place_isolated(n, crack_labels, margin, rng,
                               lambda c: np.array([[c[0], c[1], rng.uniform(rmin, rmax)]]))

    speckle_mask, speck_cov = blobs(n_speckles, 1.0, 3.0)
    pore_mask, pore_cov = blobs(n_pores, 6.0, 18.0)
    lens_mask, lens_cov = _place_isolated(n_lenses, crack_labels, margin, extra,
                                          lambda c: _lens(c, extra))

    # grey levels
    grain_offset = 1.0 + 0.03 * rng.standard_normal(n_grains + 1)
    base = greys[mineral_labels] * grain_offset[grain_labels]
    texture = ndi.gaussian_filter(rng.standard_normal((h, w)), 3.0)
    texture *= 4.0 / max(texture.std(), 1e-9)
    bline = ndi.gaussian_filter(boundary.astype(np.float32), 0.7)
    bline /= max(bline.max(), 1e-9)
    grey = base * (1.0 - boundary_depth * bline) + texture
    crack_grey = float(crack_grey) + 3.0 * rng.standard_normal()
    grey = grey * (1 - cover) + crack_grey * cover
    grey = grey * (1 - pore_cov) + (crack_grey - 5.0) * pore_cov
    grey = grey * (1 - speck_cov) + (crack_grey + 10.0) * speck_cov
    if n_lenses:
        grey = grey * (1 - lens_cov) + (crack_grey + extra.uniform(0.0, 20.0)) * lens_cov
    if blur_sigma > 0:
        grey = ndi.gaussian_filter(grey, blur_sigma)
    illum = np.ones((h, w), np.float32)
    if gradient and gradient != 1.0:
        ang = rng.uniform(0, 2 * math.pi)
        yy, xx = np.mgrid[0:h, 0:w]
        s = (xx - w / 2) * math.cos(ang) + (yy - h / 2) * math.sin(ang)
        s = (s - s.min()) / max(s.max() - s.min(), 1e-9)
        illum = (1.0 - (1.0 - 1.0 / gradient) * s).astype(np.float32)
    grey = grey * illum + noise_sigma * rng.standard_normal((h, w))
    if bit_depth == 8:
        image = np.clip(np.rint(grey), 0, 255).astype(np.uint8)
    else:
        image = np.clip(np.rint(grey * 257.0), 0, 65535).astype(np.uint16)

    gid, garea = np.unique(grain_labels, return_counts=True)
    grains = pd.DataFrame(dict(grain_id=gid.astype(np.int32),
                               mineral=[names[grain_mineral[g]] for g in gid],
                               mineral_idx=grain_mineral[gid], area_px=garea,
                               eq_diameter_px=np.sqrt(4.0 * garea / math.pi)))
    return SynthImage(image=image, crack_mask=crack_labels > 0, crack_labels=crack_labels,
                      grain_labels=grain_labels, mineral_labels=mineral_labels.astype(np.int32),
                      pixel_size_um=float(pixel_size_um), cracks=cracks, grains=grains,
                      mineral_names=names, stage=stage, seed=seed, illumination=illum,
                      speckle_mask=speckle_mask, pore_mask=pore_mask, boundary_mask=boundary,
                      traces=all_traces, lens_mask=lens_mask)


# --------------------------------------------------------------------------- sample set
#: the bundled sample set: (name, stage, gradient, pores, widths, magnification, specimen stage)
SAMPLE_SET = (
    ("S1_pre_01", "pre", 1.0, 0, (2, 8), 200, "pre-test"),
    ("S1_pre_02", "pre", 2.5, 2, (2, 8), 200, "pre-test"),
    ("S1_pre_03", "pre", 1.0, 0, (1, 3), 500, "pre-test"),
    ("S1_ini_01", "post", 1.0, 0, (2, 6), 200, "initiating"),
    ("S1_ini_02", "post", 1.8, 0, (2, 6), 200, "initiating"),
    ("S1_pro_01", "post", 1.0, 1, (2, 8), 200, "propagation"),
    ("S1_pro_02", "post", 2.5, 0, (2, 8), 100, "propagation"),
    ("S1_fail_01", "post", 1.0, 0, (2, 8), 200, "failure"),
    ("S1_fail_02", "post", 2.0, 0, (2, 8), 100, "failure"),
    ("S1_fail_03", "post", 1.0, 0, (1, 8), 500, "failure"),
)


def write_sample_set(out_dir, *, shape=(576, 768), seed=2026) -> pd.DataFrame:
    """Write the sample image set with ``manifest.csv``, ``truth.csv`` and ``truth_cracks.csv``.

    Parameters
    ----------
    out_dir : path
        Created if missing; existing files of the set are overwritten.
    shape : (int, int)
    seed : int
        Image k uses ``seed + k``.

    Returns
    -------
    truth : DataFrame
        One row per image (the content of ``truth.csv``): the crack area and length, the
        crack area fraction of the image, and for post-test images the tensile and shear
        coverage areas ``area_T_px, area_S_px`` and P = A_T / A_S (mixed cracks left out, as
        ``semkit analyse`` does by default; NaN for pre-test images).
    """
    from .config import MAGNIFICATION_TABLE_UM
    from .io import write_csv_atomic, write_image

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    man, truth, per_crack = [], [], []
    n_cr = {"pre-test": 14, "initiating": 12, "propagation": 18, "failure": 24}
    for k, (name, stage, grad, pores, wid, mag, sstage) in enumerate(SAMPLE_SET):
        px = MAGNIFICATION_TABLE_UM[mag]
        s = make_sem_image(shape, stage=stage, gradient=grad, n_pores=pores, widths=wid,
                           n_cracks=n_cr[sstage], pixel_size_um=px, seed=seed + k)
        fname = f"{name}.png"
        write_image(out / fname, s.image)
        man.append(dict(image=fname, specimen="S1", test="ucs", stage=sstage, magnification=mag,
                        pixel_size_um=px))
        kind = s.cracks["type_post"].astype(str)
        a_t = float(s.cracks.loc[kind == "tensile", "area_cov_px"].sum())
        a_s = float(s.cracks.loc[kind == "shear", "area_cov_px"].sum())
        truth.append(dict(image=fname, stage=stage, gradient=grad, n_cracks=len(s.cracks),
                          crack_area_px=s.crack_area_px, crack_length_px=s.crack_length_px,
                          crack_area_um2=s.crack_area_px * px * px,
                          crack_length_um=s.crack_length_px * px,
                          sample_area_px=s.image.size,
                          crack_area_fraction=s.crack_area_px / s.image.size,
                          area_T_px=a_t if stage == "post" else np.nan,
                          area_S_px=a_s if stage == "post" else np.nan,
                          P=a_t / a_s if stage == "post" and a_s > 0 else np.nan,
                          seed=seed + k))
        c = s.cracks.copy()
        c.insert(0, "image", fname)
        per_crack.append(c)
    write_csv_atomic(pd.DataFrame(man), out / "manifest.csv")
    truth = pd.DataFrame(truth)
    write_csv_atomic(truth, out / "truth.csv")
    write_csv_atomic(pd.concat(per_crack, ignore_index=True), out / "truth_cracks.csv")
    return truth


def main(argv=None) -> int:
    """``python -m semkit.synth OUT_DIR``: write the sample set."""
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m semkit.synth OUT_DIR", file=sys.stderr)
        return 2
    t = write_sample_set(argv[0])
    print(f"wrote {len(t)} images to {argv[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
