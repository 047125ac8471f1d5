"""Particles -> grains and bonds, checked by independent geometry on a 5 x 10 mm specimen."""
import numpy as np
import pytest
from _gbmgen_builds import small_specimen

from gbmgen import config
from gbmgen.assign import find_contacts, particles_to_grains


def _inside(px, py, poly):
    """Independent crossing-number test (numpy, one polygon, many points)."""
    x1, y1 = poly[:, 0], poly[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    px = np.asarray(px)[:, None]
    py = np.asarray(py)[:, None]
    cond = (y1 > py) != (y2 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
    return np.sum(cond & (px < xc), axis=1) % 2 == 1


def _segment_hits(p, q, poly):
    """Edges (a, b) of poly properly crossed by segment p-q."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    d = q - p
    e = b - a
    den = d[0] * e[:, 1] - d[1] * e[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((a[:, 0] - p[0]) * e[:, 1] - (a[:, 1] - p[1]) * e[:, 0]) / den
        u = ((a[:, 0] - p[0]) * d[1] - (a[:, 1] - p[1]) * d[0]) / den
    ok = (den != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    return e[ok]


def test_particle_grain_matches_independent_point_in_polygon():
    s = small_specimen()
    owner = np.full(s.n_particles, -1)
    for g in range(s.n_grains):
        owner[_inside(s.x, s.y, s.grain_polygon(g))] = g
    assert np.all(owner >= 0)
    assert np.array_equal(owner, s.grain)
    assert np.array_equal(s.mineral, s.grain_mineral[s.grain])


def test_bonds_are_exactly_the_contacts_within_the_bond_gap():
    s = small_specimen()
    gap = config.BOND_GAP_PER_RADIUS * 1e-4
    assert s.meta["bond_gap_m"] == pytest.approx(gap)
    d = np.hypot(s.x[:, None] - s.x[None], s.y[:, None] - s.y[None]) - s.r[:, None] - s.r[None]
    i, j = np.nonzero(np.triu(d <= gap, 1))
    got = set(zip(s.bond_i.tolist(), s.bond_j.tolist()))
    assert got == set(zip(i.tolist(), j.tolist()))
    assert np.all(s.bond_i < s.bond_j)


def test_every_intra_contact_is_pb_and_every_crossing_one_sj():
    s = small_specimen()
    n_sj = 0
    for b in range(s.n_bonds):
        i, j = s.bond_i[b], s.bond_j[b]
        p, q = np.array([s.x[i], s.y[i]]), np.array([s.x[j], s.y[j]])
        gi = s.grain[i]
        same = bool(_inside([q[0]], [q[1]], s.grain_polygon(gi))[0])
        hits = _segment_hits(p, q, s.grain_polygon(gi))
        if same:
            assert s.bond_kind[b] == 0
            assert hits.shape[0] == 0  # convex grain: the contact crosses no boundary
            assert np.isnan(s.joint_nx[b]) and np.isnan(s.joint_ny[b])
        else:
            n_sj += 1
            assert s.bond_kind[b] == 1
            assert hits.shape[0] >= 1
            n = np.array([s.joint_nx[b], s.joint_ny[b]])
            assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12)
            e = hits[0] / np.linalg.norm(hits[0])
            assert abs(n @ e) < 1e-9  # perpendicular to the crossed boundary segment
            assert n @ (q - p) > 0  # oriented from i to j
    assert n_sj == int(np.sum(s.bond_kind == 1)) > 100


def test_joint_normal_is_not_the_ball_direction():
    s = small_specimen()
    sj = s.bond_kind == 1
    i, j = s.bond_i[sj], s.bond_j[sj]
    u = np.c_[s.x[j] - s.x[i], s.y[j] - s.y[i]]
    u /= np.linalg.norm(u, axis=1)[:, None]
    cos = np.abs(np.sum(u * np.c_[s.joint_nx[sj], s.joint_ny[sj]], axis=1))
    assert np.median(cos) < 0.99 and np.min(cos) < 0.9


def test_particles_to_grains_on_a_hand_made_tiling():
    # two squares; points in each, one on the shared edge
    xy = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [1, 0], [2, 0], [2, 1], [1, 1]], float)
    off = np.array([0, 4, 8])
    g = particles_to_grains([0.5, 1.5, 1.9, 1.0], [0.5, 0.5, 0.1, 0.5], xy, off, [0, 2, 0, 1])
    assert g[:3].tolist() == [0, 1, 1] and g[3] in (0, 1)


def test_find_contacts_gap():
    i, j = find_contacts([0.0, 2.1, 5.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.11)
    assert list(zip(i.tolist(), j.tolist())) == [(0, 1)]
    i, j = find_contacts([0.0, 2.1, 5.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.09)
    assert i.size == 0
