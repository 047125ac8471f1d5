"""Stage 5: label crack objects and measure them (one row per crack).

Area is the pixel count x pixel area; length comes from the skeleton's chain code with
unbiased weights, plus what the skeleton leaves out at the crack's ends
(:mod:`semkit.skeleton`); the mean aperture is area / length. Round, compact dark objects
(pores) are told apart from cracks by shape and reported separately.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from . import config
from .skeleton import skeleton_length, skeleton_nodes, tip_extension

__all__ = ["label_cracks", "object_moments", "ellipse_shape", "is_pore", "crack_table",
           "partial_volume_area", "mixed_area", "parallel_traces", "trace_samples",
           "layered_share", "CRACK_COLUMNS"]

#: cracks.csv columns (DESIGN.md §4) in order; more follow.
CRACK_COLUMNS = ["image", "crack_id", "area_um2", "length_um", "mean_aperture_um",
                 "orientation_deg", "tortuosity", "n_branches", "type_pre", "type_post",
                 "confidence"]


def label_cracks(mask):
    """Label 8-connected crack objects.

    Returns
    -------
    labels : (M, N) ndarray of int32
        0 = background, 1..n objects (in raster order of their first pixel).
    n : int
        Number of objects.

    Examples
    --------
    >>> m = np.zeros((4, 6), bool); m[0, 0] = m[1, 1] = m[3, 5] = True
    >>> label_cracks(m)[1]
    2
    """
    import cv2
    n, lab = cv2.connectedComponents(np.ascontiguousarray(mask, np.uint8), connectivity=8)
    return lab.astype(np.int32, copy=False), int(n - 1)


def object_moments(labels, n, *, origin=False):
    """Per-object pixel count, centroid, second central moments and bounding box.

    Returns
    -------
    area, cx, cy, mxx, myy, mxy, bbox_w, bbox_h : (n + 1,) ndarray of float64
        Entry 0 is the background. Moments are in px² and include the 1/12 of a pixel.
    bbox_x0, bbox_y0 : (n + 1,) ndarray of float64
        Only with ``origin=True``: the bounding box's first column and row.
    """
    from . import _kernels
    m = np.zeros((n + 1, 10), np.float64)
    _kernels.label_moments(np.ascontiguousarray(labels, np.int32), n + 1, m)
    area = m[:, 0]
    a = np.maximum(area, 1)
    cx = m[:, 1] / a
    cy = m[:, 2] / a
    mxx = m[:, 3] / a - cx ** 2 + 1 / 12
    myy = m[:, 4] / a - cy ** 2 + 1 / 12
    mxy = m[:, 5] / a - cx * cy
    if origin:
        return area, cx, cy, mxx, myy, mxy, m[:, 6], m[:, 7], m[:, 8], m[:, 9]
    return area, cx, cy, mxx, myy, mxy, m[:, 6], m[:, 7]


def ellipse_shape(area, mxx, myy, mxy):
    """``(aspect, fill)`` of objects from their second central moments (:func:`object_moments`):
    the ratio of the principal axes of the equivalent ellipse, and the share of that ellipse
    the area fills (1 for a full ellipse; far less for a branched network)."""
    tr = mxx + myy
    det = np.sqrt(np.maximum((mxx - myy) ** 2 / 4 + mxy ** 2, 0))
    l1 = tr / 2 + det
    l2 = np.maximum(tr / 2 - det, 1e-9)
    return np.sqrt(l1 / l2), area / (4 * np.pi * np.sqrt(l1 * l2))


def is_pore(area, mxx, myy, mxy, *, max_aspect=2.0, min_fill=0.75, min_area_px=30):
    """Pore test: compact (aspect < ``max_aspect``), full (area / equivalent ellipse >
    ``min_fill``) and not tiny. Cracks are elongated or, when branched, far from full."""
    aspect, fill = ellipse_shape(area, mxx, myy, mxy)
    return (aspect < max_aspect) & (fill > min_fill) & (area >= min_area_px)


def crack_table(labels, n, *, pixel_size_um, skeleton=None, area_mask=None, image_name="",
                length_estimator="corner"):
    """Measure each labelled object (stage 5-6) -> one row per object.

    Parameters
    ----------
    labels : (M, N) ndarray of int32
        Object labels from :func:`label_cracks`.
    n : int
    pixel_size_um : float
    skeleton : (M, N) bool, optional
        Thin skeleton of the objects; without it lengths are NaN (``--no-length``).
    area_mask : (M, N) bool, optional
        Pixels counted for area (default: all labelled pixels).
    image_name : str

    Returns
    -------
    table : DataFrame
        :data:`CRACK_COLUMNS` then ``area_px, length_px, x_px, y_px, is_pore, thin,
        n_traces`` (1 here: :func:`parallel_traces` measures it).
        ``thin`` flags cracks narrower than ``THIN_WIDTH_PX`` (their area is the least
        reliable part; their length is still measured). ``type_pre``/``type_post`` are
        ``unknown`` until classification.
    """
    area_all, cx, cy, mxx, myy, mxy, _, _ = object_moments(labels, n)
    if area_mask is not None:
        area_px = np.bincount(np.asarray(labels)[np.asarray(area_mask, bool)],
                              minlength=n + 1).astype(np.float64)
    else:
        area_px = area_all
    px = float(pixel_size_um)
    ids = np.arange(1, n + 1)
    orient = (np.degrees(0.5 * np.arctan2(-2 * mxy, mxx - myy)) % 180.0)
    pore = is_pore(area_all, mxx, myy, mxy)
    if skeleton is not None:
        ends, junc = skeleton_nodes(skeleton)
        length_px = skeleton_length(skeleton, labels, n + 1, estimator=length_estimator)
        if length_estimator != "count":  # ImageJ's habit counts pixels and nothing more
            length_px = length_px + tip_extension(skeleton, labels, n + 1, ends=ends)
        # isolated skeleton pixels (tiny blobs) have no links: give them one pixel of length
        single = np.bincount(labels[skeleton], minlength=n + 1) > 0
        length_px = np.where(single & (length_px == 0), 1.0, length_px)
        n_end = np.bincount(labels[ends], minlength=n + 1)
        jl, nj = label_cracks(junc)
        # a junction cluster counts once, for the object it lies in
        if nj:
            first = np.zeros(nj + 1, np.int64)
            first[jl[junc]] = labels[junc]
            n_junc = np.bincount(first[1:], minlength=n + 1)
        else:
            n_junc = np.zeros(n + 1, np.int64)
        n_br = np.maximum(n_end + n_junc - 1, 1)
        # tortuosity: length over the object's extent along its principal axis
        from . import _kernels
        theta = 0.5 * np.arctan2(2 * mxy, mxx - myy)
        pmin = np.full(n + 1, np.inf)
        pmax = np.full(n + 1, -np.inf)
        _kernels.label_extent(np.ascontiguousarray(labels, np.int32), n + 1, np.cos(theta),
                              np.sin(theta), pmin, pmax)
        extent = np.maximum(pmax - pmin + 1.0, 1.0)
        tort = np.maximum(length_px / extent, 1.0)
    else:
        length_px = np.full(n + 1, np.nan)
        n_br = np.zeros(n + 1, np.int64)
        tort = np.full(n + 1, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        aperture_px = np.where(length_px > 0, area_px / length_px, np.nan)
    thin = aperture_px < config.THIN_WIDTH_PX
    df = pd.DataFrame({
        "image": image_name, "crack_id": ids,
        "area_um2": area_px[1:] * px * px, "length_um": length_px[1:] * px,
        "mean_aperture_um": aperture_px[1:] * px, "orientation_deg": orient[1:],
        "tortuosity": tort[1:], "n_branches": n_br[1:].astype(np.int64),
        "type_pre": "unknown", "type_post": "unknown", "confidence": np.nan,
        "area_px": area_px[1:], "length_px": length_px[1:], "x_px": cx[1:], "y_px": cy[1:],
        "is_pore": pore[1:], "thin": thin[1:], "n_traces": 1.0,
    })
    return df


def _partial_volume_kernel(image, lab, n, background, crack_level, rim_px, ids):
    """:func:`partial_volume_area` in one numba pass (same float32 arithmetic, same order)."""
    import cv2

    from . import _kernels
    size = max(n, int(lab.max(initial=0))) + 1
    sel = np.zeros(size, bool)
    if ids is None:
        sel[1:] = True
    else:
        sel[np.asarray(ids, np.int64)] = True
        sel[0] = False
    rim = max(int(rim_px), 0)
    from ._kernels import lookup
    near = lookup(sel, lab).view(np.uint8)
    if rim:
        near = cv2.dilate(near, np.ones((2 * rim + 1, 2 * rim + 1), np.uint8))
    out = np.zeros(size, np.float64)
    _kernels.partial_volume_sums(np.ascontiguousarray(lab), sel, near,
                                 np.ascontiguousarray(image, np.float32),
                                 np.ascontiguousarray(background, np.float32),
                                 np.float32(crack_level), rim, out)
    return out


def partial_volume_area(image, labels, n, *, background, crack_level, rim_px=1, ids=None):
    """Area of each object as the sum of its pixels' crack coverage (partial volume), px.

    For cracks about one pixel wide the blurred core never reaches the midpoint between
    background and crack grey, so a pixel count misses them; the coverage
    ``(bg - I) / (bg - crack)`` summed over the object and a ``rim_px`` rim is their area.

    Parameters
    ----------
    image : (M, N) float
        The grey image that was thresholded.
    labels : (M, N) int32 ; n : int
    background : (M, N) float
        Local background grey (``ThresholdResult.background``).
    crack_level : float
        Void (crack core) grey (``ThresholdResult.void_level``).
    ids : sequence of int, optional
        Measure only these objects (others get 0); default all.

    Returns
    -------
    area_px : (n + 1,) ndarray of float64
    """
    import cv2
    lab = np.asarray(labels, np.int32)
    if (np.zeros(1, np.float32) - crack_level).dtype == np.float32:   # float32 arithmetic
        return _partial_volume_kernel(image, lab, n, background, crack_level, rim_px, ids)
    if ids is not None:
        sel = np.zeros(n + 1, bool)
        sel[np.asarray(ids, np.int64)] = True
        lab = np.where(sel[lab], lab, 0).astype(np.int32)
    labf = lab.astype(np.float32)
    if rim_px > 0:
        k = np.ones((2 * rim_px + 1, 2 * rim_px + 1), np.uint8)
        labf = np.where(labf > 0, labf, cv2.dilate(labf, k))
    flat = labf.ravel()
    idx = np.flatnonzero(flat)
    li = flat[idx].astype(np.int64)
    img = np.asarray(image, np.float32).ravel()[idx]
    bg = np.asarray(background, np.float32).ravel()[idx]
    cov = np.clip((bg - img) / np.maximum(bg - crack_level, 1e-3), 0.0, 1.0)
    return np.bincount(li, cov, minlength=n + 1)


def mixed_area(image, labels, n, *, skeleton, background, crack_level, area_mask,
               resolved=None):
    """Area of each object: pixel count where its core is resolved, partial volume elsewhere, px.

    The midpoint count (``area_mask``) is unbiased only where a crack's core reaches its void
    grey; where a crack narrows below the blur (thin cracks, tapering tips, the thin stretches
    of a wide crack) no pixel passes the midpoint and a count loses it. There each pixel of
    the cross-section and of a 1-px rim adds its partial-volume coverage
    ``(bg - I) / (bg - crack)`` instead. A cross-section is resolved when its centreline pixel
    has a pixel at least ``resolved`` (default ``config.AREA_RESOLVED_DEPTH``) of the way from
    background to crack grey in its 3 x 3 box; each pixel belongs to the cross-section of the
    centreline pixel nearest it through the object (:func:`semkit._kernels.mixed_area_sums`).

    Parameters
    ----------
    image : (M, N) float
        The grey image that was thresholded.
    labels : (M, N) int32 ; n : int
    skeleton : (M, N) bool
        Centrelines of the objects.
    background : (M, N) float
        Local background grey (``ThresholdResult.background``).
    crack_level : float
        Void (crack core) grey.
    area_mask : (M, N) bool
        Pixels past the midpoint.

    Returns
    -------
    area_px : (n + 1,) ndarray of float64
    pv_share : (n + 1,) ndarray of float64
        Share of each object's pixels measured by partial volume (0: a pure count).
    """
    import cv2

    from . import _kernels
    if resolved is None:
        resolved = config.AREA_RESOLVED_DEPTH
    lab = np.ascontiguousarray(labels, np.int32)
    size = max(n, int(lab.max(initial=0))) + 1
    near = cv2.dilate((lab > 0).view(np.uint8), np.ones((3, 3), np.uint8))
    out = np.zeros(size, np.float64)
    n_pv = np.zeros(size, np.int64)
    n_own = np.zeros(size, np.int64)
    _kernels.mixed_area_sums(lab, np.ascontiguousarray(skeleton, bool).view(np.uint8), near,
                             np.ascontiguousarray(area_mask, bool),
                             np.ascontiguousarray(image, np.float32),
                             np.ascontiguousarray(background, np.float32),
                             np.float32(crack_level), np.float32(resolved), out, n_pv, n_own)
    share = n_pv / np.maximum(n_own, 1)
    return out[:n + 1], share[:n + 1]


def trace_samples(image, labels, *, skeleton, background, crack_level,
                  depth=config.TRACE_MIN_DEPTH, rise=config.TRACE_MIN_RISE,
                  min_half_width=config.TRACE_MIN_HALF_WIDTH_PX,
                  max_reach=config.TRACE_MAX_REACH_PX, along=config.TRACE_ALONG_PX,
                  noise=0.0, noise_z=config.TRACE_NOISE_Z):
    """The cross-sections :func:`parallel_traces` reads: every other centreline pixel (raster
    order) and the number of resolved traces across it
    (:func:`semkit._kernels.cross_section_valleys`; parameters as there).

    Returns
    -------
    rr, cc : (K,) ndarray of int64
        The centreline pixels read.
    count : (K,) ndarray of int32
        Traces across each (1 for a single trace, a wide void or a thin line).
    """
    from . import _kernels
    lab = np.ascontiguousarray(labels, np.int32)
    skel = np.ascontiguousarray(skeleton, bool) & (lab > 0)
    rr, cc = _kernels.pixel_coords(skel)
    if rr.size > 1:  # every other centreline pixel reads the mean as well
        rr, cc = rr[::2].copy(), cc[::2].copy()
    count = np.ones(rr.size, np.int32)
    if rr.size:
        _kernels.cross_section_valleys(
            np.ascontiguousarray(image, np.float32), np.ascontiguousarray(background, np.float32),
            lab, skel, rr, cc, float(crack_level), float(depth), float(rise),
            float(min_half_width), float(max_reach), float(along),
            float(noise_z * noise * np.sqrt(2.0 / (2 * int(along) + 1))), count)
    return rr, cc, count


def layered_share(mask, rr, cc, count, reach=config.LAYERED_VOID_REACH_PX):
    """Share of the pixels of ``mask`` within ``reach`` px (a square) of a cross-section
    read as two or more traces (``rr, cc, count`` of :func:`trace_samples`); NaN when
    ``mask`` is empty.

    Examples
    --------
    >>> m = np.zeros((9, 9), bool); m[3:6, 1:8] = True
    >>> round(layered_share(m, np.array([4, 4]), np.array([2, 6]), np.array([2, 1]), reach=1), 4)
    0.4286
    """
    import cv2
    m = np.asarray(mask, bool)
    n = np.count_nonzero(m)
    if n == 0:
        return float("nan")
    multi = np.zeros(m.shape, np.uint8)
    sel = np.asarray(count) > 1
    multi[np.asarray(rr)[sel], np.asarray(cc)[sel]] = 1
    k = 2 * int(reach) + 1
    near = cv2.dilate(multi, np.ones((k, k), np.uint8)).view(bool)
    return float(np.count_nonzero(m & near) / n)


def parallel_traces(image, labels, n, *, skeleton, background, crack_level,
                    depth=config.TRACE_MIN_DEPTH, rise=config.TRACE_MIN_RISE,
                    min_half_width=config.TRACE_MIN_HALF_WIDTH_PX,
                    min_share=config.TRACE_MIN_SHARE, max_reach=config.TRACE_MAX_REACH_PX,
                    min_samples=config.TRACE_MIN_BRANCH_SAMPLES,
                    along=config.TRACE_ALONG_PX, noise=0.0, noise_z=config.TRACE_NOISE_Z,
                    samples=None):
    """Mean number of resolved parallel traces along each object (1 for a single trace).

    A layered shear crack is two or three thin traces a few pixels apart; the detect mask
    joins them into one band and its skeleton runs once down the middle, so the band's
    length counts one trace. Across each centreline pixel the grey profile is read along the
    normal (:func:`semkit._kernels.cross_section_valleys`, every other centreline pixel),
    each sample averaged over ``2 * along + 1`` points 1 px apart along the line: the noise
    is averaged along the traces while the profile across them keeps the image's resolution
    (read it on the image before denoising: a 0.7-px blur merges traces 2.5-3 px apart).
    Each valley at least ``depth`` of the way from the local background to the crack grey,
    parted from the next by a rise of ``rise`` times the shallower valley's depth and of
    ``noise_z`` sigmas of the noise of a difference of two such samples (taken as ``noise *
    sqrt(2 / (2 * along + 1))``: the bilinear read averages a little more, so the bound errs
    towards one trace), is a trace. Each skeleton branch (junction to junction or end) read
    at ``min_samples`` or more centreline pixels, of which at least ``min_share`` cross two
    or more traces, counts the mean number of traces along it; other branches count 1 (a few
    split cross-sections are debris or noise, not a second trace). An object's factor is the
    mean over its centreline, so one layered branch of a crack network counts its own
    traces. A wide open crack has one valley, its flat void.

    Parameters
    ----------
    image : (M, N) float
        The grey image that was thresholded, before its denoising.
    labels : (M, N) int32 ; n : int
    skeleton : (M, N) bool
        Centrelines of the objects.
    background : (M, N) float
        Local background grey (``ThresholdResult.background``).
    crack_level : float
        Crack core grey (``ThresholdResult.crack_level``).
    depth, rise, min_half_width, min_share, max_reach : float
    min_samples, along : int
    noise_z : float
        See ``semkit.config`` (``TRACE_*``).
    noise : float
        Pixel-noise sigma of ``image`` (:func:`semkit.threshold.noise_sigma`; 0: no noise
        bound).
    samples : tuple of ndarray, optional
        The cross-sections as :func:`trace_samples` read them with the same settings (when
        the caller has them already; the settings above are then not used again).

    Returns
    -------
    traces : (n + 1,) ndarray of float64
        Length factor per object (index 0 unused: 1).

    Examples
    --------
    Two thin dark lines 5 px apart, joined by a darker band between them, and one line:

    >>> img = np.full((40, 80), 200, np.float32)
    >>> img[10:30, 20:70] = 150; img[[12, 17], 20:70] = 40; img[25, 20:70] = 40
    >>> lab = np.zeros(img.shape, np.int32); lab[11:19, 20:70] = 1; lab[24:27, 20:70] = 2
    >>> sk = np.zeros(img.shape, bool); sk[14, 21:69] = True; sk[25, 21:69] = True
    >>> t = parallel_traces(img, lab, 2, skeleton=sk, background=np.full(img.shape, 200.0),
    ...                     crack_level=40.0)
    >>> t[1:].round(2).tolist()
    [2.0, 1.0]
    """
    lab = np.ascontiguousarray(labels, np.int32)
    skel = np.ascontiguousarray(skeleton, bool) & (lab > 0)
    traces = np.ones(n + 1, np.float64)
    rr, cc, count = samples if samples is not None else trace_samples(
        image, lab, skeleton=skel, background=background, crack_level=crack_level,
        depth=depth, rise=rise, min_half_width=min_half_width, max_reach=max_reach,
        along=along, noise=noise, noise_z=noise_z)
    if rr.size == 0:
        return traces
    # judged per branch (junction to junction or end): one layered branch of a crack
    # network counts its traces, not the network's mean
    _, junc = skeleton_nodes(skel)
    br, nb = label_cracks(skel & ~junc)
    at = br[rr, cc]
    tot = np.bincount(at, minlength=nb + 1)
    multi = np.bincount(at, weights=count > 1, minlength=nb + 1)
    mean = np.bincount(at, weights=count, minlength=nb + 1) / np.maximum(tot, 1)
    f = np.where((tot >= min_samples) & (multi >= min_share * tot), mean, 1.0)
    f[0] = 1.0  # junction pixels
    obj = lab[rr, cc]
    traces_sum = np.bincount(obj, weights=f[at], minlength=n + 1)[:n + 1]
    n_obj = np.bincount(obj, minlength=n + 1)[:n + 1]
    hit = n_obj > 0
    traces[hit] = traces_sum[hit] / n_obj[hit]
    return traces
