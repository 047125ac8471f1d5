"""Field-scale models (thesis Ch. 7): ring-graded rock mass around drives and stopes.

:mod:`gbmgen.field.plan` (ring plans), :mod:`gbmgen.field.openings` (drive profile, circle,
polygon, two drives at a dip, stope) and :mod:`gbmgen.field.build` (:func:`build_field`).
Importing does no work.
"""
__all__ = ["build_field", "load_plan", "RingPlan"]


def __getattr__(name):
    import importlib
    if name == "build_field":
        return importlib.import_module(".build", __name__).build_field
    if name in ("load_plan", "RingPlan"):
        return getattr(importlib.import_module(".plan", __name__), name)
    raise AttributeError(f"module 'gbmgen.field' has no attribute {name!r}")
