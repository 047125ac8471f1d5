"""Numba policy for :mod:`sim`: every kernel is compiled lazily with ``cache=True``.

Importing this module compiles nothing. The threading layer is set to OpenMP when it is
available (TBB start-up costs ~0.7 ms per ``prange`` on the 2-core machine; see STYLE.md §7).
Numba fixes the layer when it starts its threads (the first parallel call or
``numba.set_num_threads``): a program that does either before importing :mod:`sim` keeps
numba's own choice (TBB when installed), and the step loop then runs slower (a UCS at 5 k
particles on 2 threads lost about a third of its throughput that way); importing :mod:`sim`
then warns (:class:`ThreadingLayerWarning`).
"""
import os
import warnings

import numba


class ThreadingLayerWarning(RuntimeWarning):
    """Numba's threads started on another layer before :mod:`sim` could choose OpenMP."""


def _choose_layer():
    if "NUMBA_THREADING_LAYER" in os.environ:
        return
    numba.config.THREADING_LAYER = "omp"
    try:
        running = numba.threading_layer()
    except ValueError:              # threads not started yet: the choice above holds
        return
    if running != "omp":
        warnings.warn(f"numba's threads already run on the '{running}' layer (numba was used "
                      "before sim was imported); the step loop is fastest on 'omp': import sim "
                      "before calling numba.set_num_threads or a parallel function, or set "
                      "NUMBA_THREADING_LAYER", ThreadingLayerWarning, stacklevel=2)


_choose_layer()

# fastmath without "nnan"/"ninf": the instability checks must still see NaN and inf.
_FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}
_OPTS = dict(cache=True, nogil=True, fastmath=_FASTMATH, error_model="numpy")


def njit(*args, **kwargs):
    """``numba.njit`` with the house options (cache, nogil, fastmath, numpy error model)."""
    opts = dict(_OPTS)
    opts.update(kwargs)
    if args and callable(args[0]):
        return numba.njit(**opts)(args[0])
    return numba.njit(*args, **opts)


prange = numba.prange
