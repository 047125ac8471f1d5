"""Broad phase on wide radius spreads, opening geometry, Kirsch, D/R and notches (issue 17)."""
import numpy as np
import pandas as pd
import pytest
from scipy.spatial import cKDTree

from sim.field_geometry import distance_to_polygon, points_in_polygon, ray_exit_distance
from sim.field_measures import damage_depth, kirsch, kirsch_circle_mean, notches
from sim.neighbors import _build_contacts_single, build_contacts, partner_csr, radius_levels


def _graded(rng, n=6000):
    """Disks whose radius grows 14x away from the centre, density ~ 1/r^2 (a ring grading)."""
    x = rng.uniform(-10, 10, 40 * n)
    y = rng.uniform(-10, 10, 40 * n)
    r = 0.023 * (1 + np.maximum(abs(x), abs(y)) / 0.8)
    keep = rng.random(x.size) < (0.023 / r) ** 2 * 0.9
    keep &= np.cumsum(keep) <= n
    return x[keep], y[keep], r[keep] * rng.uniform(0.8, 1.2, keep.sum())


def _list(f, x, y, r, skin, ptr, adj, old=None):
    n = x.size
    os_, oc, of = old if old else (np.zeros(n + 1, np.int64), np.zeros(0, np.int32), np.zeros(0))
    cap = 16
    while True:
        cs = np.zeros(n + 1, np.int64)
        ci, cj, fs = np.zeros(cap, np.int32), np.zeros(cap, np.int32), np.zeros(cap)
        tot = f(x, y, r, skin, ptr, adj, os_, oc, of, cs, ci, cj, fs, 2)
        if tot <= cap:
            return cs, ci[:tot], cj[:tot], fs[:tot]
        cap = tot


def test_multilevel_broad_phase_finds_exactly_the_pairs(rng):
    x, y, r = _graded(rng)
    assert r.max() / r.min() > 10
    level, nlev = radius_levels(r)
    assert level is not None and nlev >= 4
    skin = 0.5 * r.mean()
    pairs = cKDTree(np.c_[x, y]).query_pairs(2 * r.max() + skin, output_type="ndarray")
    i, j = pairs.min(1), pairs.max(1)
    near = np.hypot(x[j] - x[i], y[j] - y[i]) < r[i] + r[j] + skin
    i, j = i[near], j[near]
    # exclude some pairs as smooth joints; give the others a shear history
    sj = np.arange(0, i.size, 7)
    ptr, adj = partner_csr(x.size, i[sj].astype(np.int32), j[sj].astype(np.int32))
    cs, ci, cj, fs = _list(build_contacts, x, y, r, skin, ptr, adj)
    want = set(zip(i.tolist(), j.tolist())) - set(zip(i[sj].tolist(), j[sj].tolist()))
    assert set(zip(ci.tolist(), cj.tolist())) == want
    assert np.all(np.diff(ci) >= 0) and np.array_equal(cs[ci], cs[ci])  # owner-sorted
    # same set as the single grid, and shear history carried over by (i, j)
    cs1, ci1, cj1, _ = _list(_build_contacts_single, x, y, r, skin, ptr, adj)
    assert set(zip(ci1.tolist(), cj1.tolist())) == want
    old_fs = np.arange(ci.size, dtype=float)
    _, ci2, cj2, fs2 = _list(build_contacts, x, y, r, skin, ptr, adj, (cs, cj, old_fs))
    key = dict(zip(zip(ci.tolist(), cj.tolist()), old_fs))
    assert np.array_equal(fs2, [key[p] for p in zip(ci2.tolist(), cj2.tolist())])
    # lab spreads keep the single grid (bit-identical results)
    assert radius_levels(np.r_[1.0, 1.66])[0] is None


