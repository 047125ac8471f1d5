"""gen3 -- independent synthetic SEM (BSE / SE) rock micrographs with exact crack truth.

This module is a *blind* test-set generator for crack-measurement software.  It
was written without looking at the program under test.  Every image is a
deterministic function of ``(shape, seed)``.

Image model
-----------
1. **Rock background** ``B`` (float, arbitrary "BSE signal" units, 0..1):
   a mineral mosaic (Voronoi grains, optionally stretched and rotated for
   bedded rocks, optional intergranular matrix/cement, inclusions such as
   oxides, zircon, organic lenses, pyrite framboids, plagioclase laths), one
   BSE grey level per phase plus per-grain channelling jitter, intragranular
   texture (mottling, twin lamellae, oscillatory / core-rim zoning, mica
   cleavage, perthite stringers), polishing relief at phase boundaries,
   grain-boundary grooves, polishing scratches (faint, straight, long, darker
   or brighter -- *not* cracks), SE-like bright rims along void edges and a
   gentle illumination gradient / vignetting.
2. **Voids**: cracks (the truth) and compact pores (not truth).  Every void
   polygon is rasterised with an exact ``SS x SS`` supersampled scan-line
   fill, giving a coverage ``c`` in [0, 1] per pixel.  The grey before
   blur/noise is exactly ``B * (1 - c) + void_grey * c`` with ``void_grey``
   below every rock phase.
3. **Acquisition**: Gaussian probe blur (0.5-1.5 px), optional detector lag
   along the scan direction, Poisson-Gaussian detector noise, scan-line
   offsets/gain jitter and glitches, mapping to a (often narrow) 8- or
   16-bit output range, optional posterisation or JPEG round-trip, optional
   information bar (black / grey band with HV, WD, mag, HFW, detector, date
   and a scale bar) at the bottom.

Crack model and truth contract
------------------------------
A crack trace follows a gently bending smooth path ``P(u)`` (arc length ``u``,
unit normal ``N(u)``).  Its two walls are offsets along ``N``:
``top(u)`` and ``bottom(u)``.

* *tensile*: ``top = r(u) + g(u)/2``, ``bottom = r(u) - g(u)/2`` -- the same
  rough profile ``r`` shifted apart (matching walls), opening ``g`` tapered
  to zero at the tips, modulated and sometimes bridged; optional branches.
* *shear*: ``top = r(u) + g/2``, ``bottom = r(u - delta(u)) - g/2`` -- the
  lower wall is the upper one slid by ``delta`` along the trace, so only the
  releasing steps open (stepped / jog voids); variants: single stepped trace,
  several parallel layers, en-echelon arrays of short oblique gashes; gouge
  fragments inside wide stretches and plucked-out (incomplete) walls.
* *mixed*: opening plus moderate slip.

The mid-line is ``P + (top + bottom)/2 * N``.  The local opening is
``(top - bottom) / sqrt(1 + (d mid / du)^2)``; stretches with opening
``< MIN_OPEN`` (0.3 px) are closed: neither drawn nor counted.  Run ends are
interpolated to the exact 0.3-px crossing.

Truth (all restricted to the image rows above the information bar):

* ``area_px``: sum of crack coverage (pores excluded),
* ``length_px``: total length of the mid-line polylines of all open runs,
  clipped exactly to the image rectangle,
* ``tensile_area_px`` / ``shear_area_px`` (mixed excluded) and
  ``P = tensile / shear`` (NaN if no shear area),
* ``n_cracks``: crack objects (a crack with its branches / layers / echelon
  segments counts once) with at least 1 px of visible area.

Different cracks (and pores) are kept ~4 px apart (no void pixel of a new
crack within 5 px of an existing void pixel), so per-type coverages never
overlap.
"""
# ruff: noqa: E501
from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.signal import lfilter, lfilter_zi
from scipy.spatial import cKDTree

__all__ = [
    "make_image",
    "rasterize_coverage",
    "polyline_length_in_rect",
    "open_runs",
    "SS",
    "MIN_OPEN",
]

SS = 8  # supersampling factor per axis (SS*SS samples per pixel)
MIN_OPEN = 0.3  # opening (px) below which a stretch is closed
SEP_PX = 4.0  # minimum gap between different cracks / pores (px)
DU = 0.5  # arc-length sampling step of crack traces (px)
KINDS = ("tensile", "shear", "mixed")


# =============================================================================
# Exact supersampled rasteriser and geometry helpers
# =============================================================================
def _row_offsets(rows):
    """Sub-sample x offset in (-0.5, 0.5) of absolute sample row(s) ``rows``."""
    return np.mod(np.asarray(rows, np.float64) * 0.6180339887498949, 1.0) - 0.5


def rasterize_coverage(polys, holes=(), x0=0, y0=0, width=1, height=1, ss=SS):
    """Exact supersampled coverage of a union of polygons minus holes.

    Sample points sit at ``(j + (k + 0.5 + o_R)/ss, i + (l + 0.5)/ss)``
    with ``k, l`` in ``0..ss-1`` and ``o_R`` a golden-ratio (Weyl) offset of
    the absolute sample row ``R = i*ss + l``, so every pixel holds exactly
    ``ss*ss`` samples but the pattern is not a lattice; a sample
    is filled when the non-zero winding number of ``polys`` is non-zero and
    that of ``holes`` is zero.  All ``polys`` should share one orientation
    (use :func:`_ccw`) so that overlapping pieces form a union.

    Parameters
    ----------
    polys, holes : sequence of (n, 2) array_like
        Polygons as ``(x, y)`` vertices in full-image pixel coordinates
        (pixel ``(i, j)`` covers ``[j, j+1) x [i, i+1)``).
    x0, y0 : int
        Top-left pixel of the output window.
    width, height : int
        Window size in pixels.
    ss : int
        Supersampling factor per axis.

    Returns
    -------
    numpy.ndarray
        ``(height, width)`` float32 coverage in [0, 1], quantised in
        ``1/ss**2``.
    """
    height, width = int(height), int(width)
    cov = np.zeros((max(height, 0), max(width, 0)), np.float32)
    if height <= 0 or width <= 0:
        return cov
    chunks = []
    for kind, plist in ((0, polys), (1, holes)):
        for p in plist:
            p = np.asarray(p, np.float64)
            if p.ndim != 2 or len(p) < 3:
                continue
            q = np.roll(p, -1, axis=0)
            e = np.empty((len(p), 5))
            e[:, 0] = p[:, 0] - x0
            e[:, 1] = p[:, 1] - y0
            e[:, 2] = q[:, 0] - x0
            e[:, 3] = q[:, 1] - y0
            e[:, 4] = kind
            chunks.append(e)
    if not chunks:
        return cov
    E = np.concatenate(chunks)
    xa, ya, xb, yb, kd = E.T
    ylo = np.minimum(ya, yb) * ss
    yhi = np.maximum(ya, yb) * ss
    r0 = np.clip(np.ceil(ylo - 0.5), 0, height * ss).astype(np.int64)
    r1 = np.clip(np.ceil(yhi - 0.5), 0, height * ss).astype(np.int64)
    cnt = np.maximum(r1 - r0, 0)
    total = int(cnt.sum())
    if total == 0:
        return cov
    idx = np.repeat(np.arange(len(E)), cnt)
    start = np.cumsum(cnt) - cnt
    r = r0[idx] + (np.arange(total) - start[idx])
    yc = (r + 0.5) / ss
    x = xa[idx] + (yc - ya[idx]) * (xb - xa)[idx] / (yb - ya)[idx]
    d = np.where(yb > ya, 1, -1)[idx]
    isf = kd[idx] > 0.5
    wc = np.where(isf, 0, d)
    wf = np.where(isf, d, 0)
    order = np.lexsort((x, r))
    r = r[order]
    x = x[order]
    wc = np.cumsum(wc[order])  # closed polygons: net winding per row is 0,
    wf = np.cumsum(wf[order])  # so the global cumsum restarts every row
    # per-sample-row x offsets (Weyl sequence over the absolute row index):
    # the sample pattern is not a lattice, which removes the coherent
    # aliasing of long straight edges at special angles
    off = _row_offsets(r + int(y0) * ss)
    c = np.clip(np.ceil(x * ss - 0.5 - off), 0, width * ss).astype(np.int64)
    fill = (r[:-1] == r[1:]) & (wc[:-1] != 0) & (wf[:-1] == 0)
    a = c[:-1][fill]
    b = c[1:][fill]
    rr = r[:-1][fill]
    keep = b > a
    a, b, rr = a[keep], b[keep], rr[keep]
    if len(a) == 0:
        return cov
    # Difference-array accumulation of sample counts per pixel.
    pr = rr // ss
    qa, ma = np.divmod(a, ss)
    qb, mb = np.divmod(b, ss)
    w2 = width + 2
    base = pr * w2
    ind = np.concatenate([base + qb, base + qb + 1, base + qa, base + qa + 1])
    wts = np.concatenate([mb - ss, -mb, ss - ma, ma]).astype(np.float64)
    acc = np.bincount(ind, weights=wts, minlength=height * w2).reshape(height, w2)
    cov[:] = np.cumsum(acc, axis=1)[:, :width] / float(ss * ss)
    return cov


