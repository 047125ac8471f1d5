"""Loops over the contact lists: call the laws, write per-pair forces (no scatter, no races).

Each ``*_range`` kernel processes pairs ``lo:hi`` of one list and writes, per pair k, the force on
particle j (``fx[k], fy[k]``; particle i receives the opposite) and the moments on i and j at
``mom[2k]`` and ``mom[2k + 1]``. The particle pass (:mod:`sim.integrate`) gathers them. Kernels
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
from .contacts.linear import linear_force
from .contacts.parallel_bond import pb_update
from .contacts.smooth_joint import sj_update


@njit
def pb_range(lo, hi, step, dt, x, y, vx, vy, w, r, bi, bj, bstate, fn_, fs_, mb_, kna_, ksa_,
             kni_, ari_, tena_, coha_, tanfa_, bfx, bfy, bmom, brk_x, brk_y, brk_nx, brk_ny,
             brk_step):
    """Parallel bonds ``lo:hi``; returns the number of bonds that broke in this step."""
    nbreak = 0
    for b in range(lo, hi):
        if bstate[b] != 0:
            continue
        i = bi[b]
        j = bj[b]
        dx = x[j] - x[i]
        dy = y[j] - y[i]
        d = sqrt(dx * dx + dy * dy)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        hg = 0.5 * (d - r[i] - r[j])
        ai = r[i] + hg
        aj = r[j] + hg
        dvx = vx[j] - vx[i]
        dvy = vy[j] - vy[i]
        vn = dvx * nx + dvy * ny
        vt = -dvx * ny + dvy * nx - w[j] * aj - w[i] * ai
        fn, fs, mb, mode = pb_update(fn_[b], fs_[b], mb_[b], vn * dt, vt * dt,
                                     (w[j] - w[i]) * dt, kna_[b], ksa_[b], kni_[b], ari_[b],
                                     tena_[b], coha_[b], tanfa_[b])
        fn_[b] = fn
        fs_[b] = fs
        mb_[b] = mb
        bfx[b] = fn * nx - fs * ny
        bfy[b] = fn * ny + fs * nx
        bmom[2 * b] = -ai * fs - mb
        bmom[2 * b + 1] = -aj * fs + mb
        if mode != 0:
            bstate[b] = mode
            brk_x[b] = x[i] + ai * nx
            brk_y[b] = y[i] + ai * ny
            brk_nx[b] = nx
            brk_ny[b] = ny
            brk_step[b] = step
            nbreak += 1
    return nbreak


@njit
def sj_range(lo, hi, step, dt, x, y, vx, vy, w, r, bi, bj, bstate, fn_, fs_, un_, kna_, ksa_,
             tena_, coha_, tanfa_, fric_, tandil_, njx_, njy_, bfx, bfy, bmom, brk_x, brk_y,
             brk_nx, brk_ny, brk_step):
    """Smooth joints ``lo:hi`` (forces along the fixed joint frame, no moment); returns breaks."""
    nbreak = 0
    for b in range(lo, hi):
        i = bi[b]
        j = bj[b]
        dx = x[j] - x[i]
        dy = y[j] - y[i]
        d = sqrt(dx * dx + dy * dy)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        hg = 0.5 * (d - r[i] - r[j])
        ai = r[i] + hg
        aj = r[j] + hg
        rot = -w[j] * aj - w[i] * ai
        vxc = vx[j] - vx[i] - rot * ny
        vyc = vy[j] - vy[i] + rot * nx
        jx = njx_[b]
        jy = njy_[b]
        dun = (vxc * jx + vyc * jy) * dt
        dus = (-vxc * jy + vyc * jx) * dt
        un, fn, fs, state, broke = sj_update(un_[b], fs_[b], bstate[b], dun, dus, kna_[b],
                                             ksa_[b], tena_[b], coha_[b], tanfa_[b], fric_[b],
                                             tandil_[b])
        un_[b] = un
        fn_[b] = fn
        fs_[b] = fs
        fx = fn * jx - fs * jy
        fy = fn * jy + fs * jx
        bfx[b] = fx
        bfy[b] = fy
        c = nx * fy - ny * fx
        bmom[2 * b] = -ai * c
        bmom[2 * b + 1] = -aj * c
        if broke != 0:
            bstate[b] = state
            brk_x[b] = x[i] + ai * nx
            brk_y[b] = y[i] + ai * ny
            brk_nx[b] = jx
            brk_ny[b] = jy
            brk_step[b] = step
            nbreak += 1
    return nbreak


@njit
def contact_range(lo, hi, dt, x, y, vx, vy, w, r, ci, cj, fs_, kn_, ks_, mu_, cfx, cfy, cfn,
                  cmom):
    """Linear contacts ``lo:hi`` without dashpots.

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
        dx = x[j] - x[i]
        dy = y[j] - y[i]
        rs = r[i] + r[j]
        d2 = dx * dx + dy * dy
        if d2 >= rs * rs:
            fs_[k] = 0.0
            cfx[k] = 0.0
            cfy[k] = 0.0
            cfn[k] = 0.0
            cmom[2 * k] = 0.0
            cmom[2 * k + 1] = 0.0
            continue
        d = sqrt(d2)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        ov = rs - d
        ai = r[i] - 0.5 * ov
        aj = r[j] - 0.5 * ov
        dvx = vx[j] - vx[i]
        dvy = vy[j] - vy[i]
        vt = -dvx * ny + dvy * nx - w[j] * aj - w[i] * ai
        fn, fs, slip = linear_force(ov, vt * dt, kn_[k], ks_[k], mu_[k], fs_[k])
        fs_[k] = fs
        cfn[k] = fn
        cfx[k] = fn * nx - fs * ny
        cfy[k] = fn * ny + fs * nx
        cmom[2 * k] = -ai * fs
        cmom[2 * k + 1] = -aj * fs
        rmin = r[i] if r[i] < r[j] else r[j]
        q = ov / rmin
        if q > worst:
            worst = q
            kworst = k
    return worst, kworst


