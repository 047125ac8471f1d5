"""Seed sizes and packings."""
import numpy as np
import pytest

from gbmgen import config
from gbmgen.fidelity import ks_distance
from gbmgen.packing import pack_seeds, particle_radii, sample_grain_sizes
from sim.relax import max_overlap


def test_sample_grain_sizes_fractions_classes_and_stratification(table41):
    t = table41.scenario(1, scale=10)
    d, m, c = sample_grain_sizes(t, 25e-3 * 50e-3, np.random.default_rng(0))
    area = np.pi * d ** 2 / 4
    for k in range(3):
        sel = m == k
        assert area[sel].sum() / area.sum() == pytest.approx(t.volume_fractions[k], abs=0.01)
        counts = np.bincount(c[sel], minlength=3) / sel.sum()
        np.testing.assert_allclose(counts, t.frequencies[k], atol=1.0 / sel.sum())
        # stratified draws: KS of the sample itself ~ 1/n, far below random sampling's ~1/sqrt(n)
        assert ks_distance(d[sel] * 1e6, t, k) < 3.0 / sel.sum()
        lo, hi = t.lo_um[k] * 1e-6, t.hi_um[k] * 1e-6
        assert np.all((d[sel] >= lo[c[sel]]) & (d[sel] <= hi[c[sel]]))


def test_pack_seeds_overlap_and_radius(table41):
    t = table41.scenario(3, scale=10)
    box = np.array([0.0, 10e-3, 0.0, 10e-3])
    s = pack_seeds(t, box, rng=np.random.default_rng(1))
    assert s.info["converged"]
    assert max_overlap(s.x, s.y, s.r, box) <= config.SEED_OVERLAP_TOL + 1e-12
    frac = np.sum(np.pi * s.r ** 2) / 1e-4
    assert frac == pytest.approx(config.SEED_PACKING_FRACTION, rel=1e-9)
    np.testing.assert_allclose(s.r / s.d, s.r[0] / s.d[0])  # one scale factor for all


def test_particle_radii():
    rmin, rmax = particle_radii(1e-4, 1.66)
    assert 0.5 * (rmin + rmax) == pytest.approx(1e-4) and rmax / rmin == pytest.approx(1.66)


def test_too_dense_packing_warns():
    from gbmgen.packing import pack_particles
    box = np.array([0.0, 2e-3, 0.0, 2e-3])
    with pytest.warns(RuntimeWarning, match="largest overlap"):
        _, _, _, info = pack_particles(box, radius_mean_m=1e-4, porosity=0.05,
                                       rng=np.random.default_rng(0), max_iter=300)
    assert not info["converged"] and info["max_overlap"] > config.PARTICLE_OVERLAP_TOL
