"""Partial-volume crack areas, split by post-test type (A_T, A_S of the damage ratio P).

Thin cracks (1-2 px, typical of shear) lose about half their area to any pixel threshold
once blurred; the partial-volume area sums each pixel's darkness fraction instead.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from . import _kernels, config
from .errors import InputError

__all__ = ["darkness_fraction", "typed_areas", "PV_BAND_PX", "PV_BACKGROUND_SIGMA_PX"]

#: band (px) around the crack objects over which partial-volume darkness is summed.
PV_BAND_PX = config.PV_BAND_PX
#: Gaussian sigma (px) of the local-background estimate for the partial-volume area.
PV_BACKGROUND_SIGMA_PX = config.PV_BACKGROUND_SIGMA_PX


def _disk_offsets(radius):
    """Offsets (di, dj) with di^2 + dj^2 <= radius^2, sorted by length then raster order."""
    r = int(np.floor(radius))
    di, dj = np.mgrid[-r:r + 1, -r:r + 1]
    di, dj = di.ravel(), dj.ravel()
    keep = di * di + dj * dj <= radius * radius + 1e-9
    di, dj = di[keep], dj[keep]
    order = np.argsort(di * di + dj * dj, kind="stable")
    return di[order].astype(np.int64), dj[order].astype(np.int64)


def _band_darkness(image, crack_labels, *, core=None, band_px=PV_BAND_PX,
                   background_sigma_px=PV_BACKGROUND_SIGMA_PX, background=None,
                   owner_image=False):
    """Partial-volume darkness at the band pixels only (see :func:`darkness_fraction`).

    Returns
    -------
    idx : (K,) ndarray of int
        Flat indices (raster order) of the pixels within ``band_px`` of an object.
    f : (K,) ndarray of float64
        Their darkness fraction.
    owner : (K,) ndarray of int
        Their nearest object's label (with ``owner_image``: the (M, N) image of the nearest
        object's label of every pixel).
    """
    import cv2
    img = np.asarray(image)
    lab = np.asarray(crack_labels)
    obj = lab > 0
    di, dj = _disk_offsets(band_px)
    if owner_image or di.size >= 255:
        dist, near = cv2.distanceTransformWithLabels((~obj).astype(np.uint8), cv2.DIST_L2, 5,
                                                     labelType=cv2.DIST_LABEL_PIXEL)
        src = np.zeros(int(near.max()) + 1, lab.dtype)
        src[near[obj]] = lab[obj]
        idx = np.flatnonzero(dist <= band_px)
        owner = src[near] if owner_image else src[near.ravel()[idx]]
    else:
        # a narrow band: stamped from the object pixels, no distance transform of the image
        idx, owner = _kernels.band_owners(np.ascontiguousarray(lab), di, dj)
    if background is not None:
        bg = np.asarray(background).ravel()[idx].astype(np.float64)
    else:
        img64 = np.asarray(img, np.float64)
        r = int(np.floor(band_px + 1))
        disk = _disk_offsets(band_px + 1)
        kernel = np.zeros((2 * r + 1, 2 * r + 1), np.uint8)
        kernel[disk[0] + r, disk[1] + r] = 1
        bg_mask = cv2.dilate(obj.astype(np.uint8), kernel) == 0

        def blur(a):
            return cv2.GaussianBlur(a.astype(np.float32), (0, 0), background_sigma_px,
                                    borderType=cv2.BORDER_REFLECT).astype(np.float64)
        num = blur(np.where(bg_mask, img64, 0.0)).ravel()[idx]
        den = blur(bg_mask).ravel()[idx]
        fill = np.median(img64[bg_mask]) if bg_mask.any() else img64.max()
        bg = np.where(den > 1e-3, num / np.maximum(den, 1e-3), fill)
    if core is None:
        v = img[obj].astype(np.float64)
        core = float(np.percentile(v, 2)) if v.size else float(img.min())
    i = img.ravel()[idx].astype(np.float64)
    f = np.clip((bg - i) / np.maximum(bg - float(core), 1e-6), 0.0, 1.0)
    return idx, f, owner


def darkness_fraction(image, crack_labels, *, core=None, band_px=PV_BAND_PX,
                      background_sigma_px=PV_BACKGROUND_SIGMA_PX, background=None):
    """Partial-volume darkness of each pixel near the cracks (0 background .. 1 crack core).

    Parameters
    ----------
    image : (M, N) ndarray
    crack_labels : (M, N) ndarray of int
    core : float, optional
        Grey level of a fully dark crack pixel; default the 2nd percentile inside the objects.
    band_px, background_sigma_px : float
        See :func:`typed_areas`.
    background : (M, N) ndarray, optional
        Local background grey (e.g. the threshold stage's); estimated when not given.

    Returns
    -------
    f : (M, N) ndarray of float64
        clip((B - I) / (B - I_core), 0, 1) within ``band_px`` of an object, else 0.
    owner : (M, N) ndarray of int
        Label of the nearest object pixel (which object a band pixel belongs to).

    Notes
    -----
    OpenCV's 5 x 5 distance transform (within 2 % of the Euclidean distance) finds the band
    and the nearest object; B is a normalised Gaussian convolution of the pixels farther than
    ``band_px + 1`` from any object. The arithmetic runs on the band pixels only.
    """
    lab = np.asarray(crack_labels)
    idx, fb, owner = _band_darkness(image, lab, core=core, band_px=band_px,
                                    background_sigma_px=background_sigma_px,
                                    background=background, owner_image=True)
    f = np.zeros(lab.size, np.float64)
    f[idx] = fb
    return f.reshape(lab.shape), owner


def _owner_types(type_image, lab, owner):
    """Type of each band pixel: its own where it is an object pixel, else that of its
    nearest object's pixels (the object's majority type)."""
    n = int(lab.max())
    counts = np.zeros((n + 1, 4), np.int64)
    np.add.at(counts, (lab[lab > 0], np.clip(type_image[lab > 0], 0, 3)), 1)
    major = counts.argmax(axis=1)
    return np.where(lab > 0, type_image, major[owner])


def typed_areas(image, crack_labels, type_image=None, *, core=None, band_px=PV_BAND_PX,
                background_sigma_px=PV_BACKGROUND_SIGMA_PX, background=None):
    """Partial-volume crack areas per object, split by post-test type.

    Thin cracks (1-2 px, typical of shear) lose about half their area to any pixel threshold
    once blurred; the partial-volume area sums each pixel's darkness fraction instead, which
    is unbiased for thin and wide cracks alike.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image, cracks dark (flattened if the lighting is uneven).
    crack_labels : (M, N) ndarray of int
        Crack objects 1..n.
    type_image : (M, N) ndarray of int, optional
        Type per pixel (1 tensile, 2 shear, 3 mixed; :func:`semkit.classify.classify_post`).
    core : float, optional
        Grey level of a fully dark crack pixel; default the 2nd percentile inside the objects.
    band_px : int
        Pixels within this distance of an object count (blur spreads darkness beyond it).
    background_sigma_px : float
        Scale of the local background (normalised convolution over non-crack pixels).
    background : (M, N) ndarray, optional
        A local background already at hand (the threshold stage's); replaces the estimate.

    Returns
    -------
    table : pandas.DataFrame
        ``crack_id, area_pv_px, area_T_px, area_S_px, area_M_px``.

    Notes
    -----
    f = clip((B - I) / (B - I_core), 0, 1) with B the local background; area = sum f over the
    object and its band (band pixels belong to the nearest object and take its majority type).
    """
    img = np.asarray(image)
    lab = np.asarray(crack_labels)
    if img.shape != lab.shape or img.ndim != 2:
        raise InputError(f"crack_labels: expected shape {img.shape}, got {lab.shape}")
    n = int(lab.max())
    cols = ["crack_id", "area_pv_px", "area_T_px", "area_S_px", "area_M_px"]
    if n == 0:
        return pd.DataFrame(columns=cols)
    # sums over the band pixels only: f is 0 elsewhere, so the sums are the same
    idx, f, owner = _band_darkness(img, lab, core=core, band_px=band_px,
                                   background_sigma_px=background_sigma_px,
                                   background=background)
    out = {"crack_id": np.arange(1, n + 1),
           "area_pv_px": np.bincount(owner, f, minlength=n + 1)[1:]}
    if type_image is None:
        for name in ("area_T_px", "area_S_px", "area_M_px"):
            out[name] = np.zeros(n)
    else:
        owner_img = np.zeros(lab.size, np.int64)
        owner_img[idx] = owner
        types = _owner_types(np.asarray(type_image).astype(np.int64), lab,
                             owner_img.reshape(lab.shape)).ravel()[idx]
        for k, name in ((1, "area_T_px"), (2, "area_S_px"), (3, "area_M_px")):
            out[name] = np.bincount(owner, np.where(types == k, f, 0.0), minlength=n + 1)[1:]
    t = pd.DataFrame(out)
    # every object pixel is a band pixel that owns itself, and owners are objects: the labels
    # present are the owners
    present = np.zeros(n + 1, bool)
    present[owner] = True
    return t[present[1:]].reset_index(drop=True)
