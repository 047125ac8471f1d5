"""gbmgen: grain-based model generator (grain-size table -> bonded specimen.npz)."""
from .errors import InputError

__all__ = ["InputError"]
