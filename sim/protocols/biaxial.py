"""Biaxial (2D 'triaxial') compression with servo-held confinement.

Stage 1 (consolidation): four rigid frictionless walls on the faces of ``box``; every wall is
servo-controlled to the confining stress σ3 until all four wall stresses are within
``consolidation_tol`` of it. Stage 2 (shear): the side walls stay on the servo (their length is
updated to the current height every record); the top and bottom platens move at a constant
strain rate until the post-peak stop.

Reported (compression positive): ``ucs_mpa`` = peak axial stress σ1 (so that UCS and biaxial
runs share a column), ``deviatoric_peak_mpa`` = peak of σ1 − σ3, E and ν from the deviatoric
stress against the gauge strains, CI and CD as in UCS (on the deviatoric stress).
"""
from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from .. import analysis
from ..config import THICKNESS
from ..state import R
from . import gauges as gg
from . import loading as ld
from . import resume as rs
from .outputs import write_results
from .report import TestResult, base_summary, crack_summary
from .ucs import compression_summary

__all__ = ["run_biaxial", "DEFAULT_CONFINEMENT"]

#: Default confining stress, Pa (the thesis's triaxial tests: σ2 = σ3 = 20 MPa).
DEFAULT_CONFINEMENT = 20e6
#: File of ``out`` holding the engine state at the end of stage 1 (for ``resume``).
CONSOLIDATED = "consolidated.npz"
#: Steps between the servo updates and convergence checks of stage 1.
CONSOLIDATION_CHECK = 200


def _wall_stress(sim, k, axis, length):
    return abs(float(np.asarray(sim.wall_force(k), float)[axis])) / (length * THICKNESS)


def _sizes(sim, walls):
    """Height (platen gap) and width (side-wall gap) of the specimen, m."""
    bot, top, left, right = walls
    return ld.platen_gap(sim, bot, top, 1), ld.platen_gap(sim, left, right, 0)


def _consolidate(sim, walls, confinement, *, tol, max_steps, check=CONSOLIDATION_CHECK,
                 steps=0, on_check=None):
    """Stage 1: servo all four ``walls`` to ``confinement`` until every wall stress is within
    ``tol`` of it (or ``max_steps`` pass).

    Parameters
    ----------
    steps : int
        Stage-1 steps already done (a resumed run: the servos are in the engine state, and the
        first interval only completes the one that was interrupted, so the servo updates fall
        on the same steps as in an uninterrupted run).
    on_check : callable, optional
        ``on_check(steps, k, error, converged)`` after each check ``k`` (progress, periodic
        checkpoints); ``error`` is the largest relative wall-stress error.

    Returns
    -------
    steps : int
    converged : bool
    """
    bot, top, left, right = walls
    if steps == 0:
        h, w = _sizes(sim, walls)
        for k, length in ((bot, w), (top, w), (left, h), (right, h)):
            sim.set_servo(k, confinement, length)
    ok = False
    while steps < max_steps:
        n = min(check - steps % check, max_steps - steps)
        sim.cycle(n)
        steps += n
        h, w = _sizes(sim, walls)
        for k in (bot, top):
            sim.set_servo(k, confinement, w)
        for k in (left, right):
            sim.set_servo(k, confinement, h)
        errs = [abs(_wall_stress(sim, k, ax, ln) / confinement - 1.0)
                for k, ax, ln in ((bot, 1, w), (top, 1, w), (left, 0, h), (right, 0, h))]
        ok = max(errs) < tol
        if on_check is not None:
            on_check(steps, steps // check, max(errs), ok)
        if ok:
            break
    return steps, ok


def _stage1_summary(specimen, sim, status, steps, seconds, options, dt0):
    """``summary.json`` of a run stopped in stage 1 (``stage`` = ``"consolidation"``)."""
    from types import SimpleNamespace
    loop = SimpleNamespace(steps=steps, interrupted=status == "interrupted",
                           stop_reason="interrupted" if status == "interrupted" else "",
                           engine_error="", wall_s=seconds)
    summary = base_summary("biaxial", specimen, loop, sim, options)
    summary.update({"status": status, "stage": "consolidation", "confining_mpa":
                    options["confinement_mpa"], "consolidation_steps": steps,
                    "consolidation_converged": False, "consolidation_s": seconds,
                    "initial_dt_s": dt0})
    return summary


def _stage1(specimen, sim, walls, confinement, options, *, out, tol, max_steps,
            checkpoint_every, dt0, steps=0, seconds=0.0, progress=False):
    """Run stage 1 (from ``steps`` done in ``seconds``). With ``out``: on Ctrl-C, and every
    ``checkpoint_every`` checks, ``checkpoint.npz``, ``summary.json`` (stage
    ``consolidation``) and ``cracks.csv`` are written so that ``resume`` continues stage 1.

    Returns
    -------
    steps : int
    converged : bool
    seconds : float
        Wall time of stage 1 (earlier parts included).
    """
    t0 = time.perf_counter()

    def write(status, n):
        os.makedirs(out, exist_ok=True)
        sim.save(os.path.join(out, "checkpoint.npz"))
        summary = _stage1_summary(specimen, sim, status, n,
                                  seconds + time.perf_counter() - t0, options, dt0)
        write_results(out, summary=summary, cracks=ld.crack_frame(sim))

    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=max_steps, initial=steps, desc="consolidation", unit="step",
                   leave=False, dynamic_ncols=True, mininterval=0.5)

    def on_check(n, k, err, converged):
        if bar is not None:
            bar.update(n - bar.n)
            bar.set_postfix_str(f"wall stress error {err:.2%} (target {tol:.2%})")
        if out is not None and checkpoint_every and not converged \
                and k % checkpoint_every == 0:
            write("running", n)

    start = int(sim.step) - steps
    try:
        steps, ok = _consolidate(sim, walls, confinement, tol=tol, max_steps=max_steps,
                                 steps=steps, on_check=on_check)
    except KeyboardInterrupt:
        if out is not None:
            with ld.second_ctrl_c_waits():
                write("interrupted", int(sim.step) - start)
        raise
    finally:
        if bar is not None:
            bar.close()
    return steps, ok, seconds + time.perf_counter() - t0


