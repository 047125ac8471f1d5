"""Post-test typing parts (issue 15): groups, morphology, trained ranges, P confidence."""
import numpy as np
import pytest
from scipy import ndimage as ndi

from semkit.classify import classify_post
from semkit.classify.model import DEFAULT_POST_MODEL, load_model, out_of_range
from semkit.classify.morphology import FEATURE_NAMES, crack_groups, crack_morphology
from semkit.damage import image_damage
from semkit.damage_confidence import P_SPREAD_MAX, p_confidence
from semkit.errors import InputError

COL = {n: i for i, n in enumerate(FEATURE_NAMES)}


def _features(lab, image=None):
    g, F, _ = crack_morphology(lab, image=image)
    return g, F


def test_small_fragments_join_the_nearest_large_crack():
    lab = np.zeros((50, 100), np.int32)
    lab[10:13, 5:95] = 1      # large crack
    lab[18:20, 40:42] = 2     # speck 5 px away -> joins 1
    lab[46:48, 40:42] = 3     # speck 33 px away -> alone
    lab[30:33, 5:95] = 4      # another large crack
    lab[25:27, 60:62] = 5     # speck nearer to 4 (3 px) than to 1 (12 px)
    assert crack_groups(lab).tolist() == [0, 1, 1, 3, 4, 4]
    assert crack_groups(lab, link_px=2).tolist() == [0, 1, 2, 3, 4, 5]


def test_morphology_reads_opening_layers_steps_and_fill():
    lab = np.zeros((90, 200), np.int32)
    lab[10:17, 20:180] = 1                            # opening, 7 px
    lab[40, 20:180] = 2                               # layered pair 5 px apart
    lab[45, 20:180] = 3
    for k, c0 in enumerate(range(20, 180, 16)):       # stepped trace: 3-px offsets
        lab[70 + 3 * (k % 2), c0:c0 + 17] = 4
    img = np.where(lab > 0, 30.0, 160.0)
    img[10:17, 20:180] = 30
    img = ndi.gaussian_filter(img, 0.6)
    tr, F = _features(lab, image=img)
    o, pair, step = F[tr[1]], F[tr[2]], F[tr[4]]
    assert np.exp(o[COL["log_aperture"]]) == pytest.approx(7, rel=0.15)
    assert o[COL["aperture_cv"]] < 0.2 and o[COL["wide_share"]] > 0.8
    assert o[COL["layers"]] == pytest.approx(1, abs=0.2)
    assert pair[COL["layers"]] > 1.6 > o[COL["layers"]]
    assert step[COL["scatter"]] > 2 * o[COL["scatter"]] and step[COL["thin_share"]] > 0.8
    assert o[COL["fill"]] > 0.9 > pair[COL["fill"]] - 0.2      # thin lines read lighter
    assert np.isnan(_features(lab)[1][tr[1], COL["fill"]])     # no image: not measured


def test_a_crack_outside_the_trained_range_is_not_typed_with_confidence():
    lab = np.zeros((160, 400), np.int32)
    lab[60:100, 20:380] = 1                            # a 40-px opening: no crack trained so
    lab[20:26, 20:380] = 2                             # an ordinary 6-px opening
    t, _ = classify_post(lab)
    t = t.set_index("crack_id")
    assert not t.loc[1, "type_post_ok"] and "log_aperture" in t.loc[1, "type_note"]
    assert t.loc[2, "type_post_ok"] and t.loc[2, "type_note"] == ""
    notes = out_of_range(np.full((1, len(DEFAULT_POST_MODEL["range_lo"])), np.nan),
                         DEFAULT_POST_MODEL)
    assert notes == [""]                               # not measured is not out of range


def test_p_confidence_band_and_flags():
    ok = p_confidence([100, 50], [[0.98, 0.01, 0.01], [0.01, 0.98, 0.01]])
    assert ok["P_low"] <= 2.0 <= ok["P_high"] and not ok["low_confidence"]
    wide = p_confidence([100, 50, 80, 40], [[0.7, 0.3, 0], [0.3, 0.7, 0]] * 2)
    assert wide["low_confidence"] and "band" in wide["note"]
    assert wide["P_high"] / wide["P_low"] > P_SPREAD_MAX
    untrusted = p_confidence([100, 50], [[0.98, 0.01, 0.01], [0.01, 0.98, 0.01]],
                             trusted=[False, True], notes=["log_aperture 5 outside", ""])
    assert untrusted["low_confidence"] and "log_aperture" in untrusted["note"]
    zero = p_confidence([100, 50, 60], [[0.6, 0.4, 0], [0.4, 0.6, 0], [0.5, 0.5, 0]])
    assert zero["low_confidence"] and zero["P_low"] == 0 and "may be 0" in zero["note"]
    # two cracks of one group share their draw: P is 0 or 4, never 2
    one = p_confidence([100, 100, 50], [[0.5, 0.5, 0], [0.5, 0.5, 0], [0, 1, 0]],
                       group=[1, 1, 2])
    assert one["P_low"] == 0.0 and one["P_high"] == 4.0


