"""Measures of a field model: stresses in measurement circles beside Kirsch, the damage depth
ratio D/R by direction, notches, and crack counts by ring.

Compression positive; SI inside, MPa and m in the returned tables. Angles θ in degrees from +x
(counter-clockwise) about the opening's centroid (circle: its centre).

**Damage** is a bond break (parallel bond or smooth joint, tension or shear) logged by the
engine. The damage *connected to the opening* is the set of breaks linked to the profile:
breaks within ``LINK_SIZES`` crack sizes (bond diameters) of each other form clusters, and a
cluster counts when one of its breaks lies within ``LINK_SIZES`` sizes of the design profile.
**D(θ)** is the largest distance from the centroid to a connected break whose direction lies in
the bin around θ (D = R where there is none), **R(θ)** the distance from the centroid to the
design profile along θ (thesis Fig. 7-9).
"""
from __future__ import annotations

import numpy as np

from .field_geometry import distance_to_polygon, points_in_polygon, ray_exit_distance
from .measure import pair_forces
from .state import X, Y

__all__ = ["particle_stress", "circle_stress", "kirsch", "kirsch_circle_mean", "stress_profile",
           "damage_depth", "notches", "LINK_SIZES", "BIN_DEG", "NOTCH_MIN_DEPTH_SIZES"]

#: Breaks closer than this many crack sizes (bond diameters) are linked into one cluster, and a
#: cluster this close to the profile is connected to the opening.
LINK_SIZES = 2.0
#: Angular bin of D(θ), degrees.
BIN_DEG = 5.0
#: A notch is a run of bins whose D − R is at least this many mean crack sizes.
NOTCH_MIN_DEPTH_SIZES = 2.0


def particle_stress(state) -> np.ndarray:
    """(N, 3) virial sums per particle, (Σ l_x F_x, Σ l_y F_y, Σ sym l⊗F)/2 over its pairs, N·m.

    Half of each pair's l ⊗ F goes to each of its particles; summing rows of a set and dividing
    by its area gives the Love–Weber stress (:func:`sim.measure.virial_stress`), compression
    positive.
    """
    x, y = state.pf[X], state.pf[Y]
    n = state.n
    out = np.zeros((n, 3))
    for i, j, fx, fy in pair_forces(state):
        lx, ly = x[j] - x[i], y[j] - y[i]
        c = np.c_[lx * fx, ly * fy, 0.5 * (lx * fy + ly * fx)] * 0.5
        for k in range(3):
            out[:, k] += np.bincount(i, c[:, k], minlength=n) + np.bincount(j, c[:, k],
                                                                           minlength=n)
    return out


def circle_stress(x, y, s, centre, radius, t=1.0):
    """(2, 2) stress in a measurement circle, Pa: Σ of the per-particle sums ``s`` of the
    particles whose centres lie inside, over the circle's area (PFC measurement circle)."""
    inside = (x - centre[0]) ** 2 + (y - centre[1]) ** 2 < radius * radius
    a = np.pi * radius * radius * t
    sxx, syy, sxy = (s[inside, k].sum() / a for k in range(3))
    return np.array([[sxx, sxy], [sxy, syy]]), int(inside.sum())


def kirsch(r_over_a, theta_deg, sxx, syy):
    """(σ_rr, σ_θθ, τ_rθ) around a traction-free circular hole under far-field σxx, σyy
    (REFERENCE.md §6.3), same units and sign as the inputs."""
    ra = np.asarray(r_over_a, float)
    th = np.radians(theta_deg)
    p, q = 0.5 * (sxx + syy), 0.5 * (sxx - syy)
    a2, a4 = ra ** -2, ra ** -4
    srr = p * (1 - a2) + q * (1 - 4 * a2 + 3 * a4) * np.cos(2 * th)
    stt = p * (1 + a2) - q * (1 + 3 * a4) * np.cos(2 * th)
    trt = -q * (1 + 2 * a2 - 3 * a4) * np.sin(2 * th)
    return srr, stt, trt


