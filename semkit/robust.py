"""Robust statistics on large pixel samples, to the last bit of NumPy's, in fewer passes."""
from __future__ import annotations

import numpy as np

__all__ = ["median", "mad_sigma"]


def median(values):
    """``np.median`` of a 1-D array, bit for bit, from a single partition.

    ``np.median`` partitions at both middle positions even when one is enough; here the upper
    middle comes from one partition and the lower one (even length) is the largest value
    below it. ``values`` is reordered in place.

    Examples
    --------
    >>> bool(median(np.array([3.0, 1.0, 4.0, 1.5])) == np.median([3.0, 1.0, 4.0, 1.5]))
    True
    """
    v = np.asarray(values)
    n = v.size
    k = n // 2
    v.partition(k)
    if n % 2:
        return v[k]
    return np.mean(np.array([v[:k].max(), v[k]], dtype=v.dtype))


def mad_sigma(values):
    """Robust sigma, 1.4826 x the median absolute deviation (``values`` is reordered)."""
    v = np.asarray(values)
    m = median(v)
    return 1.4826 * median(np.abs(v - m))