@njit
def contact_range_dashpot(lo, hi, dt, x, y, vx, vy, w, r, ci, cj, fs_, kn_, ks_, mu_, cn_, cs_,
                          cfx, cfy, cfn, cmom):
    """Linear contacts ``lo:hi`` with viscous dashpots (dp_mode 0: full, may be tensile)."""
    worst = 0.0
    kworst = -1
    for k in range(lo, hi):
        i = ci[k]
        j = cj[k]
        dx = x[j] - x[i]
        dy = y[j] - y[i]
        rs = r[i] + r[j]
        d2 = dx * dx + dy * dy
        if d2 >= rs * rs:
            fs_[k] = 0.0
            cfx[k] = 0.0
            cfy[k] = 0.0
            cfn[k] = 0.0
            cmom[2 * k] = 0.0
            cmom[2 * k + 1] = 0.0
            continue
        d = sqrt(d2)
        inv = 1.0 / d
        nx = dx * inv
        ny = dy * inv
        ov = rs - d
        ai = r[i] - 0.5 * ov
        aj = r[j] - 0.5 * ov
        dvx = vx[j] - vx[i]
        dvy = vy[j] - vy[i]
        vn = dvx * nx + dvy * ny
        vt = -dvx * ny + dvy * nx - w[j] * aj - w[i] * ai
        fn, fs, slip = linear_force(ov, vt * dt, kn_[k], ks_[k], mu_[k], fs_[k])
        fs_[k] = fs
        fnt = fn - cn_[k] * vn
        fst = fs - cs_[k] * vt
        cfn[k] = fnt
        cfx[k] = fnt * nx - fst * ny
        cfy[k] = fnt * ny + fst * nx
        cmom[2 * k] = -ai * fst
        cmom[2 * k + 1] = -aj * fst
        rmin = r[i] if r[i] < r[j] else r[j]
        q = ov / rmin
        if q > worst:
            worst = q
            kworst = k
    return worst, kworst