def kirsch_circle_mean(centre_xy, rho, a, sxx, syy, n=24):
    """(2, 2) Kirsch stress averaged over a measurement circle of radius ``rho`` centred at
    ``centre_xy`` (relative to the hole's centre), Gauss-type polar quadrature, same units."""
    rq = (np.arange(n) + 0.5) / n
    tq = 2 * np.pi * (np.arange(2 * n) + 0.5) / (2 * n)
    R, T = np.meshgrid(rho * np.sqrt(rq), tq)          # equal-area rings
    px = centre_xy[0] + R * np.cos(T)
    py = centre_xy[1] + R * np.sin(T)
    rr = np.hypot(px, py)
    th = np.degrees(np.arctan2(py, px))
    srr, stt, trt = kirsch(rr / a, th, sxx, syy)
    c, s = np.cos(np.radians(th)), np.sin(np.radians(th))
    sx = srr * c * c + stt * s * s - 2 * trt * s * c
    sy = srr * s * s + stt * c * c + 2 * trt * s * c
    sxy = (srr - stt) * s * c + trt * (c * c - s * s)
    return np.array([[sx.mean(), sxy.mean()], [sxy.mean(), sy.mean()]])


def stress_profile(sim, centre, a, sxx, syy, *, profile=None,
                   r_over_a=(1.1, 1.25, 1.5, 2.0, 3.0),
                   theta_deg=(0, 45, 90, 135, 180, 225, 270, 315), circle_frac=0.9):
    """Stresses in measurement circles along rays, beside Kirsch for radius ``a``.

    Each circle is the largest that stays off the opening, up to ``circle_frac`` × a: radius
    min(circle_frac a, 0.9 d) with d the distance from its centre to the opening's ``profile``
    (default the circle of radius a: d = r − a); a centre inside the opening gives NaN. The
    Kirsch columns are the analytic field averaged over the same circle (the point values are
    ``kirsch_*_point_mpa``): at r = 1.5 a a circle of 0.45 a averages a field that varies by
    40 % across it.

    Returns
    -------
    rows : list of dict
        ``r_over_a, theta_deg, sigma_rr_mpa, sigma_tt_mpa, kirsch_rr_mpa, kirsch_tt_mpa``,
        ``kirsch_rr_point_mpa, kirsch_tt_point_mpa, circle_radius_m, particles``.
    """
    st = sim.state
    s = particle_stress(st)
    x, y = st.pf[X], st.pf[Y]
    rows = []
    for ra in r_over_a:
        for th in theta_deg:
            c, sn = np.cos(np.radians(th)), np.sin(np.radians(th))
            p = (centre[0] + ra * a * c, centre[1] + ra * a * sn)
            if profile is None:
                d, inside = (ra - 1.0) * a, ra <= 1.0
            else:
                d = float(distance_to_polygon([p[0]], [p[1]], profile)[0])
                inside = bool(points_in_polygon([p[0]], [p[1]], profile)[0])
            rho = min(circle_frac * a, 0.9 * d)
            sig, n = circle_stress(x, y, s, p, rho)
            if inside or n == 0:
                sig = np.full((2, 2), np.nan)
            nr, nt = np.array([c, sn]), np.array([-sn, c])
            krr, ktt, _ = kirsch(ra, th, sxx, syy)
            km = kirsch_circle_mean((ra * a * c, ra * a * sn), rho, a, sxx, syy)
            rows.append({"r_over_a": ra, "theta_deg": float(th),
                         "sigma_rr_mpa": float(nr @ sig @ nr) / 1e6,
                         "sigma_tt_mpa": float(nt @ sig @ nt) / 1e6,
                         "kirsch_rr_mpa": float(nr @ km @ nr) / 1e6,
                         "kirsch_tt_mpa": float(nt @ km @ nt) / 1e6,
                         "kirsch_rr_point_mpa": float(krr) / 1e6,
                         "kirsch_tt_point_mpa": float(ktt) / 1e6,
                         "circle_radius_m": rho, "particles": n})
    return rows


