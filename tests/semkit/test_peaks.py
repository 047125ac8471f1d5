import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d
from scipy.signal import find_peaks

from semkit.peaks import prominent_peaks


@pytest.mark.parametrize("kind", ["smooth", "integer", "random"])
def test_prominent_peaks_match_scipy_find_peaks(kind):
    rng = np.random.default_rng(3)
    for _ in range(500):
        n = int(rng.integers(1, 120))
        if kind == "smooth":   # a padded, smoothed histogram, as in the threshold stage
            x = np.r_[0.0, gaussian_filter1d(rng.random(n) * 100, 2.0), 0.0]
        elif kind == "integer":  # plateaus and ties
            x = rng.integers(0, 5, n).astype(float)
        else:
            x = rng.random(n)
        p = rng.random() * 0.5 * (x.max() if x.size else 1.0)
        assert prominent_peaks(x, p).tolist() == find_peaks(x, prominence=p)[0].tolist()


def test_smooth_profile_is_scipy_gaussian_filter1d_to_the_last_bit():
    """The threshold and illumination stages smooth their histograms without importing
    scipy.ndimage; the numbers must not move by one bit (they decide the mineral peaks)."""
    from semkit.peaks import smooth_profile
    rng = np.random.default_rng(5)
    for k in range(1500):
        n = int(rng.integers(1, 300))   # shorter and longer than the kernel
        x = rng.integers(0, 5000, n).astype(float) if k % 2 else rng.random(n) * 1e4
        for sigma in (1.5, 2.0, 0.8):
            assert np.array_equal(smooth_profile(x, sigma), gaussian_filter1d(x, sigma))