def test_polygon_helpers():
    sq = np.array([[0, 0], [2, 0], [2, 1], [0, 1.0]])
    assert points_in_polygon([1, 3, 1], [0.5, 0.5, 1.5], sq).tolist() == [True, False, False]
    assert ray_exit_distance(sq, (1, 0.5), np.radians([0, 90, 180])) == pytest.approx(
        [1.0, 0.5, 1.0])
    assert distance_to_polygon([1, 3], [0.5, 0.5], sq) == pytest.approx([0.5, 1.0])


def test_kirsch_reference_values():
    sx, sy = 20.0, 10.0
    srr, stt, trt = kirsch(1.0, np.array([0.0, 90.0, 33.0]), sx, sy)
    assert np.allclose(srr, 0) and np.allclose(trt, 0)
    assert stt == pytest.approx([3 * sy - sx, 3 * sx - sy, (sx + sy) - 2 * (sx - sy) * np.cos(
        np.radians(66))])
    # uniaxial decay along 90 deg: 1.22 S at 2a, 1.07 S at 3a (REFERENCE.md)
    assert kirsch(np.array([2.0, 3.0]), 90.0, 1.0, 0.0)[1] == pytest.approx([1.2188, 1.0741],
                                                                            abs=1e-4)
    # far field recovered; circle mean tends to the point value
    assert kirsch(1e4, 0.0, sx, sy)[0] == pytest.approx(sx, rel=1e-6)
    m = kirsch_circle_mean((0.0, 3.0), 1e-4, 2.0, sx, sy)
    assert m[0, 0] == pytest.approx(kirsch(1.5, 90.0, sx, sy)[1], rel=1e-6)


def test_damage_depth_and_notch_of_a_synthetic_v():
    """A V of breaks at the crown of a circle a = 2: tip 0.6 m deep, base 1.2 m wide."""
    a = 2.0
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    prof = np.c_[a * np.cos(t), a * np.sin(t)]
    pts = []
    for s in np.linspace(0, 1, 200):                     # two flanks from the base to the tip
        for bx in (-0.6, 0.6):
            base = np.array([bx, np.sqrt(a * a - bx * bx)])
            pts.append(base + s * (np.array([0.0, a + 0.6]) - base))
    pts.append([0.0, -5.0])                              # an isolated break: not connected
    c = pd.DataFrame({"x": [p[0] for p in pts], "y": [p[1] for p in pts],
                      "size_m": 0.02})
    rows, conn = damage_depth(c, prof, (0.0, 0.0))
    assert not conn[-1] and conn[:-1].all()
    dr = {r["angle_deg"]: r["D_over_R"] for r in rows}
    assert max(dr.values()) == pytest.approx((a + 0.6) / a, rel=1e-3)
    assert dr[2.5] == pytest.approx(1.0) and dr[267.5] == pytest.approx(1.0)
    (n,) = notches(rows, (0.0, 0.0), 0.05)
    assert n["depth_m"] == pytest.approx(0.6, abs=0.01)
    assert 87.5 <= n["tip_angle_deg"] <= 92.5
    # base chord ~1.2 m (to the 5 deg bins) and the V's apex angle 2 atan(0.6 / 0.6 + sag)
    assert n["height_m"] == pytest.approx(1.2, abs=0.2)
    assert 75 < n["angle_deg"] < 115


def test_rays_into_a_joined_opening_are_not_measured():
    """Two drives and a stope: a drive's rays whose profile point lies in the stope get NaN."""
    from gbmgen.field import openings as op
    lo, up = op.two_drives(dip_deg=65.0, spacing_m=20.0)
    st = op.stope(lo, up, width_m=3.0)
    empty = pd.DataFrame({"x": [], "y": [], "size_m": []})
    rows, _ = damage_depth(empty, lo["polygon"], lo["centroid"],
                           others=[up["polygon"], st["polygon"]])
    nan = [r["angle_deg"] for r in rows if np.isnan(r["D_over_R"])]
    assert nan and all(0 < a < 180 for a in nan)          # only upwards, into the stope
    ok = [r for r in rows if not np.isnan(r["D_over_R"])]
    assert all(r["D_over_R"] == 1.0 for r in ok) and len(ok) > 54
