"""Smooth joint: kernel vs reference, sliding along an inclined joint (REFERENCE.md §4)."""
import math

import numpy as np
import pytest
from _reference import smooth_joint as ref_sj
from _sim_fixtures import disks

from sim import Simulation
from sim.config import SJ_REACH
from sim.contacts.smooth_joint import sj_update

R = 1e-3


def test_kernel_matches_reference(rng):
    for _ in range(500):
        state = int(rng.integers(0, 3))
        un, fs = rng.normal(0, 1e-6), rng.normal(0, 1e3)
        dun, dus = rng.normal(0, 1e-7, 2)
        kna, ksa = rng.uniform(1e8, 1e10, 2)
        tena, coha = rng.uniform(0, 2e3, 2)
        fa, fric, dil = rng.uniform(0, 45), rng.uniform(0, 1.2), rng.uniform(0, 10)
        rmin = 1e-4
        gap = rng.uniform(-0.05, 2.0) * SJ_REACH * rmin   # in and out of reach
        got = sj_update(un, fs, state, dun, dus, kna, ksa, tena, coha, math.tan(math.radians(fa)),
                        fric, math.tan(math.radians(dil)), gap, rmin)
        want = ref_sj(un, fs, state, dun, dus, kna, ksa, tena, coha, fa, fric, dil, gap=gap,
                      rmin=rmin, reach=SJ_REACH)
        assert got[3] == want[3]
        np.testing.assert_allclose(got[:3], want[:3], rtol=1e-12, atol=1e-18)


def test_bonded_joint_breaks_in_tension_at_strength():
    ten = 5e6
    nj = (math.cos(math.radians(30)), math.sin(math.radians(30)))
    s = disks([0.0, 2 * R], [0.0, 0.0], R, bonds=[(0, 1)], kinds=[1], joint_normals=[nj],
              sj=dict(kn=1e12, ks=5e11, ten=ten, coh=1e12, fa=30.0, fric=0.6))
    sim = Simulation(s, damping=0.0)
    kna = 1e12 * 2 * R
    v = ten * 2 * R / kna / (2000 * sim.dt)
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    sim.fix_velocity([1], v * nj[0], v * nj[1], 0.0)
    fmax = 0.0
    while sim.bond_intact[0]:
        sim.cycle(1)
        if sim.bond_intact[0]:
            fmax = max(fmax, -sim.bond_forces()[0][0])
    assert fmax == pytest.approx(ten * 2 * R, rel=1e-3) and fmax < ten * 2 * R
    row = sim.cracks.to_frame().iloc[0]
    assert (row["kind"], row["mode"], row["relation"]) == ("sj", "tension", "inter")
    assert row["angle_deg"] == pytest.approx(30.0)


@pytest.mark.parametrize("fric", [0.3, 1.0])
def test_inclined_joint_slides_at_mu_fn_along_joint_plane(fric):
    """Joint normal at 30 deg to the ball-ball line: sliding meets only mu*Fn, along the joint."""
    a = math.radians(30.0)
    nj = np.array([math.cos(a), math.sin(a)])
    tj = np.array([-nj[1], nj[0]])
    s = disks([0.0, 2 * R], [0.0, 0.0], R, bonds=[(0, 1)], kinds=[1], joint_normals=[nj],
              sj=dict(kn=1e12, ks=5e11, ten=0.0, coh=0.0, fa=30.0, fric=fric))
    sim = Simulation(s, damping=0.0)
    kna = 1e12 * 2 * R
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    # close the joint by 1e-7 m along -nj (the balls then overlap; no ball-ball law acts)
    steps = 400
    v = 1e-7 / (steps * sim.dt)
    sim.fix_velocity([1], *(-v * nj), 0.0)
    sim.cycle(steps)
    sim.fix_velocity([1], 0.0, 0.0, 0.0)
    sim.cycle(1)
    fn0 = sim.bond_forces()[0][0]
    assert fn0 == pytest.approx(kna * 1e-7, rel=1e-6)
    # slide along +tj by 20 x the elastic shear displacement
    sim.fix_velocity([1], *(v * tj), 0.0)
    fns, fss = [], []
    for _ in range(8 * steps):
        sim.cycle(1)
        fn, fs, m = (x[0] for x in sim.bond_forces())
        fns.append(fn)
        fss.append(fs)
    fns, fss = np.array(fns), np.array(fss)
    # normal force unchanged although the ball-ball distance changed (joint-plane motion)
    np.testing.assert_allclose(fns, fn0, rtol=1e-9)
    d = math.hypot(sim.x[1] - sim.x[0], sim.y[1] - sim.y[0])
    assert 2 * R - d > 1e-7  # the balls did approach each other
    # sliding at the Coulomb limit, resisting the motion
    assert fss[-1] == pytest.approx(-fric * fn0, rel=1e-12)
    assert m == 0.0
    # the force on particle 1 lies in the joint frame: Fn nj + Fs tj
    fx, fy = sim.group_force([1])
    np.testing.assert_allclose([fx, fy], fn0 * nj + fss[-1] * tj, rtol=1e-9)
    # zero tensile strength: the joint is broken (unbonded) from its installation, step 0
    assert sim.cracks.counts()["sj_tension"] == 1
    assert sim.cracks.to_frame()["step"].tolist() == [0]


