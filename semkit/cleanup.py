"""Stage 4: clean a crack mask without erasing thin cracks.

The ImageJ route (threshold, then *Despeckle* = 3 x 3 median on the binary) deletes 1-px cracks:
a one-pixel line has at most 3 dark pixels in any 3 x 3 window, so the median turns it white.
semkit instead denoises the grey image before thresholding (:func:`denoise`) and afterwards
removes only *isolated specks* — small compact objects (:func:`remove_specks`). The median
despeckle stays available (:func:`despeckle_median`, CLI ``--despeckle median``) for runs that
must match ImageJ.
"""
from __future__ import annotations

import numpy as np

from . import config

__all__ = ["denoise", "despeckle_median", "remove_specks", "remove_small_objects", "bridge_gaps",
           "fill_holes"]


def _cc(mask):
    import cv2
    return cv2.connectedComponentsWithStats(np.ascontiguousarray(mask, np.uint8), connectivity=8)


def denoise(image, *, sigma_px=config.DENOISE_SIGMA_PX):
    """Gaussian smoothing of the grey image (before thresholding); ``sigma_px = 0`` is a no-op.

    Returns
    -------
    smooth : (M, N) ndarray of float32
    """
    import cv2
    img = np.asarray(image, np.float32)
    if sigma_px <= 0:
        return img
    return cv2.GaussianBlur(img, (0, 0), sigma_px, borderType=cv2.BORDER_REFLECT)


def despeckle_median(mask):
    """ImageJ *Despeckle* on a binary mask: 3 x 3 median (erases 1-px-wide cracks).

    Examples
    --------
    >>> m = np.zeros((5, 7), bool); m[2, :] = True
    >>> int(despeckle_median(m).sum())
    0
    """
    import cv2
    return cv2.medianBlur(np.ascontiguousarray(mask, np.uint8) * 255, 3) > 0


def remove_specks(mask, *, max_side_px=config.SPECK_MAX_SIDE_PX,
                  max_area_px=config.SPECK_MAX_AREA_PX):
    """Remove isolated specks: objects whose bounding box fits in ``max_side_px`` on both sides
    and whose area is at most ``max_area_px``. Elongated thin objects (cracks) are kept.

    Examples
    --------
    >>> m = np.zeros((20, 20), bool); m[2, 2:4] = True; m[10, 1:19] = True
    >>> int(remove_specks(m).sum())
    18
    """
    from ._kernels import lookup
    from .measure import label_cracks, object_moments
    lab, n = label_cracks(mask)
    area, _, _, _, _, _, bw, bh = object_moments(lab, n)
    drop = (bw <= max_side_px) & (bh <= max_side_px) & (area <= max_area_px)
    drop[0] = True
    return lookup(~drop, lab)


def remove_small_objects(mask, *, min_area_px):
    """Remove 8-connected objects with fewer than ``min_area_px`` pixels."""
    from ._kernels import lookup
    from .measure import label_cracks
    if min_area_px <= 1:
        return np.asarray(mask, bool).copy()
    lab, n = label_cracks(mask)
    area = np.bincount(lab.ravel(), minlength=n + 1)
    keep = area >= min_area_px
    keep[0] = False
    return lookup(keep, lab)


def fill_holes(mask, *, max_hole_px=None):
    """Fill background regions enclosed by a crack (4-connected holes not touching the border).

    Parameters
    ----------
    mask : (M, N) bool
    max_hole_px : int, optional
        Fill only holes up to this area; None fills all (ImageJ *Fill Holes*), which also
        fills a whole grain ringed by cracks.

    Examples
    --------
    >>> m = np.zeros((7, 7), bool); m[1:6, 1:6] = True; m[3, 3] = False
    >>> bool(fill_holes(m)[3, 3])
    True
    """
    import cv2

    from ._kernels import lookup
    m = np.asarray(mask, bool)
    if not m.any():
        return m.copy()
    if max_hole_px is None:
        roi = np.ones(m.shape, bool)
    else:  # a hole of area A lies within sqrt(A / pi) + 1 px of its rim: look only there
        r = int(np.sqrt(max_hole_px / np.pi)) + 2
        roi = cv2.dilate(m.view(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)).view(bool)
    bg = roi & ~m
    n, lab = cv2.connectedComponents(bg.view(np.uint8), connectivity=4)
    lab = lab.astype(np.int32, copy=False)
    fill = np.ones(n, bool)
    fill[0] = False
    # components touching the image border or the edge of the search region are outside
    fill[lab[0]] = fill[lab[-1]] = fill[lab[:, 0]] = fill[lab[:, -1]] = False
    if max_hole_px is not None:
        edge = roi & ~cv2.erode(roi.view(np.uint8), np.ones((3, 3), np.uint8),
                                borderType=cv2.BORDER_CONSTANT, borderValue=1).view(bool)
        fill[lab[edge]] = False
        from .measure import object_moments
        area = object_moments(lab, n - 1)[0]
        fill &= area <= max_hole_px
    fill[0] = False
    return m | lookup(fill, lab)


def bridge_gaps(mask):
    """Morphological closing with a 3 x 3 square: joins pieces of a thin crack separated by a
    one-pixel gap (where its blurred core dipped under the detection level).

    Examples
    --------
    >>> m = np.zeros((5, 12), bool); m[2, 1:5] = True; m[2, 6:11] = True
    >>> from semkit.measure import label_cracks
    >>> label_cracks(bridge_gaps(m))[1]
    1
    """
    import cv2
    m = np.ascontiguousarray(mask, np.uint8)
    return cv2.morphologyEx(m, cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8),
                            borderType=cv2.BORDER_CONSTANT, borderValue=0).astype(bool)
