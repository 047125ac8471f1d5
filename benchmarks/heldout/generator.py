"""Held-out synthetic micrographs of cracked rock with exact ground truth.

Written apart from ``semkit.synth`` (it imports nothing of semkit) and never used to tune
semkit: it is the judge. Appearance is drawn at random per image (grain size and shape,
textures, faint wavy grain boundaries, dark laths, compact opaque and mottled grains, pores,
crack grey, illumination ramp or vignette, blur, noise, contrast, 8 or 16 bit) and per crack
(see ``cracks.py``: tensile traces wide and straight with matching walls; shear traces thin,
stepped, some layered, with bright debris inside and dark chips alongside; mixed both).

Truth, per crack: ``area_px`` = sum of the 8x-supersampled partial-volume coverage (chips
included), ``length_px`` = length of the mid-line between the walls over the open stretches
(layers included, chips not), ``type``. Per image: ``crack_mask`` (coverage >= 0.5),
``crack_labels``, ``coverage``, ``area_px``, ``length_px``, ``area_T_px``, ``area_S_px`` and
``P`` = A_T / A_S (mixed cracks left out, as semkit does by default).

Run ``python benchmarks/heldout/generator.py OUT [--n 24] [--seed 7000]`` to write a set.
"""
from __future__ import annotations

import dataclasses
import pathlib
import sys

import numpy as np
import pandas as pd

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import cracks as ck  # noqa: E402
import scene  # noqa: E402

TYPES = ("tensile", "shear", "mixed")


@dataclasses.dataclass
class HeldoutImage:
    image: np.ndarray
    coverage: np.ndarray
    crack_labels: np.ndarray
    cracks: pd.DataFrame
    dark_mask: np.ndarray
    pore_coverage: np.ndarray
    pixel_size_um: float
    settings: dict

    @property
    def crack_mask(self):
        return self.crack_labels > 0

    @property
    def area_px(self):
        return float(self.cracks["area_px"].sum())

    @property
    def length_px(self):
        return float(self.cracks["length_px"].sum())

    def typed_area_px(self, kind):
        return float(self.cracks.loc[self.cracks["type"] == kind, "area_px"].sum())

    @property
    def P(self):
        a_s = self.typed_area_px("shear")
        return self.typed_area_px("tensile") / a_s if a_s > 0 else float("nan")


def draw_settings(rng, shape):
    """The appearance of one image, drawn at random."""
    crack_grey = rng.uniform(5, 45)
    area = shape[0] * shape[1]
    return dict(
        grain_px=rng.uniform(25, 90), wobble_px=rng.uniform(1.5, 5), stretch=rng.uniform(1, 1.6),
        grain_angle=rng.uniform(0, np.pi), n_minerals=int(rng.integers(2, 5)),
        texture=rng.uniform(2, 9), boundary_depth=rng.uniform(0.03, 0.15),
        boundary_px=int(rng.integers(1, 3)), n_mottled=int(rng.integers(0, 3)),
        mottle_amp=rng.uniform(20, 45), n_laths=int(rng.poisson(area / 250_000)),
        n_opaque=int(rng.poisson(area / 200_000)), n_pores=int(rng.poisson(area / 150_000)),
        crack_grey=crack_grey, n_cracks=max(3, int(rng.poisson(area / 40_000))),
        type_weights=rng.dirichlet([3, 3, 1.5]), illumination=str(rng.choice(
            ["none", "linear", "radial"])), illum_ratio=rng.uniform(1.0, 2.5),
        blur_px=rng.uniform(0.4, 1.2), noise=rng.uniform(1.5, 7), contrast=rng.uniform(0.6, 1.0),
        offset=rng.uniform(-10, 10), bit_depth=int(rng.choice([8, 8, 8, 16])),
        pixel_size_um=float(rng.uniform(0.4, 3.0)))


def draw_crack_settings(rng, kind):
    g = dict(aperture=rng.uniform(2.5, 9), rough_amp=rng.uniform(0.3, 1.5),
             rough_wl=rng.uniform(15, 60), tip_px=rng.uniform(6, 20))
    if kind != "tensile":
        g.update(shear_open=rng.uniform(0.9, 2.2), slip=rng.uniform(3, 12),
                 shear_rough=rng.uniform(0.4, 1.2), shear_wl=rng.uniform(8, 30),
                 steps=(rng.uniform(12, 35), rng.uniform(1.5, 4)) if rng.random() < 0.7 else
                 None, layered=rng.random() < 0.35, split=rng.uniform(0.35, 0.65))
    length = {"tensile": (50, 260), "shear": (40, 200), "mixed": (120, 350)}[kind]
    g["length"] = rng.uniform(*length)
    g["bend"] = rng.uniform(0, 0.012)
    return g


