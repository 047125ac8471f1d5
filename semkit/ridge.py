"""Multi-scale dark-ridge (valley) response for thin, faint cracks, from OpenCV Gaussian
derivatives.

At scale sigma the Hessian of the Gaussian-smoothed image has eigenvalues l1 >= l2; across a dark
line l1 > 0 and along it l2 ~ 0. The response is

    R_sigma = sigma^2 * (l1 - |l2|) - kappa * sigma * |grad I_sigma|,   clipped at 0,

the scale-normalised valley strength, less a blob term (|l2|: a round dark spot has l1 ~ l2) and
an edge term (the dark side of a step edge has l1 > 0 too, but a large gradient, while the
centre of a line has none). R is the maximum over scales. The finest scale runs on the full
image, coarser ones (sigma >= ``RIDGE_COARSE_SIGMA_PX``) on the image shrunk by 2 and are
resized back; the eigenvalues are one numba pass (:func:`semkit._kernels.ridge_strength`):
far cheaper than scikit-image's ``sato`` / ``frangi`` (every scale at full size, float64).

:func:`ridge_mask` turns R into crack candidates by hysteresis on its signal-to-noise ratio
(the noise response measured on the image's own Laplacian) and keeps only lines whose grey
depth below the local background (a grey closing) is a sizeable share of the local crack
contrast, so faint grain boundaries (a few % darker than their grain) stay out.
"""
from __future__ import annotations

import numpy as np

from . import config
from .robust import group_medians, mad_sigma

__all__ = ["ridge_response", "ridge_mask", "add_ridge_lines"]


def _add_scale(img, sigma, kappa, out):
    """Max ``out`` with the ridge strength at ``sigma``; returns the scale-normalised
    Laplacian (for the noise level)."""
    import cv2

    from . import _kernels
    b = cv2.BORDER_REFLECT
    g = cv2.GaussianBlur(img, (0, 0), sigma, borderType=b)
    dxx = cv2.Sobel(g, cv2.CV_32F, 2, 0, ksize=3, scale=0.25, borderType=b)
    dyy = cv2.Sobel(g, cv2.CV_32F, 0, 2, ksize=3, scale=0.25, borderType=b)
    dxy = cv2.Sobel(g, cv2.CV_32F, 1, 1, ksize=3, scale=0.25, borderType=b)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=0.125, borderType=b)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=0.125, borderType=b)
    _kernels.ridge_strength(dxx, dyy, dxy, gx, gy, float(sigma * sigma), float(kappa * sigma),
                            out)
    return dxx, dyy


