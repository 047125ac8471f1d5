"""Build a bonded grain-based specimen: table -> seeds -> tessellation -> particles -> bonds.

:func:`build_grains` makes the grain structure (from a grain-size table, or a controlled shape);
:func:`build_specimen` adds the particle packing, the grain of each particle, the bonds and the
mineral properties, and returns a :class:`sim.Specimen` (write it with ``Specimen.save``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from sim.specimen import Specimen

from . import __version__, config
from .assign import make_bonds, particles_to_grains
from .controlled import SHAPES, controlled_tessellation
from .errors import InputError
from .fidelity import fidelity_report
from .packing import pack_particles, pack_seeds
from .params import Params, load_params
from .table import GrainSizeTable
from .tessellate import Grains, fit_power_weights, polygon_areas, polygon_centroids, tessellate

__all__ = ["build_grains", "build_specimen", "BuildResult", "TESSELLATIONS"]

TESSELLATIONS = ("laguerre", "voronoi")


@dataclass
class BuildResult:
    """What :func:`build_grains` returns.

    Attributes
    ----------
    grains : Grains
    table : GrainSizeTable or None
        The scenario table at model scale (um) the grains were made from.
    seeds : Seeds or None
    info : dict
        Settings and diagnostics (JSON types) for ``meta``.
    timing_s : dict
        Seconds per stage (not written to the file, which must not depend on timing).
    """

    grains: Grains
    table: GrainSizeTable | None
    seeds: object
    info: dict
    timing_s: dict = field(default_factory=dict)


def _box(width_mm, height_mm):
    for name, v in (("width_mm", width_mm), ("height_mm", height_mm)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name}: expected a specimen size > 0 mm, got {v!r}")
    return np.array([0.0, width_mm * 1e-3, 0.0, height_mm * 1e-3])


def _assign_minerals_by_area(areas, fractions, rng):
    """Mineral of each grain: a random order of the grains cut at the cumulative fractions."""
    order = rng.permutation(areas.size)
    cum = np.cumsum(areas[order]) / areas.sum()
    mid = cum - 0.5 * areas[order] / areas.sum()
    bounds = np.cumsum(fractions)[:-1]
    m = np.searchsorted(bounds, mid, side="right").astype(np.int32)
    out = np.empty(areas.size, np.int32)
    out[order] = m
    return out


def build_grains(table: GrainSizeTable | None = None, *, width_mm, height_mm, scenario=1,
                 scale=1.0, model_scale=config.MODEL_SCALE, tessellation="laguerre",
                 fit_areas=True, shape=None, slenderness=1.0,
                 grain_area_mm2=config.GRAIN_AREA_MM2, ranges_mm=None, seed=None) -> BuildResult:
    """The grain structure of a specimen.

    Parameters
    ----------
    table : GrainSizeTable, optional
        Grain-size table at SEM scale (um). Needed unless ``shape`` is given (then only its
        minerals and volume fractions are used; without it the grains are one mineral).
    width_mm, height_mm : float
        Specimen size, mm.
    scenario : {1, 2, 3, 4}
        Size range (REFERENCE.md Table 4-2).
    scale, model_scale : float
        Size factors: model sizes = table sizes x scale x model_scale (thesis model_scale 10).
    tessellation : {"laguerre", "voronoi"}
        Laguerre: power diagram of the seed disks; Voronoi: of their centres (PFC).
    fit_areas : bool
        Laguerre only: start from weights r^2 and adjust them (damped Newton) so that every
        cell has the area of its seed's target grain size, then move the seeds to their cell
        centroids and fit again (``CENTROID_STEPS``) (default). False keeps w = r^2.
    shape : {"hexagon", "rectangle", "shield"}, optional
        Controlled tessellation instead of seeds (thesis Ch. 5).
    slenderness : float
        H/W of controlled grains.
    grain_area_mm2 : float
        Area of controlled grains, mm^2.
    ranges_mm : dict, optional
        {mineral: (d_min, d_max)} at model scale, mm: explicit size ranges instead of the
        scenario rule (e.g. the thesis' printed Table 4-2 ranges); the class edges are mapped
        linearly as for a scenario; ``scale`` still applies, ``model_scale`` does not.
    seed : int, optional
        Random seed (``np.random.default_rng``).

    Returns
    -------
    result : BuildResult
    """
    box = _box(width_mm, height_mm)
    rng = np.random.default_rng(seed)
    timing = {}
    t0 = time.perf_counter()
    if shape is not None:
        if shape not in SHAPES:
            raise InputError(f"shape: expected one of {SHAPES}, got {shape!r}")
        xy, off, interior = controlled_tessellation(
            shape, box, slenderness=slenderness, grain_area_m2=grain_area_mm2 * 1e-6)
        areas = polygon_areas(xy, off)
        if table is not None:
            mineral = _assign_minerals_by_area(areas, table.volume_fractions, rng)
        else:
            mineral = np.zeros(areas.size, np.int32)
        grains = Grains(xy=xy, offsets=off, mineral=mineral,
                        klass=np.ones(areas.size, np.int8), seed=np.full(areas.size, -1))
        timing["tessellation"] = time.perf_counter() - t0
        info = {"kind": "controlled", "shape": shape, "slenderness": float(slenderness),
                "grain_area_mm2": float(grain_area_mm2), "n_interior_grains": int(interior.sum())}
        return BuildResult(grains=grains, table=table, seeds=None, info=info, timing_s=timing)
    if table is None:
        raise InputError("table: a grain-size table is needed (or give a controlled shape)")
    if tessellation not in TESSELLATIONS:
        raise InputError(f"tessellation: expected one of {TESSELLATIONS}, got {tessellation!r}")
    if not (np.isfinite(model_scale) and model_scale > 0):
        raise InputError(f"model_scale: expected > 0, got {model_scale!r}")
    if ranges_mm is not None:
        scn = table.with_ranges({k: (1e3 * v[0], 1e3 * v[1]) for k, v in ranges_mm.items()},
                                scale=float(scale), label="ranges_mm")
    else:
        scn = table.scenario(int(scenario), scale=float(scale) * float(model_scale))
    seeds = pack_seeds(scn, box, rng=rng)
    timing["seeds"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    fit = {}
    if tessellation == "laguerre":
        w = seeds.r ** 2
        sx, sy = seeds.x, seeds.y
        if fit_areas:
            target = np.pi * seeds.d ** 2 / 4.0
            w, fit = fit_power_weights(sx, sy, box, target, weights=w)
            for _ in range(config.CENTROID_STEPS):
                xy, off, sidx = tessellate(sx, sy, box, weights=w)
                c = polygon_centroids(xy, off)
                sx, sy = sx.copy(), sy.copy()
                sx[sidx], sy[sidx] = c[:, 0], c[:, 1]
                w, fit = fit_power_weights(sx, sy, box, target, weights=w)
        xy, off, sidx = tessellate(sx, sy, box, weights=w)
        own = particles_to_grains(sx[sidx], sy[sidx], xy, off, box)
        fit = dict(fit, centroid_steps=config.CENTROID_STEPS if fit_areas else 0,
                   seeds_in_own_cell=float(np.mean(own == np.arange(sidx.size))))
    else:
        xy, off, sidx = tessellate(seeds.x, seeds.y, box)
    grains = Grains(xy=xy, offsets=off, mineral=seeds.mineral[sidx], klass=seeds.klass[sidx],
                    seed=sidx)
    timing["tessellation"] = time.perf_counter() - t0
    compare = None
    if tessellation == "laguerre":
        # the same seeds through plain Voronoi, for the fidelity report ("report both")
        t0 = time.perf_counter()
        vxy, voff, vidx = tessellate(seeds.x, seeds.y, box)
        vrep = fidelity_report(scn, polygon_areas(vxy, voff), seeds.mineral[vidx],
                               seeds.klass[vidx])
        compare = {"ks": {k: v["ks"] for k, v in vrep["minerals"].items()},
                   "area_fraction_error_max": vrep["area_fraction_error_max"],
                   "MHI": vrep["MHI"]}
        timing["voronoi_comparison"] = time.perf_counter() - t0
    info = {"kind": "tessellation", "tessellation": tessellation,
            "laguerre_weights": ("fitted to target areas" if fit_areas else "seed radius^2")
            if tessellation == "laguerre" else None,
            "weight_fit": fit, "scenario": None if ranges_mm else int(scenario),
            "ranges_mm": ranges_mm, "scale": float(scale),
            "model_scale": float(model_scale), "n_seeds": int(seeds.x.size),
            "seed_relaxation": seeds.info, "voronoi_same_seeds": compare,
            "scenario_ranges_mm": {name: [float(v) for v in scn.range_um()[k] / 1000.0]
                                   for k, name in enumerate(scn.minerals)}}
    return BuildResult(grains=grains, table=scn, seeds=seeds, info=info, timing_s=timing)


def build_specimen(table: GrainSizeTable | None = None, *, width_mm, height_mm, scenario=1,
                   scale=1.0, model_scale=config.MODEL_SCALE, tessellation="laguerre",
                   fit_areas=True, shape=None, slenderness=1.0,
                   grain_area_mm2=config.GRAIN_AREA_MM2, ranges_mm=None,
                   particle_radius_mm=config.PARTICLE_RADIUS_MM,
                   radius_ratio=config.RADIUS_RATIO, porosity=config.POROSITY,
                   seat_faces=config.SEAT_FACES, bond_gap_mm=None,
                   params: str | Params = config.DEFAULT_PARAMS, seed=None):
    """A bonded grain-based specimen (``specimen.npz`` v1) from a grain-size table.

    Parameters
    ----------
    table, width_mm, height_mm, scenario, scale, model_scale, tessellation, fit_areas, shape,
    slenderness, grain_area_mm2, ranges_mm
        As :func:`build_grains`.
    particle_radius_mm : float
        Mean particle radius, mm (radii uniform on [rmin, radius_ratio rmin]).
    radius_ratio : float
        rmax / rmin (thesis 1.66).
    porosity : float
        Target porosity of the packing (2D).
    seat_faces : bool
        Seat the packing on the four box faces (:func:`gbmgen.faces.seat_faces`: no dents
        under a platen). Default on; off reproduces, seed for seed, the specimens built
        before seating existed (the results in benchmarks/ dated 2026-11-21, CHANGELOG).
    bond_gap_mm : float, optional
        Bond gap, mm; default ``BOND_GAP_PER_RADIUS`` x mean radius (thesis 0.05 mm at 0.1 mm).
    params : str or Params
        Preset name (``thesis-ch4``, ``thesis-ch5``), a YAML/JSON path, or a Params.
    seed : int, optional
        Random seed; drawn from the OS and recorded in ``meta`` when not given.

    Returns
    -------
    specimen : sim.Specimen
        ``meta`` carries settings, the source table, the fidelity report and MHI target and
        realised.
    timing_s : dict
        Seconds per stage.

    Raises
    ------
    InputError
        Any bad input (named).
    """
    prm = params if isinstance(params, Params) else load_params(params)
    if seed is None:
        seed = int(np.random.SeedSequence().entropy % (2 ** 63))
    seed = int(seed)
    box = _box(width_mm, height_mm)
    res = build_grains(table, width_mm=width_mm, height_mm=height_mm, scenario=scenario,
                       scale=scale, model_scale=model_scale, tessellation=tessellation,
                       fit_areas=fit_areas, shape=shape, slenderness=slenderness,
                       grain_area_mm2=grain_area_mm2, ranges_mm=ranges_mm, seed=seed)
    timing = dict(res.timing_s)
    g = res.grains
    names = list(table.minerals) if table is not None else [next(iter(prm.minerals))]
    mineral_props = prm.mineral_arrays(names)
    # particles get their own stream (so grains do not change with particle settings)
    prng = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])
    t0 = time.perf_counter()
    r_mean = particle_radius_mm * 1e-3
    x, y, r, pinfo = pack_particles(box, radius_mean_m=r_mean, radius_ratio=radius_ratio,
                                    porosity=porosity, rng=prng, seat_faces=seat_faces)
    timing["particles"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    grain = particles_to_grains(x, y, g.xy, g.offsets, box)
    mineral = np.where(grain >= 0, g.mineral[np.maximum(grain, 0)], 0).astype(np.int32)
    timing["assign"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    gap = (config.BOND_GAP_PER_RADIUS * r_mean) if bond_gap_mm is None else bond_gap_mm * 1e-3
    bonds = make_bonds(x, y, r, grain, g.xy, g.offsets, gap=gap)
    timing["bonds"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    gp = np.bincount(grain[grain >= 0], minlength=g.n_grains)
    if res.table is not None and res.info.get("kind") == "tessellation":
        fid = fidelity_report(res.table, g.areas(), g.mineral, g.klass, grain_particles=gp)
    else:
        areas = g.areas()
        fid = {"n_grains": int(g.n_grains),
               "area_fraction": {n: float(areas[g.mineral == k].sum() / areas.sum())
                                 for k, n in enumerate(names)},
               "particles_per_grain": {"min": int(gp.min()), "median": float(np.median(gp)),
                                       "grains_without_particles": int(np.sum(gp == 0))}}
    timing["fidelity"] = time.perf_counter() - t0
    n_sj = int(np.sum(bonds["bond_kind"] == 1))
    meta = {
        "generator": "gbmgen", "generator_version": __version__, "seed": seed,
        "source_table": table.source if table is not None else None,
        "table": table.to_frame().to_dict(orient="list") if table is not None else None,
        "scenario": res.info.get("scenario"), "tessellation": res.info.get("tessellation",
                                                                         "controlled"),
        "grains": res.info, "params": {"name": prm.name, "source": prm.source},
        "particles": {"radius_mean_mm": particle_radius_mm, "radius_ratio": radius_ratio,
                      "porosity_target": porosity, **pinfo},
        "bond_gap_m": gap, "n_parallel_bonds": int(bonds["bond_kind"].size - n_sj),
        "n_smooth_joints": n_sj,
        "MHI_target": fid.get("MHI_target"), "MHI_realised": fid.get("MHI"),
        "H_target": fid.get("H_target"), "H_realised": fid.get("H"),
        "fidelity": fid,
    }
    spec = Specimen(x=x, y=y, r=r, mineral=mineral, grain=grain,
                    mineral_names=np.array(names), **mineral_props,
                    **prm.joint_arrays(pb_emod=mineral_props["pb_emod"], r_mean=float(np.mean(r))),
                    **bonds, box=box, grain_xy=g.xy, grain_offsets=g.offsets,
                    grain_mineral=g.mineral, grain_class=g.klass, meta=meta)
    return spec.validate("gbmgen build"), timing
