"""semkit.threshold and semkit.illumination: the auto method isolates the crack class."""
import importlib.util
import pathlib

import numpy as np
import pytest
from _synth_cases import case, dev_scene

from semkit import config
from semkit.cleanup import denoise
from semkit.errors import InputError
from semkit.illumination import flatten_illumination
from semkit.synth import make_sem_image
from semkit.threshold import (
    crack_mask,
    dark_class_levels,
    field_noise_sigma,
    noise_sigma,
    parse_method,
    threshold_local,
    threshold_otsu,
)

# the clean line images live with their benchmark (one definition for the test and it)
_spec = importlib.util.spec_from_file_location(
    "line_family", pathlib.Path(__file__).resolve().parents[2] / "benchmarks" / "line_family.py")
lines = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(lines)


def test_parse_method():
    assert parse_method("manual:80") == ("manual", 80.0)
    assert parse_method("AUTO") == ("auto", None)
    for bad in ("manual", "manual:x", "triangle"):
        with pytest.raises(InputError, match="threshold"):
            parse_method(bad)


def test_otsu_bimodal_and_manual():
    img = np.r_[np.full(500, 30.0), np.full(500, 200.0)].reshape(20, 50)
    t = threshold_otsu(img)
    assert 30 < t < 200
    r = crack_mask(img, method="manual:100")
    assert r.mask.sum() == 500 and r.value == 100.0


def test_local_threshold_follows_a_ramp():
    ramp = np.linspace(60, 200, 200)[None, :] * np.ones((50, 1))
    img = ramp.copy()
    img[20:23, 10:190] *= 0.3
    r = crack_mask(img, method="local")
    assert r.mask[20:23, 30:170].all() and r.mask.sum() < 3 * 180 * 1.2
    assert threshold_local(img).shape == img.shape


def test_flatten_removes_a_2_5x_gradient():
    s = case(13, gradient=2.5)
    flat, field = flatten_illumination(s.image)
    truth = s.illumination / s.illumination.max()
    assert np.abs(field / truth - 1).max() < 0.15  # grain mosaic leaks into the fit a little
    g = flat[s.grain_labels > 0]
    # the same mineral now has the same grey on both sides
    m0 = (s.mineral_labels == 1) & ~s.crack_mask
    left, right = flat[:, :300][m0[:, :300]], flat[:, -300:][m0[:, -300:]]
    assert abs(np.median(left) / np.median(right) - 1) < 0.06
    assert g.size


@pytest.mark.parametrize("gradient", [1.0, 2.5])
def test_auto_isolates_the_dark_crack_class(gradient):
    s = case(14, gradient=gradient)
    img = denoise(flatten_illumination(s.image)[0])
    lv = dark_class_levels(img)
    # the darkest mineral is plagioclase (grey 100 x illumination), cracks ~30
    assert 80 < lv.mineral < 120 and 15 < lv.crack < 50
    assert noise_sigma(img) < lv.sigma
    r = crack_mask(img, method="auto")
    assert r.ok
    assert 0.5 * s.crack_mask.mean() < r.dark_fraction < 2 * s.crack_mask.mean()
    # nothing of a mineral phase: < 1 % of the measured area lies outside true cracks' rims
    from scipy import ndimage as ndi
    rim = ndi.binary_dilation(s.crack_mask, iterations=2)
    assert (r.mask & ~rim).sum() < 0.01 * r.mask.sum()


def test_otsu_on_few_percent_cracks_grabs_a_mineral_and_is_flagged():
    s = case(15)
    img = denoise(flatten_illumination(s.image)[0])
    r = crack_mask(img, method="otsu")
    assert r.dark_fraction > 0.2 and not r.ok and "mineral" in r.note


def test_illumination_field_on_a_flat_nearly_noiseless_image():
    """A uniform matrix with little noise: the robust refit once dropped every pixel and
    crashed; the field is flat (evenly lit) and finite."""
    from scipy import ndimage as ndi

    from semkit.illumination import illumination_field
    rng = np.random.default_rng(3)
    img = np.full((200, 400), 170.0)
    img[54:66, 20:380] = 30
    for k, c0 in enumerate(range(20, 380, 20)):
        img[150 + 2 * (k % 2), c0:c0 + 24] = 30
    img = np.clip(ndi.gaussian_filter(img, 0.7) + rng.normal(0, 3, img.shape), 0, 255)
    f = illumination_field(img.astype(np.uint8))
    assert np.isfinite(f).all() and f.min() > 0.9 and f.max() == 1.0


