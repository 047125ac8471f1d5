"""Simulation: owns the state and the lists, drives the compiled step loop, checkpoints.

No formulas live here (STYLE.md §5 rule 5): laws are in :mod:`sim.contacts`, loops in
:mod:`sim.forces` and :mod:`sim.integrate`, walls in :mod:`sim.walls`.
"""
from __future__ import annotations

import contextlib
import json
import os
import signal
import threading

import numba
import numpy as np

from . import config
from ._io import save_npz_atomic
from .checks import instability_error
from .contacts.linear import dashpot_coefficients, linear_stiffness
from .contacts.parallel_bond import pb_constants
from .cracks import CrackLog, crack_records
from .errors import InputError
from .integrate import critical_timestep, run_steps
from .measure import energies, unbalanced_ratio, virial_stress
from .neighbors import build_contacts, partner_csr
from .specimen import Specimen
from .state import (
    ARI,
    BRK_NX,
    BRK_NY,
    BRK_STEP,
    BRK_X,
    BRK_Y,
    C_CN,
    C_CS,
    C_FS,
    C_KN,
    C_KS,
    C_MU,
    COHA,
    FIX_ROTATION,
    FIX_X,
    FIX_Y,
    FM,
    FRIC,
    FVX,
    FVY,
    FW,
    FX,
    FY,
    INERTIA,
    INVI,
    INVM,
    KNA,
    KNI,
    KSA,
    LCN,
    LCS,
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
    Q_FS,
    Q_KN,
    Q_KS,
    Q_MU,
    SIZE,
    TANDIL,
    TANFA,
    TENA,
    VX,
    VY,
    W_DISP,
    W_EMOD,
    W_FRIC,
    W_FX,
    W_FY,
    W_GAIN,
    W_LENGTH,
    W_NX,
    W_NY,
    W_PX,
    W_PY,
    W_SERVO,
    W_TARGET,
    W_VMAX,
    W_VX,
    W_VY,
    X0,
    Y0,
    R,
    State,
    W,
    X,
    Y,
    force_chunks,
)
from .walls import carry_history, wall_candidates

FORMAT = "gbmsim-checkpoint-1"


@contextlib.contextmanager
def _ctrl_c_between_calls():
    """Hold a Ctrl-C (SIGINT) that arrives while the engine runs until its bookkeeping
    matches the particles; yields a list that is non-empty once one arrived.

    Python runs a signal handler between two bytecodes, and a KeyboardInterrupt raised between
    the compiled loop's return and the step, time and crack-log updates would leave a state
    whose checkpoint cannot be resumed. Only the main thread can hold signals; elsewhere, or
    when SIGINT is ignored or handled by someone else, nothing changes.
    """
    pending = []
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield pending
        return
    prev = signal.signal(signal.SIGINT, lambda signum, frame: pending.append(signum))
    try:
        yield pending
    finally:
        signal.signal(signal.SIGINT, prev)
    if pending:                 # arrived after the last check of the loop
        raise KeyboardInterrupt


def _set_wait_policy():
    """OMP_WAIT_POLICY (config) unless set by the user; libgomp reads it when its thread pool
    starts, i.e. at the first parallel kernel call, so this runs before any kernel."""
    os.environ.setdefault("OMP_WAIT_POLICY", config.OMP_WAIT_POLICY)


