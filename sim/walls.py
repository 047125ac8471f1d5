"""Rigid walls (infinite lines): wall–particle contacts, velocity control and a stress servo.

A wall is a point p and a unit normal n̂; particles live on the side n̂ points to. The
wall–particle contact uses the linear law with r = R and L = R (k_n = 2 t E*), E* the wall's
modulus or, when unset, the particle mineral's. The force exerted by the particles on the wall is
the negative sum of the contact forces on the particles. Stress on a wall is its normal force
over (length × t), compression positive.
"""
import numpy as np

from ._jit import njit
from .contacts.linear import linear_force
from .state import (
    W_DISP,
    W_FX,
    W_FY,
    W_GAIN,
    W_KTOT,
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
)


@njit
def wall_forces(dt, x, y, vx, vy, w, r, acc, wf, qp, qw, nq, qfs, qkn, qks, qmu, qfn, kin, sleep,
                sleep_d):
    """Wall contacts and wall forces for one step (serial; W and Q are small).

    ``dt`` only scales the shear increment (0 re-evaluates the forces without motion).
    Adds the wall forces on the particles to the force buffer ``acc`` (``acc[4p:4p+3]``; with
    ``sleep`` also slot 3: |F| for awake particles, a wake vote for sleeping ones), writes
    the shear history ``qfs`` and normal force ``qfn`` of each wall contact, and the wall
    table columns W_FX, W_FY (force by the particles on the wall) and W_KTOT.

    Returns
    -------
    worst : float
        Largest overlap / R among wall contacts.
    qworst : int
        Its wall-contact index, -1 if none.
    """
    nw = wf.shape[0]
    for k in range(nw):
        wf[k, W_FX] = 0.0
        wf[k, W_FY] = 0.0
        wf[k, W_KTOT] = 0.0
    worst = 0.0
    qworst = -1
    for q in range(nq):
        p = qp[q]
        k = qw[q]
        nx = wf[k, W_NX]
        ny = wf[k, W_NY]
        dist = (x[p] - wf[k, W_PX]) * nx + (y[p] - wf[k, W_PY]) * ny
        ov = r[p] - dist
        if ov <= 0.0:
            qfs[q] = 0.0
            qfn[q] = 0.0
            continue
        a = r[p] - 0.5 * ov
        dvx = vx[p] - wf[k, W_VX]
        dvy = vy[p] - wf[k, W_VY]
        vt = -dvx * ny + dvy * nx - w[p] * a
        fn, fs, slip = linear_force(ov, vt * dt, qkn[q], qks[q], qmu[q], qfs[q])
        qfs[q] = fs
        qfn[q] = fn
        fx = fn * nx - fs * ny
        fy = fn * ny + fs * nx
        acc[4 * p] += fx
        acc[4 * p + 1] += fy
        acc[4 * p + 2] -= a * fs
        if sleep:
            if kin[8 * p + 6] > 0.0:
                if (abs(dvx) + abs(dvy)) * dt > sleep_d:
                    acc[4 * p + 3] += 1.0
            else:
                acc[4 * p + 3] += abs(fx) + abs(fy)
        wf[k, W_FX] -= fx
        wf[k, W_FY] -= fy
        wf[k, W_KTOT] += qkn[q]
        if ov / r[p] > worst:
            worst = ov / r[p]
            qworst = q
    return worst, qworst


@njit
def wall_motion(dt, t, servo_alpha, wf):
    """Servo velocities (from the current wall forces) and wall displacement over one step.

    Writes the wall table columns W_VX, W_VY (servo walls), W_PX, W_PY and W_DISP.
    """
    nw = wf.shape[0]
    for k in range(nw):
        nx = wf[k, W_NX]
        ny = wf[k, W_NY]
        if wf[k, W_SERVO] != 0.0:
            length = wf[k, W_LENGTH]
            sig = -(wf[k, W_FX] * nx + wf[k, W_FY] * ny) / (length * t)
            err = wf[k, W_TARGET] - sig
            vmax = wf[k, W_VMAX]
            if wf[k, W_GAIN] > 0.0:
                v = wf[k, W_GAIN] * err
            elif wf[k, W_KTOT] > 0.0:
                v = servo_alpha * length * t * err / (wf[k, W_KTOT] * dt)
            else:
                v = vmax if err > 0.0 else -vmax
            if v > vmax:
                v = vmax
            elif v < -vmax:
                v = -vmax
            wf[k, W_VX] = v * nx
            wf[k, W_VY] = v * ny
        ux = wf[k, W_VX] * dt
        uy = wf[k, W_VY] * dt
        wf[k, W_PX] += ux
        wf[k, W_PY] += uy
        wf[k, W_DISP] += np.sqrt(ux * ux + uy * uy)


def wall_candidates(x, y, r, wf, skin):
    """Particles within ``skin`` of each wall: (qp, qw) int32, sorted by wall then particle."""
    qp, qw = [], []
    for k in range(wf.shape[0]):
        dist = (x - wf[k, W_PX]) * wf[k, W_NX] + (y - wf[k, W_PY]) * wf[k, W_NY]
        idx = np.nonzero(dist - r < skin)[0]
        qp.append(idx)
        qw.append(np.full(idx.size, k))
    if not qp:
        return np.zeros(0, np.int32), np.zeros(0, np.int32)
    return np.concatenate(qp).astype(np.int32), np.concatenate(qw).astype(np.int32)


def carry_history(n, old_qp, old_qw, old_fs, qp, qw):
    """Shear history of the new wall contacts (qp, qw) looked up among the old ones."""
    fs = np.zeros(qp.size)
    if old_qp.size and qp.size:
        old_key = old_qw.astype(np.int64) * n + old_qp
        key = qw.astype(np.int64) * n + qp
        order = np.argsort(old_key)
        pos = np.searchsorted(old_key[order], key)
        pos = np.minimum(pos, old_key.size - 1)
        hit = old_key[order][pos] == key
        fs[hit] = old_fs[order][pos[hit]]
    return fs


def servo_stress(wf, k, t):
    """Normal stress (Pa, compression positive) on wall ``k`` of length ``wf[k, W_LENGTH]``."""
    return -(wf[k, W_FX] * wf[k, W_NX] + wf[k, W_FY] * wf[k, W_NY]) / (wf[k, W_LENGTH] * t)


__all__ = ["wall_forces", "wall_motion", "wall_candidates", "carry_history", "servo_stress"]
