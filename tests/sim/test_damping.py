"""Local damping: a 1-DOF oscillation decays by (1 - alpha)/(1 + alpha) per cycle (REFERENCE §5)."""
import numpy as np
import pytest
from _sim_fixtures import disks

from sim import Simulation, config
from sim.damping import local_damping, ratio_from_restitution, restitution_from_ratio


def test_local_damping_law():
    assert local_damping(2.0, 1.0, 0.7) == pytest.approx(-1.4)
    assert local_damping(-2.0, -3.0, 0.7) == pytest.approx(1.4)
    assert local_damping(2.0, 0.0, 0.7) == 0.0
    assert ratio_from_restitution(restitution_from_ratio(0.3)) == pytest.approx(0.3)


@pytest.mark.parametrize("alpha", [0.1, 0.3, 0.7])
def test_one_dof_decay_per_cycle(alpha):
    R = 1e-3
    s = disks([0.0, 2 * R * (1 + 2e-3)], [0.0, 0.0], R, pb_emod=(50e9,), bonds=[(0, 1)])
    # ~250 steps per period (the rotational DOF, held here, sets the critical step)
    sim = Simulation(s, damping=alpha, timestep_factor=0.02)
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    sim.fix_velocity([1], None, 0.0, 0.0)
    sim.set_velocity([1], 1e-3, 0.0)
    x0 = sim.x[1]
    u = []
    for _ in range(1500):
        sim.cycle(1)
        u.append(sim.x[1] - x0)
    u = np.array(u)
    # extremes: velocity sign changes
    v = np.diff(u)
    ext = np.nonzero(np.sign(v[1:]) != np.sign(v[:-1]))[0] + 1
    amp = np.abs(u[ext])
    ratio = amp[2:] / amp[:-2]
    want = (1 - alpha) / (1 + alpha)
    assert len(ratio) >= 2
    assert len(ratio) >= 4
    np.testing.assert_allclose(ratio[:4], want, rtol=config.TOL_DAMPING_DECAY)
