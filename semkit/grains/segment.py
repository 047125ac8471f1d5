"""Grain segmentation: boundary-strength watershed inside each mineral phase.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

from .. import config
from ..errors import InputError
from .phases import _as_grey, _smooth_masked

__all__ = ["segment_grains"]

GRAIN_DENOISE_SIGMA_PX = config.GRAIN_DENOISE_SIGMA_PX
RIDGE_SIGMA_PX = config.RIDGE_SIGMA_PX
MARKER_H_PX = config.MARKER_H_PX
BOUNDARY_LEVEL = config.BOUNDARY_LEVEL


def segment_grains(image, *, phase_labels=None, mask=None, min_diameter_px=6.0,
                   sigma_px=GRAIN_DENOISE_SIGMA_PX, ridge_sigma_px=RIDGE_SIGMA_PX,
                   marker_h_px=MARKER_H_PX):
    """Separate touching grains by a boundary-strength watershed.

    Parameters
    ----------
    image : (M, N) ndarray (or RGB)
        The micrograph.
    phase_labels : (M, N) ndarray of int, optional
        Output of :func:`mineral_phases`; phase changes count as strong boundaries (the seeds
        never straddle two phases; the flooding itself follows the grey-level strength, so the
        grain borders sit on the true edges rather than on the smoothed phase map).
    mask : (M, N) ndarray of bool, optional
        Excluded pixels (cracks, pores): label 0 in the output.
    min_diameter_px : float
        Smallest grain to resolve (equivalent diameter, px); seeds closer than half of it merge.
    sigma_px, ridge_sigma_px, marker_h_px : float
        Denoising, ridge-filter scale and h-maxima depth (px).

    Returns
    -------
    grain_labels : (M, N) ndarray of int32
        0 = excluded, 1..G grains. Every valid pixel belongs to a grain (no watershed line), so
        grain areas tile the image as a Voronoi partition does.

    Raises
    ------
    InputError
        Shapes disagree.

    Notes
    -----
    Strength B = max(|grad G_s| / median, R / median(R)), R the Sato black-ridge response,
    so B is in units of the noise level; {B > BOUNDARY_LEVEL} and the phase changes are the
    boundary pixels used to seed. Markers: connected components of the h-maxima of the Euclidean
    distance to {B > BOUNDARY_LEVEL}; flooding of B from the markers (Beucher & Meyer 1993).
    """
    from skimage.filters import sato, sobel
    from skimage.morphology import h_maxima
    from skimage.segmentation import watershed

    g = _as_grey(image)
    valid = np.ones(g.shape, bool) if mask is None else ~np.asarray(mask, bool)
    if valid.shape != g.shape:
        raise InputError(f"mask: expected shape {g.shape}, got {valid.shape}")
    s = _smooth_masked(g, valid, sigma_px)
    grad = sobel(s)
    ridge = sato(s, sigmas=[ridge_sigma_px], black_ridges=True)
    v = valid & np.isfinite(grad)

    def _norm(a):
        q = np.median(a[v]) if v.any() else 1.0
        return a / q if q > 0 else a

    strength = np.maximum(_norm(grad), _norm(ridge))
    if phase_labels is not None:
        p = np.asarray(phase_labels)
        if p.shape != g.shape:
            raise InputError(f"phase_labels: expected shape {g.shape}, got {p.shape}")
        change = ndi.maximum_filter(p, 3) != ndi.minimum_filter(p, 3)
    else:
        change = np.zeros(g.shape, bool)
    boundary = (strength > BOUNDARY_LEVEL) | change | ~valid
    dist = ndi.distance_transform_edt(~boundary)
    dist = ndi.gaussian_filter(dist, 1.0)
    h = max(marker_h_px, 0.25 * min_diameter_px / 2)
    peaks = h_maxima(dist, h)
    markers, _ = ndi.label(peaks & valid)
    if phase_labels is None:
        lab = watershed(strength, markers, mask=valid)
    else:
        # flood each phase region separately: grain borders between phases are the phase
        # borders (median-filtered classification, unbiased by the dark boundary lines)
        lab = np.zeros(g.shape, np.int64)
        for ph in np.unique(p[valid]):
            sel = valid & (p == ph)
            mk = np.where(sel, markers, 0)
            part = watershed(strength, mk, mask=sel) if mk.any() else np.zeros_like(lab)
            lab[sel] = part[sel]
        rest = valid & (lab == 0)  # phase patches without a seed: their own grains
        if rest.any():
            rl, _ = ndi.label(rest)
            lab[rest] = rl[rest] + lab.max()
    lab = _merge_small(lab, strength, min_area=np.pi * (min_diameter_px / 2) ** 2 / 2)
    lab, _, _ = _relabel(lab)
    return lab.astype(np.int32)


def _relabel(lab):
    from skimage.segmentation import relabel_sequential
    return relabel_sequential(lab)


def _merge_small(lab, strength, min_area):
    """Merge grains smaller than ``min_area`` px into the neighbour they share most border with."""
    from skimage.segmentation import watershed
    areas = np.bincount(lab.ravel())
    small = np.flatnonzero(areas < min_area)
    small = small[small > 0]
    if small.size == 0:
        return lab
    keep = lab.copy()
    keep[np.isin(lab, small)] = 0
    if not keep.any():
        return lab
    return watershed(strength, keep, mask=lab > 0)
