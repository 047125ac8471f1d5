"""semkit: SEM micro-crack and grain statistics for rock mechanics.

Importing this package does no work (no numba compilation, no matplotlib).
"""
from .errors import InputError

__all__ = ["InputError"]
