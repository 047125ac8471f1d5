"""The loading loop every laboratory test runs: cycle, record, check the stop rule; a Ctrl-C
or a periodic checkpoint leaves the engine state and the partial results.
"""
from __future__ import annotations

import contextlib
import math
import os
import signal
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..analysis import is_post_peak
from ..errors import InstabilityError
from .outputs import HISTORY_COLUMNS
from .speed import DEFAULT_POST_PEAK

__all__ = ["loop_steps", "second_ctrl_c_waits", "StopRule", "LoadingLoop", "run_and_finish"]


def loop_steps(strain_rate, dt, *, record_strain, ramp_records, max_strain, limit_strain,
               resumed=None):
    """Steps between two records and the step limit of a strain-controlled loading loop.

    A record every ``record_strain`` of loading strain; the limit is the stop strain
    (``max_strain``, at most ``limit_strain``) plus the ramp's lag, and one record more.
    ``resumed`` (the state read back by :mod:`sim.protocols.resume`) keeps the interrupted
    run's ``chunk_steps`` and ``max_steps``.

    Returns
    -------
    chunk, max_steps : int

    Examples
    --------
    >>> loop_steps(1.0, 1e-6, record_strain=2e-5, ramp_records=5, max_strain=None,
    ...            limit_strain=0.01)
    (20, 10120)
    """
    if resumed is not None:
        return resumed.chunk_steps, resumed.max_steps
    chunk = max(1, int(round(record_strain / (strain_rate * dt))))
    stop_strain = max_strain if max_strain is not None else limit_strain
    max_steps = int(math.ceil((min(stop_strain, limit_strain) + ramp_records * record_strain)
                              / (strain_rate * dt))) + chunk
    return chunk, max_steps


@contextlib.contextmanager
def second_ctrl_c_waits():
    """Ignore Ctrl-C while the checkpoint and partial results of an interrupted test are
    written (a second Ctrl-C would leave them half-written)."""
    prev = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, prev)


@dataclass
class StopRule:
    """When a strain-controlled test ends.

    Attributes
    ----------
    post_peak : float or None
        Stop once the stress has fallen below this fraction of the peak (after the peak).
    max_strain : float or None
        Stop at this loading strain (elastic checks).
    min_peak_pa : float
        A peak below this stress does not count (start-up noise), default 1 MPa.
    require_cracks : bool
        A post-peak drop counts only once at least one bond has broken (a bonded specimen
        cannot soften without cracking; wave noise at the start of loading can).
    """

    post_peak: float | None = DEFAULT_POST_PEAK
    max_strain: float | None = None
    min_peak_pa: float = 1e6
    require_cracks: bool = True

    def __post_init__(self):
        if self.post_peak is None and self.max_strain is None:
            raise ValueError("give 'post_peak' or 'max_strain': the test would never stop")
        if self.post_peak is not None and not 0.0 < self.post_peak < 1.0:
            raise ValueError(f"'post_peak' = {self.post_peak}, expected in (0, 1)")
        if self.max_strain is not None and not self.max_strain > 0:
            raise ValueError(f"'max_strain' = {self.max_strain}, expected > 0")

    def reason(self, strain, stress, n_cracks=None):
        """``"post_peak"``, ``"max_strain"`` or None."""
        if self.max_strain is not None and strain[-1] >= self.max_strain:
            return "max_strain"
        if self.require_cracks and n_cracks is not None and n_cracks <= 0:
            return None
        if self.post_peak is not None and is_post_peak(stress, fraction=self.post_peak,
                                                       min_peak=self.min_peak_pa):
            return "post_peak"
        return None


