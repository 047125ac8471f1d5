"""Central-difference integration, the compiled step loop and the critical time step.

One ``njit(parallel=True)`` function, :func:`run_steps`, runs many steps without returning to
Python (STYLE.md §7): per step one particle pass that gathers the pair forces, applies local
damping and integrates, then a bond pass, a joint pass, a contact pass (each writing per-pair
forces, race-free) and a serial wall pass. Passes a scene does not have (joints, walls, dashpots) are
skipped once per step; no per-contact branch tests for them. It returns early when the Verlet
list needs a rebuild or the run became unstable.
"""
import numpy as np

from . import config
from ._jit import njit, prange
from .damping import local_damping
from .forces import contact_range, contact_range_dashpot, pb_range, sj_range
from .state import (ARI, BFX, BFY, BRK_NX, BRK_NY, BRK_STEP, BRK_X, BRK_Y, C_CN, C_CS, C_FN,
                    C_FS, C_FX, C_FY, C_KN, C_KS, C_MU, COHA, FM, FN, FRIC, FS, FVX, FVY, FW, FX,
                    FY, INVI, INVM, KNA, KNI, KSA, MB, NJX, NJY, Q_FN, Q_FS, Q_KN, Q_KS, Q_MU, R,
                    TANDIL, TANFA, TENA, UN, VX, VY, W, W_DISP, WFM, WFX, WFY, X, X0, Y, Y0)
from .walls import wall_forces, wall_motion


@njit
def particle_range(lo, hi, dt, alpha, step_lim, has_walls, x, y, vx, vy, w, fx, fy, fm, r,
                   invm, invi, x0, y0, fvx, fvy, fw, wfx, wfy, wfm, fix, bptr, bref, bfx, bfy,
                   bmom, cptr, cref, cfx, cfy, cmom):
    """Gather pair forces, damp and integrate particles ``lo:hi`` (writes fx, fy, fm, v, w, x).

    Returns
    -------
    maxd2 : float
        Largest squared displacement since the last rebuild, m².
    bad : int
        First particle that moved more than ``step_lim`` × R in this step (or NaN), else -1.
    work : float
        Work done by local damping in this step, J (negative).
    """
    maxd2 = 0.0
    bad = -1
    work = 0.0
    for p in range(lo, hi):
        sx = 0.0
        sy = 0.0
        sm = 0.0
        for q in range(bptr[p], bptr[p + 1]):
            ref = bref[q]
            k = ref >> 1
            s = 2.0 * (ref & 1) - 1.0
            sx += s * bfx[k]
            sy += s * bfy[k]
            sm += bmom[ref]
        for q in range(cptr[p], cptr[p + 1]):
            ref = cref[q]
            k = ref >> 1
            s = 2.0 * (ref & 1) - 1.0
            sx += s * cfx[k]
            sy += s * cfy[k]
            sm += cmom[ref]
        if has_walls:
            sx += wfx[p]
            sy += wfy[p]
            sm += wfm[p]
        fx[p] = sx
        fy[p] = sy
        fm[p] = sm
        f = fix[p]
        if f & 1:
            vx[p] = fvx[p]
        else:
            u = vx[p]
            d = local_damping(sx, u, alpha)
            vx[p] = u + (sx + d) * invm[p] * dt
            work += 0.5 * dt * d * (u + vx[p])
        if f & 2:
            vy[p] = fvy[p]
        else:
            u = vy[p]
            d = local_damping(sy, u, alpha)
            vy[p] = u + (sy + d) * invm[p] * dt
            work += 0.5 * dt * d * (u + vy[p])
        if f & 4:
            w[p] = fw[p]
        else:
            u = w[p]
            d = local_damping(sm, u, alpha)
            w[p] = u + (sm + d) * invi[p] * dt
            work += 0.5 * dt * d * (u + w[p])
        ux = vx[p] * dt
        uy = vy[p] * dt
        x[p] += ux
        y[p] += uy
        if not (abs(ux) + abs(uy) <= step_lim * r[p]) and bad < 0:
            bad = p
        ex = x[p] - x0[p]
        ey = y[p] - y0[p]
        d2 = ex * ex + ey * ey
        if d2 > maxd2:
            maxd2 = d2
    return maxd2, bad, work


