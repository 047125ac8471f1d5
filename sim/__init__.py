"""sim: a compact 2D bonded-particle DEM (PFC2D style) in numba.

Public API: :class:`Specimen` (specimen.npz v1), :class:`Simulation` (state, contact lists,
compiled step loop, walls, servo, checkpoints), :class:`CrackLog`, the errors, and
:mod:`sim.config` (tolerances and defaults). Importing this package compiles nothing: kernels
compile lazily on first use and are cached on disk.
"""
import os as _os

from . import config

# Like the threading layer in _jit.py: a default read by libgomp when its pool starts (by the
# first parallel call or numba.set_num_threads), so it must be in place before either.
_os.environ.setdefault("OMP_WAIT_POLICY", config.OMP_WAIT_POLICY)
from .cracks import CrackLog
from .errors import InputError, InstabilityError
from .simulation import Simulation
from .specimen import SCHEMA_VERSION, Specimen

__all__ = ["Specimen", "Simulation", "CrackLog", "SCHEMA_VERSION", "InputError",
           "InstabilityError", "config"]
