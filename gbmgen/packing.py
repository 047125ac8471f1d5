"""Size-distributed disk packings: grain seeds from a grain-size table, and the particle packing.

Both are placed at random in the box and relaxed to a small overlap by
:func:`sim.relax.relax_overlaps` (the packing relaxation that :mod:`sim` provides).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from sim.relax import relax_overlaps

from . import config
from .errors import InputError
from .faces import seat_faces as _seat_faces
from .table import GrainSizeTable

__all__ = ["Seeds", "sample_grain_sizes", "pack_seeds", "pack_particles", "particle_radii"]


@dataclass
class Seeds:
    """Grain seeds: disks whose Laguerre cells become the grains.

    Notation: S seeds.

    Attributes
    ----------
    x, y, r : (S,) ndarray of float64, m
        Seed centres and disk radii.
    d : (S,) ndarray of float64, m
        Target equivalent diameter of the grain each seed stands for.
    mineral : (S,) ndarray of int32
    klass : (S,) ndarray of int8
        0 fine, 1 medium, 2 coarse.
    info : dict
        Relaxation report.
    """

    x: np.ndarray
    y: np.ndarray
    r: np.ndarray
    d: np.ndarray
    mineral: np.ndarray
    klass: np.ndarray
    info: dict


def _largest_remainder(total, shares):
    raw = total * np.asarray(shares, float)
    n = np.floor(raw).astype(np.int64)
    left = int(total - n.sum())
    if left > 0:
        n[np.argsort(-(raw - n), kind="stable")[:left]] += 1
    return n


def sample_grain_sizes(table: GrainSizeTable, area_m2: float, rng):
    """Grain diameters that fill ``area_m2`` with the table's mineral fractions and classes.

    Parameters
    ----------
    table : GrainSizeTable
        At the scale of the model (sizes in um).
    area_m2 : float
        Area to fill, m^2.
    rng : numpy.random.Generator

    Returns
    -------
    d : (S,) ndarray of float64, m
        Diameters; within each (mineral, class) they are stratified samples of the uniform
        class distribution (one draw in each of n equal-probability strata), which keeps the
        sample's distribution within ~1/n of the target.
    mineral : (S,) ndarray of int32
    klass : (S,) ndarray of int8

    Notes
    -----
    Mineral i gets n_i = round(w_i A / E_i[pi d^2 / 4]) grains, E_i over its class mixture
    (E[d^2] = (lo^2 + lo hi + hi^2) / 3 in a class), split over the classes by frequency
    (largest remainder).
    """
    lo = table.lo_um * 1e-6
    hi = table.hi_um * 1e-6
    d_all, m_all, c_all = [], [], []
    for k in range(table.n_minerals):
        ed2 = (lo[k] ** 2 + lo[k] * hi[k] + hi[k] ** 2) / 3.0
        mean_area = np.pi / 4.0 * float(np.dot(table.frequencies[k], ed2))
        n_k = int(round(table.volume_fractions[k] * area_m2 / mean_area))
        if table.volume_fractions[k] > 0:
            n_k = max(n_k, 1)
        n_c = _largest_remainder(n_k, table.frequencies[k])
        for c in range(3):
            n = int(n_c[c])
            if n == 0:
                continue
            u = (np.arange(n) + rng.random(n)) / n
            d_all.append(lo[k, c] + u * (hi[k, c] - lo[k, c]))
            m_all.append(np.full(n, k, np.int32))
            c_all.append(np.full(n, c, np.int8))
    if not d_all:
        raise InputError(f"{table.source}: no grains to place (all volume fractions zero?)")
    return np.concatenate(d_all), np.concatenate(m_all), np.concatenate(c_all)


def _random_inside(r, box, rng):
    x = box[0] + r + rng.random(r.size) * (box[1] - box[0] - 2 * r)
    y = box[2] + r + rng.random(r.size) * (box[3] - box[2] - 2 * r)
    return x, y


def _cell_order(x, y, h):
    """Permutation that sorts points by cell row then column (memory locality)."""
    return np.lexsort((np.floor(x / h), np.floor(y / h)))


def pack_seeds(table: GrainSizeTable, box, *, rng, packing_fraction=config.SEED_PACKING_FRACTION,
               tol=config.SEED_OVERLAP_TOL, max_iter=config.SEED_MAX_ITER) -> Seeds:
    """Seed disks for a Laguerre/Voronoi tessellation (``ball distribute`` + relax, per mineral).

    Parameters
    ----------
    table : GrainSizeTable
        Scenario table at model scale (um).
    box : (4,) array_like of float64, m
    rng : numpy.random.Generator
    packing_fraction : float
        Solid fraction of the seed disks.
    tol, max_iter
        Relaxation target (largest overlap / smaller radius) and step limit.

    Returns
    -------
    seeds : Seeds
        Disk radius r = d/2 * sqrt(f * A / sum(pi d^2 / 4)), f the packing fraction, so that
        a Laguerre cell (area ~ disk area / f) has an equivalent diameter ~ d.
    """
    box = np.asarray(box, float)
    area = (box[1] - box[0]) * (box[3] - box[2])
    d, mineral, klass = sample_grain_sizes(table, area, rng)
    r = 0.5 * d * np.sqrt(packing_fraction * area / np.sum(np.pi * d * d / 4.0))
    side = min(box[1] - box[0], box[3] - box[2])
    if np.any(2 * r > side):
        raise InputError(f"{table.source}: the largest grain ({2e3 * r.max():.3g} mm seed) does "
                         f"not fit in the specimen ({1e3 * side:.3g} mm); use a larger specimen "
                         "or a smaller --scale")
    x, y = _random_inside(r, box, rng)
    o = _cell_order(x, y, 3.0 * np.median(r))
    x, y, r, d, mineral, klass = x[o], y[o], r[o], d[o], mineral[o], klass[o]
    x, y, info = relax_overlaps(x, y, r, box, tol=tol, max_iter=max_iter)
    return Seeds(x=x, y=y, r=r, d=d, mineral=mineral, klass=klass, info=info)


def particle_radii(radius_mean_m, radius_ratio):
    """(rmin, rmax) of a uniform radius distribution with the given mean and rmax/rmin."""
    if not (radius_mean_m > 0 and np.isfinite(radius_mean_m)):
        raise InputError(f"particle radius: expected > 0, got {radius_mean_m!r}")
    if not (radius_ratio >= 1 and np.isfinite(radius_ratio)):
        raise InputError(f"radius ratio: expected >= 1, got {radius_ratio!r}")
    rmin = 2.0 * radius_mean_m / (1.0 + radius_ratio)
    return rmin, radius_ratio * rmin


def pack_particles(box, *, radius_mean_m, radius_ratio=config.RADIUS_RATIO,
                   porosity=config.POROSITY, rng, tol=config.PARTICLE_OVERLAP_TOL,
                   max_iter=config.PARTICLE_MAX_ITER, seat_faces=config.SEAT_FACES):
    """Isotropic random disk packing of the box at a target porosity.

    Parameters
    ----------
    box : (4,) array_like of float64, m
    radius_mean_m : float
        Mean radius, m; radii uniform on [rmin, radius_ratio * rmin].
    radius_ratio : float
        rmax / rmin (thesis 1.66).
    porosity : float
        1 - (disk area / box area), in (0, 1).
    rng : numpy.random.Generator
    tol, max_iter
        Relaxation target (largest overlap / smaller radius) and step limit.
    seat_faces : bool
        Close the dents along the four box faces afterwards (:func:`gbmgen.faces.seat_faces`),
        so that a platen on any face touches particles all along it. Default on.

    Returns
    -------
    x, y, r : (N,) ndarray of float64, m
        Sorted along rows of cells (neighbours near in memory).
    info : dict
        ``n``, ``porosity`` (realised, from the disk areas), ``max_overlap``, ``iterations``,
        ``converged``, and ``seating`` (the report of :func:`gbmgen.faces.seat_faces`, or None).

    Notes
    -----
    Radii are drawn until their area reaches (1 - porosity) of the box; centres are uniform;
    the radii are grown from ``GROW_FROM`` to 1 in a few steps with short relaxations (like
    PFC's radius expansion), then relaxed to ``tol``.
    """
    box = np.asarray(box, float)
    if not (0.0 < porosity < 1.0):
        raise InputError(f"porosity: expected a fraction in (0, 1), got {porosity!r}")
    rmin, rmax = particle_radii(radius_mean_m, radius_ratio)
    area = (box[1] - box[0]) * (box[3] - box[2])
    target = (1.0 - porosity) * area
    mean_a = np.pi * (rmin * rmin + rmin * rmax + rmax * rmax) / 3.0
    n = int(target / mean_a * 1.1) + 16
    r = rmin + rng.random(n) * (rmax - rmin)
    cum = np.cumsum(np.pi * r * r)
    n = int(np.searchsorted(cum, target)) + 1
    r = r[:min(n, r.size)]
    if 2 * rmax > min(box[1] - box[0], box[3] - box[2]):
        raise InputError("particle radius: particles larger than the specimen")
    x, y = _random_inside(r, box, rng)
    o = _cell_order(x, y, 4.0 * radius_mean_m)
    x, y, r = x[o], y[o], r[o]
    total = 0
    for s in np.linspace(config.GROW_FROM, 1.0, config.GROW_STEPS, endpoint=False):
        x, y, inf = relax_overlaps(x, y, r * s, box, tol=tol, max_iter=config.GROW_ITER)
        total += inf["iterations"]
    x, y, info = relax_overlaps(x, y, r, box, tol=tol, max_iter=max_iter)
    seating = None
    if seat_faces:
        x, y, r, seating = _seat_faces(x, y, r, box, rmin=rmin, rmax=rmax, rng=rng, tol=tol,
                                       max_iter=max_iter)
        info = dict(info, max_overlap=seating["max_overlap"], converged=seating["converged"])
    o = _cell_order(x, y, 4.0 * radius_mean_m)
    x, y, r = x[o], y[o], r[o]
    info = dict(info, iterations=info["iterations"] + total, n=int(r.size),
                porosity=float(1.0 - np.sum(np.pi * r * r) / area), seating=seating)
    if not info["converged"]:
        warnings.warn(f"particle packing: largest overlap {info['max_overlap']:.3f} of a radius "
                      f"after {info['iterations']} steps, above the tolerance {tol:g}; the "
                      f"porosity {porosity:g} may be below what a 2D packing reaches "
                      "without overlap (~0.16)", RuntimeWarning, stacklevel=2)
    return x, y, r, info