def polyline_length_in_rect(pts, x0, y0, x1, y1):
    """Length of a polyline clipped to the rectangle ``[x0, x1] x [y0, y1]``.

    Parameters
    ----------
    pts : (n, 2) array_like
        Vertices ``(x, y)``.
    x0, y0, x1, y1 : float
        Rectangle bounds.

    Returns
    -------
    float
        Exact (Liang-Barsky) clipped length.
    """
    pts = np.asarray(pts, np.float64)
    if len(pts) < 2:
        return 0.0
    p0 = pts[:-1]
    dxy = pts[1:] - p0
    t0 = np.zeros(len(p0))
    t1 = np.ones(len(p0))
    for pk, qk in ((-dxy[:, 0], p0[:, 0] - x0), (dxy[:, 0], x1 - p0[:, 0]),
                   (-dxy[:, 1], p0[:, 1] - y0), (dxy[:, 1], y1 - p0[:, 1])):
        zero = pk == 0
        out = zero & (qk < 0)
        t0[out] = 1.0
        t1[out] = 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            tk = qk / pk
        neg = (~zero) & (pk < 0)
        pos = (~zero) & (pk > 0)
        t0[neg] = np.maximum(t0[neg], tk[neg])
        t1[pos] = np.minimum(t1[pos], tk[pos])
    seg = np.hypot(dxy[:, 0], dxy[:, 1])
    return float(np.sum(seg * np.clip(t1 - t0, 0.0, None)))


def _signed_area(p):
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _ccw(p):
    """Return the polygon with positive signed area (shoelace convention)."""
    return p if _signed_area(p) >= 0 else p[::-1].copy()


def open_runs(P, N, top, bottom, du=DU, min_open=MIN_OPEN):
    """Split a two-walled trace into open runs (polygon + mid-line).

    Parameters
    ----------
    P, N : (n, 2) ndarray
        Smooth path points and unit normals (``x, y``).
    top, bottom : (n,) ndarray
        Wall offsets along ``N`` (``top > bottom`` where open).
    du : float
        Arc-length step of ``P``.
    min_open : float
        Opening threshold (px); stretches below it are closed.

    Returns
    -------
    list of dict
        Each with ``poly`` ((m, 2), positive orientation), ``mid`` ((k, 2)
        mid-line polyline) and ``u0``, ``u1`` (index range, fractional).
    """
    n = len(P)
    if n < 2:
        return []
    mid = 0.5 * (top + bottom)
    gap = top - bottom
    slope = np.gradient(mid, du)
    a = gap / np.sqrt(1.0 + slope * slope)
    op = a >= min_open
    if not op.any():
        return []
    dd = np.diff(op.astype(np.int8))
    starts = list(np.nonzero(dd == 1)[0] + 1)
    ends = list(np.nonzero(dd == -1)[0])
    if op[0]:
        starts.insert(0, 0)
    if op[-1]:
        ends.append(n - 1)
    out = []
    for s, e in zip(starts, ends):
        Pr, Nr, tr, br = P[s:e + 1], N[s:e + 1], top[s:e + 1], bottom[s:e + 1]
        fs, fe = float(s), float(e)
        if s > 0:
            f = (min_open - a[s - 1]) / (a[s] - a[s - 1])
            f = min(max(f, 0.0), 1.0)
            Pr = np.vstack([P[s - 1] + f * (P[s] - P[s - 1]), Pr])
            Nr = np.vstack([N[s - 1] + f * (N[s] - N[s - 1]), Nr])
            tr = np.concatenate([[top[s - 1] + f * (top[s] - top[s - 1])], tr])
            br = np.concatenate([[bottom[s - 1] + f * (bottom[s] - bottom[s - 1])], br])
            fs = s - 1 + f
        if e < n - 1:
            f = (a[e] - min_open) / (a[e] - a[e + 1])
            f = min(max(f, 0.0), 1.0)
            Pr = np.vstack([Pr, P[e] + f * (P[e + 1] - P[e])])
            Nr = np.vstack([Nr, N[e] + f * (N[e + 1] - N[e])])
            tr = np.concatenate([tr, [top[e] + f * (top[e + 1] - top[e])]])
            br = np.concatenate([br, [bottom[e] + f * (bottom[e + 1] - bottom[e])]])
            fe = e + f
        if len(Pr) < 2:
            continue
        upper = Pr + tr[:, None] * Nr
        lower = Pr + br[:, None] * Nr
        poly = _ccw(np.vstack([upper, lower[::-1]]))
        midl = Pr + (0.5 * (tr + br))[:, None] * Nr
        out.append(dict(poly=poly, mid=midl, u0=fs, u1=fe))
    return out


# =============================================================================
# Random helpers
# =============================================================================
def _logu(rng, a, b):
    return float(math.exp(rng.uniform(math.log(a), math.log(b))))


def _noise1d(n, du, rng, lam_min, lam_max, beta):
    """Band-limited 1-D fractal noise with unit standard deviation.

    Parameters
    ----------
    n : int
        Number of samples.
    du : float
        Sample spacing.
    rng : numpy.random.Generator
    lam_min, lam_max : float
        Shortest / longest wavelength kept.
    beta : float
        Power-spectrum exponent (``P(k) ~ k**-beta``).

    Returns
    -------
    ndarray
        ``(n,)`` noise, zero mean, unit std (zeros if degenerate).
    """
    if n < 4:
        return np.zeros(n)
    m = int(2 ** math.ceil(math.log2(n * 1.5)))
    k = np.fft.rfftfreq(m, d=du)
    amp = np.zeros_like(k)
    band = (k >= 1.0 / max(lam_max, 2 * du)) & (k <= 1.0 / max(lam_min, 2 * du))
    if not band[1:].any():
        band[1] = True
    band[0] = False
    amp[band] = k[band] ** (-beta / 2.0)
    spec = amp * (rng.standard_normal(len(k)) + 1j * rng.standard_normal(len(k)))
    x = np.fft.irfft(spec, m)[:n]
    x -= x.mean()
    s = x.std()
    return x / s if s > 0 else x


def _fractal2d(H, W, rng, smin, smax, beta=1.0, aniso=1.0):
    """Multi-octave value noise (bicubic upsampled Gaussian grids), unit std.

    Parameters
    ----------
    H, W : int
        Output shape.
    rng : numpy.random.Generator
    smin, smax : float
        Smallest / largest feature size (px) along y.
    beta : float
        Octave weight ``s**beta``.
    aniso : float
        Stretch factor of features along x.

    Returns
    -------
    ndarray
        float32 ``(H, W)``.
    """
    out = np.zeros((H, W), np.float32)
    s = float(smax)
    while s >= smin * 0.999:
        gh = int(math.ceil(H / s)) + 3
        gw = int(math.ceil(W / (s * aniso))) + 3
        small = rng.standard_normal((gh, gw)).astype(np.float32)
        up = cv2.resize(small, (W, H), interpolation=cv2.INTER_CUBIC)
        out += up * np.float32(s ** beta)
        s /= 2.0
    out -= out.mean()
    sd = out.std()
    return out / sd if sd > 0 else out


def _rotate_crop(arr, angle_deg, H, W, nearest):
    """Rotate a square canvas about its centre and crop the central H x W."""
    D = arr.shape[0]
    M = cv2.getRotationMatrix2D((D / 2.0, D / 2.0), angle_deg, 1.0)
    interp = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    if arr.dtype == np.int64:
        arr = arr.astype(np.int32)
    rot = cv2.warpAffine(arr, M, (D, D), flags=interp, borderMode=cv2.BORDER_REFLECT)
    y0 = (D - H) // 2
    x0 = (D - W) // 2
    return rot[y0:y0 + H, x0:x0 + W]