def _connected(cx, cy, size, profile):
    """Mask of the breaks connected to the profile (see the module docstring)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    n = cx.size
    if n == 0:
        return np.zeros(0, bool)
    link = LINK_SIZES * float(np.max(size))
    pairs = cKDTree(np.c_[cx, cy]).query_pairs(link, output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        d = np.hypot(cx[i] - cx[j], cy[i] - cy[j])
        keep = d <= LINK_SIZES * 0.5 * (size[i] + size[j])
        i, j = i[keep], j[keep]
    else:
        i = j = np.zeros(0, np.int64)
    g = coo_matrix((np.ones(i.size), (i, j)), shape=(n, n))
    _, lab = connected_components(g, directed=False)
    near = distance_to_polygon(cx, cy, profile) <= LINK_SIZES * size
    return np.isin(lab, np.unique(lab[near]))


def damage_depth(cracks, profile, centroid, *, others=(), bin_deg=BIN_DEG):
    """D/R by direction around one opening.

    Parameters
    ----------
    cracks : pandas.DataFrame
        The crack log (``x, y, size_m``).
    profile : (M, 2) array_like
        Design profile of this opening.
    centroid : (2,)
    others : sequence of (M, 2) arrays
        Profiles of the other openings: a ray whose profile point lies inside or on another
        opening (joined by a stope) gets NaN.

    Returns
    -------
    rows : list of dict
        ``angle_deg`` (bin centre), ``R_m``, ``D_m``, ``D_over_R``, ``n_cracks`` (connected
        breaks in the bin).
    connected : (C,) bool
        Breaks connected to this opening.
    """
    profile = np.asarray(profile, float)
    cx = cracks["x"].to_numpy(float) if len(cracks) else np.zeros(0)
    cy = cracks["y"].to_numpy(float) if len(cracks) else np.zeros(0)
    size = cracks["size_m"].to_numpy(float) if len(cracks) else np.zeros(0)
    conn = _connected(cx, cy, size, profile)
    nb = int(round(360.0 / bin_deg))
    ang = (np.arange(nb) + 0.5) * bin_deg
    R = ray_exit_distance(profile, centroid, np.radians(ang))
    px = centroid[0] + R * np.cos(np.radians(ang))
    py = centroid[1] + R * np.sin(np.radians(ang))
    joined = np.zeros(nb, bool)
    for o in others:
        oo = np.asarray(o, float)
        joined |= points_in_polygon(px, py, oo) | (distance_to_polygon(px, py, oo) < 1e-6)
    dx, dy = cx[conn] - centroid[0], cy[conn] - centroid[1]
    dist = np.hypot(dx, dy)
    b = (np.floor((np.degrees(np.arctan2(dy, dx)) % 360.0) / bin_deg)).astype(int) % nb
    D = R.copy()
    cnt = np.bincount(b, minlength=nb)
    if dist.size:
        np.maximum.at(D, b, dist)
    rows = []
    for k in range(nb):
        bad = joined[k] or not np.isfinite(R[k])
        rows.append({"angle_deg": float(ang[k]), "R_m": float(R[k]),
                     "D_m": float("nan") if bad else float(D[k]),
                     "D_over_R": float("nan") if bad else float(D[k] / R[k]),
                     "n_cracks": int(cnt[k])})
    return rows, conn


def notches(rows, centroid, min_depth):
    """Notches: runs of neighbouring bins with D − R ≥ ``min_depth`` (m), around the circle.

    Returns
    -------
    list of dict
        ``depth_m`` (largest D − R), ``tip_angle_deg``, ``span_deg`` (angular extent about the
        centroid), ``height_m`` (chord between the profile points at the run's two ends: the
        notch's base along the wall) and ``angle_deg`` (apex angle of the V from the tip to
        those two base points), ``max_D_over_R``.
    """
    ang = np.array([r["angle_deg"] for r in rows])
    R = np.array([r["R_m"] for r in rows])
    D = np.array([r["D_m"] for r in rows])
    deep = np.nan_to_num(D - R, nan=0.0) >= min_depth
    nb = ang.size
    if not deep.any():
        return []
    if deep.all():
        runs = [np.arange(nb)]
    else:
        start = int(np.flatnonzero(~deep)[0])
        order = (np.arange(nb) + start) % nb
        runs, cur = [], []
        for k in order:
            if deep[k]:
                cur.append(k)
            elif cur:
                runs.append(np.array(cur))
                cur = []
        if cur:
            runs.append(np.array(cur))
    step = ang[1] - ang[0] if nb > 1 else 360.0
    out = []
    for run in runs:
        tip = run[np.argmax(D[run] - R[run])]
        ends = []
        for k, side in ((run[0], -0.5), (run[-1], 0.5)):
            th = np.radians(ang[k] + side * step)
            rr = float(np.interp(np.degrees(th) % 360.0, ang, R, period=360.0))
            ends.append(np.array([centroid[0] + rr * np.cos(th), centroid[1] + rr * np.sin(th)]))
        tt = np.radians(ang[tip])
        tip_xy = np.array([centroid[0] + D[tip] * np.cos(tt), centroid[1] + D[tip] * np.sin(tt)])
        u, v = ends[0] - tip_xy, ends[1] - tip_xy
        apex = np.degrees(np.arccos(np.clip(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)),
                                            -1, 1)))
        out.append({"depth_m": float(D[tip] - R[tip]), "tip_angle_deg": float(ang[tip]),
                    "span_deg": float(run.size * step),
                    "height_m": float(np.linalg.norm(ends[1] - ends[0])),
                    "angle_deg": float(apex), "max_D_over_R": float(np.max(D[run] / R[run]))})
    return sorted(out, key=lambda n: -n["depth_m"])
