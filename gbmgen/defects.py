"""Defects (thesis Ch. 6): circular holes placed intra-, inter- or trans-grain, double holes by
bridge length and angle, inclined flaws. A defect removes the particles whose centres fall inside
it (PFC ``ball delete range``) and their bonds; the grain polygons are kept and the defects are
listed in ``meta["defects"]``.

Automatic placement of one hole of radius R on the grain structure (nearest to the specimen
centre among the candidates, so the choice is deterministic):

* ``intra``  — centre at a grain's centroid whose distance to the grain boundary is >= R: the hole
  lies inside one grain;
* ``inter``  — centre at the midpoint of a boundary segment between two grains, the segment being
  long enough (> 2R) that the hole touches those two grains only;
* ``trans3`` — centre at a junction of three grains: the hole cuts three grains;
* ``trans4`` — centre at the midpoint of a boundary segment shorter than 2R whose two ends are
  junctions: the hole cuts four grains.

Every placement is checked: the number of grains the hole disk overlaps must be 1, 2, 3 or 4.
"""
from __future__ import annotations

import numpy as np

from sim.specimen import Specimen

from .errors import InputError

__all__ = ["HOLE_KINDS", "place_hole", "double_hole_centres", "grains_cut", "cut_holes",
           "cut_flaw"]

HOLE_KINDS = {"intra": 1, "inter": 2, "trans3": 3, "trans4": 4}


def _edges(spec):
    """All polygon edges: (E, 2, 2) endpoints and (E,) owning grain."""
    xy, off = spec.grain_xy, spec.grain_offsets
    nxt = np.arange(xy.shape[0]) + 1
    nxt[off[1:] - 1] = off[:-1]
    owner = np.repeat(np.arange(spec.n_grains), np.diff(off))
    return np.stack([xy, xy[nxt]], axis=1), owner


def _seg_dist(p, seg):
    a, b = seg[:, 0], seg[:, 1]
    e = b - a
    ll = np.maximum(np.sum(e * e, axis=1), 1e-300)
    t = np.clip(np.sum((p - a) * e, axis=1) / ll, 0.0, 1.0)
    return np.hypot(*(a + t[:, None] * e - p).T)


def _inside_polys(p, spec):
    """Grain containing point p (crossing number), -1 if none."""
    from .assign import particles_to_grains
    return int(particles_to_grains([p[0]], [p[1]], spec.grain_xy, spec.grain_offsets,
                                   spec.box)[0])


def grains_cut(spec, centre, radius):
    """Indices of the grains that a disk (centre, radius) overlaps.

    Parameters
    ----------
    spec : sim.Specimen
    centre : (2,) array_like, m
    radius : float, m

    Returns
    -------
    grains : ndarray of int
        Sorted grain indices (a grain whose boundary comes within ``radius`` of the centre, or
        that contains the centre).
    """
    p = np.asarray(centre, float)
    seg, owner = _edges(spec)
    d = _seg_dist(p, seg)
    near = set(np.unique(owner[d < radius]).tolist())
    g = _inside_polys(p, spec)
    if g >= 0:
        near.add(g)
    return np.array(sorted(near), int)


def _junctions(spec, tol):
    """Distinct vertices with the number of grains meeting there."""
    key = np.round(spec.grain_xy / tol).astype(np.int64)
    owner = np.repeat(np.arange(spec.n_grains), np.diff(spec.grain_offsets))
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    pairs = np.unique(np.c_[inv, owner], axis=0)
    count = np.bincount(pairs[:, 0], minlength=first.size)
    return spec.grain_xy[first], count, inv


def place_hole(spec, kind, radius):
    """Centre of a hole of ``radius`` (m) of the given kind (see the module docstring).

    Returns
    -------
    centre : (2,) ndarray of float64, m

    Raises
    ------
    InputError
        Unknown kind, no grains, or no place where the hole fits as asked.
    """
    if kind not in HOLE_KINDS:
        raise InputError(f"hole kind: expected one of {sorted(HOLE_KINDS)}, got {kind!r}")
    if spec.n_grains == 0:
        raise InputError("specimen has no grains: automatic hole placement needs grain polygons")
    if not (np.isfinite(radius) and radius > 0):
        raise InputError(f"hole radius: expected > 0 m, got {radius!r}")
    box = spec.box
    mid = np.array([0.5 * (box[0] + box[1]), 0.5 * (box[2] + box[3])])
    inner = np.array([box[0] + radius, box[1] - radius, box[2] + radius, box[3] - radius])
    L = max(box[1] - box[0], box[3] - box[2])
    cands = []
    if kind == "intra":
        from .tessellate import polygon_centroids
        cands = polygon_centroids(spec.grain_xy, spec.grain_offsets)
    else:
        if kind == "trans3":
            verts, count, _ = _junctions(spec, 1e-9 * L)
            cands = verts[count == 3]
        else:
            seg, _ = _edges(spec)
            length = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
            ok = length > 2.0 * radius if kind == "inter" else length < 2.0 * radius
            cands = 0.5 * (seg[ok, 0] + seg[ok, 1])
    cands = np.asarray(cands, float).reshape(-1, 2)
    inside = ((cands[:, 0] >= inner[0]) & (cands[:, 0] <= inner[1])
              & (cands[:, 1] >= inner[2]) & (cands[:, 1] <= inner[3]))
    cands = cands[inside]
    order = np.argsort(np.hypot(*(cands - mid).T), kind="stable")
    want = HOLE_KINDS[kind]
    for c in cands[order][:500]:
        if grains_cut(spec, c, radius).size == want:
            return c
    raise InputError(f"hole kind {kind!r}: no place in the specimen where a hole of radius "
                     f"{radius * 1e3:g} mm cuts exactly {want} grain(s); change the hole or "
                     "grain size")


