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
from dataclasses import dataclass

import numpy as np

from ..config import THICKNESS
from . import resume as rs
from .loop import second_ctrl_c_waits
from .options import TestOptions
from .outputs import write_results
from .report import base_summary
from .rig import add_platens, crack_frame, crack_tally, make_simulation, platen_force, platen_gap
from .skeleton import Protocol, Rig, run_loading
from .ucs import compression_rig

__all__ = ["Biaxial", "run_biaxial", "DEFAULT_CONFINEMENT"]

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
    return platen_gap(sim, bot, top, 1), platen_gap(sim, left, right, 0)


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
        write_results(out, summary=summary, cracks=crack_frame(sim))

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
            with second_ctrl_c_waits():
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


@dataclass
class Biaxial(Protocol):
    """Biaxial compression at confining stress ``confinement`` (Pa).

    Attributes
    ----------
    confinement : float, Pa
        σ3 held by the side-wall servos (default 20 MPa).
    consolidation_tol : float
        Relative tolerance of every wall stress at the end of stage 1.
    consolidation_steps : int
        Step limit of stage 1 (``consolidation_converged`` false in the summary if reached).
    """

    confinement: float = DEFAULT_CONFINEMENT
    consolidation_tol: float = 0.01
    consolidation_steps: int = 200_000

    name = "biaxial"
    label = "biaxial"
    help = "biaxial compression with servo-held confinement"
    record_strain = 2e-5
    limit_strain = 0.08
    peak = "ucs_mpa"
    resume_keys = ("confinement_mpa",)

    def _stage1_options(self, opts):
        return dict(confinement_mpa=self.confinement / 1e6,
                    consolidation_tol=self.consolidation_tol,
                    consolidation_max_steps=int(self.consolidation_steps),
                    damping=opts.damping, timestep_factor=opts.timestep_factor)

    def start(self, loaded, opts: TestOptions):
        """Stage 1 (consolidation), or what an interrupted run left: a run stopped in stage 1
        continues it, a run stopped in stage 2 is read back with its consolidated state."""
        if not (self.confinement > 0 and math.isfinite(self.confinement)):
            raise ValueError(f"'confinement' = {self.confinement!r}, expected a positive "
                             "stress (Pa)")
        out = opts.out
        stage1 = self._stage1_options(opts)
        part1 = _resume_stage1(out, loaded, stage1) if opts.resume else None
        if opts.resume and part1 is None:           # stopped in stage 2
            prev = rs.load_partial(out, "biaxial", loaded.n_particles, also=(CONSOLIDATED,))
            start = rs.load_state(prev.paths[CONSOLIDATED], loaded.n_particles)
            if int(start.step) != int(prev.rows[0]["step"]):
                raise ValueError(f"cannot resume: {prev.paths[CONSOLIDATED]} is at step "
                                 f"{start.step}, expected {int(prev.rows[0]['step'])} (the "
                                 f"first record of {prev.paths['history.csv']}): not the "
                                 "same run")
            s1 = prev.summary
            seconds = float(s1["consolidation_s"])
            prev.wall_s -= seconds                  # the summary's wall time includes stage 1
            return prev.sim, prev, dict(
                walls=(0, 1, 2, 3), start=start, steps1=int(s1["consolidation_steps"]),
                converged=bool(s1["consolidation_converged"]), seconds=seconds, dt=None)
        if part1 is None:
            sim = make_simulation(loaded, **opts.engine())
            walls = (*add_platens(sim, loaded.box, axis=1, fric=0.0),
                     *add_platens(sim, loaded.box, axis=0, fric=0.0))
            dt, done, seconds = float(sim.dt), 0, 0.0
        else:                                       # stopped in stage 1: continue it
            sim, done, seconds, dt = part1
            walls = (0, 1, 2, 3)
        steps1, ok, seconds = _stage1(
            loaded, sim, walls, self.confinement, stage1, out=out, tol=self.consolidation_tol,
            max_steps=self.consolidation_steps, checkpoint_every=opts.checkpoint_every, dt0=dt,
            steps=done, seconds=seconds, progress=opts.progress)
        sim.clear_servo(walls[0])
        sim.clear_servo(walls[1])
        if out is not None:
            sim.save(os.path.join(out, CONSOLIDATED))
        return sim, None, dict(walls=walls, start=sim, steps1=steps1, converged=ok,
                               seconds=seconds, dt=dt)

    def rig(self, loaded, sim, opts: TestOptions, resumed: bool, ctx) -> Rig:
        bot, top, left, right = walls = ctx["walls"]
        start = ctx["start"]
        confinement = self.confinement
        h0, w0 = _sizes(start, walls)             # strains from the consolidated state
        x0, y0 = np.array(start.x, copy=True), np.array(start.y, copy=True)
        box = np.array([start.wall_position(left)[0], start.wall_position(right)[0],
                        start.wall_position(bot)[1], start.wall_position(top)[1]])
        read, summarize = compression_rig(loaded, x0, y0, box)
        c0 = crack_tally(start)["total"]

        def drive(v):
            sim.set_wall_velocity(bot, 0.0, v)
            sim.set_wall_velocity(top, 0.0, -v)
            h, _ = _sizes(sim, walls)
            sim.set_servo(left, confinement, h)
            sim.set_servo(right, confinement, h)

        def record():
            h, w = _sizes(sim, walls)
            ea, el = (h0 - h) / h0, (w0 - w) / w0
            s1 = platen_force(sim, bot, top, 1) / (w * THICKNESS)
            s3 = platen_force(sim, left, right, 0) / (h * THICKNESS)
            g = read(sim)
            g.pop("side_lateral_strain")          # the servo walls hold the sides
            return {"axial_strain": ea, "lateral_strain": el, "volumetric_strain": ea + el,
                    "axial_stress_mpa": s1 / 1e6, "confining_stress_mpa": s3 / 1e6,
                    "deviatoric_stress_mpa": (s1 - s3) / 1e6, **g,
                    "cracks_loading": crack_tally(sim)["total"] - c0}

        def summary_numbers(hist, cracks):
            dev = summarize(hist, cracks, "deviatoric_stress_mpa", opts.ramp_records)
            dev["deviatoric_peak_mpa"] = dev["ucs_mpa"]
            dev["ucs_mpa"] = float(np.max(hist["axial_stress_mpa"].to_numpy(float)))
            dev["stress_measure"] = ("ucs_mpa: peak axial stress sigma1; E, nu, ci_mpa, "
                                     "cd_mpa on the deviatoric stress sigma1 - sigma3")
            return dev

        def finish(summary):
            summary.update({"confining_mpa": confinement / 1e6,
                            "consolidation_steps": ctx["steps1"],
                            "consolidation_converged": ctx["converged"],
                            "consolidation_s": ctx["seconds"]})
            summary["steps"] += ctx["steps1"]
            summary["wall_s"] += ctx["seconds"]
            if summary["wall_s"] > 0:
                summary["particle_steps_per_s"] = (loaded.n_particles * summary["steps"]
                                                   / summary["wall_s"])

        stage1 = self._stage1_options(opts)
        return Rig(length=h0, drive=drive, record=record, summarize=summary_numbers,
                   min_peak_pa=max(1e6, confinement), finish=finish, dt=ctx["dt"],
                   options={k: stage1[k] for k in ("confinement_mpa", "consolidation_tol",
                                                   "consolidation_max_steps")})


