"""Damping laws: local (non-viscous) damping per degree of freedom (REFERENCE.md §5).

Viscous contact dashpots live with the linear law
(:func:`sim.contacts.linear.dashpot_coefficients`).
"""
from ._jit import njit


@njit
def local_damping(f, v, alpha):
    """Local damping force −α |F| sign(v) of one degree of freedom.

    Parameters
    ----------
    f : float
        Unbalanced generalised force (N or N·m).
    v : float
        Current generalised velocity (m/s or rad/s); sign(0) = 0.
    alpha : float
        Damping coefficient (0.7 by default, P&C 2004).

    Returns
    -------
    fd : float

    Notes
    -----
    On a 1-DOF oscillator the amplitude falls by exactly (1 − α)/(1 + α) per full cycle.
    """
    if v > 0.0:
        return -alpha * abs(f)
    if v < 0.0:
        return alpha * abs(f)
    return 0.0


def restitution_from_ratio(beta):
    """Coefficient of restitution of a linear dashpot contact, exp(−πβ/√(1−β²))."""
    import math
    return math.exp(-math.pi * beta / math.sqrt(1.0 - beta * beta))


def ratio_from_restitution(e):
    """Dashpot ratio β giving restitution ``e``: −ln e / √(π² + ln² e)."""
    import math
    le = math.log(e)
    return -le / math.sqrt(math.pi ** 2 + le * le)
