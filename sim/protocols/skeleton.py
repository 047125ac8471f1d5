"""The one loading skeleton of the laboratory tests (:func:`run_loading`).

Every test runs the same steps: make the specimen ready (:meth:`Protocol.prepare`), build the
engine or read an interrupted run back (:meth:`Protocol.start`), put its boundary conditions and
readings on it (:meth:`Protocol.rig`, a :class:`Rig`), load at a strain rate with a start-up
ramp and the test's speed rule, record every ``record_strain``, stop on the stop rule, and
write ``summary.json``, ``history.csv``, ``cracks.csv`` and figures. A test is a
:class:`Protocol` subclass: a dataclass whose fields are its own options (the shared ones are
:class:`~sim.protocols.options.TestOptions`).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Callable, ClassVar

from ..hole_damage import hole_damage_summary
from . import resume as rs
from .loop import LoadingLoop, StopRule, loop_steps, run_and_finish
from .options import TestOptions
from .report import TestResult, base_summary, crack_summary
from .representative import representativeness
from .rig import crack_frame, crack_tally, energies, make_simulation, relieve_overlaps
from .speed import DEFAULT_PLATEN_VELOCITY, loading_rate

__all__ = ["Rig", "Protocol", "RepresentativenessWarning", "run_loading"]

#: Shared options that must match when a test resumes.
RESUME_KEYS = ("strain_rate_per_s", "platen_velocity_m_per_s", "post_peak", "max_strain",
               "damping", "timestep_factor", "record_strain")


class RepresentativenessWarning(UserWarning):
    """The specimen breaks a rule of :mod:`sim.protocols.representative`."""


@dataclass
class Rig:
    """A test's boundary conditions and readings on one engine (what :meth:`Protocol.rig`
    returns).

    Attributes
    ----------
    length : float, m
        Loaded length (the strain rate is 2 v / length).
    drive : callable
        ``drive(v)``: move the platens, grips or jaws at ``v`` m/s each for the next chunk.
    record : callable
        ``record() -> dict``: the test's entries of one history row (the skeleton adds step,
        time, cracks, energies and the platen speed).
    summarize : callable
        ``summarize(history, cracks) -> dict``: the test's numbers.
    options : dict
        The test's own options for ``summary.json``.
    velocity : float, m/s, optional
        The test's default speed (when neither a strain rate nor a speed is given).
    speed : AdaptiveSpeed, optional
        Speed rule (a factor on the speed before each chunk).
    min_peak_pa : float
        A peak below this stress does not end the test.
    finish : callable, optional
        ``finish(summary)``: last changes to the summary (e.g. a first stage's cost).
    dt : float, s, optional
        Time step the record interval is set from (default the engine's at the start of
        loading; the biaxial test keeps the one before its consolidation stage).
    """

    length: float
    drive: Callable
    record: Callable
    summarize: Callable
    options: dict = field(default_factory=dict)
    velocity: float | None = None
    speed: object = None
    min_peak_pa: float = 1e6
    finish: Callable | None = None
    dt: float | None = None


class Protocol:
    """Base of the laboratory tests (subclasses are dataclasses of their own options).

    Class attributes: ``name`` (registry key), ``label`` (how messages name the test),
    ``help`` (one line), ``record_strain`` and ``limit_strain`` (defaults of the shared
    options), ``stress_key``/``strain_key`` (history columns of the stop rule, progress bar
    and curve), ``peak`` (summary key of the peak stress) and ``resume_keys`` (own options
    that must match on resume).
    """

    name: ClassVar[str] = ""
    label: ClassVar[str] = ""
    help: ClassVar[str] = ""
    record_strain: ClassVar[float] = 2e-5
    limit_strain: ClassVar[float] = 0.05
    stress_key: ClassVar[str] = "axial_stress_mpa"
    strain_key: ClassVar[str] = "axial_strain"
    peak: ClassVar[str] = "ucs_mpa"
    resume_keys: ClassVar[tuple] = ()

    def prepare(self, specimen):
        """The specimen as loaded: validated, initial overlaps relieved
        (:func:`sim.protocols.rig.relieve_overlaps`)."""
        return relieve_overlaps(specimen.validate("specimen"))[0]

    def start(self, loaded, opts: TestOptions):
        """``(sim, partial, context)``: a new engine, or the interrupted run read back from
        ``opts.out`` (:func:`sim.protocols.resume.load_partial`); ``context`` goes to
        :meth:`rig`."""
        if opts.resume:
            prev = rs.load_partial(opts.out, self.name, loaded.n_particles, what=self.what)
            return prev.sim, prev, None
        return make_simulation(loaded, **opts.engine()), None, None

    #: How messages name the loaded specimen.
    what: ClassVar[str] = "the specimen"

    def rig(self, loaded, sim, opts: TestOptions, resumed: bool, context) -> Rig:
        raise NotImplementedError


def run_loading(protocol: Protocol, specimen, opts: TestOptions) -> TestResult:
    """Run the laboratory test ``protocol`` on ``specimen`` with the shared options ``opts``.

    Returns
    -------
    result : TestResult
        ``summary`` (the content of ``summary.json``), ``history``, ``cracks``, ``sim``.

    Raises
    ------
    ValueError, FileNotFoundError
        Bad options; with ``resume``, see :func:`sim.protocols.resume.load_partial` (nothing is
        written). KeyboardInterrupt is re-raised after the checkpoint and the partial results
        are written; :class:`sim.errors.InstabilityError` before the peak propagates.
    """
    stop = StopRule(post_peak=opts.post_peak, max_strain=opts.max_strain)
    loaded = protocol.prepare(specimen)
    rep = representativeness(loaded)
    for w in rep["warnings"]:
        warnings.warn(f"{protocol.label} specimen not representative: {w}",
                      RepresentativenessWarning, stacklevel=3)
    sim, prev, context = protocol.start(loaded, opts)
    rig = protocol.rig(loaded, sim, opts, prev is not None, context)
    stop.min_peak_pa = rig.min_peak_pa
    if opts.platen_velocity is not None:
        v0 = opts.platen_velocity
    else:
        v0 = rig.velocity if rig.velocity is not None else DEFAULT_PLATEN_VELOCITY
    strain_rate, v = loading_rate(opts.strain_rate, v0, rig.length)
    record_strain = opts.record_strain or protocol.record_strain
    limit_strain = opts.limit_strain or protocol.limit_strain
    dt = float(sim.dt if rig.dt is None else rig.dt)
    chunk, max_steps = loop_steps(strain_rate, dt, record_strain=record_strain,
                                  ramp_records=opts.ramp_records, max_strain=opts.max_strain,
                                  limit_strain=limit_strain, resumed=prev)
    options = dict(strain_rate_per_s=strain_rate, platen_velocity_m_per_s=v,
                   post_peak=opts.post_peak, max_strain=opts.max_strain, damping=opts.damping,
                   timestep_factor=opts.timestep_factor, record_strain=record_strain,
                   ramp_records=opts.ramp_records, limit_strain=limit_strain, **rig.options,
                   chunk_steps=chunk, max_steps=max_steps)
    if prev is not None:
        rs.check_options(prev, options, protocol.resume_keys + RESUME_KEYS)
    speed_now = [0.0]

    def on_chunk(k):
        f = min(1.0, (k + 1) / max(1, opts.ramp_records)) * loop.factor
        speed_now[0] = f * v
        rig.drive(f * v)

    def record():
        row = {"step": int(sim.step), "time_s": float(sim.time)}
        row.update(rig.record())
        c = crack_tally(sim)
        ek, es = energies(sim)
        row.update({f"cracks_{k}": n for k, n in c.items() if k != "total"})
        row.update(cracks_total=c["total"], kinetic_energy_j=ek, strain_energy_j=es,
                   platen_velocity_m_per_s=speed_now[0])
        return row

    loop = LoadingLoop(sim=sim, record=record, chunk=chunk, max_steps=max_steps, stop=stop,
                       stress_key=protocol.stress_key, strain_key=protocol.strain_key,
                       on_chunk=on_chunk, progress=opts.progress, desc=protocol.name,
                       speed=rig.speed, checkpoint_every=opts.checkpoint_every,
                       checkpoint=None if opts.out is None else f"{opts.out}/checkpoint.npz")

    def finish(figures=opts.figures):
        hist = loop.history()
        cracks = crack_frame(sim)
        summary = base_summary(protocol.name, loaded, loop, sim, options)
        summary["representative"] = rep
        if len(hist) > 2:
            summary.update(rig.summarize(hist, cracks))
        summary.update(crack_summary(cracks))
        summary.update(hole_damage_summary(loaded, sim))   # Ch. 6 measures, holes only
        if rig.finish is not None:
            rig.finish(summary)
        res = TestResult(summary=summary, history=hist, cracks=cracks, sim=sim,
                         specimen=loaded, stress_column=protocol.stress_key,
                         strain_column=protocol.strain_key)
        if opts.out is not None:
            res.write(opts.out, figures=figures)
        return res

    if prev is not None:
        rs.restore_loop(loop, prev)
    return run_and_finish(loop, finish)

