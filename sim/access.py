"""What a simulation offers on its particles, bonds and walls (mixed into
:class:`sim.simulation.Simulation`): views of the particle table, prescribed velocities, group
forces and stresses, bond states, particle removal, rigid walls and their servos."""
from __future__ import annotations

import numpy as np

from . import config
from .errors import InputError
from .measure import virial_stress
from .neighbors import partner_csr
from .state import (
    FIX_ROTATION,
    FIX_X,
    FIX_Y,
    FM,
    FVX,
    FVY,
    FW,
    FX,
    FY,
    INERTIA,
    MASS,
    NWF,
    VX,
    VY,
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
    R,
    State,
    W,
    X,
    Y,
)

__all__ = ["ParticleAccess", "WallAccess"]


class ParticleAccess:
    """Particles and bonds of a running simulation (``self.state``, ``self.specimen``)."""

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


class WallAccess:
    """Rigid infinite walls of a running simulation: motion, forces, servo control."""

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
