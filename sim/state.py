"""Structure-of-arrays state of a simulation.

Notation: N particles, B bonds (parallel bonds first, then smooth joints), C contact capacity
(unbonded ball–ball pairs in the Verlet list, bonded pairs included for their linear part),
W walls, Q wall-contact capacity.

Float data sit in a few 2-D arrays whose rows are named by the integer constants below, so
that a kernel takes one argument per table (row views are contiguous). Everything is SI.
"""
from __future__ import annotations

import numpy as np

# --- particle float table pf[row, p] -------------------------------------------------------
X, Y, VX, VY, W, FX, FY, FM, R, INVM, INVI, X0, Y0, FVX, FVY, FW, WFX, WFY, WFM, MASS, INERTIA = \
    range(21)
NPF = 21
PF_NAMES = ("x", "y", "vx", "vy", "w", "fx", "fy", "fm", "r", "invm", "invi", "x0", "y0",
            "fvx", "fvy", "fw", "wfx", "wfy", "wfm", "mass", "inertia")

# particle fix flags (int8): bit 0 vx prescribed, bit 1 vy prescribed, bit 2 rotation prescribed
FIX_X = 1
FIX_Y = 2
FIX_ROTATION = 4

# --- bond float table bf[row, b] ------------------------------------------------------------
(FN, FS, MB, KNA, KSA, KNI, ARI, TENA, COHA, TANFA, NJX, NJY, UN, FRIC, TANDIL, BFX, BFY,
 SIZE, BRK_X, BRK_Y, BRK_NX, BRK_NY, BRK_STEP) = range(23)
NBF = 23

# --- contact float table cf[row, c] ---------------------------------------------------------
C_FS, C_KN, C_KS, C_MU, C_CN, C_CS, C_FX, C_FY, C_FN = range(9)
NCF = 9

# --- wall table wf[w, col] ------------------------------------------------------------------
(W_PX, W_PY, W_NX, W_NY, W_VX, W_VY, W_FRIC, W_EMOD, W_FX, W_FY, W_SERVO, W_TARGET, W_LENGTH,
 W_GAIN, W_DISP, W_KTOT, W_VMAX) = range(17)
NWF = 17

# --- wall-contact float table qf[row, q] ----------------------------------------------------
Q_FS, Q_KN, Q_KS, Q_MU, Q_FN = range(5)
NQF = 5


class State:
    """All arrays of a running simulation (no formulas; kernels do the work).

    Attributes
    ----------
    pf : (21, N) ndarray of float64
        Particle table, rows ``X, Y, VX, ...`` (see module constants).
    fix, mineral, grain : (N,) ndarray of int8, int32, int32
    bf : (23, B) ndarray of float64
        Bond table; ``bmom`` (2B,) holds the moments on particle i (2b) and j (2b + 1).
    bi, bj : (B,) int32; bkind, bstate : (B,) int8; bid : (B,) int64
        Pairs, kind (0 pb, 1 sj), state (0 intact, 1 tension, 2 shear), specimen bond index.
    bptr, bref : CSR gather of bonds per particle (ref = 2b + side, side 1 when p is j).
    cf : (9, C) float64; ci, cj : (C,) int32; cstart : (N+1,) int64; nc : int
        Contact table, pairs and owner index (contacts of i are cstart[i]:cstart[i+1]).
    cptr, cref, cmom : CSR gather of contacts and the contact moments (2C,).
    wf : (W, 17) float64; qf : (5, Q) float64; qp, qw : (Q,) int32; nq : int
        Walls and wall contacts.
    """

    ARRAYS = ("pf", "fix", "mineral", "grain", "bf", "bmom", "bi", "bj", "bkind", "bstate",
              "bid", "bptr", "bref", "sj_ptr", "sj_adj", "cf", "ci", "cj", "cstart", "cmom",
              "cptr", "cref", "wf", "qf", "qp", "qw", "logged")

    def __init__(self, **arrays):
        for k in self.ARRAYS:
            setattr(self, k, arrays[k])
        self.nc = int(arrays.get("nc", 0))
        self.nq = int(arrays.get("nq", 0))
        self.npb = int(arrays.get("npb", 0))

    @property
    def n(self) -> int:
        return int(self.pf.shape[1])

    @property
    def n_bonds(self) -> int:
        return int(self.bi.size)

    @property
    def n_walls(self) -> int:
        return int(self.wf.shape[0])

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.ARRAYS}
        d.update(nc=np.int64(self.nc), nq=np.int64(self.nq), npb=np.int64(self.npb))
        return d

    @classmethod
    def from_dict(cls, d) -> "State":
        return cls(**{k: np.array(d[k]) for k in cls.ARRAYS},
                   nc=int(d["nc"]), nq=int(d["nq"]), npb=int(d["npb"]))