@pytest.mark.parametrize("seed", [3, 7])
def test_cracks_as_dark_as_the_darkest_mineral_are_measured_and_flagged(seed):
    """A dark mineral as dark as the thin cracks' partial volumes leaves no pixel darker than
    the darkest mineral. The cracks must still be found as narrow dark lines (their grey read
    on the lines) and the result flagged; the image was once reported crack-free and valid."""
    from semkit.analysis import analyse_image
    from semkit.threshold import _percentiles
    minerals = (("m0", 140.0, 0.47), ("m1", 168.5, 0.31), ("m2", 203.3, 0.20),
                ("dark", 51.0, 0.11))
    s = make_sem_image((512, 640), stage="post", seed=seed, minerals=minerals,
                       widths=(1.0, 4.5), noise_sigma=8.0, blur_sigma=0.8, mean_grain_px=100)
    a = analyse_image(s.image, pixel_size_um=1.0, name="dark_mineral")
    lv = dark_class_levels(a.smooth)  # the case: no dark tail, nothing below the mineral
    assert not (np.isfinite(lv.crack) and lv.n_dark >= 10)
    assert _percentiles(a.smooth[::2, ::2], (0.2,))[0] >= lv.mineral - 6.0 * lv.noise
    row = a.summary()
    area = row["crack_area_um2"] / s.cracks["area_cov_px"].sum() - 1.0
    length = row["crack_length_um"] / s.cracks["length_px"].sum() - 1.0
    assert abs(area) < 0.25 and abs(length) < 0.2, (area, length)  # +15/+8 %, +7/+3 %
    assert not row["threshold_ok"] and not row["valid"]


def test_line_crack_level_ignores_noise_inside_a_dark_grain():
    """Inside a dark grain every noise dip is below the closing; only lines in the brighter
    rock count, so a crack-free image with a dark mineral has (almost) no line pixels."""
    from semkit.threshold import dark_class_levels, line_crack_level
    s = make_sem_image((512, 640), stage="pre", n_cracks=0, n_speckles=0, seed=0,
                       minerals=(("a", 200.0, 0.5), ("b", 150.0, 0.35), ("dark", 50.0, 0.15)))
    img = s.image.astype(np.float32)
    lv = dark_class_levels(img)
    _, share = line_crack_level(img, lv.mineral, lv.noise)
    assert share < 0.002
    c = make_sem_image((512, 640), stage="pre", n_cracks=8, widths=(2.0, 4.0), seed=0,
                       minerals=(("a", 200.0, 0.5), ("b", 150.0, 0.35), ("dark", 50.0, 0.15)))
    level, share = line_crack_level(c.image.astype(np.float32), lv.mineral, lv.noise)
    assert share > 0.005 and level < 100.0


def test_too_few_lines_to_read_give_no_crack_but_a_flag(monkeypatch):
    """Lines holding more than LINE_WARN_SHARE but less than LINE_CRACK_MIN_SHARE of the image
    are too few to read a crack grey from: no crack, and threshold_ok False with the reason."""
    from semkit import config
    from semkit.analysis import analyse_image
    minerals = (("m0", 140.0, 0.47), ("m1", 168.5, 0.31), ("m2", 203.3, 0.20),
                ("dark", 51.0, 0.11))
    s = make_sem_image((512, 640), stage="post", seed=3, minerals=minerals,
                       widths=(1.0, 4.5), noise_sigma=8.0, blur_sigma=0.8, mean_grain_px=100)
    smooth = analyse_image(s.image, pixel_size_um=1.0).smooth
    monkeypatch.setattr(config, "LINE_CRACK_MIN_SHARE", 1.0)
    r = crack_mask(smooth)
    assert not r.ok and "may be missed" in r.note and not r.mask.any()
    monkeypatch.setattr(config, "LINE_WARN_SHARE", 1.0)
    r = crack_mask(smooth)
    assert r.ok and r.note == "no dark class" and not r.mask.any()


