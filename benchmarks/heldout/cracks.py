"""Crack geometry of the held-out generator: two walls offset from a path, rasterised with
exact partial-volume coverage.

A crack is a path P(s) (points 1 px apart) with two walls at signed normal offsets
w1(s) < w2(s). A rough wall profile h(s) and a displacement of the second wall, an opening a
normal to the path and a slip u along it, give w1 = h(s) - a/2, w2 = h(s - u) + a/2:

* tensile (u = 0): the walls match, the aperture a is the same everywhere (tapered at the tips);
* shear (u of the order of the roughness wavelength, a small): the aperture a + h(s-u) - h(s)
  varies and closes where asperities meet, so the walls are incomplete; the path itself is
  stepped (en-echelon offsets), some traces are layered (a second thin trace beside the first)
  and bright debris sits inside the wider stretches, dark chips alongside;
* mixed: one path, tensile over one part and shear over the rest.

Coverage is computed on a 8x supersampled grid (quads between consecutive wall points), so the
truth area is the sum of coverage; the truth length is the length of the mid-line between the
walls over the open stretches.
"""
from __future__ import annotations

import numpy as np
from skimage.draw import ellipse as draw_ellipse
from skimage.draw import polygon as draw_polygon

SS = 8  # supersampling per axis


def rough_profile(rng, n, amplitude, wavelength):
    """A random smooth wall profile: a sum of sines over wavelengths around ``wavelength``."""
    s = np.arange(n, dtype=float)
    h = np.zeros(n)
    for k in range(4):
        lam = wavelength * rng.uniform(0.4, 1.6) / (1 + k)
        h += rng.normal(0, 1) / (1 + k) * np.sin(2 * np.pi * s / lam + rng.uniform(0, 2 * np.pi))
    return amplitude * h / max(np.abs(h).max(), 1e-9)


def path(rng, start, angle, length, *, bend=0.0, steps=None):
    """Points 1 px apart from ``start`` (x, y) along ``angle`` (rad), gently bent, optionally
    stepped: ``steps = (segment_px, offset_px)`` shifts the path sideways by +-offset every
    segment over a short oblique link."""
    n = int(length) + 1
    s = np.arange(n, dtype=float)
    turn = np.cumsum(rng.normal(0, bend, n))
    turn -= np.linspace(0, turn[-1], n) * 0.5
    th = angle + turn
    x = start[0] + np.concatenate([[0], np.cumsum(np.cos(th[1:]))])
    y = start[1] + np.concatenate([[0], np.cumsum(np.sin(th[1:]))])
    if steps is not None:
        seg, off = steps
        lateral = np.zeros(n)
        cur, pos = 0.0, 0.0
        link = 3.0
        while pos < n:
            nxt = cur + rng.choice([-1, 1]) * off * rng.uniform(0.6, 1.2)
            a = pos + seg * rng.uniform(0.7, 1.3)
            lateral[(s >= pos) & (s < a)] = cur
            ramp = (s >= a) & (s < a + link)
            lateral[ramp] = cur + (nxt - cur) * (s[ramp] - a) / link
            cur, pos = nxt, a + link
        nx, ny = -np.sin(th), np.cos(th)
        x, y = x + nx * lateral, y + ny * lateral
    return np.stack([x, y], 1)


def normals(p):
    d = np.gradient(p, axis=0)
    d /= np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
    return np.stack([-d[:, 1], d[:, 0]], 1)