def _separated_pair(nj, gap_r, steps=500):
    """Two touching disks joined by a zero-strength joint (broken at step 0), ball 1 carried
    along +x until the ball gap is ``gap_r`` x R, then both at rest and free."""
    s = disks([0.0, 2 * R], [0.0, 0.0], R, bonds=[(0, 1)], kinds=[1], joint_normals=[nj],
              sj=dict(kn=1e12, ks=5e11, ten=0.0, coh=0.0, fa=30.0, fric=0.6))
    sim = Simulation(s, damping=0.0)
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    sim.fix_velocity([1], gap_r * R / (steps * sim.dt), 0.0, 0.0)
    sim.cycle(steps)
    sim.free([0, 1])
    sim.set_velocity([0, 1], 0.0, 0.0, 0.0)
    assert (sim.x[1] - sim.x[0]) - 2 * R == pytest.approx(gap_r * R, rel=1e-9)
    return sim


def test_separated_unbonded_joint_cannot_act_at_a_distance():
    """Regression (UCS seed-3 blow-up, 'particle moved > 0.25 R' on particle 489): a grain
    squeezed out of a specimen kept its broken smooth joints to balls 70 R away. The joint's
    contact point sits at mid-gap, so spin increments w·a (a ≈ d/2) drove the open joint
    closed again and it fired with F = kn·Ā·un at a lever arm of 36 R. An unbonded joint
    whose balls are more than config.SJ_REACH x min(R) apart carries nothing."""
    nj = (math.cos(math.radians(60.0)), math.sin(math.radians(60.0)))
    sim = _separated_pair(nj, 20.0)
    # same-sense spin: the relative contact-point velocity at mid-gap is -w·d along t,
    # i.e. w·d·sin(60°) per unit time closing along the joint normal (d = 22 R)
    w = 1000.0
    sim.set_velocity([0, 1], 0.0, 0.0, w)
    ek0 = sim.energy()["kinetic"]
    steps = 3000   # the spurious closure (w d sin60 · steps dt) is ~3x the 10 R opening
    assert w * 22 * R * math.sin(math.radians(60.0)) * steps * sim.dt > 2.5 * 10 * R
    for _ in range(steps // 100):
        sim.cycle(100)
        assert sim.bond_forces()[0][0] == 0.0 and sim.bond_forces()[1][0] == 0.0
    np.testing.assert_array_equal(sim.vx, [0.0, 0.0])
    np.testing.assert_array_equal(sim.vy, [0.0, 0.0])
    np.testing.assert_array_equal(sim.w, [w, w])
    assert sim.energy()["kinetic"] == ek0


def test_separated_joint_closes_again_when_the_balls_touch():
    """Out of reach the joint's normal state follows the ball gap (un = -g), so a pair that
    comes back head-on along the joint normal is pushed apart from the moment it touches."""
    sim = _separated_pair((1.0, 0.0), 3.0)
    kna = 1e12 * 2 * R
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    steps = 600
    ov = 1e-7
    v = -(3.0 * R + ov) / (steps * sim.dt)
    sim.fix_velocity([1], v, 0.0, 0.0)
    sim.cycle(steps)
    assert 2 * R - (sim.x[1] - sim.x[0]) == pytest.approx(ov, rel=1e-6)
    assert sim.bond_forces()[0][0] == pytest.approx(kna * ov, rel=1e-5)
