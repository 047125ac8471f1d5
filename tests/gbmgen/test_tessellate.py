"""Voronoi / Laguerre tessellations clipped to the box; area-fitted weights."""
import numpy as np
import pytest
from scipy.spatial import cKDTree

from gbmgen.errors import InputError
from gbmgen.tessellate import fit_power_weights, polygon_areas, polygon_centroids, tessellate


def _power_owner(points, sx, sy, w):
    W = w.max()
    _, k = cKDTree(np.c_[sx, sy, np.sqrt(W - w)]).query(np.c_[points, np.zeros(len(points))])
    return k


def test_two_seeds_voronoi_and_laguerre_bisector():
    xy, off, seed = tessellate([0.25, 0.75], [0.5, 0.5], [0, 1, 0, 1])
    np.testing.assert_allclose(polygon_areas(xy, off), [0.5, 0.5])
    # power bisector: x = (|c2|^2 - |c1|^2 - w2 + w1) / (2 * 0.5) along y = 0.5 -> x = 0.5 + 0.04
    xy, off, seed = tessellate([0.25, 0.75], [0.5, 0.5], [0, 1, 0, 1], weights=[0.04, 0.0])
    np.testing.assert_allclose(polygon_areas(xy, off), [0.54, 0.46])
    np.testing.assert_allclose(polygon_centroids(xy, off)[0], [0.27, 0.5])


@pytest.mark.parametrize("laguerre", [False, True])
def test_cells_tile_the_box_and_match_power_nearest(laguerre):
    rng = np.random.default_rng(1)
    n, box = 300, np.array([0.0, 1.0, 0.0, 2.0])
    sx, sy = rng.uniform(0, 1, n), rng.uniform(0, 2, n)
    w = rng.uniform(0, 2e-3, n) if laguerre else np.zeros(n)
    xy, off, seed = tessellate(sx, sy, box, weights=w if laguerre else None)
    a = polygon_areas(xy, off)
    assert np.all(a > 0)
    assert a.sum() == pytest.approx(2.0, rel=1e-12)
    # each vertex lies in the box
    assert xy[:, 0].min() >= 0 and xy[:, 0].max() <= 1 and xy[:, 1].max() <= 2
    # Monte-Carlo areas by power-nearest seed agree with the polygons
    p = rng.uniform([0, 0], [1, 2], (200_000, 2))
    mc = np.bincount(_power_owner(p, sx, sy, w), minlength=n) / len(p) * 2.0
    full = np.zeros(n)
    full[seed] = a
    assert np.abs(mc - full).max() < 2.5e-3  # ~4 sigma of the MC noise for these cells


def test_hidden_seed_has_no_cell():
    # seed 1 inside the power disk of seed 0 and with a tiny weight: empty Laguerre cell
    xy, off, seed = tessellate([0.3, 0.32, 0.8, 0.5], [0.5, 0.5, 0.5, 0.9], [0, 1, 0, 1],
                               weights=[0.05, 0.0, 0.0, 0.0])
    assert 1 not in seed.tolist()
    assert polygon_areas(xy, off).sum() == pytest.approx(1.0)


def test_fit_power_weights_hits_targets():
    rng = np.random.default_rng(2)
    n, box = 400, np.array([0.0, 1.0, 0.0, 1.0])
    # disks of a wide size range, placed without overlap on a jittered grid
    g = np.stack(np.meshgrid(np.arange(20), np.arange(20)), -1).reshape(-1, 2)
    sx, sy = (g[:, 0] + 0.5) / 20, (g[:, 1] + 0.5) / 20
    r = rng.uniform(0.005, 0.024, n)
    target = rng.uniform(0.2, 3.0, n)
    w, info = fit_power_weights(sx, sy, box, target, weights=r ** 2, rtol=0.01)
    assert info["max_rel_error"] <= 0.01
    xy, off, seed = tessellate(sx, sy, box, weights=w)
    a = np.zeros(n)
    a[seed] = polygon_areas(xy, off)
    t = target / target.sum()
    np.testing.assert_allclose(a, t, rtol=0.0101)


def test_bad_input():
    with pytest.raises(InputError, match="inside the box"):
        tessellate([2.0], [0.5], [0, 1, 0, 1])
    with pytest.raises(InputError, match="box"):
        tessellate([0.5], [0.5], [0, 0, 0, 1])


def test_fit_power_weights_from_overlapping_disks():
    # random seeds with strongly overlapping disks: some cells start empty and are revived
    rng = np.random.default_rng(4)
    n, box = 300, np.array([0.0, 1.0, 0.0, 1.0])
    sx, sy = rng.uniform(0.01, 0.99, n), rng.uniform(0.01, 0.99, n)
    r = rng.uniform(0.01, 0.08, n)
    xy, off, seed = tessellate(sx, sy, box, weights=r ** 2)
    assert seed.size < n  # empty cells at the start
    w, info = fit_power_weights(sx, sy, box, np.pi * r ** 2, weights=r ** 2, rtol=0.01)
    xy, off, seed = tessellate(sx, sy, box, weights=w)
    assert seed.size == n
    assert info["max_rel_error"] <= 0.01
