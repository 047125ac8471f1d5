"""Stage 3: threshold the grey image into dark crack pixels.

Methods (``method`` strings accepted by :func:`crack_mask`):

``manual:VALUE``
    pixels darker than VALUE (on the grey scale of the image given, i.e. after flattening).
``otsu``
    global Otsu threshold (fine when cracks are a large share; it splits mineral phases when they
    are a few % and minerals' grey levels are far apart — then ``auto`` is the method).
``local``
    adaptive: darker than ``(1 - offset)`` x the local Gaussian mean over a block.
``auto``
    dark-class analysis (:func:`dark_class_levels`): the darkest mineral peak of the histogram
    and its noise width, the crack core grey level below it; then a pixel-wise partial-volume
    midpoint between the *local* background (normalised convolution over non-crack pixels) and
    the crack core. Thin cracks are detected at a weaker level and kept by hysteresis only if
    they hold a pixel past the midpoint (see :data:`semkit.config.AUTO_DETECT_FRACTION`).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from . import config
from .errors import InputError
from .robust import group_medians, median

__all__ = ["ThresholdResult", "DarkLevels", "dark_class_levels", "noise_sigma", "coverage",
           "threshold_otsu",
           "threshold_local", "threshold_auto", "crack_mask", "parse_method"]


@dataclasses.dataclass
class DarkLevels:
    """Grey levels found by :func:`dark_class_levels` (image units)."""

    mineral: float      #: the darkest mineral peak
    sigma: float        #: its noise width (std)
    crack: float        #: crack core level (NaN when no dark class)
    seed: float         #: the dark-tail level, ``mineral - DARK_TAIL_SIGMAS * sigma``
    n_dark: int         #: pixels below ``seed``
    noise: float = float("nan")  #: pixel-noise sigma (:func:`noise_sigma`)
    #: False when no crack is wide enough to show its core grey: ``crack`` is then assumed
    resolved: bool = True
    #: median grey of the flat interior pixels (the plateaus); NaN when not resolved
    flat_crack: float = float("nan")
    #: share of the flat interior pixels on plateaus brighter than the void (a brighter dark
    #: phase, left out of the void grey with the pores, :func:`_void_components`); 0 when none
    #: stands apart
    phase_share: float = 0.0
    #: share of the darkest mineral phase (on the closed image) in long, narrow objects
    #: (:func:`_elongated_share`); 0 when it is the only phase
    line_share: float = 0.0
    #: True when every plateau of the dark class lies above the cores of thinner cracks (a
    #: dark phase): ``crack`` is then read on those cores and ``resolved`` is False
    phase_plateaus: bool = False
    #: True when the void grey was read on compact blobs alone (:func:`_compact_void`)
    compact_void: bool = False


@dataclasses.dataclass
class ThresholdResult:
    """Output of :func:`crack_mask`.

    Attributes
    ----------
    mask : (M, N) bool
        Crack pixels counted for area.
    detect_mask : (M, N) bool
        Crack pixels used to find objects and skeletons (``mask`` or a superset of it).
    method : str
    value : float
        The global threshold (for ``auto`` the grey level midway between the darkest mineral
        and the crack core; the decision itself is local). NaN for ``local``.
    dark_fraction : float
        Share of the image in ``mask``.
    ok : bool
        False when the dark class looks like a mineral phase rather than cracks.
    note : str
        Why ``ok`` is False, else empty.
    """

    mask: np.ndarray
    detect_mask: np.ndarray
    method: str
    value: float
    dark_fraction: float
    ok: bool = True
    note: str = ""
    background: np.ndarray | None = None   #: local background grey (``auto`` only)
    crack_level: float = float("nan")      #: crack core grey (``auto`` only)
    noise: float = float("nan")            #: fine-scale noise sigma (``auto`` only)
    contrast: float = float("nan")         #: darkest mineral minus crack grey (``auto`` only)
    #: void grey (``auto`` only): the crack grey read on flat cores (plateaus) when some crack
    #: shows one, else ``crack_level``; areas are measured against it
    void_level: float = float("nan")
    #: share of the dark class's flat cores on plateaus brighter than the void (a dark phase,
    #: ``DarkLevels.phase_share``; ``auto`` only)
    dark_phase_share: float = 0.0
    #: True when ``void_level`` was read on plateaus (flat crack cores), False when assumed
    #: (no crack shows its core) or not ``auto``
    void_read: bool = False

    @property
    def contrast_to_noise(self) -> float:
        """Crack contrast over the fine-scale noise (:func:`field_noise_sigma`); NaN
        unless ``auto`` found a crack grey darker than the darkest mineral."""
        ok = self.noise > 0 and self.contrast > 0
        return float(self.contrast / self.noise) if ok else float("nan")


def parse_method(method: str):
    """Split a method string: ``"manual:80"`` -> ``("manual", 80.0)``; checks the name."""
    m = str(method).strip().lower()
    if m.startswith("manual"):
        try:
            return "manual", float(m.split(":", 1)[1])
        except (IndexError, ValueError):
            raise InputError(f"threshold: expected 'manual:VALUE' with a number, got {method!r}") \
                from None
    if m in ("auto", "otsu", "local"):
        return m, None
    raise InputError(f"threshold: expected auto, otsu, local or manual:VALUE, got {method!r}")


def _hist(img, lo, hi, bins=256):
    h, edges = np.histogram(img, bins=bins, range=(lo, hi))
    return h.astype(np.float64), 0.5 * (edges[1:] + edges[:-1])


def _percentiles(a, q):
    """Fast approximate percentiles from a 4096-bin histogram (no sort)."""
    mn, mx = float(a.min()), float(a.max())
    if mx <= mn:
        return mn, mx
    h, c = _hist(a.ravel(), mn, mx, bins=4096)
    cdf = np.cumsum(h) / h.sum() * 100.0
    return tuple(float(c[min(int(np.searchsorted(cdf, qq)), len(c) - 1)]) for qq in q)


def threshold_otsu(image) -> float:
    """Global Otsu threshold of a grey image (cracks are the pixels below it).

    Examples
    --------
    >>> img = np.r_[np.full(50, 20.0), np.full(50, 200.0)]
    >>> 20 < threshold_otsu(img) < 200
    True
    """
    a = np.asarray(image, np.float64).ravel()
    lo, hi = float(a.min()), float(a.max())
    if hi <= lo:
        return lo
    h, c = _hist(a, lo, hi)
    w0 = np.cumsum(h)
    w1 = w0[-1] - w0
    m0 = np.cumsum(h * c)
    mt = m0[-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        between = (mt * w0 / w0[-1] - m0) ** 2 / (w0 * w1)
    between[~np.isfinite(between)] = -1
    return float(c[int(np.argmax(between))] + 0.5 * (c[1] - c[0]))


def threshold_local(image, *, block_size=config.LOCAL_BLOCK_PX,
                    offset=config.LOCAL_OFFSET_FRACTION):
    """Adaptive threshold image: ``(1 - offset) * local Gaussian mean`` over ``block_size``.

    Returns
    -------
    threshold : (M, N) ndarray of float32
    """
    import cv2
    if block_size < 3:
        raise ValueError(f"block_size: expected >= 3 px, got {block_size}")
    img = np.asarray(image, np.float32)
    mean = cv2.GaussianBlur(img, (0, 0), block_size / 6.0, borderType=cv2.BORDER_REFLECT)
    return (1.0 - offset) * mean


def dark_class_levels(image) -> DarkLevels:
    """Find the darkest mineral grey level, its noise width and the crack core level.

    Mineral phases are found on a grey *closing* of the image (an 11 x 11 square removes
    every dark feature narrower than ~10 px: cracks, specks, boundaries), so a crack class of
    a few % can never pass for a mineral: the darkest peak of the closed image's histogram
    holding at least ``MINERAL_MIN_FRACTION`` of the pixels is the darkest mineral. Its level
    and noise sigma (half-maximum on the dark side / 1.1774) are then read on the histogram
    of the image itself. Pixels below ``mineral - DARK_TAIL_SIGMAS * sigma`` form the dark
    class; the crack core level is the median of its interior pixels when some crack shows a
    plateau (flat core), else assumed from the tail's mode (the epoxy/void grey). Plateaus
    that the cores of thinner cracks undercut are a dark phase's (``phase_plateaus``): the
    crack grey is then read on those cores (:func:`_void_components`).
    """
    import cv2

    from .peaks import prominent_peaks, smooth_profile
    a = np.asarray(image, np.float32)
    step = max(int(np.ceil(np.sqrt(a.size / 300_000))), 1)
    sub = np.ascontiguousarray(a[::step, ::step])
    sn = noise_sigma(a)
    lo, hi = _percentiles(sub, (0.01, 99.99))
    if hi <= lo:
        return DarkLevels(lo, 1.0, float("nan"), lo, 0, sn)
    ksz = max(11 // step, 5) | 1
    closed = cv2.morphologyEx(sub, cv2.MORPH_CLOSE, np.ones((ksz, ksz), np.uint8))
    hc, c = _hist(closed.ravel(), lo, hi)
    hcs = smooth_profile(hc, 2.0)
    peaks = prominent_peaks(np.r_[0.0, hcs, 0.0], 0.01 * hcs.max())
    peaks = peaks - 1
    if peaks.size == 0:
        peaks = np.array([int(np.argmax(hcs))])
    bounds = [0] + [int(peaks[i] + np.argmin(hcs[peaks[i]:peaks[i + 1] + 1]))
                    for i in range(len(peaks) - 1)] + [len(hcs)]
    mass = np.array([hcs[bounds[i]:bounds[i + 1]].sum() for i in range(len(peaks))]) / max(
        hcs.sum(), 1e-12)
    major = np.flatnonzero(mass >= config.MINERAL_MIN_FRACTION)
    q = int(major[0]) if major.size else int(np.argmax(mass))
    # a darkest "phase" lying largely in long, narrow objects may be cracks wider than the
    # closing, not a mineral (measured here, flagged by threshold_auto)
    line_share = _elongated_share(_phase_mask(closed, c, bounds, q), step) \
        if major.size > 1 else 0.0
    # refine on the image's own histogram: the local maximum near the closed-image peak
    # (closing shifts a noisy level up by ~1-2 sigma)
    h, _ = _hist(sub.ravel(), lo, hi)
    hs = smooth_profile(h, 2.0)
    p0 = int(peaks[q])
    win = max(int(0.1 * len(hs)), 3)
    lo_i = max(bounds[q] - win // 2, 0)
    p = lo_i + int(np.argmax(hs[lo_i:p0 + 1]))
    half = hs[p] / 2
    left = p
    while left > 0 and hs[left] > half:
        left -= 1
    sigma = max((c[p] - c[left]) / 1.1774, (c[1] - c[0]))
    mineral = float(c[p])
    # the dark tail starts a few peak widths below the mineral, or (when the peak is wide
    # because grains differ, not because of noise) DARK_TAIL_NOISE_SIGMAS pixel-noise sigmas
    seed = mineral - min(config.DARK_TAIL_SIGMAS * sigma,
                         max(3.0 * sigma, config.DARK_TAIL_NOISE_SIGMAS * sn))
    tail = sub[sub < seed]
    n_dark = int(tail.size * a.size / max(sub.size, 1))
    crack = flat_crack = float("nan")
    resolved = True
    phase_share = 0.0
    below = np.zeros(0, np.float32)   # dark-class pixels under every plateau
    compact = False                   # the void's plateaus all on compact blobs
    if tail.size >= 20:
        # interior pixels of cracks >= 3 px wide carry the core grey; thin cracks only
        # partial volumes, so they are used only when there is no interior at all
        dark = (sub < seed).view(np.uint8)
        interior = cv2.erode(dark, np.ones((3, 3), np.uint8)).view(bool)
        core = sub[interior]
        max_range = max(config.FLAT_CORE_SIGMAS * sn, config.FLAT_CORE_CONTRAST
                        * (mineral - float(np.median(core)))) if core.size >= 20 else 0.0
        flat, flat_at = _flat_core_values(a, interior, step, max_range) \
            if core.size >= 20 else (np.zeros(0, np.float32), np.zeros(0, np.int64))
        resolved = flat.size >= config.MIN_FLAT_CORE_PX
        full = _full_resolution_plateaus(a, seed, sn, max_range) if step > 2 else None
        vstep, comps = step, None
        if full is not None:  # the void is read on them
            dark, flat, flat_at, comps = full
            vstep = 1
        if resolved or full is not None:
            # the void grey leaves out plateaus at a brighter grey (laths of a dark mineral);
            # detection keeps the dark class's median (its levels were set on it)
            void, phase_share, below, compact = _void_components(
                dark, flat, flat_at, sn, mineral, vstep, components=comps,
                grey=sub if full is None else a, check_compact=True)
        if below.size:
            # every plateau lies above the cores of thinner cracks: a dark phase; the
            # void is at most as dark as those cores
            crack = float(np.percentile(below, config.LINE_CRACK_PERCENTILE))
            resolved = False
        elif resolved or full is not None:
            crack = float(np.median(core)) if core.size >= 20 else float(np.median(flat))
            resolved = True
            flat_crack = float(np.median(flat if void is None else flat[void]))
        else:  # all cracks thin: their darkest values are partial volumes; the core is
            # assumed at least as dark as 30 % of the darkest mineral (epoxy / void in BSE)
            th, tc = _hist(tail, float(tail.min()), float(seed), bins=64)
            crack = min(float(tc[int(np.argmax(smooth_profile(th, 1.5)))]),
                        config.THIN_ONLY_CRACK_RATIO * mineral)
    return DarkLevels(mineral, float(sigma), crack, float(seed), n_dark, sn, resolved=resolved,
                      flat_crack=flat_crack, phase_share=phase_share, line_share=line_share,
                      phase_plateaus=bool(below.size), compact_void=compact)


def _compact_void(comp, at, moments, step=1):
    """Whether every plateau pixel holding the void lies in a compact blob.

    A blob's principal axes lie less than ``VOID_COMPACT_ASPECT`` apart and it fills at least
    ``VOID_COMPACT_FILL`` of its equivalent ellipse (a pore, a round or lens-shaped grain).
    A component of the dark class holding plateau pixels is one, or it is opened by a disc
    ``REJECT_COMPACT_WIDTH_PX`` wide, so thin cracks joined to a blob fall away, and its
    plateau pixels must lie in blobs of the opened mask.

    Parameters
    ----------
    comp : (M, N) ndarray of int32
        The dark class's 8-connected components (the image subsampled by ``step``).
    at : (K,) ndarray of int
        Flat indices (in ``comp``) of the plateau pixels holding the void.
    moments : tuple
        ``object_moments(comp, n, origin=True)``.

    Returns
    -------
    bool
        False when any plateau pixel lies outside a blob (a crack shows the void).
    """
    import cv2

    from .measure import ellipse_shape, object_moments
    if at.size == 0:
        return False
    s2 = float(step) ** 2

    def blob(area, mxx, myy, mxy):
        aspect, fill = ellipse_shape(area * s2, mxx * s2, myy * s2, mxy * s2)
        return (aspect < config.VOID_COMPACT_ASPECT) & (fill >= config.VOID_COMPACT_FILL)

    area, _, _, mxx, myy, mxy, bw, bh, bx, by = moments
    lab = comp.ravel()[at]
    ids, cnt = np.unique(lab, return_counts=True)
    whole = blob(area[ids], mxx[ids], myy[ids], mxy[ids])
    k = max(int(round(config.REJECT_COMPACT_WIDTH_PX / step)), 3) | 1
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    rr, cc = np.divmod(at, comp.shape[1])
    for c in ids[~whole][np.argsort(-cnt[~whole])]:  # most plateau pixels first
        x, y, w, h = int(bx[c]), int(by[c]), int(bw[c]), int(bh[c])
        one = (comp[y:y + h, x:x + w] == c).view(np.uint8)
        opened = cv2.morphologyEx(one, cv2.MORPH_OPEN, disc, borderType=cv2.BORDER_CONSTANT,
                                  borderValue=0)  # outside the box is not this component
        m, blobs = cv2.connectedComponents(opened, connectivity=8)
        b = blobs[rr[lab == c] - y, cc[lab == c] - x]
        if (b == 0).any():
            return False
        u = np.unique(b)
        ba, _, _, bxx, byy, bxy, _, _ = object_moments(blobs, m - 1)
        if not blob(ba[u], bxx[u], byy[u], bxy[u]).all():
            return False
    return True


def _phase_mask(closed, centres, bounds, k):
    """Pixels of the closed image in histogram peak ``k``'s range (between its valleys)."""
    lo = centres[bounds[k]] if bounds[k] > 0 else -np.inf
    hi = centres[bounds[k + 1]] if bounds[k + 1] < len(centres) else np.inf
    return (closed >= lo) & (closed < hi)


