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
X, Y, VX, VY, W, FX, FY, FM, R, INVM, INVI, X0, Y0, FVX, FVY, FW, MASS, INERTIA = range(18)
NPF = 18
PF_NAMES = ("x", "y", "vx", "vy", "w", "fx", "fy", "fm", "r", "invm", "invi", "x0", "y0",
            "fvx", "fvy", "fw", "mass", "inertia")

# particle fix flags (int8): bit 0 vx prescribed, bit 1 vy prescribed, bit 2 rotation prescribed,
# bit 3 asleep (Simulation(sleep=True))
FIX_X = 1
FIX_Y = 2
FIX_ROTATION = 4

# --- bond float table bf[row, b] ------------------------------------------------------------
(FN, FS, MB, KNA, KSA, KNI, ARI, TENA, COHA, TANFA, NJX, NJY, UN, FRIC, TANDIL, SIZE, BRK_X,
 BRK_Y, BRK_NX, BRK_NY, BRK_STEP, LFS, LFN, LKN, LKS, LMU, LCN, LCS) = range(28)
NBF = 28


# --- contact float table cf[row, c] ---------------------------------------------------------
C_FS, C_KN, C_KS, C_MU, C_CN, C_CS, C_FN = range(7)
NCF = 7

# --- wall table wf[w, col] ------------------------------------------------------------------
(W_PX, W_PY, W_NX, W_NY, W_VX, W_VY, W_FRIC, W_EMOD, W_FX, W_FY, W_SERVO, W_TARGET, W_LENGTH,
 W_GAIN, W_DISP, W_KTOT, W_VMAX) = range(17)
NWF = 17

# --- wall-contact float table qf[row, q] ----------------------------------------------------
Q_FS, Q_KN, Q_KS, Q_MU, Q_FN = range(5)
NQF = 5


def force_chunks() -> int:
    """Chunk count of the step loop for scenes of ``config.PARALLEL_MIN_PARTICLES`` or more.

    ``config.FORCE_CHUNKS`` unless the environment variable ``SIM_FORCE_CHUNKS`` sets it. The
    chunk count, not the thread count, fixes the order in which the forces on a particle are
    summed, so a run is bit-identical on any number of threads at a given chunk count; at most
    this many threads work in the step loop.

    Raises
    ------
    InputError
        ``SIM_FORCE_CHUNKS`` is not a whole number from 1 to 256.
    """
    import os

    from .config import FORCE_CHUNKS
    from .errors import InputError
    raw = os.environ.get("SIM_FORCE_CHUNKS", "").strip()
    if not raw:
        return FORCE_CHUNKS
    try:
        k = int(raw)
    except ValueError:
        k = 0
    if not 1 <= k <= 256:
        raise InputError(f"environment variable SIM_FORCE_CHUNKS = {raw!r}: expected a whole "
                         "number from 1 to 256 (the step loop's force-buffer chunks)")
    return k


class State:
    """All arrays of a running simulation (no formulas; kernels do the work).

    Attributes
    ----------
    pf : (18, N) ndarray of float64
        Particle table, rows ``X, Y, VX, ...`` (see module constants).
    fix, mineral, grain : (N,) ndarray of int8, int32, int32
    quiet : (N,) ndarray of int32
        Consecutive quiet steps (sleep test).
    pid : (N,) ndarray of int64
        Specimen index of each particle (differs from the position once particles are removed).
    bf : (28, B) ndarray of float64
        Bond table: bond forces, moment, constants, break records, and for parallel-bonded
        pairs the linear contact part (rows LFS, LFN, LKN, LKS, LMU, LCN, LCS), which is
        computed with the bond instead of in the Verlet contact list.
    bi, bj : (B,) int32; bkind, bstate : (B,) int8; bid : (B,) int64
        Pairs, kind (0 pb, 1 sj), state (0 intact, 1 tension, 2 shear), specimen bond index.
    excl_ptr, excl_adj : CSR of bonded partners (excluded from the Verlet contact list).
    cf : (7, C) float64; ci, cj : (C,) int32; cstart : (N+1,) int64; nc : int
        Contact table, pairs and owner index (contacts of i are cstart[i]:cstart[i+1]).
    acc : (K, 4N) ndarray of float64
        Force buffers, one row per chunk of the step loop (one row at first; the engine
        grows it to its chunk count with :meth:`ensure_rows`), ``acc[c, 4p:4p+3]`` =
        (fx, fy, moment); between calls row 0
        holds the force at the current positions and the other rows are zero (rebuilt from
        fx, fy, fm on load, so not saved).
    wf : (W, 17) float64; qf : (5, Q) float64; qp, qw : (Q,) int32; nq : int
        Walls and wall contacts.
    """

    ARRAYS = ("pf", "fix", "quiet", "mineral", "grain", "pid", "bf", "bi", "bj", "bkind",
              "bstate", "bid", "excl_ptr", "excl_adj", "cf", "ci", "cj", "cstart", "wf", "qf", "qp",
              "qw", "logged")

    def __init__(self, **arrays):
        for k in self.ARRAYS:
            setattr(self, k, arrays[k])
        self.acc = np.zeros((1, 4 * self.pf.shape[1]))
        self.acc[0, 0::4] = self.pf[FX]
        self.acc[0, 1::4] = self.pf[FY]
        self.acc[0, 2::4] = self.pf[FM]
        self.nc = int(arrays.get("nc", 0))
        self.nq = int(arrays.get("nq", 0))
        self.npb = int(arrays.get("npb", 0))

    def ensure_rows(self, k: int) -> None:
        """Give ``acc`` at least ``k`` rows (the new rows zero: canonical form is kept)."""
        if self.acc.shape[0] < k:
            grown = np.zeros((k, self.acc.shape[1]))
            grown[:self.acc.shape[0]] = self.acc
            self.acc = grown

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
