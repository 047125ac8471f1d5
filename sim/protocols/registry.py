"""The laboratory tests by name, and one entry point to run any of them.

``TESTS`` maps a test name to its protocol class (:class:`sim.protocols.skeleton.Protocol`); the
command line (``gbmsim TEST``), the ensembles, the calibration and ``gbmgen run`` all take their
list of tests from here. :func:`run_test` runs one::

    from sim.protocols.registry import run_test
    result = run_test("biaxial", specimen, out="res/bx", confinement=10e6, post_peak=0.7)

Keywords are the shared options (:class:`sim.protocols.options.TestOptions`) and the test's
own (the fields of its protocol class: ``adaptive`` for ``ucs``, ``grip_depth`` for
``tension``, ``cut``, ``diameter``, ``loading``, ``jaw_half_angle_deg``, ``platen_fric`` for
``brazilian``, ``confinement``, ``consolidation_tol``, ``consolidation_steps`` for
``biaxial``).
"""
from __future__ import annotations

from .biaxial import Biaxial
from .brazilian import Brazilian
from .options import TestOptions, split_options
from .skeleton import run_loading
from .tension import Tension
from .ucs import UCS

__all__ = ["TESTS", "test_names", "protocol", "run_test"]

#: Test name -> protocol class.
TESTS = {cls.name: cls for cls in (UCS, Tension, Brazilian, Biaxial)}


def test_names() -> tuple:
    """The names of the tests, in registry order."""
    return tuple(TESTS)


def protocol(name: str):
    """The protocol class of test ``name``.

    Raises
    ------
    ValueError
        Unknown test (names the valid ones).
    """
    try:
        return TESTS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown test {name!r}; expected one of {', '.join(TESTS)}") from None


def run_test(name: str, specimen, out=None, *, options: TestOptions | None = None, **kwargs):
    """Run the laboratory test ``name`` on ``specimen``.

    Parameters
    ----------
    name : {"ucs", "tension", "brazilian", "biaxial"}
    specimen : sim.Specimen
    out : path, optional
        Results directory (``summary.json``, ``history.csv``, ``cracks.csv``, figures).
    options : TestOptions, optional
        Shared options as one object (a sweep keeps one and varies a few keywords).
    **kwargs
        Shared options (:class:`~sim.protocols.options.TestOptions`; they override ``options``)
        and the test's own.

    Returns
    -------
    result : sim.protocols.report.TestResult

    Raises
    ------
    ValueError
        Unknown test or option, or a bad value (the message names it).
    """
    cls = protocol(name)
    if out is not None:
        kwargs["out"] = out
    shared, own = split_options(cls, kwargs, base=options)
    return run_loading(cls(**own), specimen, shared)