def _elongated_share(mask, step=1):
    """Share of the pixels of ``mask`` (an image subsampled by ``step``) in line-like objects:
    8-connected components whose principal second moments differ by ``LINE_PHASE_ELONGATION``
    squared or more and whose widest point (twice the largest distance to their edge) is at
    most ``LINE_PHASE_MAX_WIDTH_PX`` of the full image. Grains, and a mineral's matrix around
    them, are about as long as wide, and an elongated cluster of grains is wide; a crack, even
    40 px wide, is many times longer than wide (crossing cracks, closed into one network,
    less so)."""
    import cv2

    from .measure import object_moments
    m8 = np.ascontiguousarray(mask).view(np.uint8)
    n, lab = cv2.connectedComponents(m8, connectivity=8)
    if n <= 1:
        return 0.0
    area, _, _, mxx, myy, mxy, _, _ = object_moments(lab, n - 1)
    half = 0.5 * (mxx + myy)
    disc = np.sqrt(0.25 * (mxx - myy) ** 2 + mxy ** 2)
    widest = np.zeros(n, np.float32)
    np.maximum.at(widest, lab.ravel(), cv2.distanceTransform(m8, cv2.DIST_L2, 3).ravel())
    line = ((half + disc) >= config.LINE_PHASE_ELONGATION ** 2 * np.maximum(half - disc, 1e-2)) \
        & (2.0 * step * widest <= config.LINE_PHASE_MAX_WIDTH_PX)
    line[0] = False
    return float(area[line].sum() / max(area[1:].sum(), 1.0))


