"""Linear contact law (PFC ``linear``, deformability method; REFERENCE.md §1a, §2).

The per-step law is a scalar ``njit`` function of one contact and checks nothing; the stiffness
and dashpot constants are plain numpy functions (scalars or arrays), evaluated at list rebuilds.
"""
import numpy as np

from .._jit import njit


def linear_stiffness(r1, r2, e1, e2, kratio, t):
    """Deformability stiffnesses of a ball–ball contact.

    Parameters
    ----------
    r1, r2 : float, m
        Radii.
    e1, e2 : float, Pa
        Effective moduli E* of the two particles' minerals.
    kratio : float
        kn / ks.
    t : float, m
        Thickness.

    Returns
    -------
    kn, ks : float, N/m

    Notes
    -----
    k_n = A E*/L with A = 2 min(R1, R2) t and L = R1 + R2. Between two minerals the moduli are
    combined as two springs of lengths R1 and R2 in series, E = L / (R1/E1 + R2/E2), which is E*
    when both minerals agree.
    """
    kn = 2.0 * np.minimum(r1, r2) * t / (r1 / e1 + r2 / e2)
    return kn, kn / kratio


@njit
def linear_force(overlap, dus, kn, ks, mu, fs):
    """Normal and shear force of a linear contact (lin_mode 0).

    Parameters
    ----------
    overlap : float, m
        -g, positive when the balls overlap (the caller ensures it is).
    dus : float, m
        Shear displacement increment V·t Δt.
    kn, ks : float, N/m
    mu : float
        Friction coefficient.
    fs : float, N
        Shear force of the previous step (history).

    Returns
    -------
    fn, fs : float, N
        Compression-positive normal force k_n·overlap; shear force after the Coulomb limit.
    slipping : bool
    """
    fn = kn * overlap
    fs = fs - ks * dus
    lim = mu * fn
    if fs > lim:
        return fn, lim, True
    if fs < -lim:
        return fn, -lim, True
    return fn, fs, False


@njit
def linear_force_masked(overlap, dus, kn, ks, mu, fs):
    """:func:`linear_force` for a pair that may or may not touch, without branches.

    Parameters are those of :func:`linear_force`, except that ``overlap`` may be ≤ 0 (the
    balls are apart): then both forces are 0 and the shear history is reset. About half the
    parallel-bonded pairs of a packing touch at any time, so a branch on the overlap would be
    mispredicted half the time (measured: 15.6 vs 19.6 ns per bond).

    Returns
    -------
    fn, fs : float, N
    on : float
        1.0 when the balls touch, else 0.0.
    """
    on = 1.0 if overlap > 0.0 else 0.0
    fn = kn * overlap * on
    lim = mu * fn
    fs = min(max((fs - ks * dus) * on, -lim), lim)
    return fn, fs, on


def dashpot_coefficients(m1, m2, kn, ks, beta_n, beta_s):
    """Viscous dashpot constants c_n = 2β_n √(m_c k_n), c_s = 2β_s √(m_c k_s), N·s/m."""
    mc = m1 * m2 / (m1 + m2)
    return 2.0 * beta_n * np.sqrt(mc * kn), 2.0 * beta_s * np.sqrt(mc * ks)