@pytest.mark.parametrize("seed", [1, 3, 4])
def test_cracks_as_dark_as_a_dark_mineral_read_their_void_on_their_own_plateaus(seed):
    """Cracks (grey ~30) in rock with a dark mineral at 46: the dark class below the mineral
    shows no plateau, and the crack grey was assumed at 0.3 x the darkest mineral, 14-21
    greys below the cores of the 8-px cracks, so every partial-volume area read low (area
    -35 to -56 %). The void grey is now read on the flat cores of the widest detected cracks:
    within 10 % of the contrast of the true cores' grey, and said so."""
    import cv2

    from semkit.analysis import analyse_image
    minerals = (("m0", 118.0, 0.22), ("m1", 104.0, 0.27), ("m2", 122.0, 0.44),
                ("m3", 78.0, 0.31), ("dark", 46.0, 0.11))
    s = make_sem_image((512, 640), stage="post", seed=seed, minerals=minerals,
                       widths=(1.8, 8.5), noise_sigma=7.0, blur_sigma=1.2, mean_grain_px=140,
                       boundary_depth=0.07)
    a = analyse_image(s.image, pixel_size_um=1.0, stage="failure", classify=False)
    lv = dark_class_levels(a.smooth)
    assert not lv.resolved
    core = cv2.erode(s.crack_mask.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    truth = float(np.median(a.smooth[core]))
    th = a.thresholded
    assert abs(th.void_level - truth) < 0.1 * (lv.mineral - truth), (th.void_level, truth)
    assert "void grey is read as" in th.note


def test_a_large_image_finds_the_plateaus_of_its_4_px_cracks():
    """On a 3-MP image the dark class is read on every 4th pixel, where a plateau needed
    12 px of width: 4-px cracks showed none, and a small dark grain (105 grey, 1.4 % of the
    image, under the mineral share) gave the void grey, 105 instead of 30 (a speed-set
    image read area +39 %, valid). The plateaus are looked for at full resolution."""
    import cv2
    from scipy import ndimage as ndi
    rng = np.random.default_rng(0)
    img = np.full((1536, 2048), 170.0)
    img[1200:1420, 300:500] = 105.0
    for k in range(6):
        x = 300 + k * 280
        cv2.line(img, (x, 50), (x + 120, 1450), 30.0, 4)   # the first one through the grain
    img = ndi.gaussian_filter(img, 1.0) + rng.normal(0, 3, img.shape)
    lv = dark_class_levels(img.astype(np.float32))
    assert lv.resolved and abs(lv.flat_crack - 30.0) < 0.1 * (lv.mineral - 30.0), lv
    assert lv.phase_share > 0.4          # the grain's plateau is a brighter phase


@pytest.mark.parametrize("widths", [(15.0, 40.0), (25.0, 60.0)])
def test_cracks_wider_than_the_closing_are_flagged_not_read_as_none(widths):
    """Cracks 15-60 px wide (a high magnification) survive the 11 x 11 closing that finds the
    minerals: they were the darkest mineral, nothing was darker, and the image read no crack
    and was valid. Their phase lies mostly in long, narrow objects: flagged."""
    from semkit.analysis import analyse_image
    s = make_sem_image((768, 1024), stage="pre", widths=widths, n_cracks=10, seed=5)
    row = analyse_image(s.image, pixel_size_um=1.0, stage="pre-test",
                        classify=False).summary()
    assert not row["valid"] and "long objects" in row["threshold_note"], row["valid_note"]


def test_a_dark_mineral_of_grains_is_not_flagged_as_wide_cracks():
    """Development image 6's dark mineral (74 grey) closes into an elongated cluster of
    grains, but 145 px wide: not long narrow objects."""
    from semkit.analysis import analyse_image
    s = dev_scene(6)
    lv = dark_class_levels(np.asarray(analyse_image(s.image, pixel_size_um=1.0).smooth,
                                      np.float32))
    assert 0.0 < lv.line_share < config.LINE_PHASE_MIN_SHARE, lv.line_share


@pytest.mark.parametrize("width,blur", [(1.5, 1.0), (2.0, 1.4), (3.0, 1.0)])
def test_hairline_only_image_reads_no_partial_volume_as_the_crack_grey(width, blur):
    """Every crack 1.5-3 px wide and blurred: the darkest grey across each is a partial volume
    with no flat core. Read as the crack grey it inflated every area 1.3-2.1x (the image was
    marked valid); the crack grey is now assumed, said so, and areas are within 15 %."""
    from semkit.analysis import analyse_image
    img, true_area, _ = lines.hairlines(width, blur, noise=3.0)
    lv = dark_class_levels(denoise(img.astype(np.float32)))
    assert not lv.resolved
    a = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=False)
    row = a.summary()
    assert abs(row["crack_area_um2"] / true_area - 1) < 0.15, row["crack_area_um2"] / true_area
    assert "no crack shows its core grey" in row["threshold_note"]