class Simulation:
    """A 2D bonded-particle DEM run (PFC2D style) on a :class:`~sim.Specimen`.

    Notation: N particles, B bonds (parallel bonds and smooth joints, specimen order in the
    public API), W walls. SI units; compression positive for stresses reported on walls.

    Parameters
    ----------
    specimen : Specimen
        Particles, minerals, bonds (``bond_kind`` 0 parallel bond, 1 smooth joint).
    damping : float
        Local damping coefficient α in [0, 1) (PFC default 0.7).
    timestep_factor : float
        Safety factor f on the per-particle critical step; dt = f · min_p Δt_crit,p. The step is
        recomputed at every neighbour-list rebuild (PFC ``timestep auto``).
    dashpot_ratio : float or (float, float)
        Viscous dashpot ratios (β_n, β_s) of the linear contacts; 0 compiles no dashpot work.
    density_scale : bool
        Quasi-static mode (PFC ``timestep scale``): dt = 1 and every particle's inertial mass
        and moment of inertia are set to k/f² so that all particles are critically stable.
        Time and velocities lose their physical meaning; use only to pack or equilibrate.
    sleep : bool
        Let settled particles sleep (not integrated; pairs between two sleepers skipped) and
        wake when a pair or wall contact around them moves (thresholds ``sleep_disp`` ×
        mean radius per step, ``sleep_force_ratio``, ``sleep_steps``; sim.config). Off by
        default: it trades exactness for speed in large, mostly static models.
    skin : float, optional
        Verlet skin, m (default config.SKIN_FACTOR × mean radius).
    pb_mcf : float
        Parallel-bond moment contribution factor β̄ (default 1).
    sj_dilation_deg : float
        Smooth-joint dilation angle ψ (default 0).

    Attributes
    ----------
    step : int
        Steps completed.
    time : float
        Simulated time, s.
    dt : float
        Current time step, s.
    state : State
        The arrays (``state.pf[sim.state_rows...]``); the properties below are views.
    cracks : CrackLog
        One record per bond break.

    Examples
    --------
    >>> s = Specimen.lattice(nx=4, ny=4, radius=1e-3)
    >>> sim = Simulation(s)          # doctest: +SKIP
    >>> sim.cycle(100)               # doctest: +SKIP
    """

    def __init__(self, specimen: Specimen, *, damping: float = config.DAMPING,
                 timestep_factor: float = config.TIMESTEP_FACTOR, dashpot_ratio=0.0,
                 density_scale: bool = False, sleep: bool = False, skin: float | None = None,
                 pb_mcf: float = 1.0, sj_dilation_deg: float = 0.0,
                 sleep_disp: float = config.SLEEP_DISP,
                 sleep_force_ratio: float = config.SLEEP_FORCE_RATIO,
                 sleep_steps: int = config.SLEEP_STEPS):
        if not isinstance(specimen, Specimen):
            raise TypeError("specimen: expected a sim.Specimen")
        _set_wait_policy()
        specimen.validate()
        if not 0.0 <= damping < 1.0:
            raise InputError(f"damping = {damping}: expected 0 <= alpha < 1")
        if not 0.0 < timestep_factor:
            raise InputError(f"timestep_factor = {timestep_factor}: expected > 0")
        beta = np.broadcast_to(np.asarray(dashpot_ratio, float), (2,))
        if np.any(beta < 0) or np.any(beta >= 1):
            raise InputError(f"dashpot_ratio = {dashpot_ratio}: expected 0 <= beta < 1")
        if sleep and not (sleep_disp > 0 and sleep_force_ratio > 0 and sleep_steps >= 1):
            raise InputError("sleep_disp, sleep_force_ratio: expected > 0; sleep_steps >= 1")
        self.sleep = bool(sleep)
        self.sleep_disp = float(sleep_disp)
        self.sleep_force_ratio = float(sleep_force_ratio)
        self.sleep_steps = int(sleep_steps)
        self.specimen = specimen
        self.damping = float(damping)
        self.timestep_factor = float(timestep_factor)
        self.dashpot = (float(beta[0]), float(beta[1]))
        self.density_scale = bool(density_scale)
        self.pb_mcf = float(pb_mcf)
        self.sj_dilation_deg = float(sj_dilation_deg)
        self.skin = float(skin) if skin is not None else config.SKIN_FACTOR * float(
            np.mean(specimen.r))
        if self.skin <= 0:
            raise InputError(f"skin = {skin}: expected > 0 m")
        self.step = 0
        self.time = 0.0
        self.dt = 0.0
        self.damping_work = 0.0
        self.cracks = CrackLog()
        self.state = self._initial_state(specimen)
        self._rmean = float(np.mean(specimen.r))
        self._info = np.zeros(8)
        self.rebuild()

    # ------------------------------------------------------------------ construction
    def _initial_state(self, sp: Specimen) -> State:
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
            np.radians(sp.pb_fa[m]), sp.pb_rmul[m], self.pb_mcf, t)
        sj = slice(npb, nb)
        rb = np.minimum(r1[sj], r2[sj])
        area = 2.0 * rb * t
        bf[KNA, sj] = sp.sj_kn[0] * area
        bf[KSA, sj] = sp.sj_ks[0] * area
        bf[TENA, sj] = sp.sj_ten[0] * area
        bf[COHA, sj] = sp.sj_coh[0] * area
        bf[TANFA, sj] = np.tan(np.radians(sp.sj_fa[0]))
        bf[FRIC, sj] = sp.sj_fric[0]
        bf[TANDIL, sj] = np.tan(np.radians(self.sj_dilation_deg))
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

    # ------------------------------------------------------------------ neighbour lists
    def rebuild(self) -> None:
        """Rebuild the Verlet contact list and wall-contact list, then update the time step.

        Called automatically when the largest displacement since the last build exceeds half
        the skin; call it yourself after moving particles or walls by hand.
        """
        st = self.state
        sp = self.specimen
        n = st.n
        pf = st.pf
        nc_old = st.nc
        old_start, old_cj, old_fs = st.cstart, st.cj[:nc_old].copy(), st.cf[C_FS, :nc_old].copy()
        cap = max(st.ci.size, 16)
        nch = numba.get_num_threads()
        while True:
            cstart = np.zeros(n + 1, np.int64)
            ci = np.zeros(cap, np.int32)
            cj = np.zeros(cap, np.int32)
            fs = np.zeros(cap)
            total = build_contacts(pf[X], pf[Y], pf[R], self.skin, st.excl_ptr, st.excl_adj,
                                   old_start, old_cj, old_fs, cstart, ci, cj, fs, nch)
            if total <= cap:
                break
            cap = int(total * config.CAPACITY_GROWTH) + 16
        nc = int(total)
        cf = np.zeros((NCF, cap))
        cf[C_FS] = fs
        i, j = ci[:nc], cj[:nc]
        mi, mj = st.mineral[i], st.mineral[j]
        t = config.THICKNESS
        kr = 0.5 * (sp.kratio[mi] + sp.kratio[mj])
        cf[C_KN, :nc], cf[C_KS, :nc] = linear_stiffness(pf[R][i], pf[R][j], sp.emod[mi],
                                                        sp.emod[mj], kr, t)
        cf[C_MU, :nc] = np.minimum(sp.fric[mi], sp.fric[mj])
        st.cf, st.ci, st.cj, st.cstart, st.nc = cf, ci, cj, cstart, nc
        # walls
        qp, qw = wall_candidates(pf[X], pf[Y], pf[R], st.wf, self.skin)
        qf = np.zeros((NQF, qp.size))
        qf[Q_FS] = carry_history(n, st.qp[:st.nq], st.qw[:st.nq], st.qf[Q_FS, :st.nq], qp, qw)
        if qp.size:
            wm = st.mineral[qp]
            e = np.where(np.isnan(st.wf[qw, W_EMOD]), sp.emod[wm], st.wf[qw, W_EMOD])
            qf[Q_KN] = 2.0 * t * e
            qf[Q_KS] = qf[Q_KN] / sp.kratio[wm]
            qf[Q_MU] = st.wf[qw, W_FRIC]
        st.qp, st.qw, st.qf, st.nq = qp, qw, qf, int(qp.size)
        st.wf[:, W_DISP] = 0.0
        pf[X0] = pf[X]
        pf[Y0] = pf[Y]
        self._update_timestep()
        if self.dashpot != (0.0, 0.0):
            m = pf[MASS]
            cf[C_CN, :nc], cf[C_CS, :nc] = dashpot_coefficients(
                m[i], m[j], cf[C_KN, :nc], cf[C_KS, :nc], self.dashpot[0], self.dashpot[1])
            pb = slice(0, st.npb)
            bf = st.bf
            bf[LCN, pb], bf[LCS, pb] = dashpot_coefficients(
                m[st.bi[pb]], m[st.bj[pb]], bf[LKN, pb], bf[LKS, pb], self.dashpot[0],
                self.dashpot[1])
        # contact and wall forces at the current positions (shear history carried over)
        self._refresh = True
        self._run(0)

    def _update_timestep(self) -> None:
        st = self.state
        dt_p, ktr, krot = critical_timestep(st)
        f = self.timestep_factor
        if self.density_scale:
            has = ktr > 0
            st.pf[MASS] = np.where(has, ktr / f ** 2, st.pf[MASS])
            st.pf[INERTIA] = np.where(krot > 0, krot / f ** 2, st.pf[INERTIA])
            st.pf[INVM] = 1.0 / st.pf[MASS]
            st.pf[INVI] = 1.0 / st.pf[INERTIA]
            self.dt = 1.0
            return
        dmin = float(np.min(dt_p)) if dt_p.size else np.inf
        if not np.isfinite(dmin):
            # nothing touches anything: any step is stable; take one based on a stiff contact
            e = self.specimen.emod[st.mineral]
            dmin = float(np.min(np.sqrt(st.pf[MASS] / (2.0 * config.THICKNESS * e))))
        self.dt = f * dmin
        has = ktr > 0
        kom = ktr[has] / st.pf[MASS][has]
        self._kspread = float(kom.max() / kom.min()) if kom.size else float("nan")

    # ------------------------------------------------------------------ running
    def cycle(self, n: int, *, checkpoint=None, every: int = 0) -> "Simulation":
        """Run ``n`` steps.

        Parameters
        ----------
        n : int
            Number of steps (>= 0).
        checkpoint : path, optional
            Write :meth:`save` to this path every ``every`` steps (and never a partial file).
        every : int
            Checkpoint interval in steps.

        Raises
        ------
        InstabilityError
            NaN/inf, energy blow-up or excessive overlap; names cause, step, particle/contact
            and a hint. The state in memory is then invalid; checkpoint files are not touched.
        """
        n = int(n)
        if n < 0:
            raise InputError(f"n = {n}: expected a non-negative number of steps")
        if checkpoint is not None and every > 0:
            left = n
            while left > 0:
                k = min(every - self.step % every, left)
                self._run(k)
                left -= k
                if self.step % every == 0:
                    self.save(checkpoint)
            return self
        self._run(n)
        return self

    @property
    def force_chunks(self) -> int:
        """Chunks of the step loop: 1 below ``config.PARALLEL_MIN_PARTICLES`` particles, else
        :func:`sim.state.force_chunks` (``config.FORCE_CHUNKS`` = 2 unless ``SIM_FORCE_CHUNKS``
        is set). It fixes the summation order of the forces, so results do not depend on the
        thread count; at most this many threads work in the step loop."""
        if self.state.n < config.PARALLEL_MIN_PARTICLES:
            return 1
        return force_chunks()

    def _run(self, n: int) -> None:
        nch = self.force_chunks
        self.state.ensure_rows(nch)
        # one chunk runs on one thread: waking a thread pool costs more than the work
        nthreads = numba.get_num_threads()
        with _ctrl_c_between_calls() as pending:
            if nch == 1 and nthreads > 1:
                numba.set_num_threads(1)
                try:
                    self._run_chunks(n, 1, pending)
                finally:
                    numba.set_num_threads(nthreads)
            else:
                self._run_chunks(n, nch, pending)

    def _run_chunks(self, n: int, nch: int, pending=()) -> None:
        st = self.state
        info = self._info
        left = n
        use_dash = self.dashpot != (0.0, 0.0)
        while left > 0 or self._refresh:
            info[:] = 0.0
            step0, time0, dt = self.step, self.time, self.dt
            done, status = run_steps(
                left, step0, dt, self.damping, nch, self.skin, config.MAX_STEP_DISPLACEMENT,
                config.MAX_OVERLAP, config.THICKNESS, config.SERVO_ALPHA, st.pf, st.fix, st.bi,
                st.bj, st.bstate, st.bf, st.npb, st.ci, st.cj, st.cf, st.nc, use_dash, st.wf,
                st.qp, st.qw, st.qf, st.nq, st.acc, self._refresh, self.sleep,
                self.sleep_disp * self._rmean, self.sleep_force_ratio, self.sleep_steps,
                st.quiet, info)
            self._refresh = False
            self.step += int(done)
            self.time += int(done) * dt
            self.damping_work += float(info[3])
            left -= int(done)
            if info[0] > 0:
                self._harvest_cracks(step0, time0, dt)
            if status == config.STATUS_UNSTABLE:
                raise instability_error(int(info[1]), int(info[2]), self.step, self.dt,
                                        self.timestep_factor, (st.ci, st.cj), (st.qp, st.qw),
                                        getattr(self, "_kspread", None), (st.bi, st.bj))
            if status == config.STATUS_REBUILD:
                self.rebuild()
            if pending:
                # Ctrl-C arrived during the call: the step, time and crack log now match
                # the particles, so a checkpoint taken by the caller is consistent
                raise KeyboardInterrupt

    def _harvest_cracks(self, step0, time0, dt) -> None:
        st = self.state
        new = np.nonzero((st.bstate != 0) & ~st.logged)[0]
        if new.size == 0:
            return
        new = new[np.argsort(st.bf[BRK_STEP, new], kind="stable")]
        st.logged[new] = True
        bf = st.bf
        i, j = st.bi[new], st.bj[new]
        steps = bf[BRK_STEP, new].astype(np.int64)
        ang = np.degrees(np.arctan2(bf[BRK_NY, new], bf[BRK_NX, new])) % 180.0
        self.cracks.append(**crack_records(
            st.bkind[new], st.bstate[new], step=steps, time=time0 + (steps - step0) * dt,
            x=bf[BRK_X, new], y=bf[BRK_Y, new], mineral_i=st.mineral[i], mineral_j=st.mineral[j],
            grain_i=st.grain[i], grain_j=st.grain[j], size_m=bf[SIZE, new], angle_deg=ang,
            bond=st.bid[new]))

    def solve(self, ratio: float = config.SOLVE_RATIO, max_steps: int = 1_000_000,
              interval: int = config.SOLVE_CHECK_INTERVAL) -> float:
        """Cycle until the mean unbalanced-force ratio falls below ``ratio``.

        Returns
        -------
        ratio : float
            The ratio reached (above the target if ``max_steps`` ran out first).
        """
        done = 0
        cur = self.unbalanced_ratio()
        while done < max_steps:
            k = min(interval, max_steps - done)
            self.cycle(k)
            done += k
            cur = self.unbalanced_ratio()
            if cur <= ratio:
                break
        return cur

    def unbalanced_ratio(self) -> float:
        """Mean unbalanced force / mean contact force (see :func:`sim.measure.unbalanced_ratio`)."""
        return unbalanced_ratio(self.state)

    def energy(self) -> dict:
        """Energies, J: ``kinetic, strain_bond, strain_contact, strain_wall, damping`` (work
        dissipated by local damping since the start, positive) and ``total`` (kinetic + strain)."""
        e = energies(self.state, self.dt, self.damping)
        e["damping"] = -self.damping_work
        e["total"] = e["kinetic"] + e["strain_bond"] + e["strain_contact"] + e["strain_wall"]
        return e

    # ------------------------------------------------------------------ particles
    def _idx(self, idx):
        idx = np.asarray(idx)
        if idx.dtype == bool:
            if idx.shape != (self.state.n,):
                raise InputError(f"idx: boolean mask of shape {idx.shape}, expected "
                                 f"({self.state.n},)")
            return np.nonzero(idx)[0]
        idx = np.atleast_1d(idx).astype(np.int64)
        if idx.size and (idx.min() < 0 or idx.max() >= self.state.n):
            raise InputError(f"idx: particle indices outside 0..{self.state.n - 1}")
        return idx

    def fix_velocity(self, idx, vx: float | None, vy: float | None,
                     w: float | None = None) -> None:
        """Prescribe the velocity of particles ``idx`` (index array or boolean mask).

        Each of ``vx, vy`` (m/s) and ``w`` (rad/s) that is not None is held (a scalar or one
        value per particle); a None component stays free (``vx=None, vy=0`` is a roller).
        The reaction on the group is :meth:`group_force`.
        """
        p = self._idx(idx)
        st = self.state
        st.fix[p] &= np.int8(~8)  # wake
        st.quiet[p] = 0
        for comp, flag, frow, vrow in ((vx, FIX_X, FVX, VX), (vy, FIX_Y, FVY, VY),
                                       (w, FIX_ROTATION, FW, W)):
            if comp is not None:
                comp = np.broadcast_to(np.asarray(comp, float), p.shape)
                st.fix[p] |= flag
                st.pf[frow, p] = comp
                st.pf[vrow, p] = comp

    def free(self, idx) -> None:
        """Release particles ``idx`` from any prescribed velocity (and wake them)."""
        p = self._idx(idx)
        self.state.fix[p] = 0
        self.state.quiet[p] = 0

    @property
    def asleep(self):
        """(N,) bool: particles currently asleep (only with ``sleep=True``)."""
        return (self.state.fix & 8) != 0

    def set_velocity(self, idx, vx: float, vy: float, w: float = 0.0) -> None:
        """Set the current velocity of (free) particles ``idx``."""
        p = self._idx(idx)
        self.state.fix[p] &= np.int8(~8)  # wake
        self.state.quiet[p] = 0
        self.state.pf[VX, p] = vx
        self.state.pf[VY, p] = vy
        self.state.pf[W, p] = w

    def stress(self, idx, area: float) -> np.ndarray:
        """Mean stress (virial) of particles ``idx`` over ``area`` (m²), Pa, compression positive.

        Returns
        -------
        sigma : (2, 2) ndarray
            Symmetric; see :func:`sim.measure.virial_stress`.
        """
        mask = np.zeros(self.state.n, bool)
        mask[self._idx(idx)] = True
        return virial_stress(self.state, mask, area)

    def group_force(self, idx) -> tuple:
        """(fx, fy), N: sum of the contact forces acting on particles ``idx`` in the last step,
        i.e. the force the rest of the model exerts on the group (internal forces cancel)."""
        p = self._idx(idx)
        return float(np.sum(self.state.pf[FX, p])), float(np.sum(self.state.pf[FY, p]))

    # ------------------------------------------------------------------ walls
    def add_wall(self, point, normal, *, velocity=(0.0, 0.0), fric: float = 0.0,
                 emod: float | None = None) -> int:
        """Add a rigid infinite line through ``point`` with unit ``normal`` toward the particles.

        Parameters
        ----------
        point, normal : (2,) array-like, m and unit vector
        velocity : (2,) m/s
        fric : float
            Wall–particle friction coefficient.
        emod : float, optional
            E* of the wall contacts (k_n = 2 t E*); default: the particle mineral's ``emod``.

        Returns
        -------
        index : int
        """
        nrm = np.asarray(normal, float)
        if nrm.shape != (2,) or not np.isfinite(nrm).all() or np.hypot(*nrm) == 0:
            raise InputError(f"normal = {normal}: expected a non-zero 2-vector")
        if fric < 0:
            raise InputError(f"fric = {fric}: expected >= 0")
        if emod is not None and not emod > 0:
            raise InputError(f"emod = {emod}: expected > 0 Pa")
        nrm = nrm / np.hypot(*nrm)
        row = np.zeros(NWF)
        row[[W_PX, W_PY]] = np.asarray(point, float)
        row[[W_NX, W_NY]] = nrm
        row[[W_VX, W_VY]] = np.asarray(velocity, float)
        row[W_FRIC] = fric
        row[W_EMOD] = np.nan if emod is None else emod
        row[W_VMAX] = config.SERVO_VMAX
        self.state.wf = np.vstack([self.state.wf, row[None]])
        self.rebuild()
        return self.state.wf.shape[0] - 1

    def _wall(self, i):
        if not 0 <= int(i) < self.state.wf.shape[0]:
            raise InputError(f"wall {i}: expected 0..{self.state.wf.shape[0] - 1}")
        return int(i)

    def set_wall_velocity(self, i: int, vx: float, vy: float) -> None:
        """Move wall ``i`` at (vx, vy) m/s (clears its servo)."""
        k = self._wall(i)
        self.state.wf[k, W_SERVO] = 0.0
        self.state.wf[k, [W_VX, W_VY]] = vx, vy

    def wall_position(self, i: int) -> tuple:
        """Current point (x, y) of wall ``i``, m."""
        k = self._wall(i)
        return float(self.state.wf[k, W_PX]), float(self.state.wf[k, W_PY])

    def wall_velocity(self, i: int) -> tuple:
        k = self._wall(i)
        return float(self.state.wf[k, W_VX]), float(self.state.wf[k, W_VY])

    def wall_force(self, i: int) -> tuple:
        """(fx, fy), N: force exerted BY the particles ON wall ``i`` in the last step."""
        k = self._wall(i)
        return float(self.state.wf[k, W_FX]), float(self.state.wf[k, W_FY])

    def wall_stress(self, i: int, length_m: float) -> float:
        """Normal stress on wall ``i`` over ``length_m`` × t, Pa, compression positive."""
        k = self._wall(i)
        wf = self.state.wf
        return float(-(wf[k, W_FX] * wf[k, W_NX] + wf[k, W_FY] * wf[k, W_NY])
                     / (length_m * config.THICKNESS))

    def set_servo(self, i: int, stress_pa: float, length_m: float, gain: float | None = None,
                  vmax: float = config.SERVO_VMAX) -> None:
        """Servo-control wall ``i`` along its normal to hold normal force/(length × t) at
        ``stress_pa`` (compression positive).

        The wall speed is v = G (σ_target − σ) along n̂. Without ``gain`` (m/s/Pa), G is chosen
        every step as α L t /(Σk_n Δt) with α = config.SERVO_ALPHA (PFC), capped at ``vmax``.
        """
        k = self._wall(i)
        if not length_m > 0:
            raise InputError(f"length_m = {length_m}: expected > 0 m")
        if gain is not None and not gain > 0:
            raise InputError(f"gain = {gain}: expected > 0 m/s/Pa")
        wf = self.state.wf
        wf[k, W_SERVO] = 1.0
        wf[k, W_TARGET] = stress_pa
        wf[k, W_LENGTH] = length_m
        wf[k, W_GAIN] = 0.0 if gain is None else gain
        wf[k, W_VMAX] = vmax

    def clear_servo(self, i: int) -> None:
        """Stop the servo of wall ``i`` and hold it still."""
        k = self._wall(i)
        self.state.wf[k, W_SERVO] = 0.0
        self.state.wf[k, [W_VX, W_VY]] = 0.0

    @property
    def n_walls(self) -> int:
        return int(self.state.wf.shape[0])

    # ------------------------------------------------------------------ views
    def _row(k):
        return property(lambda self: self.state.pf[k],
                        doc="(N,) float64 view into the particle table (SI).")

    x = _row(X)
    y = _row(Y)
    vx = _row(VX)
    vy = _row(VY)
    w = _row(W)
    fx = _row(FX)
    fy = _row(FY)
    fm = _row(FM)
    radius = _row(R)
    mass = _row(MASS)
    inertia = _row(INERTIA)
    del _row

    @property
    def n_particles(self) -> int:
        return self.state.n

    @property
    def mineral(self):
        return self.state.mineral

    @property
    def grain(self):
        return self.state.grain

    def _to_specimen_order(self, a, fill=0):
        out = np.full(self.specimen.n_bonds, fill, dtype=a.dtype)
        out[self.state.bid] = a
        return out

    @property
    def bond_state(self):
        """(B,) int8 in specimen bond order: 0 intact, 1 broken in tension, 2 in shear,
        3 removed with a particle (:meth:`remove_particles`)."""
        return self._to_specimen_order(self.state.bstate, fill=3)

    @property
    def bond_intact(self):
        """(B,) bool in specimen bond order."""
        return self.bond_state == 0

    def bond_forces(self):
        """Per bond, specimen order: (fn, fs, moment) — compression-positive normal force (N),
        shear force (N), bond moment (N·m; 0 for smooth joints)."""
        bf = self.state.bf
        from .state import FN, FS, MB
        return tuple(self._to_specimen_order(bf[k]) for k in (FN, FS, MB))

    @property
    def particle_id(self):
        """(N,) specimen index of each current particle (identity until particles are removed)."""
        return self.state.pid

    def remove_particles(self, mask) -> int:
        """Delete particles (e.g. excavation) with their bonds and contacts, then re-list.

        Parameters
        ----------
        mask : (N,) bool or index array
            Particles to remove (current indexing).

        Returns
        -------
        n_removed : int

        Notes
        -----
        Remaining particles are renumbered in order (see :attr:`particle_id`); bonds touching
        a removed particle get state 3 in :attr:`bond_state`; shear histories of the remaining
        contacts are kept. Forces are re-evaluated at once, so the removed particles' pull or
        push vanishes in the next step (an instantaneous excavation).
        """
        st = self.state
        gone = np.zeros(st.n, bool)
        gone[self._idx(mask)] = True
        if not gone.any():
            return 0
        if gone.all():
            raise InputError("mask: would remove every particle")
        keep = ~gone
        new = np.cumsum(keep) - 1
        kb = keep[st.bi] & keep[st.bj]
        bi, bj = new[st.bi[kb]].astype(np.int32), new[st.bj[kb]].astype(np.int32)
        n = int(keep.sum())
        kc = keep[st.ci[:st.nc]] & keep[st.cj[:st.nc]]
        ci, cj = new[st.ci[:st.nc][kc]].astype(np.int32), new[st.cj[:st.nc][kc]].astype(np.int32)
        cf = st.cf[:, :st.nc][:, kc]
        cstart = np.zeros(n + 1, np.int64)
        np.add.at(cstart, ci.astype(np.int64) + 1, 1)
        kq = keep[st.qp[:st.nq]]
        qp, qw = new[st.qp[:st.nq][kq]].astype(np.int32), st.qw[:st.nq][kq]
        excl_ptr, excl_adj = partner_csr(n, bi, bj)
        pf = st.pf[:, keep].copy()
        self.state = State(pf=pf, fix=st.fix[keep], quiet=st.quiet[keep], mineral=st.mineral[keep],
                           grain=st.grain[keep], pid=st.pid[keep], bf=st.bf[:, kb].copy(),
                           bi=bi, bj=bj, bkind=st.bkind[kb], bstate=st.bstate[kb],
                           bid=st.bid[kb], excl_ptr=excl_ptr, excl_adj=excl_adj, cf=cf.copy(),
                           ci=ci, cj=cj, cstart=np.cumsum(cstart), wf=st.wf, qf=st.qf[:, kq],
                           qp=qp, qw=qw, logged=st.logged[kb], nc=int(kc.sum()),
                           nq=int(kq.sum()), npb=int(np.sum(st.bkind[kb] == 0)))
        self.rebuild()
        return int(gone.sum())

    # ------------------------------------------------------------------ checkpoint
    def save(self, path) -> None:
        """Write the full state to ``path`` (npz, no pickle) atomically: temp file, fsync, rename.

        :meth:`load` of the file continues bit-identically on the same machine at the same
        :attr:`force_chunks` (any thread count).
        """
        meta = dict(format=FORMAT, step=self.step, time=self.time, dt=self.dt,
                    damping=self.damping, timestep_factor=self.timestep_factor,
                    dashpot=list(self.dashpot), density_scale=self.density_scale,
                    skin=self.skin, pb_mcf=self.pb_mcf, sj_dilation_deg=self.sj_dilation_deg,
                    damping_work=self.damping_work, kspread=getattr(self, "_kspread", None),
                    refresh=bool(self._refresh), sleep=self.sleep, sleep_disp=self.sleep_disp,
                    sleep_force_ratio=self.sleep_force_ratio, sleep_steps=self.sleep_steps)
        arrays = {"sim_meta": np.array(json.dumps(meta))}
        arrays.update({"state__" + k: v for k, v in self.state.to_dict().items()})
        arrays.update({"spec__" + k: v for k, v in self.specimen.to_arrays().items()})
        arrays.update(self.cracks.to_npz_dict())
        save_npz_atomic(path, arrays)

    @classmethod
    def load(cls, path) -> "Simulation":
        """Read a checkpoint written by :meth:`save`."""
        _set_wait_policy()
        path = os.fspath(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except FileNotFoundError:
            raise InputError(f"{path}: file not found") from None
        except Exception as exc:
            raise InputError(f"{path}: not a readable checkpoint ({exc})") from None
        try:
            meta = json.loads(str(data["sim_meta"][()]))
        except (KeyError, json.JSONDecodeError):
            raise InputError(f"{path}: field 'sim_meta' missing or not JSON") from None
        if meta.get("format") != FORMAT:
            raise InputError(f"{path}: format {meta.get('format')!r}, expected {FORMAT!r}")
        spec = Specimen.from_arrays({k[6:]: v for k, v in data.items() if k.startswith("spec__")},
                                    source=path)
        self = cls.__new__(cls)
        self.specimen = spec
        self.damping = meta["damping"]
        self.timestep_factor = meta["timestep_factor"]
        self.dashpot = tuple(meta["dashpot"])
        self.density_scale = meta["density_scale"]
        self.skin = meta["skin"]
        self.pb_mcf = meta["pb_mcf"]
        self.sj_dilation_deg = meta["sj_dilation_deg"]
        self.step = int(meta["step"])
        self.time = float(meta["time"])
        self.dt = float(meta["dt"])
        self.damping_work = float(meta["damping_work"])
        self._refresh = bool(meta["refresh"])
        self.sleep = bool(meta["sleep"])
        self.sleep_disp = float(meta["sleep_disp"])
        self.sleep_force_ratio = float(meta["sleep_force_ratio"])
        self.sleep_steps = int(meta["sleep_steps"])
        self._rmean = float(np.mean(spec.r))
        if meta.get("kspread") is not None:
            self._kspread = meta["kspread"]
        self.state = State.from_dict({k[7:]: v for k, v in data.items()
                                      if k.startswith("state__")})
        self.cracks = CrackLog.from_npz_dict(data)
        self._info = np.zeros(8)
        return self

    def __repr__(self) -> str:
        st = self.state
        return (f"Simulation(N={st.n}, bonds={st.n_bonds} ({int(np.sum(st.bstate == 0))} intact), "
                f"contacts={st.nc}, walls={st.n_walls}, step={self.step}, dt={self.dt:.3e} s)")


__all__ = ["Simulation"]
