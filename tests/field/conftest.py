"""Fixtures of the field-scale tests: a small ring plan and small field specimens (seconds)."""
import pytest

from gbmgen.field import openings as op
from gbmgen.field.build import build_field
from gbmgen.field.plan import plan_from_dict

#: Three rings, particle radii 25/50/100 mm (ranges [0.75, 1.25] x mean: they do not overlap),
#: grains ~4x the particle radius; an 8 m domain around a 1 m opening.
MINI_PLAN = {"core_half_m": 1.0, "domain_m": 8.0, "radius_ratio": 1.66, "porosity": 0.2,
             "rings": [[0.75, 90, 110, 25], [1.0, 180, 220, 50], [1.5, 360, 440, 100]]}


@pytest.fixture(scope="session")
def mini_plan():
    return plan_from_dict(MINI_PLAN, "mini plan")


@pytest.fixture(scope="session")
def mini_circle(mini_plan):
    """A circle of radius 1 m in the 8 m mini domain (~7.5 k particles), seed 3."""
    spec, _ = build_field(plan=mini_plan, openings=[op.circle(radius_m=1.0)], seed=3)
    return spec


@pytest.fixture(scope="session")
def tiny_drive(mini_plan):
    """A 2 x 2.2 m drive in a 5 m domain of the mini plan, seed 4 (for CLI and resume)."""
    spec, _ = build_field(plan=mini_plan, openings=[op.drive(width_m=1.2, height_m=1.4)],
                          domain_m=4.0, seed=4)
    return spec