def _plateaus(image, mask, interior, max_range):
    """Flat pixels of ``interior`` and the components of ``mask``, or None when no object of
    ``mask`` holds a plateau.

    The flat pixels are those of :func:`_flat_core_values` (full resolution); one 8-connected
    component of ``mask`` (uint8) must hold at least ``DETECTED_PLATEAU_MIN_PX`` of them: where
    blurred 3-px lines cross, the flat spot is a partial volume of a few tens of px.

    Returns
    -------
    (flat, flat_at, components) or None
        The flat pixels' grey and raveled indices, and
        ``cv2.connectedComponents(mask, connectivity=8)``.
    """
    import cv2
    if np.count_nonzero(interior) < config.DETECTED_PLATEAU_MIN_PX:
        return None
    flat, flat_at = _flat_core_values(image, interior, 1, max_range)
    if flat.size < config.DETECTED_PLATEAU_MIN_PX:
        return None
    comps = cv2.connectedComponents(mask, connectivity=8)
    if np.bincount(comps[1].ravel()[flat_at]).max() < config.DETECTED_PLATEAU_MIN_PX:
        return None
    return flat, flat_at, comps


def _full_resolution_plateaus(image, seed, noise, max_range):
    """The dark class's plateaus read at full resolution, or None when no crack holds one.

    :func:`dark_class_levels` reads the dark class on the image subsampled by ``step``, where
    a plateau needs 3 x ``step`` px of width: 6 px up to 1.2 MP, 12 px on a 3-MP image (8-px
    cracks showed none, and a dark grain's plateau was taken for the void). Used from step 3
    on, so the width stays that of step 2: the interior is the dark class eroded by 7 x 7 at
    full resolution (cracks >= 7 px wide), and :func:`_plateaus` reads its flat pixels
    (``max_range`` as there, or ``FLAT_CORE_SIGMAS`` noise sigmas when 0).

    Returns
    -------
    (dark, flat, flat_at, components) or None
        The full-resolution dark mask (uint8) and :func:`_plateaus`' output.
    """
    import cv2
    dark = (image < np.float32(seed)).view(np.uint8)
    interior = cv2.erode(dark, np.ones((7, 7), np.uint8)).view(bool)
    found = _plateaus(image, dark, interior, max_range or config.FLAT_CORE_SIGMAS * noise)
    return None if found is None else (dark, *found)


