"""Uniaxial compression (UCS) test: rigid frictionless platens at ``box``, strain-controlled.

Measured (compression positive, report units in the names):

- axial stress = mean platen force / (initial width × t); axial strain from the platen gap;
- lateral strain from the side layers and volumetric strain = axial + lateral (specimen scale;
  used for CD); axial strain of the end layers (:mod:`sim.protocols.gauges`);
- the gauge: strains from an affine fit of the middle half of the height across the width (less
  a skin at the free sides), mean stress of the same particles; E and ν with their validity
  (:mod:`sim.protocols.elastic`);
- cumulative cracks by kind, kinetic and strain energy.

Stops at ``post_peak`` × peak after the peak (default 0.8, as the thesis) or at ``max_strain``.
The platen speed is adaptive by default (:class:`sim.protocols.speed.AdaptiveSpeed`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import analysis
from ..config import THICKNESS
from . import gauges as gg
from .elastic import elastic_constants
from .options import TestOptions
from .rig import add_platens, platen_force, platen_gap
from .skeleton import Protocol, Rig, run_loading
from .speed import ADAPTIVE_DEFAULT, AdaptiveSpeed, adaptive_speeds

__all__ = ["UCS", "run_ucs", "compression_summary", "compression_rig"]


def compression_summary(history, *, cracks=None, gauge_box=None, link=None,
                        stress_col="axial_stress_mpa", first_steady=0,
                        ci_fraction=analysis.CI_FRACTION) -> dict:
    """E and ν with their validity (:func:`sim.protocols.elastic.elastic_constants`), peak,
    CI and CD from a compression history (report units).

    Uses ``axial_strain`` (platen gap) for the peak strain, ``volumetric_strain`` for CD and
    ``cracks_total`` for CI.
    """
    s = history[stress_col].to_numpy(float) * 1e6
    ea = history["axial_strain"].to_numpy(float)
    ip = analysis.peak_index(s)
    out = elastic_constants(history, cracks, gauge_box=gauge_box, link=link,
                            stress_col=stress_col, first_steady=first_steady)
    out.update({
        "ucs_mpa": float(s[ip]) / 1e6,
        "ci_mpa": analysis.crack_initiation(s, history["cracks_total"].to_numpy(float),
                                            fraction=ci_fraction) / 1e6,
        "cd_mpa": analysis.crack_damage(s, history["volumetric_strain"].to_numpy(float)) / 1e6,
        "peak_axial_strain": float(ea[ip]),
        "ci_criterion": f"cumulative cracks >= max(1, ceil({ci_fraction} x count at peak))",
        "cd_criterion": "maximum of volumetric strain before the peak",
    })
    return out


def compression_rig(specimen, x0, y0, box):
    """The gauge and boundary readings of a compression test on ``specimen`` whose particles
    start at ``x0``, ``y0`` inside ``box`` (the platens' and side faces' positions).

    Returns
    -------
    read : callable
        ``read(sim) -> dict`` of ``gauge_axial_strain``, ``gauge_lateral_strain``,
        ``gauge_stress_xx_mpa``, ``gauge_stress_yy_mpa``, ``end_axial_strain``,
        ``side_lateral_strain``.
    summarize : callable
        ``summarize(history, cracks, stress_col, first_steady) -> dict``
        (:func:`compression_summary`).
    """
    margin = 4.0 * float(np.mean(specimen.r))     # two diameters: cells closed inside the packing
    gauge = gg.gauge_indices(x0, y0, box, margin=margin)
    mask = np.zeros(x0.size, bool)
    mask[gauge] = True
    area = gg.cell_area(x0, y0, gauge)
    left, right = gg.side_indices(x0, specimen.r, box)
    bottom, top = gg.end_indices(y0, specimen.r, box)
    left, right, bottom, top = gg.bonded_only(specimen, left, right, bottom, top)
    gbox = gg.gauge_box(box, margin=margin)
    link = 2.1 * float(specimen.r.max())

    def read(sim):
        x, y = sim.x, sim.y
        gl, ga = gg.gauge_strains(x0, y0, x, y, gauge)
        sx, sy = gg.gauge_stress(sim, mask, area)
        return {"gauge_axial_strain": ga, "gauge_lateral_strain": gl,
                "gauge_stress_xx_mpa": sx / 1e6, "gauge_stress_yy_mpa": sy / 1e6,
                "end_axial_strain": gg.layer_strain(y0, y, bottom, top),
                "side_lateral_strain": gg.layer_strain(x0, x, left, right)}

    def summarize(history, cracks, stress_col, first_steady):
        return compression_summary(history, cracks=cracks, gauge_box=gbox, link=link,
                                   stress_col=stress_col, first_steady=first_steady)

    return read, summarize


@dataclass
class UCS(Protocol):
    """Uniaxial compression between rigid frictionless platens.

    Attributes
    ----------
    adaptive : bool or dict, optional
        Adaptive platen speed (:class:`sim.protocols.speed.AdaptiveSpeed`): up to 0.1 m/s
        while elastic and crack-free (capped by a kinetic/strain energy check), the base speed
        from the first crack on. Default :data:`sim.protocols.speed.ADAPTIVE_DEFAULT` (True);
        the base speed is then :func:`sim.protocols.speed.adaptive_speeds` of the length
        unless ``platen_velocity`` or ``strain_rate`` is given. A dict: adaptive, with these
        fields of :class:`~sim.protocols.speed.AdaptiveSpeed` changed (e.g. ``f_max``).
    """

    adaptive: bool | dict | None = None

    name = "ucs"
    label = "UCS"
    help = "uniaxial compression between rigid frictionless platens"
    record_strain = 2e-5
    limit_strain = 0.05
    peak = "ucs_mpa"
    resume_keys = ("adaptive", "adaptive_rule")

    def rig(self, loaded, sim, opts: TestOptions, resumed: bool, context) -> Rig:
        adaptive = ADAPTIVE_DEFAULT if self.adaptive is None else self.adaptive
        rule = dict(adaptive) if isinstance(adaptive, dict) else {}
        box = loaded.box
        h0, w0 = float(box[3] - box[2]), float(box[1] - box[0])
        velocity = None
        if adaptive and opts.platen_velocity is None and opts.strain_rate is None:
            velocity, f_max = adaptive_speeds(h0)     # size-aware: cracking at a fixed rate
            rule.setdefault("f_max", f_max)
        speed = AdaptiveSpeed(**rule) if adaptive else None
        lo, hi = (0, 1) if resumed else add_platens(sim, box, axis=1, fric=0.0)
        x0, y0 = np.array(loaded.x, copy=True), np.array(loaded.y, copy=True)
        read, summarize = compression_rig(loaded, x0, y0, box)

        def drive(v):
            sim.set_wall_velocity(lo, 0.0, v)
            sim.set_wall_velocity(hi, 0.0, -v)

        def record():
            ea = (h0 - platen_gap(sim, lo, hi)) / h0
            g = read(sim)
            el = g.pop("side_lateral_strain")
            return {"axial_strain": ea, "lateral_strain": el, "volumetric_strain": ea + el,
                    "axial_stress_mpa": platen_force(sim, lo, hi) / (w0 * THICKNESS) / 1e6,
                    "confining_stress_mpa": 0.0, **g}

        return Rig(length=h0, drive=drive, record=record, velocity=velocity, speed=speed,
                   summarize=lambda h, c: summarize(h, c, "axial_stress_mpa",
                                                    opts.ramp_records),
                   options=dict(adaptive=bool(adaptive), adaptive_rule=None if speed is None
                                else {k: getattr(speed, k) for k in (
                                    "f_max", "tan_fast", "tan_slow", "peak_drop", "window",
                                    "rise", "ke_ratio", "f_peak", "tan_peak")}))


def run_ucs(specimen, *, adaptive: bool | dict | None = None, **options):
    """Uniaxial compression of ``specimen`` between rigid frictionless platens.

    Parameters
    ----------
    specimen : sim.Specimen
    adaptive : bool or dict, optional
        See :class:`UCS`.
    **options
        The shared options (:class:`sim.protocols.options.TestOptions`: ``out``,
        ``strain_rate``, ``platen_velocity``, ``post_peak``, ``max_strain``, ``damping``,
        ``timestep_factor``, ``record_strain``, ``ramp_records``, ``limit_strain``,
        ``progress``, ``figures``, ``checkpoint_every``, ``resume``, ``sim_options``).

    Returns
    -------
    result : TestResult
        ``summary`` has ``E_gpa, nu`` (with ``E_ok``, ``nu_ok`` and reasons), ``ucs_mpa,
        ci_mpa, cd_mpa, cracks, P_sim, steps, wall_s, particle_steps_per_s`` and more.

    """
    return run_loading(UCS(adaptive=adaptive), specimen, TestOptions(**options))