def ridge_response(image, *, sigmas=config.RIDGE_SIGMAS_PX, kappa=config.RIDGE_EDGE_KAPPA):
    """Scale-normalised dark-ridge response and its noise level.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image (flattened, denoised), cracks dark.
    sigmas : sequence of float
        Scales, px; those >= ``RIDGE_COARSE_SIGMA_PX`` are computed on the image shrunk by 2.
    kappa : float
        Weight of the edge (gradient) term.

    Returns
    -------
    response : (M, N) ndarray of float32
        Max over scales of R_sigma (grey units).
    noise : float
        Robust std of the scale-normalised Laplacian at the finest scale: the response of
        pure noise, the unit of :func:`ridge_mask`'s hysteresis.

    Examples
    --------
    >>> img = np.full((40, 60), 100, np.float32); img[20, 5:55] = 60
    >>> r, _ = ridge_response(img, sigmas=(1.0,))
    >>> int(np.argmax(r[:, 30])), bool(r[20, 30] > 10 * r[10, 30] + 1)
    (20, True)
    """
    import cv2
    a = np.ascontiguousarray(image, np.float32)
    h, w = a.shape
    out = np.zeros(a.shape, np.float32)
    small = np.ascontiguousarray(cv2.resize(a, (w // 2, h // 2), interpolation=cv2.INTER_AREA)) \
        if min(h, w) >= 32 and max(sigmas) >= config.RIDGE_COARSE_SIGMA_PX else None
    out_small = None if small is None else np.zeros(small.shape, np.float32)
    noise = None
    for s in sorted(sigmas):
        if small is not None and s >= config.RIDGE_COARSE_SIGMA_PX:
            _add_scale(small, s / 2.0, kappa, out_small)
        else:
            dxx, dyy = _add_scale(a, s, kappa, out)
            if noise is None:
                v = (s * s * (dxx[::2, ::2] + dyy[::2, ::2])).ravel()
                # v is a fresh array: the medians may reorder it in place
                noise = float(mad_sigma(v))
    if out_small is not None:
        np.maximum(out, cv2.resize(out_small, (w, h), interpolation=cv2.INTER_LINEAR), out=out)
    return out, max(noise or 0.0, 1e-6)


def ridge_mask(image, *, crack_level, region=None, sigmas=config.RIDGE_SIGMAS_PX,
               high_snr=config.RIDGE_HIGH_SNR, low_snr=config.RIDGE_LOW_SNR,
               min_depth=config.RIDGE_MIN_DEPTH_FRACTION, closing_px=config.RIDGE_CLOSING_PX,
               return_components=False):
    """Thin dark lines: hysteresis on the ridge response, kept where deep enough.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image (flattened, denoised).
    crack_level : float
        Crack core grey (from the threshold stage).
    region : (M, N) ndarray of bool, optional
        Sample region; nothing is found outside.
    sigmas : sequence of float
    high_snr, low_snr : float
        Hysteresis levels of R in units of the noise response.
    min_depth : float
        Least depth below the local background, as a share of ``background - crack_level``,
        at the seed pixels of a line.
    closing_px : int
        Side of the grey closing that gives the local background (wider than thin cracks).

    Returns
    -------
    mask : (M, N) ndarray of bool
        Crack candidates (the ridge cores: pixels where R passes the low level).
    depth : (M, N) ndarray of float32
        Depth below the local background as a share of the local contrast.
    components : tuple
        Only with ``return_components``: ``(labels, keep)``, the 8-connected components of
        the low-level mask and which of them form ``mask`` (for :func:`add_ridge_lines`).
    """
    import cv2

    from . import _kernels
    a = np.ascontiguousarray(image, np.float32)
    r, noise = ridge_response(a, sigmas=sigmas)
    bg = cv2.morphologyEx(a, cv2.MORPH_CLOSE, cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (closing_px, closing_px)))
    bg = cv2.GaussianBlur(bg, (0, 0), 1.0)
    depth = np.empty(a.shape, np.float32)
    seed = np.empty(a.shape, bool)
    low = np.empty(a.shape, bool)
    reg = np.ones(a.shape, bool) if region is None else np.ascontiguousarray(region, bool)
    f32 = np.float32
    _kernels.ridge_levels(a, bg, r, f32(crack_level), f32(noise), f32(high_snr), f32(low_snr),
                          f32(min_depth), f32(0.5 * min_depth), reg, depth, seed, low)
    n, lab = cv2.connectedComponents(low.view(np.uint8), connectivity=8)
    keep = np.zeros(n, bool)
    keep[lab[seed]] = True
    keep[0] = False
    mask = _kernels.lookup(keep, lab)
    if return_components:
        return mask, depth, (lab, keep)
    return mask, depth


def add_ridge_lines(detect, area, ridge, depth, components=None, *,
                    continuations=True, min_px=config.RIDGE_CONTINUATION_MIN_PX,
                    min_depth=config.RIDGE_MIN_DEPTH_FRACTION, return_continuations=False):
    """Fuse ridge lines with a threshold's masks: lines the threshold missed become cracks.

    A ridge line apart from every threshold object is added whole. A line touching one is
    not (the threshold's objects keep their shape and measured width), but its pieces beyond
    the object are: the faint continuation of a crack the threshold found only in part. A
    piece is added when it holds at least ``min_px`` pixels and its median depth is at
    least ``min_depth`` (a ridge line may run on along a fainter grain boundary; a crack's
    continuation is as deep as a line the ridge detector starts on). Added pixels go to the
    detect mask, and to the area mask where they are at least ``AUTO_AREA_FRACTION`` deep
    (thin ones are measured by partial volume later).

    Parameters
    ----------
    detect, area : (M, N) ndarray of bool
        The threshold's detect and area masks.
    ridge : (M, N) ndarray of bool
    depth : (M, N) ndarray of float32
        :func:`ridge_mask` outputs.
    components : tuple, optional
        ``(labels, keep)`` from ``ridge_mask(..., return_components=True)``: the lines are
        the kept components, so they need not be labelled again.
    continuations : bool
        Add the pieces of touching lines beyond the objects.
    min_px : int
    min_depth : float
    return_continuations : bool
        Also return the continuation pieces added.

    Returns
    -------
    detect, area : (M, N) ndarray of bool
    added : (M, N) ndarray of bool
        Only with ``return_continuations``: the continuation pieces.
    """
    import cv2

    from . import _kernels
    if components is None:
        n, lab = cv2.connectedComponents(ridge.view(np.uint8), connectivity=8)
        touch = np.zeros(n, bool)
        keep = np.ones(n, bool)
    else:  # components not in the ridge mask count as touching: never new
        lab, keep = components
        touch = ~keep
    keep = keep.copy()
    keep[0] = False
    near = cv2.dilate(detect.view(np.uint8), np.ones((3, 3), np.uint8)).view(bool)
    touch[lab[near & ridge]] = True
    touch[0] = True
    new = _kernels.lookup(~touch, lab)
    added = np.zeros(detect.shape, bool)
    if continuations:
        beyond = ridge & ~detect & _kernels.lookup(touch & keep, lab)
        if beyond.any():
            m, pieces = cv2.connectedComponents(beyond.view(np.uint8), connectivity=8)
            at = pieces[beyond]
            size = np.bincount(at, minlength=m)
            ok = (size >= min_px) & (group_medians(depth[beyond], at, size) >= min_depth)
            ok[0] = False
            if ok.any():
                added = _kernels.lookup(ok, pieces)
                new |= added
    out = detect | new, area | (new & (depth >= config.AUTO_AREA_FRACTION))
    return (*out, added) if return_continuations else out
