"""Loops over the contact lists: call the laws, accumulate forces into a per-thread buffer.

Each ``*_range`` kernel processes pairs ``lo:hi`` of one list and adds, per pair, the force on
particle j and −(that force) on particle i, and the moments on both, into ``acc`` laid out as
``acc[4p:4p+3]`` = (fx, fy, moment) of particle p. Every thread owns its own ``acc`` (one row of
the (threads, 4N) buffer), so the scatter is race-free (STYLE.md §5 rule 6); the particle pass
(:mod:`sim.integrate`) sums the rows. Pair state (forces, shear history) is stored per pair.
Particle kinematics are read from the packed ``kin[8p:8p+6]`` = (x, y, vx, vy, w, r), one cache
line per particle.
Kernels
check nothing; arrays are the row views of the :mod:`sim.state` tables.

Kinematics (REFERENCE.md conventions): n̂ = (x_j − x_i)/d, t̂ = (−n_y, n_x), g = d − (R_i + R_j);
the contact point lies a_i = R_i + g/2 from i along n̂ and a_j = R_j + g/2 from j along −n̂;
Δδ = V Δt with V the relative velocity of j with respect to i at the contact point.
The force on j is F = F_n n̂ + F_s t̂ with F_n > 0 in compression (REFERENCE.md prints −F_n n̂;
with n̂ pointing from i to j that sign would make a compressed contact attract, so we use the
sign the analytic cases require; shear, moment and stress formulas are as printed).
"""
from math import sqrt

from ._jit import njit
from .contacts.linear import linear_force, linear_force_masked
from .contacts.parallel_bond import pb_update
from .contacts.smooth_joint import sj_update


@njit
def _sleep_slots(acc, i, j, si, sj, fx, fy, du, sleep_d):
    """Fourth buffer slot: for an awake particle the sum of |pair force| (its sleep test), for a
    sleeping one a wake vote when the pair moves more than ``sleep_d`` in this step."""
    moving = 1.0 if du > sleep_d else 0.0
    mag = abs(fx) + abs(fy)
    acc[4 * i + 3] += moving if si > 0.0 else mag
    acc[4 * j + 3] += moving if sj > 0.0 else mag


@njit
def pb_range(lo, hi, step, dt, kin, bi, bj, bstate, fn_, fs_, mb_, kna_, ksa_, kni_, ari_, tena_,
             coha_, tanfa_, lfs_, lfn_, lkn_, lks_, lmu_, lcn_, lcs_, use_dash, acc, sleep,
             sleep_d, brk_x, brk_y, brk_nx,
             brk_ny, brk_step):
    """Parallel-bonded pairs ``lo:hi``: the bond (while intact) plus the linear contact part of
    the pair (whenever the balls overlap, bonded or not, with its own shear history and
    dashpots ``lcn, lcs``, read only when ``use_dash``). These pairs are kept out of the
    Verlet contact list, so each is computed once per step.

    Returns
    -------
    nbreak : int
        Bonds that broke in this step.
    worst : float
        Largest overlap / min radius among these pairs.
    bworst : int
        Its bond index (-1 if none overlaps).
    """
    nbreak = 0
    worst = 0.0
    bworst = -1
    for b in range(lo, hi):
        i = bi[b]
        j = bj[b]
        oi = 8 * i
        oj = 8 * j
        xi = kin[oi]
        yi = kin[oi + 1]
        vxi = kin[oi + 2]
        vyi = kin[oi + 3]
        wi = kin[oi + 4]
        ri = kin[oi + 5]
        xj = kin[oj]
        yj = kin[oj + 1]
        vxj = kin[oj + 2]
        vyj = kin[oj + 3]
        wj = kin[oj + 4]
        rj = kin[oj + 5]
        if sleep and kin[oi + 6] + kin[oj + 6] == 2.0:
            continue  # both asleep: nothing moves, the stored pair state stays valid
        dx = xj - xi
        dy = yj - yi
        d = sqrt(dx * dx + dy * dy)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        ov = ri + rj - d
        ai = ri - 0.5 * ov
        aj = rj - 0.5 * ov
        dvx = vxj - vxi
        dvy = vyj - vyi
        vn = dvx * nx + dvy * ny
        vt = -dvx * ny + dvy * nx - wj * aj - wi * ai
        fn = 0.0
        fs = 0.0
        mb = 0.0
        if bstate[b] == 0:
            fn, fs, mb, mode = pb_update(fn_[b], fs_[b], mb_[b], vn * dt, vt * dt,
                                         (wj - wi) * dt, kna_[b], ksa_[b], kni_[b], ari_[b],
                                         tena_[b], coha_[b], tanfa_[b])
            fn_[b] = fn
            fs_[b] = fs
            mb_[b] = mb
            if mode != 0:
                bstate[b] = mode
                brk_x[b] = xi + ai * nx
                brk_y[b] = yi + ai * ny
                brk_nx[b] = nx
                brk_ny[b] = ny
                brk_step[b] = step
                nbreak += 1
        # linear part of the pair (branch-free: about half the bonded pairs touch)
        fnl, fsl, on = linear_force_masked(ov, vt * dt, lkn_[b], lks_[b], lmu_[b], lfs_[b])
        ovp = ov * on
        lfs_[b] = fsl
        if use_dash:
            fnl -= lcn_[b] * vn * on
            fsl -= lcs_[b] * vt * on
        lfn_[b] = fnl
        fn += fnl
        fs += fsl
        rmin = min(ri, rj)
        if ovp > worst * rmin:
            worst = ovp / rmin
            bworst = b
        fx = fn * nx - fs * ny
        fy = fn * ny + fs * nx
        o = 4 * i
        acc[o] -= fx
        acc[o + 1] -= fy
        acc[o + 2] += -ai * fs - mb
        o = 4 * j
        acc[o] += fx
        acc[o + 1] += fy
        acc[o + 2] += -aj * fs + mb
        if sleep:
            _sleep_slots(acc, i, j, kin[oi + 6], kin[oj + 6], fx, fy,
                         (abs(vn) + abs(vt)) * dt, sleep_d)
    return nbreak, worst, bworst


