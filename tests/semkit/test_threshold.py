"""semkit.threshold and semkit.illumination: the auto method isolates the crack class."""
import numpy as np
import pytest
from _synth_cases import case

from semkit.cleanup import denoise
from semkit.errors import InputError
from semkit.illumination import flatten_illumination
from semkit.threshold import (
    crack_mask,
    dark_class_levels,
    noise_sigma,
    parse_method,
    threshold_local,
    threshold_otsu,
)


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