def run_biaxial(specimen, *, confinement: float = DEFAULT_CONFINEMENT,
                consolidation_tol: float = 0.01, consolidation_steps: int = 200_000,
                **options):
    """Biaxial compression of ``specimen`` at confining stress ``confinement`` (Pa).

    Parameters
    ----------
    specimen : sim.Specimen
    confinement, consolidation_tol, consolidation_steps :
        See :class:`Biaxial`.
    **options
        The shared options (:class:`sim.protocols.options.TestOptions`). With ``out``, the
        state at the end of stage 1 is also saved as ``out/consolidated.npz`` (the reference of
        the strains). ``resume`` continues a test stopped in stage 2 from ``checkpoint.npz``,
        ``history.csv``, ``summary.json`` and ``consolidated.npz`` (stage 1 is not run again),
        and a test stopped in stage 1 (``summary.json`` with ``"stage": "consolidation"``,
        written on Ctrl-C and every ``checkpoint_every`` servo intervals of
        :data:`CONSOLIDATION_CHECK` steps) from its ``checkpoint.npz`` through stage 2.

    Returns
    -------
    result : TestResult
        ``ucs_mpa`` = peak σ1, ``deviatoric_peak_mpa``, E and ν on the deviatoric stress,
        ``consolidation_*``.
    """
    return run_loading(Biaxial(confinement=confinement, consolidation_tol=consolidation_tol,
                               consolidation_steps=consolidation_steps), specimen,
                       TestOptions(**options))