@njit
def gather_range(lo, hi, has_walls, fx, fy, fm, wfx, wfy, wfm, bptr, bref, bfx, bfy, bmom, cptr,
                 cref, cfx, cfy, cmom):
    """Sum the current pair (and wall) forces on particles ``lo:hi`` into fx, fy, fm only."""
    for p in range(lo, hi):
        sx = 0.0
        sy = 0.0
        sm = 0.0
        for q in range(bptr[p], bptr[p + 1]):
            ref = bref[q]
            k = ref >> 1
            s = 2.0 * (ref & 1) - 1.0
            sx += s * bfx[k]
            sy += s * bfy[k]
            sm += bmom[ref]
        for q in range(cptr[p], cptr[p + 1]):
            ref = cref[q]
            k = ref >> 1
            s = 2.0 * (ref & 1) - 1.0
            sx += s * cfx[k]
            sy += s * cfy[k]
            sm += cmom[ref]
        if has_walls:
            sx += wfx[p]
            sy += wfy[p]
            sm += wfm[p]
        fx[p] = sx
        fy[p] = sy
        fm[p] = sm


@njit(parallel=True)
def run_steps(nsteps, step0, dt, alpha, nchunks, skin, step_lim, overlap_lim, t, servo_alpha,
              pf, fix, bi, bj, bstate, bf, bmom, bptr, bref, npb, ci, cj, cf, cmom, cptr, cref,
              nc, use_dash, wf, qp, qw, qf, nq, refresh, info):
    """Run up to ``nsteps`` steps in place (PFC cycle order).

    Each step: (1) particle pass: gather the pair forces F^n, local damping with v^{n-1/2},
    v^{n+1/2} and x^{n+1}; (2) wall motion (servo from the wall forces F^n); (3) force passes
    at x^{n+1} with increments Δδ = V^{n+1/2} Δt: parallel bonds, smooth joints, contacts,
    walls. After a call the stored pair forces and the particle sums fx, fy, fm belong to the
    current positions.

    Parameters
    ----------
    nsteps, step0 : int
        Steps to run; number of steps completed before (break events are stamped step0 + s + 1).
    dt, alpha : float
        Time step (s) and local damping coefficient.
    nchunks : int
        Static split of every pass (number of threads).
    skin : float, m
        Verlet skin; the loop stops for a rebuild when the largest particle displacement since
        the last build exceeds skin/2, or that plus the largest wall displacement exceeds skin.
    step_lim, overlap_lim : float
        Instability bounds (config.MAX_STEP_DISPLACEMENT, config.MAX_OVERLAP).
    t, servo_alpha : float
        Thickness (m) and servo relaxation factor.
    pf, fix, bi ... qf, nq
        The :class:`sim.state.State` tables (written in place).
    use_dash : bool
        Contacts carry viscous dashpots (cf rows C_CN, C_CS).
    refresh : bool
        First re-evaluate the contact and wall forces at the current positions with zero
        increments (after a list rebuild or at the start).
    info : (8,) float64, written
        [bond breaks, cause code, worst index, damping work (added), worst overlap ratio,
        max displacement, unused, unused].

    Returns
    -------
    done : int
        Steps completed.
    status : int
        config.STATUS_DONE, STATUS_REBUILD or STATUS_UNSTABLE.
    """
    x = pf[X]
    y = pf[Y]
    vx = pf[VX]
    vy = pf[VY]
    w = pf[W]
    r = pf[R]
    n = x.size
    nb = bi.size
    nsj = nb - npb
    nw = wf.shape[0]
    has_walls = nw > 0
    half = 0.5 * skin
    dres = np.zeros(nchunks)
    bres = np.zeros(nchunks, np.int64)
    wres = np.zeros(nchunks)
    ores = np.zeros(nchunks)
    kres = np.zeros(nchunks, np.int64)
    maxd2 = 0.0
    s = -1 if refresh else 0
    while s < nsteps:
        moving = s >= 0
        step = step0 + s + 1
        dti = dt if moving else 0.0
        if moving:
            # 1. particles: gather, damp, integrate
            for c in prange(nchunks):
                lo = (n * c) // nchunks
                hi = (n * (c + 1)) // nchunks
                dres[c], kres[c], wres[c] = particle_range(
                    lo, hi, dt, alpha, step_lim, has_walls, x, y, vx, vy, w, pf[FX], pf[FY],
                    pf[FM], r, pf[INVM], pf[INVI], pf[X0], pf[Y0], pf[FVX], pf[FVY], pf[FW],
                    pf[WFX], pf[WFY], pf[WFM], fix, bptr, bref, bf[BFX], bf[BFY], bmom, cptr,
                    cref, cf[C_FX], cf[C_FY], cmom)
            maxd2 = 0.0
            bad = -1
            for c in range(nchunks):
                info[3] += wres[c]
                if dres[c] > maxd2:
                    maxd2 = dres[c]
                if bad < 0 and kres[c] >= 0:
                    bad = kres[c]
            if bad >= 0:
                info[1] = 1.0 if (vx[bad] != vx[bad] or vy[bad] != vy[bad] or w[bad] != w[bad]
                                  or x[bad] != x[bad] or y[bad] != y[bad]) else 2.0
                info[2] = bad
                return s, 2
            # 2. walls move
            if has_walls:
                wall_motion(dt, t, servo_alpha, wf)
            # 3a. parallel bonds
            if npb > 0:
                for c in prange(nchunks):
                    lo = (npb * c) // nchunks
                    hi = (npb * (c + 1)) // nchunks
                    bres[c] = pb_range(lo, hi, step, dt, x, y, vx, vy, w, r, bi, bj, bstate,
                                       bf[FN], bf[FS], bf[MB], bf[KNA], bf[KSA], bf[KNI],
                                       bf[ARI], bf[TENA], bf[COHA], bf[TANFA], bf[BFX],
                                       bf[BFY], bmom, bf[BRK_X], bf[BRK_Y], bf[BRK_NX],
                                       bf[BRK_NY], bf[BRK_STEP])
                info[0] += bres.sum()
            # 3b. smooth joints
            if nsj > 0:
                for c in prange(nchunks):
                    lo = npb + (nsj * c) // nchunks
                    hi = npb + (nsj * (c + 1)) // nchunks
                    bres[c] = sj_range(lo, hi, step, dt, x, y, vx, vy, w, r, bi, bj, bstate,
                                       bf[FN], bf[FS], bf[UN], bf[KNA], bf[KSA], bf[TENA],
                                       bf[COHA], bf[TANFA], bf[FRIC], bf[TANDIL], bf[NJX],
                                       bf[NJY], bf[BFX], bf[BFY], bmom, bf[BRK_X], bf[BRK_Y],
                                       bf[BRK_NX], bf[BRK_NY], bf[BRK_STEP])
                info[0] += bres.sum()
        # 3c. contacts (bonded pairs included for their linear part)
        worst = 0.0
        kworst = -1
        if nc > 0:
            if use_dash:
                for c in prange(nchunks):
                    lo = (nc * c) // nchunks
                    hi = (nc * (c + 1)) // nchunks
                    ores[c], kres[c] = contact_range_dashpot(
                        lo, hi, dti, x, y, vx, vy, w, r, ci, cj, cf[C_FS], cf[C_KN], cf[C_KS],
                        cf[C_MU], cf[C_CN], cf[C_CS], cf[C_FX], cf[C_FY], cf[C_FN], cmom)
            else:
                for c in prange(nchunks):
                    lo = (nc * c) // nchunks
                    hi = (nc * (c + 1)) // nchunks
                    ores[c], kres[c] = contact_range(
                        lo, hi, dti, x, y, vx, vy, w, r, ci, cj, cf[C_FS], cf[C_KN], cf[C_KS],
                        cf[C_MU], cf[C_FX], cf[C_FY], cf[C_FN], cmom)
            for c in range(nchunks):
                if ores[c] > worst:
                    worst = ores[c]
                    kworst = kres[c]
        # 3d. walls
        wworst = 0.0
        qworst = -1
        if has_walls:
            wworst, qworst = wall_forces(dti, x, y, vx, vy, w, r, pf[WFX], pf[WFY], pf[WFM], wf,
                                         qp, qw, nq, qf[Q_FS], qf[Q_KN], qf[Q_KS], qf[Q_MU],
                                         qf[Q_FN])
        info[4] = max(worst, wworst)
        if worst > overlap_lim:
            info[1] = 3.0
            info[2] = kworst
            return s + 1, 2
        if wworst > overlap_lim:
            info[1] = 4.0
            info[2] = qworst
            return s + 1, 2
        status = 0
        if moving:
            maxd = np.sqrt(maxd2)
            info[5] = maxd
            if maxd > half:
                status = 1
            elif has_walls:
                wmax = 0.0
                for k in range(nw):
                    if wf[k, W_DISP] > wmax:
                        wmax = wf[k, W_DISP]
                if maxd + wmax > skin:
                    status = 1
        s += 1
        if status == 1 or s >= nsteps:
            # leave fx, fy, fm = F at the current positions (read by energies, group forces)
            for c in prange(nchunks):
                lo = (n * c) // nchunks
                hi = (n * (c + 1)) // nchunks
                gather_range(lo, hi, has_walls, pf[FX], pf[FY], pf[FM], pf[WFX], pf[WFY],
                             pf[WFM], bptr, bref, bf[BFX], bf[BFY], bmom, cptr, cref, cf[C_FX],
                             cf[C_FY], cmom)
            if status == 1:
                return s, 1
    return nsteps, 0


