"""Smoothing and prominent peaks of a short 1-D profile (a grey histogram).

:func:`prominent_peaks` returns the peaks of ``scipy.signal.find_peaks(x, prominence=p)``,
the same indices by the same rules (plateau midpoints, prominence from the higher of the two
bases, no window), without importing ``scipy.signal``: that import (it pulls in
``scipy.stats``) costs about 0.7 s of CPU, more than analysing a 1 MP image, and every worker
process of a folder run pays it once. :func:`smooth_profile` is
``scipy.ndimage.gaussian_filter1d`` on a float64 profile, to the last bit, without importing
``scipy.ndimage`` (about 0.2 s per worker). The profiles are histograms of at most a few
thousand bins, so plain NumPy is enough.
"""
from __future__ import annotations

import numpy as np

__all__ = ["prominent_peaks", "smooth_profile"]


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


def smooth_profile(x, sigma, truncate=4.0):
    """Gaussian smoothing of a 1-D float64 profile, reflected at the ends: the same numbers as
    ``scipy.ndimage.gaussian_filter1d(x, sigma)`` (its kernel, its ``reflect`` mode and the
    order of its sums, so the results agree to the last bit).

    Examples
    --------
    >>> smooth_profile([0.0, 0.0, 3.0, 0.0, 0.0], 1.0).round(3).tolist()
    [0.175, 0.726, 1.197, 0.726, 0.175]
    """
    x = np.asarray(x, np.float64)
    r = int(truncate * float(sigma) + 0.5)
    k = np.arange(-r, r + 1)
    w = np.exp(-0.5 / (float(sigma) * float(sigma)) * k ** 2)
    w = w / w.sum()
    if x.size == 0 or r == 0:   # a one-tap kernel of weight 1: the profile itself
        return x.copy()
    # scipy's 'reflect' is NumPy's 'symmetric'; pad as far as the kernel reaches, repeating the
    # reflection for profiles shorter than the kernel
    xp = np.pad(x, r, mode="symmetric")
    n = x.size
    out = xp[r:r + n] * w[r]
    for j in range(r, 0, -1):   # scipy's symmetric-kernel loop: outermost pair first
        out = out + (xp[r - j:r - j + n] + xp[r + j:r + j + n]) * w[r - j]
    return out
