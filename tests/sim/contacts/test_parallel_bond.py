"""Parallel bond: kernel vs reference law, tensile and shear break strengths (REFERENCE.md §3)."""
import math

import numpy as np
import pytest
from _reference import parallel_bond as ref_pb
from _sim_fixtures import disks

from sim import Simulation, config
from sim.contacts.parallel_bond import pb_constants, pb_update

R = 1e-3
EBAR = 50e9


def test_kernel_matches_reference(rng):
    for _ in range(300):
        r1, r2 = rng.uniform(0.5e-3, 1.5e-3, 2)
        emod, kr = rng.uniform(1e9, 1e11), rng.uniform(1, 3)
        ten, coh, fa = rng.uniform(1e6, 1e8), rng.uniform(1e6, 1e8), rng.uniform(0, 50)
        fn, fs, m = rng.normal(0, 1e3, 3)
        dun, dus = rng.normal(0, 1e-8, 2)
        dth = rng.normal(0, 1e-6)
        c = pb_constants(r1, r2, emod, kr, ten, coh, math.radians(fa), 1.0, 1.0, 1.0)
        got = pb_update(fn, fs, m, dun, dus, dth, *c[:7])
        want = ref_pb(fn, fs, m, dun, dus, dth, r1, r2, emod, kr, ten, coh, fa)
        assert got[3] == want[3]
        np.testing.assert_allclose(got[:3], want[:3], rtol=1e-12, atol=1e-12)


def _pair(ten, coh, fa):
    return disks([0.0, 2 * R * (1 + 2e-3)], [0.0, 0.0], R, emod=(EBAR,), pb_emod=(EBAR,),
                 pb_kratio=(2.0,), pb_ten=(ten,), pb_coh=(coh,), pb_fa=(fa,), bonds=[(0, 1)])


def test_tensile_break_at_strength():
    ten = 20e6
    sim = Simulation(_pair(ten, 1e12, 0.0), damping=0.0)
    area = 2 * R
    # pull at a speed that reaches the strength in ~2000 steps
    v = ten * area / EBAR / (2000 * sim.dt)
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    sim.fix_velocity([1], v, 0.0, 0.0)
    fmax = 0.0
    for _ in range(4000):
        sim.cycle(1)
        if not sim.bond_intact[0]:
            break
        fmax = max(fmax, -sim.bond_forces()[0][0])
    assert not sim.bond_intact[0]
    assert fmax == pytest.approx(ten * area, rel=config.TOL_BOND_STRENGTH)
    assert fmax < ten * area
    log = sim.cracks.to_frame()
    assert len(log) == 1
    row = log.iloc[0]
    assert (row["kind"], row["mode"], row["relation"]) == ("pb", "tension", "intra")
    assert row["size_m"] == pytest.approx(2 * R)
    assert row["x"] == pytest.approx(0.5 * (sim.x[0] + sim.x[1]), abs=v * sim.dt)
    assert row["angle_deg"] == pytest.approx(0.0, abs=1e-6)
    assert row["step"] == sim.step


@pytest.mark.parametrize("sigma", [0.0, 30e6])
def test_shear_break_at_coulomb_strength(sigma):
    coh, fa = 40e6, 35.0
    sim = Simulation(_pair(1e12, coh, fa), damping=0.0)
    area = 2 * R
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    # 1) compress the bond to sigma (the pair stays apart: gap 4e-6 m > 2R sigma / E)
    vn = 1e-3
    sim.fix_velocity([1], -vn, 0.0, 0.0)
    while sim.bond_forces()[0][0] < sigma * area - 1e-9 and sigma > 0:
        dfn = EBAR * vn * sim.dt
        left = sigma * area - sim.bond_forces()[0][0]
        if left < dfn:
            sim.fix_velocity([1], -vn * left / dfn, 0.0, 0.0)
        sim.cycle(1)
    fn0 = sim.bond_forces()[0][0]
    assert fn0 == pytest.approx(sigma * area, rel=1e-9, abs=1e-9)
    # 2) shear slowly at constant normal position
    strength = coh * area + fn0 * math.tan(math.radians(fa))
    vs = strength / (EBAR / 2.0) / (2000 * sim.dt)
    sim.fix_velocity([1], 0.0, vs, 0.0)
    fsmax = 0.0
    for _ in range(4000):
        sim.cycle(1)
        if not sim.bond_intact[0]:
            break
        fn, fs, _m = (a[0] for a in sim.bond_forces())
        fsmax = max(fsmax, abs(fs))
    assert sim.bond_state[0] == config.BOND_BROKEN_SHEAR
    assert fsmax == pytest.approx(coh * area + fn * math.tan(math.radians(fa)),
                                  rel=config.TOL_BOND_STRENGTH)
    assert sim.cracks.to_frame().iloc[0]["mode"] == "shear"
