"""Direct tension test: the particles of the two end groups (grips) are pulled apart.

The grips are the particles within ``grip_depth`` of the top and bottom faces of ``box``; their
velocities are prescribed (±v along y, no lateral motion). The tensile force is the mean of the
contact forces the specimen exerts on the two grips; σt = peak force / (width × t).

History (compression positive as everywhere): ``axial_stress_mpa`` and ``axial_strain`` are
negative in tension; ``tensile_stress_mpa`` and ``tensile_strain`` (gauge extension) are the
same quantities with tension positive, used for the stop rule and the figure.
"""
from __future__ import annotations

import numpy as np

from .. import analysis
from ..config import THICKNESS
from . import loading as ld
from . import resume as rs
from .report import TestResult, base_summary, crack_summary

__all__ = ["run_tension", "grip_indices", "GRIP_FRACTION"]

#: Depth of each grip as a fraction of the specimen height (at least two mean diameters).
GRIP_FRACTION = 0.1


def grip_indices(y, r, box, *, depth=None):
    """Particles of the bottom and top grips (within ``depth`` of the faces, m).

    ``depth`` defaults to max(GRIP_FRACTION × height, 2 mean diameters).
    """
    h = float(box[3] - box[2])
    d = max(GRIP_FRACTION * h, 4.0 * float(np.mean(r))) if depth is None else float(depth)
    bottom = np.nonzero(y - r <= box[2] + d)[0]
    top = np.nonzero(y + r >= box[3] - d)[0]
    if bottom.size == 0 or top.size == 0 or np.intersect1d(bottom, top).size:
        raise ValueError(f"grip depth {d} m leaves no free length between the grips")
    return bottom, top


def _group_fy(sim, idx):
    if hasattr(sim, "group_force"):
        return float(np.asarray(sim.group_force(idx), float)[1])
    return float(np.sum(np.asarray(sim.fy)[idx]))


