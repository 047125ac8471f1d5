"""Central-difference integration, the compiled step loop and the critical time step.

One ``njit(parallel=True)`` function, :func:`run_steps`, runs many steps without returning to
Python (STYLE.md §7). Per step: a particle pass (sum the per-thread force buffers, local damping,
integration), wall motion, one pass over all pairs (parallel-bonded pairs, smooth joints, Verlet
contacts; each chunk scatters into its own force buffer, race-free) and a short serial wall
pass. Passes a scene does not have (joints, walls, dashpots) are skipped once per step; no
per-contact branch tests for them. It returns early when the Verlet list needs a rebuild or the
run became unstable.
"""
import numpy as np

from . import config
from ._jit import njit, prange
from .damping import local_damping
from .forces import contact_range, contact_range_dashpot, pb_range, sj_range
from .state import (
    ARI,
    BRK_NX,
    BRK_NY,
    BRK_STEP,
    BRK_X,
    BRK_Y,
    C_CN,
    C_CS,
    C_FN,
    C_FS,
    C_KN,
    C_KS,
    C_MU,
    COHA,
    FM,
    FN,
    FRIC,
    FS,
    FVX,
    FVY,
    FW,
    FX,
    FY,
    INVI,
    INVM,
    KNA,
    KNI,
    KSA,
    LCN,
    LCS,
    LFN,
    LFS,
    LKN,
    LKS,
    LMU,
    MB,
    NJX,
    NJY,
    Q_FN,
    Q_FS,
    Q_KN,
    Q_KS,
    Q_MU,
    TANDIL,
    TANFA,
    TENA,
    UN,
    VX,
    VY,
    W_DISP,
    X0,
    Y0,
    R,
    W,
    X,
    Y,
)
from .walls import wall_forces, wall_motion


