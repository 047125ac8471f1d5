"""Uniaxial compression (UCS) test: rigid frictionless platens at ``box``, strain-controlled.

Measured (compression positive, report units in the names):

- axial stress = mean platen force / (initial width × t); axial strain from the platen gap;
- lateral strain from the side particles (one diameter deep at each face) and volumetric
  strain = axial + lateral (specimen scale; used for CD);
- gauge strains from an affine fit of the central half of the specimen (like strain gauges:
  platen contact compliance excluded; used for E and ν);
- cumulative cracks by kind, kinetic and strain energy.

Stops at ``post_peak`` × peak after the peak (default 0.8, as the thesis) or at ``max_strain``.
"""
from __future__ import annotations

import numpy as np

from .. import analysis
from ..config import THICKNESS
from . import gauges as gg
from . import loading as ld
from . import resume as rs
from .elastic import elastic_constants
from .report import TestResult, base_summary, crack_summary

__all__ = ["run_ucs", "compression_summary"]


def compression_summary(history, *, cracks=None, gauge_box=None, link=None,
                        stress_col="axial_stress_mpa", first_steady=0,
                        ci_fraction=analysis.CI_FRACTION) -> dict:
    """E and ν with their validity (:func:`sim.protocols.elastic.elastic_constants`), peak,
    CI and CD from a compression history (report units).

    Uses ``axial_strain`` (platen gap) for the peak strain, ``volumetric_strain`` for CD and
    ``cracks_total`` for CI.
    """
    s = history[stress_col].to_numpy(float) * 1e6
    ea = history["axial_strain"].to_numpy(float)
    ip = analysis.peak_index(s)
    out = elastic_constants(history, cracks, gauge_box=gauge_box, link=link,
                            stress_col=stress_col, first_steady=first_steady)
    out.update({
        "ucs_mpa": float(s[ip]) / 1e6,
        "ci_mpa": analysis.crack_initiation(s, history["cracks_total"].to_numpy(float),
                                            fraction=ci_fraction) / 1e6,
        "cd_mpa": analysis.crack_damage(s, history["volumetric_strain"].to_numpy(float)) / 1e6,
        "peak_axial_strain": float(ea[ip]),
        "ci_criterion": f"cumulative cracks >= max(1, ceil({ci_fraction} x count at peak))",
        "cd_criterion": "maximum of volumetric strain before the peak",
    })
    return out


