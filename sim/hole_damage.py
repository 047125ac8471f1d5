"""Damage around circular holes after a test (thesis Ch. 6): damaged area per hole, whether a
crack path joins two holes, largest particle displacement.

Definitions (N particles, B bonds, H holes of radius R; positions are those of the specimen
before loading):

* **damaged particle** — a particle with at least one bond broken during the test (in tension
  or in shear; bonds removed with a hole are not counted);
* **damaged area of a hole** — the summed disk area πr² of the damaged particles whose centres
  lie within ``radius_factor`` × R of the hole centre (default 2R: the ring from the wall to one
  radius beyond it). A planar area, mm²; it does not depend on the thickness. The total over
  the holes counts a particle once even when the rings of two holes overlap;
* **crack path joining two holes** — broken bonds that share a particle form one crack cluster
  (consecutive broken bonds along a crack share a particle of the contact network); two holes
  are joined when one cluster holds a rim particle of each, a rim particle being one whose
  centre lies within R + 2 r_max of the hole centre (the first layer of particles around it);
* **maximum displacement** — the largest |u| = |x_end − x_start| over all particles, and over
  the particles within ``radius_factor`` × R of a hole, mm.

The holes are those that ``gbmgen defect`` records in ``meta["defects"]`` (``type: hole``,
``centres_m``, ``radius_m``). :func:`hole_damage` works on arrays; :func:`hole_damage_summary`
reads a specimen and a finished simulation and gives the entries of ``summary.json``.
"""
from __future__ import annotations

import numpy as np

__all__ = ["DAMAGE_RADIUS_FACTOR", "holes_in_meta", "crack_clusters", "hole_damage",
           "hole_damage_summary"]

#: Damaged area is counted within this many hole radii of the hole centre.
DAMAGE_RADIUS_FACTOR = 2.0


def holes_in_meta(meta) -> list:
    """The holes a specimen's meta records: ``[(cx, cy, R), ...]`` in m (empty when none)."""
    out = []
    for rec in (meta or {}).get("defects", []) or []:
        if rec.get("type") == "hole":
            r = float(rec["radius_m"])
            out += [(float(c[0]), float(c[1]), r) for c in rec.get("centres_m", [])]
    return out