def test_image_damage_reports_the_band_and_low_confidence():
    import pandas as pd
    c = pd.DataFrame(dict(image="a", crack_id=[1, 2], area_um2=[100.0, 50.0],
                          type_post=["tensile", "shear"], frac_tensile=[1.0, 0.0],
                          frac_shear=[0.0, 1.0], frac_mixed=[0.0, 0.0],
                          p_tensile=[0.55, 0.45], p_shear=[0.45, 0.55], p_mixed=[0.0, 0.0],
                          type_post_ok=[True, True], type_note=["", ""]))
    d = image_damage(c).iloc[0]
    # crack 2 is drawn tensile in 45 % of the draws: no shear, P undefined there
    assert d.P == 2.0 and d.P_status == "low_confidence" and "no shear" in d.P_note
    assert np.isnan(d.P_high)
    sure = c.assign(p_tensile=[0.99, 0.0], p_shear=[0.01, 1.0])
    assert image_damage(sure).iloc[0].P_status == "ok"
    users = c.assign(type_source="user")
    assert image_damage(users).iloc[0].P_status == "ok"    # user types are certain
    # a common lean of the model that typed them (type_shift_sd) moves uncertain groups, not
    # sure ones nor user types
    assert image_damage(sure.assign(type_shift_sd=2.0)).iloc[0].P_status == "ok"
    assert image_damage(users.assign(type_shift_sd=2.0)).iloc[0].P_status == "ok"


def test_a_common_lean_widens_the_band_of_many_groups():
    area, prob = [10.0] * 40, [[0.9, 0.1, 0.0]] * 20 + [[0.1, 0.9, 0.0]] * 20
    alone = p_confidence(area, prob)
    lean = p_confidence(area, prob, shift_sd=2.0)
    # independent draws average out over 40 groups; a lean shared by all of them does not
    assert not alone["low_confidence"] and alone["P_high"] / alone["P_low"] < 1.6
    assert lean["low_confidence"] and lean["P_high"] / lean["P_low"] > 4
    # the band under a lean of +-1.28 sd (its 10-90 % quantiles) holds the P of that lean
    for d in (-1.28 * 2.0, 1.28 * 2.0):
        w = np.asarray(prob) * np.exp(d * np.array([0.5, -0.5, 0.0]))
        w /= w.sum(axis=1, keepdims=True)
        p_lean = (w[:, 0] * 10).sum() / (w[:, 1] * 10).sum()
        assert lean["P_low"] * 0.8 <= p_lean <= lean["P_high"] * 1.25
    with pytest.raises(InputError, match="shift_sd"):
        p_confidence(area, prob, shift_sd=-1.0)


@pytest.mark.parametrize("sd", [0.0, 1.5])
def test_image_shift_is_recovered_from_labels_drawn_with_a_known_lean(sd):
    from semkit.classify.model import SHIFT_DIRECTION, shift_sd_mle
    rng = np.random.default_rng(1)
    per_image = []
    for _ in range(200):
        s = rng.normal(0.0, 2.0, (8, 3))
        z = s + sd * rng.standard_normal() * np.asarray(SHIFT_DIRECTION)
        p = np.exp(z - z.max(axis=1, keepdims=True))
        p /= p.sum(axis=1, keepdims=True)
        per_image.append((s, (rng.random((8, 1)) > p.cumsum(axis=1)[:, :-1]).sum(axis=1)))
    r = shift_sd_mle(per_image)
    assert abs(r["sd"] - sd) < 0.3 and r["sd_low"] <= sd <= r["sd_high"]


def test_the_built_in_model_passes_its_lean_to_the_crack_table():
    from semkit.classify import classify_post
    sd = DEFAULT_POST_MODEL["image_shift_sd"]
    assert 1.0 < sd < 3.0           # fitted on held-out renderings (benchmarks/typing_model.py)
    lab = np.zeros((40, 80), np.int32)
    lab[18:24, 5:75] = 1
    t, _ = classify_post(lab)
    assert t["type_shift_sd"].tolist() == [sd]


def test_load_model_refuses_an_old_model(tmp_path):
    import json
    (tmp_path / "old.json").write_text(json.dumps({"version": 2, "coef": [0.0] * 13}))
    with pytest.raises(InputError, match="version 2"):
        load_model(tmp_path / "old.json")


def _scene(opening_px):
    """A crack-free semkit.synth micrograph with a straight opening (``opening_px`` wide; 0:
    none), a 6-px opening and a thin stepped trace drawn on it."""
    from semkit.synth import make_sem_image
    s = make_sem_image((256, 384), stage="pre", n_cracks=0, seed=5)
    img = s.image.astype(float)
    dark = 0.2 * np.median(img)
    if opening_px:
        img[70 - opening_px // 2:70 + opening_px // 2, 20:360] = dark
    img[120:126, 30:350] = dark
    for k, c0 in enumerate(range(20, 360, 20)):
        img[180 + 2 * (k % 2), c0:c0 + 24] = dark
    return ndi.gaussian_filter(img, 0.7).astype(s.image.dtype)


def test_analysis_flags_a_crack_unlike_the_training_family():
    """End to end: a 12-px opening (the trained log-aperture range ends near 10 px) is typed
    but not trusted, its note names the feature, and the image's P is low_confidence with a
    note naming it, rather than a number printed as if fine."""
    from semkit.analysis import analyse_image
    a = analyse_image(_scene(12), stage="failure")
    c = a.typed_cracks
    wide = c.loc[c.area_px.idxmax()]
    assert not wide.type_post_ok and wide.type_note.startswith("log_aperture")
    row = a.summary()
    assert row["P_status"] == "low_confidence"
    assert "untyped" in row["P_note"] and "log_aperture" in row["P_note"], row["P_note"]
    b = analyse_image(_scene(0), stage="failure").typed_cracks
    assert b.loc[b.area_px.idxmax()].type_post_ok              # the 6-px opening is trusted