@njit
def sj_range(lo, hi, step, dt, kin, bi, bj, bstate, fn_, fs_, un_, kna_, ksa_,
             tena_, coha_, tanfa_, fric_, tandil_, njx_, njy_, acc, sleep, sleep_d, brk_x, brk_y,
             brk_nx, brk_ny,
             brk_step):
    """Smooth joints ``lo:hi`` (forces along the fixed joint frame, no moment); returns breaks."""
    nbreak = 0
    for b in range(lo, hi):
        i = bi[b]
        j = bj[b]
        oi = 8 * i
        oj = 8 * j
        xi = kin[oi]
        yi = kin[oi + 1]
        vxi = kin[oi + 2]
        vyi = kin[oi + 3]
        wi = kin[oi + 4]
        ri = kin[oi + 5]
        xj = kin[oj]
        yj = kin[oj + 1]
        vxj = kin[oj + 2]
        vyj = kin[oj + 3]
        wj = kin[oj + 4]
        rj = kin[oj + 5]
        if sleep and kin[oi + 6] + kin[oj + 6] == 2.0:
            continue  # both asleep: nothing moves, the stored pair state stays valid
        dx = xj - xi
        dy = yj - yi
        d = sqrt(dx * dx + dy * dy)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        hg = 0.5 * (d - ri - rj)
        ai = ri + hg
        aj = rj + hg
        rot = -wj * aj - wi * ai
        vxc = vxj - vxi - rot * ny
        vyc = vyj - vyi + rot * nx
        jx = njx_[b]
        jy = njy_[b]
        dun = (vxc * jx + vyc * jy) * dt
        dus = (-vxc * jy + vyc * jx) * dt
        un, fn, fs, state, broke = sj_update(un_[b], fs_[b], bstate[b], dun, dus, kna_[b],
                                             ksa_[b], tena_[b], coha_[b], tanfa_[b], fric_[b],
                                             tandil_[b], hg + hg, ri if ri < rj else rj)
        un_[b] = un
        fn_[b] = fn
        fs_[b] = fs
        fx = fn * jx - fs * jy
        fy = fn * jy + fs * jx
        c = nx * fy - ny * fx
        o = 4 * i
        acc[o] -= fx
        acc[o + 1] -= fy
        acc[o + 2] -= ai * c
        o = 4 * j
        acc[o] += fx
        acc[o + 1] += fy
        acc[o + 2] -= aj * c
        if sleep:
            _sleep_slots(acc, i, j, kin[oi + 6], kin[oj + 6], fx, fy,
                         (abs(vxc) + abs(vyc)) * dt, sleep_d)
        if broke != 0:
            bstate[b] = state
            brk_x[b] = xi + ai * nx
            brk_y[b] = yi + ai * ny
            brk_nx[b] = jx
            brk_ny[b] = jy
            brk_step[b] = step
            nbreak += 1
    return nbreak


