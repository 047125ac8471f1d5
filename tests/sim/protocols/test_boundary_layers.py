"""The whole-height strains of a compression test leave out boundary particles without a bond:
pressed by a platen such a particle slips into the packing, and its layer would read a strain
the specimen does not have (an unbonded corner particle moved 41 um against the platen's 12 um
on a 10 x 20 mm specimen)."""
import dataclasses
import types

import numpy as np
import pytest

from sim import Simulation, Specimen
from sim.protocols.ucs import compression_rig


def _unbond(s, k):
    keep = (s.bond_i != k) & (s.bond_j != k)
    return dataclasses.replace(s, **{f: getattr(s, f)[keep] for f in
                                     ("bond_i", "bond_j", "bond_kind", "joint_nx", "joint_ny")})


@pytest.fixture(scope="module")
def rig():
    s = Specimen.lattice(nx=8, ny=12, radius=1e-3, gap=2e-3)
    k = int(np.argmax(s.x + s.y))                   # the top-right corner particle
    u = _unbond(s, k)
    read, _ = compression_rig(u, u.x.copy(), u.y.copy(), u.box)
    return u, k, read, Simulation(u).state


def _moved(u, state, k, dx=0.0, dy=0.0):
    x, y = u.x.copy(), u.y.copy()
    x[k] += dx
    y[k] += dy
    return types.SimpleNamespace(x=x, y=y, state=state)


def test_an_unbonded_boundary_particle_moves_no_layer_strain(rig):
    u, k, read, state = rig
    assert read(_moved(u, state, k))["end_axial_strain"] == 0.0
    got = read(_moved(u, state, k, dx=-2e-4, dy=-2e-4))
    assert got["end_axial_strain"] == 0.0 and got["side_lateral_strain"] == 0.0


def test_bonded_boundary_particles_still_count(rig):
    u, k, read, state = rig
    top = int(np.argmax(np.where(np.arange(u.x.size) == k, -np.inf, u.y)))
    got = read(_moved(u, state, top, dy=-2e-4))
    layer = np.sum(u.y + u.r >= u.box[3] - 0.25 * u.r.mean())     # the top layer, k included
    h = u.y[u.y + u.r >= u.box[3] - 0.25 * u.r.mean()].mean() - \
        u.y[u.y - u.r <= u.box[2] + 0.25 * u.r.mean()].mean()
    assert got["end_axial_strain"] == pytest.approx(2e-4 / (layer - 1) / h, rel=1e-6)
