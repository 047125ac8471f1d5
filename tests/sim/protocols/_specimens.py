"""Small seeded bonded specimens for the protocol tests and benchmarks (no gbmgen needed).

``random_specimen`` packs disks at random in a rectangle, relaxes the overlaps with the engine's
``sim.relax.relax_overlaps``, bonds every pair closer than a gap, and (optionally) cuts the
rectangle into Voronoi grains: pairs inside a grain get a parallel bond, pairs across a grain
boundary a smooth joint whose normal is the Voronoi edge normal (seed_j − seed_i).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from sim import Specimen
from sim.relax import relax_overlaps


def _clip(poly, a, b, c):
    """Keep the part of polygon ``poly`` with a x + b y <= c (Sutherland–Hodgman)."""
    out = []
    n = len(poly)
    for k in range(n):
        p, q = poly[k], poly[(k + 1) % n]
        fp, fq = a * p[0] + b * p[1] - c, a * q[0] + b * q[1] - c
        if fp <= 0:
            out.append(p)
        if fp * fq < 0:
            t = fp / (fp - fq)
            out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def voronoi_polygons(seeds, box):
    """Voronoi cells of ``seeds`` clipped to ``box`` (list of (K, 2) arrays)."""
    polys = []
    for i, s in enumerate(seeds):
        poly = [(box[0], box[2]), (box[1], box[2]), (box[1], box[3]), (box[0], box[3])]
        for j, t in enumerate(seeds):
            if i == j:
                continue
            a, b = t[0] - s[0], t[1] - s[1]
            c = 0.5 * (a * (s[0] + t[0]) + b * (s[1] + t[1]))
            poly = _clip(poly, a, b, c)
        polys.append(np.array(poly, float))
    return polys


def random_specimen(width, height, r_mean, *, seed=0, r_ratio=1.6, solid=0.83, bond_gap=0.2,
                    n_grains=0, n_minerals=1, emod=60e9, kratio=1.5, pb_emod=60e9,
                    pb_kratio=2.0, pb_ten=100e6, pb_coh=100e6, pb_fa=30.0, fric=0.5,
                    density=2650.0, sj_kn=None, sj_ks=None, sj_ten=20e6, sj_coh=40e6,
                    sj_fa=30.0, sj_fric=0.6):
    """A seeded random bonded packing in [0, width] x [0, height] (SI units).

    Parameters
    ----------
    r_mean : float, m
        Mean radius; radii uniform in [r_mean·2/(1+ratio), r_mean·2·ratio/(1+ratio)].
    bond_gap : float
        Pairs with gap <= bond_gap × min radius are bonded.
    n_grains : int
        0: no grains (all parallel bonds); else Voronoi grains of random seeds.
    sj_kn, sj_ks : float, Pa/m
        Smooth-joint stiffness; default pb_emod / (2 r_mean) and sj_kn / pb_kratio (as stiff as
        the bonds, so that grains do not dominate the stiffness).
    """
    rng = np.random.default_rng(seed)
    lo, hi = 2 * r_mean / (1 + r_ratio), 2 * r_mean * r_ratio / (1 + r_ratio)
    mean_r2 = (hi ** 3 - lo ** 3) / (3 * (hi - lo))
    n = int(round(solid * width * height / (np.pi * mean_r2)))
    r = rng.uniform(lo, hi, n)
    x = rng.uniform(r, width - r)
    y = rng.uniform(r, height - r)
    box = np.array([0.0, width, 0.0, height])
    x, y, info = relax_overlaps(x, y, r, box, tol=0.02, max_iter=20000)
    # no initial overlaps: shrink the radii by the largest remaining relative overlap, so that
    # the bonded specimen starts force-free (PFC zeroes the linear forces after bonding)
    r = r * (1.0 - 1.05 * info["max_overlap"])
    box = np.array([(x - r).min(), (x + r).max(), (y - r).min(), (y + r).max()])
    pairs = cKDTree(np.c_[x, y]).query_pairs(2 * hi * (1 + bond_gap), output_type="ndarray")
    pairs = np.sort(pairs, axis=1)
    i, j = pairs[:, 0], pairs[:, 1]
    gap = np.hypot(x[j] - x[i], y[j] - y[i]) - r[i] - r[j]
    keep = gap <= bond_gap * np.minimum(r[i], r[j])
    i, j = i[keep], j[keep]
    order = np.lexsort((j, i))
    i, j = i[order], j[order]
    grain = np.full(n, -1)
    kind = np.zeros(i.size, np.int8)
    jnx = np.full(i.size, np.nan)
    jny = np.full(i.size, np.nan)
    extra = {}
    mineral = np.zeros(n, np.int32)
    if n_grains:
        seeds = np.c_[rng.uniform(0, width, n_grains), rng.uniform(0, height, n_grains)]
        grain = cKDTree(seeds).query(np.c_[x, y])[1]
        gmin = np.arange(n_grains) % n_minerals
        mineral = gmin[grain].astype(np.int32)
        cross = grain[i] != grain[j]
        kind[cross] = 1
        d = seeds[grain[j[cross]]] - seeds[grain[i[cross]]]
        d /= np.hypot(d[:, 0], d[:, 1])[:, None]
        jnx[cross], jny[cross] = d[:, 0], d[:, 1]
        polys = voronoi_polygons(seeds, box)
        extra = dict(grain_xy=np.concatenate(polys),
                     grain_offsets=np.r_[0, np.cumsum([len(p) for p in polys])],
                     grain_mineral=gmin, grain_class=np.ones(n_grains, np.int8))
    m = max(1, n_minerals)

    def tab(v):
        return np.full(m, float(v))

    kn = pb_emod / (2 * r_mean) if sj_kn is None else sj_kn
    ks = kn / pb_kratio if sj_ks is None else sj_ks
    names = np.array([f"mineral{k}" for k in range(m)])
    return Specimen(x=x, y=y, r=r, mineral=mineral, grain=grain, mineral_names=names,
                    density=tab(density), emod=tab(emod), kratio=tab(kratio), fric=tab(fric),
                    pb_emod=tab(pb_emod), pb_kratio=tab(pb_kratio), pb_ten=tab(pb_ten),
                    pb_coh=tab(pb_coh), pb_fa=tab(pb_fa), pb_rmul=tab(1.0),
                    sj_kn=[kn], sj_ks=[ks], sj_ten=[sj_ten], sj_coh=[sj_coh], sj_fa=[sj_fa],
                    sj_fric=[sj_fric], bond_i=i, bond_j=j, bond_kind=kind, joint_nx=jnx,
                    joint_ny=jny, box=box,
                    meta={"generator": "tests/sim/protocols/_specimens.py", "seed": seed,
                          "relax": info},
                    **extra).validate("random_specimen")
