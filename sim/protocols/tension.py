"""Direct tension test: the particles of the two end groups (grips) are pulled apart.

The grips are the particles within ``grip_depth`` of the top and bottom faces of ``box``; their
velocities are prescribed (±v along y, no lateral motion). The tensile force is the mean of the
contact forces the specimen exerts on the two grips; σt = peak force / (width × t).

History (compression positive as everywhere): ``axial_stress_mpa`` and ``axial_strain`` are
negative in tension; ``tensile_stress_mpa`` and ``tensile_strain`` (grip extension) are the
same quantities with tension positive, used for the stop rule and the figure.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import analysis
from ..config import THICKNESS
from . import gauges as gg
from .options import TestOptions
from .skeleton import Protocol, Rig, run_loading

__all__ = ["Tension", "run_tension", "grip_indices", "GRIP_FRACTION"]

#: Depth of each grip as a fraction of the specimen height (at least two mean diameters).
GRIP_FRACTION = 0.1


def grip_indices(y, r, box, *, depth=None):
    """Particles of the bottom and top grips (within ``depth`` of the faces, m).

    ``depth`` defaults to max(GRIP_FRACTION × height, 2 mean diameters).
    """
    h = float(box[3] - box[2])
    d = max(GRIP_FRACTION * h, 4.0 * float(np.mean(r))) if depth is None else float(depth)
    bottom = np.nonzero(y - r <= box[2] + d)[0]
    top = np.nonzero(y + r >= box[3] - d)[0]
    if bottom.size == 0 or top.size == 0 or np.intersect1d(bottom, top).size:
        raise ValueError(f"grip depth {d} m leaves no free length between the grips")
    return bottom, top


@dataclass
class Tension(Protocol):
    """Direct tension by pulled end groups.

    Attributes
    ----------
    grip_depth : float, m, optional
        Depth of each grip; default :func:`grip_indices`.
    """

    grip_depth: float | None = None

    name = "tension"
    label = "tension"
    help = "direct tension by pulled end groups"
    record_strain = 0.5e-5          # 4x denser than the UCS: tension peaks early
    limit_strain = 0.01
    stress_key = "tensile_stress_mpa"
    strain_key = "tensile_strain"
    peak = "tensile_mpa"
    resume_keys = ("grip_depth_m",)

    def rig(self, loaded, sim, opts: TestOptions, resumed: bool, context) -> Rig:
        box = loaded.box
        x0, y0 = np.array(loaded.x, copy=True), np.array(loaded.y, copy=True)
        bottom, top = grip_indices(y0, loaded.r, box, depth=self.grip_depth)
        l0 = float(y0[top].mean() - y0[bottom].mean())
        w0 = float(box[1] - box[0])
        free = np.setdiff1d(np.arange(x0.size), np.r_[bottom, top])
        gbox = np.array([box[0], box[1], (y0[bottom] + loaded.r[bottom]).max(),
                         (y0[top] - loaded.r[top]).min()])
        gauge = np.intersect1d(gg.gauge_indices(x0, y0, gbox, fraction=0.8), free)

        def drive(v):
            sim.fix_velocity(bottom, 0.0, -v)
            sim.fix_velocity(top, 0.0, v)

        def record():
            et = (float(sim.y[top].mean() - sim.y[bottom].mean()) - l0) / l0
            gl, ga = gg.gauge_strains(x0, y0, sim.x, sim.y, gauge)
            force = 0.5 * (sim.group_force(bottom)[1] - sim.group_force(top)[1])
            st = force / (w0 * THICKNESS) / 1e6                  # tension positive
            return {"axial_strain": -et, "lateral_strain": gl, "volumetric_strain": -et + gl,
                    "axial_stress_mpa": -st, "confining_stress_mpa": 0.0,
                    "tensile_strain": et, "tensile_stress_mpa": st, "gauge_axial_strain": ga,
                    "gauge_lateral_strain": gl}

        def summarize(hist, cracks):
            st = hist["tensile_stress_mpa"].to_numpy(float) * 1e6
            ext = -hist["gauge_axial_strain"].to_numpy(float)
            ip = analysis.peak_index(st)
            return {"tensile_mpa": float(st[ip]) / 1e6,
                    "peak_tensile_strain": float(hist["tensile_strain"].iloc[ip]),
                    "E_tension_gpa": analysis.young_modulus(ext, st) / 1e9,
                    "grip_length_m": l0, "width_m": w0}

        return Rig(length=l0, drive=drive, record=record, summarize=summarize,
                   options=dict(grip_depth_m=self.grip_depth))


def run_tension(specimen, *, grip_depth: float | None = None, **options):
    """Direct tension of ``specimen`` by pulled end groups.

    Parameters
    ----------
    specimen : sim.Specimen
    grip_depth : float, m, optional
        See :class:`Tension`.
    **options
        The shared options (:class:`sim.protocols.options.TestOptions`).

    Returns
    -------
    result : TestResult
        ``summary["tensile_mpa"]`` = σt (positive), ``E_tension_gpa``, cracks and P_sim.
    """
    return run_loading(Tension(grip_depth=grip_depth), specimen, TestOptions(**options))
