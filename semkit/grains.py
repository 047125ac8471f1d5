"""Mineral phases, grain segmentation, per-grain shape and the grain-size table (``grains.csv``).

Pipeline (each step a function on arrays):

1. :func:`mineral_phases` — grey-level classes of the denoised, crack-masked image by
   multi-Otsu (default) or a 1-D Gaussian mixture; phase 1 is the brightest, names are given
   brightest-first (``--minerals pyroxene,plagioclase,biotite``).
2. :func:`segment_grains` — boundary-strength watershed: strength = grey gradient + dark-ridge
   response (faint boundaries between grains of one phase) + phase changes; markers are the
   h-maxima of the distance to the strong-boundary pixels.
3. :func:`grain_table` — per grain: area, equivalent diameter, aspect ratio, orientation,
   slenderness H/W (Equ. 5-2), mineral by majority vote of the phase map.
4. :func:`grain_size_table` — ``grains.csv`` (DESIGN.md §4): volume (area) fraction per mineral
   and fine/medium/coarse classes from user edges (``--classes 20,140``) or the automatic rule
   (10th and 90th count percentiles of the mineral's equivalent diameters).
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import ndimage as ndi

from . import config
from .errors import InputError

__all__ = ["mineral_phases", "phase_separability", "segment_grains", "grain_table", "grain_size_table",
           "slenderness", "plot_grain_histograms", "plot_grain_map",
           "AUTO_CLASS_PERCENTILES"]

#: automatic class edges: these count percentiles of the equivalent diameters of each mineral.
AUTO_CLASS_PERCENTILES = config.AUTO_CLASS_PERCENTILES
#: Gaussian denoising (px) before boundary detection.
GRAIN_DENOISE_SIGMA_PX = config.GRAIN_DENOISE_SIGMA_PX
#: median filter (px, odd) before phase classification: removes 1-2 px boundary lines.
PHASE_MEDIAN_PX = config.PHASE_MEDIAN_PX
#: Gaussian denoising (px) after the median, before phase classification.
PHASE_SIGMA_PX = config.PHASE_SIGMA_PX
#: scale (px) of the dark-ridge filter that finds faint boundaries inside one phase.
RIDGE_SIGMA_PX = config.RIDGE_SIGMA_PX
#: h of the h-maxima transform of the distance map that seeds the watershed, in px.
MARKER_H_PX = config.MARKER_H_PX
#: a pixel whose boundary strength (gradient or ridge response over its image median, i.e. in
#: units of the noise level) exceeds this is "boundary" when seeding the watershed.
BOUNDARY_LEVEL = config.BOUNDARY_LEVEL
#: EM iterations of the 1-D Gaussian mixture.
GMM_ITERATIONS = config.GMM_ITERATIONS


def _as_grey(image):
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[-1] in (3, 4):
        a = a[..., :3].astype(np.float64) @ np.array([0.2125, 0.7154, 0.0721])
    if a.ndim != 2 or a.size == 0:
        raise InputError(f"image: expected a 2-D grey (or RGB) array, got shape {a.shape}")
    return a.astype(np.float64)


def _gmm_1d(x, means, n_iter, seed):
    rng = np.random.default_rng(seed)
    k = len(means)
    mu = np.asarray(means, float) + rng.normal(0, 1e-6, k)
    var = np.full(k, np.var(x) / k ** 2 + 1e-9)
    pi = np.full(k, 1.0 / k)
    for _ in range(n_iter):
        d = -0.5 * (x[:, None] - mu) ** 2 / var - 0.5 * np.log(var) + np.log(pi)
        d -= d.max(axis=1, keepdims=True)
        r = np.exp(d)
        r /= r.sum(axis=1, keepdims=True)
        nk = r.sum(axis=0) + 1e-12
        mu = (r * x[:, None]).sum(axis=0) / nk
        # tied variance: robust to the mixed edge pixels that widen one component
        var = np.full(k, (r * (x[:, None] - mu) ** 2).sum() / x.size + 1e-9)
        pi = nk / nk.sum()
    return mu, var, pi


def mineral_phases(image, n_phases, *, mask=None, method="multiotsu",
                   median_px=PHASE_MEDIAN_PX, sigma_px=PHASE_SIGMA_PX, seed=None):
    """Classify pixels into mineral phases by grey level (BSE: brighter = heavier).

    Parameters
    ----------
    image : (M, N) ndarray, or (M, N, 3) RGB (converted to grey)
        The micrograph.
    n_phases : int
        Number of mineral phases (>= 2).
    mask : (M, N) ndarray of bool, optional
        Pixels to exclude (cracks, pores); they get phase 0 and are ignored in the fit.
    method : {"multiotsu", "gmm"}
        ``multiotsu``: skimage multi-level Otsu thresholds. ``gmm``: 1-D Gaussian mixture
        with a tied (common) variance fitted by EM (initialised at the multi-Otsu class means); the threshold between two
        adjacent components is where the more probable one changes, between their means.
    median_px : int
        Size of the median filter applied first (odd, px; 1 = none). It removes thin dark
        grain-boundary lines and specks while keeping phase edges in place, so phase areas are
        not biased toward the darker phase.
    sigma_px : float
        Gaussian denoising after the median, px (0 = none).
    seed : int, optional
        Seed of the (tiny) jitter of the GMM initialisation.

    Returns
    -------
    phase_labels : (M, N) ndarray of int32
        0 for masked pixels, 1 = brightest phase ... n_phases = darkest.
    thresholds : (n_phases - 1,) ndarray of float64
        Grey levels separating the phases, increasing.

    Raises
    ------
    InputError
        Bad shape, n_phases < 2, unknown method, too few unmasked pixels.

    Notes
    -----
    Multi-Otsu maximises the between-class variance of the grey histogram (Liao et al. 2001).
    """
    from skimage.filters import threshold_multiotsu

    g = _as_grey(image)
    if int(n_phases) != n_phases or n_phases < 2:
        raise InputError(f"n_phases: expected an integer >= 2, got {n_phases}")
    n_phases = int(n_phases)
    if method not in ("multiotsu", "gmm"):
        raise InputError(f"method: expected 'multiotsu' or 'gmm', got {method!r}")
    valid = np.ones(g.shape, bool) if mask is None else ~np.asarray(mask, bool)
    if valid.shape != g.shape:
        raise InputError(f"mask: expected shape {g.shape}, got {valid.shape}")
    if valid.sum() < 10 * n_phases:
        raise InputError("image: too few unmasked pixels to classify mineral phases")
    s = _median(g, median_px)
    if sigma_px > 0:
        s = _smooth_masked(s, valid, sigma_px)
    x = s[valid]
    thr = np.asarray(threshold_multiotsu(x, classes=n_phases), float)
    if method == "gmm":
        cls = np.digitize(x, thr)
        init = [x[cls == k].mean() if (cls == k).any() else np.percentile(x, 100 * (k + .5)
                / n_phases) for k in range(n_phases)]
        sub = x if x.size <= 200_000 else x[:: int(np.ceil(x.size / 200_000))]
        mu, var, pi = _gmm_1d(sub, init, GMM_ITERATIONS, seed)
        order = np.argsort(mu)
        mu, var, pi = mu[order], var[order], pi[order]
        thr = np.empty(n_phases - 1)
        for k in range(1, n_phases):  # decision point between adjacent components
            grid = np.linspace(mu[k - 1], mu[k], 2048)
            lp = (-0.5 * (grid[:, None] - mu[k - 1:k + 1]) ** 2 / var[k - 1:k + 1]
                  - 0.5 * np.log(var[k - 1:k + 1]) + np.log(pi[k - 1:k + 1]))
            thr[k - 1] = grid[np.argmax(lp[:, 1] >= lp[:, 0])]
    dark_rank = np.digitize(s, thr)  # 0 darkest .. n-1 brightest
    labels = (n_phases - dark_rank).astype(np.int32)
    labels[~valid] = 0
    return labels, thr


def _median(g, size):
    size = int(size)
    if size <= 1:
        return g
    if size % 2 == 0:
        raise InputError(f"median_px: expected an odd size, got {size}")
    if size <= 5:  # OpenCV: float32 medians up to 5 x 5, ~100x faster than ndimage
        import cv2
        return cv2.medianBlur(np.ascontiguousarray(g, np.float32), size).astype(np.float64)
    return ndi.median_filter(g, size=size, mode="reflect")


def _smooth_masked(g, valid, sigma):
    if sigma <= 0:
        return g.copy()
    num = ndi.gaussian_filter(np.where(valid, g, 0.0), sigma)
    den = ndi.gaussian_filter(valid.astype(float), sigma)
    return np.where(den > 1e-6, num / np.maximum(den, 1e-6), g)


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


def slenderness(grain_mask):
    """Slenderness ratio H/W of one grain (Equ. 5-2).

    Parameters
    ----------
    grain_mask : (M, N) ndarray of bool
        The grain (a crop is fine).

    Returns
    -------
    ratio : float
        Vertical chord length / horizontal chord length, both through the centroid (the
        contiguous run of grain pixels through the centroid pixel), NaN for an empty mask.

    Examples
    --------
    >>> m = np.zeros((9, 9), bool); m[1:8, 3:6] = True
    >>> float(slenderness(m))
    2.3333333333333335
    """
    m = np.asarray(grain_mask, bool)
    if not m.any():
        return float("nan")
    rr, cc = np.nonzero(m)
    r0, c0 = int(round(rr.mean())), int(round(cc.mean()))
    if not m[r0, c0]:  # non-convex grain: nearest grain pixel to the centroid
        k = np.argmin((rr - rr.mean()) ** 2 + (cc - cc.mean()) ** 2)
        r0, c0 = rr[k], cc[k]

    def run(line, i):
        lo = i
        while lo > 0 and line[lo - 1]:
            lo -= 1
        hi = i
        while hi < len(line) - 1 and line[hi + 1]:
            hi += 1
        return hi - lo + 1

    return run(m[:, c0], r0) / run(m[r0, :], c0)


def grain_table(grain_labels, phase_labels=None, *, pixel_size_um=1.0, names=None):
    """Per-grain measurements.

    Parameters
    ----------
    grain_labels : (M, N) ndarray of int
        0 = none, 1..G grains.
    phase_labels : (M, N) ndarray of int, optional
        Phase map (1 = brightest); the grain's mineral is its majority phase.
    pixel_size_um : float
        Pixel size, um.
    names : sequence of str, optional
        Mineral names brightest-first (phase k -> names[k-1]); default ``phase1``...

    Returns
    -------
    grains : pandas.DataFrame
        ``grain_id, mineral, phase, area_um2, eq_diameter_um, aspect_ratio, orientation_deg,
        slenderness, centroid_x_um, centroid_y_um``. ``orientation_deg`` is the major axis
        angle from the image x axis, anticlockwise as displayed, in [0, 180).

    Notes
    -----
    d_eq = sqrt(4 A / pi); aspect = major / minor axis of the inertia ellipse; slenderness =
    vertical / horizontal chord through the centroid (Equ. 5-2).
    """
    from skimage.measure import regionprops

    lab = np.asarray(grain_labels)
    if lab.ndim != 2:
        raise InputError(f"grain_labels: expected a 2-D array, got shape {lab.shape}")
    if not (pixel_size_um > 0):
        raise InputError(f"pixel_size_um: expected > 0, got {pixel_size_um}")
    ph = None if phase_labels is None else np.asarray(phase_labels)
    if ph is not None and ph.shape != lab.shape:
        raise InputError(f"phase_labels: expected shape {lab.shape}, got {ph.shape}")
    rows = []
    for rp in regionprops(lab.astype(np.int32)):
        if ph is not None:
            vals = ph[rp.slice][rp.image]
            vals = vals[vals > 0]
            phase = int(np.bincount(vals).argmax()) if vals.size else 0
        else:
            phase = 1
        if names is not None and 1 <= phase <= len(names):
            mineral = str(names[phase - 1])
        else:
            mineral = f"phase{phase}"
        major, minor = rp.axis_major_length, rp.axis_minor_length
        ang = (np.degrees(rp.orientation) + 90.0) % 180.0
        rows.append(dict(grain_id=rp.label, mineral=mineral, phase=phase,
                         area_um2=rp.area * pixel_size_um ** 2,
                         eq_diameter_um=np.sqrt(4 * rp.area / np.pi) * pixel_size_um,
                         aspect_ratio=major / minor if minor > 0 else np.inf,
                         orientation_deg=ang, slenderness=slenderness(rp.image),
                         centroid_x_um=rp.centroid[1] * pixel_size_um,
                         centroid_y_um=rp.centroid[0] * pixel_size_um))
    cols = ["grain_id", "mineral", "phase", "area_um2", "eq_diameter_um", "aspect_ratio",
            "orientation_deg", "slenderness", "centroid_x_um", "centroid_y_um"]
    return pd.DataFrame(rows, columns=cols)


def _edges(value, what):
    if isinstance(value, str):
        try:
            value = [float(v) for v in value.split(",")]
        except ValueError:
            raise InputError(f"{what}: expected 'e1,e2' in um, got {value!r}") from None
    e = tuple(float(v) for v in value)
    if len(e) != 2 or not (0 < e[0] < e[1]):
        raise InputError(f"{what}: expected two increasing edges 'fine/medium,medium/coarse' "
                         f"in um, got {value}")
    return e


def _parse_classes(classes):
    if classes is None:
        return None
    if isinstance(classes, dict):
        return {str(k): _edges(v, f"classes[{k!r}]") for k, v in classes.items()}
    return {None: _edges(classes, "classes")}


def grain_size_table(grains, *, classes=None, volume_fractions=None):
    """Build the grain-size table (``grains.csv``, DESIGN.md §4) from per-grain measurements.

    Parameters
    ----------
    grains : pandas.DataFrame
        Output of :func:`grain_table` (``mineral, area_um2, eq_diameter_um``).
    classes : (2,) sequence, "20,140" string, or dict {mineral: (e1, e2)}, optional
        Class edges in um: fine < e1 <= medium < e2 <= coarse. Default: the automatic rule,
        per mineral e1, e2 = the 10th and 90th count percentiles of its equivalent diameters.
    volume_fractions : dict {mineral: fraction}, optional
        Use these (e.g. phase-map pixel fractions) instead of the grain-area fractions.

    Returns
    -------
    table : pandas.DataFrame
        One row per (mineral, class): ``mineral, class, d_min_um, d_max_um, frequency_pct,
        volume_fraction_pct, d_mean_um, n_grains``. Minerals in order of decreasing volume.
        ``d_min_um``/``d_max_um`` are the class edges, closed by the smallest and largest grain
        measured; ``frequency_pct`` the share of the mineral's grains by count.

    Raises
    ------
    InputError
        Missing columns, no grains, bad class edges.

    Notes
    -----
    Volume fraction = area fraction in 2-D (Delesse principle).
    """
    for col in ("mineral", "area_um2", "eq_diameter_um"):
        if col not in grains.columns:
            raise InputError(f"grains table: missing column {col!r}")
    if len(grains) == 0:
        raise InputError("grains table: no grains")
    minerals = list(grains.groupby("mineral")["area_um2"].sum().sort_values(
        ascending=False).index)
    edges_cfg = _parse_classes(classes)
    total = grains["area_um2"].sum()
    rows = []
    for name in minerals:
        g = grains[grains["mineral"] == name]
        d = g["eq_diameter_um"].to_numpy(float)
        if edges_cfg is None:
            e1, e2 = np.percentile(d, AUTO_CLASS_PERCENTILES)
            if not e1 < e2:
                e2 = e1 * (1 + 1e-9) + 1e-12
        elif None in edges_cfg:
            e1, e2 = edges_cfg[None]
        elif str(name) in edges_cfg:
            e1, e2 = edges_cfg[str(name)]
        else:
            raise InputError(f"classes: no class edges given for mineral {name!r}")
        lo, hi = min(d.min(), e1), max(d.max(), e2)
        bounds = [(lo, e1), (e1, e2), (e2, hi)]
        cls_idx = np.digitize(d, [e1, e2])
        if volume_fractions is not None:
            vf = 100.0 * float(volume_fractions.get(name, 0.0))
        else:
            vf = 100.0 * g["area_um2"].sum() / total
        for c, cls in enumerate(("fine", "medium", "coarse")):
            sel = cls_idx == c
            rows.append(dict(mineral=name, **{"class": cls}, d_min_um=bounds[c][0],
                             d_max_um=bounds[c][1], frequency_pct=100.0 * sel.mean(),
                             volume_fraction_pct=vf,
                             d_mean_um=float(d[sel].mean()) if sel.any() else np.nan,
                             n_grains=int(sel.sum())))
    return pd.DataFrame(rows)


def _save(fig, path):
    import os
    path = str(path)
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def plot_grain_histograms(grains, path=None, *, bins=20):
    """Grain-size histograms per mineral (thesis Fig. 4-4 form); returns the Figure."""
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    minerals = list(dict.fromkeys(grains["mineral"]))
    fig, axes = plt.subplots(1, max(len(minerals), 1), figsize=(3.2 * max(len(minerals), 1), 3),
                             squeeze=False)
    for ax, name in zip(axes[0], minerals):
        d = grains.loc[grains["mineral"] == name, "eq_diameter_um"]
        ax.hist(d, bins=bins, color="0.4")
        ax.set_title(str(name))
        ax.set_xlabel("equivalent diameter (um)")
    axes[0][0].set_ylabel("grains")
    fig.tight_layout()
    if path is not None:
        _save(fig, path)
    return fig


def plot_grain_map(grain_labels, phase_labels=None, path=None, *, seed=0):
    """Segmented grain map: grains in random colours, boundaries in black; returns the Figure."""
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from skimage.segmentation import find_boundaries
    lab = np.asarray(grain_labels)
    rng = np.random.default_rng(seed)
    colours = rng.uniform(0.3, 1.0, (lab.max() + 1, 3))
    colours[0] = 0
    if phase_labels is not None:
        base = np.array([[0, 0, 0], [0.9, 0.5, 0.3], [0.4, 0.7, 0.9], [0.6, 0.9, 0.5],
                         [0.9, 0.9, 0.4], [0.7, 0.5, 0.9]])
        ph = np.asarray(phase_labels) % len(base)
        rgb = base[ph] * (0.75 + 0.25 * colours[lab][..., :1])
    else:
        rgb = colours[lab]
    rgb[find_boundaries(lab)] = 0
    fig = plt.figure(figsize=(6, 6 * lab.shape[0] / max(lab.shape[1], 1)))
    ax = fig.add_axes([0, 0, 1, 1])
    ax.imshow(rgb, interpolation="nearest")
    ax.axis("off")
    if path is not None:
        _save(fig, path)
    return fig


def phase_separability(image, n_phases, *, mask=None, median_px=PHASE_MEDIAN_PX):
    """Otsu's effectiveness eta = between-class / total grey variance of the phase split.

    Used to choose between the raw and the illumination-flattened image: a real lighting
    gradient smears the phase peaks of the raw image, a wrong flattening those of the flat one.
    """
    from skimage.filters import threshold_multiotsu
    g = _median(_as_grey(image), median_px)
    x = g if mask is None else g[~np.asarray(mask, bool)]
    x = x.ravel()
    if x.size > 200_000:
        x = x[:: int(np.ceil(x.size / 200_000))]
    var = x.var()
    if var <= 0:
        return 0.0
    cls = np.digitize(x, threshold_multiotsu(x, classes=n_phases))
    mu = x.mean()
    between = sum((cls == k).mean() * (x[cls == k].mean() - mu) ** 2
                  for k in range(n_phases) if (cls == k).any())
    return float(between / var)


def grains_stage(image, *, mask=None, pixel_size_um=1.0, names=None, n_phases=3,
                 min_diameter_um=None, seed=None, alt_image=None):
    """Phases, grains and the per-grain table of one image (the ``--grains`` stage).

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image (flattened if the lighting is uneven).
    mask : (M, N) ndarray of bool, optional
        Cracks and pores, excluded.
    pixel_size_um : float
    names : sequence of str, optional
        Mineral names brightest-first; their number sets the number of phases.
    n_phases : int
        Number of phases when ``names`` is not given.
    min_diameter_um : float, optional
        Smallest grain resolved; default 8 px.
    seed : int, optional
    alt_image : (M, N) ndarray, optional
        A second version of the image (e.g. raw when ``image`` is flattened); the one whose
        phases separate better (:func:`phase_separability`) is used.

    Returns
    -------
    grain_labels, phase_labels : (M, N) ndarray of int32
    grains : pandas.DataFrame
        :func:`grain_table` output.
    """
    n = len(names) if names else int(n_phases)
    if alt_image is not None and phase_separability(alt_image, n, mask=mask) > \
            phase_separability(image, n, mask=mask):
        image = alt_image
    ph, _ = mineral_phases(image, n, mask=mask, seed=seed)
    dmin = 8.0 if min_diameter_um is None else max(min_diameter_um / pixel_size_um, 2.0)
    lab = segment_grains(image, phase_labels=ph, mask=mask, min_diameter_px=dmin)
    return lab, ph, grain_table(lab, ph, pixel_size_um=pixel_size_um, names=names)


def parse_minerals(value):
    """``"pyroxene,plagioclase,biotite"`` -> names; ``"3"`` -> 3 unnamed phases."""
    if value is None:
        return None, 3
    v = str(value).strip()
    if v.isdigit():
        if int(v) < 2:
            raise InputError(f"--minerals: expected >= 2 phases, got {v}")
        return None, int(v)
    names = [s.strip() for s in v.split(",") if s.strip()]
    if len(names) < 2 or len(set(names)) != len(names):
        raise InputError(f"--minerals: expected >= 2 distinct names brightest-first, got {v!r}")
    return names, len(names)


def analyse_grains_folder(folder, out, *, minerals=None, classes=None, pixel_size_um=None,
                          progress=False, seed=None, **options):
    """``semkit grains DIR``: grain map, per-grain table and ``grains.csv`` for a folder.

    Writes ``grains_per_grain.csv`` (every grain of every image), ``grains.csv`` (the
    grain-size table over all images), ``grain_maps/<name>_grains.png`` and
    ``grain_histograms.png`` to ``out``.

    Parameters
    ----------
    folder, out : path
    minerals : str, optional
        ``--minerals`` value (names brightest-first, or a number of phases).
    classes : str, optional
        ``--classes`` value (``"20,140"``); default the automatic rule.
    pixel_size_um : float, optional
        Fallback pixel size.
    **options
        Crack-pipeline options (cracks are masked out before grains are measured).

    Returns
    -------
    table : pandas.DataFrame
        The grain-size table written to ``grains.csv``.
    """
    import pathlib

    from .io import list_images, load_image, read_manifest, write_csv_atomic
    from .pipeline import AnalysisOptions, CrackAnalysis
    folder, out = pathlib.Path(folder), pathlib.Path(out)
    names, n = parse_minerals(minerals)
    files = list_images(folder)
    if not files:
        raise InputError(f"{folder}: no image files found")
    man = read_manifest(folder)
    mrows = {} if man is None else {str(r["image"]): r for r in man.to_dict("records")}
    opts = AnalysisOptions(**options)
    (out / "grain_maps").mkdir(parents=True, exist_ok=True)
    tables = []
    it = files
    if progress:
        from tqdm import tqdm
        it = tqdm(files, unit="img", desc="semkit grains")
    for p in it:
        li = load_image(p, manifest_row=mrows.get(p.name), pixel_size_um=pixel_size_um)
        a = CrackAnalysis(li.image, pixel_size_um=li.pixel_size_um, name=p.name, options=opts)
        lab, ph, g = grains_stage(a.flat, mask=a.object_mask, pixel_size_um=li.pixel_size_um,
                                  names=names, n_phases=n, seed=seed, alt_image=a.image)
        g.insert(0, "image", p.name)
        tables.append(g)
        import matplotlib.pyplot as plt
        fig = plot_grain_map(lab, ph, out / "grain_maps" / f"{p.stem}_grains.png")
        plt.close(fig)
    allg = pd.concat(tables, ignore_index=True)
    table = grain_size_table(allg, classes=classes)
    write_csv_atomic(allg, out / "grains_per_grain.csv")
    write_csv_atomic(table, out / "grains.csv")
    import matplotlib.pyplot as plt
    plt.close(plot_grain_histograms(allg, out / "grain_histograms.png"))
    return table
