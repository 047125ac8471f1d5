"""sim: a compact 2D bonded-particle DEM (PFC2D style) in numba.

Importing this package compiles nothing.
"""
from .errors import InputError, InstabilityError
from .specimen import SCHEMA_VERSION, Specimen

__all__ = ["Specimen", "SCHEMA_VERSION", "InputError", "InstabilityError"]
