"""Atomic file writes for :mod:`sim` (temporary file in the target folder, then rename), and
the checked read of an ``.npz`` file."""
from __future__ import annotations

import os
import tempfile

import numpy as np

from .errors import InputError


def write_atomic(path, write, *, fsync: bool = False) -> str:
    """Create ``path`` through ``write(tmp_path)`` so that a reader never sees a partial file.

    Parameters
    ----------
    path : str or path-like
        Destination; its folder is created.
    write : callable
        ``write(tmp_path)`` writes the whole file at ``tmp_path`` (same folder and suffix).
    fsync : bool
        Flush the data to disk before the rename (checkpoints).

    Returns
    -------
    path : str
        The path written.

    Notes
    -----
    ``os.replace`` is atomic on POSIX. On any error, including KeyboardInterrupt, the temporary
    file is removed and ``path`` is left as it was.
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=os.path.splitext(path)[1], prefix=".tmp-", dir=folder)
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)         # mkstemp makes 0600; results are meant to be shared
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        if fsync:
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    return path


def save_npz_atomic(path, arrays: dict, *, compressed: bool = False, fsync: bool = True) -> str:
    """Write ``arrays`` to ``path`` as ``.npz`` (no pickles) with :func:`write_atomic`.

    Parameters
    ----------
    path : str or path-like
    arrays : dict of str -> ndarray
    compressed : bool
        ``np.savez_compressed`` instead of ``np.savez``.
    fsync : bool

    Returns
    -------
    path : str
    """
    def write(tmp):
        with open(tmp, "wb") as f:
            (np.savez_compressed if compressed else np.savez)(f, **arrays)

    return write_atomic(path, write, fsync=fsync)


def load_npz(path, what: str) -> dict:
    """All arrays of the ``.npz`` file ``path`` (no pickle), as a dict.

    Raises
    ------
    InputError
        ``path`` is missing or not a readable ``what`` (one line naming the file).
    """
    path = os.fspath(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except Exception as exc:  # zipfile.BadZipFile, ValueError (pickled arrays), ...
        raise InputError(f"{path}: not a readable {what} ({exc})") from None
