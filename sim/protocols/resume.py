"""Resume an interrupted laboratory test from its results directory (``resume=True``,
``gbmsim ucs|tension|brazilian|biaxial SPEC --out DIR --resume``).

A test run with ``out`` leaves the engine state ``checkpoint.npz`` and the partial results
``history.csv``, ``cracks.csv`` and ``summary.json`` (status ``interrupted`` or ``running``) on
Ctrl-C and beside every periodic checkpoint (``checkpoint_every``, see
:func:`sim.protocols.loop.run_and_finish`). :func:`load_partial` reads and checks them before
anything is written; the protocol rebuilds what its loop derives from the specimen (platens,
grips, jaws, gauges, reference lengths) and :func:`restore_loop` puts the records, the step
count, the wall time and the state of the adaptive speed rule back into its
:class:`~sim.protocols.loop.LoadingLoop`, which then continues where the run stopped.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import pandas as pd

from .outputs import json_ready

__all__ = ["Partial", "PARTIAL_FILES", "TEST_LABELS", "load_partial", "load_state",
           "check_options", "restore_loop"]

#: Files every resumable test leaves in its results directory.
PARTIAL_FILES = ("checkpoint.npz", "history.csv", "summary.json")
#: How the messages name each test.
TEST_LABELS = {"ucs": "UCS", "tension": "tension", "brazilian": "Brazilian",
               "biaxial": "biaxial"}


@dataclass
class Partial:
    """What an interrupted test left in its results directory.

    Attributes
    ----------
    sim : Simulation
        The engine state of ``checkpoint.npz``.
    rows : list of dict
        The records of ``history.csv``.
    steps : int
        Loading steps between the first and the last record.
    wall_s : float
        Wall time so far (``summary.json``).
    chunk_steps, max_steps : int
        Steps between records and the step limit of the loop (``summary.json`` options).
    summary : dict
        ``summary.json``.
    paths : dict
        File name -> path of the files read.
    """

    sim: object
    rows: list
    steps: int
    wall_s: float
    chunk_steps: int
    max_steps: int
    summary: dict = field(default_factory=dict)
    paths: dict = field(default_factory=dict)


def load_state(path, n_particles: int, what: str = "the specimen"):
    """The engine state saved at ``path``, checked to hold ``n_particles`` particles.

    Raises
    ------
    ValueError
        The particle counts differ (names ``path``, both counts and ``what`` was expected).
    """
    from ..simulation import Simulation
    sim = Simulation.load(path)
    if sim.n_particles != n_particles:
        raise ValueError(f"cannot resume: {path} holds {sim.n_particles} particles, expected "
                         f"{n_particles} ({what}): not the same specimen")
    return sim


def _require(paths):
    missing = [p for p in paths if not os.path.exists(p)]
    if missing:
        raise FileNotFoundError(f"cannot resume: missing {', '.join(missing)}")


def load_partial(out, test: str, n_particles: int, *, also=(),
                 what: str = "the specimen") -> Partial:
    """Read and check what an interrupted ``test`` left in ``out``.

    Parameters
    ----------
    out : path
        The interrupted run's results directory.
    test : {"ucs", "tension", "brazilian", "biaxial"}
        The test that resumes (``summary.json`` must be of that test).
    n_particles : int
        Particles of the specimen that resumes (the checkpoint must hold as many).
    also : sequence of str
        More files the test needs (e.g. ``consolidated.npz`` of the biaxial test); their paths
        are in ``Partial.paths``.
    what : str
        How the messages name the specimen (``"the disc"``).

    Returns
    -------
    partial : Partial

    Raises
    ------
    FileNotFoundError
        A file is missing (named; the others are looked for once ``summary.json`` is found to
        be of an unfinished ``test``).
    ValueError
        No ``out``; ``summary.json`` of another test, of a run without a record interval or of a
        finished run; an empty history; a checkpoint with another particle count or behind the
        last record. Nothing is written.
    """
    if out is None:
        raise ValueError("'resume' needs 'out' (the interrupted run's results directory)")
    paths = {k: os.path.join(out, k) for k in PARTIAL_FILES}
    spath = paths["summary.json"]
    if not os.path.exists(spath):
        _require(paths.values())
    try:
        with open(spath, encoding="utf-8") as f:
            summary = json.load(f)
    except json.JSONDecodeError as exc:
        raise ValueError(f"cannot resume: {spath} is not JSON ({exc})") from None
    opts = summary.get("options", {}) if isinstance(summary, dict) else {}
    label = TEST_LABELS.get(test, test)
    if not isinstance(summary, dict) or summary.get("test") != test or "chunk_steps" not in opts:
        found = summary.get("test") if isinstance(summary, dict) else None
        raise ValueError(f"cannot resume: {spath} is not a resumable {label} run (test "
                         f"{found!r}, expected {test!r} with options.chunk_steps)")
    if summary.get("status") == "complete":
        raise ValueError(f"cannot resume: {spath} is a finished {label} run (stop_reason "
                         f"{summary.get('stop_reason')!r}); nothing to continue")
    paths.update({k: os.path.join(out, k) for k in also})
    _require(p for p in paths.values() if p != spath)
    sim = load_state(paths["checkpoint.npz"], n_particles, what)
    try:
        hist = pd.read_csv(paths["history.csv"])
    except pd.errors.EmptyDataError:
        hist = pd.DataFrame()
    if not len(hist) or "step" not in hist:
        raise ValueError(f"cannot resume: {paths['history.csv']} holds no records")
    rows = [{k: (v.item() if hasattr(v, "item") else v) for k, v in r.items()}
            for r in hist.to_dict("records")]
    if int(sim.step) < int(rows[-1]["step"]):
        raise ValueError(f"cannot resume: {paths['checkpoint.npz']} is at step {sim.step}, "
                         f"behind the last record of {paths['history.csv']} (step "
                         f"{int(rows[-1]['step'])})")
    return Partial(sim=sim, rows=rows, steps=int(rows[-1]["step"] - rows[0]["step"]),
                   wall_s=float(summary.get("wall_s") or 0.0),
                   chunk_steps=int(opts["chunk_steps"]), max_steps=int(opts["max_steps"]),
                   summary=summary, paths=paths)


def check_options(partial: Partial, options: dict, keys) -> None:
    """Raise ValueError when an option in ``keys`` differs from the interrupted run's.

    Values are compared as ``summary.json`` stores them (exact: JSON keeps every float).
    """
    old = partial.summary.get("options", {})
    for k in keys:
        new = json_ready(options.get(k))
        if old.get(k) != new:
            raise ValueError(f"cannot resume: {partial.paths['summary.json']} has "
                             f"options.{k} = {old.get(k)!r}, this run {new!r}; give the "
                             "interrupted run's options")


def restore_loop(loop, partial: Partial):
    """Put the records, step count and wall time of ``partial`` into ``loop``.

    The adaptive speed rule (``loop.speed``, its state: factor and largest tangent) is replayed
    over the records. A checkpoint taken between two records (Ctrl-C inside a chunk) adds one
    record at the resume point.

    Returns
    -------
    loop : LoadingLoop
    """
    loop.rows = partial.rows
    loop.steps, loop.wall_s = partial.steps, partial.wall_s
    if loop.speed is not None:
        for n in range(1, len(loop.rows)):
            loop.factor = float(loop.speed.update(loop.rows[:n]))
    if int(loop.sim.step) != int(loop.rows[-1]["step"]):     # checkpoint inside a chunk
        loop.steps += int(loop.sim.step) - int(loop.rows[-1]["step"])
        loop.rows.append(loop.record())
    return loop
