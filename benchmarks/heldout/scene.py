"""Background of the held-out generator: grains, textures, boundaries, dark grains, pores,
illumination, blur, noise and contrast.

Grains are nearest-seed cells of jittered, anisotropic seed points whose pixel coordinates are
displaced by a smooth random field, so grain boundaries are wavy (not straight Voronoi edges).
Each grain takes a mineral grey level and a texture of band-limited noise. A share of grains
is replaced by dark phases of three kinds: laths (elongated ellipses, biotite-like), compact
opaque grains and mottled grains (dark patches of large low-frequency texture). Pores are
compact dark holes (void, the crack grey).
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi
from scipy.spatial import cKDTree


def smooth_noise(rng, shape, sigma):
    """Zero-mean unit-SD Gaussian-filtered noise."""
    f = ndi.gaussian_filter(rng.normal(size=shape), sigma, mode="wrap")
    return f / max(f.std(), 1e-12)


def grain_map(rng, shape, mean_px, wobble_px, stretch, angle):
    """Label image 0..G-1 of wavy anisotropic grains of mean size ``mean_px``."""
    h, w = shape
    n = max(4, int(h * w / mean_px ** 2))
    seeds = rng.uniform([0, 0], [h, w], size=(n, 2))
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    scale = np.diag([stretch, 1 / stretch])
    A = rot @ scale @ rot.T
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    rr += wobble_px * smooth_noise(rng, shape, mean_px / 6)
    cc += wobble_px * smooth_noise(rng, shape, mean_px / 6)
    pts = np.stack([rr.ravel(), cc.ravel()], 1) @ A.T
    _, idx = cKDTree(seeds @ A.T).query(pts, workers=1)
    return idx.reshape(shape).astype(np.int32)


def boundaries(labels):
    b = np.zeros(labels.shape, bool)
    b[:, 1:] |= labels[:, 1:] != labels[:, :-1]
    b[1:, :] |= labels[1:, :] != labels[:-1, :]
    return b


def mineral_greys(rng, n):
    """``n`` mineral grey levels in 105-235, at least 18 apart."""
    while True:
        g = np.sort(rng.uniform(105, 235, n))
        if n == 1 or np.diff(g).min() >= 18:
            return g


def background(rng, shape, st):
    """Grey background (0-255 scale, float) and masks of the dark phases and pores.

    ``st`` holds the image's settings (see :func:`generator.draw_settings`).
    """
    lab = grain_map(rng, shape, st["grain_px"], st["wobble_px"], st["stretch"],
                    st["grain_angle"])
    n_g = lab.max() + 1
    greys = mineral_greys(rng, st["n_minerals"])
    share = rng.dirichlet(np.full(st["n_minerals"], 2.0))
    phase = rng.choice(st["n_minerals"], size=n_g, p=share)
    level = greys[phase] + rng.normal(0, 4, n_g)
    img = level[lab] + st["texture"] * smooth_noise(rng, shape, rng.uniform(0.8, 2.5))
    dark = np.zeros(shape, bool)
    # mottled grains: large low-frequency texture with dark patches
    for g in rng.choice(n_g, size=min(st["n_mottled"], n_g), replace=False):
        m = lab == g
        patch = smooth_noise(rng, shape, rng.uniform(3, 7))
        img[m] += st["mottle_amp"] * np.minimum(patch[m], 0.6)
    # boundaries: slightly darker, 1-2 px
    bd = boundaries(lab)
    if st["boundary_px"] > 1:
        bd = ndi.binary_dilation(bd)
    img[bd] *= 1 - st["boundary_depth"]
    # dark laths (biotite-like) and compact opaque grains
    rr, cc = np.mgrid[0:shape[0], 0:shape[1]]
    for kind, count in (("lath", st["n_laths"]), ("opaque", st["n_opaque"])):
        for _ in range(count):
            y, x = rng.uniform(0, shape[0]), rng.uniform(0, shape[1])
            if kind == "lath":
                b = rng.uniform(4, 10)
                a = b * rng.uniform(1.8, 5)
                grey = rng.uniform(st["crack_grey"] + 30, st["crack_grey"] + 75)
            else:
                a = rng.uniform(5, 16)
                b = a / rng.uniform(1.0, 1.7)
                grey = rng.uniform(st["crack_grey"] + 22, st["crack_grey"] + 55)
            t = rng.uniform(0, np.pi)
            u = ((cc - x) * np.cos(t) + (rr - y) * np.sin(t)) / a
            v = (-(cc - x) * np.sin(t) + (rr - y) * np.cos(t)) / b
            wob = 1 + 0.12 * np.sin(np.arctan2(v, u) * rng.integers(2, 5) + rng.uniform(0, 6))
            m = u ** 2 + v ** 2 <= wob ** 2
            img[m] = grey + 3 * rng.normal(size=m.sum())
            dark |= m
    return img, dark


def pores(rng, shape, n, avoid):
    """Coverage (0-1) of ``n`` compact pores (8x supersampled ellipses), away from ``avoid``."""
    from cracks import CoverageCanvas
    cov = np.zeros(shape, np.float32)
    for _ in range(n):
        r = rng.uniform(3.5, 9)
        y, x = rng.uniform(r + 4, shape[0] - r - 4), rng.uniform(r + 4, shape[1] - r - 4)
        c = CoverageCanvas.around(np.array([[x - r, y - r], [x + r, y + r]]), shape, margin=2)
        if c is None:
            continue
        c.ellipse(x, y, r, r / rng.uniform(1.0, 1.4), rng.uniform(0, np.pi))
        win = c.coverage()
        sl = (slice(c.origin[0], c.origin[0] + win.shape[0]),
              slice(c.origin[1], c.origin[1] + win.shape[1]))
        if (avoid[sl] & (win > 0)).any():
            continue
        cov[sl] = np.maximum(cov[sl], win)
    return cov


def illumination(rng, shape, kind, ratio):
    """Multiplicative field with max/min = ``ratio``: linear ramp or radial vignette."""
    h, w = shape
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    if kind == "linear":
        t = rng.uniform(0, 2 * np.pi)
        d = (cc - w / 2) * np.cos(t) + (rr - h / 2) * np.sin(t)
        d = (d - d.min()) / max(np.ptp(d), 1e-9)
    elif kind == "radial":
        y0, x0 = rng.uniform(0.3, 0.7) * h, rng.uniform(0.3, 0.7) * w
        d = np.hypot(rr - y0, cc - x0)
        d = 1 - d / d.max()
    else:
        return np.ones(shape)
    return 1 / ratio + (1 - 1 / ratio) * d


def finish(rng, img, st):
    """Illumination, blur, noise, contrast and quantisation of a 0-255 float image."""
    img = img * illumination(rng, img.shape, st["illumination"], st["illum_ratio"])
    img = ndi.gaussian_filter(img, st["blur_px"])
    img = img + rng.normal(0, st["noise"], img.shape) + rng.normal(
        0, st["noise"] * 0.04, img.shape) * np.sqrt(np.maximum(img, 0)) * 3
    m = img.mean()
    img = m + st["contrast"] * (img - m) + st["offset"]
    if st["bit_depth"] == 16:
        return np.clip(np.rint(img * 257), 0, 65535).astype(np.uint16)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)
