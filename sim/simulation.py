"""Simulation: owns the state and the lists and drives the compiled step loop.

No formulas live here (STYLE.md §5 rule 5): laws are in :mod:`sim.contacts`, loops in
:mod:`sim.forces` and :mod:`sim.integrate`, walls in :mod:`sim.walls`. The state is built by
:mod:`sim.build_state`, read and changed through :mod:`sim.access` (particles, bonds, walls) and
saved by :mod:`sim.checkpoint`.
"""
from __future__ import annotations

import contextlib
import os
import signal
import threading

import numba
import numpy as np

from . import config
from .access import ParticleAccess, WallAccess
from .build_state import initial_state
from .checkpoint import load_simulation, save_simulation
from .checks import instability_error
from .contacts.linear import dashpot_coefficients, linear_stiffness
from .cracks import CrackLog, crack_records
from .errors import InputError
from .integrate import critical_timestep, run_steps
from .measure import energies, unbalanced_ratio
from .neighbors import build_contacts
from .specimen import Specimen
from .state import (
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
    INERTIA,
    INVI,
    INVM,
    LCN,
    LCS,
    LKN,
    LKS,
    MASS,
    NCF,
    NQF,
    Q_FS,
    Q_KN,
    Q_KS,
    Q_MU,
    SIZE,
    W_DISP,
    W_EMOD,
    W_FRIC,
    X0,
    Y0,
    R,
    X,
    Y,
    force_chunks,
)
from .walls import carry_history, wall_candidates


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


class Simulation(ParticleAccess, WallAccess):
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
        self.state = initial_state(specimen, pb_mcf=self.pb_mcf,
                                   sj_dilation_deg=self.sj_dilation_deg)
        self._rmean = float(np.mean(specimen.r))
        self._info = np.zeros(8)
        self.rebuild()

    # ------------------------------------------------------------------ construction
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

    # ------------------------------------------------------------------ checkpoint
    def save(self, path) -> None:
        """Write the full state to ``path`` (:func:`sim.checkpoint.save_simulation`)."""
        save_simulation(self, path)

    @classmethod
    def load(cls, path) -> "Simulation":
        """Read a checkpoint written by :meth:`save` (:func:`sim.checkpoint.load_simulation`)."""
        _set_wait_policy()
        return load_simulation(cls, path)

    def __repr__(self) -> str:
        st = self.state
        return (f"Simulation(N={st.n}, bonds={st.n_bonds} ({int(np.sum(st.bstate == 0))} intact), "
                f"contacts={st.nc}, walls={st.n_walls}, step={self.step}, dt={self.dt:.3e} s)")


__all__ = ["Simulation"]
