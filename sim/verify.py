"""``gbmsim verify``: short analytic checks of the engine (REFERENCE.md §6).

Kept apart from :mod:`sim.measure` (observables, imported by the engine) because the checks
run the engine itself.
"""
from __future__ import annotations

import numpy as np

from . import config
from .measure import collision_reference, lattice_elastic, moduli_from_strain
from .simulation import Simulation
from .specimen import Specimen

__all__ = ["verification_cases"]


def verification_cases():
    """Run the short analytic checks of REFERENCE.md §6 and return one dict per check.

    Each dict has ``check, measured, expected, rel_error, tolerance, ok``. Cases: two-disk
    collision duration and restitution (β = 0.3), parallel-bond tensile strength, local damping
    decay per cycle (α = 0.7), and E, ν of a gap-bonded triangular lattice under uniaxial stress.
    Tests in tests/sim/ cover more (these take a few seconds once compiled).
    """
    out = []

    def add(check, measured, expected, tol):
        err = abs(measured - expected) / abs(expected)
        out.append(dict(check=check, measured=float(measured), expected=float(expected),
                        rel_error=float(err), tolerance=tol, ok=bool(err <= tol)))

    def pair(r, gap, **kw):
        s = Specimen.lattice(2, 1, r, gap=gap, **kw)
        return s

    # 1. collision, beta = 0.3 (m1 = m2; kn = E* t)
    r, kn, beta = 0.1, 1e6, 0.3
    s = pair(r, 0.05, emod=kn, density=1.0 / (np.pi * r * r), pb_ten=0.0, pb_coh=0.0)
    s.bond_i, s.bond_j = s.bond_i[:0], s.bond_j[:0]
    s.bond_kind, s.joint_nx, s.joint_ny = s.bond_kind[:0], s.joint_nx[:0], s.joint_ny[:0]
    sim = Simulation(s, damping=0.0, dashpot_ratio=beta, timestep_factor=0.005)
    sim.set_velocity([0], 0.5, 0.0)
    sim.set_velocity([1], -0.5, 0.0)
    ov, tt = [], []
    while len(ov) < 20000:
        sim.cycle(1)
        ov.append(2 * r - (sim.x[1] - sim.x[0]))
        tt.append(sim.time)
        if ov[-1] < 0 < max(ov):
            break
    ov, tt = np.array(ov), np.array(tt)
    a, b = np.nonzero(ov > 0)[0][[0, -1]]
    t_in = tt[a - 1] + (tt[a] - tt[a - 1]) * -ov[a - 1] / (ov[a] - ov[a - 1])
    t_out = tt[b] + (tt[b + 1] - tt[b]) * -ov[b] / (ov[b + 1] - ov[b])
    tc, e, _ = collision_reference(1.0, 1.0, kn, 1.0, beta)
    add("collision duration (beta 0.3)", t_out - t_in, tc, config.TOL_COLLISION_DURATION)
    add("restitution (beta 0.3)", sim.vx[1] - sim.vx[0], e, config.TOL_RESTITUTION)

    # 2. parallel bond pulled apart
    rb, ebar, ten = 1e-3, 50e9, 20e6
    sim = Simulation(pair(rb, 2e-3, pb_emod=ebar, pb_ten=ten), damping=0.0)
    v = ten * 2 * rb / ebar / (2000 * sim.dt)
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    sim.fix_velocity([1], v, 0.0, 0.0)
    fmax = 0.0
    while sim.bond_intact[0] and sim.step < 5000:
        sim.cycle(1)
        if sim.bond_intact[0]:
            fmax = max(fmax, -sim.bond_forces()[0][0])
    add("parallel-bond tensile strength", fmax, ten * 2 * rb, config.TOL_BOND_STRENGTH)

    # 3. local damping, 1-DOF
    alpha = 0.7
    sim = Simulation(pair(rb, 2e-3, pb_emod=ebar), damping=alpha, timestep_factor=0.02)
    sim.fix_velocity([0], 0.0, 0.0, 0.0)
    sim.fix_velocity([1], None, 0.0, 0.0)
    sim.set_velocity([1], 1e-3, 0.0)
    x0 = sim.x[1]
    u = []
    for _ in range(1200):
        sim.cycle(1)
        u.append(sim.x[1] - x0)
    u = np.array(u)
    dv = np.diff(u)
    ext = np.nonzero(np.sign(dv[1:]) != np.sign(dv[:-1]))[0] + 1
    add("local damping decay per cycle (alpha 0.7)", abs(u[ext[2]] / u[ext[0]]),
        (1 - alpha) / (1 + alpha), config.TOL_DAMPING_DECAY)

    # 4. lattice E and nu (bonds only)
    nx, ny, kap = 20, 24, 2.0
    sp = 2 * rb * (1 + 2e-3)
    sim = Simulation(Specimen.lattice(nx, ny, rb, gap=2e-3, pb_emod=ebar, pb_kratio=kap))
    xs, ys = sim.x.copy(), sim.y.copy()
    allp = np.arange(sim.n_particles)
    eps, k = -1e-4, 400
    sim.fix_velocity(allp, 0.0, eps / (k * sim.dt) * (sim.y - ys.mean()), 0.0)
    sim.cycle(k)
    sim.free(allp)
    rows = np.round(ys / sp, 3)
    ends = (rows == rows.min()) | (rows == rows.max())
    sim.fix_velocity(ends, None, 0.0)
    sim.fix_velocity([0], 0.0, 0.0)
    sim.solve(1e-7, max_steps=60000)
    inner = ((xs > xs.min() + 4 * sp) & (xs < xs.max() - 4 * sp)
             & (ys > ys.min() + 4 * sp) & (ys < ys.max() - 4 * sp))
    m = np.c_[xs[inner], ys[inner], np.ones(inner.sum())]
    exx = np.linalg.lstsq(m, (sim.x - xs)[inner], rcond=None)[0][0]
    eyy = np.linalg.lstsq(m, (sim.y - ys)[inner], rcond=None)[0][1]
    sig = sim.stress(np.nonzero(inner)[0], inner.sum() * np.sqrt(3) / 2 * sp * sp)
    e_ref, nu_ref = lattice_elastic(ebar, ebar / kap)
    e_sim, nu_sim = moduli_from_strain(sig, exx, eyy)
    add("lattice Young's modulus (bonds only)", e_sim, e_ref, config.TOL_LATTICE_MODULUS)
    add("lattice Poisson's ratio (bonds only)", nu_sim, nu_ref, config.TOL_LATTICE_MODULUS)
    return out
