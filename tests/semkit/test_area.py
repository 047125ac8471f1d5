"""Crack areas: the midpoint count, the partial volume of thin cracks and the ``mixed``
estimator, against exact (supersampled) coverage."""
import numpy as np
import pandas as pd
import pytest
from scipy import ndimage as ndi

from semkit import cli
from semkit.analysis import analyse_image


def _tapered(blur=1.0, noise=3.0, seed=0, shape=(240, 400)):
    """Two horizontal cracks, each 7 px wide over its left half and 1.5 px over its right
    half (grey 30 in a 170 mineral), rendered by 4 x 4 supersampled coverage, a Gaussian
    blur and white noise; returns (image, true area px)."""
    h, w = shape
    ss = 4
    y = (np.arange(h * ss) + 0.5) / ss
    x = (np.arange(w * ss) + 0.5) / ss
    width = np.where(x < w / 2, 7.0, 1.5)
    inside = (x > 40) & (x < w - 40)
    band = np.zeros((h * ss, w * ss), bool)
    for y0 in (0.3 * h, 0.7 * h):
        band |= (np.abs(y[:, None] - y0) < width[None, :] / 2) & inside[None, :]
    cov = band.reshape(h, ss, w, ss).mean(axis=(1, 3))
    img = 170.0 - 140.0 * ndi.gaussian_filter(cov, blur)
    img += np.random.default_rng(seed).normal(0.0, noise, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), float(cov.sum())


def test_mixed_area_keeps_the_thin_stretches_of_wide_cracks():
    """A crack that narrows below the blur: its thin stretch never passes the midpoint, so
    the count (``--area midpoint``: the object's mean width is over 1.6 px) loses most of it;
    the ``mixed`` estimator (the default) measures that stretch by partial volume and the
    wide one by count."""
    img, true_area = _tapered()
    mid = analyse_image(img, pixel_size_um=1.0, classify=False, flatten="none",
                        area="midpoint")
    mixed = analyse_image(img, pixel_size_um=1.0, classify=False, flatten="none")
    assert len(mid.cracks) == 2 and len(mixed.cracks) == 2
    err_mid = mid.cracks.area_px.sum() / true_area - 1
    err_mixed = mixed.cracks.area_px.sum() / true_area - 1
    assert err_mid < -0.10                       # the thin stretches' area is lost
    assert abs(err_mixed) < 0.05, err_mixed        # measured +3.3 %; the count -13.8 %
    assert set(mixed.cracks.area_method) == {"mixed"}
    assert set(mid.cracks.area_method) == {"count"}


def test_mixed_area_equals_the_count_on_resolved_cracks():
    """Cracks wide enough to show the void grey everywhere: ``mixed`` is the midpoint count."""
    img = np.full((200, 300), 170, np.uint8)
    img[60:68, 30:270] = 30
    img[130:136, 30:270] = 30
    img = ndi.gaussian_filter(img.astype(float), 0.8)
    img = np.clip(np.rint(img + np.random.default_rng(1).normal(0, 3, img.shape)), 0, 255)
    img = img.astype(np.uint8)
    mid = analyse_image(img, pixel_size_um=1.0, classify=False, flatten="none",
                        area="midpoint")
    mixed = analyse_image(img, pixel_size_um=1.0, classify=False, flatten="none")
    assert mixed.cracks.area_px.sum() == pytest.approx(mid.cracks.area_px.sum())
    assert mid.cracks.area_px.sum() == pytest.approx(240 * 14, rel=0.03)


def test_area_option_from_the_command_line(tmp_path):
    import tifffile
    img, _ = _tapered()
    (tmp_path / "d").mkdir()
    tifffile.imwrite(tmp_path / "d" / "t.tif", img)
    area = {}
    for flag in (["--area", "midpoint"], []):
        out = tmp_path / ("o" + str(len(flag)))  # o2: midpoint, o0: the default
        assert cli.main(["analyse", str(tmp_path / "d"), "--out", str(out), "--no-progress",
                         "--jobs", "1", "--pixel-size-um", "1", *flag]) == 0
        area[len(flag)] = pd.read_csv(out / "images.csv").iloc[0]["crack_area_um2"]
    assert area[0] > 1.05 * area[2]   # the default (mixed) keeps the thin stretches


def test_bad_area_option_is_one_clear_error():
    from semkit.errors import InputError
    from semkit.options import AnalysisOptions
    with pytest.raises(InputError, match="area: expected midpoint or mixed"):
        AnalysisOptions(area="pv")


def _lone_pair(spacing, blur, angle=0.0):
    """A layered crack alone: two 1.2-px traces (grey 30 in 180) ``spacing`` px apart, 160 px
    long at ``angle`` degrees; its analysis and area / truth."""
    from test_parallel_traces import _pair, _render
    img, _ = _render(_pair(spacing, angle), blur=blur)
    a = analyse_image(img, pixel_size_um=1.0, classify=False, flatten="none")
    return a, float(a.cracks.area_px.sum()) / (2 * 1.2 * 160.0)


@pytest.mark.parametrize("spacing,blur,angle,lo,hi", [(2.5, 0.7, 0.0, 0.95, 1.05),
                                                      (3.0, 1.0, 0.0, 0.95, 1.05),
                                                      (2.5, 0.7, 45.0, 1.1, 1.25)])
def test_a_layered_crack_alone_is_not_its_own_void(spacing, blur, angle, lo, hi):
    """One layered crack and nothing else dark: the 0.7-px denoising merges the traces into a
    flat band at grey 108-132, which passes for the void's plateau (area 2.1-2.5x against it).
    Read across before denoising, the band is two traces, so the void is taken as when no
    crack shows its core (54 here), and the note says why. Area 0.99x along the pixel grid;
    1.22x at 45 degrees, by partial volume against the assumed void (54, not the true 30:
    the bias of thin lines alone)."""
    a, ratio = _lone_pair(spacing, blur, angle)
    assert a.thresholded.void_read and a.thresholded.void_level > 100
    assert a.void_level[0] == pytest.approx(0.3 * 180, abs=3)
    assert lo <= ratio <= hi, ratio
    row = a.summary()
    assert "two or more traces" in row["threshold_note"] and row["valid"]


def test_a_layered_crack_beside_an_open_one_keeps_the_open_void():
    """The same pair beside a 6-px crack: the void's plateau is the open crack's core (one
    trace across), and the void grey read there is kept."""
    from test_parallel_traces import _pair, _render
    img, _ = _render(_pair(2.5, 0.0) + [(40.0, 170.0, 280.0, 170.0, 6.0)], blur=0.7)
    a = analyse_image(img, pixel_size_um=1.0, classify=False, flatten="none")
    assert a.void_level == (a.thresholded.void_level, "")
    assert a.void_level[0] < 45


@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="known limit (docs/semkit.md, Known limits): traces the raw image "
                   "does not part read as one band whose grey passes for the void")
@pytest.mark.parametrize("spacing,angle", [(2.5, 0.0), (3.0, 30.0)])
def test_a_layered_crack_merged_in_the_image_is_not_its_own_void(spacing, angle):
    """Two 1.2-px traces under a 1-px blur that the image before denoising does not part: 2.5
    px apart (one valley across them), or 3 px apart at 30 degrees (58-84 % of the band on
    two-trace cross-sections at 15-75 degrees, under the 90 % asked). The band's grey (122-124)
    passes for the void's plateau, and the area reads 2.45-2.49x, valid. Strict: passes once
    the area reads within 25 % or the image is flagged."""
    a, ratio = _lone_pair(spacing, 1.0, angle)
    assert ratio <= 1.25 or not a.summary()["valid"], ratio
