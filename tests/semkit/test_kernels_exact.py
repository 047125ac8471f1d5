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


def test_partial_volume_area_kernel_equals_numpy_path():
    import cv2

    from semkit.measure import label_cracks, partial_volume_area
    rng = np.random.default_rng(3)
    m = cv2.dilate((rng.random((90, 120)) > 0.97).view(np.uint8), np.ones((2, 3), np.uint8))
    lab, n = label_cracks(m.astype(bool))
    img = rng.uniform(20, 200, lab.shape).astype(np.float32)
    bg = (img + rng.uniform(-10, 60, lab.shape)).astype(np.float32)
    for ids in (None, np.arange(1, n + 1, 3)):
        for rim in (0, 1, 2):
            fast = partial_volume_area(img, lab, n, background=bg, crack_level=25.0,
                                       rim_px=rim, ids=ids)
            ref = partial_volume_area(img, lab, n, background=bg,
                                      crack_level=np.float64(25.0), rim_px=rim, ids=ids)
            # the float64 crack level takes the NumPy path in float64: compare to float32 math
            lab32 = lab if ids is None else np.where(np.isin(lab, ids), lab, 0)
            labf = lab32.astype(np.float32)
            if rim:
                k = np.ones((2 * rim + 1,) * 2, np.uint8)
                labf = np.where(labf > 0, labf, cv2.dilate(labf, k))
            idx = np.flatnonzero(labf.ravel())
            cov = np.clip((bg.ravel()[idx] - img.ravel()[idx])
                          / np.maximum(bg.ravel()[idx] - 25.0, 1e-3), 0.0, 1.0)
            want = np.bincount(labf.ravel()[idx].astype(np.int64), cov, minlength=n + 1)
            assert np.array_equal(fast, want)
            assert np.allclose(ref, want, rtol=1e-5)


def test_crack_candidates_equal_numpy_expression_for_both_scalar_kinds():
    from semkit.threshold import _operand
    rng = np.random.default_rng(11)
    img = rng.uniform(0, 200, (70, 90)).astype(np.float32)
    closed = (img + rng.uniform(0, 30, img.shape)).astype(np.float32)
    for mineral, crack in ((120.3, 41.7), (np.float64(120.3), np.float64(41.7)),
                           (np.float32(120.3), 41.7)):
        dark, kmin, frac = mineral - 3.0 * 2.1, 4.0 * 1.3, 0.35
        line = closed - img
        want = (img < dark) | ((line > kmin) & (line > frac * (closed - crack)))
        got = np.empty(img.shape, bool)
        _kernels.crack_candidates(img, closed, _operand(dark), _operand(kmin), _operand(frac),
                                  _operand(crack), got)
        assert np.array_equal(got, want)


def test_pixel_coords_and_lookup_equal_numpy():
    rng = np.random.default_rng(3)
    for dtype in (bool, np.uint8):
        m = (rng.random((37, 53)) < 0.2).astype(dtype)
        rr, cc = _kernels.pixel_coords(m)
        r0, c0 = np.nonzero(m)
        assert np.array_equal(rr, r0) and np.array_equal(cc, c0) and rr.dtype == np.int64
    lab = rng.integers(0, 40, (37, 53)).astype(np.int32)
    for table in (rng.random(40) < 0.5, rng.integers(-5, 5, 40).astype(np.int8)):
        assert np.array_equal(_kernels.lookup(table, lab), table[lab])


def _fill_reference(img, exclude, n_rings, band):
    """The ring fill written plainly: rings from OpenCV's chessboard distance transform, each
    ring decided from the pixels known before it, then applied."""
    import cv2
    out = img.astype(np.float32).copy()
    known = ~exclude
    ring = cv2.distanceTransform(exclude.astype(np.uint8), cv2.DIST_C, 3).astype(int)
    h, w = img.shape
    for r in range(1, n_rings + 1):
        new = {}
        for i, j in zip(*np.nonzero(exclude & (ring == r))):
            vals = [out[a, b] for a in range(i - 1, i + 2) for b in range(j - 1, j + 2)
                    if 0 <= a < h and 0 <= b < w and known[a, b]]
            m = min(vals)
            near = [v for v in vals if v <= m + band]
            new[i, j] = np.float32(sum(float(v) for v in near) / len(near))
        for (i, j), v in new.items():
            out[i, j], known[i, j] = v, True
    return out, known


def test_fill_excluded_equals_the_plain_ring_fill():
    rng = np.random.default_rng(11)
    img = rng.uniform(40, 200, (30, 41)).astype(np.float32)
    exclude = np.zeros(img.shape, bool)
    exclude[5:17, 3:30] = True          # a wide block: rings 1-6
    exclude[0:3, 35:41] = True          # at the image corner
    exclude[20:29, 10:12] = rng.random((9, 2)) < 0.7
    for n_rings in (2, 64):
        val, known, left = _kernels.fill_excluded(img, exclude, n_rings, 12.5)
        ref, kref = _fill_reference(img, exclude, n_rings, 12.5)
        assert np.array_equal(known.astype(bool), kref)
        assert left == int((~kref).sum())
        assert np.allclose(val[kref], ref[kref], rtol=0, atol=1e-4)
    assert _kernels.fill_excluded(img, exclude, 2, 12.5)[2] > 0   # the block's core is left


def test_robust_median_is_numpys_to_the_last_bit():
    from semkit.robust import mad_sigma, median
    rng = np.random.default_rng(5)
    for n in (1, 2, 7, 1000, 65537):
        for dtype in (np.float32, np.float64):
            v = rng.normal(100.0, 7.0, n).astype(dtype)
            m = median(v.copy())
            assert m == np.median(v) and m.dtype == np.median(v).dtype
            ref = 1.4826 * np.median(np.abs(v - np.median(v)))
            assert mad_sigma(v.copy()) == ref


def test_band_owners_are_the_euclidean_band_and_nearest_object():
    import cv2

    from semkit.damage_areas import _disk_offsets
    from semkit.measure import label_cracks
    rng = np.random.default_rng(11)
    m = cv2.dilate((rng.random((70, 90)) > 0.985).view(np.uint8), np.ones((3, 4), np.uint8))
    lab, n = label_cracks(m.astype(bool))
    assert n > 20
    di, dj = _disk_offsets(2)
    assert len(di) == 13 and (di[0], dj[0]) == (0, 0)
    idx, owner = _kernels.band_owners(lab.astype(np.int32), di, dj)
    # brute force: squared distance to every object, per pixel
    rr, cc = np.mgrid[:lab.shape[0], :lab.shape[1]]
    d2 = np.full((n + 1,) + lab.shape, 10 ** 9)
    for k in range(1, n + 1):
        pr, pc = np.nonzero(lab == k)
        d2[k] = ((rr[..., None] - pr) ** 2 + (cc[..., None] - pc) ** 2).min(axis=-1)
    best = d2[1:].min(axis=0)
    assert np.array_equal(idx, np.flatnonzero(best <= 4))
    near = d2[1:].argmin(axis=0).ravel()[idx] + 1
    unique = ((d2[1:] == best).sum(axis=0) == 1).ravel()[idx]
    assert unique.mean() > 0.95
    assert np.array_equal(owner[unique], near[unique])
    assert np.array_equal(owner[lab.ravel()[idx] > 0], lab.ravel()[idx][lab.ravel()[idx] > 0])