def _resume_stage1(out, specimen, options):
    """The engine state, steps, seconds and initial time step of a run stopped in stage 1, or
    None when ``out/summary.json`` is not of one (then stage 2 resumes)."""
    spath = os.path.join(out, "summary.json")
    try:
        with open(spath, encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, ValueError):
        return None                      # load_partial names the problem
    if not (isinstance(summary, dict) and summary.get("test") == "biaxial"
            and summary.get("stage") == "consolidation"):
        return None
    cpath = os.path.join(out, "checkpoint.npz")
    if not os.path.exists(cpath):
        raise FileNotFoundError(f"cannot resume: missing {cpath}")
    old = summary.get("options", {})
    for k in ("confinement_mpa", "consolidation_tol", "consolidation_max_steps"):
        if old.get(k) != options[k]:
            raise ValueError(f"cannot resume: {spath} has options.{k} = {old.get(k)!r}, this "
                             f"run {options[k]!r}; give the interrupted run's options")
    sim = rs.load_state(cpath, specimen.n_particles)
    steps = int(summary["consolidation_steps"])
    return sim, steps, float(summary["consolidation_s"]), float(summary["initial_dt_s"])


def run_biaxial(specimen, *, confinement: float = DEFAULT_CONFINEMENT,
                strain_rate: float | None = None,
                platen_velocity: float = ld.DEFAULT_PLATEN_VELOCITY,
                post_peak: float | None = ld.DEFAULT_POST_PEAK, max_strain: float | None = None,
                damping: float = 0.7, timestep_factor: float | None = ld.DEFAULT_TIMESTEP_FACTOR,
                record_strain: float = ld.RECORD_STRAIN, ramp_records: int = 5,
                consolidation_tol: float = 0.01, consolidation_steps: int = 200_000,
                limit_strain: float = 0.08, out=None, progress: bool = True,
                figures: bool = True,
                checkpoint_every: int = 0, resume: bool = False,
                sim_options=None) -> TestResult:
    """Biaxial compression at confining stress ``confinement`` (Pa).

    Parameters
    ----------
    specimen : sim.Specimen
    confinement : float, Pa
        σ3 held by the side-wall servos (default 20 MPa).
    consolidation_tol : float
        Relative tolerance of every wall stress at the end of stage 1.
    consolidation_steps : int
        Step limit of stage 1 (a warning goes into the summary if it is reached).
    strain_rate, platen_velocity, post_peak, max_strain, damping, timestep_factor,
    record_strain, ramp_records, limit_strain, out, progress, figures, checkpoint_every,
    sim_options :
        As in :func:`sim.protocols.ucs.run_ucs`. With ``out``, the state at the end of stage 1
        is also saved as ``out/consolidated.npz`` (the reference of the strains, for
        ``resume``).
    resume : bool
        Continue a test interrupted in stage 2 from ``out`` (as
        :func:`sim.protocols.ucs.run_ucs`): the engine state (walls, servos and platen
        velocities included) from ``checkpoint.npz``, the records from ``history.csv``, the
        record interval and the stage-1 outcome from ``summary.json``, the reference positions
        and lengths from ``consolidated.npz``; stage 1 is not run again. Give the same
        specimen and options (confinement and strain rate are checked). A test stopped in
        stage 1 (``summary.json`` with ``"stage": "consolidation"``, written on Ctrl-C and
        every ``checkpoint_every`` servo intervals of :data:`CONSOLIDATION_CHECK` steps)
        continues stage 1 from ``checkpoint.npz`` and then runs stage 2 (confinement,
        ``consolidation_tol`` and ``consolidation_steps`` are checked).

    Returns
    -------
    result : TestResult

    Raises
    ------
    ValueError, FileNotFoundError
        Bad confinement, rate or stop rule; with ``resume``, see
        :func:`sim.protocols.resume.load_partial`.
    """
    if not (confinement > 0 and math.isfinite(confinement)):
        raise ValueError(f"'confinement' = {confinement!r}, expected a positive stress (Pa)")
    stop = ld.StopRule(post_peak=post_peak, max_strain=max_strain,
                       min_peak_pa=max(1e6, confinement))
    specimen, _ = ld.relieve_overlaps(specimen.validate("specimen"))
    opts = dict(damping=damping, **(sim_options or {}))
    if timestep_factor is not None:
        opts["timestep_factor"] = timestep_factor
    box = specimen.box
    stage1_opts = dict(confinement_mpa=confinement / 1e6, consolidation_tol=consolidation_tol,
                       consolidation_max_steps=int(consolidation_steps), damping=damping,
                       timestep_factor=timestep_factor)
    part1 = _resume_stage1(out, specimen, stage1_opts) if resume else None
    resume2 = resume and part1 is None          # stopped in stage 2
    if resume2:
        prev = rs.load_partial(out, "biaxial", specimen.n_particles, also=(CONSOLIDATED,))
        start = rs.load_state(prev.paths[CONSOLIDATED], specimen.n_particles)
        if int(start.step) != int(prev.rows[0]["step"]):
            raise ValueError(f"cannot resume: {prev.paths[CONSOLIDATED]} is at step "
                             f"{start.step}, expected {int(prev.rows[0]['step'])} (the first "
                             f"record of {prev.paths['history.csv']}): not the same run")
        sim, walls = prev.sim, (0, 1, 2, 3)
        dt = None                               # the loop's step counts come from prev
        stage1 = prev.summary
        steps1 = int(stage1["consolidation_steps"])
        ok = bool(stage1["consolidation_converged"])
        consolidation_s = float(stage1["consolidation_s"])
        prev.wall_s -= consolidation_s          # the summary's wall time includes stage 1
    else:
        if part1 is None:
            sim = ld.make_simulation(specimen, **opts)
            walls = (*ld.add_platens(sim, box, axis=1, fric=0.0),
                     *ld.add_platens(sim, box, axis=0, fric=0.0))
            dt = float(sim.dt)
            done, seconds = 0, 0.0
        else:                                   # stopped in stage 1: continue it
            sim, done, seconds, dt = part1
            walls = (0, 1, 2, 3)
        # ---- stage 1: isotropic consolidation by four servos
        steps1, ok, consolidation_s = _stage1(
            specimen, sim, walls, confinement, stage1_opts, out=out, tol=consolidation_tol,
            max_steps=consolidation_steps, checkpoint_every=checkpoint_every, dt0=dt,
            steps=done, seconds=seconds, progress=progress)
        sim.clear_servo(walls[0])
        sim.clear_servo(walls[1])
        start = sim
    bot, top, left, right = walls

    def sizes():
        return _sizes(sim, walls)

    # ---- stage 2: axial loading, side servos kept; strains from the consolidated state
    h0, w0 = _sizes(start, walls)
    strain_rate, v = ld.loading_rate(strain_rate, platen_velocity, h0)
    x0, y0 = np.array(start.x, copy=True), np.array(start.y, copy=True)
    cur_box = np.array([np.asarray(start.wall_position(left))[0],
                        np.asarray(start.wall_position(right))[0],
                        np.asarray(start.wall_position(bot))[1],
                        np.asarray(start.wall_position(top))[1]])
    gauge = gg.gauge_indices(x0, y0, cur_box)
    gmask = np.zeros(x0.size, bool)
    gmask[gauge] = True
    garea = gg.cell_area(x0, y0, gauge)
    ends = gg.end_indices(y0, np.asarray(start.state.pf[R]), cur_box)
    speed_now = [0.0]
    c_start = ld.crack_tally(start)
    chunk, max_steps = ld.loop_steps(strain_rate, dt, record_strain=record_strain,
                                     ramp_records=ramp_records, max_strain=max_strain,
                                     limit_strain=limit_strain, resumed=prev if resume2 else None)
    if out is not None and not resume2:
        sim.save(os.path.join(out, CONSOLIDATED))

    def on_chunk(k):
        f = min(1.0, (k + 1) / max(1, ramp_records))
        speed_now[0] = f * v
        sim.set_wall_velocity(bot, 0.0, f * v)
        sim.set_wall_velocity(top, 0.0, -f * v)
        h, _ = sizes()
        sim.set_servo(left, confinement, h)
        sim.set_servo(right, confinement, h)

    def record():
        h, w = sizes()
        ea = (h0 - h) / h0
        el = (w0 - w) / w0
        s1 = ld.platen_force(sim, bot, top, 1) / (w * THICKNESS)
        s3 = ld.platen_force(sim, left, right, 0) / (h * THICKNESS)
        gl, ga = gg.gauge_strains(x0, y0, sim.x, sim.y, gauge)
        gsx, gsy = gg.gauge_stress(sim, gmask, garea)
        c = ld.crack_tally(sim)
        ek, es = ld.energies(sim)
        return {"step": int(sim.step), "time_s": float(sim.time), "axial_strain": ea,
                "lateral_strain": el, "volumetric_strain": ea + el,
                "axial_stress_mpa": s1 / 1e6, "confining_stress_mpa": s3 / 1e6,
                **{f"cracks_{k}": c[k] for k in analysis.CRACK_KINDS},
                "cracks_total": c["total"], "kinetic_energy_j": ek, "strain_energy_j": es,
                "deviatoric_stress_mpa": (s1 - s3) / 1e6, "gauge_axial_strain": ga,
                "gauge_lateral_strain": gl, "gauge_stress_xx_mpa": gsx / 1e6,
                "gauge_stress_yy_mpa": gsy / 1e6,
                "end_axial_strain": gg.layer_strain(y0, sim.y, *ends),
                "platen_velocity_m_per_s": speed_now[0],
                "cracks_loading": c["total"] - c_start["total"]}

    options = dict(**stage1_opts, strain_rate_per_s=strain_rate,
                   platen_velocity_m_per_s=v, post_peak=post_peak, max_strain=max_strain,
                   chunk_steps=chunk, max_steps=max_steps)
    if resume2:
        rs.check_options(prev, options, ("confinement_mpa", "strain_rate_per_s"))
    loop = ld.LoadingLoop(sim=sim, record=record, chunk=chunk, max_steps=max_steps, stop=stop,
                          on_chunk=on_chunk, progress=progress, desc="biaxial",
                          checkpoint_every=checkpoint_every,
                          checkpoint=None if out is None else f"{out}/checkpoint.npz")

    def finish(figures=figures):
        hist = loop.history()
        cracks = ld.crack_frame(sim)
        summary = base_summary("biaxial", specimen, loop, sim, options)
        summary.update({"confining_mpa": confinement / 1e6, "consolidation_steps": steps1,
                        "consolidation_converged": ok, "consolidation_s": consolidation_s})
        summary["steps"] += steps1
        summary["wall_s"] += consolidation_s
        n = specimen.n_particles
        summary["particle_steps_per_s"] = n * summary["steps"] / summary["wall_s"]
        if len(hist) > 2:
            dev = compression_summary(hist, cracks=cracks, gauge_box=gg.gauge_box(cur_box),
                                      link=2.1 * float(specimen.r.max()),
                                      stress_col="deviatoric_stress_mpa",
                                      first_steady=ramp_records)
            s1 = hist["axial_stress_mpa"].to_numpy(float)
            summary.update(dev)
            summary["deviatoric_peak_mpa"] = dev["ucs_mpa"]
            summary["ucs_mpa"] = float(np.max(s1))
            summary["stress_measure"] = ("ucs_mpa: peak axial stress sigma1; E, nu, ci_mpa, "
                                         "cd_mpa on the deviatoric stress sigma1 - sigma3")
        summary.update(crack_summary(cracks))
        res = TestResult(summary=summary, history=hist, cracks=cracks, sim=sim,
                         specimen=specimen, stress_column="axial_stress_mpa")
        if out is not None:
            res.write(out, figures=figures)
        return res

    if resume2:
        rs.restore_loop(loop, prev)
    return ld.run_and_finish(loop, finish)
