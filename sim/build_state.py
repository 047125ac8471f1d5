"""The engine's arrays built from a specimen (:class:`~sim.state.State`): particle masses,
bond constants (parallel bonds first, then smooth joints), the linear part of bonded pairs."""
from __future__ import annotations

import numpy as np

from . import config
from .contacts.linear import linear_stiffness
from .contacts.parallel_bond import pb_constants
from .neighbors import partner_csr
from .specimen import Specimen
from .state import (
    ARI,
    BRK_STEP,
    COHA,
    FRIC,
    INERTIA,
    INVI,
    INVM,
    KNA,
    KNI,
    KSA,
    LKN,
    LKS,
    LMU,
    MASS,
    NBF,
    NCF,
    NJX,
    NJY,
    NPF,
    NQF,
    NWF,
    SIZE,
    TANDIL,
    TANFA,
    TENA,
    X0,
    Y0,
    R,
    State,
    X,
    Y,
)

__all__ = ["initial_state"]


def initial_state(sp: Specimen, *, pb_mcf: float = 1.0, sj_dilation_deg: float = 0.0) -> State:
    """The state of a new simulation of specimen ``sp`` (no contacts or walls yet).

    Parameters
    ----------
    sp : Specimen
    pb_mcf : float
        Parallel-bond moment contribution factor β̄.
    sj_dilation_deg : float
        Smooth-joint dilation angle ψ.
    """
    t = config.THICKNESS
    n = sp.n_particles
    pf = np.zeros((NPF, n))
    pf[X] = sp.x
    pf[Y] = sp.y
    pf[R] = sp.r
    pf[X0] = sp.x
    pf[Y0] = sp.y
    mass = sp.density[sp.mineral] * np.pi * sp.r ** 2 * t
    pf[MASS] = mass
    pf[INERTIA] = 0.5 * mass * sp.r ** 2
    pf[INVM] = 1.0 / pf[MASS]
    pf[INVI] = 1.0 / pf[INERTIA]
    # bonds: parallel bonds first, then smooth joints, each in order of bond_i
    kind = sp.bond_kind
    order = np.lexsort((sp.bond_j, sp.bond_i, kind))
    bi = sp.bond_i[order].astype(np.int32)
    bj = sp.bond_j[order].astype(np.int32)
    bkind = kind[order].astype(np.int8)
    nb = bi.size
    npb = int(np.sum(bkind == 0))
    bf = np.zeros((NBF, nb))
    r1, r2 = sp.r[bi], sp.r[bj]
    pb = slice(0, npb)
    m = sp.mineral[bi[pb]]
    (bf[KNA, pb], bf[KSA, pb], bf[KNI, pb], bf[ARI, pb], bf[TENA, pb], bf[COHA, pb],
     bf[TANFA, pb], bf[SIZE, pb]) = pb_constants(
        r1[pb], r2[pb], sp.pb_emod[m], sp.pb_kratio[m], sp.pb_ten[m], sp.pb_coh[m],
        np.radians(sp.pb_fa[m]), sp.pb_rmul[m], pb_mcf, t)
    sj = slice(npb, nb)
    rb = np.minimum(r1[sj], r2[sj])
    area = 2.0 * rb * t
    bf[KNA, sj] = sp.sj_kn[0] * area
    bf[KSA, sj] = sp.sj_ks[0] * area
    bf[TENA, sj] = sp.sj_ten[0] * area
    bf[COHA, sj] = sp.sj_coh[0] * area
    bf[TANFA, sj] = np.tan(np.radians(sp.sj_fa[0]))
    bf[FRIC, sj] = sp.sj_fric[0]
    bf[TANDIL, sj] = np.tan(np.radians(sj_dilation_deg))
    bf[SIZE, sj] = 2.0 * rb
    jx, jy = sp.joint_nx[order][sj], sp.joint_ny[order][sj]
    flip = np.where(jx * (sp.x[bj[sj]] - sp.x[bi[sj]]) + jy * (sp.y[bj[sj]] - sp.y[bi[sj]])
                    < 0, -1.0, 1.0)
    bf[NJX, sj] = jx * flip
    bf[NJY, sj] = jy * flip
    bf[BRK_STEP] = -1
    # linear contact part of parallel-bonded pairs (computed with the bond)
    mi, mj = sp.mineral[bi[pb]], sp.mineral[bj[pb]]
    bf[LKN, pb], bf[LKS, pb] = linear_stiffness(r1[pb], r2[pb], sp.emod[mi], sp.emod[mj],
                                                0.5 * (sp.kratio[mi] + sp.kratio[mj]), t)
    bf[LMU, pb] = np.minimum(sp.fric[mi], sp.fric[mj])
    # every bonded pair stays out of the Verlet contact list
    excl_ptr, excl_adj = partner_csr(n, bi, bj)
    cap = 0
    return State(pf=pf, fix=np.zeros(n, np.int8), quiet=np.zeros(n, np.int32),
                 mineral=sp.mineral.copy(),
                 grain=sp.grain.copy(), pid=np.arange(n, dtype=np.int64), bf=bf, bi=bi, bj=bj,
                 bkind=bkind, bstate=np.zeros(nb, np.int8), bid=order.astype(np.int64),
                 excl_ptr=excl_ptr, excl_adj=excl_adj,
                 cf=np.zeros((NCF, cap)), ci=np.zeros(cap, np.int32),
                 cj=np.zeros(cap, np.int32), cstart=np.zeros(n + 1, np.int64),
                 wf=np.zeros((0, NWF)),
                 qf=np.zeros((NQF, 0)), qp=np.zeros(0, np.int32), qw=np.zeros(0, np.int32),
                 logged=np.zeros(nb, bool), nc=0, nq=0, npb=npb)