def test_a_crack_with_a_flat_core_keeps_its_measured_grey():
    """6 px cracks show their void grey on a plateau: read there (near 30), not assumed."""
    img, _, _ = lines.hairlines(6.0, 0.6, noise=3.0)
    lv = dark_class_levels(denoise(img.astype(np.float32)))
    assert lv.resolved and abs(lv.crack - 30.0) < 10.0


def test_cracks_found_only_in_part_are_flagged():
    """1-px hairlines blurred by 1.4 px: with the crack grey assumed (no flat core), the
    threshold catches a fifth of their length and the ridge lines carry on from it; the image
    read area -75 %, length -78 % and was marked valid. The continuation was then measured
    and the image flagged; now its pieces deep enough are added as crack (length -2.3 %, area
    +11 %), and the image stays flagged: a ridge line carries on along a grain boundary as
    well (``test_phase_edges_are_rejected_and_no_crack_with_them``)."""
    from semkit.analysis import analyse_image
    img, area, length = lines.hairlines(1.0, 1.4, noise=3.0)
    row = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=False).summary()
    assert abs(row["crack_length_um"] / length - 1) < 0.05
    assert abs(row["crack_area_um2"] / area - 1) < 0.15
    assert not row["valid"] and "faint continuations" in row["valid_note"]


@pytest.mark.parametrize("blur", [0.6, 1.0, 1.4])
def test_areas_are_measured_against_the_void_grey_of_the_flat_cores(blur):
    """Cracks 1.5-8 px wide under blur: the narrower ones' cores pull the dark class's median
    from 30 up to ~67 (blur 1.4), and a midpoint on that grey read every counted area 8-27 %
    high. The void grey is read on the flat cores instead: total area within 3 %."""
    from semkit.analysis import analyse_image
    img, true_area, _ = lines.line_mix(blur)
    a = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=False)
    th = a.thresholded
    assert abs(th.void_level - 30.0) < 0.05 * (170.0 - 30.0)
    if blur == 1.4:
        assert th.crack_level > 60.0          # the pulled-up grey is still what detection uses
    row = a.summary()
    assert row["valid"] and abs(row["crack_area_um2"] / true_area - 1) < 0.03


@pytest.mark.parametrize("blur", [1.0, 1.4])
def test_typed_areas_use_the_void_grey_too(blur):
    """A_T and A_S come from the typed partial-volume areas (``area_pv_um2``): against the
    pulled-up crack grey they read the 1.5-8 px lines +12 % (blur 1) and +28 % (blur 1.4);
    against the void grey, as the crack areas do, within 5 %."""
    from semkit.analysis import analyse_image
    img, true_area, _ = lines.line_mix(blur)
    c = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=True).typed_cracks
    assert abs(c.area_pv_um2.sum() / true_area - 1) < 0.05


def test_field_noise_sigma_reads_smoothed_noise_as_deep_as_it_is():
    """Smoothed noise is correlated over a few pixels: the pixel-to-pixel sigma reads it ~1.6 x
    low, so "6 sigmas" let noise specks seed cracks; the field sigma reads it within 20 %."""
    rng = np.random.default_rng(2)
    for sigma in (4.0, 24.0):
        sm = denoise(rng.normal(120.0, sigma, (600, 700)).astype(np.float32), sigma_px=0.7)
        assert abs(field_noise_sigma(sm) / sm.std() - 1) < 0.2
        assert field_noise_sigma(sm) > 1.25 * noise_sigma(sm)


def _dev_image(seed, noise):
    from semkit.analysis import analyse_image
    s = dev_scene(seed, noise_sigma=noise)
    row = analyse_image(s.image, pixel_size_um=s.pixel_size_um, name="x", classify=False
                        ).summary()
    return row, row["crack_length_um"] / s.pixel_size_um / s.cracks["length_px"].sum() - 1


