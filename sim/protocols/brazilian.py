"""Brazilian (indirect tension) test on a disc: σt = 2P/(πDt) at the peak diametral load P.

The disc is cut from a rectangular specimen (:func:`cut_disc`: the particles lying wholly
inside a circle, their bonds and grain labels), or given ready-made (``cut=False``). By default
the load is applied by curved jaws: the rim particles within ±15° of the vertical diameter
move towards the centre at a constant rate (:func:`jaw_indices`); ``loading="platens"`` uses
two rigid walls instead.

History: ``axial_stress_mpa`` = P/(D t) (mean platen stress, compression positive),
``brazilian_stress_mpa`` = 2P/(πDt), ``axial_strain`` = platen closure / D.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import analysis
from ..config import THICKNESS
from . import loading as ld
from . import resume as rs
from .report import TestResult, base_summary, crack_summary

__all__ = ["cut_disc", "disc_diameter", "jaw_indices", "run_brazilian", "PLATEN_FRIC",
           "JAW_HALF_ANGLE_DEG"]

#: Platen friction when ``loading="platens"``. A disc between frictionless platens touches each
#: platen at one particle; any offset of the two contacts makes a couple that rolls the disc
#: away (the load then falls without a crack), so the platens hold the disc by friction.
PLATEN_FRIC = 0.5
#: Half-angle α of the loading arcs (curved jaws) of ``loading="jaws"``, degrees. A flat platen
#: loads one particle and crushes it locally first (measured: σt 3× too low, cracks under the
#: platen); the flattened-Brazilian analysis of Wang et al. (2004) needs 2α >= 19.5° for the
#: crack to start at the centre, and 2α = 30° is used here. For a load spread over 2α the centre
#: stress is 2P/(πDt)·sin 2α/(2α) (Hondros): 4.5 % below the point-load formula at α = 15°.
#: ``tensile_mpa`` is 2P/(πDt) as the issue and ISRM define it; ``tensile_hondros_mpa`` has the
#: arc factor.
JAW_HALF_ANGLE_DEG = 15.0


def jaw_indices(x, y, r, *, half_angle_deg: float = JAW_HALF_ANGLE_DEG):
    """Rim particles of the disc within ±half_angle of the top and of the bottom.

    Returns
    -------
    bottom, top : (K,) ndarray of int64
    """
    cx, cy = x.mean(), y.mean()
    rad = 0.5 * disc_diameter(x, y, r)
    dist = np.hypot(x - cx, y - cy) + r
    rim = dist >= rad - 2.0 * float(np.mean(r))
    ang = np.degrees(np.arctan2(np.abs(x - cx), np.abs(y - cy)))
    near = rim & (ang <= half_angle_deg)
    top = np.nonzero(near & (y > cy))[0]
    bottom = np.nonzero(near & (y < cy))[0]
    if top.size == 0 or bottom.size == 0:
        raise ValueError(f"no rim particle within {half_angle_deg} deg of the loading axis")
    return bottom, top


def cut_disc(specimen, *, diameter=None, center=None):
    """The disc of ``specimen`` made of the particles lying wholly inside a circle.

    Parameters
    ----------
    specimen : sim.Specimen
    diameter : float, m, optional
        Default: the smaller side of ``box``.
    center : (float, float), m, optional
        Default: the centre of ``box``.

    Returns
    -------
    disc : sim.Specimen
        Particles, bonds (re-indexed) and grain labels kept; grain polygons kept as they are;
        ``box`` = the disc's bounding box; ``meta["disc"]`` records the cut.
    """
    b = specimen.box
    d = float(min(b[1] - b[0], b[3] - b[2])) if diameter is None else float(diameter)
    cx, cy = ((0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3])) if center is None
              else (float(center[0]), float(center[1])))
    if not d > 0:
        raise ValueError(f"'diameter' = {diameter!r}, expected > 0 m")
    keep = np.hypot(specimen.x - cx, specimen.y - cy) + specimen.r <= 0.5 * d
    if keep.sum() < 10:
        raise ValueError(f"the disc of diameter {d} m holds {int(keep.sum())} particles, "
                         "expected at least 10")
    new = -np.ones(specimen.n_particles, np.int64)
    new[keep] = np.arange(int(keep.sum()))
    bk = keep[specimen.bond_i] & keep[specimen.bond_j]
    x, y, r = specimen.x[keep], specimen.y[keep], specimen.r[keep]
    box = np.array([(x - r).min(), (x + r).max(), (y - r).min(), (y + r).max()])
    meta = dict(specimen.meta)
    meta["disc"] = {"diameter_m": d, "center_m": [cx, cy], "source_particles": specimen.n_particles}
    return dataclasses.replace(
        specimen, x=x, y=y, r=r, mineral=specimen.mineral[keep], grain=specimen.grain[keep],
        bond_i=new[specimen.bond_i[bk]], bond_j=new[specimen.bond_j[bk]],
        bond_kind=specimen.bond_kind[bk], joint_nx=specimen.joint_nx[bk],
        joint_ny=specimen.joint_ny[bk], box=box, meta=meta).validate("disc")


def disc_diameter(x, y, r) -> float:
    """Diameter of the smallest centred circle enclosing the particles (about their centroid)."""
    cx, cy = x.mean(), y.mean()
    return float(2.0 * np.max(np.hypot(x - cx, y - cy) + r))


def run_brazilian(specimen, *, cut: bool = True, diameter=None,
                  strain_rate: float | None = None,
                  platen_velocity: float = ld.DEFAULT_PLATEN_VELOCITY,
                  post_peak: float | None = ld.DEFAULT_POST_PEAK, max_strain: float | None = None,
                  damping: float = 0.7, timestep_factor: float | None = ld.DEFAULT_TIMESTEP_FACTOR,
                  record_strain: float = 0.25 * ld.RECORD_STRAIN, ramp_records: int = 5,
                  limit_strain: float = 0.02, out=None, progress: bool = True,
                  figures: bool = True,
                  checkpoint_every: int = 0, loading: str = "jaws",
                  jaw_half_angle_deg: float = JAW_HALF_ANGLE_DEG,
                  platen_fric: float = PLATEN_FRIC, resume: bool = False,
                  sim_options=None) -> TestResult:
    """Brazilian test: diametral compression of a disc by curved jaws or rigid platens.

    Parameters
    ----------
    specimen : sim.Specimen
        Rectangular specimen (``cut=True``: the disc is cut from it) or a disc.
    cut : bool
    diameter : float, m, optional
        Disc diameter when cutting (default the smaller side).
    strain_rate : float, 1/s, optional
        Loading strain rate; default 2 ``platen_velocity`` / L (L the loaded length).
    platen_velocity : float, m/s
        Speed of each platen when ``strain_rate`` is not given (default
        :data:`sim.protocols.loading.DEFAULT_PLATEN_VELOCITY`).
    loading : {"jaws", "platens"}
        ``jaws``: the rim particles within ±``jaw_half_angle_deg`` of the vertical diameter
        move at prescribed velocity (curved jaws; load = reaction on the groups). ``platens``:
        two rigid walls with friction ``platen_fric``.
    jaw_half_angle_deg, platen_fric : float
    post_peak, max_strain, damping, timestep_factor, record_strain, ramp_records,
    limit_strain, out, progress, figures, checkpoint_every, sim_options :
        As in :func:`sim.protocols.ucs.run_ucs`.
    resume : bool
        Continue an interrupted test from ``out`` (as :func:`sim.protocols.ucs.run_ucs`): the
        engine state of the disc (platens or jaw velocities included) from ``checkpoint.npz``,
        the records from ``history.csv``, the record interval from ``summary.json``; the disc
        is cut again and the jaws or platen gap rebuilt from it. Give the same specimen and
        options (cut, loading, jaw angle and strain rate are checked).

    Returns
    -------
    result : TestResult
        ``summary["tensile_mpa"]`` = 2 P_max / (π D t), ``peak_load_n_per_m``, ``diameter_m``.

    Raises
    ------
    ValueError, FileNotFoundError
        Bad rate, stop rule or loading; with ``resume``, see
        :func:`sim.protocols.resume.load_partial`.
    """
    stop = ld.StopRule(post_peak=post_peak, max_strain=max_strain)
    disc = cut_disc(specimen, diameter=diameter) if cut else specimen.validate("specimen")
    disc, _ = ld.relieve_overlaps(disc)
    d = disc_diameter(disc.x, disc.y, disc.r)
    opts = dict(damping=damping, **(sim_options or {}))
    if timestep_factor is not None:
        opts["timestep_factor"] = timestep_factor
    if loading not in ("jaws", "platens"):
        raise ValueError(f"'loading' = {loading!r}, expected 'jaws' or 'platens'")
    if resume:
        prev = rs.load_partial(out, "brazilian", disc.n_particles, what="the disc")
        sim = prev.sim
    else:
        sim = ld.make_simulation(disc, **opts)
    if loading == "platens":
        lo, hi = (0, 1) if resume else ld.add_platens(sim, disc.box, axis=1, fric=platen_fric)
        h0 = float(disc.box[3]) - float(disc.box[2])      # the platens start on the box
    else:
        jb, jt = jaw_indices(disc.x, disc.y, disc.r, half_angle_deg=jaw_half_angle_deg)

        def jaw_gap(y):
            return float(y[jt].mean() - y[jb].mean())
        h0 = d
        g0 = jaw_gap(disc.y)
    strain_rate, v = ld.loading_rate(strain_rate, platen_velocity, h0)
    chunk, max_steps = ld.loop_steps(strain_rate, float(sim.dt), record_strain=record_strain,
                                     ramp_records=ramp_records, max_strain=max_strain,
                                     limit_strain=limit_strain, resumed=prev if resume else None)

    def on_chunk(k):
        f = min(1.0, (k + 1) / max(1, ramp_records))
        if loading == "platens":
            sim.set_wall_velocity(lo, 0.0, f * v)
            sim.set_wall_velocity(hi, 0.0, -f * v)
        else:
            sim.fix_velocity(jb, 0.0, f * v)
            sim.fix_velocity(jt, 0.0, -f * v)

    def record():
        if loading == "platens":
            p = ld.platen_force(sim, lo, hi)
            ea = (h0 - ld.platen_gap(sim, lo, hi)) / h0
        else:   # the disc pushes the top jaw up (+y) and the bottom jaw down
            p = 0.5 * (float(sim.group_force(jt)[1]) - float(sim.group_force(jb)[1]))
            ea = (g0 - jaw_gap(sim.y)) / h0
        c = ld.crack_tally(sim)
        ek, es = ld.energies(sim)
        return {"step": int(sim.step), "time_s": float(sim.time), "axial_strain": ea,
                "lateral_strain": math.nan, "volumetric_strain": math.nan,
                "axial_stress_mpa": p / (d * THICKNESS) / 1e6, "confining_stress_mpa": 0.0,
                **{f"cracks_{k}": c[k] for k in analysis.CRACK_KINDS},
                "cracks_total": c["total"], "kinetic_energy_j": ek, "strain_energy_j": es,
                "load_n_per_m": p,
                "brazilian_stress_mpa": 2.0 * p / (math.pi * d * THICKNESS) / 1e6}

    options = dict(strain_rate_per_s=strain_rate, platen_velocity_m_per_s=v,
                   post_peak=post_peak, max_strain=max_strain, damping=damping,
                   timestep_factor=timestep_factor, cut=cut, loading=loading,
                   jaw_half_angle_deg=jaw_half_angle_deg if loading == "jaws" else None,
                   platen_fric=platen_fric if loading == "platens" else None,
                   chunk_steps=chunk, max_steps=max_steps)
    if resume:
        rs.check_options(prev, options, ("cut", "loading", "jaw_half_angle_deg",
                                         "strain_rate_per_s"))
    loop = ld.LoadingLoop(sim=sim, record=record, chunk=chunk, max_steps=max_steps, stop=stop,
                          stress_key="brazilian_stress_mpa", on_chunk=on_chunk,
                          progress=progress, desc="brazilian",
                          checkpoint_every=checkpoint_every,
                          checkpoint=None if out is None else f"{out}/checkpoint.npz")

    def finish(figures=figures):
        hist = loop.history()
        cracks = ld.crack_frame(sim)
        summary = base_summary("brazilian", disc, loop, sim, options)
        summary["diameter_m"] = d
        if len(hist) > 2:
            load = hist["load_n_per_m"].to_numpy(float)
            summary["tensile_mpa"] = analysis.brazilian_strength(load, d, thickness=THICKNESS) / 1e6
            summary["peak_load_n_per_m"] = float(np.max(load))
            if loading == "jaws":
                a2 = 2.0 * math.radians(jaw_half_angle_deg)
                summary["tensile_hondros_mpa"] = summary["tensile_mpa"] * math.sin(a2) / a2
        summary.update(crack_summary(cracks))
        res = TestResult(summary=summary, history=hist, cracks=cracks, sim=sim, specimen=disc,
                         stress_column="brazilian_stress_mpa")
        if out is not None:
            res.write(out, figures=figures)
        return res

    if resume:
        rs.restore_loop(loop, prev)
    return ld.run_and_finish(loop, finish)
