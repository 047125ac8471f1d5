"""Ring plans of a field-scale specimen: nested square rings of particle and grain size.

Thesis Ch. 7 (Table 7-4, Appendix D): the particles and grains of a 40 x 40 m rock mass grow in
nine square rings away from the opening. A ring plan gives, ring by ring from the inside out,
the thickness (m), the grain radius range and the mean particle radius. The innermost square
(the *core*, half-size ``core_half_m`` around each focus, where the opening lies) belongs to
ring 1; beyond the last ring's outer edge the last ring continues to the domain boundary.

The ring of a point is set by its Chebyshev (L-infinity) distance to the nearest focus (the
opening centres; points along a stope axis), so the rings are the nested boxes of Appendix D.

Table 7-4's sizes are read as **radii** (grain and particle): the particle counts of rings 3-9
then follow from the ring areas at a solid fraction of 0.85 within 5 %, and a grain of radius
4 x the particle radius holds ~13 particles, which the thesis's ">= 10 particles per grain" needs
(read as diameters, grains would hold ~3).
"""
from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field

import numpy as np

from sim.field_geometry import ring_index

from ..errors import InputError
from ..params import read_preset_or_file

__all__ = ["RingPlan", "load_plan", "plan_from_dict", "PLAN_PRESETS"]

#: Presets that carry a ``field:`` ring plan (gbmgen/presets/NAME.yaml).
PLAN_PRESETS = ("thesis-ch7",)

#: Columns of a CSV ring plan (one row per ring, inside out).
CSV_COLUMNS = ("thickness_m", "grain_rmin_mm", "grain_rmax_mm", "particle_radius_mm")


@dataclass(frozen=True)
class RingPlan:
    """Nested square rings of grain and particle size.

    Notation: K rings, numbered 1..K from the opening outwards.

    Attributes
    ----------
    thickness : (K,) ndarray of float64, m
    grain_rmin, grain_rmax : (K,) ndarray of float64, m
        Grain (equivalent-circle) radius range of each ring; radii are uniform within it.
    particle_r : (K,) ndarray of float64, m
        Mean particle radius; radii uniform on [rmin, radius_ratio rmin] with this mean.
    core_half : float, m
        Half-size of the innermost square (ring 1 includes it).
    domain : float, m
        Default side of the square domain.
    radius_ratio, porosity : float
        Particle rmax/rmin and target 2D porosity of every ring.
    mineral_fractions : dict
        {mineral: area fraction}, summing to 1.
    source : str
    """

    thickness: np.ndarray
    grain_rmin: np.ndarray
    grain_rmax: np.ndarray
    particle_r: np.ndarray
    core_half: float = 2.25
    domain: float = 40.0
    radius_ratio: float = 1.66
    porosity: float = 0.20
    mineral_fractions: dict = field(default_factory=lambda: {
        "pyroxene": 0.5, "plagioclase": 0.3, "biotite": 0.2})
    source: str = "plan"

    @property
    def n_rings(self) -> int:
        return int(self.thickness.size)

    @property
    def outer(self) -> np.ndarray:
        """(K,) distance of each ring's outer edge from the core edge, m."""
        return np.cumsum(self.thickness)

    def particle_range(self, k: int) -> tuple:
        """(rmin, rmax) of the particles of ring ``k`` (1-based), m."""
        rmin = 2.0 * self.particle_r[k - 1] / (1.0 + self.radius_ratio)
        return rmin, self.radius_ratio * rmin

    def ring_of(self, x, y, foci) -> np.ndarray:
        """Ring (1..K, int8) of points ``x, y`` for rings around ``foci`` ((F, 2), m)."""
        return ring_index(x, y, foci, self.core_half, self.outer)

    def to_dict(self) -> dict:
        """JSON form (mm for sizes, as in the preset)."""
        return {"core_half_m": self.core_half, "domain_m": self.domain,
                "radius_ratio": self.radius_ratio, "porosity": self.porosity,
                "mineral_fractions": dict(self.mineral_fractions), "source": self.source,
                "rings": [[float(t), 1e3 * a, 1e3 * b, 1e3 * p] for t, a, b, p in
                          zip(self.thickness, self.grain_rmin, self.grain_rmax,
                              self.particle_r)]}


def _num(v, where, positive=True):
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected a number, got {v!r}") from None
    if not np.isfinite(f) or (positive and f <= 0):
        raise InputError(f"{where}: expected a {'positive ' if positive else ''}finite number, "
                         f"got {v!r}")
    return f