def test_noisy_image_reads_fewer_specks_and_is_flagged():
    """Development image 1 with its noise raised from 10.6 to 24 grey: counted in pixel
    sigmas, the seeds let noise specks through (348 objects, length +114 %, valid). In
    fine-scale noise sigmas: 196 objects, +39 %, and the image is flagged for its noise."""
    row, err = _dev_image(1, 24.0)
    assert row["n_cracks"] < 250 and err < 0.6
    assert row["contrast_to_noise"] < config.MIN_CONTRAST_TO_NOISE
    assert not row["valid"] and "noise:" in row["valid_note"]
    row, err = _dev_image(1, 4.0)       # the same scene, quiet: valid, length within 5 %
    assert row["contrast_to_noise"] >= config.MIN_CONTRAST_TO_NOISE
    assert row["valid"] and abs(err) < 0.05


def test_a_clipped_image_is_flagged_saturated():
    """Development image 11 with its grey raised 1.4x and clipped at 255 (its brightest mineral
    saturates): area -17 %, length -11 %, valid before; now flagged. Unclipped: valid."""
    from semkit.analysis import analyse_image
    s = dev_scene(11)
    clipped = np.minimum(s.image.astype(np.float64) * 1.4, 255).astype(np.uint8)
    for img, saturated in ((s.image, False), (clipped, True)):
        row = analyse_image(img, pixel_size_um=s.pixel_size_um, name="x", classify=False
                            ).summary()
        assert ("saturated:" in row["valid_note"]) == saturated
    assert not row["valid"]


def test_bright_crack_walls_are_flagged():
    """Development image 14 with a bright rim (a quarter of the grey range, blurred by 1 px)
    along every crack wall, as a secondary-electron edge effect makes it: area -22 %, valid
    before. The walls' upper quartile lies >= 0.05 of the crack contrast above the rock's:
    flagged ``bright walls``. Without the rim the walls are darker than the rock (blur), and
    the image stays valid."""
    import cv2

    from semkit.analysis import analyse_image
    s = dev_scene(14)
    m = (s.crack_labels > 0).astype(np.uint8)
    ring = cv2.dilate(m, np.ones((5, 5), np.uint8)).astype(bool) & (m == 0)
    rim = cv2.GaussianBlur(ring.astype(np.float32), (0, 0), 1.0) * 0.25 * 255
    bright = np.clip(np.rint(s.image + rim), 0, 255).astype(np.uint8)
    truth = float(s.cracks["area_cov_px"].sum()) * s.pixel_size_um ** 2
    for img, flagged in ((s.image, False), (bright, True)):
        a = analyse_image(img, pixel_size_um=s.pixel_size_um, name="x", classify=False)
        row = a.summary()
        assert (a._bright_walls() >= config.BRIGHT_WALLS_MIN_LIFT) == flagged, a._bright_walls()
        assert ("bright walls:" in row["valid_note"]) == flagged, row["valid_note"]
        assert row["valid"] != flagged
    assert row["crack_area_um2"] / truth - 1 < -0.15   # what the flag is for


def test_normalised_float_and_signed_images_read_as_the_8_bit_one():
    """A float image in 0..1 read area -12 % where its 8-bit original reads -6.8 % (absolute
    floors on a grey range of 1), and a signed one with negative greys -62 % (the illumination
    model is multiplicative); both are now put on the working scale first."""
    from semkit.analysis import analyse_image
    s = dev_scene(1)

    def area(img):
        return analyse_image(img, pixel_size_um=s.pixel_size_um, name="x", classify=False
                             ).summary()["crack_area_um2"]
    ref = area(s.image)
    for img in (s.image.astype(np.float32) / 255, s.image.astype(np.int16) - 100):
        assert abs(area(img) / ref - 1) < 0.005


