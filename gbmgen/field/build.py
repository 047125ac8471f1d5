"""Build a ring-graded field-scale specimen (thesis Ch. 7): particles, grains and bonds by ring.

Stages: ring areas -> particle radii per ring (mean radius of the ring, uniform on
[rmin, ratio rmin], drawn until (1 - porosity) of the ring's area) -> centres at random inside
their ring -> one overlap relaxation of the whole domain (``sim.relax.relax_overlaps``: the rings
settle against each other, so there is neither a gap nor an overlap spike at a junction) ->
grain seeds per ring (radii uniform on the ring's range) -> one Laguerre tessellation of the
domain with areas fitted to the seeds' targets -> minerals by area fraction within each ring ->
radii shrunk by the relaxation's last overlaps (<= 2 %: a stress-free start) -> bonds
between neighbours with a gap below ``BOND_GAP_PER_RADIUS`` x the smaller radius
(parallel bond inside a grain, smooth joint across a boundary), across ring junctions as
anywhere else.
"""
from __future__ import annotations

import time

import numpy as np

from sim.relax import relax_overlaps
from sim.specimen import Specimen

from .. import __version__, config
from ..assign import make_bonds, particles_to_grains
from ..build import _assign_minerals_by_area
from ..errors import InputError
from ..params import BOND, Params, load_params
from ..tessellate import fit_with_centroid_steps, polygon_areas, tessellate
from .plan import RingPlan, load_plan

__all__ = ["build_field", "ring_areas", "local_bond_pairs", "remove_overlaps",
           "MIN_PARTICLES_PER_GRAIN"]

#: Thesis Ch. 7: every grain should hold at least this many particles.
MIN_PARTICLES_PER_GRAIN = 10
#: Grid step of the ring-area estimate, as a fraction of the domain side.
AREA_GRID = 1.0 / 1000.0


def _foci(openings):
    out = []
    for o in openings:
        out.extend(o.get("foci", [o["focus"]]))
    return np.asarray(out, float).reshape(-1, 2)


def ring_areas(plan: RingPlan, box, foci) -> np.ndarray:
    """(K,) area of each ring inside ``box``, m² (midpoint grid of ``AREA_GRID`` x side)."""
    side = max(box[1] - box[0], box[3] - box[2])
    g = side * AREA_GRID
    xs = np.arange(box[0] + g / 2, box[1], g)
    ys = np.arange(box[2] + g / 2, box[3], g)
    a = np.zeros(plan.n_rings)
    for yv in ys:
        k = plan.ring_of(xs, np.full(xs.size, yv), foci)
        a += np.bincount(k - 1, minlength=plan.n_rings)
    return a * g * g


def _place(k, r, plan, box, foci, rng):
    """Uniform random centres inside ring ``k`` (and the box, one radius in)."""
    n = r.size
    x = np.empty(n)
    y = np.empty(n)
    got = 0
    reach = plan.core_half + plan.outer[k - 1] if k < plan.n_rings else np.inf
    lo = np.maximum([box[0], box[2]], foci.min(0) - reach)
    hi = np.minimum([box[1], box[3]], foci.max(0) + reach)
    tries = 0
    while got < n:
        m = 4 * (n - got) + 64
        px = lo[0] + rng.random(m) * (hi[0] - lo[0])
        py = lo[1] + rng.random(m) * (hi[1] - lo[1])
        rr = r[got:got + m] if got + m <= n else np.r_[r[got:], np.zeros(got + m - n)]
        ok = plan.ring_of(px, py, foci) == k
        ok &= (px - rr > box[0]) & (px + rr < box[1]) & (py - rr > box[2]) & (py + rr < box[3])
        idx = np.flatnonzero(ok)[:n - got]
        x[got:got + idx.size] = px[idx]
        y[got:got + idx.size] = py[idx]
        got += idx.size
        tries += 1
        if tries > 1000:
            raise InputError(f"ring {k}: no room inside the domain for its particles")
    return x, y