def _flat_core_values(image, interior, step, max_range):
    """Grey of the ``interior`` pixels (of the image subsampled by ``step``) that have a flat
    3 x 3 neighbourhood in the full image: grey range at most ``max_range``; and the flat
    pixels' raveled indices in the subsampled image."""
    from . import _kernels
    rr0, cc0 = _kernels.pixel_coords(interior)
    rr, cc = rr0 * step, cc0 * step
    h, w = image.shape
    ok = (rr > 0) & (cc > 0) & (rr < h - 1) & (cc < w - 1)
    rr, cc = rr[ok], cc[ok]
    lo = np.full(rr.size, np.inf, np.float32)
    hi = np.full(rr.size, -np.inf, np.float32)
    for i in (-1, 0, 1):
        for j in (-1, 0, 1):
            v = image[rr + i, cc + j]
            np.minimum(lo, v, out=lo)
            np.maximum(hi, v, out=hi)
    flat = hi - lo <= max_range
    at = (rr0[ok][flat].astype(np.int64) * interior.shape[1] + cc0[ok][flat])
    return image[rr, cc][flat], at


def _void_components(dark, flat, flat_at, noise, mineral, step=1, components=None, grey=None,
                     check_compact=False):
    """Which flat-core pixels of the dark class hold the void of the open cracks.

    Pores (compact, full components of ``dark``, :func:`semkit.measure.is_pore` at the full
    image's scale: ``dark`` is subsampled by ``step``) are left out when at least
    ``MIN_FLAT_CORE_PX`` flat pixels remain: a pore's flat core, often darker than the
    cracks' (a deeper hole), would otherwise outweigh the few flat pixels of cracks a few px
    wide. Every other 8-connected component holding flat-core pixels has a plateau grey
    (their median); the darkest of those with at least ``VOID_PLATEAU_MIN_PX`` is the void,
    and components, small ones too, whose plateau lies more than ``VOID_PLATEAU_BAND`` above
    it (noise sigmas, or that share of the mineral-to-void contrast, whichever is larger) are
    a dark phase (laths of a dark mineral), not open cracks: many small laths together would
    otherwise outweigh one crack's plateau. When no open component holds that many, the
    pores' plateaus are the reference instead (a dark mineral in round grains passes for
    pores, and the few open flat pixels left may be a lath's), provided some open component
    lies within the band of the darkest (pores darker than every crack, a deeper hole, show
    no dark phase).

    With ``grey`` (the image ``dark`` was taken from, at its scale), the darkest plateau is
    checked too: partial volumes are brighter than the void, never darker, so when at least
    ``VOID_UNDERCUT_SHARE`` of the non-pore dark pixels (and ``VOID_PLATEAU_MIN_PX`` at the
    full scale) lie more than the band below it, no plateau holds the void: all are a dark
    phase's, and those darker pixels are returned.

    ``components`` may pass ``cv2.connectedComponents(dark, connectivity=8)`` when the caller
    has it already. With ``check_compact``, whether the void's plateau pixels all lie on
    compact blobs is read too (:func:`_compact_void`).

    Returns
    -------
    keep : (len(flat),) ndarray of bool or None
        Which flat-core pixels hold the void; None when every pixel does (all False when the
        plateaus are undercut).
    phase_share : float
        Share of the flat-core pixels on the brighter plateaus (0 when none; 1 when every
        plateau is undercut).
    below : ndarray of float32
        Grey of the dark pixels under every plateau (empty unless they undercut them).
    compact : bool
        The void's plateau pixels all lie on compact blobs (False unless ``check_compact``,
        and when the plateaus are undercut).
    """
    import cv2

    from .measure import is_pore, object_moments
    n, comp = cv2.connectedComponents(dark, connectivity=8) if components is None \
        else components
    lab = comp.ravel()[flat_at]
    moments = object_moments(comp, n - 1, origin=True)
    area, _, _, mxx, myy, mxy = moments[:6]
    s2 = float(step) ** 2
    pore = is_pore(area * s2, mxx * s2, myy * s2, mxy * s2)
    pore[0] = False
    keep = np.ones(n, bool)
    below = np.zeros(0, np.float32)
    if np.count_nonzero(~pore[lab]) >= config.MIN_FLAT_CORE_PX:
        keep &= ~pore
    cnt = np.bincount(lab, minlength=n)
    big = np.flatnonzero((cnt >= config.VOID_PLATEAU_MIN_PX) & keep)
    big = big[big > 0]
    # with no open plateau of VOID_PLATEAU_MIN_PX, the pores' plateaus are the reference
    ref = big if big.size else np.flatnonzero((cnt >= config.VOID_PLATEAU_MIN_PX) & ~keep)
    ref = ref[ref > 0]
    above = np.zeros(0, np.int64)
    if ref.size:
        # every component holding flat-core pixels has a plateau grey (their median); the
        # darkest of the reference is the void, and any kept component, small ones too,
        # lying more than the band above it is a dark phase's
        held = np.flatnonzero(cnt[1:]) + 1
        plateau = group_medians(flat, lab, cnt)[held]
        void = float(plateau[np.isin(held, ref)].min())
        band = max(config.VOID_PLATEAU_BAND * noise,
                   config.VOID_PLATEAU_CONTRAST * (float(mineral) - void))
        kept = keep[held]
        above = held[kept & (plateau > void + band)]
        if not big.size and not (kept & (plateau <= void + band)).any():
            above = above[:0]   # pores darker than every crack: no evidence of a dark phase
        keep[above] = False
        if grey is not None and big.size:
            # partial volumes are brighter than the void, never darker: dark pixels (not
            # pores) well below the darkest plateau show a darker void, and the plateaus
            # are a dark phase
            gv = np.asarray(grey).ravel()
            at = np.flatnonzero(gv < void - band)
            c = comp.ravel()[at]
            at = at[(c > 0) & ~pore[c]]
            open_px = float(area[1:][~pore[1:]].sum())
            if at.size * s2 >= config.VOID_PLATEAU_MIN_PX \
                    and at.size >= config.VOID_UNDERCUT_SHARE * open_px:
                below = gv[at]
    if below.size:
        return np.zeros(len(flat), bool), 1.0, below, False
    compact = check_compact and _compact_void(comp, flat_at[keep[lab]], moments, step)
    if keep[lab].all():
        return None, 0.0, below, compact
    return keep[lab], float(cnt[above].sum()) / max(len(flat), 1), below, compact