def _lath_scene(seed=0):
    """One open crack 8 px wide at grey 30 and twenty laths of a dark mineral, 8 px wide, at
    grey 90, in a 170 rock (blur 1 px, noise 3): the laths' plateaus outnumber the crack's."""
    import cv2
    from scipy import ndimage as ndi
    rng = np.random.default_rng(seed)
    h, w, ss = 400, 600, 4
    crack = np.zeros((h * ss, w * ss), np.float32)
    laths = np.zeros_like(crack)
    cv2.line(crack, (40 * ss, 60 * ss), (560 * ss, 80 * ss), 1.0, 8 * ss)
    for k in range(20):
        cy, cx = 120 + 120 * (k % 3), 40 + 26 * k
        cv2.line(laths, (cx * ss, cy * ss), ((cx + 30) * ss, (cy + 40) * ss), 1.0, 8 * ss)
    c, lath = (ndi.gaussian_filter(m.reshape(h, ss, w, ss).mean(axis=(1, 3)), 1.0)
               for m in (crack, laths))
    g = 170 * (1 - c - lath) + 30 * c + 90 * lath + rng.normal(0, 3, (h, w))
    return np.clip(np.rint(g), 0, 255).astype(np.float32)


def test_the_void_grey_leaves_out_the_plateaus_of_dark_laths():
    """The dark class's flat cores lie at two greys: the crack's void (30) and the laths' (90),
    which hold most of them; their median read 88, and every crack's midpoint with it. The
    darkest open plateau is the void; the laths' plateaus are left out of it. Detection keeps
    the dark class's median, as its levels were set on it."""
    from semkit.threshold import dark_class_levels
    lv = dark_class_levels(_lath_scene())
    assert abs(lv.flat_crack - 30.0) < 0.05 * (170.0 - 30.0), lv
    assert lv.crack > 60.0, lv


def _synth_with_laths(n_laths, seed=3, widths=(3.0, 8.0), lath_width=(6, 10)):
    """A ``semkit.synth`` post-test image (8 cracks ``widths`` px wide) with ``n_laths`` laths
    of a dark mineral (the drawn family's :func:`paint_laths`: 30-80 x ``lath_width`` px, 6 px
    or more from every crack) at a grey 0.45 of the way from the crack grey to the rock around
    them."""
    import sys

    from scipy import ndimage as ndi

    from semkit.synth import CRACK_GREY
    bench = pathlib.Path(__file__).resolve().parents[2] / "benchmarks"
    if str(bench) not in sys.path:   # one definition of the laths for the test and it
        sys.path.insert(0, str(bench))
    from semkit_drawn_family import paint_laths
    s = make_sem_image((384, 512), stage="post", seed=seed, n_cracks=8, widths=widths)
    keep_out = ndi.binary_dilation(s.crack_mask, iterations=6)
    img = paint_laths(s.image, keep_out, n_laths, np.random.default_rng(seed), blur=0.8,
                      crack_grey=CRACK_GREY, share=(0.45, 0.45), size=((30, 80), lath_width))
    return img, s


@pytest.mark.parametrize("seed", [1, 2])
def test_plateaus_above_the_cores_of_thinner_cracks_are_a_dark_phase(seed):
    """Cracks 1.5-3 px wide (void 30) show no plateau; 12 laths 8-12 px wide at ~100 grey do.
    The laths' plateau read as the void (64-65), and every lath and partial volume counted
    against it: area +201 % and +63 %. Partial volumes are brighter than the void, never
    darker: the cracks' cores lying well below every plateau show the plateaus are a dark
    phase, and the crack grey is read on those cores."""
    from semkit.analysis import analyse_image
    from semkit.synth import CRACK_GREY
    from semkit.threshold import dark_class_levels
    img, s = _synth_with_laths(12, seed=seed, widths=(1.5, 3.0), lath_width=(8, 12))
    a = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=False)
    lv = dark_class_levels(a.smooth)
    assert lv.phase_plateaus and not lv.resolved
    assert abs(a.thresholded.void_level - CRACK_GREY) < 10.0, a.thresholded.void_level
    assert "plateaus lie above the cores of thinner cracks" in a.thresholded.note
    row = a.summary()   # and the laths are rejected as dark_band (step 5b): +34 / +20 % before
    assert abs(row["crack_area_um2"] / s.cracks["area_cov_px"].sum() - 1) < 0.2
    # without the laths: the cracks' own greys, no such reading
    assert not dark_class_levels(denoise(flatten_illumination(s.image)[0])).phase_plateaus


