"""The sample region: where the sample is, as opposed to a black or white surround (the
corners outside a round core, a mount, an empty stage) and the SEM data bar.

``--roi auto`` (:func:`find_sample_region`): the data bar (:func:`semkit.databar.find_data_bar`)
is cropped away by the analysis; the surround is the set of pixels within a tolerance of one
extreme grey (near the darkest or the brightest) that are connected to the image border,
found only when it holds at least :data:`~semkit.config.SURROUND_MIN_BORDER_FRACTION` of the
border. The region is the rest, holes filled, shrunk by :data:`~semkit.config.ROI_MARGIN_PX`
(the blurred edge of the sample is dark against a black surround and would read as a crack).
Burned-in annotations (:func:`find_annotations`: a scale bar drawn on the image, its box and
its label, at exactly the darkest or brightest grey the pixel type holds) are left out too.
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

__all__ = ["SampleRegion", "find_sample_region", "find_annotations", "read_roi_mask",
           "without_no_data", "fill_outside", "parse_roi"]


@dataclasses.dataclass
class SampleRegion:
    """The sample region of one (cropped) image.

    Attributes
    ----------
    mask : (M, N) ndarray of bool
        True inside the sample.
    kind : str
        ``full`` (no surround found), ``surround`` (black or white surround removed),
        ``annotation`` (only burned-in annotations removed), ``user`` (a mask file),
        ``none`` (``--roi none``) or ``no_data`` (only the NaN or inf pixels of a float image
        left out).
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


def without_no_data(region, no_data):
    """``region`` less the pixels that hold no data (NaN or inf in a float image).

    Parameters
    ----------
    region : SampleRegion
    no_data : (M, N) ndarray of bool

    Returns
    -------
    SampleRegion
        Its kind is ``no_data`` where the region was the whole image (``full`` or ``none``);
        the note says how much of the image holds no data.
    """
    mask = region.mask & ~np.asarray(no_data, bool)
    kind = "no_data" if region.kind in ("full", "none") else region.kind
    note = f"{float(np.mean(no_data)):.0%} of the image holds no data (NaN or inf): left out"
    return _finish(mask, kind, "; ".join(t for t in (region.note, note) if t))


def find_annotations(image):
    """Burned-in annotations: scale bars, their boxes and labels drawn on the image.

    They are drawn at exactly the darkest or brightest grey the pixel type holds (0, or 255 /
    65535). A *box* is a component of one such grey whose bounding box's outline lies at least
    ``ANNOT_OUTLINE_FILL`` in it (a filled bar, or a frame with a label inside), at least
    ``ANNOT_MIN_THICK_PX`` thick and ``ANNOT_MIN_LENGTH_PX`` long, and at most
    ``ANNOT_MAX_SHARE`` of the image's width and height. The annotation is each box's bounding
    box with the extreme-grey components (the label's glyphs) whose own boxes lie within one
    box length of it, grown by 2 px (the drawing's antialiased edge). Rock does not draw an
    axis-aligned rectangle of one exact grey; a clipped crack, pore or surround is not one.
    Float images have no such grey: nothing is found.

    Parameters
    ----------
    image : (M, N) ndarray

    Returns
    -------
    mask : (M, N) ndarray of bool
        The annotations.
    n_boxes : int

    Examples
    --------
    >>> img = np.full((60, 80), 120, np.uint8); img[50:54, 40:75] = 0   # a scale bar
    >>> m, n = find_annotations(img); n, bool(m[52, 50]), bool(m[20, 20])
    (1, True, False)
    """
    import cv2
    a = np.asarray(image)
    out = np.zeros(a.shape, bool)
    if a.ndim != 2 or not np.issubdtype(a.dtype, np.integer):
        return out, 0
    h, w = a.shape
    boxes, parts = [], []
    for v in (0, np.iinfo(a.dtype).max):
        m = a == v
        if np.count_nonzero(m) < config.ANNOT_MIN_LENGTH_PX * config.ANNOT_MIN_THICK_PX:
            continue
        n, lab, st, _ = cv2.connectedComponentsWithStats(m.view(np.uint8), connectivity=8)
        x, y, bw, bh = (st[1:, k] for k in (cv2.CC_STAT_LEFT, cv2.CC_STAT_TOP,
                                            cv2.CC_STAT_WIDTH, cv2.CC_STAT_HEIGHT))
        parts.append(np.stack([x, y, bw, bh], axis=1))
        cand = np.flatnonzero((np.minimum(bw, bh) >= config.ANNOT_MIN_THICK_PX)
                              & (np.maximum(bw, bh) >= config.ANNOT_MIN_LENGTH_PX)
                              & (bw <= config.ANNOT_MAX_SHARE * w)
                              & (bh <= config.ANNOT_MAX_SHARE * h))
        for i in cand:
            sub = lab[y[i]:y[i] + bh[i], x[i]:x[i] + bw[i]] == i + 1
            outline = np.r_[sub[0], sub[-1], sub[1:-1, 0], sub[1:-1, -1]]
            if outline.mean() >= config.ANNOT_OUTLINE_FILL:
                boxes.append((x[i], y[i], bw[i], bh[i]))
    if not boxes:
        return out, 0
    parts = np.concatenate(parts)
    for x0, y0, bw0, bh0 in boxes:
        reach = max(bw0, bh0)
        lo_x, lo_y, hi_x, hi_y = x0 - reach, y0 - reach, x0 + bw0 + reach, y0 + bh0 + reach
        near = ((parts[:, 0] >= lo_x) & (parts[:, 1] >= lo_y)
                & (parts[:, 0] + parts[:, 2] <= hi_x) & (parts[:, 1] + parts[:, 3] <= hi_y))
        for px, py, pw, ph in np.concatenate([[(x0, y0, bw0, bh0)], parts[near]]):
            out[max(py - 2, 0):py + ph + 2, max(px - 2, 0):px + pw + 2] = True
    return out, len(boxes)


def find_sample_region(image, *, noise=None):
    """Find the sample inside a (data-bar-free) image: everything but a flat surround and
    burned-in annotations (:func:`find_annotations`).

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
    ('surround', 0.6)
    """
    mask, kind, note = _surround(image, noise)
    ann, n_boxes = find_annotations(image)
    if n_boxes and (ann & mask).any():
        mask = mask & ~ann
        kind = "annotation" if kind == "full" else kind
        note = "; ".join(t for t in (note, f"{n_boxes} burned-in annotation(s) left out (a "
                                     f"scale bar, its box or label: {ann.mean():.1%} of the "
                                     "image)") if t)
    return _finish(mask, kind, note)


def _surround(image, noise):
    """``(mask, kind, note)`` of :func:`find_sample_region` without the annotations."""
    import cv2

    from .threshold import noise_sigma
    a = np.asarray(image, np.float32)
    h, w = a.shape
    full = np.ones(a.shape, bool)
    if h < 16 or w < 16:
        return full, "full", ""
    sn = noise_sigma(a) if noise is None else float(noise)
    lo, hi = float(a.min()), float(a.max())
    if hi <= lo:
        return full, "full", ""
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
        return full, "full", ""
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
    return inside, "surround", f"{side} surround removed ({1 - inside.mean():.0%})"


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