def _detected_void(image, mask, noise, mineral):
    """Void grey read on the flat cores of the objects of ``mask``, or NaN when they have none.

    For an image whose dark class shows no plateau (:func:`dark_class_levels`, ``resolved``
    False): cracks as dark as a dark mineral lie above the dark class, yet the threshold finds
    them by their depth below the local background. ``mask`` is the midpoint mask on the darker
    guess of the crack grey (a blurred line's detect mask is wide, its midpoint mask is not).
    Its pixels at least ``DETECTED_CORE_PX`` from its edge (the cores of cracks >= 5 px wide)
    are the candidates, one object holding a plateau of them (:func:`_plateaus`); pores and
    brighter plateaus (a dark phase) are left out by :func:`_void_components`, and the void
    grey is the median of the rest.
    """
    import cv2
    mask = np.ascontiguousarray(mask).view(np.uint8)
    interior = cv2.distanceTransform(mask, cv2.DIST_L2, 5) >= config.DETECTED_CORE_PX
    core = image[interior]
    if core.size < config.DETECTED_PLATEAU_MIN_PX:
        return float("nan")
    found = _plateaus(image, mask, interior, max(
        config.FLAT_CORE_SIGMAS * noise,
        config.FLAT_CORE_CONTRAST * (mineral - float(median(core)))))
    if found is None:
        return float("nan")
    flat, flat_at, comps = found
    void, _, below, _ = _void_components(mask, flat, flat_at, noise, mineral, components=comps,
                                      grey=image)
    if below.size:
        return float("nan")
    return float(np.median(flat if void is None else flat[void]))