def test_an_image_whose_dark_class_holds_a_dark_phase_is_flagged():
    """22 laths of a dark mineral pull the dark class's grey from the void (34) to 62, 0.23
    of the contrast; their plateaus hold 81 % of the dark class's flat cores: the image is
    flagged ``dark phase``. Most laths are rejected as ``dark_band`` (wide, smooth, short of
    the void, darkest inside; their area was counted as crack: +89 %, now +6 %), and the
    image is flagged for resting on that rule too. Without the laths the dark class stays at
    its void and the area is right; no flag. (Thin cracks raise the gap too, without
    plateaus: ``test_areas_are_measured_against_the_void_grey_of_the_flat_cores`` keeps those
    images valid.)"""
    from semkit.analysis import analyse_image
    img, s = _synth_with_laths(22)
    a = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=False)
    assert a._void_gap() > 0.2 and a.thresholded.dark_phase_share > 0.6
    assert (a.rejected_as == "dark_band").sum() >= 10
    row = a.summary()
    assert abs(row["crack_area_um2"] / s.cracks["area_cov_px"].sum() - 1) < 0.15
    assert not row["valid"] and "dark phase" in row["valid_note"], row["valid_note"]
    assert "dark_band" in row["valid_note"]
    img, s = _synth_with_laths(0)
    c = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=False)
    assert c._void_gap() < 0.05
    row = c.summary()
    assert abs(row["crack_area_um2"] / s.cracks["area_cov_px"].sum() - 1) < 0.05
    assert "dark phase" not in row["valid_note"]


def test_pores_darker_than_the_cracks_do_not_set_the_void_grey():
    """Fifteen round pores (grey 25, 3-9 px radius) hold most of the dark class's flat cores
    beside cracks 1.5-5 px wide (grey 30) under a 1-px blur: the void grey read 24.7, every
    partial volume against it too small. Pores are left out of it: 29.3."""
    s = make_sem_image((768, 1024), stage="post", seed=1, n_pores=15, widths=(1.5, 5.0),
                       blur_sigma=1.0)
    th = crack_mask(denoise(flatten_illumination(s.image)[0]))
    assert abs(th.void_level - 30.0) < 2.0, th.void_level


def _blob_scene(blobs, wide_crack=False, seed=0):
    """Eight 2-px cracks (no flat core under a 1-px blur) at grey 30 in a 170 rock (noise 3),
    with ``blobs``: ``"lens"`` (one dark grain 64 x 20 px at grey 40, as dark as the void
    nearly) or ``"pores"`` (six round pores 14 px across at grey 30); with ``wide_crack`` also
    one open crack 9 px wide at grey 30."""
    import cv2
    from scipy import ndimage as ndi
    rng = np.random.default_rng(seed)
    h, w, ss = 400, 600, 4
    crack, blob = (np.zeros((h * ss, w * ss), np.float32) for _ in range(2))
    for k in range(8):
        x0, y0 = 30 + 70 * k, 40 + 10 * (k % 3)
        cv2.line(crack, (x0 * ss, y0 * ss), ((x0 + 40) * ss, (y0 + 150) * ss), 1.0, 2 * ss)
    if blobs == "lens":
        cv2.ellipse(blob, ((300 * ss, 300 * ss), (64 * ss, 20 * ss), 20.0), 1.0, -1)
    else:
        for k in range(6):
            cv2.circle(blob, ((60 + 90 * k) * ss, 330 * ss), 7 * ss, 1.0, -1)
    if wide_crack:
        cv2.line(crack, (40 * ss, 250 * ss), (560 * ss, 270 * ss), 1.0, 9 * ss)
    c, b = (ndi.gaussian_filter(m.reshape(h, ss, w, ss).mean(axis=(1, 3)), 1.0)
            for m in (crack, blob))
    grey = 40.0 if blobs == "lens" else 30.0
    g = 170 * (1 - c - b) + 30 * c + grey * b + rng.normal(0, 3, (h, w))
    return denoise(np.clip(np.rint(g), 0, 255).astype(np.float32))


@pytest.mark.parametrize("blobs", ["lens", "pores"])
def test_a_void_read_on_compact_blobs_alone_is_flagged(blobs):
    """No crack shows its core; the only plateaus lie on a dark grain (or pores). Read there,
    the void grey is a grain's as likely as the void's, and every thin crack's area scales
    with it (held-out renderings with an opaque lens: areas 1.4-2.2x, marked valid): the
    threshold says so and is not ok."""
    img = _blob_scene(blobs)
    lv = dark_class_levels(img)
    assert lv.resolved and lv.compact_void, lv
    r = crack_mask(img)
    assert not r.ok and "compact dark blobs" in r.note, r.note


