"""The ring-graded specimen: radii follow the plan, junctions bonded, grains reported."""
import numpy as np
import pytest

from gbmgen.field.build import MIN_PARTICLES_PER_GRAIN
from sim.field_geometry import points_in_polygon, ring_index


def _radius_ring(plan, r):
    """Ring whose radius range holds r (the mini plan's ranges do not overlap), else 0."""
    k = np.zeros(r.size, int)
    for i in range(1, plan.n_rings + 1):
        lo, hi = plan.particle_range(i)
        k[(r >= lo * (1 - 0.02)) & (r <= hi * (1 + 1e-9))] = i   # 2 %: overlap removal
    return k


def test_radii_follow_the_plan_ring_by_ring(mini_circle, mini_plan):
    s = mini_circle
    f = s.meta["field"]
    kr = _radius_ring(mini_plan, s.r)
    assert np.all(kr > 0)                       # every radius is one ring's (to the 2 % shrink)
    kp = ring_index(s.x, s.y, f["foci"], mini_plan.core_half, mini_plan.outer)
    # a particle sits in the ring its radius belongs to, or next to a junction it drifted over
    off = kr != kp
    d = np.maximum(np.abs(s.x), np.abs(s.y)) - mini_plan.core_half
    dist_to_edge = np.min(np.abs(d[:, None] - mini_plan.outer[None, :-1]), axis=1)
    assert np.all(np.abs(kr[off] - kp[off]) == 1)
    assert np.all(dist_to_edge[off] <= 2 * 2 * mini_plan.particle_range(3)[1])
    assert off.mean() < 0.05
    # mean radius of each ring's particles = the plan's (uniform radii: sample mean within 3 %)
    for k in range(1, mini_plan.n_rings + 1):
        assert s.r[kr == k].mean() == pytest.approx(mini_plan.particle_r[k - 1], rel=0.03)
    # the opening is filled (removed by the test, not the generator)
    inside = points_in_polygon(s.x, s.y, f["openings"][0]["polygon"])
    assert inside.sum() > 0.7 * np.pi * 1.0 ** 2 * 0.8 / (np.pi * 0.025 ** 2)


def test_junctions_are_bonded_without_gap_or_overlap(mini_circle, mini_plan):
    s = mini_circle
    kr = _radius_ring(mini_plan, s.r)
    i, j = s.bond_i, s.bond_j
    d = np.hypot(s.x[j] - s.x[i], s.y[j] - s.y[i])
    gap = d - s.r[i] - s.r[j]
    assert gap.min() >= -1e-12                  # no overlap anywhere: a stress-free start
    across = kr[i] != kr[j]
    # bonds across each junction: about one per small-particle diameter of junction length
    for a in (1, 2):
        n = np.sum(across & (np.minimum(kr[i], kr[j]) == a))
        edge = 8 * (mini_plan.core_half + mini_plan.outer[a - 1])
        assert n > 0.5 * edge / (2 * mini_plan.particle_r[a - 1])
    # bonds per particle near a junction as inside a ring (no gap)
    deg = np.bincount(np.r_[i, j], minlength=s.n_particles)
    dd = np.maximum(np.abs(s.x), np.abs(s.y)) - mini_plan.core_half
    near = np.abs(dd - mini_plan.outer[0]) < 0.05
    inner = (dd > -0.5) & (dd < mini_plan.outer[0] - 0.2)
    assert deg[near].mean() > 0.85 * deg[inner].mean()


def test_grains_have_ten_particles_or_are_reported(mini_circle):
    s = mini_circle
    gp = np.bincount(s.grain[s.grain >= 0], minlength=s.n_grains)
    reported = sum(r["particles_per_grain"][f"below_{MIN_PARTICLES_PER_GRAIN}"]
                   for r in s.meta["field"]["rings"])
    assert reported == np.sum(gp < MIN_PARTICLES_PER_GRAIN)
    for r in s.meta["field"]["rings"]:
        assert 3.5 < r["grain_to_particle_radius"] < 4.6      # ~4, as the thesis
        assert r["particles_per_grain"]["median"] >= 10
        fr = r["mineral_area_fraction"]
        assert fr["pyroxene"] == pytest.approx(0.5, abs=0.08)
    # joints get the per-joint bond-like stiffness rule
    assert s.meta["field"]["joint_stiffness"] == "per_joint_bond"
    assert {0, 1} <= set(np.unique(s.bond_kind))