def _trace(rng, kind, g, start, angle, shape):
    """(canvas, length_px) of one trace, or None when it leaves the image."""
    if kind != "tensile":
        g = dict(g, rough_amp=g["shear_rough"], rough_wl=g["shear_wl"])
    steps = g.get("steps") if kind == "shear" else None
    p = ck.path(rng, start, angle, g["length"], bend=g["bend"], steps=steps)
    if kind == "mixed" and g.get("steps"):  # the shear part of a mixed crack steps too
        k = int(g["split"] * len(p))
        q = ck.path(rng, p[k], angle, len(p) - k - 1, steps=g["steps"])
        p = np.concatenate([p[:k], q])[:len(p)]
    w1, w2 = ck.crack_walls(rng, kind, len(p), g)
    canvas = ck.CoverageCanvas.around(p, shape, margin=int(np.abs([w1, w2]).max()) + 8)
    if canvas is None:
        return None
    open_ = w2 - w1 > 0.05
    for a, b in ck.open_runs(open_):  # stretches shorter than 5 px close up
        if b - a < 5:
            open_[a:b] = False
    for a, b in ck.open_runs(open_):
        if b - a >= 2:
            canvas.quad_strip(p[a:b], w1[a:b], w2[a:b])
    length = ck.midline_length(p, w1, w2, open_)
    if kind != "tensile":
        n = ck.normals(p)
        mid = p + n * ((w1 + w2) / 2)[:, None]
        shear_part = np.arange(len(p)) >= (int(g["split"] * len(p)) + 12 if kind == "mixed"
                                           else 0)
        wide = np.flatnonzero(shear_part & (w2 - w1 > 2.5))
        for i in rng.choice(wide, size=min(len(wide) // 15, 8), replace=False) if len(
                wide) else []:  # bright debris inside the band
            r = rng.uniform(0.6, 1.1)
            canvas.ellipse(*mid[i], r, r, 0.0, value=False)
        idx = np.flatnonzero(shear_part)
        for i in rng.choice(idx, size=int(len(idx) / 90), replace=False):  # dark chips
            side = rng.choice([-1, 1]) * rng.uniform(3.0, 6.0)
            canvas.ellipse(*(mid[i] + n[i] * side), rng.uniform(0.9, 1.6),
                           rng.uniform(0.7, 1.1), rng.uniform(0, np.pi))
        if g.get("layered"):
            a = int(len(p) * rng.uniform(0.0, 0.3) if kind == "shear" else g["split"] * len(p))
            b = min(len(p), a + int(len(p) * rng.uniform(0.4, 0.8)))
            if b - a > 10:
                off = rng.choice([-1, 1]) * rng.uniform(3.0, 6.0)
                q = p[a:b] + n[a:b] * off
                half = rng.uniform(0.45, 0.8)
                lw1, lw2 = np.full(b - a, -half), np.full(b - a, half)
                canvas.quad_strip(q, lw1, lw2)
                length += ck.midline_length(q, lw1, lw2, np.ones(b - a, bool))
    return canvas, length


def make_heldout_image(shape=(768, 1024), *, seed=None):
    """One held-out image with its truth (see the module docstring)."""
    rng = np.random.default_rng(seed)
    st = draw_settings(rng, shape)
    img, dark = scene.background(rng, shape, st)
    labels = np.zeros(shape, np.int32)
    cov = np.zeros(shape, np.float32)
    taken = np.zeros(shape, bool)
    rows = []
    tries = 0
    while len(rows) < st["n_cracks"] and tries < 40 * st["n_cracks"]:
        tries += 1
        kind = TYPES[rng.choice(3, p=st["type_weights"])]
        g = draw_crack_settings(rng, kind)
        start = rng.uniform([0, 0], [shape[1], shape[0]])
        out = _trace(rng, kind, g, start, rng.uniform(0, 2 * np.pi), shape)
        if out is None:
            continue
        canvas, length = out
        win = canvas.coverage()
        sl = (slice(canvas.origin[0], canvas.origin[0] + win.shape[0]),
              slice(canvas.origin[1], canvas.origin[1] + win.shape[1]))
        if (taken[sl] & (win > 0)).any() or win.sum() < 8:
            continue
        cid = len(rows) + 1
        cov[sl] += win
        labels[sl][win >= 0.5] = cid
        from scipy import ndimage as ndi
        taken[sl] |= ndi.binary_dilation(win > 0, iterations=4)
        rows.append(dict(crack_id=cid, type=kind, area_px=float(win.sum()),
                         area_mask_px=int((win >= 0.5).sum()), length_px=length,
                         aperture_px=g["aperture"] if kind != "shear" else g["shear_open"]))
    pore_cov = scene.pores(rng, shape, st["n_pores"], taken)
    void = np.clip(cov + pore_cov, 0, 1)
    img = img * (1 - void) + (st["crack_grey"] + rng.normal(0, 2, shape)) * void
    image = scene.finish(rng, img, st)
    return HeldoutImage(image=image, coverage=cov, crack_labels=labels,
                        cracks=pd.DataFrame(rows, columns=["crack_id", "type", "area_px",
                                                           "area_mask_px", "length_px",
                                                           "aperture_px"]),
                        dark_mask=dark, pore_coverage=pore_cov,
                        pixel_size_um=st["pixel_size_um"], settings=st)


SET_SHAPES = [(768, 1024)] * 16 + [(512, 640)] * 8
SET_SEED = 7000


def heldout_set(n=len(SET_SHAPES), *, seed0=SET_SEED):
    """(seed, shape) of the benchmark set: image k has seed ``seed0 + k``."""
    return [(seed0 + k, SET_SHAPES[k % len(SET_SHAPES)]) for k in range(n)]


def main(argv=None):
    import argparse
    ap = argparse.ArgumentParser(description="write held-out images with truth")
    ap.add_argument("out")
    ap.add_argument("--n", type=int, default=len(SET_SHAPES))
    ap.add_argument("--seed", type=int, default=SET_SEED)
    a = ap.parse_args(argv)
    import cv2
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for seed, shape in heldout_set(a.n, seed0=a.seed):
        h = make_heldout_image(shape, seed=seed)
        name = f"heldout_{seed}.{'tif' if h.image.dtype == np.uint16 else 'png'}"
        cv2.imwrite(str(out / name), h.image)
        cv2.imwrite(str(out / f"heldout_{seed}_truth.png"), (h.crack_mask * 255).astype(np.uint8))
        rows.append(dict(image=name, seed=seed, pixel_size_um=h.pixel_size_um,
                         area_px=h.area_px, length_px=h.length_px, P=h.P))
    pd.DataFrame(rows).to_csv(out / "truth.csv", index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
