"""Controlled grains (Ch. 5): slenderness and area within 3 %, 4/6/6 vertices, exact tiling."""
import numpy as np
import pytest

from gbmgen import config
from gbmgen.controlled import SHAPES, controlled_tessellation, measure_slenderness
from gbmgen.errors import InputError
from gbmgen.tessellate import polygon_areas

VERTICES = {"rectangle": 4, "hexagon": 6, "shield": 6}


@pytest.mark.parametrize("shape", SHAPES)
def test_slenderness_area_vertices_over_thesis_range(shape):
    lo, hi = config.SLENDERNESS_RANGE[shape]
    box = np.array([0.0, 25e-3, 0.0, 50e-3])
    A = config.GRAIN_AREA_MM2 * 1e-6
    for s in np.linspace(lo, hi, 5):
        xy, off, inner = controlled_tessellation(shape, box, slenderness=s, grain_area_m2=A)
        areas = polygon_areas(xy, off)
        # the grains tile the specimen exactly (no gaps, no overlaps)
        assert areas.sum() == pytest.approx(25e-3 * 50e-3, rel=1e-9)
        assert inner.sum() > 100
        idx = np.flatnonzero(inner)
        np.testing.assert_allclose(areas[idx], A, rtol=config.SHAPE_TOL)
        meas = np.array([measure_slenderness(xy[off[g]:off[g + 1]]) for g in idx])
        np.testing.assert_allclose(meas, s, rtol=config.SHAPE_TOL)
        assert set(np.diff(off)[idx].tolist()) == {VERTICES[shape]}


def test_shield_is_not_a_hexagon():
    # the shield's centroid sits above its mid-height (long bottom cap): asymmetric top/bottom
    box = np.array([0.0, 10.0, 0.0, 10.0])
    xy, off, inner = controlled_tessellation("shield", box, slenderness=1.0, grain_area_m2=1.0)
    g = np.flatnonzero(inner)[0]
    p = xy[off[g]:off[g + 1]]
    mid = 0.5 * (p[:, 1].max() + p[:, 1].min())
    from gbmgen.tessellate import polygon_centroids
    c = polygon_centroids(p, np.array([0, p.shape[0]]))[0]
    assert abs(c[1] - mid) > 0.05


def test_measure_slenderness_examples():
    assert measure_slenderness([[0, 0], [2, 0], [2, 1], [0, 1]]) == pytest.approx(0.5)
    hexagon = [[0, -1], [np.sqrt(3) / 2, -0.5], [np.sqrt(3) / 2, 0.5], [0, 1],
               [-np.sqrt(3) / 2, 0.5], [-np.sqrt(3) / 2, -0.5]]
    assert measure_slenderness(hexagon) == pytest.approx(2 / np.sqrt(3))


def test_bad_shape_input():
    with pytest.raises(InputError, match="shape"):
        controlled_tessellation("circle", [0, 1, 0, 1], slenderness=1, grain_area_m2=0.1)
    with pytest.raises(InputError, match="slenderness"):
        controlled_tessellation("hexagon", [0, 1, 0, 1], slenderness=-1, grain_area_m2=0.1)