# =============================================================================
# Rock recipes (BSE grey ~ mean atomic number, arbitrary 0..1 units)
# =============================================================================
# phase tuple: (name, grey, abundance, texture dict)
# inclusion tuple: (name, grey, count per mm^2, size_um range, aspect range, shape, texture)
ROCKS = {
    "granite": dict(
        grain_um=(150.0, 2500.0), aniso=(1.0, 1.35), bedded=False, seeds="poisson",
        phases=[("quartz", 0.40, 0.32, dict(hard=1.0, noise=0.006)),
                ("K-feldspar", 0.50, 0.27, dict(hard=0.85, perthite=0.035, noise=0.007, dust=0.04)),
                ("plagioclase", 0.45, 0.28, dict(hard=0.85, zoning=0.03, twins=0.014, dust=0.05)),
                ("biotite", 0.27, 0.10, dict(hard=0.35, cleavage=0.05, noise=0.012)),
                ("chlorite", 0.33, 0.03, dict(hard=0.3, cleavage=0.03, noise=0.01))],
        matrix=None,
        inclusions=[("magnetite", 0.88, 12.0, (5, 60), (1.0, 1.6), "blob", dict(hard=1.0)),
                    ("zircon", 0.95, 6.0, (4, 25), (1.2, 2.5), "blob", dict(hard=1.2, zoning=0.04)),
                    ("apatite", 0.60, 8.0, (5, 40), (1.5, 3.0), "blob", dict(hard=0.9))],
        pores=(0.0, 15.0, 8.0)),
    "sandstone": dict(
        grain_um=(60.0, 450.0), aniso=(1.0, 1.5), bedded=False, seeds="poisson",
        phases=[("quartz", 0.40, 0.62, dict(hard=1.0, noise=0.005)),
                ("K-feldspar", 0.50, 0.12, dict(hard=0.85, perthite=0.02, noise=0.007, dust=0.05)),
                ("plagioclase", 0.45, 0.08, dict(hard=0.85, twins=0.012)),
                ("lithic fragment", 0.36, 0.13, dict(hard=0.6, noise=0.03, dust=0.04)),
                ("muscovite", 0.44, 0.05, dict(hard=0.35, cleavage=0.04))],
        matrix=[("illite-kaolinite matrix", 0.31, dict(hard=0.2, noise=0.035)),
                ("calcite cement", 0.55, dict(hard=0.45, noise=0.008)),
                ("dolomite cement", 0.47, dict(hard=0.5, noise=0.01))],
        inclusions=[("zircon", 0.95, 15.0, (4, 30), (1.2, 2.0), "blob", dict(hard=1.2)),
                    ("rutile", 0.78, 10.0, (4, 30), (1.2, 3.0), "blob", dict(hard=1.1)),
                    ("Fe-oxide", 0.86, 15.0, (4, 40), (1.0, 2.0), "blob", dict(hard=1.0))],
        pores=(10.0, 70.0, 14.0)),
    "marble": dict(
        grain_um=(80.0, 2000.0), aniso=(1.0, 1.3), bedded=False, seeds="jitter",
        phases=[("calcite", 0.55, 0.85, dict(hard=0.4, twins=0.03, noise=0.004)),
                ("dolomite", 0.47, 0.15, dict(hard=0.5, noise=0.006, dust=0.03))],
        matrix=None,
        inclusions=[("quartz", 0.40, 20.0, (10, 150), (1.0, 1.8), "blob", dict(hard=1.0)),
                    ("phlogopite", 0.36, 15.0, (15, 200), (3.0, 8.0), "flake", dict(hard=0.3, cleavage=0.04)),
                    ("graphite", 0.14, 10.0, (10, 120), (3.0, 10.0), "flake", dict(hard=0.1, noise=0.01)),
                    ("pyrite", 0.92, 6.0, (5, 60), (1.0, 1.4), "blob", dict(hard=1.3))],
        pores=(0.0, 25.0, 10.0)),
    "shale": dict(
        grain_um=(4.0, 40.0), aniso=(2.0, 5.0), bedded=True, seeds="poisson",
        phases=[("quartz silt", 0.40, 0.55, dict(hard=1.0, noise=0.006)),
                ("calcite", 0.55, 0.20, dict(hard=0.45, noise=0.006)),
                ("feldspar", 0.48, 0.15, dict(hard=0.85, noise=0.006)),
                ("dolomite", 0.47, 0.10, dict(hard=0.5, noise=0.006))],
        matrix=[("clay matrix", 0.33, dict(hard=0.2, noise=0.04)),
                ("carbonate-clay matrix", 0.40, dict(hard=0.3, noise=0.035))],
        inclusions=[("organic matter", 0.15, 1500.0, (3, 40), (2.0, 7.0), "lens", dict(hard=0.1, noise=0.01)),
                    ("pyrite framboid", 0.92, 300.0, (3, 20), (1.0, 1.3), "framboid", dict(hard=1.3)),
                    ("mica flake", 0.38, 400.0, (5, 50), (4.0, 10.0), "flake", dict(hard=0.3, cleavage=0.03))],
        pores=(10.0, 120.0, 6.0)),
    "basalt": dict(
        grain_um=(30.0, 800.0), aniso=(1.0, 1.3), bedded=False, seeds="poisson",
        phases=[("augite", 0.62, 0.50, dict(hard=0.9, zoning=0.03, noise=0.006)),
                ("olivine", 0.68, 0.18, dict(hard=1.0, zoning=0.04, noise=0.005)),
                ("plagioclase", 0.45, 0.20, dict(hard=0.85, twins=0.012)),
                ("glass", 0.42, 0.12, dict(hard=0.7, noise=0.02, dust=0.04))],
        matrix=None,
        inclusions=[("plagioclase lath", 0.45, 60.0, (20, 250), (3.0, 9.0), "lath", dict(hard=0.85, twins=0.012)),
                    ("Ti-magnetite", 0.90, 25.0, (5, 60), (1.0, 2.0), "blob", dict(hard=1.1)),
                    ("ilmenite", 0.84, 30.0, (10, 150), (4.0, 12.0), "lath", dict(hard=1.1))],
        pores=(0.0, 30.0, 40.0)),
}


