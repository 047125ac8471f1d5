"""Whether a grain-based specimen is big and fine enough for its test numbers to mean much.

Two rules, checked before every test and recorded in ``summary.json`` (``representative``):

- **particles per grain** >= :data:`MIN_PARTICLES_PER_GRAIN` (10, the thesis's rule for its
  grain-based models): the particles of the specimen over its grains. With fewer, a grain is
  a handful of bonds and the grain structure (sizes, minerals, boundaries) is barely resolved;
- **grains across the width** >= :data:`MIN_GRAINS_ACROSS` (10, the laboratory rule that a
  specimen's diameter is at least ten grain sizes, ISRM suggested methods for the UCS test;
  here with the mean grain): the smaller side of the specimen over the mean grain's
  equivalent-circle diameter. With fewer, one grain or one grain boundary in the wrong place
  sets the strength, and seeds scatter by tens of per cent.

A specimen without grains (a lattice, a plain packing) is outside these rules (``ok`` true).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["MIN_PARTICLES_PER_GRAIN", "MIN_GRAINS_ACROSS", "representativeness"]

#: Least mean number of particles per grain.
MIN_PARTICLES_PER_GRAIN = 10
#: Least number of mean grain diameters across the smaller side of the specimen.
MIN_GRAINS_ACROSS = 10


def representativeness(specimen) -> dict:
    """The two rules on ``specimen`` (a :class:`sim.Specimen`).

    Returns
    -------
    dict
        ``ok``, ``grains``, ``particles_per_grain``, ``mean_grain_diameter_mm``,
        ``grains_across_width``, ``rules`` (text) and ``warnings`` (one line per broken rule,
        empty when ``ok``).

    Examples
    --------
    >>> from sim import Specimen
    >>> representativeness(Specimen.lattice(nx=4, ny=4, radius=1e-3))["ok"]
    True
    """
    rules = (f"particles per grain >= {MIN_PARTICLES_PER_GRAIN} (thesis); mean grain diameters "
             f"across the smaller side >= {MIN_GRAINS_ACROSS} (ISRM, with the mean grain)")
    labels = np.unique(specimen.grain[specimen.grain >= 0])
    n_grains = max(int(specimen.n_grains), int(labels.size))
    if n_grains == 0:
        return {"ok": True, "grains": 0, "particles_per_grain": None,
                "mean_grain_diameter_mm": None, "grains_across_width": None, "rules": rules,
                "warnings": [], "note": "no grains: the rules do not apply"}
    box = specimen.box
    disc = (specimen.meta or {}).get("disc")
    if disc:
        d = float(disc["diameter_m"])
        area, width = math.pi * d * d / 4.0, d
    else:
        w, h = float(box[1] - box[0]), float(box[3] - box[2])
        area, width = w * h, min(w, h)
    per_grain = int(np.sum(specimen.grain >= 0)) / n_grains
    diameter = math.sqrt(4.0 * area / (math.pi * n_grains))
    across = width / diameter
    warnings = []
    if per_grain < MIN_PARTICLES_PER_GRAIN:
        warnings.append(f"{per_grain:.1f} particles per grain, expected >= "
                        f"{MIN_PARTICLES_PER_GRAIN} (thesis): use smaller particles "
                        "(gbmgen --particle-radius-mm)")
    if across < MIN_GRAINS_ACROSS:
        warnings.append(f"{across:.1f} mean grain diameters ({1e3 * diameter:.2f} mm) across "
                        f"the {1e3 * width:.1f} mm side, expected >= {MIN_GRAINS_ACROSS}: use a "
                        "wider specimen")
    return {"ok": not warnings, "grains": n_grains, "particles_per_grain": per_grain,
            "mean_grain_diameter_mm": 1e3 * diameter, "grains_across_width": across,
            "rules": rules, "warnings": warnings}
