"""Damage around holes (sim.hole_damage): exact answers on hand-made arrays, and the measures in
the summary.json of a test on a specimen with holes (thesis Ch. 6)."""
import doctest

import numpy as np
import pytest

from sim import hole_damage as hd


def test_docstring_examples():
    res = doctest.testmod(hd)
    assert res.failed == 0 and res.attempted > 0


def _row(n, r=0.5):
    """Particles 0..n-1 on the x axis at x = 0, 1, ..., bonded to their neighbours."""
    x0 = np.arange(n, dtype=float)
    return x0, np.zeros(n), np.full(n, r), np.arange(n - 1), np.arange(1, n)


def test_damaged_area_counts_particles_near_each_hole_once():
    x0, y0, r, bi, bj = _row(8)
    broken = np.zeros(7, bool)
    broken[[0, 5]] = True                 # bonds 0-1 and 5-6: particles 0, 1, 5, 6 damaged
    holes = [(-1.0, 0.0, 0.5), (7.5, 0.0, 0.5)]          # rings reach x <= 0.5 and x >= 6
    m = hd.hole_damage(x0, y0, r, bi, bj, broken, holes, radius_factor=3.0)   # 1.5 m
    disk_mm2 = np.pi * 0.25 * 1e6
    assert m["holes"][0]["damaged_particles"] == 1       # particle 0 (1 m away); 1 is 2 m
    assert m["holes"][1]["damaged_particles"] == 1       # particle 6 (1.5 m); 5 is 2.5 m
    assert m["holes"][0]["damaged_area_mm2"] == pytest.approx(disk_mm2)
    assert m["damaged_area_mm2"] == pytest.approx(2 * disk_mm2)
    # overlapping rings: a particle near both holes counts once in the total
    m = hd.hole_damage(x0, y0, r, bi, bj, broken, [(0.0, 1.0, 0.5), (1.0, 1.0, 0.5)],
                       radius_factor=3.0)
    assert m["holes"][0]["damaged_particles"] == 2 and m["holes"][1]["damaged_particles"] == 2
    assert m["damaged_area_mm2"] == pytest.approx(2 * disk_mm2)


def test_crack_path_joins_holes_only_through_a_connected_cluster():
    x0, y0, r, bi, bj = _row(8)
    holes = [(-1.0, 0.0, 0.5), (8.0, 0.0, 0.5)]   # rims: particle 0 and particle 7
    broken = np.ones(7, bool)
    m = hd.hole_damage(x0, y0, r, bi, bj, broken, holes)
    assert m["crack_joins_holes"] is True and m["joined_pairs"] == [[0, 1]]
    broken[3] = False                               # the cluster is cut in the middle
    m = hd.hole_damage(x0, y0, r, bi, bj, broken, holes)
    assert m["crack_joins_holes"] is False and m["joined_pairs"] == []
    m = hd.hole_damage(x0, y0, r, bi, bj, broken, holes[:1])
    assert m["crack_joins_holes"] is None           # one hole: nothing to join


def test_displacements():
    x0, y0, r, bi, bj = _row(4)
    x, y = x0.copy(), y0.copy()
    x[3] += 3e-3
    y[0] += 4e-3
    m = hd.hole_damage(x0, y0, r, bi, bj, np.zeros(3, bool), [(-1.0, 0.0, 0.5)], x=x, y=y)
    assert m["max_displacement_mm"] == pytest.approx(4.0)
    assert m["max_displacement_near_holes_mm"] == pytest.approx(4.0)   # particle 0 is near
    assert m["damaged_area_mm2"] == 0.0


def test_holes_in_meta():
    meta = {"defects": [{"type": "flaw"}, {"type": "hole", "radius_m": 1e-3,
                                           "centres_m": [[0.0, 1.0], [2.0, 3.0]]}]}
    assert hd.holes_in_meta(meta) == [(0.0, 1.0, 1e-3), (2.0, 3.0, 1e-3)]
    assert hd.holes_in_meta({}) == [] and hd.holes_in_meta(None) == []