def critical_timestep(state, t=config.THICKNESS):
    """Per-particle critical time step √(m/k_tran), √(I/k_rot) (REFERENCE.md §5), s.

    Stiffness sums run over intact bonds, every pair in the Verlet list (touching or not: a
    conservative bound for contacts that form before the next rebuild) and wall candidates; per
    contact the larger of normal and shear stiffness is taken.

    Returns
    -------
    dt_p : (N,) ndarray of float64
        Critical step per particle (inf for a particle with no stiffness).
    k_tran, k_rot : (N,) ndarray of float64
    """
    n = state.n
    r = state.pf[R]
    ktr = np.zeros(n)
    krot = np.zeros(n)
    intact = state.bstate == 0
    sj = state.bkind == 1
    live = intact | sj  # an unbonded smooth joint still has frictional stiffness
    for ends in (state.bi, state.bj):
        e = ends[live]
        kna = state.bf[KNA][live]
        ksa = state.bf[KSA][live]
        kni = state.bf[KNI][live] * intact[live]
        ktr += np.bincount(e, np.maximum(kna, ksa), minlength=n)
        krot += np.bincount(e, ksa * r[e] ** 2 + kni, minlength=n)
    nc = state.nc
    if nc:
        kn = state.cf[C_KN, :nc]
        ks = state.cf[C_KS, :nc]
        for ends in (state.ci[:nc], state.cj[:nc]):
            ktr += np.bincount(ends, np.maximum(kn, ks), minlength=n)
            krot += np.bincount(ends, ks * r[ends] ** 2, minlength=n)
    nq = state.nq
    if nq:
        e = state.qp[:nq]
        ktr += np.bincount(e, np.maximum(state.qf[Q_KN, :nq], state.qf[Q_KS, :nq]), minlength=n)
        krot += np.bincount(e, state.qf[Q_KS, :nq] * r[e] ** 2, minlength=n)
    from .state import INERTIA, MASS
    with np.errstate(divide="ignore"):
        dt_p = np.minimum(np.sqrt(state.pf[MASS] / ktr), np.sqrt(state.pf[INERTIA] / krot))
    return dt_p, ktr, krot


__all__ = ["run_steps", "particle_range", "critical_timestep", "C_FS", "FX", "FY", "FM"]
