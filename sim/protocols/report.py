"""The result of a laboratory test: summary (DESIGN.md §4), history, cracks, and their files."""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numba
import pandas as pd

from ..analysis import crack_counts, damage_ratio
from ..config import THICKNESS
from . import outputs

__all__ = ["TestResult", "crack_summary", "base_summary"]


def crack_summary(cracks: pd.DataFrame) -> dict:
    """``cracks`` (counts by kind and relation) and ``P_sim`` (by area and by count; crack
    areas per unit thickness, m² per m)."""
    if len(cracks):
        counts = crack_counts(cracks["kind"], cracks["mode"], cracks["relation"])
        p = damage_ratio(cracks["mode"], cracks["size_m"].astype(float))
    else:
        counts = crack_counts([], [], [])
        p = damage_ratio([], [])
    return {"cracks": counts,
            "P_sim": {"by_area": p["by_area"], "by_count": p["by_count"],
                      "area_tension_m2_per_m": p["area_tension_m2"] / THICKNESS,
                      "area_shear_m2_per_m": p["area_shear_m2"] / THICKNESS}}


def base_summary(test: str, specimen, loop, sim, options: dict) -> dict:
    """Fields common to every test: specimen meta, run status, cost."""
    n = specimen.n_particles
    steps = int(loop.steps)
    return {"test": test, "specimen": dict(specimen.meta),
            "n_particles": n, "n_bonds": specimen.n_bonds,
            "status": ("interrupted" if loop.interrupted else
                       "complete" if loop.stop_reason else "running"),
            "stop_reason": loop.stop_reason, "steps": steps,
            "engine_error": loop.engine_error or None,
            "dt_s": float(getattr(sim, "dt", float("nan"))),
            "wall_s": loop.wall_s,
            "particle_steps_per_s": n * steps / loop.wall_s if loop.wall_s > 0 else None,
            # the chunk count fixes the result; threads only the speed (docs/sim.md)
            "force_chunks": getattr(sim, "force_chunks", None),
            "threads": int(numba.get_num_threads()),
            "options": options}


@dataclass
class TestResult:
    """Outcome of one laboratory test.

    Attributes
    ----------
    summary : dict
        The ``summary.json`` content (report units: MPa, GPa; compression positive).
    history : pandas.DataFrame
        ``history.csv`` rows.
    cracks : pandas.DataFrame
        ``cracks.csv`` rows, one per broken bond.
    sim : Simulation
        The engine at the end of the test (final positions, walls).
    specimen : sim.Specimen
        The specimen that was loaded (the cut disc for a Brazilian test).
    files : dict
        Paths written by :meth:`write`.
    """

    __test__ = False   # not a pytest class

    summary: dict
    history: pd.DataFrame
    cracks: pd.DataFrame
    sim: object = None
    specimen: object = None
    stress_column: str = "axial_stress_mpa"
    strain_column: str = "axial_strain"
    files: dict = field(default_factory=dict)

    def write(self, out, *, figures: bool = True) -> dict:
        """Write summary.json, history.csv, cracks.csv and the figures into ``out``."""
        self.files = outputs.write_results(out, summary=self.summary, history=self.history,
                                           cracks=self.cracks)
        if figures and len(self.history) > 1:
            self.files["stress_strain.png"] = outputs.plot_history(
                self.history, os.path.join(out, "stress_strain.png"), summary=self.summary,
                stress_column=self.stress_column, strain_column=self.strain_column,
                title=self.summary.get("test", ""))
            x = y = None
            if self.sim is not None and hasattr(self.sim, "x"):
                x, y = self.sim.x, self.sim.y
            mag = self.summary.get("options", {}).get("map_magnify", 20.0)
            self.files["crack_map.png"] = outputs.plot_crack_map(
                self.specimen, self.cracks, os.path.join(out, "crack_map.png"), x=x, y=y,
                magnify=mag, title=f"{self.summary.get('test', '')}: {len(self.cracks)} cracks"
                f" (grain displacements x{mag:g})")
        return self.files
