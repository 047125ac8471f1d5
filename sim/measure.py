"""Observables: energies, the unbalanced-force ratio, pair forces and the virial stress, and the
analytic reference values of ``gbmsim verify`` (:mod:`sim.verify`, REFERENCE.md §6)."""
from __future__ import annotations

import math

import numpy as np

from .state import (
    C_FN,
    C_FS,
    C_KN,
    C_KS,
    FM,
    FN,
    FS,
    FX,
    FY,
    INERTIA,
    INVI,
    INVM,
    KNA,
    KNI,
    KSA,
    LFN,
    LFS,
    LKN,
    LKS,
    MASS,
    MB,
    NJX,
    NJY,
    Q_FN,
    Q_FS,
    Q_KN,
    Q_KS,
    UN,
    VX,
    VY,
    W,
    X,
    Y,
)


def energies(state, dt, alpha=0.0):
    """Kinetic and strain energies, J.

    The kinetic energy of each degree of freedom is ½ m v^{n−1/2} v^{n+1/2}, with v^{n+1/2}
    the velocity the next step will produce from the current forces F^n (local damping ``alpha``
    included). With the strain energy of the forces at x^n this is the quantity the central
    difference scheme conserves exactly for an undamped linear system (a plain ½ m v² of either
    half-step velocity oscillates by O((ω Δt)²)).

    Returns
    -------
    dict
        ``kinetic, strain_bond, strain_contact, strain_wall``.
    """
    pf = state.pf
    kin = 0.0
    for vrow, frow, irow, mrow, bit in ((VX, FX, INVM, MASS, 1), (VY, FY, INVM, MASS, 2),
                                        (W, FM, INVI, INERTIA, 4)):
        v = pf[vrow]
        f = pf[frow]
        fd = -alpha * np.abs(f) * np.sign(v)
        vnext = np.where((state.fix & bit) == 0, v + (f + fd) * pf[irow] * dt, v)
        kin += 0.5 * float(np.sum(pf[mrow] * v * vnext))
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
    lin = np.nonzero(state.bkind == 0)[0]
    e_c += np.sum(0.5 * bf[LFN, lin] ** 2 / bf[LKN, lin] + 0.5 * bf[LFS, lin] ** 2 / bf[LKS, lin])
    nq = state.nq
    qf = state.qf
    e_w = np.sum(0.5 * qf[Q_FN, :nq] ** 2 / qf[Q_KN, :nq]
                 + 0.5 * qf[Q_FS, :nq] ** 2 / qf[Q_KS, :nq])
    return {"kinetic": kin, "strain_bond": float(e_pb + e_sj), "strain_contact": float(e_c),
            "strain_wall": float(e_w)}


def pair_forces(state):
    """Force vectors on particle j of every pair, from the stored pair state.

    Returns
    -------
    list of (i, j, fx, fy)
        Parallel-bonded pairs (bond F̄n n̂ + F̄s t̂ plus their linear contact part), smooth
        joints (Fn n̂j + Fs t̂j) and touching contacts (normal force incl. the normal dashpot,
        plus the shear spring force), N.
    """
    pf = state.pf
    x, y = pf[X], pf[Y]
    out = []
    bf = state.bf
    pb = state.bkind == 0
    for sel, jframe in ((np.nonzero(pb & ((bf[FN] != 0) | (bf[FS] != 0) | (bf[LFN] != 0)))[0],
                         False), (np.nonzero(state.bkind == 1)[0], True)):
        i, j = state.bi[sel], state.bj[sel]
        if jframe:
            nx, ny = bf[NJX, sel], bf[NJY, sel]
            fn, fs = bf[FN, sel], bf[FS, sel]
        else:
            dx, dy = x[j] - x[i], y[j] - y[i]
            d = np.hypot(dx, dy)
            nx, ny = dx / d, dy / d
            fn, fs = bf[FN, sel] + bf[LFN, sel], bf[FS, sel] + bf[LFS, sel]
        out.append((i, j, fn * nx - fs * ny, fn * ny + fs * nx))
    nc = state.nc
    sel = np.nonzero(state.cf[C_FN, :nc] != 0)[0]
    i, j = state.ci[sel], state.cj[sel]
    dx, dy = x[j] - x[i], y[j] - y[i]
    d = np.hypot(dx, dy)
    nx, ny = dx / d, dy / d
    fn, fs = state.cf[C_FN, sel], state.cf[C_FS, sel]
    out.append((i, j, fn * nx - fs * ny, fn * ny + fs * nx))
    return out


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
    mags = [np.hypot(fx, fy) for _i, _j, fx, fy in pair_forces(state)]
    fq = np.abs(state.qf[Q_FN, :state.nq])
    mags.append(fq[fq > 0])
    allf = np.concatenate(mags)
    allf = allf[allf > 0]
    if allf.size == 0:
        return 0.0 if unb == 0 else float("inf")
    return float(unb / np.mean(allf))


def virial_stress(state, mask, area, t=1.0):
    """Average stress of a particle set from its pair forces (Love–Weber virial), Pa.

    σ = (1/(A t)) Σ_pairs w_k l_k ⊗ F_k, with l = x_j − x_i, F the force on j, and weight
    w_k = (mask_i + mask_j)/2, so a pair counts fully when both particles are in the set.
    Compression positive. Wall contacts and the shear dashpot force are not included: keep the
    set away from walls.

    Parameters
    ----------
    state : State
    mask : (N,) bool
    area : float, m²
        Area the particles represent (e.g. cell area × count in a regular lattice).

    Returns
    -------
    sigma : (2, 2) ndarray of float64, symmetric.
    """
    pf = state.pf
    x, y = pf[X], pf[Y]
    m = mask.astype(float)
    sig = np.zeros((2, 2))
    for i, j, fx, fy in pair_forces(state):
        wgt = 0.5 * (m[i] + m[j])
        lx, ly = x[j] - x[i], y[j] - y[i]
        sig[0, 0] += np.sum(wgt * lx * fx)
        sig[1, 1] += np.sum(wgt * ly * fy)
        sig[0, 1] += np.sum(wgt * 0.5 * (lx * fy + ly * fx))
    sig[1, 0] = sig[0, 1]
    return sig / (area * t)


def moduli_from_strain(sigma, exx, eyy):
    """E (Pa) and ν of an isotropic 2D (plane-stress) solid from one measured state.

    Solves ε_xx = (s_xx − ν s_yy)/E, ε_yy = (s_yy − ν s_xx)/E with s = −σ (``sigma``
    compression positive, strains extension positive), so a small residual lateral stress
    (edges, platens) does not bias ν as the plain ratio −ε_xx/ε_yy would.
    """
    s = -np.asarray(sigma, float)
    e, nu = np.linalg.solve([[exx, s[1, 1]], [eyy, s[0, 0]]], [s[0, 0], s[1, 1]])
    return float(e), float(nu)


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


__all__ = ["energies", "unbalanced_ratio", "pair_forces", "virial_stress", "moduli_from_strain",
           "collision_reference", "lattice_elastic"]