@pytest.mark.parametrize("blobs", ["lens", "pores"])
def test_a_wide_crack_confirms_the_void_beside_blobs(blobs):
    """The same scene with one open crack 9 px wide: its plateau confirms the void grey."""
    img = _blob_scene(blobs, wide_crack=True)
    lv = dark_class_levels(img)
    assert lv.resolved and not lv.compact_void, lv
    assert abs(lv.flat_crack - 30.0) < 6.0, lv
    r = crack_mask(img)
    assert r.ok, r.note


def _render(masks_greys, seed=0, h=400, w=600, ss=4, rock=170.0):
    """Render ``[(draw, grey), ...]`` (``draw(canvas, ss)`` paints 1.0 on a ``ss`` x
    supersampled canvas) as area coverage under a 1-px blur on a ``rock`` grey, noise 3."""
    from scipy import ndimage as ndi
    rng = np.random.default_rng(seed)
    g = np.full((h, w), rock)
    for draw, grey in masks_greys:
        m = np.zeros((h * ss, w * ss), np.float32)
        draw(m, ss)
        c = ndi.gaussian_filter(m.reshape(h, ss, w, ss).mean(axis=(1, 3)), 1.0)
        g += (grey - rock) * c
    return np.clip(np.rint(g + rng.normal(0, 3, (h, w))), 0, 255).astype(np.float32)


def test_small_laths_are_left_out_of_the_void_one_by_one():
    """One open crack 8 px wide (grey 30, 124 flat-core px) beside 48 laths of a dark
    mineral (95), each too small to hold a plateau of ``VOID_PLATEAU_MIN_PX`` on its own
    (14-18 flat px), together 700: the void grey read 95.9, the laths' (held-out renderings
    with small laths: areas +123 %, marked valid). Each component is judged by its own
    plateau against the open crack's."""
    import cv2

    def crack(m, ss):
        cv2.line(m, (100 * ss, 60 * ss), (160 * ss, 70 * ss), 1.0, 8 * ss)

    def laths(m, ss):
        for k in range(48):
            cy, cx = 120 + 70 * (k % 4), 30 + 45 * (k // 4)
            cv2.line(m, (cx * ss, cy * ss), ((cx + 16) * ss, (cy + 22) * ss), 1.0, 6 * ss)

    lv = dark_class_levels(denoise(_render([(crack, 30.0), (laths, 95.0)])))
    assert abs(lv.flat_crack - 30.0) < 3.0, lv
    assert lv.phase_share > 0.5, lv


def test_grey_blobs_shaped_like_pores_do_not_set_the_void():
    """Eight round grains of a dark mineral (100, 24 px across) and three pores (25) are
    pore-shaped and left out of the void; the open plateaus left are one short crack's (25,
    5 flat px) and a small lath's (105, 18 px), none of ``VOID_PLATEAU_MIN_PX``: the void
    read 101 (held-out rendering with dark blobs: area +49 %, marked valid). With no open
    plateau of that size the pores' are the reference: the lath lies far above the darkest,
    the short crack on it, and the void is read there."""
    import cv2

    def thin(m, ss):
        for k in range(6):
            x0 = 30 + 90 * k
            cv2.line(m, (x0 * ss, 40 * ss), ((x0 + 40) * ss, 160 * ss), 1.0, 2 * ss)
        cv2.line(m, (300 * ss, 200 * ss), (314 * ss, 204 * ss), 1.0, 6 * ss)

    def pores(m, ss):
        for k in range(3):
            cv2.circle(m, ((80 + 200 * k) * ss, 370 * ss), 7 * ss, 1.0, -1)

    def blobs(m, ss):
        for k in range(8):
            cv2.circle(m, ((40 + 70 * k) * ss, 280 * ss), 12 * ss, 1.0, -1)

    def lath(m, ss):
        cv2.line(m, (420 * ss, 200 * ss), (432 * ss, 214 * ss), 1.0, 6 * ss)

    img = denoise(_render([(thin, 25.0), (pores, 25.0), (blobs, 100.0), (lath, 105.0)]))
    assert abs(crack_mask(img).void_level - 25.0) < 5.0