def double_hole_centres(centre, radius, bridge_length, angle_deg):
    """Centres of two holes of ``radius`` whose walls are ``bridge_length`` apart along a line
    at ``angle_deg`` from horizontal through ``centre`` (thesis Ch. 6: bridge 0.5R..4R, 0..150°).

    Examples
    --------
    >>> double_hole_centres([0, 0], 1.0, 2.0, 0.0).tolist()
    [[-2.0, 0.0], [2.0, 0.0]]
    """
    c = np.asarray(centre, float)
    a = np.deg2rad(angle_deg)
    h = radius + 0.5 * bridge_length
    u = np.array([np.cos(a), np.sin(a)])
    return np.stack([c - h * u, c + h * u])


def _remove(spec, remove_mask, record):
    """A new Specimen without the masked particles and their bonds; ``record`` -> meta."""
    keep = ~remove_mask
    if not np.any(keep):
        raise InputError("defect removes every particle")
    new_index = np.cumsum(keep) - 1
    bk = keep[spec.bond_i] & keep[spec.bond_j]
    meta = dict(spec.meta or {})
    meta["defects"] = list(meta.get("defects", [])) + [record]
    arrays = {k: getattr(spec, k) for k in spec.__dataclass_fields__ if k != "meta"}
    for k in ("x", "y", "r", "mineral", "grain"):
        arrays[k] = arrays[k][keep]
    arrays["bond_i"] = new_index[spec.bond_i[bk]]
    arrays["bond_j"] = new_index[spec.bond_j[bk]]
    for k in ("bond_kind", "joint_nx", "joint_ny"):
        arrays[k] = arrays[k][bk]
    record["particles_removed"] = int(remove_mask.sum())
    record["bonds_removed"] = int((~bk).sum())
    return Specimen(**arrays, meta=meta).validate("gbmgen defect")


def cut_holes(spec, centres, radius, *, kind="manual"):
    """Remove the particles whose centres lie in circular holes.

    Parameters
    ----------
    spec : sim.Specimen
    centres : (H, 2) array_like, m
    radius : float, m
    kind : str
        Recorded in ``meta["defects"]``.

    Returns
    -------
    specimen : sim.Specimen
        A new specimen; ``meta["defects"]`` gains {type: hole, kind, centres_m, radius_m,
        grains_cut, particles_removed, bonds_removed}.
    """
    c = np.asarray(centres, float).reshape(-1, 2)
    mask = np.zeros(spec.n_particles, bool)
    for p in c:
        mask |= np.hypot(spec.x - p[0], spec.y - p[1]) < radius
    cut = [grains_cut(spec, p, radius).tolist() if spec.n_grains else [] for p in c]
    rec = {"type": "hole", "kind": kind, "centres_m": c.tolist(), "radius_m": float(radius),
           "grains_cut": cut}
    return _remove(spec, mask, rec)


def cut_flaw(spec, centre, length, width, angle_deg):
    """Remove the particles in an inclined flaw (a slot of ``length`` x ``width``, m, at
    ``angle_deg`` from horizontal, centred at ``centre``)."""
    if not (length > 0 and width > 0):
        raise InputError(f"flaw: expected length and width > 0, got {length!r}, {width!r}")
    a = np.deg2rad(angle_deg)
    u = np.array([np.cos(a), np.sin(a)])
    v = np.array([-u[1], u[0]])
    d = np.c_[spec.x - centre[0], spec.y - centre[1]]
    mask = (np.abs(d @ u) <= 0.5 * length) & (np.abs(d @ v) <= 0.5 * width)
    rec = {"type": "flaw", "centre_m": [float(centre[0]), float(centre[1])],
           "length_m": float(length), "width_m": float(width), "angle_deg": float(angle_deg)}
    return _remove(spec, mask, rec)