@njit
def contact_range(lo, hi, dt, kin, ci, cj, fs_, kn_, ks_, mu_, cfn, acc, sleep, sleep_d):
    """Linear contacts ``lo:hi`` without dashpots (``cfn`` = normal force, N).

    Returns
    -------
    worst : float
        Largest overlap / min(R_i, R_j) in the range.
    kworst : int
        Its contact index (-1 if no overlap).
    """
    worst = 0.0
    kworst = -1
    for k in range(lo, hi):
        i = ci[k]
        j = cj[k]
        oi = 8 * i
        oj = 8 * j
        xi = kin[oi]
        yi = kin[oi + 1]
        vxi = kin[oi + 2]
        vyi = kin[oi + 3]
        wi = kin[oi + 4]
        ri = kin[oi + 5]
        xj = kin[oj]
        yj = kin[oj + 1]
        vxj = kin[oj + 2]
        vyj = kin[oj + 3]
        wj = kin[oj + 4]
        rj = kin[oj + 5]
        if sleep and kin[oi + 6] + kin[oj + 6] == 2.0:
            continue  # both asleep: nothing moves, the stored pair state stays valid
        dx = xj - xi
        dy = yj - yi
        rs = ri + rj
        d2 = dx * dx + dy * dy
        if d2 >= rs * rs:
            if cfn[k] != 0.0 or fs_[k] != 0.0:
                fs_[k] = 0.0
                cfn[k] = 0.0
            continue
        d = sqrt(d2)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        ov = rs - d
        ai = ri - 0.5 * ov
        aj = rj - 0.5 * ov
        dvx = vxj - vxi
        dvy = vyj - vyi
        vt = -dvx * ny + dvy * nx - wj * aj - wi * ai
        fn, fs, slip = linear_force(ov, vt * dt, kn_[k], ks_[k], mu_[k], fs_[k])
        fs_[k] = fs
        cfn[k] = fn
        fx = fn * nx - fs * ny
        fy = fn * ny + fs * nx
        o = 4 * i
        acc[o] -= fx
        acc[o + 1] -= fy
        acc[o + 2] -= ai * fs
        o = 4 * j
        acc[o] += fx
        acc[o + 1] += fy
        acc[o + 2] -= aj * fs
        if sleep:
            _sleep_slots(acc, i, j, kin[oi + 6], kin[oj + 6], fx, fy,
                         (abs(dvx) + abs(dvy) + abs(vt)) * dt, sleep_d)
        rmin = ri if ri < rj else rj
        q = ov / rmin
        if q > worst:
            worst = q
            kworst = k
    return worst, kworst


@njit
def contact_range_dashpot(lo, hi, dt, kin, ci, cj, fs_, kn_, ks_, mu_, cn_, cs_,
                          cfn, acc, sleep, sleep_d):
    """Linear contacts ``lo:hi`` with viscous dashpots (dp_mode 0: full, may be tensile)."""
    worst = 0.0
    kworst = -1
    for k in range(lo, hi):
        i = ci[k]
        j = cj[k]
        oi = 8 * i
        oj = 8 * j
        xi = kin[oi]
        yi = kin[oi + 1]
        vxi = kin[oi + 2]
        vyi = kin[oi + 3]
        wi = kin[oi + 4]
        ri = kin[oi + 5]
        xj = kin[oj]
        yj = kin[oj + 1]
        vxj = kin[oj + 2]
        vyj = kin[oj + 3]
        wj = kin[oj + 4]
        rj = kin[oj + 5]
        if sleep and kin[oi + 6] + kin[oj + 6] == 2.0:
            continue  # both asleep: nothing moves, the stored pair state stays valid
        dx = xj - xi
        dy = yj - yi
        rs = ri + rj
        d2 = dx * dx + dy * dy
        if d2 >= rs * rs:
            if cfn[k] != 0.0 or fs_[k] != 0.0:
                fs_[k] = 0.0
                cfn[k] = 0.0
            continue
        d = sqrt(d2)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        ov = rs - d
        ai = ri - 0.5 * ov
        aj = rj - 0.5 * ov
        dvx = vxj - vxi
        dvy = vyj - vyi
        vn = dvx * nx + dvy * ny
        vt = -dvx * ny + dvy * nx - wj * aj - wi * ai
        fn, fs, slip = linear_force(ov, vt * dt, kn_[k], ks_[k], mu_[k], fs_[k])
        fs_[k] = fs
        fnt = fn - cn_[k] * vn
        fst = fs - cs_[k] * vt
        cfn[k] = fnt
        fx = fnt * nx - fst * ny
        fy = fnt * ny + fst * nx
        o = 4 * i
        acc[o] -= fx
        acc[o + 1] -= fy
        acc[o + 2] -= ai * fst
        o = 4 * j
        acc[o] += fx
        acc[o + 1] += fy
        acc[o + 2] -= aj * fst
        if sleep:
            _sleep_slots(acc, i, j, kin[oi + 6], kin[oj + 6], fx, fy,
                         (abs(vn) + abs(vt)) * dt, sleep_d)
        rmin = ri if ri < rj else rj
        q = ov / rmin
        if q > worst:
            worst = q
            kworst = k
    return worst, kworst