def run_ucs(specimen, *, strain_rate: float | None = None,
            platen_velocity: float | None = None,
            post_peak: float | None = ld.DEFAULT_POST_PEAK, max_strain: float | None = None,
            damping: float = 0.7, timestep_factor: float | None = ld.DEFAULT_TIMESTEP_FACTOR,
            record_strain: float = ld.RECORD_STRAIN, ramp_records: int = 5,
            e_method: str = "tangent", limit_strain: float = 0.05, out=None,
            progress: bool = True, figures: bool = True, checkpoint_every: int = 0,
            adaptive: bool | dict | None = None, resume: bool = False,
            sim_options=None) -> TestResult:
    """Uniaxial compression of ``specimen`` between rigid frictionless platens.

    Parameters
    ----------
    specimen : sim.Specimen
    strain_rate : float, 1/s, optional
        Loading strain rate; default 2 ``platen_velocity`` / L (L the loaded length).
    platen_velocity : float, m/s, optional
        Speed of each platen when ``strain_rate`` is not given: the constant speed, or the
        base (slowest) speed of the adaptive rule. Default when adaptive: the size-aware
        base speed of :func:`sim.protocols.loading.adaptive_speeds` (0.00625 m/s up to 8 mm
        long, then a strain rate of 1.5625/s: 0.039 m/s at 50 mm, with the fast phase capped
        at 0.1 m/s); at constant speed
        :data:`sim.protocols.loading.DEFAULT_PLATEN_VELOCITY` (0.0125).
        The speed is reached after a linear ramp over the first ``ramp_records`` records.
    post_peak : float or None
        Stop when the stress falls below this fraction of the peak (default 0.8).
    max_strain : float or None
        Stop at this axial strain (elastic checks where nothing breaks).
    damping, timestep_factor : float
        Engine options: local damping α; safety factor on the critical step (default
        :data:`sim.protocols.loading.DEFAULT_TIMESTEP_FACTOR` = 0.6; None: the engine's).
    record_strain : float
        Axial strain between history records.
    e_method : {"tangent", "secant"}
    limit_strain : float
        Safety stop at this axial strain.
    out : path, optional
        Write the results there (and ``checkpoint.npz`` on Ctrl-C).
    progress : bool
        tqdm progress bar.
    figures : bool
        Also draw stress_strain.png and crack_map.png when writing ``out``.
    checkpoint_every : int
        Also checkpoint every this many records (0: only on Ctrl-C), with the partial
        ``history.csv``, ``cracks.csv`` and ``summary.json`` (status ``running``) beside it.
    adaptive : bool, optional
        Adaptive platen speed (:class:`sim.protocols.loading.AdaptiveSpeed`): up to
        0.1 m/s while elastic and crack-free (capped by a kinetic/strain energy check), the
        base speed while cracking, softening and after the peak. Default
        :data:`sim.protocols.loading.ADAPTIVE_DEFAULT` (True). A dict: adaptive, with these
        fields of :class:`~sim.protocols.loading.AdaptiveSpeed` changed (e.g. ``f_max``).
    resume : bool
        Continue an interrupted test from ``out``: the engine state from
        ``out/checkpoint.npz``, the records from ``out/history.csv`` and the step count and
        record interval from ``out/summary.json`` (written on Ctrl-C and beside every
        periodic checkpoint; :mod:`sim.protocols.resume`). Give the same specimen and options
        as the interrupted run. A checkpoint taken between two records (Ctrl-C inside a chunk)
        adds one record at the resume point.
    sim_options : dict, optional
        More keyword options for the engine's ``Simulation``.

    Returns
    -------
    result : TestResult
        ``summary`` has ``E_gpa, nu, ucs_mpa, ci_mpa, cd_mpa, cracks, P_sim, steps, wall_s,
        particle_steps_per_s`` (DESIGN.md §4) and more.

    Raises
    ------
    ValueError
        Bad rate or stop rule; with ``resume``, results of another test or specimen in ``out``
        (FileNotFoundError: a file missing). KeyboardInterrupt is re-raised after the
        checkpoint and the partial outputs are written.
    """
    stop = ld.StopRule(post_peak=post_peak, max_strain=max_strain)
    if adaptive is None:
        adaptive = ld.ADAPTIVE_DEFAULT
    specimen, _ = ld.relieve_overlaps(specimen.validate("specimen"))
    rule = dict(adaptive) if isinstance(adaptive, dict) else {}
    if platen_velocity is None:
        if adaptive and strain_rate is None:    # size-aware: cracking at a fixed strain rate
            platen_velocity, f_max = ld.adaptive_speeds(float(specimen.box[3] - specimen.box[2]))
            rule.setdefault("f_max", f_max)
        else:                                   # (unused when strain_rate is given)
            platen_velocity = ld.DEFAULT_PLATEN_VELOCITY
    opts = dict(damping=damping, **(sim_options or {}))
    if timestep_factor is not None:
        opts["timestep_factor"] = timestep_factor
    box = specimen.box
    if resume:
        prev = rs.load_partial(out, "ucs", specimen.n_particles)
        sim = prev.sim
        lo, hi = 0, 1
        x0, y0 = np.array(specimen.x, copy=True), np.array(specimen.y, copy=True)
    else:
        sim = ld.make_simulation(specimen, **opts)
        lo, hi = ld.add_platens(sim, box, axis=1, fric=0.0)
        x0, y0 = np.array(sim.x, copy=True), np.array(sim.y, copy=True)
    h0 = float(box[3]) - float(box[2])
    w0 = float(box[1] - box[0])
    strain_rate, v = ld.loading_rate(strain_rate, platen_velocity, h0)
    gauge = gg.gauge_indices(x0, y0, box)
    gmask = np.zeros(x0.size, bool)
    gmask[gauge] = True
    garea = gg.cell_area(x0, y0, gauge)
    left, right = gg.side_indices(x0, specimen.r, box)
    bottom, top = gg.end_indices(y0, specimen.r, box)
    speed_now = [0.0]
    chunk, max_steps = ld.loop_steps(strain_rate, float(sim.dt), record_strain=record_strain,
                                     ramp_records=ramp_records, max_strain=max_strain,
                                     limit_strain=limit_strain, resumed=prev if resume else None)

    speed = None
    if adaptive:
        speed = ld.AdaptiveSpeed(**rule)

    def on_chunk(k):
        f = min(1.0, (k + 1) / max(1, ramp_records)) * loop.factor
        speed_now[0] = f * v
        sim.set_wall_velocity(lo, 0.0, f * v)
        sim.set_wall_velocity(hi, 0.0, -f * v)

    def record():
        x, y = sim.x, sim.y
        ea = (h0 - ld.platen_gap(sim, lo, hi)) / h0
        el = gg.layer_strain(x0, x, left, right)
        gl, ga = gg.gauge_strains(x0, y0, x, y, gauge)
        gsx, gsy = gg.gauge_stress(sim, gmask, garea)
        c = ld.crack_tally(sim)
        ek, es = ld.energies(sim)
        return {"step": int(sim.step), "time_s": float(sim.time), "axial_strain": ea,
                "lateral_strain": el, "volumetric_strain": ea + el,
                "axial_stress_mpa": ld.platen_force(sim, lo, hi) / (w0 * THICKNESS) / 1e6,
                "confining_stress_mpa": 0.0,
                **{f"cracks_{k}": c[k] for k in analysis.CRACK_KINDS},
                "cracks_total": c["total"], "kinetic_energy_j": ek, "strain_energy_j": es,
                "gauge_axial_strain": ga, "gauge_lateral_strain": gl,
                "gauge_stress_xx_mpa": gsx / 1e6, "gauge_stress_yy_mpa": gsy / 1e6,
                "end_axial_strain": gg.layer_strain(y0, y, bottom, top),
                "platen_velocity_m_per_s": speed_now[0]}

    options = dict(strain_rate_per_s=strain_rate, platen_velocity_m_per_s=v,
                   post_peak=post_peak, max_strain=max_strain, damping=damping,
                   timestep_factor=timestep_factor, record_strain=record_strain,
                   e_method=e_method, chunk_steps=chunk, max_steps=max_steps,
                   adaptive=bool(adaptive),
                   adaptive_rule=None if speed is None else {
                       k: getattr(speed, k) for k in ("f_max", "crack_scale", "tan_fast",
                                                      "tan_slow", "peak_drop", "window",
                                                      "rise", "ke_ratio", "f_peak",
                                                      "tan_peak")})
    if resume:
        rs.check_options(prev, options, ("strain_rate_per_s", "platen_velocity_m_per_s",
                                         "adaptive", "adaptive_rule", "post_peak",
                                         "max_strain", "damping", "timestep_factor",
                                         "record_strain"))
    loop = ld.LoadingLoop(sim=sim, record=record, chunk=chunk, max_steps=max_steps, stop=stop,
                          on_chunk=on_chunk, progress=progress, desc="ucs", speed=speed,
                          checkpoint_every=checkpoint_every,
                          checkpoint=None if out is None else f"{out}/checkpoint.npz")

    def finish(figures=figures):
        hist = loop.history()
        cracks = ld.crack_frame(sim)
        summary = base_summary("ucs", specimen, loop, sim, options)
        if len(hist) > 2:
            summary.update(compression_summary(hist, cracks=cracks, gauge_box=gg.gauge_box(box),
                                               link=2.1 * float(specimen.r.max()),
                                               first_steady=ramp_records))
        summary.update(crack_summary(cracks))
        res = TestResult(summary=summary, history=hist, cracks=cracks, sim=sim,
                         specimen=specimen)
        if out is not None:
            res.write(out, figures=figures)
        return res

    if resume:
        rs.restore_loop(loop, prev)
    return ld.run_and_finish(loop, finish)
