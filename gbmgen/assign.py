"""Particles -> grains (point in polygon) and bonds: parallel bonds inside, smooth joints across.

A contact with gap <= ``bond_gap`` becomes a bond. Both particles in one grain: parallel bond
(kind 0, properties of the mineral of particle i). In different grains: smooth joint (kind 1)
whose normal is the unit normal of the grain-boundary segment that the centre-to-centre segment
crosses, oriented so that n . (x_j - x_i) > 0 (REFERENCE.md §4(d)); not the ball-ball direction.
"""
from __future__ import annotations

import numpy as np

from ._kernels import bbox_grid, crossing_normals, points_in_polygons
from .errors import InputError

__all__ = ["particles_to_grains", "find_contacts", "make_bonds"]


def particles_to_grains(x, y, xy, offsets, box):
    """Grain index of every particle centre (crossing-number point in polygon, vectorised).

    Parameters
    ----------
    x, y : (N,) array_like of float64, m
    xy : (K, 2) ndarray of float64, m
        Grain polygons, grain g = ``xy[offsets[g]:offsets[g+1]]``.
    offsets : (G+1,) ndarray of int64
    box : (4,) array_like of float64, m

    Returns
    -------
    grain : (N,) ndarray of int32
        A point on a boundary (to rounding) or outside every polygon takes the nearest grain
        among the candidates of its grid cell; -1 only where no grain is near.
    """
    x = np.ascontiguousarray(x, float)
    y = np.ascontiguousarray(y, float)
    xy = np.ascontiguousarray(xy, float)
    offsets = np.ascontiguousarray(offsets, np.int64)
    box = np.asarray(box, float)
    g_n = offsets.size - 1
    if g_n == 0:
        return np.full(x.size, -1, np.int32)
    area = (box[1] - box[0]) * (box[3] - box[2])
    h = max(np.sqrt(area / g_n), 1e-12)
    nx = int((box[1] - box[0]) / h) + 1
    ny = int((box[3] - box[2]) / h) + 1
    start, items = bbox_grid(xy, offsets, box[0], box[2], h, nx, ny)
    out = np.empty(x.size, np.int32)
    points_in_polygons(x, y, xy, offsets, start, items, box[0], box[2], h, nx, ny, out)
    return out


def find_contacts(x, y, r, gap):
    """Pairs (i < j) with d_ij - r_i - r_j <= gap, sorted by (i, j).

    Returns
    -------
    i, j : (B,) ndarray of int32
    """
    from scipy.spatial import cKDTree

    if not (np.isfinite(gap) and gap >= 0):
        raise InputError(f"bond gap: expected >= 0 m, got {gap!r}")
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    r = np.asarray(r, float)
    pairs = cKDTree(np.c_[x, y]).query_pairs(2.0 * r.max() + gap, output_type="ndarray")
    if len(pairs) == 0:
        return np.zeros(0, np.int32), np.zeros(0, np.int32)
    pairs = np.sort(pairs, axis=1)
    i, j = pairs[:, 0], pairs[:, 1]
    keep = np.hypot(x[j] - x[i], y[j] - y[i]) - r[i] - r[j] <= gap
    i, j = i[keep], j[keep]
    o = np.lexsort((j, i))
    return i[o].astype(np.int32), j[o].astype(np.int32)


def make_bonds(x, y, r, grain, xy, offsets, *, gap=None, pairs=None):
    """Bonds of a packing: parallel bonds inside grains, smooth joints across boundaries.

    Parameters
    ----------
    x, y, r : (N,) ndarray of float64, m
    grain : (N,) ndarray of int32
        Grain of each particle (from :func:`particles_to_grains`).
    xy, offsets
        Grain polygons.
    gap : float, m
        Bond gap (contacts with d - r_i - r_j <= gap are bonded).
    pairs : (i, j), optional
        The bonded pairs (i < j, sorted) when they are chosen otherwise (field models bond
        by a gap relative to the pair's radii); ``gap`` is then not used.

    Returns
    -------
    bonds : dict
        ``bond_i, bond_j`` (int32, i < j), ``bond_kind`` (int8: 0 parallel bond, 1 smooth
        joint), ``joint_nx, joint_ny`` (float64, NaN for kind 0).
    """
    i, j = find_contacts(x, y, r, gap) if pairs is None else pairs
    gi, gj = grain[i], grain[j]
    kind = ((gi != gj) & (gi >= 0) & (gj >= 0)).astype(np.int8)
    nx = np.full(i.size, np.nan)
    ny = np.full(i.size, np.nan)
    sj = np.flatnonzero(kind == 1)
    if sj.size:
        ox = np.empty(sj.size)
        oy = np.empty(sj.size)
        edge = np.empty(sj.size, np.int64)
        crossing_normals(x[i[sj]], y[i[sj]], x[j[sj]], y[j[sj]],
                         gi[sj].astype(np.int64), gj[sj].astype(np.int64),
                         np.ascontiguousarray(xy, float), np.ascontiguousarray(offsets, np.int64),
                         ox, oy, edge)
        nx[sj] = ox
        ny[sj] = oy
    return {"bond_i": i, "bond_j": j, "bond_kind": kind, "joint_nx": nx, "joint_ny": ny}
