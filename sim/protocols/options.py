"""The options every laboratory test shares (:class:`TestOptions`).

Each test adds its own boundary-condition options (the UCS's adaptive speed, the tension
grips, the Brazilian disc and jaws, the biaxial confinement: the fields of its protocol class
in :mod:`sim.protocols.registry`). :func:`split_options` sorts a flat keyword set into the two.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from .. import config
from .speed import DEFAULT_POST_PEAK, DEFAULT_TIMESTEP_FACTOR

__all__ = ["TestOptions", "split_options"]


@dataclass(frozen=True)
class TestOptions:
    """Keywords shared by every laboratory test (SI units).

    Attributes
    ----------
    out : path, optional
        Results directory: ``summary.json``, ``history.csv``, ``cracks.csv``, figures, and
        ``checkpoint.npz`` on Ctrl-C. None: nothing is written.
    strain_rate : float, 1/s, optional
        Loading strain rate; default 2 ``platen_velocity`` / L (L the loaded length).
    platen_velocity : float, m/s, optional
        Speed of each platen (grip, jaw) when ``strain_rate`` is not given. Default: the
        test's (:data:`sim.protocols.speed.DEFAULT_PLATEN_VELOCITY`, 0.0125 m/s; the adaptive
        UCS: the size-aware base speed of :func:`sim.protocols.speed.adaptive_speeds`). Reached
        after a linear ramp over the first ``ramp_records`` records.
    post_peak : float or None
        Stop when the stress has fallen below this fraction of the peak (default 0.8).
    max_strain : float or None
        Stop at this loading strain instead (elastic checks).
    damping : float
        Local damping α of the engine (default :data:`sim.config.DAMPING`).
    timestep_factor : float or None
        Safety factor on the critical time step (default
        :data:`sim.protocols.speed.DEFAULT_TIMESTEP_FACTOR`; None: the engine's).
    record_strain : float, optional
        Loading strain between two history records (default: the test's).
    ramp_records : int
        Records over which the speed ramps up linearly from 0.
    limit_strain : float, optional
        Safety stop at this loading strain (default: the test's).
    progress : bool
        tqdm progress bar on stderr.
    figures : bool
        Also draw the figures when writing ``out``.
    checkpoint_every : int
        Also write ``checkpoint.npz`` and the partial results (status ``running``) every this
        many records (0: only on Ctrl-C).
    resume : bool
        Continue an interrupted test from ``out`` (:mod:`sim.protocols.resume`); give the same
        specimen and options.
    sim_options : dict, optional
        More keyword options of the engine's :class:`~sim.simulation.Simulation`.
    """

    __test__ = False   # not a pytest class

    out: object = None
    strain_rate: float | None = None
    platen_velocity: float | None = None
    post_peak: float | None = DEFAULT_POST_PEAK
    max_strain: float | None = None
    damping: float = config.DAMPING
    timestep_factor: float | None = DEFAULT_TIMESTEP_FACTOR
    record_strain: float | None = None
    ramp_records: int = 5
    limit_strain: float | None = None
    progress: bool = True
    figures: bool = True
    checkpoint_every: int = 0
    resume: bool = False
    sim_options: dict | None = None

    def __post_init__(self):
        for name in ("strain_rate", "platen_velocity", "record_strain", "limit_strain"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)
                                      and v > 0):
                raise ValueError(f"'{name}' = {v!r}, expected a positive number or None")
        if not (isinstance(self.ramp_records, int) and self.ramp_records >= 1):
            raise ValueError(f"'ramp_records' = {self.ramp_records!r}, expected an integer >= 1")
        if not (isinstance(self.checkpoint_every, int) and self.checkpoint_every >= 0):
            raise ValueError(f"'checkpoint_every' = {self.checkpoint_every!r}, expected an "
                             "integer >= 0")
        if self.resume and self.out is None:
            raise ValueError("'resume' needs 'out' (the interrupted run's results directory)")

    def engine(self) -> dict:
        """Keyword options of the engine's Simulation."""
        opts = dict(damping=self.damping, **(self.sim_options or {}))
        if self.timestep_factor is not None:
            opts["timestep_factor"] = self.timestep_factor
        return opts

    def replace(self, **changes) -> "TestOptions":
        """A copy with ``changes``."""
        return dataclasses.replace(self, **changes)


#: Names of the shared options.
SHARED = tuple(f.name for f in dataclasses.fields(TestOptions))


def split_options(protocol_cls, options: dict, base: TestOptions | None = None):
    """Sort keyword ``options`` into :class:`TestOptions` and the test's own options.

    Parameters
    ----------
    protocol_cls : type
        The test's protocol class (its dataclass fields are its own options).
    options : dict
    base : TestOptions, optional
        Shared options that ``options`` change (default: the defaults).

    Returns
    -------
    shared : TestOptions
    own : dict

    Raises
    ------
    ValueError
        A keyword is neither shared nor the test's (names the valid ones).
    """
    own_names = {f.name for f in dataclasses.fields(protocol_cls)}
    unknown = [k for k in options if k not in SHARED and k not in own_names]
    if unknown:
        raise ValueError(f"{protocol_cls.name} test: unknown option {unknown[0]!r}; expected one "
                         f"of {', '.join(sorted(set(SHARED) | own_names))}")
    changes = {k: v for k, v in options.items() if k in SHARED}
    shared = TestOptions(**changes) if base is None else base.replace(**changes)
    return shared, {k: v for k, v in options.items() if k in own_names}
