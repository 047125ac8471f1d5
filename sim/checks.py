"""Instability detection at the Python boundary: turn a kernel status into InstabilityError."""
from __future__ import annotations

import numpy as np

from . import config
from .errors import InstabilityError


def instability_error(cause_code, index, step, dt, factor, pairs=None, wall_pairs=None,
                      kratio_spread=None, bond_pairs=None):
    """Build the :class:`InstabilityError` for a kernel stop.

    Parameters
    ----------
    cause_code : int
        1 NaN/inf, 2 energy blow-up (a particle moved > MAX_STEP_DISPLACEMENT·R in one step),
        3 ball–ball overlap, 4 wall overlap, 5 overlap of a bonded pair (> MAX_OVERLAP ×
        smaller radius).
    index : int
        Worst particle (codes 1, 2), contact (3) or wall contact (4).
    step : int
        Last good step.
    dt, factor : float
        Current step (s) and safety factor, quoted in the hint.
    pairs, wall_pairs : tuple of arrays, optional
        (ci, cj) and (qp, qw) to name the particles of a contact.
    kratio_spread : float, optional
        Largest / smallest per-particle k/m, quoted in the hint.
    """
    cause = {1: "nan", 2: "energy", 3: "overlap", 4: "overlap", 5: "overlap"}[int(cause_code)]
    if cause_code in (1, 2):
        what = f"particle {index}"
        detail = ("velocity or position became NaN/inf" if cause_code == 1 else
                  f"particle moved more than {config.MAX_STEP_DISPLACEMENT} x its radius in "
                  "one step (kinetic-energy blow-up)")
    elif cause_code == 3:
        i, j = (int(pairs[0][index]), int(pairs[1][index])) if pairs is not None else (-1, -1)
        what = f"contact {index} (particles {i}, {j})"
        detail = f"overlap exceeded {config.MAX_OVERLAP} x the smaller radius"
    elif cause_code == 5:
        i, j = ((int(bond_pairs[0][index]), int(bond_pairs[1][index])) if bond_pairs is not None
                else (-1, -1))
        what = f"bonded pair {index} (particles {i}, {j})"
        detail = f"overlap exceeded {config.MAX_OVERLAP} x the smaller radius"
    else:
        p, w = (int(wall_pairs[0][index]), int(wall_pairs[1][index])) \
            if wall_pairs is not None else (-1, -1)
        what = f"wall contact {index} (particle {p}, wall {w})"
        detail = f"wall overlap exceeded {config.MAX_OVERLAP} x the particle radius"
    hint = (f"hint: reduce timestep_factor (now {factor:g}, dt = {dt:.3e} s); check the stiffness "
            "contrast between minerals")
    if kratio_spread is not None and np.isfinite(kratio_spread):
        hint += f" (k/m spread across particles {kratio_spread:.3g}:1)"
    hint += ", wall/servo speeds and initial overlaps. The last checkpoint file is untouched."
    msg = f"unstable at step {step}: {cause}: {detail} at {what}; {hint}"
    return InstabilityError(msg, step=step, cause=cause, index=int(index))
