"""Numba policy for :mod:`sim`: every kernel is compiled lazily with ``cache=True``.

Importing this module compiles nothing. The threading layer is set to OpenMP when it is
available (TBB start-up costs ~0.7 ms per ``prange`` on the 2-core machine; see STYLE.md §7).
"""
import os

import numba

if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "omp"

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
