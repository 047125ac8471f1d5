"""Cached builds shared by the gbmgen tests (small specimens, 25 x 50 mm grain structures)."""
import functools
from importlib import resources

from gbmgen.table import read_table


def table_4_1_path():
    return str(resources.files("gbmgen").joinpath("presets", "table_4_1.csv"))


@functools.lru_cache(maxsize=None)
def small_specimen(seed=7, tessellation="laguerre", shape=None):
    """A 5 x 10 mm Scenario-1 specimen of Table 4-1 (about 1.2 k particles)."""
    from gbmgen.build import build_specimen
    t = None if shape else read_table(table_4_1_path())
    spec, _ = build_specimen(t, width_mm=5.0, height_mm=10.0, scenario=1,
                             tessellation=tessellation, shape=shape, seed=seed)
    return spec


@functools.lru_cache(maxsize=None)
def full_grains(scenario=1, scale=1.0, tessellation="laguerre", fit_areas=True, seed=7):
    """Grain structure (no particles) of a 25 x 50 mm specimen of Table 4-1 at model scale."""
    from gbmgen.build import build_grains
    return build_grains(read_table(table_4_1_path()), width_mm=25.0, height_mm=50.0,
                        scenario=scenario, scale=scale, tessellation=tessellation,
                        fit_areas=fit_areas, seed=seed)
