"""The test rig: the specimen made ready for loading, the engine, rigid platens, and what the
engine reports (platen forces and gaps, the crack log, energies).

Everything that touches the engine (:class:`sim.simulation.Simulation`) goes through these small
functions, so that the protocols hold no engine details. Compression positive.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from ..analysis import CRACK_KINDS
from .outputs import CRACK_COLUMNS

__all__ = ["relieve_overlaps", "make_simulation", "add_platens", "platen_gap", "platen_force",
           "crack_frame", "crack_tally", "energies"]


def relieve_overlaps(specimen):
    """A copy of ``specimen`` whose particles do not overlap, and what was changed.

    PFC bonds a packing and then zeroes the linear contact forces (thesis App. E: ``lin_mode 1``
    with the forces reset after bonding), so the initial overlaps of a packing carry no force.
    The engine's linear law is overlap based (``lin_mode 0``): a packing with overlaps of 0.2 %
    of a radius starts with tens of MPa of locked-in stress and breaks bonds before loading.
    This removes the overlaps geometrically instead: each particle's radius shrinks by half of
    its largest overlap (so that r_i + r_j <= d_ij for every pair), and ``box`` is set to the
    particles' extent so that the platens start touching.

    Returns
    -------
    specimen : sim.Specimen
    info : dict
        ``n_overlaps``, ``max_overlap_rel`` (largest overlap / smaller radius before) and
        ``max_radius_change_rel``.

    Examples
    --------
    >>> from sim import Specimen
    >>> s = Specimen.lattice(nx=3, ny=2, radius=1e-3, gap=-1e-3)   # 0.2 % overlaps
    >>> t, info = relieve_overlaps(s)
    >>> info["n_overlaps"], round(info["max_radius_change_rel"], 6)
    (9, 0.001)
    """
    from scipy.spatial import cKDTree
    x, y, r = specimen.x, specimen.y, specimen.r
    pairs = cKDTree(np.c_[x, y]).query_pairs(2.0 * float(r.max()), output_type="ndarray")
    cut = np.zeros_like(r)
    n_ov, worst = 0, 0.0
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        ov = r[i] + r[j] - np.hypot(x[j] - x[i], y[j] - y[i])
        hit = ov > 0
        n_ov = int(hit.sum())
        if n_ov:
            i, j, ov = i[hit], j[hit], ov[hit] * (1.0 + 1e-9)
            worst = float(np.max(ov / np.minimum(r[i], r[j])))
            np.maximum.at(cut, i, 0.5 * ov)
            np.maximum.at(cut, j, 0.5 * ov)
    r2 = r - cut
    box = np.array([(x - r2).min(), (x + r2).max(), (y - r2).min(), (y + r2).max()])
    meta = dict(specimen.meta)
    info = {"n_overlaps": n_ov, "max_overlap_rel": worst,
            "max_radius_change_rel": float(np.max(cut / r))}
    meta["relieved_overlaps"] = info
    return dataclasses.replace(specimen, r=r2, box=box, meta=meta), info


def make_simulation(specimen, **options):
    """Build the engine's Simulation from a specimen (keyword options passed through)."""
    from ..simulation import Simulation
    return Simulation(specimen, **options)


def add_platens(sim, box, *, axis: int = 1, fric: float = 0.0, emod=None):
    """Two rigid frictionless platens on the faces of ``box`` normal to ``axis`` (1 = y).

    Returns
    -------
    lo, hi : int
        Wall indices of the platen at the low and at the high face; normals point inwards.
    """
    xmin, xmax, ymin, ymax = (float(v) for v in box)
    kw = dict(fric=fric) if emod is None else dict(fric=fric, emod=emod)
    if axis == 1:
        lo = sim.add_wall((0.5 * (xmin + xmax), ymin), (0.0, 1.0), **kw)
        hi = sim.add_wall((0.5 * (xmin + xmax), ymax), (0.0, -1.0), **kw)
    else:
        lo = sim.add_wall((xmin, 0.5 * (ymin + ymax)), (1.0, 0.0), **kw)
        hi = sim.add_wall((xmax, 0.5 * (ymin + ymax)), (-1.0, 0.0), **kw)
    return lo, hi


def platen_gap(sim, lo: int, hi: int, axis: int = 1) -> float:
    """Distance between two parallel platens, m."""
    return float(np.asarray(sim.wall_position(hi))[axis] - np.asarray(sim.wall_position(lo))[axis])


def platen_force(sim, lo: int, hi: int, axis: int = 1) -> float:
    """Mean compressive force of the particles on two facing platens, N (compression +)."""
    f_lo = np.asarray(sim.wall_force(lo), float)[axis]     # pushed towards -axis: negative
    f_hi = np.asarray(sim.wall_force(hi), float)[axis]     # pushed towards +axis: positive
    return 0.5 * (f_hi - f_lo)


def crack_frame(sim) -> pd.DataFrame:
    """The engine's crack log as a DataFrame, :data:`CRACK_COLUMNS` first."""
    frame = sim.cracks.to_frame()
    rest = [c for c in frame.columns if c not in CRACK_COLUMNS]
    return frame[list(CRACK_COLUMNS) + rest]


def crack_tally(sim) -> dict:
    """Cumulative crack counts by kind (:data:`sim.analysis.CRACK_KINDS`) and ``total``."""
    c = sim.cracks.counts()
    out = {k: int(c.get(k, 0)) for k in CRACK_KINDS}
    out["total"] = int(sum(out.values()))
    return out


def energies(sim) -> tuple:
    """(kinetic, strain) energy of the particles and contacts, J."""
    e = sim.energy()
    strain = 0.0
    for k in ("strain_bond", "strain_contact", "strain_wall"):
        strain += e[k]
    return float(e["kinetic"]), float(strain)