@njit
def particle_range(lo, hi, nrows, dt, alpha, step_lim, fx, fy, fm, invm, invi, x0, y0, fvx, fvy,
                   fw, fix, acc, kin, sleep, sleep_d, sleep_ratio, sleep_steps, quiet):
    """Sum the force buffers, damp and integrate particles ``lo:hi``.

    Reads and zeroes ``acc[:nrows, 4p:4p+4]``; writes fx, fy, fm (the unbalanced contact
    force and moment) and integrates in the packed ``kin[8p:8p+7]`` = (x, y, vx, vy, w, r,
    asleep), one cache line per particle, which the pair passes read. During a
    :func:`run_steps` call ``kin`` is the only copy of x, y, vx, vy, w that moves; the
    particle table rows are written back when the call returns (:func:`sync_range`).

    With ``sleep``: a free particle that moved less than ``sleep_d`` per step with an unbalanced
    force below ``sleep_ratio`` × the sum of its pair-force magnitudes for ``sleep_steps``
    consecutive steps falls asleep (v = w = 0, fix bit 8, ``kin[8p+6]`` = 1); a sleeping
    particle is not integrated and wakes when a pair or wall contact around it moved more than
    ``sleep_d`` in the last step (a vote in slot 3 of its buffer).

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
        o = 4 * p
        sx = acc[0, o]
        sy = acc[0, o + 1]
        sm = acc[0, o + 2]
        s3 = acc[0, o + 3]
        acc[0, o] = 0.0
        acc[0, o + 1] = 0.0
        acc[0, o + 2] = 0.0
        acc[0, o + 3] = 0.0
        for c in range(1, nrows):
            sx += acc[c, o]
            sy += acc[c, o + 1]
            sm += acc[c, o + 2]
            s3 += acc[c, o + 3]
            acc[c, o] = 0.0
            acc[c, o + 1] = 0.0
            acc[c, o + 2] = 0.0
            acc[c, o + 3] = 0.0
        fx[p] = sx
        fy[p] = sy
        fm[p] = sm
        k = 8 * p
        f = fix[p]
        if sleep and f & 8:
            if s3 > 0.0:
                # woken: integrate from the next step, once all its pairs are summed again
                fix[p] = f & ~8
                quiet[p] = 0
                kin[k + 6] = 0.0
            continue
        if f & 1:
            vxn = fvx[p]
        else:
            u = kin[k + 2]
            d = local_damping(sx, u, alpha)
            vxn = u + (sx + d) * invm[p] * dt
            work += 0.5 * dt * d * (u + vxn)
        if f & 2:
            vyn = fvy[p]
        else:
            u = kin[k + 3]
            d = local_damping(sy, u, alpha)
            vyn = u + (sy + d) * invm[p] * dt
            work += 0.5 * dt * d * (u + vyn)
        if f & 4:
            wn = fw[p]
        else:
            u = kin[k + 4]
            d = local_damping(sm, u, alpha)
            wn = u + (sm + d) * invi[p] * dt
            work += 0.5 * dt * d * (u + wn)
        ux = vxn * dt
        uy = vyn * dt
        xn = kin[k] + ux
        yn = kin[k + 1] + uy
        rp = kin[k + 5]
        if not (abs(ux) + abs(uy) <= step_lim * rp) and bad < 0:
            bad = p
        if sleep and f == 0:
            if (abs(ux) + abs(uy) + abs(wn) * rp * dt < sleep_d
                    and abs(sx) + abs(sy) <= sleep_ratio * s3):
                quiet[p] += 1
                if quiet[p] >= sleep_steps:
                    fix[p] = 8
                    vxn = 0.0
                    vyn = 0.0
                    wn = 0.0
                    kin[k + 6] = 1.0
            else:
                quiet[p] = 0
        kin[k] = xn
        kin[k + 1] = yn
        kin[k + 2] = vxn
        kin[k + 3] = vyn
        kin[k + 4] = wn
        ex = xn - x0[p]
        ey = yn - y0[p]
        d2 = ex * ex + ey * ey
        if d2 > maxd2:
            maxd2 = d2
    return maxd2, bad, work


@njit
def sync_range(lo, hi, x, y, vx, vy, w, kin):
    """Copy the packed kinematics of particles ``lo:hi`` back to the particle table rows."""
    for p in range(lo, hi):
        k = 8 * p
        x[p] = kin[k]
        y[p] = kin[k + 1]
        vx[p] = kin[k + 2]
        vy[p] = kin[k + 3]
        w[p] = kin[k + 4]


@njit
def particles_chunk(lo, hi, nrows, dt, alpha, step_lim, fx, fy, fm, invm, invi, x0, y0, fvx,
                    fvy, fw, fix, acc, kin, sleep, sleep_d, sleep_ratio, sleep_steps, quiet):
    """:func:`particle_range` with the number of buffer rows as a compile-time constant for 1
    and 2 rows (the usual thread counts), so the row sum is unrolled: with ``nrows`` known
    only at run time the pass cost 12 instead of 7 ns per particle (20k, one thread)."""
    if nrows == 1:
        return particle_range(lo, hi, 1, dt, alpha, step_lim, fx, fy, fm,
                              invm, invi, x0, y0, fvx, fvy, fw, fix, acc, kin, sleep, sleep_d,
                              sleep_ratio, sleep_steps, quiet)
    if nrows == 2:
        return particle_range(lo, hi, 2, dt, alpha, step_lim, fx, fy, fm,
                              invm, invi, x0, y0, fvx, fvy, fw, fix, acc, kin, sleep, sleep_d,
                              sleep_ratio, sleep_steps, quiet)
    return particle_range(lo, hi, nrows, dt, alpha, step_lim, fx, fy, fm,
                          invm, invi, x0, y0, fvx, fvy, fw, fix, acc, kin, sleep, sleep_d,
                          sleep_ratio, sleep_steps, quiet)


@njit
def gather_range(lo, hi, nrows, fx, fy, fm, acc):
    """Sum the force buffers of particles ``lo:hi`` into fx, fy, fm and leave the sum in row 0
    (canonical form: the other rows zero), without moving anything."""
    for p in range(lo, hi):
        o = 4 * p
        sx = acc[0, o]
        sy = acc[0, o + 1]
        sm = acc[0, o + 2]
        s3 = acc[0, o + 3]
        for c in range(1, nrows):
            sx += acc[c, o]
            sy += acc[c, o + 1]
            sm += acc[c, o + 2]
            s3 += acc[c, o + 3]
            acc[c, o] = 0.0
            acc[c, o + 1] = 0.0
            acc[c, o + 2] = 0.0
            acc[c, o + 3] = 0.0
        acc[0, o] = sx
        acc[0, o + 1] = sy
        acc[0, o + 2] = sm
        acc[0, o + 3] = s3
        fx[p] = sx
        fy[p] = sy
        fm[p] = sm


PAIR_BLOCK = 1024  # particles per block of the pair pass (kin + acc of a block stay in L2)


@njit
def pairs_chunk(c, nchunks, step, dt, use_dash, kin, bi, bj, bstate, bf, npb, nsj, ci, cj, cf,
                nc, acc, sleep, sleep_d):
    """All pair laws of chunk ``c``, accumulated into ``acc`` (this chunk's buffer row).

    The chunk owns the particles ``n c / T : n (c + 1) / T`` and takes the parallel-bonded pairs
    and the contacts whose first particle it owns (both lists are sorted by first particle; the
    ranges come from binary searches, which tile each list exactly whatever its order). It walks
    its particles in blocks of ``PAIR_BLOCK``: the bonds, then the contacts of each block, so
    the block's kinematics and force buffer are still in cache for the second list. Smooth
    joints are split by count.

    Returns
    -------
    nbreak : int
    worst : float
        Largest overlap / min radius among the chunk's pairs.
    kworst : int
        Its contact index, or −(bond index) − 2 for a parallel-bonded pair.
    """
    n = kin.size // 8
    plo = (n * c) // nchunks
    phi = (n * (c + 1)) // nchunks
    nbreak = 0
    bworst = 0.0
    kb = -1
    worst = 0.0
    kworst = -1
    bpb = bi[:npb]
    cic = ci[:nc]
    b0 = np.searchsorted(bpb, plo)
    k0 = np.searchsorted(cic, plo)
    p0 = plo
    while p0 < phi:
        p1 = min(p0 + PAIR_BLOCK, phi)
        if p1 == phi and c == nchunks - 1:
            b1 = npb
            k1 = nc
        else:
            b1 = np.searchsorted(bpb, p1)
            k1 = np.searchsorted(cic, p1)
        if b1 > b0:
            nb_, w_, kb_ = pb_range(b0, b1, step, dt, kin, bi, bj, bstate, bf[FN], bf[FS],
                                    bf[MB], bf[KNA], bf[KSA], bf[KNI], bf[ARI], bf[TENA],
                                    bf[COHA], bf[TANFA], bf[LFS], bf[LFN], bf[LKN], bf[LKS],
                                    bf[LMU], bf[LCN], bf[LCS], use_dash, acc, sleep, sleep_d,
                                    bf[BRK_X], bf[BRK_Y], bf[BRK_NX], bf[BRK_NY],
                                    bf[BRK_STEP])
            nbreak += nb_
            if w_ > bworst:
                bworst = w_
                kb = kb_
        if k1 > k0:
            if use_dash:
                w_, k_ = contact_range_dashpot(k0, k1, dt, kin, ci, cj,
                                               cf[C_FS], cf[C_KN], cf[C_KS], cf[C_MU],
                                               cf[C_CN], cf[C_CS], cf[C_FN], acc,
                                               sleep, sleep_d)
            else:
                w_, k_ = contact_range(k0, k1, dt, kin, ci, cj, cf[C_FS],
                                       cf[C_KN], cf[C_KS], cf[C_MU], cf[C_FN], acc, sleep,
                                       sleep_d)
            if w_ > worst:
                worst = w_
                kworst = k_
        b0 = b1
        k0 = k1
        p0 = p1
    if nsj > 0:
        lo = npb + (nsj * c) // nchunks
        hi = npb + (nsj * (c + 1)) // nchunks
        nbreak += sj_range(lo, hi, step, dt, kin, bi, bj, bstate, bf[FN], bf[FS],
                           bf[UN], bf[KNA], bf[KSA], bf[TENA], bf[COHA], bf[TANFA], bf[FRIC],
                           bf[TANDIL], bf[NJX], bf[NJY], acc, sleep, sleep_d, bf[BRK_X], bf[BRK_Y],
                           bf[BRK_NX],
                           bf[BRK_NY], bf[BRK_STEP])
    if bworst > worst:
        # overlap records of bonded pairs are encoded as -(bond index) - 2
        worst = bworst
        kworst = -kb - 2
    return nbreak, worst, kworst


@njit(parallel=True)
def run_steps(nsteps, step0, dt, alpha, nchunks, skin, step_lim, overlap_lim, t, servo_alpha,
              pf, fix, bi, bj, bstate, bf, npb, ci, cj, cf, nc, use_dash, wf, qp, qw, qf, nq,
              acc, refresh, sleep, sleep_d, sleep_ratio, sleep_steps, quiet, info):
    """Run up to ``nsteps`` steps in place (PFC cycle order).

    Each step: (1) particle pass: sum the force buffers (F^n), local damping with v^{n-1/2},
    v^{n+1/2} and x^{n+1}; (2) wall motion (servo from the wall forces F^n); (3) one parallel
    pass over all pairs at x^{n+1} with increments Δδ = V^{n+1/2} Δt (parallel bonds, smooth
    joints, contacts), each chunk into its own buffer row; (4) wall contacts (serial, row 0).
    Two parallel regions per step. Passes a scene lacks (joints, walls, dashpots) are skipped
    per step, never tested per contact.

    Parameters
    ----------
    nsteps, step0 : int
        Steps to run; number of steps completed before (break events are stamped step0 + s + 1).
    dt, alpha : float
        Time step (s) and local damping coefficient.
    nchunks : int
        Static split of every pass; at most ``acc.shape[0]``.
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
    acc : (T, 4N) float64
        Force buffers, one row per chunk; on entry and exit in canonical form (row 0 = F at
        the current positions, other rows zero) unless ``refresh``.
    refresh : bool
        First re-evaluate all pair and wall forces at the current positions with zero
        increments (after a list rebuild, or after loading).
    sleep, sleep_d, sleep_ratio, sleep_steps, quiet
        Sleeping particles (see :func:`particle_range`); ``quiet`` (N,) int32 counts quiet
        steps. With ``sleep`` False nothing of it runs.
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
    kin = np.empty(8 * n)
    for c in prange(nchunks):
        for p in range((n * c) // nchunks, (n * (c + 1)) // nchunks):
            k = 8 * p
            kin[k] = x[p]
            kin[k + 1] = y[p]
            kin[k + 2] = vx[p]
            kin[k + 3] = vy[p]
            kin[k + 4] = w[p]
            kin[k + 5] = r[p]
            kin[k + 6] = 1.0 if fix[p] & 8 else 0.0
    # strided views of the packed kinematics for the (serial) wall pass
    kx = kin[0::8]
    ky = kin[1::8]
    kvx = kin[2::8]
    kvy = kin[3::8]
    kw = kin[4::8]
    if refresh:
        acc[:, :] = 0.0
    s = -1 if refresh else 0
    while s < nsteps:
        moving = s >= 0
        step = step0 + s + 1
        dti = dt if moving else 0.0
        if moving:
            # 1. particles: sum buffers, damp, integrate
            for c in prange(nchunks):
                lo = (n * c) // nchunks
                hi = (n * (c + 1)) // nchunks
                dres[c], kres[c], wres[c] = particles_chunk(
                    lo, hi, nchunks, dt, alpha, step_lim, pf[FX], pf[FY], pf[FM], pf[INVM],
                    pf[INVI], pf[X0], pf[Y0], pf[FVX], pf[FVY], pf[FW], fix, acc, kin, sleep,
                    sleep_d, sleep_ratio, sleep_steps, quiet)
            maxd2 = 0.0
            bad = -1
            for c in range(nchunks):
                info[3] += wres[c]
                if dres[c] > maxd2:
                    maxd2 = dres[c]
                if bad < 0 and kres[c] >= 0:
                    bad = kres[c]
            if bad >= 0:
                sync_range(0, n, x, y, vx, vy, w, kin)
                info[1] = 1.0 if (vx[bad] != vx[bad] or vy[bad] != vy[bad] or w[bad] != w[bad]
                                  or x[bad] != x[bad] or y[bad] != y[bad]) else 2.0
                info[2] = bad
                return s, 2
            # 2. walls move
            if has_walls:
                wall_motion(dt, t, servo_alpha, wf)
        # 3. all pairs, one region
        for c in prange(nchunks):
            bres[c], ores[c], kres[c] = pairs_chunk(c, nchunks, step, dti, use_dash, kin, bi, bj,
                                                    bstate, bf, npb, nsj, ci, cj, cf, nc, acc[c],
                                                    sleep, sleep_d)
        worst = 0.0
        kworst = -1
        for c in range(nchunks):
            info[0] += bres[c]
            if ores[c] > worst:
                worst = ores[c]
                kworst = kres[c]
        # 4. walls
        wworst = 0.0
        qworst = -1
        if has_walls:
            wworst, qworst = wall_forces(dti, kx, ky, kvx, kvy, kw, r, acc[0], wf, qp, qw, nq,
                                         qf[Q_FS], qf[Q_KN], qf[Q_KS], qf[Q_MU], qf[Q_FN],
                                         kin, sleep, sleep_d)
        info[4] = max(worst, wworst)
        if worst > overlap_lim:
            info[1] = 3.0 if kworst >= 0 else 5.0
            info[2] = kworst if kworst >= 0 else -kworst - 2
            sync_range(0, n, x, y, vx, vy, w, kin)
            return s + 1, 2
        if wworst > overlap_lim:
            info[1] = 4.0
            info[2] = qworst
            sync_range(0, n, x, y, vx, vy, w, kin)
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
            # canonical buffers and fx, fy, fm = F at the current positions
            for c in prange(nchunks):
                lo = (n * c) // nchunks
                hi = (n * (c + 1)) // nchunks
                gather_range(lo, hi, nchunks, pf[FX], pf[FY], pf[FM], acc)
                sync_range(lo, hi, x, y, vx, vy, w, kin)
            if status == 1:
                return s, 1
    return nsteps, 0


def critical_timestep(state, t=config.THICKNESS):
    """Per-particle critical time step √(m/k_tran), √(I/k_rot) (REFERENCE.md §5), s.

    Stiffness sums run over intact bonds, the linear part of every parallel-bonded pair, every
    pair in the Verlet list (touching or not: a conservative bound for contacts that form before
    the next rebuild) and wall candidates; per contact the larger of normal and shear stiffness
    is taken.

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
    # the bond part changes only when bonds break: cached on the state, keyed by the states
    key = (int(np.count_nonzero(intact)), state.n_bonds, n)
    cache = getattr(state, "_kbond_cache", None)
    if cache is not None and cache[0] == key:
        ktr += cache[1]
        krot += cache[2]
    else:
        kt_b = np.zeros(n)
        kr_b = np.zeros(n)
        pb = state.bkind == 0
        for ends in (state.bi, state.bj):
            e = ends[live]
            kna = state.bf[KNA][live]
            ksa = state.bf[KSA][live]
            kni = state.bf[KNI][live] * intact[live]
            kt_b += np.bincount(e, np.maximum(kna, ksa), minlength=n)
            kr_b += np.bincount(e, ksa * r[e] ** 2 + kni, minlength=n)
            # linear contact part of parallel-bonded pairs (whether or not they touch now)
            e = ends[pb]
            lkn, lks = state.bf[LKN][pb], state.bf[LKS][pb]
            kt_b += np.bincount(e, np.maximum(lkn, lks), minlength=n)
            kr_b += np.bincount(e, lks * r[e] ** 2, minlength=n)
        state._kbond_cache = (key, kt_b, kr_b)
        ktr += kt_b
        krot += kr_b
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
