"""Regular triangular lattice: E and ν against the lattice formula (REFERENCE.md §6.2)."""
import math

import numpy as np
import pytest

from sim import Simulation, Specimen, config
from sim.measure import lattice_elastic, moduli_from_strain
from sim.state import LFN

R = 1e-3
EBAR, KBAR = 50e9, 2.0
ESTAR, KSTAR = 30e9, 1.5


def _rows(sim, ny, k):
    ys = np.unique(np.round(sim.y / R, 6))
    return np.isin(np.round(sim.y / R, 6), ys[k])


def _strain(x0, y0, x, y, mask):
    """Least-squares uniform strain (exx, eyy) of the particles in ``mask``."""
    a = np.c_[x0[mask], y0[mask], np.ones(mask.sum())]
    ux = np.linalg.lstsq(a, (x - x0)[mask], rcond=None)[0]
    uy = np.linalg.lstsq(a, (y - y0)[mask], rcond=None)[0]
    return ux[0], uy[1], 0.5 * (ux[1] + uy[0])


def _interior(sim, s, margin):
    x, y = sim.x, sim.y
    return ((x > x.min() + margin * s) & (x < x.max() - margin * s)
            & (y > y.min() + margin * s) & (y < y.max() - margin * s))


def test_uniaxial_bonds_only():
    """Neighbours 2R(1 + 2e-3) apart: only the parallel bonds act (kn = Ē t, ks = kn/κ̄)."""
    nx, ny = 24, 28
    spec = Specimen.lattice(nx, ny, R, gap=2e-3, pb_emod=EBAR, pb_kratio=KBAR, emod=ESTAR,
                            kratio=KSTAR)
    s = 2 * R * (1 + 2e-3)
    sim = Simulation(spec, damping=0.7)
    x0, y0 = sim.x.copy(), sim.y.copy()
    yc = 0.5 * (y0.min() + y0.max())
    # affine compression eps = -1e-4 in y in 400 steps, then rollers on top and bottom
    eps, k = -1e-4, 400
    rate = eps / (k * sim.dt)
    allp = np.arange(sim.n_particles)
    sim.fix_velocity(allp, 0.0, rate * (sim.y - yc), 0.0)
    sim.cycle(k)
    sim.free(allp)
    ends = _rows(sim, ny, [0, -1])
    sim.fix_velocity(ends, None, 0.0)
    sim.fix_velocity([0], 0.0, 0.0)  # no rigid drift
    ratio = sim.solve(1e-7, max_steps=60000)
    assert ratio < 1e-7
    inner = _interior(sim, s, 4)
    exx, eyy, _ = _strain(x0, y0, sim.x, sim.y, inner)
    area = inner.sum() * math.sqrt(3) / 2 * s * s
    sig = sim.stress(np.nonzero(inner)[0], area)
    e_ref, nu_ref = lattice_elastic(EBAR, EBAR / KBAR)
    assert eyy == pytest.approx(eps, rel=0.02)
    assert abs(sig[0, 0]) < 5e-3 * abs(sig[1, 1])     # uniaxial: ~no lateral stress inside
    e_sim, nu_sim = moduli_from_strain(sig, exx, eyy)
    assert e_sim == pytest.approx(e_ref, rel=config.TOL_LATTICE_MODULUS)
    assert nu_sim == pytest.approx(nu_ref, rel=config.TOL_LATTICE_MODULUS)
    # the plain ratios, with the free-edge bias of a finite lattice (~1.6 % on nu here)
    assert sig[1, 1] / -eyy == pytest.approx(e_ref, rel=config.TOL_LATTICE_MODULUS)
    assert -exx / eyy == pytest.approx(nu_ref, rel=0.025)
    # the reaction on the top row agrees with the interior stress (section width ~ nx * s;
    # the free zig-zag edges make the effective width a few % uncertain)
    fy = sim.group_force(np.nonzero(_rows(sim, ny, [-1]))[0])[1]
    assert fy / (nx * s) == pytest.approx(sig[1, 1], rel=0.05)


def test_linear_plus_bond_under_isotropic_precompression():
    """Touching lattice, every contact kept closed: kn = (E* + Ē)t, ks = E*t/κ* + Ēt/κ̄."""
    nx, ny = 16, 18
    spec = Specimen.lattice(nx, ny, R, gap=0.0, pb_emod=EBAR, pb_kratio=KBAR, emod=ESTAR,
                            kratio=KSTAR, fric=1.0)
    s = 2 * R
    sim = Simulation(spec, damping=0.7)
    allp = np.arange(sim.n_particles)
    xc, yc = sim.x.mean(), sim.y.mean()
    k = 400
    # 1) isotropic compression -2e-4 (affine, all particles driven)
    e_iso = -2e-4
    rate = e_iso / (k * sim.dt)
    sim.fix_velocity(allp, rate * (sim.x - xc), rate * (sim.y - yc), 0.0)
    sim.cycle(k)
    inner = _interior(sim, s, 4)
    idx = np.nonzero(inner)[0]
    area = inner.sum() * math.sqrt(3) / 2 * s * s
    sig1 = sim.stress(idx, area)
    xa, ya = sim.x.copy(), sim.y.copy()
    # 2) pure shear increment +-5e-5 on the boundary, interior free
    e_sh = 5e-5
    rate = e_sh / (k * sim.dt)
    sim.free(allp)
    edge = ~_interior(sim, s, 2)
    sim.fix_velocity(edge, rate * (sim.x[edge] - xc), -rate * (sim.y[edge] - yc), 0.0)
    sim.cycle(k)
    sim.fix_velocity(edge, 0.0, 0.0, 0.0)
    assert sim.solve(1e-7, max_steps=40000) < 1e-7
    sig2 = sim.stress(idx, area)
    dxx, dyy, _ = _strain(xa, ya, sim.x, sim.y, inner)
    # 2D bulk and shear moduli (compression-positive stress, extension-positive strain)
    bulk = -0.5 * (sig1[0, 0] + sig1[1, 1]) / (2 * e_iso)
    shear = -(sig2[0, 0] - sig1[0, 0] - (sig2[1, 1] - sig1[1, 1])) / (2 * (dxx - dyy))
    e_sim = 4 * bulk * shear / (bulk + shear)
    nu_sim = (bulk - shear) / (bulk + shear)
    kn = ESTAR + EBAR
    ks = ESTAR / KSTAR + EBAR / KBAR
    e_ref, nu_ref = lattice_elastic(kn, ks)
    assert bulk == pytest.approx(math.sqrt(3) / 2 * kn, rel=config.TOL_LATTICE_MODULUS)
    assert e_sim == pytest.approx(e_ref, rel=config.TOL_LATTICE_MODULUS)
    assert nu_sim == pytest.approx(nu_ref, rel=config.TOL_LATTICE_MODULUS)
    # every ball-ball contact stayed closed (bonded pairs carry their linear part themselves)
    assert sim.state.nc == 0 and np.all(sim.state.bf[LFN] > 0)
