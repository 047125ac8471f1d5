"""Kernels that fuse NumPy expressions give NumPy's bits."""
import numpy as np

from semkit import _kernels


def test_ridge_levels_equal_numpy_expressions():
    rng = np.random.default_rng(7)
    a = rng.uniform(0, 255, (64, 80)).astype(np.float32)
    bg = (a + rng.uniform(-5, 40, a.shape)).astype(np.float32)
    bg[::7, ::5] = 30.0005          # at the 1e-3 floor of the contrast
    r = rng.gamma(1.0, 3.0, a.shape).astype(np.float32)
    region = rng.random(a.shape) > 0.1
    crack_level, noise, high, low_snr, min_depth = 30.0, 0.731, 8.0, 4.0, 0.2
    depth = (bg - a) / np.maximum(bg - crack_level, 1e-3)
    snr = r / noise
    seed = (snr > high) & (depth > min_depth) & region
    low = (snr > low_snr) & (depth > 0.5 * min_depth) & region
    d2, s2, l2 = np.empty_like(a), np.empty(a.shape, bool), np.empty(a.shape, bool)
    f = np.float32
    _kernels.ridge_levels(a, bg, r, f(crack_level), f(noise), f(high), f(low_snr),
                          f(min_depth), f(0.5 * min_depth), region, d2, s2, l2)
    assert np.array_equal(depth, d2)
    assert np.array_equal(seed, s2) and np.array_equal(low, l2)