@dataclass
class LoadingLoop:
    """Cycle, record, check the stop rule; Ctrl-C leaves a checkpoint and partial outputs.

    Attributes
    ----------
    sim : Simulation
    record : callable
        ``record() -> dict`` one history row (keys of :data:`HISTORY_COLUMNS` and more).
    chunk : int
        Steps between records.
    max_steps : int
        Safety limit on the number of loading steps.
    stop : StopRule
    stress_key, strain_key : str
        History columns the stop rule looks at (stress in MPa).
    on_chunk : callable, optional
        Called before each chunk with the chunk index (velocity ramps, servo updates); it
        should multiply the loading speed by ``loop.factor``.
    speed : AdaptiveSpeed, optional
        Adaptive loading speed: before each chunk ``factor = speed.update(rows)`` and the
        chunk is ``chunk / factor`` steps (records stay equally spaced in strain).
    checkpoint : path, optional
        Where ``sim.save`` writes on Ctrl-C (and every ``checkpoint_every`` records).
    on_checkpoint : callable, optional
        Called after each periodic checkpoint; :func:`run_and_finish` sets it to write the
        partial results there (so that a run killed without Ctrl-C leaves them).
    progress : bool
        tqdm progress bar on stderr.
    """

    sim: object
    record: object
    chunk: int
    max_steps: int
    stop: StopRule
    stress_key: str = "axial_stress_mpa"
    strain_key: str = "axial_strain"
    on_chunk: object = None
    checkpoint: object = None
    checkpoint_every: int = 0
    on_checkpoint: object = None
    speed: object = None
    factor: float = 1.0
    progress: bool = True
    desc: str = "loading"
    rows: list = field(default_factory=list)
    stop_reason: str = ""
    engine_error: str = ""
    interrupted: bool = False
    wall_s: float = 0.0
    steps: int = 0

    def history(self) -> pd.DataFrame:
        """Recorded rows as a DataFrame, :data:`HISTORY_COLUMNS` first."""
        h = pd.DataFrame(self.rows)
        for c in HISTORY_COLUMNS:
            if c not in h:
                h[c] = pd.Series(np.nan, index=h.index, dtype=float)
        rest = [c for c in h.columns if c not in HISTORY_COLUMNS]
        return h[list(HISTORY_COLUMNS) + rest]

    def save_checkpoint(self):
        if self.checkpoint is not None:
            os.makedirs(os.path.dirname(os.path.abspath(self.checkpoint)), exist_ok=True)
            self.sim.save(self.checkpoint)

    def run(self):
        """Run until the stop rule fires, ``max_steps`` pass, or Ctrl-C (re-raised after the
        checkpoint is written: the caller writes the partial outputs)."""
        bar = None
        if self.progress:
            from tqdm import tqdm
            bar = tqdm(total=self.max_steps, desc=self.desc, unit="step", leave=False,
                       dynamic_ncols=True, mininterval=0.5)
        t0, wall_before = time.perf_counter(), self.wall_s
        strain, stress = [], []
        if not self.rows:
            self.rows.append(self.record())
        strain.extend(r[self.strain_key] for r in self.rows)
        stress.extend(r[self.stress_key] * 1e6 for r in self.rows)
        k = len(self.rows) - 1          # chunks done (> 0 when resuming)
        try:
            while self.steps < self.max_steps:
                if self.speed is not None:
                    self.factor = float(self.speed.update(self.rows))
                if self.on_chunk is not None:
                    self.on_chunk(k)
                n = min(max(1, int(round(self.chunk / self.factor))),
                        self.max_steps - self.steps)
                self.sim.cycle(n)
                self.steps += n
                row = self.record()
                self.rows.append(row)
                strain.append(row[self.strain_key])
                stress.append(row[self.stress_key] * 1e6)
                k += 1
                if bar is not None:
                    bar.update(n)
                    bar.set_postfix_str(f"{self.stress_key}={row[self.stress_key]:.1f} "
                                        f"peak={max(stress) / 1e6:.1f} "
                                        f"{self.strain_key}={row[self.strain_key]:.3e} "
                                        f"speed=x{self.factor:.2f}")
                if self.checkpoint_every and k % self.checkpoint_every == 0:
                    self.save_checkpoint()
                    if self.on_checkpoint is not None:
                        self.wall_s = wall_before + time.perf_counter() - t0
                        self.on_checkpoint()
                why = self.stop.reason(strain, stress, row.get("cracks_total"))
                if why:
                    self.stop_reason = why
                    break
            else:
                self.stop_reason = "max_steps"
        except InstabilityError as exc:
            # after the peak the test has given its answer (peak, E, CI, CD): an engine
            # instability among the fragments ends it like the post-peak rule, and is reported
            ip = int(np.argmax(stress))
            if ip < len(stress) - 1 and stress[-1] < 0.98 * stress[ip] \
                    and self.rows[-1].get("cracks_total", 1) > 0:
                self.stop_reason = "instability_after_peak"
                self.engine_error = str(exc)
            else:
                raise
        except KeyboardInterrupt:
            self.interrupted = True
            self.stop_reason = "interrupted"
            with second_ctrl_c_waits():
                self.save_checkpoint()
            raise
        finally:
            self.wall_s = wall_before + time.perf_counter() - t0
            if bar is not None:
                bar.close()
        return self


def run_and_finish(loop, finish):
    """Run ``loop`` and return ``finish()``; on Ctrl-C call ``finish()`` (partial outputs) first.

    Parameters
    ----------
    loop : LoadingLoop
    finish : callable
        ``finish(figures=...)`` builds (and, with ``out``, writes) the test's result from what
        was recorded. With periodic checkpoints (``loop.checkpoint_every``) it is also called
        after each of them with ``figures=False``: the partial history and summary (status
        ``running``) lie beside every checkpoint, so a run killed without Ctrl-C (SIGKILL, power
        loss) leaves results, and the test can be resumed (:mod:`sim.protocols.resume`).

    Returns
    -------
    result : TestResult

    Raises
    ------
    KeyboardInterrupt
        Re-raised after ``finish()`` has written the partial results.
    """
    if loop.checkpoint_every and loop.checkpoint is not None and loop.on_checkpoint is None:
        loop.on_checkpoint = lambda: finish(figures=False)
    try:
        loop.run()
    except KeyboardInterrupt:
        finish()
        raise
    return finish()
