"""Plane geometry of openings (field models): polygons, point in polygon, rays to a profile.

An opening is a simple polygon (counter-clockwise vertices, m; circles and arches are sampled
finely). ``specimen.meta["field"]["openings"]`` holds them as written by ``gbmgen field``:
a list of mappings with ``name``, ``kind`` (drive | circle | polygon | stope), ``polygon``
([[x, y], ...]), ``centroid`` and the kind's parameters (``radius_m`` and ``centre`` for a
circle). Numpy only; nothing here is per step.
"""
from __future__ import annotations

import numpy as np

__all__ = ["polygon_area", "polygon_centroid", "points_in_polygon", "ray_exit_distance",
           "distance_to_polygon", "ring_index"]


def polygon_area(xy) -> float:
    """Signed area (counter-clockwise positive), m²."""
    xy = np.asarray(xy, float)
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def polygon_centroid(xy) -> np.ndarray:
    """Area centroid (2,), m."""
    xy = np.asarray(xy, float)
    x, y = xy[:, 0], xy[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    c = x * yn - xn * y
    a = 0.5 * c.sum()
    return np.array([np.sum((x + xn) * c), np.sum((y + yn) * c)]) / (6.0 * a)


def points_in_polygon(x, y, xy) -> np.ndarray:
    """(N,) bool: points strictly inside the polygon (crossing number; edges loop once)."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    xy = np.asarray(xy, float)
    inside = np.zeros(x.shape, bool)
    ax, ay = xy[:, 0], xy[:, 1]
    bx, by = np.roll(ax, -1), np.roll(ay, -1)
    for k in range(ax.size):
        cond = (ay[k] > y) != (by[k] > y)
        if not cond.any():
            continue
        xc = ax[k] + (y - ay[k]) * (bx[k] - ax[k]) / np.where(by[k] != ay[k], by[k] - ay[k], 1.0)
        inside ^= cond & (x < xc)
    return inside


def ray_exit_distance(xy, origin, angles_rad) -> np.ndarray:
    """Distance from ``origin`` along each direction to the first crossing of the polygon's
    boundary, m (NaN where a ray meets no edge).

    For a profile that is star-shaped about ``origin`` (drives, circles: about the centroid)
    this is the design radius R(θ) of the damage-depth ratio D/R.
    """
    xy = np.asarray(xy, float)
    ox, oy = float(origin[0]), float(origin[1])
    th = np.atleast_1d(np.asarray(angles_rad, float))
    dx, dy = np.cos(th)[:, None], np.sin(th)[:, None]
    ax, ay = xy[:, 0][None, :] - ox, xy[:, 1][None, :] - oy
    ex = np.roll(xy[:, 0], -1)[None, :] - xy[:, 0][None, :]
    ey = np.roll(xy[:, 1], -1)[None, :] - xy[:, 1][None, :]
    den = dx * ey - dy * ex
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (ax * ey - ay * ex) / den          # along the ray
        s = (ax * dy - ay * dx) / den          # along the edge
    ok = (np.abs(den) > 1e-15) & (t > 0) & (s >= 0) & (s <= 1)
    t = np.where(ok, t, np.inf)
    out = t.min(axis=1)
    return np.where(np.isfinite(out), out, np.nan)


def distance_to_polygon(x, y, xy) -> np.ndarray:
    """(N,) distance from points to the polygon's boundary, m (inside or outside)."""
    x = np.asarray(x, float)[:, None]
    y = np.asarray(y, float)[:, None]
    xy = np.asarray(xy, float)
    ax, ay = xy[:, 0][None, :], xy[:, 1][None, :]
    ex = np.roll(xy[:, 0], -1)[None, :] - ax
    ey = np.roll(xy[:, 1], -1)[None, :] - ay
    ll = np.maximum(ex * ex + ey * ey, 1e-300)
    s = np.clip(((x - ax) * ex + (y - ay) * ey) / ll, 0.0, 1.0)
    return np.sqrt(np.min((x - ax - s * ex) ** 2 + (y - ay - s * ey) ** 2, axis=1))


def ring_index(x, y, foci, core_half, outer) -> np.ndarray:
    """Ring (1..K, int8) of points for nested square rings around ``foci``.

    Parameters
    ----------
    x, y : (N,) array_like, m
    foci : (F, 2) array_like, m
        Ring centres; the Chebyshev (L-infinity) distance to the nearest one counts.
    core_half : float, m
        Half-size of the innermost square (ring 1).
    outer : (K,) array_like, m
        Outer edge of each ring beyond the core (cumulative thicknesses); points farther out
        are in ring K.
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    d = np.full(x.shape, np.inf)
    for fx, fy in np.asarray(foci, float).reshape(-1, 2):
        d = np.minimum(d, np.maximum(np.abs(x - fx), np.abs(y - fy)))
    outer = np.asarray(outer, float)
    k = np.searchsorted(outer, d - core_half, side="right") + 1
    return np.minimum(k, outer.size).astype(np.int8)
