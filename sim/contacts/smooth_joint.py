"""Smooth joint (Mas Ivars et al. 2011, PFC ``smoothjoint``; REFERENCE.md §4).

The joint frame (n̂j, t̂j) is fixed at installation; forces act along it and never along the
ball–ball line, and the joint carries no moment. The normal state is kept as the elastic normal
overlap ``un`` = −(U_n − U_n,0) + U_d (m), so that F_n = sj_kn·Ā·un in the bonded state
(tension allowed) and F_n = sj_kn·Ā·max(0, un) once unbonded. An unbonded joint acts only while
its balls are within reach (gap ≤ ``config.SJ_REACH`` × min(R)); beyond that its normal state
follows the gap (un = −g) and it carries nothing. Scalar laws; they check nothing.
"""
from .._jit import njit
from ..config import SJ_REACH


@njit
def sj_update(un, fs, state, dun, dus, kna, ksa, tena, coha, tanfa, fric, tandil, gap, rmin):
    """Incremental update of one smooth joint.

    Parameters
    ----------
    un : float, m
        Elastic normal overlap (positive closing), 0 at installation.
    fs : float, N
        Shear force along t̂j of the previous step.
    state : int
        0 bonded, 1 broken in tension, 2 broken in shear (both then frictional).
    dun, dus : float, m
        Increments of the contact-point displacement along n̂j (positive opening) and t̂j.
    kna, ksa : float, N/m
        sj_kn·Ā, sj_ks·Ā.
    tena, coha : float, N
        sj_ten·Ā, sj_coh·Ā.
    tanfa, fric, tandil : float
        tan(sj_fa), μ_j (sj_fric), tan ψ (dilation).
    gap, rmin : float, m
        Current ball gap d − R_i − R_j and the smaller radius. An unbonded joint whose gap
        exceeds ``SJ_REACH`` × rmin is out of reach: no force, shear history cleared, and
        un = −gap, so that it closes again when the balls touch. Without this, the spin
        increments w·a of balls far apart (a = R + gap/2) closed the open joint and it fired
        across the gap with a lever arm of d/2.

    Returns
    -------
    un, fn, fs : float
        New overlap (m) and forces (N, fn compression positive).
    state : int
        New state.
    broke : int
        0 no event, 1 tensile break now, 2 shear break now.
    """
    un = un - dun
    broke = 0
    if state == 0:
        fn = kna * un
        fsb = fs - ksa * dus
        if -fn >= tena:
            return un, 0.0, 0.0, 1, 1
        if abs(fsb) < coha + fn * tanfa:
            return un, fn, fsb, 0, 0
        state = 2
        broke = 2
    # unbonded (frictional, with dilation)
    if gap > SJ_REACH * rmin:
        return -gap, 0.0, 0.0, state, broke
    if un <= 0.0:
        return un, 0.0, 0.0, state, broke
    fn = kna * un
    fst = fs - ksa * dus
    lim = fric * fn
    a = abs(fst)
    if a > lim:
        excess = a - lim
        fst = lim if fst > 0.0 else -lim
        un = un + excess / ksa * tandil
        fn = kna * un
    return un, fn, fst, state, broke