def crack_clusters(n_particles: int, bond_i, bond_j, broken_mask):
    """Label of each particle's crack cluster: broken bonds sharing a particle are one cluster.

    Parameters
    ----------
    n_particles : int
    bond_i, bond_j : (B,) ndarray of int
    broken_mask : (B,) ndarray of bool

    Returns
    -------
    label : (N,) ndarray of int64
        Cluster label; -1 for particles without a broken bond.

    Examples
    --------
    >>> crack_clusters(5, [0, 1, 3], [1, 2, 4], [True, True, False]).tolist()
    [0, 0, 0, -1, -1]
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    bi = np.asarray(bond_i)[np.asarray(broken_mask, bool)]
    bj = np.asarray(bond_j)[np.asarray(broken_mask, bool)]
    label = np.full(n_particles, -1, np.int64)
    if bi.size == 0:
        return label
    g = coo_matrix((np.ones(bi.size), (bi, bj)), shape=(n_particles, n_particles))
    _, comp = connected_components(g, directed=False)
    touched = np.zeros(n_particles, bool)
    touched[bi] = touched[bj] = True
    _, label[touched] = np.unique(comp[touched], return_inverse=True)
    return label


def hole_damage(x0, y0, r, bond_i, bond_j, broken_mask, holes, *, x=None, y=None,
                radius_factor: float = DAMAGE_RADIUS_FACTOR) -> dict:
    """Damage measures around ``holes`` (module docstring).

    Parameters
    ----------
    x0, y0, r : (N,) ndarray of float64, m
        Particle centres before loading and radii.
    bond_i, bond_j : (B,) ndarray of int
    broken_mask : (B,) ndarray of bool
        Bonds broken during the test.
    holes : sequence of (cx, cy, R), m
    x, y : (N,) ndarray of float64, m, optional
        Centres at the end of the test (for the displacements).
    radius_factor : float
        Damaged area within this many hole radii of a hole centre.

    Returns
    -------
    measures : dict
        ``holes`` (per hole: centre_mm, radius_mm, damaged_area_mm2, damaged_particles),
        ``damaged_area_mm2`` (all holes, each particle once), ``crack_joins_holes`` (None with
        fewer than two holes), ``joined_pairs``, ``max_displacement_mm``,
        ``max_displacement_near_holes_mm`` and ``damage_radius_factor``.

    Examples
    --------
    >>> x0 = np.array([0.0, 1.0, 2.0, 3.0]); y0 = np.zeros(4); r = np.full(4, 0.5)
    >>> m = hole_damage(x0, y0, r, [0, 1, 2], [1, 2, 3], [True, True, True],
    ...                 [(-1.0, 0.0, 0.5), (4.0, 0.0, 0.5)], radius_factor=4.0)
    >>> m["crack_joins_holes"], m["joined_pairs"]
    (True, [[0, 1]])
    """
    x0, y0, r = (np.asarray(a, float) for a in (x0, y0, r))
    n = x0.size
    broken = np.asarray(broken_mask, bool)
    bi, bj = np.asarray(bond_i, np.int64), np.asarray(bond_j, np.int64)
    damaged = np.zeros(n, bool)
    damaged[bi[broken]] = damaged[bj[broken]] = True
    disk = np.pi * r * r
    label = crack_clusters(n, bi, bj, broken)
    rim_width = 2.0 * float(r.max()) if n else 0.0
    per_hole, near_any, rims = [], np.zeros(n, bool), []
    for cx, cy, rad in holes:
        d = np.hypot(x0 - cx, y0 - cy)
        near = d <= radius_factor * rad
        near_any |= near
        sel = near & damaged
        per_hole.append({"centre_mm": [1e3 * cx, 1e3 * cy], "radius_mm": 1e3 * rad,
                         "damaged_area_mm2": 1e6 * float(disk[sel].sum()),
                         "damaged_particles": int(sel.sum())})
        rim = (d <= rad + rim_width) & (label >= 0)
        rims.append(set(np.unique(label[rim]).tolist()))
    pairs = [[a, b] for a in range(len(rims)) for b in range(a + 1, len(rims))
             if rims[a] & rims[b]]
    out = {"holes": per_hole,
           "damaged_area_mm2": 1e6 * float(disk[near_any & damaged].sum()),
           "damage_radius_factor": float(radius_factor),
           "crack_joins_holes": bool(pairs) if len(holes) > 1 else None,
           "joined_pairs": pairs}
    if x is not None and y is not None and n:
        u = np.hypot(np.asarray(x, float) - x0, np.asarray(y, float) - y0)
        out["max_displacement_mm"] = 1e3 * float(u.max())
        out["max_displacement_near_holes_mm"] = (1e3 * float(u[near_any].max())
                                                 if near_any.any() else None)
    return out


def hole_damage_summary(specimen, sim, *, radius_factor: float = DAMAGE_RADIUS_FACTOR) -> dict:
    """``{"hole_damage": measures}`` for a specimen with holes after a test, else ``{}``.

    Parameters
    ----------
    specimen : sim.Specimen
        The specimen as loaded (its ``meta`` lists the holes; its positions are the start).
    sim : sim.Simulation
        The engine at the end of the test.
    """
    holes = holes_in_meta(specimen.meta)
    if not holes or sim is None:
        return {}
    pid = np.asarray(sim.particle_id)
    x = np.array(specimen.x, float)
    y = np.array(specimen.y, float)
    x[pid], y[pid] = sim.x, sim.y
    state = np.asarray(sim.bond_state)
    broken = (state == 1) | (state == 2)
    return {"hole_damage": hole_damage(specimen.x, specimen.y, specimen.r, specimen.bond_i,
                                       specimen.bond_j, broken, holes, x=x, y=y,
                                       radius_factor=radius_factor)}