def local_bond_pairs(x, y, r, *, gap_per_radius=config.BOND_GAP_PER_RADIUS):
    """Pairs (i < j) with d_ij - r_i - r_j <= gap_per_radius x min(r_i, r_j), sorted.

    Each pair is found from its larger particle (query radius (2 + gap) r), so the search
    costs O(N) whatever the radius spread.
    """
    from scipy.spatial import cKDTree

    tree = cKDTree(np.c_[x, y])
    nb = tree.query_ball_point(np.c_[x, y], (2.0 + gap_per_radius) * r, return_sorted=False)
    cnt = np.fromiter((len(v) for v in nb), np.int64, count=len(nb))
    i = np.repeat(np.arange(x.size), cnt)
    j = np.fromiter((q for v in nb for q in v), np.int64, count=int(cnt.sum()))
    keep = (i != j) & (r[i] >= r[j])
    i, j = i[keep], j[keep]
    gap = np.hypot(x[j] - x[i], y[j] - y[i]) - r[i] - r[j]
    keep = gap <= gap_per_radius * np.minimum(r[i], r[j])
    a, b = np.minimum(i[keep], j[keep]), np.maximum(i[keep], j[keep])
    ab = np.unique(a * x.size + b)
    return (ab // x.size).astype(np.int32), (ab % x.size).astype(np.int32)


def remove_overlaps(x, y, r, box):
    """Radii shrunk just enough that no two particles overlap and none crosses the box.

    Each overlap δ_ij is split in proportion to the radii (particle i gives up
    δ_ij r_i / (r_i + r_j) at most), so a relaxed packing (overlaps ≤ 2 % of a radius) loses
    ≤ 2 % of a radius. The engine's linear contacts act on the absolute overlap (no lin_mode 1),
    so a packing bonded with overlaps would carry a locked-in, self-balanced stress (contacts
    pushing, bonds pulling, tens of MPa at field scale); a touching packing starts stress-free.

    Returns
    -------
    r : (N,) ndarray of float64, m
    shrink : float
        Largest relative change of a radius.
    """
    from scipy.spatial import cKDTree

    i, j = (a.astype(np.int64) for a in cKDTree(np.c_[x, y]).query_pairs(
        2.0 * float(r.max()), output_type="ndarray").T)
    d = np.hypot(x[j] - x[i], y[j] - y[i])
    ov = np.maximum(r[i] + r[j] - d, 0.0) * (1.0 + 1e-9)
    cut = np.zeros_like(r)
    np.maximum.at(cut, i, ov * r[i] / (r[i] + r[j]))
    np.maximum.at(cut, j, ov * r[j] / (r[i] + r[j]))
    wall = np.maximum.reduce([r - (x - box[0]), r - (box[1] - x), r - (y - box[2]),
                              r - (box[3] - y), np.zeros_like(r)]) * (1.0 + 1e-9)
    cut = np.maximum(cut, wall)
    return r - cut, float(np.max(cut / r))


def _grains(plan, box, foci, areas, rng, fit=True):
    """Seeds per ring, Laguerre cells fitted to their target areas."""
    sx, sy, sr, tg, ring = [], [], [], [], []
    for k in range(1, plan.n_rings + 1):
        if areas[k - 1] <= 0:
            continue
        lo, hi = plan.grain_rmin[k - 1], plan.grain_rmax[k - 1]
        mean_area = np.pi * (lo * lo + lo * hi + hi * hi) / 3.0
        n = max(int(round(areas[k - 1] / mean_area)), 1)
        g = lo + (np.arange(n) + rng.random(n)) / n * (hi - lo)   # stratified, as gbmgen.packing
        rs = g * np.sqrt(config.SEED_PACKING_FRACTION)
        x, y = _place(k, rs, plan, box, foci, rng)
        sx.append(x)
        sy.append(y)
        sr.append(rs)
        tg.append(np.pi * g * g)
        ring.append(np.full(n, k, np.int8))
    sx, sy, sr, tg, ring = (np.concatenate(v) for v in (sx, sy, sr, tg, ring))
    sx, sy, info = relax_overlaps(sx, sy, sr, box, tol=config.SEED_OVERLAP_TOL,
                                  max_iter=config.SEED_MAX_ITER)
    w = sr ** 2
    fitinfo = {}
    if fit:
        sx, sy, w, fitinfo = fit_with_centroid_steps(sx, sy, box, tg, weights=w,
                                                     steps=config.CENTROID_STEPS)
    xy, off, sidx = tessellate(sx, sy, box, weights=w)
    return xy, off, ring[sidx], {"n_seeds": int(sx.size), "seed_relaxation": info,
                                 "weight_fit": fitinfo}


def build_field(*, plan="thesis-ch7", openings, domain_m=None, params="thesis-ch7",
                seed=None, progress=None):
    """A ring-graded, bonded grain-based rock mass around ``openings``.

    Parameters
    ----------
    plan : str or RingPlan
        Preset name, YAML/CSV path or a :class:`RingPlan`.
    openings : list of dict
        From :mod:`gbmgen.field.openings`; recorded in ``meta["field"]["openings"]`` and filled
        with particles (``gbmsim excavate`` removes them).
    domain_m : float, optional
        Side of the square domain centred on the openings' foci (default: the plan's).
    params : str or Params
        Mineral and joint properties (default the ``thesis-ch7`` preset).
    seed : int, optional
        Drawn and recorded when not given.
    progress : callable, optional
        ``progress(stage_name)`` before each stage.

    Returns
    -------
    specimen : sim.Specimen
        ``meta["field"]``: plan, openings, foci, per-ring report (particles, radii, grains,
        particles per grain, grain/particle size ratio, mineral fractions) and the joint
        stiffness rule.
    timing_s : dict
    """
    plan = plan if isinstance(plan, RingPlan) else load_plan(plan)
    prm = params if isinstance(params, Params) else load_params(params)
    if not openings:
        raise InputError("openings: expected at least one opening")
    if seed is None:
        seed = int(np.random.SeedSequence().entropy % (2 ** 63))
    seed = int(seed)
    say = progress or (lambda s: None)
    foci = _foci(openings)
    c = 0.5 * (foci.min(0) + foci.max(0))
    side = float(plan.domain if domain_m is None else domain_m)
    if not side > 0:
        raise InputError(f"domain_m = {domain_m!r}: expected > 0")
    box = np.array([c[0] - side / 2, c[0] + side / 2, c[1] - side / 2, c[1] + side / 2])
    for o in openings:
        p = np.asarray(o["polygon"])
        if p[:, 0].min() <= box[0] or p[:, 0].max() >= box[1] or p[:, 1].min() <= box[2] \
                or p[:, 1].max() >= box[3]:
            raise InputError(f"opening {o['name']!r} does not fit inside the {side:g} m domain")
    rng = np.random.default_rng(seed)
    timing = {}
    t0 = time.perf_counter()
    say("ring areas")
    areas = ring_areas(plan, box, foci)
    say("particles")
    xs, ys, rs = [], [], []
    for k in range(1, plan.n_rings + 1):
        if areas[k - 1] <= 0:
            continue
        rmin, rmax = plan.particle_range(k)
        target = (1.0 - plan.porosity) * areas[k - 1]
        mean_a = np.pi * (rmin * rmin + rmin * rmax + rmax * rmax) / 3.0
        m = int(target / mean_a * 1.1) + 16
        r = rmin + rng.random(m) * (rmax - rmin)
        r = r[:int(np.searchsorted(np.cumsum(np.pi * r * r), target)) + 1]
        x, y = _place(k, r, plan, box, foci, rng)
        xs.append(x)
        ys.append(y)
        rs.append(r)
    x, y, r = np.concatenate(xs), np.concatenate(ys), np.concatenate(rs)
    for s in np.linspace(config.GROW_FROM, 1.0, config.GROW_STEPS, endpoint=False):
        x, y, _ = relax_overlaps(x, y, r * s, box, tol=config.PARTICLE_OVERLAP_TOL,
                                 max_iter=config.GROW_ITER)
    x, y, rinfo = relax_overlaps(x, y, r, box, tol=config.PARTICLE_OVERLAP_TOL,
                                 max_iter=config.PARTICLE_MAX_ITER)
    r, shrink = remove_overlaps(x, y, r, box)
    rinfo = dict(rinfo, radius_shrink_max=shrink)
    timing["particles"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    say("grains")
    gxy, goff, gring, ginfo = _grains(plan, box, foci, areas, rng)
    grain = particles_to_grains(x, y, gxy, goff, box)
    garea = polygon_areas(gxy, goff)
    names = list(plan.mineral_fractions)
    fr = np.array([plan.mineral_fractions[n] for n in names])
    gmin = np.zeros(garea.size, np.int32)
    for k in np.unique(gring):
        sel = np.flatnonzero(gring == k)
        gmin[sel] = _assign_minerals_by_area(garea[sel], fr, rng)
    mineral = np.where(grain >= 0, gmin[np.maximum(grain, 0)], 0).astype(np.int32)
    timing["grains"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    say("bonds")
    pairs = local_bond_pairs(x, y, r)
    bonds = make_bonds(x, y, r, grain, gxy, goff, pairs=pairs)
    timing["bonds"] = time.perf_counter() - t0
    props = prm.mineral_arrays(names)
    per_joint = BOND in (prm.joint["sj_kn"], prm.joint["sj_ks"])
    report = _ring_report(plan, x, y, r, foci, grain, gxy, goff, gring, gmin, names, areas)
    meta = {
        "generator": "gbmgen field", "generator_version": __version__, "seed": seed,
        "params": {"name": prm.name, "source": prm.source},
        "bond_gap": f"{config.BOND_GAP_PER_RADIUS} x min(r_i, r_j)",
        "n_parallel_bonds": int(np.sum(bonds["bond_kind"] == 0)),
        "n_smooth_joints": int(np.sum(bonds["bond_kind"] == 1)),
        "particles": {"porosity_target": plan.porosity,
                      "porosity": float(1.0 - np.sum(np.pi * r * r) / side ** 2), **rinfo},
        "grains": ginfo,
        "field": {"plan": plan.to_dict(), "box": box.tolist(), "foci": foci.tolist(),
                  "openings": openings,
                  "joint_stiffness": "per_joint_bond" if per_joint else "uniform",
                  "rings": report},
    }
    spec = Specimen(x=x, y=y, r=r, mineral=mineral, grain=grain, mineral_names=np.array(names),
                    **props, **prm.joint_arrays(pb_emod=props["pb_emod"],
                                                r_mean=float(np.mean(r))),
                    **bonds, box=box, grain_xy=gxy, grain_offsets=goff, grain_mineral=gmin,
                    grain_class=np.ones(garea.size, np.int8), meta=meta)
    return spec.sort_spatial().validate("gbmgen field"), timing


def _ring_report(plan, x, y, r, foci, grain, gxy, goff, gring, gmin, names, areas):
    """Per ring: particles, radii, grains, particles per grain, size ratio, mineral fractions."""
    ring = plan.ring_of(x, y, foci)
    gp = np.bincount(grain[grain >= 0], minlength=goff.size - 1)
    garea = polygon_areas(gxy, goff)
    out = []
    for k in range(1, plan.n_rings + 1):
        sel = ring == k
        gs = gring == k
        if not sel.any():
            continue
        rmin, rmax = plan.particle_range(k)
        g_r = np.sqrt(garea[gs] / np.pi)
        ppg = gp[gs]
        out.append({
            "ring": k, "area_m2": float(areas[k - 1]), "particles": int(sel.sum()),
            "radius_plan_mm": [1e3 * rmin, 1e3 * rmax],
            "radius_mm": [1e3 * float(r[sel].min()), 1e3 * float(r[sel].mean()),
                          1e3 * float(r[sel].max())],
            "outside_plan_range": int(np.sum((r[sel] < rmin * (1 - 1e-9))
                                             | (r[sel] > rmax * (1 + 1e-9)))),
            "grains": int(gs.sum()),
            "grain_radius_mm": [1e3 * float(g_r.min()), 1e3 * float(g_r.mean()),
                                1e3 * float(g_r.max())] if gs.any() else None,
            "grain_to_particle_radius": float(g_r.mean() / r[sel].mean()) if gs.any() else None,
            "particles_per_grain": {"min": int(ppg.min()), "median": float(np.median(ppg)),
                                    f"below_{MIN_PARTICLES_PER_GRAIN}": int(
                                        np.sum(ppg < MIN_PARTICLES_PER_GRAIN))}
            if gs.any() else None,
            "mineral_area_fraction": {n: float(garea[gs & (gmin == m)].sum()
                                               / max(garea[gs].sum(), 1e-300))
                                      for m, n in enumerate(names)},
        })
    return out