def run_tension(specimen, *, strain_rate: float | None = None,
                platen_velocity: float = ld.DEFAULT_PLATEN_VELOCITY,
                post_peak: float | None = ld.DEFAULT_POST_PEAK, max_strain: float | None = None,
                grip_depth: float | None = None, damping: float = 0.7,
                timestep_factor: float | None = ld.DEFAULT_TIMESTEP_FACTOR,
                record_strain: float = 0.25 * ld.RECORD_STRAIN,
                ramp_records: int = 5, limit_strain: float = 0.01, out=None,
                progress: bool = True, figures: bool = True, checkpoint_every: int = 0,
                resume: bool = False, sim_options=None) -> TestResult:
    """Direct tension of ``specimen`` by pulled end groups.

    Parameters
    ----------
    specimen : sim.Specimen
    strain_rate : float, 1/s, optional
        Loading strain rate; default 2 ``platen_velocity`` / L (L the loaded length).
    platen_velocity : float, m/s
        Speed of each grip when ``strain_rate`` is not given (default
        :data:`sim.protocols.loading.DEFAULT_PLATEN_VELOCITY`).
    post_peak, max_strain : float or None
        Stop rule on the tensile stress (see :func:`sim.protocols.ucs.run_ucs`).
    grip_depth : float, m, optional
        Default :func:`grip_indices`.
    damping, timestep_factor, record_strain, ramp_records, limit_strain, out, progress,
    checkpoint_every, sim_options, figures :
        As in :func:`sim.protocols.ucs.run_ucs` (records are 4× denser: tension peaks early).
    resume : bool
        Continue an interrupted test from ``out`` (as :func:`sim.protocols.ucs.run_ucs`): the
        engine state (grips and their velocities included) from ``checkpoint.npz``, the records
        from ``history.csv``, the record interval from ``summary.json``; grips, gauge and grip
        length are rebuilt from the specimen. Give the same specimen and options (the grip
        depth and strain rate are checked).

    Returns
    -------
    result : TestResult
        ``summary["tensile_mpa"]`` = σt (positive), ``E_tension_gpa``, cracks and P_sim.

    Raises
    ------
    ValueError, FileNotFoundError
        Bad rate or stop rule; with ``resume``, see :func:`sim.protocols.resume.load_partial`.
    """
    stop = ld.StopRule(post_peak=post_peak, max_strain=max_strain)
    specimen, _ = ld.relieve_overlaps(specimen.validate("specimen"))
    opts = dict(damping=damping, **(sim_options or {}))
    if timestep_factor is not None:
        opts["timestep_factor"] = timestep_factor
    if resume:
        prev = rs.load_partial(out, "tension", specimen.n_particles)
        sim = prev.sim
    else:
        sim = ld.make_simulation(specimen, **opts)
    box = specimen.box
    x0, y0 = np.array(specimen.x, copy=True), np.array(specimen.y, copy=True)
    bottom, top = grip_indices(y0, specimen.r, box, depth=grip_depth)
    l0 = float(y0[top].mean() - y0[bottom].mean())
    w0 = float(box[1] - box[0])
    strain_rate, v = ld.loading_rate(strain_rate, platen_velocity, l0)
    free = np.setdiff1d(np.arange(x0.size), np.r_[bottom, top])
    gbox = np.array([box[0], box[1], (y0[bottom] + specimen.r[bottom]).max(),
                     (y0[top] - specimen.r[top]).min()])
    gauge = np.intersect1d(ld.gauge_indices(x0, y0, gbox, fraction=0.8), free)
    chunk, max_steps = ld.loop_steps(strain_rate, float(sim.dt), record_strain=record_strain,
                                     ramp_records=ramp_records, max_strain=max_strain,
                                     limit_strain=limit_strain, resumed=prev if resume else None)

    def on_chunk(k):
        f = min(1.0, (k + 1) / max(1, ramp_records))
        sim.fix_velocity(bottom, 0.0, -f * v)
        sim.fix_velocity(top, 0.0, f * v)

    def record():
        x, y = sim.x, sim.y
        lt = float(y[top].mean() - y[bottom].mean())
        et = (lt - l0) / l0
        gl, ga = ld.gauge_strains(x0, y0, x, y, gauge)
        force = 0.5 * (_group_fy(sim, bottom) - _group_fy(sim, top))   # tension positive
        st = force / (w0 * THICKNESS) / 1e6
        c = ld.crack_tally(sim)
        ek, es = ld.energies(sim)
        return {"step": int(sim.step), "time_s": float(sim.time), "axial_strain": -et,
                "lateral_strain": gl, "volumetric_strain": -et + gl,
                "axial_stress_mpa": -st, "confining_stress_mpa": 0.0,
                **{f"cracks_{k}": c[k] for k in analysis.CRACK_KINDS},
                "cracks_total": c["total"], "kinetic_energy_j": ek, "strain_energy_j": es,
                "tensile_strain": et, "tensile_stress_mpa": st, "gauge_axial_strain": ga,
                "gauge_lateral_strain": gl}

    options = dict(strain_rate_per_s=strain_rate, grip_velocity_m_per_s=v,
                   grip_depth_m=grip_depth, post_peak=post_peak, max_strain=max_strain,
                   damping=damping, timestep_factor=timestep_factor, chunk_steps=chunk,
                   max_steps=max_steps)
    if resume:
        rs.check_options(prev, options, ("grip_depth_m", "strain_rate_per_s"))
    loop = ld.LoadingLoop(sim=sim, record=record, chunk=chunk, max_steps=max_steps, stop=stop,
                          stress_key="tensile_stress_mpa", strain_key="tensile_strain",
                          on_chunk=on_chunk, progress=progress, desc="tension",
                          checkpoint_every=checkpoint_every,
                          checkpoint=None if out is None else f"{out}/checkpoint.npz")

    def finish(figures=figures):
        hist = loop.history()
        cracks = ld.crack_frame(sim)
        summary = base_summary("tension", specimen, loop, sim, options)
        if len(hist) > 2:
            st = hist["tensile_stress_mpa"].to_numpy(float) * 1e6
            ext = -hist["gauge_axial_strain"].to_numpy(float)
            ip = analysis.peak_index(st)
            summary.update({
                "tensile_mpa": float(st[ip]) / 1e6,
                "peak_tensile_strain": float(hist["tensile_strain"].iloc[ip]),
                "E_tension_gpa": analysis.young_modulus(ext, st) / 1e9,
                "grip_length_m": l0, "width_m": w0})
        summary.update(crack_summary(cracks))
        res = TestResult(summary=summary, history=hist, cracks=cracks, sim=sim,
                         specimen=specimen, stress_column="tensile_stress_mpa",
                         strain_column="tensile_strain")
        if out is not None:
            res.write(out, figures=figures)
        return res

    if resume:
        rs.restore_loop(loop, prev)
    return ld.run_and_finish(loop, finish)