def _voronoi_labels(h, w, n_seeds, rng, mode):
    """Voronoi label map (0-based) from random or jittered-grid seeds."""
    n_seeds = int(max(2, min(n_seeds, h * w // 16)))
    if mode == "jitter":
        g = int(max(1, round(math.sqrt(n_seeds * w / max(h, 1)))))
        gy = int(max(1, round(n_seeds / g)))
        yy, xx = np.meshgrid((np.arange(gy) + 0.5) * h / gy, (np.arange(g) + 0.5) * w / g, indexing="ij")
        ys = yy.ravel() + rng.uniform(-0.4, 0.4, yy.size) * h / gy
        xs = xx.ravel() + rng.uniform(-0.4, 0.4, xx.size) * w / g
    else:
        ys = rng.uniform(0, h, n_seeds)
        xs = rng.uniform(0, w, n_seeds)
    ys = np.clip(ys.astype(int), 0, h - 1)
    xs = np.clip(xs.astype(int), 0, w - 1)
    img = np.ones((h, w), np.uint8)
    img[ys, xs] = 0
    _, lab = cv2.distanceTransformWithLabels(img, cv2.DIST_L2, 5, labelType=cv2.DIST_LABEL_PIXEL)
    return (lab - 1).astype(np.int32)


def _blob_poly(cx, cy, rx, ry, ang, rng, rough=0.08, nv=None):
    """Irregular elliptical polygon (int32 vertices for cv2.fillPoly)."""
    if nv is None:
        nv = int(np.clip(2 * math.pi * max(rx, ry) / 2.0, 10, 80))
    phi = np.linspace(0, 2 * math.pi, nv, endpoint=False)
    rad = np.ones(nv)
    for k in range(2, 6):
        rad += rough / k * rng.standard_normal() * np.cos(k * phi + rng.uniform(0, 2 * math.pi))
    x = rx * rad * np.cos(phi)
    y = ry * rad * np.sin(phi)
    ca, sa = math.cos(ang), math.sin(ang)
    return np.stack([cx + ca * x - sa * y, cy + sa * x + ca * y], axis=1)


def _render_background(H, W, rng, ps, rock_name):
    """Render the rock background (no voids).

    Parameters
    ----------
    H, W : int
        Image shape.
    rng : numpy.random.Generator
    ps : float
        Pixel size (um / px).
    rock_name : str
        Key of :data:`ROCKS`.

    Returns
    -------
    B : ndarray
        float32 background signal.
    info : dict
        Settings used (JSON-friendly) plus ``min_phase_grey``.
    """
    rk = ROCKS[rock_name]
    info = {"rock": rock_name}
    se_look = bool(rng.random() < 0.3)
    info["se_look"] = se_look
    # ---------------------------------------------------------------- phases
    phases = []
    abund = rng.dirichlet(np.array([p[2] for p in rk["phases"]]) * 12.0 + 0.3)
    for (name, grey, _, tex), ab in zip(rk["phases"], abund):
        phases.append(dict(name=name, grey=float(grey + rng.normal(0, 0.02)), frac=float(ab), **tex))
    grain_px = _logu(rng, *rk["grain_um"]) / ps
    big_ok = rng.random() < 0.15  # occasionally allow a single grain filling the field
    grain_px = float(np.clip(grain_px, 10.0, (1.3 if big_ok else 0.3) * max(H, W)))
    aniso = float(rng.uniform(*rk["aniso"]))
    bedding = float(rng.uniform(-25, 25)) if rk["bedded"] else float(rng.uniform(-90, 90))
    info.update(grain_px=round(grain_px, 2), aniso=round(aniso, 3), fabric_angle_deg=round(bedding, 2))
    # ------------------------------------------------------------ mosaic
    rotate = aniso > 1.3
    if rotate:
        D = int(math.ceil(math.hypot(H, W))) + 4
        hh, ww = D, D
    else:
        hh, ww = H, W
    wq = max(2, int(round(ww / aniso)))
    n_seeds = hh * wq / (grain_px / math.sqrt(aniso)) ** 2 * 1.0
    n_seeds = min(n_seeds, 120000)
    lab = _voronoi_labels(hh, wq, n_seeds, rng, rk["seeds"])
    if wq != ww:
        lab = cv2.resize(lab, (ww, hh), interpolation=cv2.INTER_NEAREST)
    if rotate:
        lab = _rotate_crop(lab, bedding, H, W, nearest=True)
    lab = np.ascontiguousarray(lab)
    n_lab = int(lab.max()) + 1
    phase_of = rng.choice(len(phases), size=n_lab, p=abund / abund.sum())
    # ------------------------------------------------------------ matrix
    def boundaries(lb):
        b = np.zeros(lb.shape, bool)
        b[:, 1:] |= lb[:, 1:] != lb[:, :-1]
        b[1:, :] |= lb[1:, :] != lb[:-1, :]
        return b

    if rk["matrix"] is not None:
        mname, mgrey, mtex = rk["matrix"][int(rng.integers(len(rk["matrix"])))]
        phases.append(dict(name=mname, grey=float(mgrey + rng.normal(0, 0.02)), frac=0.0, **mtex))
        m_phase = len(phases) - 1
        bd = boundaries(lab)
        dist = cv2.distanceTransform((~bd).astype(np.uint8), cv2.DIST_L2, 3)
        mfrac = rng.uniform(0.25, 0.5) if rock_name == "shale" else rng.uniform(0.04, 0.18)
        thick = mfrac * grain_px / math.sqrt(aniso)
        wob = _fractal2d(H, W, rng, max(2.0, grain_px / 8), max(4.0, grain_px), 1.0)
        mmask = dist < thick * (1.0 + 0.5 * wob)
        lab = np.where(mmask, n_lab, lab).astype(np.int32)
        phase_of = np.append(phase_of, m_phase)
        n_lab += 1
        info["matrix"] = mname
        info["matrix_thickness_px"] = round(float(thick), 2)
    # ------------------------------------------------------------ inclusions
    area_mm2 = H * W * ps * ps * 1e-6
    inc_log = {}
    for name, grey, dens, size_um, asp, shape, tex in rk["inclusions"]:
        n_inc = int(rng.poisson(dens * area_mm2 * _logu(rng, 0.3, 2.0)))
        n_inc = min(n_inc, 3000)
        if n_inc == 0:
            continue
        phases.append(dict(name=name, grey=float(grey + rng.normal(0, 0.02)), frac=0.0, **tex))
        ph = len(phases) - 1
        drawn = 0
        for _ in range(n_inc):
            size = _logu(rng, *size_um) / ps
            if size < 1.5:
                continue
            size = min(size, 0.35 * max(H, W))
            a = rng.uniform(*asp)
            cx, cy = rng.uniform(0, W), rng.uniform(0, H)
            ang = math.radians(bedding + rng.normal(0, 8)) if rk["bedded"] else rng.uniform(0, math.pi)
            lid = n_lab
            n_lab += 1
            phase_of = np.append(phase_of, ph)
            if shape == "framboid":
                nd = int(np.clip((size / 2.0) ** 2 / 2.0, 3, 60))
                rr = size / 2.0 * np.sqrt(rng.uniform(0, 1, nd))
                th = rng.uniform(0, 2 * math.pi, nd)
                dot = max(1, int(round(size / 10.0)))
                for x_, y_ in zip(cx + rr * np.cos(th), cy + rr * np.sin(th)):
                    cv2.circle(lab, (int(x_), int(y_)), dot, int(lid), -1)
            elif shape == "lath":
                rx, ry = size / 2.0, size / 2.0 / a
                ca, sa = math.cos(ang), math.sin(ang)
                corners = np.array([[-rx, -ry], [rx, -ry], [rx, ry], [-rx, ry]])
                pts = np.stack([cx + ca * corners[:, 0] - sa * corners[:, 1], cy + sa * corners[:, 0] + ca * corners[:, 1]], 1)
                cv2.fillPoly(lab, [np.round(pts).astype(np.int32)], int(lid))
            else:
                rx, ry = size / 2.0, max(0.8, size / 2.0 / a)
                if shape == "blob" and rng.random() < 0.5:  # euhedral / angular crystal
                    pts = _blob_poly(cx, cy, rx, ry, ang, rng, rough=0.15, nv=int(rng.integers(5, 9)))
                else:
                    pts = _blob_poly(cx, cy, rx, ry, ang, rng, rough=0.25 if shape in ("lens", "blob") else 0.1)
                cv2.fillPoly(lab, [np.round(pts).astype(np.int32)], int(lid))
            drawn += 1
        inc_log[name] = drawn
    info["inclusions"] = inc_log
    info["phases"] = [(p["name"], round(p["grey"], 3)) for p in phases]
    phase_of = np.asarray(phase_of, np.int32)
    # ------------------------------------------------------------ per-label properties
    def prop(key, default=0.0):
        return np.array([p.get(key, default) for p in phases], np.float32)[phase_of]

    grey_l = prop("grey") + rng.normal(0, rng.uniform(0.004, 0.02), n_lab).astype(np.float32)  # channelling
    comp_scale = 0.55 if se_look else 1.0
    mean_g = float(np.mean([p["grey"] for p in phases]))
    grey_l = mean_g + (grey_l - mean_g) * comp_scale
    B = grey_l[lab]
    # mottling / intragranular texture
    fine = _fractal2d(H, W, rng, 1.5, 12.0, 0.6)
    B += prop("noise", 0.004)[lab] * fine
    coarse = _fractal2d(H, W, rng, 32.0, max(64.0, min(H, W) / 2.0), 1.0)
    coarse_amp = rng.uniform(0.0, 0.012)
    B += coarse_amp * coarse
    # alteration dust (sericite / clay specks, fluid-inclusion trails) -- darker, never void-dark
    du_l = prop("dust")
    if (du_l > 0).any():
        speck = _fractal2d(H, W, rng, 1.0, 3.0, 0.3)
        thr = rng.uniform(1.6, 2.4)
        sp = cv2.GaussianBlur(np.clip(speck - thr, 0, 0.8).astype(np.float32), (0, 0), 0.5) / 0.8
        B -= du_l[lab] * sp * 3.0
    theta_l = rng.uniform(0, math.pi, n_lab).astype(np.float32)
    if rk["bedded"]:
        theta_l = (math.radians(bedding) + rng.normal(0, 0.1, n_lab)).astype(np.float32)
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    # twin lamellae (calcite, plagioclase)
    tw_l = prop("twins")
    sel = tw_l[lab] > 0
    has_tw = rng.random(n_lab) < 0.75
    if sel.any():
        lam = np.clip(rng.uniform(0.015, 0.07, n_lab) * grain_px, 3.0, 60.0).astype(np.float32)
        phs = rng.uniform(0, 2 * math.pi, n_lab).astype(np.float32)
        duty = rng.uniform(-0.6, 0.3, n_lab).astype(np.float32)
        L = lab[sel]
        ph = (xx[sel] * np.cos(theta_l[L]) + yy[sel] * np.sin(theta_l[L])) * (2 * math.pi / lam[L]) + phs[L]
        stripe = (np.sin(ph) > duty[L]).astype(np.float32) - 0.5
        B[sel] += (tw_l[L] * np.sign(rng.standard_normal()) * has_tw[L]) * stripe
    # zoning (core-rim + oscillatory)
    zo_l = prop("zoning")
    sel = zo_l[lab] > 0
    bd = boundaries(lab)
    dist_b = cv2.distanceTransform((~bd).astype(np.uint8), cv2.DIST_L2, 3)
    if sel.any():
        area = np.bincount(lab.ravel(), minlength=n_lab).astype(np.float32)
        rad = np.sqrt(area / math.pi) + 1.0
        L = lab[sel]
        z = np.clip(dist_b[sel] / (0.8 * rad[L]), 0, 1)
        sgn = np.where(rng.random(n_lab) < 0.5, -1.0, 1.0).astype(np.float32)
        lamz = rng.uniform(4.0, 20.0, n_lab).astype(np.float32)
        osc = 0.35 * np.sin(2 * math.pi * dist_b[sel] / lamz[L])
        B[sel] += zo_l[L] * sgn[L] * (z ** 0.7 - 0.5 + osc)
    # mica cleavage (fine dark lines)
    cl_l = prop("cleavage")
    sel = cl_l[lab] > 0
    if sel.any():
        L = lab[sel]
        lamc = rng.uniform(2.5, 7.0, n_lab).astype(np.float32)
        ph = (xx[sel] * -np.sin(theta_l[L]) + yy[sel] * np.cos(theta_l[L])) / lamc[L]
        line = (np.mod(ph, 1.0) < 0.22).astype(np.float32) * (fine[sel] > -0.6)
        B[sel] -= cl_l[L] * line
    # perthite stringers
    pe_l = prop("perthite")
    sel = pe_l[lab] > 0
    if sel.any():
        L = lab[sel]
        lamp = rng.uniform(6.0, 22.0, n_lab).astype(np.float32)
        ph = (xx[sel] * np.cos(theta_l[L]) + yy[sel] * np.sin(theta_l[L])) * (2 * math.pi / lamp[L])
        st = (np.sin(ph + 2.0 * fine[sel]) > 0.55).astype(np.float32)
        B[sel] += pe_l[L] * st
    del yy, xx
    # polishing relief at phase boundaries (hardness -> height -> shading)
    relief_amp = rng.uniform(0.02, 0.09) if se_look else rng.uniform(0.0, 0.04)
    relief_sigma = rng.uniform(1.2, 3.5)
    det_ang = rng.uniform(0, 2 * math.pi)
    height = cv2.GaussianBlur(prop("hard", 0.5)[lab], (0, 0), relief_sigma)
    gx = cv2.Sobel(height, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gy = cv2.Sobel(height, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    B += relief_amp * 2.5 * relief_sigma * (math.cos(det_ang) * gx + math.sin(det_ang) * gy)
    # grain-boundary grooves (thin relief lines)
    groove_amp = rng.uniform(0.0, 0.05)
    gsig = rng.uniform(0.5, 1.0)
    groove = cv2.GaussianBlur(bd.astype(np.float32), (0, 0), gsig)
    B -= groove_amp * groove / max(float(groove.max()), 1e-6) * (1.0 if rng.random() < 0.8 else -1.0)
    info.update(relief_amp=round(relief_amp, 4), relief_sigma=round(relief_sigma, 3),
                detector_azimuth_deg=round(math.degrees(det_ang), 1), groove_amp=round(groove_amp, 4),
                coarse_mottle=round(coarse_amp, 4), n_grains=int(n_lab))
    # polishing scratches (long straight faint lines -- not cracks)
    n_scr = int(rng.choice([0, 0, 1, 2, 3, 5, 8, 12]))
    scr_dark = np.zeros((H, W), np.uint8)
    scr_bright = np.zeros((H, W), np.uint8)
    main_dir = rng.uniform(0, math.pi)
    for _ in range(n_scr):
        ang = main_dir + rng.normal(0, 0.08) if rng.random() < 0.7 else rng.uniform(0, math.pi)
        cx, cy = rng.uniform(0, W), rng.uniform(0, H)
        Ls = rng.uniform(0.4, 2.0) * max(H, W)
        p1 = (int(cx - Ls * math.cos(ang)), int(cy - Ls * math.sin(ang)))
        p2 = (int(cx + Ls * math.cos(ang)), int(cy + Ls * math.sin(ang)))
        level = int(rng.integers(140, 256))
        thick = int(rng.choice([1, 1, 1, 2]))
        canvas = scr_dark if rng.random() < 0.6 else scr_bright
        cv2.line(canvas, p1, p2, level, thick, cv2.LINE_AA)
    scr_amp = rng.uniform(0.02, 0.06)
    if n_scr:
        fade = np.clip(0.6 + 0.6 * _fractal2d(H, W, rng, 64.0, 512.0, 1.0), 0.0, 1.0)
        sd = cv2.GaussianBlur(scr_dark.astype(np.float32) / 255.0, (0, 0), 0.6)
        sb = cv2.GaussianBlur(scr_bright.astype(np.float32) / 255.0, (0, 0), 0.6)
        B += scr_amp * fade * (sb - sd) * 1.6
    info.update(n_scratches=n_scr, scratch_amp=round(scr_amp, 4))
    min_phase = float(min(p["grey"] for p in phases))
    info["min_phase_grey"] = round(min_phase, 4)
    return B.astype(np.float32), info


# =============================================================================
# Crack geometry
# =============================================================================
@dataclass
class _Crack:
    """Geometry of one crack object (all pieces share one type)."""

    kind: str
    variant: str
    pieces: list = field(default_factory=list)  # list of open-run dicts
    holes: list = field(default_factory=list)  # gouge fragments (solid)


def _smooth_path(anchor, theta0, L, rng, bend, at="center", du=DU):
    """Gently bending path of arc length ``L`` (sampled every ``du``).

    Returns
    -------
    u, P, N, th : ndarray
        Arc length, points (x, y), unit normals and headings.
    """
    n = max(2, int(math.ceil(L / du)) + 1)
    step = L / (n - 1)
    u = np.arange(n) * step
    th = theta0 + bend * _noise1d(n, step, rng, lam_min=120.0, lam_max=max(2.0 * L, 400.0), beta=2.5)
    dx = np.cos(th) * step
    dy = np.sin(th) * step
    P = np.zeros((n, 2))
    P[1:, 0] = np.cumsum(0.5 * (dx[1:] + dx[:-1]))
    P[1:, 1] = np.cumsum(0.5 * (dy[1:] + dy[:-1]))
    ref = P[n // 2] if at == "center" else P[0]
    P += np.asarray(anchor, float) - ref
    N = np.stack([-np.sin(th), np.cos(th)], axis=1)
    return u, P, N, th


def _roughness(u, rng, slope_rms, zig_frac):
    """Rough wall profile: band-limited fractal plus zig-zag facets."""
    n = len(u)
    if n < 4:
        return np.zeros(n)
    du = u[1] - u[0]
    L = u[-1]
    hurst = rng.uniform(0.5, 0.85)
    lmin = rng.uniform(5.0, 9.0)
    base = _noise1d(n, du, rng, lam_min=lmin, lam_max=max(2.5 * lmin, min(L, 400.0)), beta=1 + 2 * hurst)

    def unit_slope(x):
        s = np.gradient(x, du)
        rms = math.sqrt(float(np.mean(s * s)))
        return x / rms if rms > 1e-9 else x * 0

    r = (1 - zig_frac) * unit_slope(base)
    if zig_frac > 0:
        Lz = rng.uniform(12.0, 70.0)
        knots = [0.0]
        while knots[-1] < L:
            knots.append(knots[-1] + max(4.0, rng.exponential(Lz)))
        knots = np.array(knots)
        sl = rng.uniform(0.3, 1.0, len(knots)) * np.where(np.arange(len(knots)) % 2 == 0, 1.0, -1.0)
        if rng.random() < 0.5:
            sl = -sl
        seg = np.searchsorted(knots, u, side="right") - 1
        z = np.cumsum(sl[np.clip(seg, 0, len(sl) - 1)]) * du
        z -= np.polyval(np.polyfit(u, z, 1), u)
        z = cv2.GaussianBlur(z.reshape(1, -1), (0, 0), 1.0 / du).ravel() if n > 8 else z
        r += zig_frac * unit_slope(z)
    r = unit_slope(r) * slope_rms
    smax = float(np.max(np.abs(np.gradient(r, du))))
    if smax > 1.0:
        r *= 1.0 / smax
    return r - r.mean()


def _tip_shape(u, L, alpha):
    t = np.clip(u / max(L, 1e-9), 0.0, 1.0)
    return np.clip(4.0 * t * (1.0 - t), 0.0, 1.0) ** alpha


def _modulation(u, rng, sigma, bridges_per_px):
    """Multiplicative opening modulation with occasional closed rock bridges."""
    n = len(u)
    du = u[1] - u[0] if n > 1 else 1.0
    m = np.exp(sigma * _noise1d(n, du, rng, lam_min=15.0, lam_max=200.0, beta=2.0))
    m /= m.mean()
    nb = int(rng.poisson(bridges_per_px * u[-1])) if n > 1 else 0
    for _ in range(nb):
        uc = rng.uniform(0.15, 0.85) * u[-1]
        wb = rng.uniform(2.0, 10.0)
        m *= 1.0 - rng.uniform(0.8, 1.0) * np.exp(-((u - uc) / wb) ** 2)
    return m


def _plucks(u, rng, w, rate):
    """Bumps for plucked / chipped (incomplete) walls."""
    out = np.zeros(len(u))
    nb = int(rng.poisson(rate * u[-1]))
    for _ in range(nb):
        uc = rng.uniform(0.1, 0.9) * u[-1]
        a = rng.uniform(1.5, 6.0)
        h = rng.uniform(0.8, 2.5) * max(1.0, 0.6 * w)
        x = (u - uc) / a
        out += h * np.sqrt(np.clip(1 - x * x, 0, None))
    return out


def _fragments(P, N, u, top, bottom, run, rng, max_n):
    """Solid gouge fragments strictly inside an open stretch (local u, v frame)."""
    holes = []
    gap = top - bottom
    i0, i1 = int(math.ceil(run["u0"])), int(math.floor(run["u1"]))
    cand = np.arange(i0, i1 + 1)
    cand = cand[gap[cand] >= 3.0] if len(cand) else cand
    if len(cand) == 0:
        return holes
    du = u[1] - u[0]
    for _ in range(int(rng.integers(0, max_n + 1))):
        ic = int(rng.choice(cand))
        rv = rng.uniform(0.2, 0.38) * gap[ic]
        ru = rv * rng.uniform(1.0, 2.5)
        vc = 0.5 * (top[ic] + bottom[ic]) + rng.uniform(-0.15, 0.15) * gap[ic]
        nv = int(rng.integers(5, 9))
        phi = np.sort(rng.uniform(0, 2 * math.pi, nv))
        rj = rng.uniform(0.7, 1.0, nv)
        uu = u[ic] + ru * rj * np.cos(phi)
        vv = vc + rv * rj * np.sin(phi)
        if uu.min() < u[i0] or uu.max() > u[i1]:
            continue
        tt = np.interp(uu, u, top)
        bb = np.interp(uu, u, bottom)
        if np.any(vv > tt - 0.6) or np.any(vv < bb + 0.6):
            continue
        fi = uu / du
        Px = np.interp(fi, np.arange(len(u)), P[:, 0])
        Py = np.interp(fi, np.arange(len(u)), P[:, 1])
        Nx = np.interp(fi, np.arange(len(u)), N[:, 0])
        Ny = np.interp(fi, np.arange(len(u)), N[:, 1])
        holes.append(_ccw(np.stack([Px + vv * Nx, Py + vv * Ny], 1)))
    return holes


def _profile(kind, u, L, w, r, rng, cfg):
    """Wall offsets (top, bottom) for a single trace of the given kind."""
    alpha = rng.uniform(0.25, 0.6)
    shape = _tip_shape(u, L, alpha)
    mod = _modulation(u, rng, rng.uniform(0.1, 0.45), cfg["bridges_per_px"])
    slope = math.sqrt(float(np.mean(np.gradient(r, u[1] - u[0]) ** 2))) + 1e-3
    if kind == "tensile":
        g = w * shape * mod
        top, bottom = r + 0.5 * g, r - 0.5 * g
    else:
        if kind == "shear":
            d0 = float(np.clip(w / slope * rng.uniform(0.5, 1.0), 2.0, 35.0))
            g = rng.uniform(-0.25, 0.45) * w * shape * mod
        else:
            d0 = float(np.clip(w / slope * rng.uniform(0.2, 0.5), 1.0, 15.0))
            g = rng.uniform(0.5, 0.8) * w * shape * mod
        delta = d0 * _tip_shape(u, L, 0.5) * (1.0 if rng.random() < 0.5 else -1.0)
        rs = np.interp(u - delta, u, r)
        top, bottom = r + 0.5 * g, rs - 0.5 * g
        if kind == "shear":
            pl = _plucks(u, rng, w, cfg["pluck_rate"]) * (shape > 0.2)
            if rng.random() < 0.5:
                top = top + pl
            else:
                bottom = bottom - pl
    top = np.minimum(top, bottom + 12.0)
    return top, bottom


def _min_piece_distance(pa, pb):
    """Smallest vertex distance between two lists of open-run polygons."""
    A = np.vstack([p["poly"] for p in pa]) if pa else None
    Bv = np.vstack([p["poly"] for p in pb]) if pb else None
    if A is None or Bv is None:
        return np.inf
    d, _ = cKDTree(A).query(Bv, k=1)
    return float(d.min())


def _build_crack(kind, L, w, center, theta, rng, cfg):
    """Build one crack object of the requested kind (may be empty)."""
    if kind == "shear":
        variant = str(rng.choice(["stepped", "layered", "echelon"], p=[0.45, 0.25, 0.30]))
    else:
        variant = "branched" if rng.random() < (0.35 if kind == "tensile" else 0.25) else "simple"
    cr = _Crack(kind, variant)
    slope_rms = rng.uniform(0.12, 0.35) if kind == "tensile" else rng.uniform(0.2, 0.45)
    zig = rng.uniform(0.0, 0.6) if kind == "tensile" else rng.uniform(0.4, 0.9)
    if variant == "echelon":
        alpha = math.radians(rng.uniform(12.0, 30.0)) * (1 if rng.random() < 0.5 else -1)
        ell = min(L, rng.uniform(25.0, 110.0))
        s_min = (1.2 * w + 3.5) / abs(math.sin(alpha))
        s = max(ell * math.cos(alpha) * rng.uniform(0.5, 1.1), s_min)
        nseg = int(np.clip(L / s, 2, 15))
        Lm = (nseg - 1) * s + 1.0
        um, Pm, Nm, thm = _smooth_path(center, theta, Lm, rng, bend=rng.uniform(0.02, 0.1))
        for k in range(nseg):
            uc = min(Lm, max(0.0, k * s + rng.uniform(-0.1, 0.1) * s))
            ic = int(round(uc / (um[1] - um[0])))
            ic = min(max(ic, 0), len(um) - 1)
            c = Pm[ic] + Nm[ic] * rng.uniform(-1.0, 1.0)
            Lk = max(20.0, ell * rng.uniform(0.7, 1.3))
            u, P, N, th = _smooth_path(c, thm[ic] + alpha, Lk, rng, bend=0.05)
            r = _roughness(u, rng, rng.uniform(0.08, 0.25), rng.uniform(0.0, 0.4))
            g = w * rng.uniform(0.6, 1.1) * _tip_shape(u, Lk, rng.uniform(0.5, 0.9)) * _modulation(u, rng, 0.15, 0.0)
            pcs = open_runs(P, N, r + 0.5 * g, r - 0.5 * g)
            if pcs and _min_piece_distance(cr.pieces, pcs) >= 2.5:
                cr.pieces.extend(pcs)
        return cr
    u, P, N, th = _smooth_path(center, theta, L, rng, bend=rng.uniform(0.03, 0.25))
    r = _roughness(u, rng, slope_rms, zig)
    if variant == "layered":
        nl = int(rng.integers(2, 4))
        prev_top = None
        offset = 0.0
        for k in range(nl):
            if k == 0:
                rk, a0, a1 = r, 0.0, 1.0
            else:
                rho = rng.uniform(0.4, 0.9)
                rk = rho * r + math.sqrt(1 - rho * rho) * _roughness(u, rng, slope_rms, zig)
                a0, a1 = rng.uniform(0.0, 0.3), rng.uniform(0.7, 1.0)
            sub = (u >= a0 * L) & (u <= a1 * L)
            us = u[sub] - a0 * L
            top = rk.copy()
            bot = rk.copy()
            if sub.sum() >= 8:
                t_, b_ = _profile("shear", us, us[-1], w * (1.0 if k == 0 else rng.uniform(0.5, 0.9)), rk[sub], rng, cfg)
                top[sub], bot[sub] = t_, b_
            if prev_top is not None:
                offset += float(np.max(prev_top - bot)) + rng.uniform(2.5, 6.0)
            for _ in range(6):
                pcs = open_runs(P, N, top + offset, bot + offset)
                if not pcs or _min_piece_distance(cr.pieces, pcs) >= 2.2:
                    break
                offset += 1.5
            else:
                pcs = []
            for pc in pcs:
                cr.holes.extend(_fragments(P, N, u, top + offset, bot + offset, pc, rng, cfg["frag_max"]))
            cr.pieces.extend(pcs)
            prev_top = top + offset
        return cr
    top, bot = _profile(kind, u, L, w, r, rng, cfg)
    pcs = open_runs(P, N, top, bot)
    cr.pieces.extend(pcs)
    if kind == "shear":
        for pc in pcs:
            cr.holes.extend(_fragments(P, N, u, top, bot, pc, rng, cfg["frag_max"]))
    if variant == "branched" and L > 80:
        for _ in range(int(rng.integers(1, 3))):
            ib = int(rng.uniform(0.25, 0.75) * (len(u) - 1))
            gap_b = float(top[ib] - bot[ib])
            if gap_b < 0.8:
                continue
            anchor = P[ib] + 0.5 * (top[ib] + bot[ib]) * N[ib]
            hb = th[ib] + math.radians(rng.uniform(15.0, 40.0)) * (1 if rng.random() < 0.5 else -1)
            Lb = float(np.clip(L * rng.uniform(0.15, 0.5), 30.0, 700.0))
            ub, Pb, Nb, _ = _smooth_path(anchor, hb, Lb, rng, bend=rng.uniform(0.02, 0.1), at="start")
            rb = _roughness(ub, rng, slope_rms, zig) * (ub / (ub + 6.0))
            rb -= rb[0]
            gb = gap_b * rng.uniform(0.5, 0.85) * (1.0 - ub / Lb) ** rng.uniform(0.4, 0.8) * _modulation(ub, rng, 0.2, 0.0)
            cr.pieces.extend(open_runs(Pb, Nb, rb + 0.5 * gb, rb - 0.5 * gb))
    return cr


# =============================================================================
# Crack population and pores
# =============================================================================
def _disk(radius):
    k = 2 * radius + 1
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))


def _violates(points, forbidden, H, W):
    x = points[:, 0]
    y = points[:, 1]
    ok = (x >= 0) & (x < W) & (y >= 0) & (y < H)
    if not ok.any():
        return False
    return bool(forbidden[y[ok].astype(np.int64), x[ok].astype(np.int64)].any())


class _Canvas:
    """Accumulates void coverage, per-type truth and the exclusion mask."""

    def __init__(self, H, W, Hc):
        self.H, self.W, self.Hc = H, W, Hc
        self.cov = {k: np.zeros((H, W), np.float32) for k in KINDS}
        self.pore = np.zeros((H, W), np.float32)
        self.forbidden = np.zeros((H, W), bool)
        self.crack_id = np.zeros((H, W), np.int32)
        self.kernel = _disk(int(round(SEP_PX)) + 1)
        self.pad = int(round(SEP_PX)) + 3

    def window(self, polys):
        allp = np.vstack(polys)
        x0 = int(math.floor(allp[:, 0].min())) - self.pad
        x1 = int(math.ceil(allp[:, 0].max())) + self.pad + 1
        y0 = int(math.floor(allp[:, 1].min())) - self.pad
        y1 = int(math.ceil(allp[:, 1].max())) + self.pad + 1
        x0, y0 = max(x0, 0), max(y0, 0)
        x1, y1 = min(x1, self.W), min(y1, self.Hc)
        return x0, y0, x1, y1

    def add(self, polys, holes, target, ident=0):
        """Rasterise and add a void object; returns its in-region area."""
        x0, y0, x1, y1 = self.window(polys)
        if x1 <= x0 or y1 <= y0:
            return 0.0
        c = rasterize_coverage(polys, holes, x0, y0, x1 - x0, y1 - y0)
        target[y0:y1, x0:x1] += c
        m = c > 0
        if ident:
            self.crack_id[y0:y1, x0:x1][m] = ident
        self.forbidden[y0:y1, x0:x1] |= cv2.dilate(m.astype(np.uint8), self.kernel) > 0
        return float(c.sum(dtype=np.float64))


def _place_cracks(cv, rng, info):
    """Plan and place the crack population; returns per-crack records."""
    W, Hc = cv.W, cv.Hc
    A = W * Hc
    mp = A / 1e6
    density = _logu(rng, 6.0, 35.0)
    n_plan = max(3, int(round(density * mp)))
    frac = _logu(rng, 0.005, 0.055)
    Lmax = min(1500.0, 0.9 * math.hypot(W, Hc))
    gam = rng.uniform(0.8, 1.7)
    uu = rng.random(n_plan)
    a_, b_ = 30.0 ** (1 - gam), Lmax ** (1 - gam)
    lengths = (a_ + uu * (b_ - a_)) ** (1.0 / (1 - gam)) if abs(gam - 1) > 1e-3 else 30.0 * (Lmax / 30.0) ** uu
    lengths = np.sort(lengths)[::-1]
    pk = rng.dirichlet([1.3, 1.3, 0.8])
    roll = rng.random()
    if roll < 0.08:  # sometimes no shear cracks at all (P = NaN)
        pk[1] = 0.0
    elif roll < 0.12:  # sometimes no tensile cracks (P = 0)
        pk[0] = 0.0
    pk = pk / pk.sum()
    kinds = rng.choice(3, size=n_plan, p=pk)
    e = np.exp(rng.normal(0, 0.35, n_plan))
    kappa = np.array([0.55, 0.35, 0.5])[kinds]
    wrel = (lengths / 100.0) ** 0.3 * e
    w0 = float(np.clip(frac * A / max(float(np.sum(kappa * wrel * lengths)), 1.0), 0.9, 7.0))
    widths = np.clip(w0 * wrel, 1.0, 10.0)
    n_sets = int(rng.integers(1, 4))
    set_mu = rng.uniform(0, math.pi, n_sets)
    set_kappa = np.array([_logu(rng, 0.5, 8.0) for _ in range(n_sets)])
    cfg = dict(bridges_per_px=_logu(rng, 0.0003, 0.004), pluck_rate=_logu(rng, 0.002, 0.02),
               frag_max=int(rng.integers(0, 7)))
    info.update(crack_density_per_mp=round(density, 2), planned_cracks=n_plan, target_area_frac=round(frac, 5),
                length_exponent=round(gam, 3), kind_probs=[round(float(p), 3) for p in pk],
                opening_scale_px=round(w0, 3), crack_sets_deg=[round(math.degrees(m), 1) for m in set_mu],
                crack_sets_kappa=[round(float(k), 2) for k in set_kappa], **{k: (round(v, 5) if isinstance(v, float) else v) for k, v in cfg.items()})
    records = []
    area_tot = 0.0
    plan = list(zip(lengths, widths, kinds))
    extra = 0
    i = 0
    while i < len(plan):
        L, w, kidx = plan[i]
        i += 1
        if area_tot > 0.05 * A:
            break
        kind = KINDS[int(kidx)]
        placed = False
        for att in range(7):
            Lt = max(30.0, L * (0.8 ** max(0, att - 1)))
            cx, cy = rng.uniform(0, W), rng.uniform(0, Hc)
            if cv.forbidden[int(cy), int(cx)]:
                continue
            if rng.random() < 0.15:
                th = rng.uniform(0, math.pi)
            else:
                s = int(rng.integers(n_sets))
                th = float(rng.vonmises(set_mu[s], set_kappa[s]))
            cr = _build_crack(kind, Lt, float(w), (cx, cy), th, rng, cfg)
            if not cr.pieces:
                continue
            pts = np.vstack([p["poly"] for p in cr.pieces] + [p["mid"] for p in cr.pieces])
            if _violates(pts, cv.forbidden, Hc, W):
                continue
            polys = [p["poly"] for p in cr.pieces]
            ident = len(records) + 1
            area = cv.add(polys, cr.holes, cv.cov[kind], ident)
            length = sum(polyline_length_in_rect(p["mid"], 0.0, 0.0, float(W), float(Hc)) for p in cr.pieces)
            records.append(dict(kind=kind, variant=cr.variant, area=area, length=length, n_traces=len(cr.pieces),
                                n_fragments=len(cr.holes), L_nominal=float(Lt), w_nominal=float(w)))
            area_tot += area
            placed = True
            break
        if i == len(plan) and area_tot < 0.0035 * A and extra < 60:
            extra += 1
            kk = int(rng.choice(3, p=pk))
            plan.append((float(rng.uniform(60, Lmax)), float(np.clip(w0 * 1.5, 1.5, 8.0)), kk))
        _ = placed
    return records


def _place_pores(cv, rng, info, rock):
    """Compact, roundish pores (void but not cracks), kept off the cracks."""
    dmin, dmax, rmax = ROCKS[rock]["pores"]
    dens = rng.uniform(dmin, dmax) if rng.random() < 0.85 else 0.0
    n = int(rng.poisson(dens * cv.W * cv.Hc / 1e6))
    placed = 0
    for _ in range(n):
        R = _logu(rng, 1.5, max(2.0, rmax))
        cx, cy = rng.uniform(0, cv.W), rng.uniform(0, cv.Hc)
        if cv.forbidden[int(cy), int(cx)]:
            continue
        asp = rng.uniform(1.0, 1.6)
        poly = _ccw(_blob_poly(cx, cy, R * math.sqrt(asp), R / math.sqrt(asp), rng.uniform(0, math.pi), rng,
                               rough=0.12, nv=int(np.clip(2 * math.pi * R, 12, 120))))
        if _violates(poly, cv.forbidden, cv.Hc, cv.W):
            continue
        cv.add([poly], [], cv.pore)
        placed += 1
    info.update(pore_density_per_mp=round(float(dens), 2), n_pores=placed, pore_rmax_px=rmax)


# =============================================================================
# Information bar
# =============================================================================
def _nice_scale(hfw_um, rng):
    target = hfw_um * rng.uniform(0.12, 0.28)
    exp10 = 10.0 ** math.floor(math.log10(target))
    best = max(v * exp10 for v in (1, 2, 5, 10) if v * exp10 <= target)
    return best


def _fmt_um(v):
    return f"{v:g}"


def _put_text(mask, text, org, font, scale, thick):
    """cv2.putText on a uint8 mask, drawing 'µ' as a 'u' with a descender."""
    plain = text.replace("µ", "u")
    cv2.putText(mask, plain, org, font, scale, 255, thick, cv2.LINE_AA)
    i = text.find("µ")
    while i >= 0:
        (wp, _), _ = cv2.getTextSize(plain[:i], font, scale, thick)
        (wu, hu), _ = cv2.getTextSize("u", font, scale, thick)
        x = org[0] + wp + max(1, int(0.18 * wu))
        cv2.line(mask, (x, org[1] - hu // 2), (x, org[1] + int(0.4 * hu)), 255, thick, cv2.LINE_AA)
        i = text.find("µ", i + 1)


def _info_bar(H, W, bh, ps, rng):
    """Draw an SEM information bar.

    Returns
    -------
    fg : ndarray
        float32 ``(bh, W)`` foreground (text / scale bar) alpha in [0, 1].
    band_level, fg_level : float
        Band and foreground levels as fractions of full scale.
    meta : dict
        Text / scale-bar settings.
    """
    style = str(rng.choice(["fei", "zeiss", "jeol"]))
    if style == "zeiss" and rng.random() < 0.6:
        band, fgl = rng.uniform(0.55, 0.85), 0.0
    else:
        band, fgl = rng.uniform(0.0, 0.15) if rng.random() < 0.7 else 0.0, rng.uniform(0.85, 1.0)
    hfw = W * ps
    sb_um = _nice_scale(hfw, rng)
    sb_px = int(round(sb_um / ps))
    unit = "µm" if rng.random() < 0.5 else "um"
    label = f"{_fmt_um(sb_um)} {unit}"
    kv = float(rng.choice([3, 5, 10, 12, 15, 20, 25, 30]))
    wd = rng.uniform(4.0, 16.0)
    mag = 127000.0 / hfw
    det = str(rng.choice(["BSE", "CBS", "BSD", "vCD", "ETD", "SE", "InLens", "QBSD"]))
    date = f"{int(rng.integers(2009, 2025))}-{int(rng.integers(1, 13)):02d}-{int(rng.integers(1, 29)):02d}"
    tm = f"{int(rng.integers(0, 24)):02d}:{int(rng.integers(0, 60)):02d}:{int(rng.integers(0, 60)):02d}"
    font = int(rng.choice([cv2.FONT_HERSHEY_SIMPLEX, cv2.FONT_HERSHEY_DUPLEX, cv2.FONT_HERSHEY_PLAIN]))
    mask = np.zeros((bh, W), np.uint8)
    (_, h1), _ = cv2.getTextSize("Hg", font, 1.0, 1)
    two_rows = style != "jeol"
    th = bh * (0.27 if two_rows else 0.38)
    scale = th / h1
    thick = max(1, int(round(scale * 1.4)))
    sb_h = max(3, int(round(bh * rng.uniform(0.1, 0.2))))
    if style == "jeol":
        txt = f"{kv:g}kV  X{mag:,.0f}  " if rng.random() < 0.5 else f"{kv:g}kV  X{mag:,.0f}  WD{wd:.0f}mm  {det}  "
        y = int(bh * 0.68)
        x = int(W * 0.03)
        _put_text(mask, txt, (x, y), font, scale, thick)
        (tw, _), _ = cv2.getTextSize(txt, font, scale, thick)
        xb = x + tw + 10
        if xb + sb_px + 200 > W:
            xb = max(10, W - sb_px - 220)
        cv2.rectangle(mask, (xb, y - sb_h), (xb + sb_px, y), 255, -1)
        _put_text(mask, label, (xb + sb_px + 12, y), font, scale, thick)
        _put_text(mask, date, (int(W * 0.8), y), font, scale * 0.8, thick)
    else:
        rows = [[f"HV {kv:.2f} kV", f"WD {wd:.1f} mm", f"mag {mag:,.0f} x", f"det {det}"],
                [f"HFW {hfw:.1f} {unit}", date, tm, f"pixel {ps * 1000:.1f} nm" if rng.random() < 0.5 else "Mode BSE"]]
        y1, y2 = int(bh * 0.40), int(bh * 0.82)
        colw = int(W * 0.14)
        x = int(W * 0.015)
        for c in range(4):
            for row, y in zip(rows, (y1, y2)):
                t = row[c]
                s = scale
                while cv2.getTextSize(t, font, s, thick)[0][0] > colw - 6 and s > 0.2:
                    s *= 0.9
                _put_text(mask, t, (x + c * colw, y), font, s, thick)
        xb0 = int(W * 0.63)
        room = W - xb0 - 10
        if sb_px > room:
            sb_px = room
        xb = xb0 + (room - sb_px) // 2
        cv2.rectangle(mask, (xb, int(bh * 0.62)), (xb + sb_px, int(bh * 0.62) + sb_h), 255, -1)
        (lw, _), _ = cv2.getTextSize(label.replace("µ", "u"), font, scale, thick)
        _put_text(mask, label, (xb + sb_px // 2 - lw // 2, int(bh * 0.5)), font, scale, thick)
        if rng.random() < 0.6:
            cv2.line(mask, (0, 0), (W - 1, 0), 255, 1)
    meta = dict(bar_style=style, bar_level=round(float(band), 3), bar_fg_level=round(float(fgl), 3),
                scalebar_um=float(sb_um), scalebar_px=int(sb_px), scalebar_label=label, mag=round(mag, 1))
    return mask.astype(np.float32) / 255.0, float(band), float(fgl), meta


# =============================================================================
# Main entry point
# =============================================================================
def make_image(shape=(768, 1024), seed=0, return_layers=False):
    """Generate one synthetic SEM rock micrograph with exact crack truth.

    Parameters
    ----------
    shape : tuple of int
        ``(H, W)`` of the output image.
    seed : int
        Seed for ``numpy.random.default_rng``; output is deterministic.
    return_layers : bool
        Also return ``background`` (float32 B incl. rims/illumination),
        ``void_cov`` (crack + pore coverage), ``clean`` (grey before blur and
        noise) and ``void_grey``, for verification.

    Returns
    -------
    dict
        ``image`` (uint8 or uint16), ``pixel_size_um``, ``area_px``,
        ``length_px``, ``P``, ``n_cracks``, ``tensile_area_px``,
        ``shear_area_px``, ``has_bar``, ``crack_mask`` (coverage >= 0.5),
        ``settings``; additionally ``coverage`` (float32 crack coverage),
        ``mixed_area_px``, ``bar_rows`` and ``cracks`` (per-crack records).
    """
    H, W = int(shape[0]), int(shape[1])
    rng = np.random.default_rng(seed)
    st = {"seed": int(seed), "shape": [H, W]}
    ps = _logu(rng, 0.05, 2.0)
    has_bar = bool(rng.random() < 0.6)
    bh = int(round(H * rng.uniform(0.06, 0.10))) if has_bar else 0
    Hc = H - bh
    rock = str(rng.choice(list(ROCKS), p=[0.26, 0.22, 0.17, 0.2, 0.15]))
    st.update(pixel_size_um=round(ps, 5), has_bar=has_bar, bar_rows=bh)
    # ---------------------------------------------------------------- background
    B, binfo = _render_background(H, W, rng, ps, rock)
    st.update(binfo)
    # ---------------------------------------------------------------- voids
    cv = _Canvas(H, W, Hc)
    records = _place_cracks(cv, rng, st)
    _place_pores(cv, rng, st, rock)
    crack_cov = cv.cov["tensile"] + cv.cov["shear"] + cv.cov["mixed"]
    void_cov = np.clip(crack_cov + cv.pore, 0.0, 1.0)
    # ---------------------------------------------------------------- SE-like bright rims
    se = st["se_look"]
    rim_amp = rng.uniform(0.15, 0.4) if se else (rng.uniform(0.0, 0.12) if rng.random() < 0.6 else 0.0)
    rim_sig = rng.uniform(0.8, 2.5)
    if rim_amp > 0:
        rim = np.clip(3.0 * (cv2.GaussianBlur(void_cov, (0, 0), rim_sig) - void_cov), 0.0, 1.0)
        B = B + rim_amp * rim
    # illumination gradient / vignetting
    gx, gy = rng.uniform(-0.12, 0.12, 2)
    vig = rng.uniform(0.0, 0.18)
    yy = (np.arange(H, dtype=np.float32) / H - 0.5)[:, None]
    xx = (np.arange(W, dtype=np.float32) / W - 0.5)[None, :]
    cx_, cy_ = rng.uniform(-0.2, 0.2, 2)
    illum = 1.0 + gx * xx + gy * yy - vig * ((xx - cx_) ** 2 + (yy - cy_) ** 2) * 2.0
    B = B * illum.astype(np.float32)
    void_grey = float(rng.uniform(0.0, 0.05))
    B = np.maximum(B, np.float32(void_grey + 0.06))  # void stays darker than any rock
    st.update(rim_amp=round(rim_amp, 4), rim_sigma=round(rim_sig, 3), illum_gradient=[round(float(gx), 4), round(float(gy), 4)],
              vignetting=round(vig, 4), void_grey=round(void_grey, 4))
    clean = B * (1.0 - void_cov) + np.float32(void_grey) * void_cov
    # ---------------------------------------------------------------- acquisition
    blur = rng.uniform(0.5, 1.5)
    S = cv2.GaussianBlur(clean, (0, 0), blur)
    lag = rng.uniform(0.45, 0.9) if rng.random() < 0.4 else 1.0
    if lag < 1.0:
        b_, a_ = [lag], [1.0, -(1.0 - lag)]
        zi = lfilter_zi(b_, a_)[None, :] * S[:, :1]
        S = lfilter(b_, a_, S, axis=1, zi=zi)[0].astype(np.float32)
    ne = _logu(rng, 40.0, 450.0)
    read = rng.uniform(0.002, 0.02)
    S = rng.poisson(np.clip(S, 0, None) * ne).astype(np.float32) / np.float32(ne)
    S += rng.normal(0.0, read, S.shape).astype(np.float32)
    line_sig = rng.uniform(0.0, 0.015) if rng.random() < 0.6 else 0.0
    line_phi = rng.uniform(0.0, 0.9)
    e = rng.normal(0, line_sig, H)
    off = lfilter([1.0], [1.0, -line_phi], e) * math.sqrt(1 - line_phi ** 2)
    gain = 1.0 + rng.normal(0, rng.uniform(0.0, 0.01), H)
    n_glitch = int(rng.choice([0, 0, 0, 1, 2, 3]))
    for _ in range(n_glitch):
        off[int(rng.integers(0, H))] += rng.choice([-1, 1]) * rng.uniform(0.03, 0.1)
    S = S * gain[:, None].astype(np.float32) + off[:, None].astype(np.float32)
    st.update(blur_sigma=round(blur, 3), detector_lag=round(lag, 3), electrons_at_unit=round(ne, 1),
              read_noise=round(read, 4), scanline_sigma=round(line_sig, 4), scanline_ar=round(line_phi, 3),
              scanline_glitches=n_glitch)
    # ---------------------------------------------------------------- output mapping
    bits16 = bool(rng.random() < 0.25)
    s_lo = void_grey - rng.uniform(0.0, 0.04)
    s_hi = rng.uniform(0.62, 1.0)
    if bits16:
        lo = rng.uniform(200, 6000)
        hi = lo + rng.uniform(2500, 30000)
        full = 65535.0
    else:
        lo = rng.uniform(0, 45)
        hi = rng.uniform(170, 255)
        full = 255.0
    out = lo + (hi - lo) * (S - s_lo) / (s_hi - s_lo)
    quant = 1
    if bits16 and rng.random() < 0.4:
        quant = int(rng.choice([4, 16]))
    elif (not bits16) and rng.random() < 0.1:
        quant = int(rng.choice([2, 4]))
    out = np.clip(np.round(out / quant) * quant, 0, full)
    img = out.astype(np.uint16 if bits16 else np.uint8)
    st.update(bit_depth=16 if bits16 else 8, out_lo=round(float(lo), 1), out_hi=round(float(hi), 1),
              signal_lo=round(float(s_lo), 4), signal_hi=round(float(s_hi), 4), quant_step=quant)
    if has_bar:
        fg, band, fgl, meta = _info_bar(H, W, bh, ps, rng)
        val = band * full * (1 - fg) + fgl * full * fg
        img[Hc:] = np.clip(np.round(val), 0, full).astype(img.dtype)
        st.update(meta)
    jpeg_q = 0
    if (not bits16) and rng.random() < 0.25:
        jpeg_q = int(rng.integers(60, 93))
        ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, jpeg_q])
        img = cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE)
    st["jpeg_quality"] = jpeg_q
    # ---------------------------------------------------------------- truth
    cov_t = float(cv.cov["tensile"].sum(dtype=np.float64))
    cov_s = float(cv.cov["shear"].sum(dtype=np.float64))
    cov_m = float(cv.cov["mixed"].sum(dtype=np.float64))
    area = float(crack_cov.sum(dtype=np.float64))
    length = float(sum(r["length"] for r in records))
    n_cracks = int(sum(1 for r in records if r["area"] >= 1.0))
    P = cov_t / cov_s if cov_s > 0 else float("nan")
    st["n_cracks_by_kind"] = {k: int(sum(1 for r in records if r["kind"] == k and r["area"] >= 1.0)) for k in KINDS}
    st["n_cracks_by_variant"] = {}
    for r in records:
        if r["area"] >= 1.0:
            st["n_cracks_by_variant"][r["variant"]] = st["n_cracks_by_variant"].get(r["variant"], 0) + 1
    st["crack_area_frac"] = round(area / (W * Hc), 5)
    res = dict(image=img, pixel_size_um=float(ps), area_px=area, length_px=length, P=float(P), n_cracks=n_cracks,
               tensile_area_px=cov_t, shear_area_px=cov_s, mixed_area_px=cov_m, has_bar=has_bar,
               crack_mask=crack_cov >= 0.5, coverage=crack_cov, bar_rows=bh, settings=st, cracks=records)
    if return_layers:
        res.update(background=B, void_cov=void_cov, clean=clean, void_grey=void_grey,
                   crack_id=cv.crack_id, pore_cov=cv.pore)
    return res
