"""Atomic file writes for :mod:`sim` (temporary file in the target folder, fsync, rename)."""
from __future__ import annotations

import os
import tempfile

import numpy as np


def save_npz_atomic(path, arrays: dict, *, compressed: bool = False) -> str:
    """Write ``arrays`` to ``path`` as ``.npz`` so that a reader never sees a partial file.

    Parameters
    ----------
    path : str or path-like
        Destination; its folder is created.
    arrays : dict of str -> ndarray
        Saved with ``np.savez`` (``np.savez_compressed`` when ``compressed``); no pickles.
    compressed : bool

    Returns
    -------
    path : str
        The path written.

    Notes
    -----
    The data go to a temporary file beside ``path``, are flushed and fsynced, and the file is
    renamed over ``path`` (``os.replace`` is atomic on POSIX). On any error, including
    KeyboardInterrupt, the temporary file is removed and ``path`` is left as it was.
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".npz.tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            (np.savez_compressed if compressed else np.savez)(f, **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    return path
