"""Observables: energies, the unbalanced-force ratio, and the analytic reference values used by
``gbmsim verify`` (REFERENCE.md §6)."""
from __future__ import annotations

import math

import numpy as np

from .state import (C_FN, C_FS, C_FX, C_FY, C_KN, C_KS, FM, FN, FS, FX, FY, INERTIA, INVI,
                    INVM, KNA, KNI, KSA, MASS, MB, Q_FN, Q_FS, Q_KN, Q_KS, UN, VX, VY, W, BFX,
                    BFY)


def energies(state, dt):
    """Kinetic and strain energies, J.

    Kinetic energy uses the time-centred velocity v^n = v^{n-1/2} + ½ (F^n/m) Δt so that it pairs
    with the strain energy of the forces at x^n (exact for undamped linear systems).

    Returns
    -------
    dict
        ``kinetic, strain_bond, strain_contact, strain_wall``.
    """
    pf = state.pf
    vx = pf[VX] + 0.5 * pf[FX] * pf[INVM] * dt * ((state.fix & 1) == 0)
    vy = pf[VY] + 0.5 * pf[FY] * pf[INVM] * dt * ((state.fix & 2) == 0)
    w = pf[W] + 0.5 * pf[FM] * pf[INVI] * dt * ((state.fix & 4) == 0)
    kin = 0.5 * float(np.sum(pf[MASS] * (vx * vx + vy * vy) + pf[INERTIA] * w * w))
    bf = state.bf
    intact = state.bstate == 0
    pb = (state.bkind == 0) & intact
    sj = state.bkind == 1
    e_pb = np.sum((bf[FN][pb] ** 2 / bf[KNA][pb] + bf[FS][pb] ** 2 / bf[KSA][pb]
                   + bf[MB][pb] ** 2 / bf[KNI][pb]) * 0.5)
    unp = np.where(intact[sj], bf[UN][sj], np.maximum(bf[UN][sj], 0.0))
    e_sj = np.sum(0.5 * bf[KNA][sj] * unp ** 2 + 0.5 * bf[FS][sj] ** 2 / bf[KSA][sj])
    nc = state.nc
    cf = state.cf
    fn = cf[C_FN, :nc]
    e_c = np.sum(0.5 * fn ** 2 / cf[C_KN, :nc] + 0.5 * cf[C_FS, :nc] ** 2 / cf[C_KS, :nc])
    nq = state.nq
    qf = state.qf
    e_w = np.sum(0.5 * qf[Q_FN, :nq] ** 2 / qf[Q_KN, :nq] + 0.5 * qf[Q_FS, :nq] ** 2 / qf[Q_KS, :nq])
    return {"kinetic": kin, "strain_bond": float(e_pb + e_sj), "strain_contact": float(e_c),
            "strain_wall": float(e_w)}


def unbalanced_ratio(state):
    """Mean unbalanced force over mean contact force (PFC ``mech ratio-average``).

    Unbalanced force = |sum of contact forces| on every particle with no prescribed velocity;
    contact force = |F| of every intact bond, touching contact and touching wall contact.
    Returns 0 when nothing carries force.
    """
    pf = state.pf
    free = (state.fix & 3) == 0
    if not np.any(free):
        return 0.0
    unb = np.mean(np.hypot(pf[FX][free], pf[FY][free]))
    mags = [np.hypot(state.bf[BFX], state.bf[BFY])[(state.bstate == 0) | (state.bkind == 1)]]
    nc = state.nc
    fc = np.hypot(state.cf[C_FX, :nc], state.cf[C_FY, :nc])
    mags.append(fc[fc > 0])
    fq = np.abs(state.qf[Q_FN, :state.nq])
    mags.append(fq[fq > 0])
    allf = np.concatenate(mags)
    allf = allf[allf > 0]
    if allf.size == 0:
        return 0.0 if unb == 0 else float("inf")
    return float(unb / np.mean(allf))


# --- analytic references (REFERENCE.md §6) ------------------------------------------------------

def collision_reference(m1, m2, kn, v0, beta):
    """Two-disk linear collision: duration t_c (s), restitution e, undamped peak overlap (m)."""
    mstar = m1 * m2 / (m1 + m2)
    wn = math.sqrt(kn / mstar)
    return (math.pi / (wn * math.sqrt(1.0 - beta * beta)),
            math.exp(-math.pi * beta / math.sqrt(1.0 - beta * beta)),
            v0 * math.sqrt(mstar / kn))


def lattice_elastic(kn, ks, t=1.0):
    """Regular triangular lattice, per-contact kn, ks (N/m): E (Pa) and ν.

    E = 2√3 kn(kn+ks)/((3kn+ks)t), ν = (kn−ks)/(3kn+ks).
    """
    return (2.0 * math.sqrt(3.0) * kn * (kn + ks) / ((3.0 * kn + ks) * t),
            (kn - ks) / (3.0 * kn + ks))


__all__ = ["energies", "unbalanced_ratio", "collision_reference", "lattice_elastic"]