def plan_from_dict(data: dict, source: str = "plan") -> RingPlan:
    """Validate a ``field:`` mapping (see ``gbmgen/presets/thesis-ch7.yaml``).

    ``rings`` is a list of ``[thickness_m, grain_rmin_mm, grain_rmax_mm, particle_radius_mm]``
    from the opening outwards; the other keys are optional.

    Raises
    ------
    InputError
        Names the ring and column, or the key, that is wrong.
    """
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a mapping with 'rings'")
    rings = data.get("rings")
    if not isinstance(rings, (list, tuple)) or not rings:
        raise InputError(f"{source}: field 'rings' missing or empty, expected a list of "
                         f"[{', '.join(CSV_COLUMNS)}]")
    rows = []
    for k, row in enumerate(rings, start=1):
        if not isinstance(row, (list, tuple)) or len(row) != 4:
            raise InputError(f"{source}: ring {k}: expected 4 numbers "
                             f"[{', '.join(CSV_COLUMNS)}], got {row!r}")
        rows.append([_num(v, f"{source}: ring {k} {c}") for v, c in zip(row, CSV_COLUMNS)])
    a = np.array(rows)
    for k in range(a.shape[0]):
        if a[k, 2] < a[k, 1]:
            raise InputError(f"{source}: ring {k + 1} grain_rmax_mm {a[k, 2]:g} < grain_rmin_mm "
                             f"{a[k, 1]:g}")
    fr = data.get("mineral_fractions", {"pyroxene": 0.5, "plagioclase": 0.3, "biotite": 0.2})
    if not isinstance(fr, dict) or not fr:
        raise InputError(f"{source}: field 'mineral_fractions' expected {{mineral: fraction}}")
    fr = {str(k): _num(v, f"{source}: mineral_fractions.{k}", positive=False)
          for k, v in fr.items()}
    tot = sum(fr.values())
    if not abs(tot - 1.0) < 1e-3:
        raise InputError(f"{source}: mineral_fractions sum to {tot:g}, expected 1")
    ratio = _num(data.get("radius_ratio", 1.66), f"{source}: radius_ratio")
    if ratio < 1:
        raise InputError(f"{source}: radius_ratio = {ratio:g}, expected >= 1")
    por = _num(data.get("porosity", 0.20), f"{source}: porosity")
    if not por < 1:
        raise InputError(f"{source}: porosity = {por:g}, expected a fraction in (0, 1)")
    return RingPlan(thickness=a[:, 0], grain_rmin=a[:, 1] * 1e-3, grain_rmax=a[:, 2] * 1e-3,
                    particle_r=a[:, 3] * 1e-3,
                    core_half=_num(data.get("core_half_m", 2.25), f"{source}: core_half_m"),
                    domain=_num(data.get("domain_m", 40.0), f"{source}: domain_m"),
                    radius_ratio=ratio, porosity=por,
                    mineral_fractions={k: v / tot for k, v in fr.items()}, source=source)


def _read_csv(path) -> dict:
    with open(path, newline="", encoding="utf-8") as fh:
        rd = csv.DictReader(fh)
        missing = [c for c in CSV_COLUMNS if c not in (rd.fieldnames or [])]
        if missing:
            raise InputError(f"{path}: missing column(s) {', '.join(missing)}, expected "
                             f"{', '.join(CSV_COLUMNS)}")
        return {"rings": [[row[c] for c in CSV_COLUMNS] for row in rd]}


def load_plan(name_or_path="thesis-ch7") -> RingPlan:
    """A ring plan from a preset name, a YAML/JSON file (its ``field:`` mapping, or the
    mapping itself) or a CSV file (columns ``CSV_COLUMNS``, defaults for the rest).

    Raises
    ------
    InputError
        Unknown preset, unreadable file, or an invalid field (named).
    """
    if name_or_path not in PLAN_PRESETS and os.fspath(name_or_path).lower().endswith(".csv"):
        path = os.fspath(name_or_path)
        if not os.path.exists(path):
            raise InputError(f"{path}: no such ring plan (presets: {', '.join(PLAN_PRESETS)})")
        return plan_from_dict(_read_csv(path), path)
    data, source = read_preset_or_file(name_or_path, PLAN_PRESETS, "ring plan")
    if isinstance(data, dict) and "field" in data:
        data = data["field"]
    return plan_from_dict(data, source)