def line_crack_level(image, mineral, noise, *, closed=None):
    """Crack grey read on narrow dark lines in the rock, and the share of the image they hold.

    Used when no pixel is darker than the darkest mineral phase, as when a dark mineral is as
    dark as the partial volumes of thin cracks. A line pixel lies more than
    ``AUTO_SEED_SIGMAS`` noise sigmas and ``AUTO_SEED_FRACTION`` of the local contrast below
    the image's 7 x 7 grey closing (which fills every dark feature narrower than ~6 px and
    leaves grains, however dark, as they are), where that closing is itself that many sigmas
    above the darkest mineral (inside a dark grain every noise dip would count), in a
    component of at least ``LINE_MIN_COMPONENT_PX`` (specks and grain corners are smaller).
    The crack grey is the ``LINE_CRACK_PERCENTILE`` percentile of the line pixels: the cores
    of the widest lines (the lines' median would mix in partial volumes, read the crack grey
    too bright and inflate every partial-volume area).

    ``closed`` may pass the image's 7 x 7 grey closing when the caller has it already.

    Returns
    -------
    level : float
        Crack grey; NaN when there are no line pixels.
    share : float
        Line pixels over image pixels.
    """
    import cv2
    img = np.ascontiguousarray(image, np.float32)
    if closed is None:
        closed = cv2.morphologyEx(img, cv2.MORPH_CLOSE, np.ones((7, 7), np.uint8))
    line = closed - img
    lift = closed - np.float32(mineral)
    deep = np.float32(config.AUTO_SEED_SIGMAS * noise)
    on = (line > deep) & (line > np.float32(config.AUTO_SEED_FRACTION) * lift) & (lift > deep)
    n, lab, stats, _ = cv2.connectedComponentsWithStats(on.view(np.uint8), connectivity=8)
    big = np.r_[False, stats[1:, cv2.CC_STAT_AREA] >= config.LINE_MIN_COMPONENT_PX]
    vals = img[big[lab]]
    if vals.size == 0:
        return float("nan"), 0.0
    return (float(_percentiles(vals, (config.LINE_CRACK_PERCENTILE,))[0]),
            float(vals.size) / img.size)


def _local_background(img, exclude, *, band, n_rings=4, max_rings=64):
    """Grey level the image would have without the excluded (dark) pixels.

    Known pixels keep their own value. Excluded pixels are filled ring by ring from their known
    3 x 3 neighbours (:func:`semkit._kernels.fill_excluded`): of those neighbours, the ones
    within ``band`` of the darkest are averaged, so next to a phase boundary the rim of a
    crack, or the boundary line itself, takes the grey of one phase — a plain box mean would
    mix a dark and a bright mineral and make the dark one look like crack. The first
    ``n_rings`` rings decide the rim; filling goes on (up to ``max_rings``) into the core of wide
    cracks, where the decision does not depend on it; anything left takes the median.
    """
    from . import _kernels
    val, known, left = _kernels.fill_excluded(np.ascontiguousarray(img, np.float32),
                                              np.ascontiguousarray(exclude, bool),
                                              int(max_rings), float(band))
    if left:
        rest = known == 0
        val[rest] = float(np.median(img[~exclude])) if (~exclude).any() else float(img.max())
    return val


