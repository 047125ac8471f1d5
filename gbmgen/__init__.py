"""gbmgen: grain-based model generator (grain-size table -> bonded specimen.npz).

Importing this package does no work (no numba compilation, no matplotlib); the API below is
loaded on first use.
"""
from .errors import InputError

__version__ = "0.1.0"

__all__ = ["InputError", "GrainSizeTable", "read_table", "build_grains", "build_specimen",
           "load_params", "controlled_tessellation", "tessellate", "fidelity_report",
           "export_geom", "read_geom", "export_vtk", "run", "__version__"]

_LAZY = {
    "GrainSizeTable": "table", "read_table": "table",
    "build_grains": "build", "build_specimen": "build",
    "load_params": "params", "controlled_tessellation": "controlled",
    "tessellate": "tessellate", "fidelity_report": "fidelity",
    "export_geom": "export", "read_geom": "export", "export_vtk": "export", "run": "run",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module 'gbmgen' has no attribute {name!r}")
