"""Openings of a field model: the arched drive profile, circles, polygons, two drives at a dip
and the stope joining them (thesis Ch. 7, Appendix D).

Every opening is a mapping (JSON, stored in ``specimen.meta["field"]["openings"]``) with
``name``, ``kind``, ``polygon`` (counter-clockwise [[x, y], ...], m), ``centroid``, ``focus``
(the centre of its rings) and the parameters of its kind. The generator fills openings with
particles like the rest of the rock; ``gbmsim excavate`` removes them, so one specimen serves
before and after excavation.
"""
from __future__ import annotations

import numpy as np

from sim.field_geometry import polygon_area, polygon_centroid

from ..errors import InputError

__all__ = ["drive", "circle", "polygon", "two_drives", "stope", "ARC_SEGMENTS"]

#: Segments of a full circle (arches use the same angular step): the chord sags by
#: r (1 - cos(pi / n)) = 1.7e-5 r, 39 um on the 2.25 m drive arch.
ARC_SEGMENTS = 720


def _record(name, kind, xy, focus, **params):
    xy = np.asarray(xy, float)
    if polygon_area(xy) < 0:
        xy = xy[::-1]
    return {"name": name, "kind": kind, "polygon": xy.tolist(),
            "centroid": polygon_centroid(xy).tolist(), "area_m2": polygon_area(xy),
            "focus": [float(focus[0]), float(focus[1])], **params}


def drive(origin=(0.0, 0.0), *, width_m=4.5, height_m=5.0, name="drive"):
    """The arched drive profile: a box under a half circle (Appendix D).

    With the defaults: box x ±2.25, y −2.5…0.25 and a circle r = 2.25 m at (0, 0.25), i.e.
    4.5 m wide and 5.0 m high, ``origin`` at mid-height of the centre line.

    Returns
    -------
    opening : dict
        Corners at (±w/2, −h/2) and (±w/2, h/2 − w/2) exactly (plus ``origin``); the arch
        sampled every 0.5°.
    """
    w, h = float(width_m), float(height_m)
    if not (w > 0 and h > w / 2):
        raise InputError(f"drive: expected width > 0 and height > width/2, got {w:g} x {h:g} m")
    ox, oy = float(origin[0]), float(origin[1])
    a = w / 2.0
    spring = h / 2.0 - a
    t = np.linspace(0.0, np.pi, ARC_SEGMENTS // 2 + 1)
    arch = np.c_[ox + a * np.cos(t), oy + spring + a * np.sin(t)]
    xy = np.vstack([[[ox - a, oy - h / 2.0], [ox + a, oy - h / 2.0]], arch])
    return _record(name, "drive", xy, (ox, oy), origin=[ox, oy], width_m=w, height_m=h,
                   arch_radius_m=a, arch_centre=[ox, oy + spring])


def circle(centre=(0.0, 0.0), *, radius_m, name="circle"):
    """A circular opening of radius ``radius_m`` (sampled at ``ARC_SEGMENTS`` vertices)."""
    a = float(radius_m)
    if not a > 0:
        raise InputError(f"circle: radius_m = {radius_m!r}, expected > 0")
    cx, cy = float(centre[0]), float(centre[1])
    t = np.linspace(0.0, 2.0 * np.pi, ARC_SEGMENTS, endpoint=False)
    return _record(name, "circle", np.c_[cx + a * np.cos(t), cy + a * np.sin(t)], (cx, cy),
                   centre=[cx, cy], radius_m=a)


def polygon(xy, *, name="polygon"):
    """Any simple polygon (vertices in either orientation), m."""
    xy = np.asarray(xy, float)
    if xy.ndim != 2 or xy.shape[1] != 2 or xy.shape[0] < 3 or not np.isfinite(xy).all():
        raise InputError("polygon: expected at least 3 finite [x, y] vertices (m)")
    if abs(polygon_area(xy)) <= 0:
        raise InputError("polygon: vertices enclose no area")
    c = polygon_centroid(xy)
    return _record(name, "polygon", xy, c)


def two_drives(*, dip_deg=65.0, spacing_m=20.0, width_m=4.5, height_m=5.0, centre=(0.0, 0.0)):
    """Two drives on levels ``spacing_m`` apart, the upper offset along a dip of ``dip_deg``.

    The drive origins lie on a line through ``centre`` rising to the right at ``dip_deg`` from
    the horizontal: lower at centre − (s / tan δ, s) / 2, upper at centre + (s / tan δ, s) / 2.

    Returns
    -------
    lower, upper : dict
    """
    d = float(dip_deg)
    if not 0.0 < d < 90.0:
        raise InputError(f"dip_deg = {dip_deg!r}: expected 0 < dip < 90 degrees")
    s = float(spacing_m)
    if not s > height_m:
        raise InputError(f"spacing_m = {spacing_m!r}: expected more than the drive height")
    dx = s / np.tan(np.radians(d))
    cx, cy = float(centre[0]), float(centre[1])
    lo = drive((cx - dx / 2, cy - s / 2), width_m=width_m, height_m=height_m, name="lower_drive")
    up = drive((cx + dx / 2, cy + s / 2), width_m=width_m, height_m=height_m, name="upper_drive")
    for o in (lo, up):
        o.update(dip_deg=d, level_spacing_m=s)
    return lo, up


def stope(lower, upper, *, width_m, name="stope", focus_step_m=2.25):
    """The stope joining two drives: a band of true width ``width_m`` (normal to the dip) along
    the line from the lower to the upper drive origin, cut by the horizontals through them.

    Returns
    -------
    opening : dict
        Parallelogram; ``foci`` = points every ``focus_step_m`` along its axis (its rings
        follow the whole stope).
    """
    w = float(width_m)
    if not w > 0:
        raise InputError(f"stope width_m = {width_m!r}: expected > 0")
    (xl, yl), (xu, yu) = lower["origin"], upper["origin"]
    dip = np.arctan2(yu - yl, xu - xl)
    hw = 0.5 * w / np.sin(dip)                 # horizontal half-width of the band
    xy = [[xl - hw, yl], [xl + hw, yl], [xu + hw, yu], [xu - hw, yu]]
    length = float(np.hypot(xu - xl, yu - yl))
    n = max(int(np.ceil(length / focus_step_m)), 1)
    t = np.linspace(0.0, 1.0, n + 1)
    foci = np.c_[xl + t * (xu - xl), yl + t * (yu - yl)]
    rec = _record(name, "stope", xy, (0.5 * (xl + xu), 0.5 * (yl + yu)), width_m=w,
                  dip_deg=float(np.degrees(dip)))
    rec["foci"] = foci.tolist()
    return rec
