"""The sample region: where the sample is, as opposed to a black or white surround (the
corners outside a round core, a mount, an empty stage) and the SEM data bar.

``--roi auto`` (:func:`find_sample_region`): the data bar (:func:`semkit.databar.find_data_bar`)
is cropped away by the analysis; the surround is the set of pixels within a tolerance of one
extreme grey (near the darkest or the brightest) that are connected to the image border,
found only when it holds at least :data:`~semkit.config.SURROUND_MIN_BORDER_FRACTION` of the
border. The region is the rest, holes filled, shrunk by :data:`~semkit.config.ROI_MARGIN_PX`
(the blurred edge of the sample is dark against a black surround and would read as a crack).
``--roi MASK.png``: a user mask (non-zero = sample); ``--roi none``: the whole image.

Pixels outside the region are never cracks and count in no per-area figure. Before the
threshold, they are filled with the normalised-convolution mean of the region around them
(:func:`fill_outside`), so the surround is not a dark phase of the histogram.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from . import config
from .errors import InputError

__all__ = ["SampleRegion", "find_sample_region", "read_roi_mask", "fill_outside",
           "parse_roi"]


@dataclasses.dataclass
class SampleRegion:
    """The sample region of one (cropped) image.

    Attributes
    ----------
    mask : (M, N) ndarray of bool
        True inside the sample.
    kind : str
        ``full`` (no surround found), ``surround`` (black or white surround removed),
        ``user`` (a mask file) or ``none`` (``--roi none``).
    fraction : float
        Share of the image inside.
    ok : bool
        False when the region is below :data:`~semkit.config.ROI_MIN_FRACTION` of the image.
    note : str
    """

    mask: np.ndarray
    kind: str
    fraction: float
    ok: bool = True
    note: str = ""


def parse_roi(value):
    """``auto`` | ``none`` | a mask file path; returns the checked value."""
    v = "auto" if value is None else str(value)
    if v in ("auto", "none"):
        return v
    import pathlib
    if not pathlib.Path(v).is_file():
        raise InputError(f"roi: expected auto, none or a mask image file, got {v!r}")
    return v


def _finish(mask, kind, note=""):
    frac = float(mask.mean())
    ok = frac >= config.ROI_MIN_FRACTION
    if not ok:
        note = "; ".join(t for t in (note, f"sample region only {frac:.0%} of the image") if t)
    return SampleRegion(mask, kind, frac, ok, note)


def find_sample_region(image, *, noise=None):
    """Find the sample inside a (data-bar-free) image: everything but a flat surround.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image, data bar already cropped.
    noise : float, optional
        Pixel-noise sigma (default :func:`semkit.threshold.noise_sigma`).

    Returns
    -------
    region : SampleRegion

    Examples
    --------
    >>> yy, xx = np.mgrid[:100, :100]
    >>> img = np.where((yy - 50) ** 2 + (xx - 50) ** 2 < 45 ** 2, 120, 2).astype(np.uint8)
    >>> r = find_sample_region(img); r.kind, round(r.fraction, 2)
    ('surround', 0.58)
    """
    import cv2

    from .threshold import noise_sigma
    a = np.asarray(image, np.float32)
    h, w = a.shape
    full = np.ones(a.shape, bool)
    if h < 16 or w < 16:
        return _finish(full, "full")
    sn = noise_sigma(a) if noise is None else float(noise)
    lo, hi = float(a.min()), float(a.max())
    if hi <= lo:
        return _finish(full, "full")
    tol = max(config.SURROUND_TOL_SIGMAS * sn, config.SURROUND_TOL_FRACTION * (hi - lo))
    sm = cv2.GaussianBlur(a, (0, 0), 1.0)
    border = np.concatenate([sm[0], sm[-1], sm[1:-1, 0], sm[1:-1, -1]])
    best = None
    med = None
    for level in (lo, hi):
        cand_b = np.abs(border - level) <= tol
        if cand_b.mean() < config.SURROUND_MIN_BORDER_FRACTION:
            continue
        if med is None:  # the bulk's level, only needed once the border qualifies
            med = float(np.median(sm[::2, ::2]))
        if abs(level - med) < config.SURROUND_MIN_SEPARATION * tol:
            continue  # an extreme near the bulk of the image: no surround of its own
        frac_b = cand_b.mean()
        if best is None or frac_b > best[1]:
            best = (level, frac_b)
    if best is None:
        return _finish(full, "full")
    cand = np.abs(sm - best[0]) <= tol
    n, lab = cv2.connectedComponents(cand.view(np.uint8), connectivity=8)
    edge = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    keep = np.zeros(n, bool)
    keep[edge] = True
    keep[0] = False
    surround = keep[lab]
    from scipy import ndimage as ndi  # only with a surround (its import costs ~0.2 s)
    inside = ndi.binary_fill_holes(~surround)
    m = int(config.ROI_MARGIN_PX)
    if m > 0:
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * m + 1, 2 * m + 1))
        inside = cv2.erode(inside.view(np.uint8), k, borderType=cv2.BORDER_CONSTANT,
                           borderValue=1).view(bool)
    # drop slivers: keep components of at least 5 % of the largest
    n, lab, st, _ = cv2.connectedComponentsWithStats(inside.view(np.uint8), connectivity=8)
    if n > 2:
        big = st[1:, cv2.CC_STAT_AREA].max()
        keep = np.r_[False, st[1:, cv2.CC_STAT_AREA] >= 0.05 * big]
        inside = keep[lab]
    side = "black" if best[0] == lo else "white"
    return _finish(inside, "surround", f"{side} surround removed ({1 - inside.mean():.0%})")


def read_roi_mask(path, shape):
    """Read a user ROI mask (any image; non-zero = sample) of the image's shape."""
    from .io import read_image
    m = read_image(path) > 0
    if m.shape != tuple(shape):
        raise InputError(f"{path}: ROI mask is {m.shape[1]} x {m.shape[0]} px, the image "
                         f"{shape[1]} x {shape[0]}")
    return _finish(m, "user")


def fill_outside(image, mask, *, sigma_px=8.0):
    """Replace pixels outside ``mask`` by the normalised-convolution mean of the inside.

    Parameters
    ----------
    image : (M, N) ndarray
    mask : (M, N) ndarray of bool
        True inside the region.
    sigma_px : float
        Gaussian sigma of the normalised convolution, doubled until every outside pixel has
        support.

    Returns
    -------
    filled : (M, N) ndarray of float32
    """
    import cv2
    a = np.asarray(image, np.float32)
    m = np.asarray(mask, bool)
    if m.all() or not m.any():
        return a.copy()
    mf = m.astype(np.float32)
    out = a.copy()
    todo = ~m
    s = float(sigma_px)
    while todo.any() and s < 4 * max(a.shape):
        num = cv2.GaussianBlur(a * mf, (0, 0), s)
        den = cv2.GaussianBlur(mf, (0, 0), s)
        ok = todo & (den > 1e-3)
        out[ok] = num[ok] / den[ok]
        todo &= ~ok
        s *= 2
    if todo.any():
        out[todo] = float(np.median(a[m]))
    return out
