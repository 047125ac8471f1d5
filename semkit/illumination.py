"""Stage 2: flatten uneven illumination (background removal).

The illumination field is smooth and multiplicative (a BSE detector sees one side of the
specimen darker). It is estimated on a shrunken copy of the image, then divided out.
"""
from __future__ import annotations

import numpy as np

from . import config

__all__ = ["illumination_field", "flatten_illumination"]


def _shrink(image, size):
    """Shrink by an integer factor (block mean; OpenCV's fast INTER_AREA path) so that the
    long side has about ``size`` px. Returns the float32 small image and the factor."""
    import cv2
    h, w = image.shape
    f = int(np.ceil(max(h, w) / float(size)))
    if f <= 1:
        return image.astype(np.float32), 1
    a = image if image.dtype in (np.uint8, np.uint16, np.float32) else image.astype(np.float32)
    a = np.ascontiguousarray(a[:h // f * f, :w // f * f])
    small = cv2.resize(a, (w // f, h // f), interpolation=cv2.INTER_AREA)
    return small.astype(np.float32), f


def _poly_terms(u, v, degree):
    return [u ** i * v ** j for i in range(degree + 1) for j in range(degree + 1 - i)]


def _phase_offsets(r, keep):
    """Log-grey level of the phase (mineral) each pixel belongs to: peaks of the residual
    histogram, each pixel assigned to the nearest. Without this, a region rich in a bright
    mineral would pass for a brightly lit one."""
    from .peaks import prominent_peaks, smooth_profile
    v = r[keep]
    lo, hi = np.percentile(v, [0.5, 99.5])
    if hi - lo < 0.1:  # phases differing by < ~10 % in grey are not told apart
        return np.zeros_like(r)
    h, e = np.histogram(v, bins=64, range=(lo, hi))
    hs = smooth_profile(h.astype(float), 1.5)
    pk = prominent_peaks(np.r_[0.0, hs, 0.0], 0.05 * hs.max())
    c = 0.5 * (e[1:] + e[:-1])[pk - 1]
    if c.size > 1:  # merge peaks closer than 0.05 in log grey (5 %)
        keep = np.r_[True, np.diff(c) > 0.05]
        c = c[keep]
    if c.size <= 1:
        return np.zeros_like(r)
    idx = np.argmin(np.abs(r[:, None] - c[None, :]), axis=1)
    return c[idx] - np.median(c)


def illumination_field(image, *, method="polynomial", degree=config.FLATTEN_POLY_DEGREE,
                       fit_size_px=config.FLATTEN_FIT_SIZE_PX):
    """Estimate the smooth multiplicative illumination field of an image.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image, cracks dark.
    method : {"polynomial", "gaussian"}
        ``polynomial``: least-squares fit of a 2-D polynomial of ``degree`` to log(grey) on
        the shrunken image, refitted without the dark outliers (cracks, pores) and with each
        pixel's mineral level (a peak of the residual histogram) taken out, so that a region
        rich in a bright mineral does not pass for a brightly lit one. ``gaussian``: grey
        closing (removes cracks)
        then a Gaussian of sigma ``FLATTEN_GAUSS_FRACTION`` x the short side (rolling-ball-like).
    degree : int
    fit_size_px : int
        Long side of the shrunken image used for the fit.

    Returns
    -------
    field : (M, N) ndarray of float32
        Relative illumination, max 1 (1 = the brightest part of the field).
    """
    import cv2
    img = np.asarray(image)
    h, w = img.shape
    small, _ = _shrink(img, fit_size_px)
    sh, sw = small.shape
    if method == "polynomial":
        yy, xx = np.mgrid[0:sh, 0:sw]
        u = (xx.ravel() + 0.5) / sw * 2 - 1
        v = (yy.ravel() + 0.5) / sh * 2 - 1
        a = np.column_stack(_poly_terms(u, v, degree))
        y = np.log(np.maximum(small.ravel().astype(np.float64), 1.0))
        keep = np.ones(y.size, bool)
        offset = np.zeros(y.size)
        for it in range(5):  # normal equations: 6 unknowns, a few thousand rows
            ak = a[keep]
            coef = np.linalg.solve(ak.T @ ak + 1e-9 * np.eye(a.shape[1]),
                                   ak.T @ (y - offset)[keep])
            r = y - a @ coef
            if it >= 1:  # the grain mosaic: subtract each pixel's phase level (log grey)
                offset = _phase_offsets(r, keep)
                r = r - offset
            s = 1.4826 * np.median(np.abs(r[keep] - np.median(r[keep]))) + 1e-6
            nxt = r > -2.5 * s
            if nxt.sum() < 4 * a.shape[1]:  # a flat, noiseless image: keep the last fit
                break
            keep = nxt
        # evaluate at full resolution, separably: sum_j (sum_i c_ij u^i) (x) v^j
        uf = ((np.arange(w) + 0.5) / w * 2 - 1).astype(np.float32)
        vf = ((np.arange(h) + 0.5) / h * 2 - 1).astype(np.float32)
        logf = np.zeros((h, w), np.float32)
        k = 0
        rows = {}
        for i in range(degree + 1):
            for j in range(degree + 1 - i):
                rows[j] = rows.get(j, 0.0) + np.float32(coef[k]) * uf ** i
                k += 1
        for j, row in rows.items():
            logf += np.outer(vf ** j, row)
        logf -= logf.max()
        field = np.exp(logf, out=logf)
    elif method == "gaussian":
        ksz = max(3, int(round(min(sh, sw) * 0.03)) * 2 + 1)
        closed = cv2.morphologyEx(small, cv2.MORPH_CLOSE, np.ones((ksz, ksz), np.uint8))
        sig = config.FLATTEN_GAUSS_FRACTION * min(sh, sw)
        bg = cv2.GaussianBlur(closed, (0, 0), sig, borderType=cv2.BORDER_REFLECT)
        bg = cv2.resize(bg, (w, h), interpolation=cv2.INTER_LINEAR).astype(np.float64)
        bg = np.maximum(bg, 1e-6)
        field = bg / bg.max()
    else:
        raise ValueError(f"method: expected 'polynomial' or 'gaussian', got {method!r}")
    return field.astype(np.float32, copy=False)


def flatten_illumination(image, *, method="polynomial", degree=config.FLATTEN_POLY_DEGREE):
    """Divide out the illumination field (stage 2).

    Parameters
    ----------
    image : (M, N) ndarray
    method, degree
        See :func:`illumination_field`.

    Returns
    -------
    flat : (M, N) ndarray of float32
        ``image / field``: grey levels as if the whole field were lit like its brightest part.
    field : (M, N) ndarray of float32

    Examples
    --------
    >>> ramp = np.linspace(0.6, 1.0, 64)[None, :] * np.full((48, 64), 200.0)
    >>> flat, field = flatten_illumination(ramp)
    >>> bool(np.ptp(flat) / 200 < 0.02)
    True
    """
    field = illumination_field(image, method=method, degree=degree)
    flat = np.asarray(image, np.float32) / np.maximum(field, 1e-3)
    return flat, field
