"""Training family of the crack-typing model: domain-randomised renderings with known types.

Two kinds of scene, drawn at random from a settings family (:data:`TRAIN`):

* ``synth`` — ``semkit.synth.make_sem_image`` post-test images with randomised widths, noise,
  blur, illumination gradient, grain size, boundary depth, pores and bit depth;
* ``drawn`` — a crack-free ``semkit.synth`` background with cracks drawn here, in more
  morphologies than ``semkit.synth`` has: tensile openings of constant or slowly varying
  aperture whose walls follow the same wiggle (matching walls); shear traces that are stepped
  (en-echelon segments, joined by oblique links or overlapping), layered (2-3 thin parallel
  traces), or offset (a thin trace whose walls no longer match: the aperture beads and closes),
  with dark chips alongside and bright debris inside; mixed cracks that change from one to the
  other along one path (2-3 parts).

Cracks are rendered from centrelines with a width per point on a 4x grid (distance transform
from the centreline, OpenCV), blurred with the image's PSF and composited onto the background
with its illumination and noise. :data:`HELDOUT` is the same family with other settings
(larger noise and blur, stronger illumination, other widths, step lengths and grain sizes):
accuracy is quoted there, never on :data:`TRAIN`.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import ndimage as ndi

TYPES = ("tensile", "shear", "mixed")
SS = 4

TRAIN = dict(
    noise=(2.0, 7.0), blur=(0.4, 0.9), gradient=(1.0, 2.0), grain_px=(40, 110),
    boundary_depth=(0.05, 0.15), pores=(0, 4), bit16=0.25, crack_grey=(15, 45),
    n_cracks=(6, 12), drawn_share=0.6,
    synth_widths=((1.0, 6.0), (2.0, 8.0)),
    aperture=(2.0, 7.0), aperture_var=(0.0, 0.15), wiggle=(0.0, 1.5), wiggle_px=(15, 60),
    tip_px=(4, 20), t_length=(40, 220),
    shear_width=(0.8, 2.2), step_px=(10, 35), offset_px=(1.5, 4.5), layer_px=(2.5, 6.0),
    gaps=(0.0, 0.35), bead=(0.3, 1.2), chips=(0.0, 0.03), s_length=(40, 200),
    m_length=(120, 300),
)
HELDOUT = dict(
    TRAIN, noise=(7.0, 10.0), blur=(0.9, 1.3), gradient=(2.0, 3.0), grain_px=(20, 40),
    crack_grey=(40, 60), synth_widths=((1.5, 7.0),), aperture=(3.0, 9.0),
    step_px=(30, 45), offset_px=(3.0, 6.0), layer_px=(4.0, 7.0), shear_width=(1.0, 2.6),
)


def _u(rng, r):
    return float(rng.uniform(*r))


def _smooth(rng, n, corr):
    f = ndi.gaussian_filter1d(rng.normal(size=n + 4 * int(corr) + 8), corr, mode="wrap")
    f = f[2 * int(corr) + 4:2 * int(corr) + 4 + n]
    return f / max(f.std(), 1e-9)


def _base_path(rng, start, angle, length):
    n = max(int(length), 4)
    th = angle + np.cumsum(rng.normal(0, 0.01, n))
    return np.stack([start[0] + np.cumsum(np.cos(th)), start[1] + np.cumsum(np.sin(th))], 1), th


def tensile_traces(rng, st, p, th, *, tips=(True, True)):
    """One trace: constant (slowly varying) aperture, both walls on the same wiggle; tapered
    at its crack tips, narrowing over ~10 px where it meets a shear part of a mixed crack."""
    n = len(p)
    lat = _u(rng, st["wiggle"]) * _smooth(rng, n, _u(rng, st["wiggle_px"]) / 4)
    nrm = np.stack([-np.sin(th), np.cos(th)], 1)
    q = p + nrm * lat[:, None]
    s = np.arange(n)
    tip = _u(rng, st["tip_px"])
    ends = [tip if t else 10.0 for t in tips]
    taper = np.clip(np.minimum(s / ends[0], (n - 1 - s) / ends[1]), 0, 1) ** 0.5
    w = _u(rng, st["aperture"]) * (1 + _u(rng, st["aperture_var"]) * _smooth(rng, n, 20))
    return [np.column_stack([q, np.maximum(w * taper, 1.0)])], []


def shear_traces(rng, st, p, th):
    """Stepped, layered or offset thin traces; chips alongside; bright debris inside."""
    n = len(p)
    nrm = np.stack([-np.sin(th), np.cos(th)], 1)
    w0 = _u(rng, st["shear_width"])
    kind = rng.choice(["stepped", "layered", "offset"])
    traces = []
    if kind == "stepped":
        seg, off = _u(rng, st["step_px"]), _u(rng, st["offset_px"])
        pos, lat = 0, 0.0
        linked = rng.random() < 0.6
        while pos < n - 4:
            ln = int(seg * rng.uniform(0.7, 1.3))
            a, b = pos, min(n, pos + ln + (0 if linked else int(rng.uniform(2, 6))))
            traces.append(np.column_stack([p[a:b] + nrm[a:b] * lat, np.full(b - a, w0)]))
            new = lat + rng.choice([-1, 1]) * off * rng.uniform(0.6, 1.2)
            if linked and b < n - 4:
                k = np.linspace(0, 1, 6)[:, None]
                link = p[b - 1] + nrm[b - 1] * (lat + (new - lat) * k)
                traces.append(np.column_stack([link, np.full(6, w0 * 0.8)]))
            pos, lat = pos + ln, new
    elif kind == "layered":
        sp = _u(rng, st["layer_px"])
        for k in range(int(rng.integers(2, 4))):
            a = int(rng.uniform(0, 0.25) * n)
            b = n - int(rng.uniform(0, 0.25) * n)
            traces.append(np.column_stack([p[a:b] + nrm[a:b] * (k * sp),
                                           np.full(b - a, w0 * rng.uniform(0.7, 1.0))]))
    else:  # offset: walls that no longer match, the aperture beads and closes
        lat = 0.8 * _smooth(rng, n, 6)
        w = np.minimum(w0 * (1 + _u(rng, st["bead"]) * _smooth(rng, n, 4)), 1.6 * w0)
        traces.append(np.column_stack([p + nrm * lat[:, None], w]))
    # closures (incomplete walls): drop random stretches
    out = []
    for t in traces:
        keep = _smooth(rng, len(t), 5) > np.quantile(_smooth(rng, 64, 5), _u(rng, st["gaps"]))
        keep &= t[:, 2] >= 0.6
        idx = np.flatnonzero(np.diff(np.r_[0, keep.astype(int), 0]))
        for a, b in zip(idx[::2], idx[1::2]):
            if b - a >= 3:
                out.append(t[a:b])
    chips = []
    for _ in range(int(n * _u(rng, st["chips"]))):
        i = int(rng.integers(0, n))
        d = rng.choice([-1, 1]) * rng.uniform(2.5, 7.0)
        chips.append(np.array([[*(p[i] + nrm[i] * d), rng.uniform(1.0, 2.4)]]))
    return out, chips


def crack_traces(rng, st, kind, start, angle, path=None):
    """Centreline traces (x, y, width), chips, and the mode (1 tensile, 2 shear) of each
    trace and chip, of one crack of the given kind (``path``: the base-path function, by
    default :func:`_base_path`)."""
    length = _u(rng, st[{"tensile": "t_length", "shear": "s_length", "mixed": "m_length"}[kind]])
    p, th = (path or _base_path)(rng, start, angle, length)
    if kind == "tensile":
        t, c = tensile_traces(rng, st, p, th)
        return t, c, [1] * len(t + c)
    if kind == "shear":
        t, c = shear_traces(rng, st, p, th)
        return t, c, [2] * len(t + c)
    cuts = np.linspace(0, len(p), int(rng.integers(2, 4)) + 1).astype(int)
    first_t = rng.random() < 0.5
    traces, chips, tmode, cmode = [], [], [], []
    for q in range(len(cuts) - 1):
        a, b = cuts[q], cuts[q + 1]
        if (q % 2 == 0) == first_t:
            t, c = tensile_traces(rng, st, p[a:b], th[a:b], tips=(q == 0, q == len(cuts) - 2))
            k = 1
        else:
            t, c = shear_traces(rng, st, p[a:b], th[a:b])
            k = 2
        traces += t
        chips += c
        tmode += [k] * len(t)
        cmode += [k] * len(c)
    return traces, chips, tmode + cmode


def coverage(traces, shape, margin=6):
    """Coverage (0-1) of traces of (x, y, width) points and the window it was drawn in."""
    import cv2
    pts = np.vstack(traces)
    x0 = max(int(np.floor(pts[:, 0].min() - pts[:, 2].max() - margin)), 0)
    y0 = max(int(np.floor(pts[:, 1].min() - pts[:, 2].max() - margin)), 0)
    x1 = min(int(np.ceil(pts[:, 0].max() + pts[:, 2].max() + margin)), shape[1] - 1)
    y1 = min(int(np.ceil(pts[:, 1].max() + pts[:, 2].max() + margin)), shape[0] - 1)
    h, w = (y1 - y0 + 1) * SS, (x1 - x0 + 1) * SS
    width = np.zeros((h, w), np.float32)
    for t in traces:
        d = np.hypot(*np.diff(t[:, :2], axis=0).T)
        k = np.r_[0, np.cumsum(d)]
        s = np.arange(0, k[-1] + 1e-9, 1.0 / SS) if k[-1] > 0 else np.zeros(1)
        x, y, wd = (np.interp(s, k, t[:, j]) for j in range(3))
        c = np.rint((x - x0 + 0.5) * SS - 0.5).astype(int)
        r = np.rint((y - y0 + 0.5) * SS - 0.5).astype(int)
        ok = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        np.maximum.at(width, (r[ok], c[ok]), wd[ok].astype(np.float32))
    src = width > 0
    dist, near = cv2.distanceTransformWithLabels((~src).astype(np.uint8), cv2.DIST_L2, 5,
                                                 labelType=cv2.DIST_LABEL_PIXEL)
    lw = np.zeros(int(near.max()) + 1, np.float32)
    lw[near[src]] = width[src]
    inside = dist / SS <= lw[near] / 2
    cov = inside.reshape(h // SS, SS, w // SS, SS).mean(axis=(1, 3))
    return cov.astype(np.float32), (y0, x0)


def draw_settings(rng, family):
    return dict(noise=_u(rng, family["noise"]), blur=_u(rng, family["blur"]),
                gradient=_u(rng, family["gradient"]), grain_px=_u(rng, family["grain_px"]),
                boundary_depth=_u(rng, family["boundary_depth"]),
                pores=int(rng.integers(family["pores"][0], family["pores"][1] + 1)),
                bit_depth=16 if rng.random() < family["bit16"] else 8,
                crack_grey=_u(rng, family["crack_grey"]),
                n_cracks=int(rng.integers(family["n_cracks"][0], family["n_cracks"][1] + 1)),
                drawn=rng.random() < family["drawn_share"])


def _synth_keywords(rng, st):
    return dict(gradient=st["gradient"], noise_sigma=st["noise"], blur_sigma=st["blur"],
                mean_grain_px=st["grain_px"], boundary_depth=st["boundary_depth"],
                n_pores=st["pores"], bit_depth=st["bit_depth"], seed=int(rng.integers(2**31)))


def render_scene(shape, family=TRAIN, *, seed=None):
    """One training (or held-out-settings) image and its per-pixel crack types.

    Returns
    -------
    image : (H, W) ndarray of uint8 or uint16
    type_image : (H, W) ndarray of int8
        0 none, 1 tensile, 2 shear, 3 mixed (pixels with coverage >= 0.5).
    mode_image : (H, W) ndarray of int8
        The local mode: 1 tensile, 2 shear stretch (the parts of mixed cracks too; 0 where
        unknown: mixed cracks of ``semkit.synth``).
    settings : dict
    """
    from semkit.synth import make_sem_image
    rng = np.random.default_rng(seed)
    st = draw_settings(rng, family)
    kw = _synth_keywords(rng, st)
    if not st["drawn"]:
        ws = family["synth_widths"][int(rng.integers(len(family["synth_widths"])))]
        s = make_sem_image(shape, stage="post", n_cracks=st["n_cracks"], widths=ws, **kw)
        code = np.zeros(len(s.cracks) + 1, np.int8)
        code[s.cracks["crack_id"].to_numpy()] = [TYPES.index(t) + 1 for t in s.cracks.type_post]
        types = code[s.crack_labels]
        return s.image, types, np.where(types <= 2, types, 0).astype(np.int8), st
    s = make_sem_image(shape, stage="pre", n_cracks=0, **kw)
    image, types, modes, _ = draw_cracks(rng, st, family, s.image, s.illumination)
    return image, types, modes, st


def drawn_scene(shape, family=TRAIN, *, seed=None):
    """A ``drawn`` scene (whatever the family's ``drawn_share``) with its exact truth.

    Returns
    -------
    image : (H, W) ndarray of uint8 or uint16
    truth : dict
        As :func:`draw_cracks`, with ``settings``.
    """
    from semkit.synth import make_sem_image
    rng = np.random.default_rng(seed)
    st = draw_settings(rng, family)
    s = make_sem_image(shape, stage="pre", n_cracks=0, **_synth_keywords(rng, st))
    image, _, _, truth = draw_cracks(rng, st, family, s.image, s.illumination)
    return image, dict(truth, settings=st | dict(drawn=True))


def _polylen(t):
    return float(np.hypot(*np.diff(t[:, :2], axis=0).T).sum()) if len(t) > 1 else 0.0


def draw_cracks(rng, st, family, background, illumination):
    """Draw ``st["n_cracks"]`` cracks of the family's morphologies onto a crack-free image.

    Parameters
    ----------
    rng : numpy.random.Generator
    st : dict
        :func:`draw_settings` of the scene.
    family : dict
        :data:`TRAIN` or :data:`HELDOUT`.
    background : (H, W) ndarray of uint8 or uint16
        Crack-free ``semkit.synth`` image.
    illumination : (H, W) ndarray
        Its illumination field (the crack grey follows it).

    Returns
    -------
    image : (H, W) ndarray, the dtype of ``background``
    type_image, mode_image : (H, W) ndarray of int8
        As :func:`render_scene`.
    truth : dict
        ``coverage`` (H, W) float32, the exact crack coverage (chips and debris included);
        ``trace_length_px``, the length of every drawn trace (each layer, step and link);
        ``path_length_px``, the length of each crack's path (a layered or stepped shear crack
        counted once, along its base path).
    """
    shape = background.shape
    paths = []

    def recording_path(*args):
        p, th = _base_path(*args)
        paths.append(_polylen(p))
        return p, th

    cov = np.zeros(shape, np.float32)
    types = np.zeros(shape, np.int8)
    modes = np.zeros(shape, np.int8)
    taken = np.zeros(shape, bool)
    placed = tries = 0
    trace_len = path_len = 0.0
    while placed < st["n_cracks"] and tries < 30 * st["n_cracks"]:
        tries += 1
        kind = TYPES[int(rng.choice(3, p=[0.45, 0.35, 0.2]))]
        start = rng.uniform([20, 20], [shape[1] - 20, shape[0] - 20])
        paths.clear()
        traces, chips, part = crack_traces(rng, st | family, kind, start,
                                           rng.uniform(0, 2 * np.pi), path=recording_path)
        if not traces:
            continue
        pts = np.vstack(traces)
        if (pts[:, 0].min() < 8 or pts[:, 1].min() < 8 or pts[:, 0].max() > shape[1] - 9
                or pts[:, 1].max() > shape[0] - 9):
            continue
        c, (y0, x0) = coverage(traces + chips, shape)
        sl = (slice(y0, y0 + c.shape[0]), slice(x0, x0 + c.shape[1]))
        if (taken[sl] & (c > 0)).any():
            continue
        if kind != "tensile":  # bright debris inside the wider stretches
            wide = np.argwhere(c >= 0.99)
            for i in rng.choice(len(wide), size=min(len(wide) // 40, 6), replace=False) \
                    if len(wide) else []:
                c[tuple(wide[i])] *= rng.uniform(0.0, 0.4)
        cov[sl] = np.maximum(cov[sl], c)
        types[sl][c >= 0.5] = TYPES.index(kind) + 1
        for code_, tr in ((1, [t for t, k in zip(traces + chips, part) if k == 1]),
                          (2, [t for t, k in zip(traces + chips, part) if k == 2])):
            if tr:
                cp, (py, px) = coverage(tr, shape)
                win = modes[py:py + cp.shape[0], px:px + cp.shape[1]]
                win[(cp >= 0.5) & (c[py - y0:py - y0 + cp.shape[0],
                                     px - x0:px - x0 + cp.shape[1]] >= 0.5)] = code_
        taken[sl] |= ndi.binary_dilation(c > 0, iterations=4)
        placed += 1
        trace_len += sum(_polylen(t) for t in traces)
        path_len += paths[0] if kind != "tensile" else sum(_polylen(t) for t in traces)
    grey = background.astype(np.float64) / (257.0 if st["bit_depth"] == 16 else 1.0)
    c = ndi.gaussian_filter(cov, st["blur"])
    core = st["crack_grey"] * illumination + st["noise"] * rng.normal(size=shape)
    grey = grey * (1 - c) + core * c
    if st["bit_depth"] == 16:
        image = np.clip(np.rint(grey * 257), 0, 65535).astype(np.uint16)
    else:
        image = np.clip(np.rint(grey), 0, 255).astype(np.uint8)
    return image, types, modes, dict(coverage=cov, trace_length_px=trace_len,
                                     path_length_px=path_len)


def scene_table(seeds, shape=(384, 512), family=TRAIN):
    """(seed, shape, family) rows of a set of scenes (for worker processes)."""
    return pd.DataFrame(dict(seed=list(seeds), shape=[shape] * len(seeds),
                             family=[family] * len(seeds)))