def _highpass_mad(image, k):
    """MAD of the image minus its k x k mean, every other pixel of a central 512 x 512 crop
    (a crop is plenty; edges and cracks are a minority and do not enter)."""
    import cv2
    a = np.asarray(image, np.float32)
    h, w = a.shape
    if h * w > 512 * 512:
        r0, c0 = max((h - 512) // 2, 0), max((w - 512) // 2, 0)
        a = np.ascontiguousarray(a[r0:r0 + 512, c0:c0 + 512])
    hp = a - cv2.blur(a, (k, k), borderType=cv2.BORDER_REFLECT)
    e = k // 2
    v = hp[e:-e:2, e:-e:2].ravel()
    return median(np.abs(v - median(v)))


def noise_sigma(image) -> float:
    """Robust pixel-noise sigma: MAD of the image minus its 3 x 3 mean (/0.943 for white
    noise), on a subsample; smooth texture and grain contrast do not enter."""
    return float(1.4826 * _highpass_mad(image, 3) / 0.943) + 1e-6


def field_noise_sigma(image) -> float:
    """Robust std of the image's fine-scale fluctuation: the noise as a detector sees it on a
    smoothed image (where it is correlated over a few pixels, so the pixel-to-pixel
    :func:`noise_sigma` reads it low). MAD of the image minus its 5 x 5 mean."""
    return float(1.4826 * _highpass_mad(image, 5)) + 1e-6


def _operand(x):
    """A scalar as NumPy uses it against a float32 array: a Python number is cast to float32
    (NEP 50), a NumPy scalar keeps its type."""
    return np.float32(x) if type(x) in (float, int) else x


def threshold_auto(image, *, area_fraction=config.AUTO_AREA_FRACTION,
                   detect_fraction=config.AUTO_DETECT_FRACTION,
                   seed_fraction=config.AUTO_SEED_FRACTION) -> ThresholdResult:
    """The ``auto`` crack threshold on a flattened, denoised grey image (see module doc).

    Three levels below the local background ``bg``, as fractions of the local contrast
    ``bg - crack`` (each at least a few noise sigmas deep): *area* (the partial-volume
    midpoint, 0.5), *seed* and *detect*. Objects are the components of the detect mask
    that hold a seed pixel (hysteresis); area counts the pixels past the midpoint, except for
    thin objects, measured by partial volume (:func:`coverage`).

    Returns
    -------
    result : ThresholdResult
    """
    import cv2

    from . import _kernels
    img = np.asarray(image, np.float32)
    lv = dark_class_levels(img)

    def flagged(r):
        """``r``, not ok when the darkest mineral phase lies largely in long, narrow objects:
        cracks wider than the closing pass for a mineral and are missed."""
        if lv.line_share >= config.LINE_PHASE_MIN_SHARE:
            r.ok = False
            r.note = "; ".join(t for t in (r.note, (
                f"the darkest mineral phase (grey {lv.mineral:.4g}) lies {lv.line_share:.0%} "
                f"in long objects at most {config.LINE_PHASE_MAX_WIDTH_PX:g} px wide: cracks "
                "wider than about 10 px may pass for a mineral and be missed")) if t)
        return r

    # a 7 x 7 grey closing fills every dark feature narrower than ~6 px: the narrow dark lines
    # of the no-dark-class branch and of the candidates below lie well under it
    closed = cv2.morphologyEx(img, cv2.MORPH_CLOSE, np.ones((7, 7), np.uint8))
    note0 = ""
    void_read = bool(lv.resolved and np.isfinite(lv.flat_crack))  # on the plateaus
    if not np.isfinite(lv.crack) or lv.n_dark < 10:
        # nothing darker than the darkest mineral phase (e.g. a dark biotite as dark as the
        # cracks in a bright mineral): take the crack grey from the darkest pixels and find
        # cracks as narrow dark lines only (the closing criterion below)
        lo = _percentiles(img[::2, ::2], (config.DARKEST_PERCENT,))[0]
        if lo < lv.mineral - config.AUTO_SEED_SIGMAS * lv.noise:
            crack = float(lo)
        else:  # the darkest mineral is as dark as the darkest crack pixels (thin cracks are
            # partial volumes): the crack grey is read on the narrow dark lines themselves
            crack, share = line_crack_level(img, lv.mineral, lv.noise, closed=closed)
            if share < config.LINE_CRACK_MIN_SHARE:
                m = np.zeros(img.shape, bool)
                if share < config.LINE_WARN_SHARE:
                    return flagged(ThresholdResult(m, m, "auto", lv.seed, 0.0, True,
                                                   "no dark class"))
                return flagged(ThresholdResult(
                    m, m, "auto", lv.seed, 0.0, False,
                    f"no dark class, but narrow dark lines hold {share:.2%} of the image: "
                    "cracks as dark as the darkest mineral may be missed"))
        lv = dataclasses.replace(lv, crack=crack)
        void_read = False
        note0 = "no dark tail below the darkest mineral: cracks found as narrow dark lines"
    sn = lv.noise
    # exclude everything that might be crack (incl. its blurred rim) from the background:
    # darker than the darkest mineral, or a narrow dark line that the grey closing fills in
    # (img < mineral - 3 sigma) | (line > k sn) & (line > f (closed - crack)), line = closed - img
    cand = np.empty(img.shape, bool)
    _kernels.crack_candidates(np.ascontiguousarray(img), closed,
                              _operand(lv.mineral - 3.0 * lv.sigma),
                              _operand(config.AUTO_DETECT_SIGMAS * sn),
                              _operand(config.CANDIDATE_LINE_FRACTION), _operand(lv.crack),
                              cand)
    cand = cv2.dilate(cand.view(np.uint8), np.ones((5, 5), np.uint8)).view(bool)
    bg = _local_background(img, cand, band=config.BACKGROUND_BAND_SIGMAS * sn)
    # only candidates can differ from their background: decide there
    idx = np.flatnonzero(cand)
    b = np.maximum(bg.ravel()[idx], lv.mineral - 3.0 * lv.sigma)
    contrast = np.maximum(b - lv.crack, 1e-3)
    depth = b - img.ravel()[idx]
    area = np.zeros(img.shape, bool)
    seed = np.zeros(img.shape, bool)
    detect = np.zeros(img.shape, bool)
    # the depth tests count noise as the smoothed image carries it: correlated over a few
    # pixels, so a speck-sized dip is ~1.3-1.6 x deeper than the pixel-to-pixel sigma says
    sd = max(field_noise_sigma(img), sn)
    seed.ravel()[idx] = depth > np.maximum(seed_fraction * contrast, config.AUTO_SEED_NOISE * sd)
    detect.ravel()[idx] = depth > np.maximum(detect_fraction * contrast,
                                             config.AUTO_DETECT_NOISE * sd)
    # hysteresis: keep weak components that hold a seed pixel
    n, lab = cv2.connectedComponents(detect.view(np.uint8), connectivity=8)
    keep = np.zeros(n, bool)
    keep[lab[seed]] = True
    keep[0] = False
    detect = _kernels.lookup(keep, lab)
    # areas are measured against the void grey: the plateaus of resolved cracks (the cores
    # of partly resolved ones pull the dark class's median up, and a midpoint on it reads
    # every counted crack wide); when the dark class shows no plateau, those of the
    # detected objects (cracks as dark as a dark mineral lie above the dark class)
    void = lv.crack
    detected_void = float("nan")
    if lv.resolved and np.isfinite(lv.flat_crack) and lv.flat_crack < lv.crack:
        void = lv.flat_crack
    area.ravel()[idx] = depth > area_fraction * np.maximum(b - void, 1e-3)
    area &= detect
    if not lv.resolved:
        # the cores are read inside the midpoint mask on the darker guess: a blurred line's
        # detect mask is wide, its midpoint mask is not
        detected_void = _detected_void(img, area, sn, lv.mineral)
        if np.isfinite(detected_void):
            void = detected_void
            area.ravel()[idx] = depth > area_fraction * np.maximum(b - void, 1e-3)
            area &= detect
    frac = float(area.mean())
    value = 0.5 * (lv.mineral + lv.crack)
    ok, note = _check_dark_class(img, area, frac, lv)
    if ok and lv.compact_void and void_read:
        ok, note = False, (
            f"the void grey ({void:.4g}) is read only on compact dark blobs (pores or grains, "
            f"aspect under {config.VOID_COMPACT_ASPECT:g}) and no crack wide enough to show its "
            "core confirms it: a dark grain or lens may pass for the void (and for a crack), "
            "and areas scale with the contrast to it")
    phase = "the dark class's plateaus lie above the cores of thinner cracks (a dark phase)" \
        if lv.phase_plateaus else ""
    if not lv.resolved and np.isfinite(detected_void):
        why = phase or "no crack shows its core grey below the darkest mineral"
        note0 = "; ".join(t for t in (note0, (
            f"{why}: the void grey is read as {detected_void:.4g} on the flat cores of the "
            "widest detected objects, and areas scale with the contrast to it")) if t)
    elif phase:
        note0 = "; ".join(t for t in (note0, (
            f"{phase}: the crack grey is read as {lv.crack:.4g} on those cores, and areas "
            "scale with the contrast to it")) if t)
    elif not lv.resolved:
        note0 = "; ".join(t for t in (note0, (
            f"no crack shows its core grey (all are narrower than the blur): the crack grey "
            f"is taken as {lv.crack:.4g}, at most {config.THIN_ONLY_CRACK_RATIO:g} x the darkest "
            "mineral, and thin-crack areas scale with the contrast to it")) if t)
    note = "; ".join(t for t in (note0, note) if t)
    return flagged(ThresholdResult(area, detect, "auto", value, frac, ok, note, background=bg,
                                   crack_level=lv.crack, noise=sd,
                                   contrast=lv.mineral - lv.crack, void_level=void,
                                   dark_phase_share=lv.phase_share,
                                   void_read=void_read or bool(np.isfinite(detected_void))))


def coverage(image, background, crack_level):
    """Partial-volume crack coverage of each pixel, ``(bg - I) / (bg - crack)`` clipped to
    [0, 1]; its sum over a thin crack and its rim is the crack's area in px."""
    c = (background - np.asarray(image, np.float32)) / np.maximum(background - crack_level, 1e-3)
    return np.clip(c, 0.0, 1.0)


def _check_dark_class(img, mask, frac, lv):
    if frac > config.MAX_DARK_FRACTION:
        return False, f"dark class holds {frac:.0%} of the image: a mineral phase, not cracks?"
    if mask.any():
        inside = float(median(img[mask]))  # a copy: reordered in place
        if inside > lv.mineral - 2.0 * lv.sigma:
            return False, "dark class is not darker than the darkest mineral"
    return True, ""


def crack_mask(image, *, method="auto", block_size=config.LOCAL_BLOCK_PX,
               offset=config.LOCAL_OFFSET_FRACTION) -> ThresholdResult:
    """Threshold a (flattened, denoised) grey image into crack pixels (stage 3).

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image, cracks dark.
    method : str
        ``auto``, ``otsu``, ``local`` or ``manual:VALUE``; see the module docstring.
    block_size, offset
        For ``local``; see :func:`threshold_local`.

    Returns
    -------
    result : ThresholdResult
        ``result.ok`` is False (with a ``note``) when the dark class looks like a mineral
        phase: more than ``MAX_DARK_FRACTION`` of the image, or not darker than the darkest
        mineral peak.
    """
    name, val = parse_method(method)
    img = np.asarray(image, np.float32)
    if name == "auto":
        return threshold_auto(img)
    if name == "manual":
        t = val
        m = img < t
    elif name == "otsu":
        t = threshold_otsu(img)
        m = img < t
    else:
        t = float("nan")
        m = img < threshold_local(img, block_size=block_size, offset=offset)
    frac = float(m.mean())
    ok, note = _check_dark_class(img, m, frac, dark_class_levels(img))
    return ThresholdResult(m, m, name, float(t), frac, ok, note)
