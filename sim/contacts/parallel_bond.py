"""Linear parallel bond (PFC 5/6 ``linearpbond``; REFERENCE.md §1a, §2, §3).

Scalar ``njit`` laws of one bond. They check nothing.
"""
import numpy as np

from .._jit import njit


def pb_constants(r1, r2, emod, kratio, ten, coh, fa_rad, rmul, mcf, t):
    """Per-bond constants, computed once at installation (numpy; scalars or arrays).

    Parameters
    ----------
    r1, r2 : float, m
    emod : float, Pa
        Bond modulus Ē (``pb_emod``).
    kratio : float
        k̄n / k̄s.
    ten, coh : float, Pa
        σ̄c and c̄.
    fa_rad : float, rad
        φ̄.
    rmul, mcf : float
        λ̄ and β̄ (moment contribution factor).
    t : float, m

    Returns
    -------
    kna, ksa, kni : float
        k̄n·Ā and k̄s·Ā (N/m), k̄n·Ī (N·m/rad).
    ari : float, 1/m
        β̄ Ā R̄ / Ī = 3 β̄ / R̄: multiplies |M̄| to give the moment part of σ̄·Ā.
    tena, coha : float, N
        σ̄c·Ā and c̄·Ā.
    tanfa : float
    size : float, m
        Bond diameter 2R̄ (crack length; area = size × t).

    Notes
    -----
    k̄n = Ē/L, L = R1 + R2; R̄ = λ̄ min(R1, R2); Ā = 2R̄t; Ī = (2/3)R̄³t.
    """
    rb = rmul * np.minimum(r1, r2)
    area = 2.0 * rb * t
    inertia = 2.0 / 3.0 * rb * rb * rb * t
    kn = emod / (r1 + r2)
    ks = kn / kratio
    return (kn * area, ks * area, kn * inertia, mcf * 3.0 / rb,
            ten * area, coh * area, np.tan(fa_rad), 2.0 * rb)


@njit
def pb_update(fn, fs, mb, dun, dus, dth, kna, ksa, kni, ari, tena, coha, tanfa):
    """Incremental update and break test of one intact parallel bond.

    Parameters
    ----------
    fn, fs, mb : float
        F̄n (N, compression positive), F̄s (N, along t̂), M̄ (N·m) of the previous step.
    dun, dus, dth : float
        Δδn (m, positive opening), Δδs (m), Δθ (rad).
    kna, ksa, kni, ari, tena, coha, tanfa : float
        From :func:`pb_constants`.

    Returns
    -------
    fn, fs, mb : float
        Updated force and moment (zero when the bond broke).
    mode : int
        0 intact, 1 tensile break, 2 shear break.

    Notes
    -----
    σ̄Ā = −F̄n + β̄|M̄|R̄Ā/Ī ≥ σ̄cĀ → tension; otherwise
    τ̄Ā = |F̄s| ≥ c̄Ā − min(−F̄n, σ̄cĀ) tan φ̄ → shear (PFC ``pbShearStrength``).
    """
    fn = fn - kna * dun
    fs = fs - ksa * dus
    mb = mb - kni * dth
    sig = -fn + ari * abs(mb)
    if sig >= tena:
        return 0.0, 0.0, 0.0, 1
    sn = -fn
    if sn > tena:
        sn = tena
    if abs(fs) >= coha - sn * tanfa:
        return 0.0, 0.0, 0.0, 2
    return fn, fs, mb, 0
