"""Slow plain-Python contact laws written straight from REFERENCE.md, to compare kernels with."""
import math


def linear(overlap, dus, kn, ks, mu, fs):
    fn = kn * overlap
    trial = fs - ks * dus
    lim = mu * fn
    if abs(trial) > lim:
        return fn, math.copysign(lim, trial)
    return fn, trial


def parallel_bond(fn, fs, m, dun, dus, dth, r1, r2, emod, kratio, ten, coh, fa_deg, rmul=1.0,
                  mcf=1.0, t=1.0):
    """Returns (fn, fs, m, state) with state 0 intact, 1 tension, 2 shear (REFERENCE.md §2-3)."""
    rb = rmul * min(r1, r2)
    a = 2 * rb * t
    i = 2.0 / 3.0 * rb ** 3 * t
    kn = emod / (r1 + r2)
    ks = kn / kratio
    fn = fn - kn * a * dun
    fs = fs - ks * a * dus
    m = m - kn * i * dth
    sigma = -fn / a + mcf * abs(m) * rb / i
    if sigma >= ten:
        return 0.0, 0.0, 0.0, 1
    s = min(-fn / a, ten)
    tau_c = coh - s * math.tan(math.radians(fa_deg))
    if abs(fs) / a >= tau_c:
        return 0.0, 0.0, 0.0, 2
    return fn, fs, m, 0


def smooth_joint(un, fs, state, dun, dus, kn_a, ks_a, ten_a, coh_a, fa_deg, fric, dil_deg=0.0,
                 gap=0.0, rmin=1.0, reach=1.0):
    """Returns (un, fn, fs, state) (REFERENCE.md §4); un = elastic normal overlap.

    Engine rule (config.SJ_REACH = ``reach``): an unbonded joint whose ball gap exceeds
    reach x rmin is out of reach: no force, un = -gap.
    """
    un = un - dun
    if state == 0:
        fn = kn_a * un
        fsb = fs - ks_a * dus
        if -fn >= ten_a:
            return un, 0.0, 0.0, 1
        if abs(fsb) < coh_a + fn * math.tan(math.radians(fa_deg)):
            return un, fn, fsb, 0
        state = 2
    if gap > reach * rmin:
        return -gap, 0.0, 0.0, state
    if un <= 0:
        return un, 0.0, 0.0, state
    fn = kn_a * un
    trial = fs - ks_a * dus
    lim = fric * fn
    if abs(trial) > lim:
        up = (abs(trial) - lim) / ks_a
        trial = math.copysign(lim, trial)
        un += up * math.tan(math.radians(dil_deg))
        fn = kn_a * un
    return un, fn, trial, state