def open_runs(open_mask):
    """(start, stop) index pairs of the True runs."""
    m = np.concatenate([[False], open_mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


class CoverageCanvas:
    """A supersampled boolean canvas over the image window ``rows x cols`` starting at
    ``origin`` = (row, col); coverage = block mean."""

    def __init__(self, shape, origin=(0, 0)):
        self.shape = tuple(shape)
        self.origin = origin
        self.fine = np.zeros((shape[0] * SS, shape[1] * SS), bool)

    @classmethod
    def around(cls, points, image_shape, margin=6):
        """A canvas over the bounding box of ``points`` (x, y) plus ``margin``, clipped to the
        image; None when the box leaves the image."""
        x0, y0 = np.floor(points.min(0)).astype(int) - margin
        x1, y1 = np.ceil(points.max(0)).astype(int) + margin
        if x0 < 0 or y0 < 0 or x1 >= image_shape[1] or y1 >= image_shape[0]:
            return None
        return cls((y1 - y0 + 1, x1 - x0 + 1), origin=(y0, x0))

    def _fine_xy(self, x, y):
        return ((np.asarray(x) - self.origin[1] + 0.5) * SS - 0.5,
                (np.asarray(y) - self.origin[0] + 0.5) * SS - 0.5)

    def quad_strip(self, p, w1, w2, *, value=True):
        """Fill the band between the walls p + n w1 and p + n w2, quad by quad; inner quads
        reach 0.5 px past their ends so that no gap opens where the path turns."""
        n = normals(p)
        a, b = p + n * w1[:, None], p + n * w2[:, None]
        t = np.gradient(p, axis=0)
        t /= np.maximum(np.hypot(t[:, 0], t[:, 1]), 1e-9)[:, None]
        for i in range(len(p) - 1):
            e0 = 0.0 if i == 0 else 0.5
            e1 = 0.0 if i == len(p) - 2 else 0.5
            poly = np.array([a[i] - e0 * t[i], a[i + 1] + e1 * t[i + 1],
                             b[i + 1] + e1 * t[i + 1], b[i] - e0 * t[i]])
            fx, fy = self._fine_xy(poly[:, 0], poly[:, 1])
            rr, cc = draw_polygon(fy, fx, shape=self.fine.shape)
            self.fine[rr, cc] = value

    def ellipse(self, x, y, ra, rb, angle, *, value=True):
        fx, fy = self._fine_xy(x, y)
        rr, cc = draw_ellipse(fy, fx, rb * SS, ra * SS, shape=self.fine.shape,
                              rotation=-angle)
        self.fine[rr, cc] = value

    def coverage(self):
        h, w = self.shape
        return self.fine.reshape(h, SS, w, SS).mean(axis=(1, 3)).astype(np.float32)


def midline_length(p, w1, w2, open_mask):
    """Length of the mid-line between the walls over the open stretches, px."""
    m = p + normals(p) * ((w1 + w2) / 2)[:, None]
    total = 0.0
    for a, b in open_runs(open_mask):
        if b - a >= 2:
            total += float(np.hypot(*np.diff(m[a:b], axis=0).T).sum())
    return total


def taper(n, tip_px):
    s = np.arange(n, dtype=float)
    return np.clip(np.minimum(s, n - 1 - s) / max(tip_px, 1.0), 0.0, 1.0) ** 0.5


def crack_walls(rng, kind, n, g):
    """Walls (w1, w2) of a crack of ``n`` path points.

    ``g`` holds the drawn settings: tensile ``aperture``, ``rough_amp``, ``rough_wl``,
    ``tip_px``; shear ``shear_open``, ``slip``; mixed ``split``.
    """
    h = rough_profile(rng, n + 64, g["rough_amp"], g["rough_wl"])
    base = h[32:32 + n]
    if kind == "tensile":
        a = np.maximum(g["aperture"] * taper(n, g["tip_px"]), 1.0)
        return base - a / 2, base + a / 2
    slip = int(round(g["slip"]))
    shifted = h[32 - slip:32 - slip + n]
    a_sh = g["shear_open"]
    w1, w2 = base - a_sh / 2, shifted + a_sh / 2
    if kind == "shear":
        return w1, w2
    k = int(g["split"] * n)                      # mixed: tensile before k, shear after
    a_t = np.maximum(g["aperture"] * taper(2 * k, g["tip_px"])[:k], 1.0)
    ramp = np.clip((np.arange(n) - k) / 12.0, 0, 1)
    t1, t2 = base - np.r_[a_t, np.full(n - k, a_t[-1])] / 2, base + np.r_[
        a_t, np.full(n - k, a_t[-1])] / 2
    return t1 * (1 - ramp) + w1 * ramp, t2 * (1 - ramp) + w2 * ramp
