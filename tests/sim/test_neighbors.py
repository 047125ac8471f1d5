"""Broad phase: cell grid + Verlet skin against brute force; shear history across rebuilds."""
import numba
import numpy as np
import pytest
from scipy.spatial import cKDTree

from sim import Simulation, Specimen
from sim.neighbors import build_contacts, partner_csr


def _pairs(x, y, r, skin, sj_i=(), sj_j=(), cap=None):
    n = x.size
    sj_ptr, sj_adj = partner_csr(n, np.asarray(sj_i, np.int32), np.asarray(sj_j, np.int32))
    cap = cap or 20 * n
    cstart = np.zeros(n + 1, np.int64)
    ci, cj, fs = np.zeros(cap, np.int32), np.zeros(cap, np.int32), np.zeros(cap)
    total = build_contacts(x, y, r, skin, sj_ptr, sj_adj, np.zeros(n + 1, np.int64),
                           np.zeros(0, np.int32), np.zeros(0), cstart, ci, cj, fs,
                           numba.get_num_threads())
    return total, ci[:min(total, cap)], cj[:min(total, cap)], cstart


def test_contact_list_equals_brute_force(rng):
    n = 3000
    x, y = rng.uniform(0, 0.1, n), rng.uniform(0, 0.05, n)
    r = rng.uniform(0.3e-3, 1.5e-3, n)   # wide size spread
    skin = 0.2e-3
    total, ci, cj, cstart = _pairs(x, y, r, skin)
    cand = cKDTree(np.c_[x, y]).query_pairs(2 * r.max() + skin, output_type="ndarray")
    d = np.hypot(*(np.c_[x, y][cand[:, 1]] - np.c_[x, y][cand[:, 0]]).T)
    want = {tuple(p) for p in np.sort(cand[d < r[cand[:, 0]] + r[cand[:, 1]] + skin], axis=1)}
    got = set(zip(ci.tolist(), cj.tolist()))
    assert got == want and total == len(want)
    assert np.all(ci < cj)
    # owner index: the pairs of particle i are cstart[i]:cstart[i+1]
    assert np.all(ci == np.repeat(np.arange(n), np.diff(cstart)))


def test_overflow_returns_the_needed_count_and_joints_are_excluded(rng):
    s = Specimen.lattice(6, 6, 1e-3)
    total, *_ = _pairs(s.x, s.y, s.r, 1e-4, cap=5)
    assert total == s.n_bonds             # touching lattice: the bonded neighbours
    i, j = s.bond_i[:4], s.bond_j[:4]
    total2, ci, cj, _ = _pairs(s.x, s.y, s.r, 1e-4, sj_i=i, sj_j=j)
    assert total2 == total - 4
    assert not ({tuple(p) for p in zip(i, j)} & set(zip(ci.tolist(), cj.tolist())))


def test_shear_history_survives_rebuilds():
    """A contact sheared while the list is rebuilt every few steps keeps its shear force:
    same history as without rebuilds, k_s u before sliding, then mu Fn."""
    from _sim_fixtures import disks

    from sim.state import C_FN, C_FS

    R = 1e-3

    def run(skin):
        s = disks([0.0, 0.0], [0.0, 2 * R * (1 - 1e-3)], R, emod=(1e9,), kratio=(2.0,),
                  fric=(0.5,))
        sim = Simulation(s, damping=0.0, skin=skin)
        sim.fix_velocity([0], 0.0, 0.0, 0.0)
        v = 1e-5 / (2000 * sim.dt)          # 10 um of tangential travel in 2000 steps
        sim.fix_velocity([1], v, 0.0, 0.0)
        n_rebuild = [0]
        orig = sim.rebuild

        def counted():
            n_rebuild[0] += 1
            orig()
        sim.rebuild = counted
        fs, fn = [], []
        for _ in range(20):
            sim.cycle(100)
            fs.append(sim.state.cf[C_FS, 0])
            fn.append(sim.state.cf[C_FN, 0])
        return np.array(fs), n_rebuild[0], np.array(fn)

    fa, na, fn = run(1e-2)
    fb, nb, _ = run(2e-6)
    assert na == 0 and nb >= 8
    np.testing.assert_array_equal(fa, fb)
    kn = 1e9                                   # E* t with equal radii
    assert fn[0] == pytest.approx(kn * 2 * R * 1e-3, rel=1e-3)
    u = np.arange(1, 21) * 100 * 1e-5 / 2000
    elastic = np.abs(fa) < 0.5 * fn * (1 - 1e-9)
    assert elastic[0] and not elastic[-1]
    np.testing.assert_allclose(np.abs(fa[elastic]), kn / 2 * u[elastic], rtol=1e-3)
    np.testing.assert_allclose(np.abs(fa[~elastic]), 0.5 * fn[~elastic], rtol=1e-12)
