"""Prominent peaks of a short 1-D profile (a smoothed grey histogram).

:func:`prominent_peaks` returns the peaks of ``scipy.signal.find_peaks(x, prominence=p)``,
the same indices by the same rules (plateau midpoints, prominence from the higher of the two
bases, no window), without importing ``scipy.signal``: that import (it pulls in
``scipy.stats``) costs about 0.7 s of CPU, more than analysing a 1 MP image, and every worker
process of a folder run pays it once. The profiles are histograms of at most a few hundred
bins, so a plain loop is enough.
"""
from __future__ import annotations

import numpy as np

__all__ = ["prominent_peaks"]


def prominent_peaks(x, min_prominence):
    """Indices of the local maxima of ``x`` whose prominence is at least ``min_prominence``.

    Parameters
    ----------
    x : (K,) array_like of float
        A short profile; its first and last samples are never peaks.
    min_prominence : float

    Returns
    -------
    peaks : (P,) ndarray of int64
        Increasing indices; a flat maximum gives its midpoint (rounded down).

    Examples
    --------
    >>> x = [0, 2, 1, 5, 5, 5, 0, 1, 0]
    >>> prominent_peaks(x, 0.5).tolist(), prominent_peaks(x, 1.5).tolist()
    ([1, 4, 7], [4])
    """
    v = np.asarray(x, np.float64).tolist()
    n = len(v)
    peaks = []
    i = 1
    while i < n - 1:
        if v[i - 1] < v[i]:
            j = i + 1
            while j < n - 1 and v[j] == v[i]:
                j += 1
            if v[j] < v[i]:
                peaks.append((i + j - 1) // 2)
                i = j
        i += 1
    out = []
    for p in peaks:
        top = v[p]
        left = right = top
        k = p
        while k >= 0 and v[k] <= top:
            left = min(left, v[k])
            k -= 1
        k = p
        while k <= n - 1 and v[k] <= top:
            right = min(right, v[k])
            k += 1
        if top - max(left, right) >= min_prominence:
            out.append(p)
    return np.asarray(out, np.int64)
