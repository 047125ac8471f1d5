"""Tests of semkit.classify (issues #3, 15): He et al.'s pre-existing rule, post-test typing."""
import functools

import numpy as np
import pandas as pd
import pytest
from scipy import ndimage as ndi

from semkit import config
from semkit.classify import (
    DEFAULT_POST_MODEL,
    INTER_MIN_FRACTION,
    apply_labels,
    classify_post,
    classify_pre,
    load_model,
    read_labels,
    save_model,
    train_post,
)
from semkit.classify.model import (
    STAGE2_NAMES,
    _group_rows,
    calibrate,
    image_samples,
    type_probabilities,
)
from semkit.damage import typed_areas
from semkit.errors import InputError

PRE = {"inter": 1, "intra": 2, "trans": 3}
POST = {"tensile": 1, "shear": 2, "mixed": 3}
# issue #3 target for pre-existing types: 0.90 by area. Post-test typing (issue 15) is
# trained on the domain-randomised family of benchmarks/typing/render.py, of which
# semkit.synth is one part; its accuracy on semkit.synth seeds 200-205 is asserted at
# POST_SYNTH_ACCURACY_MIN, P within P_MEDIAN_ERROR_MAX or flagged (docs/semkit_science.md).
PRE_AREA_ACCURACY_MIN = config.PRE_TYPE_ACCURACY_MIN
POST_SYNTH_ACCURACY_MIN = config.POST_TYPE_ACCURACY_SYNTH_MIN
P_MEDIAN_ERROR_MAX = config.P_TOL_MEDIAN
CALIBRATION_GAP_MAX = config.POST_CALIBRATION_GAP_MAX
HELD_OUT_SEEDS = (200, 201, 202, 203, 204, 205)


def _grain_map():
    """Four rectangular grains in a 100 x 100 image: boundaries at row 50 and column 50."""
    g = np.ones((100, 100), np.int32)
    g[:50, 50:] = 2
    g[50:, :50] = 3
    g[50:, 50:] = 4
    return g


def test_classify_pre_hand_drawn_exact():
    g = _grain_map()
    lab = np.zeros_like(g)
    lab[49:51, 55:95] = 1          # along the horizontal boundary (grains 2 | 4)
    lab[10:13, 10:40] = 2          # inside grain 1
    lab[70:72, 5:95] = 3           # crosses grains 3 and 4 (and the vertical boundary)
    lab[20:80, 30:32] = 4          # crosses grains 1 and 3 across the horizontal boundary
    t = classify_pre(lab, g)[0].set_index("crack_id")
    assert t.type_pre.to_dict() == {1: "inter", 2: "intra", 3: "trans", 4: "trans"}
    assert t.loc[1, "boundary_fraction"] > INTER_MIN_FRACTION
    assert t.loc[2, "boundary_fraction"] == 0 and t.loc[2, "max_grain_fraction"] == 1.0
    assert t.loc[3, "n_grains"] == 2
    assert t.loc[3, "max_grain_fraction"] == pytest.approx(0.5, abs=0.05)
    assert (t.confidence >= 0.5).all() and (t.confidence <= 1).all()
    # a grain map with holes (0 under the cracks) is filled from the nearest grain
    g0 = g.copy()
    g0[lab > 0] = 0
    assert classify_pre(lab, g0)[0].type_pre.tolist() == t.type_pre.tolist()
    with pytest.raises(InputError, match="grain_labels"):
        classify_pre(lab, g[:50])


def _detect(image, area=False):
    """Crack objects as the pipeline finds them (``auto`` detection mask), optionally with
    the skeleton of the stricter area mask."""
    from skimage.morphology import skeletonize

    from semkit.threshold import crack_mask
    r = crack_mask(ndi.gaussian_filter(image.astype(np.float32), 0.7), method="auto")
    lab, _ = ndi.label(r.detect_mask, structure=np.ones((3, 3)))
    if area:
        return lab, skeletonize(r.mask) & (lab > 0)
    return lab


def test_classify_pre_on_synthetic_images_with_known_grains():
    synth = pytest.importorskip("semkit.synth")
    good = tot = 0
    for seed in (300, 303, 305):
        s = synth.make_sem_image((384, 512), stage="pre", n_cracks=12, seed=seed)
        lab, skel = _detect(s.image, area=True)
        t, types = classify_pre(lab, s.grain_labels, skeleton=skel)
        code = np.zeros(len(s.cracks) + 1, int)
        code[s.cracks.crack_id] = [PRE[x] for x in s.cracks.type_pre]
        truth = code[s.crack_labels]
        sel = (truth > 0) & (lab > 0)
        good += (types[sel] == truth[sel]).sum()
        tot += sel.sum()
    assert good / tot >= PRE_AREA_ACCURACY_MIN, good / tot


def _draw(img, rr, cc, grey=30):
    ok = (rr >= 0) & (rr < img.shape[0]) & (cc >= 0) & (cc < img.shape[1])
    img[rr[ok], cc[ok]] = grey


def test_classify_post_hand_drawn_tensile_and_shear():
    rng = np.random.default_rng(0)
    img = np.full((120, 200), 150.0)
    # tensile: wide, smooth, straight opening
    img[28:34, 20:180] = 30
    # shear: thin en-echelon pieces stepping up and down, debris alongside
    for k, c0 in enumerate(range(20, 180, 20)):
        r = 88 + (2 if k % 2 else -1)
        img[r, c0:c0 + 24] = 30
    for c in range(25, 180, 12):
        img[94 + rng.integers(0, 2), c:c + 2] = 30
    img = ndi.gaussian_filter(img, 0.6) + rng.normal(0, 3, img.shape)
    from semkit.analysis import analyse_image
    a = analyse_image(np.clip(img, 0, 255).astype(np.uint8), pixel_size_um=1.0,
                      stage="failure")
    lab = a.crack_labels
    t, types = classify_post(lab, image=a.smooth, skeleton=a.skeleton)
    a_t = ((types == 1) & (lab > 0))[20:40].sum() / (lab[20:40] > 0).sum()
    a_s = ((types == 2) & (lab > 0))[80:100].sum() / (lab[80:100] > 0).sum()
    assert a_t > 0.9 and a_s > 0.9, (a_t, a_s)
    tensile = t[t.type_post == "tensile"]
    assert np.exp(tensile["log_aperture"]).min() > 4.0 and tensile.type_post_ok.all()
    assert (t.p_tensile + t.p_shear + t.p_mixed).round(9).eq(1).all()
    np.testing.assert_allclose(t.confidence, t[["p_tensile", "p_shear", "p_mixed"]].max(axis=1))


@functools.lru_cache(maxsize=None)
def _post_sample(seed):
    """A post-test synthetic image analysed by the crack pipeline: (synth, analysis, truth)."""
    synth = pytest.importorskip("semkit.synth")
    from semkit.analysis import analyse_image
    s = synth.make_sem_image((384, 512), stage="post", n_cracks=12, seed=seed)
    a = analyse_image(s.image, pixel_size_um=s.pixel_size_um, stage="failure")
    code = np.zeros(len(s.cracks) + 1, int)
    code[s.cracks.crack_id] = [POST[x] for x in s.cracks.type_post]
    return s, a, code[s.crack_labels]


def test_classify_post_synthetic_accuracy_and_p():
    """Type accuracy by area on held-out semkit.synth images, and the issue-15 rule for P:
    within 15 % of the truth or flagged low_confidence, never a confident P off by more than
    2x; the typing's 10-90 % P band holds the true P in at least 4 of the 6 images."""
    good = tot = covered = 0
    for seed in HELD_OUT_SEEDS:
        s, a, truth = _post_sample(seed)
        lab = a.crack_labels
        th = a.thresholded
        table, types = classify_post(lab, image=a.smooth, skeleton=a.skeleton,
                                     background=th.background, crack_level=th.crack_level)
        sel = (truth > 0) & (lab > 0)
        good += (types[sel] == truth[sel]).sum()
        tot += sel.sum()
        assert set(table.type_post) <= {"tensile", "shear", "mixed"}
        assert ((table.confidence >= 1 / 3) & (table.confidence <= 1)).all()
        np.testing.assert_allclose(table[["frac_tensile", "frac_shear", "frac_mixed"]].sum(
            axis=1), 1.0, atol=1e-9)
        row = a.summary()
        p_true = (truth == 1).sum() / (truth == 2).sum()
        err = row["P"] / p_true - 1
        assert abs(err) <= P_MEDIAN_ERROR_MAX or row["P_status"] == "low_confidence", (
            seed, err, row["P_status"])
        assert row["P_status"] != "ok" or 0.5 <= row["P"] / p_true <= 2, (seed, err)
        covered += row["P_low"] <= p_true <= row["P_high"]
    assert good / tot >= POST_SYNTH_ACCURACY_MIN, good / tot
    assert covered >= 4, covered


def test_a_network_longer_than_any_trained_crack_is_typed_in_pieces():
    """A 1190-px straight opening (log length 7.1 against the trained 6.6) read as out of
    range and untrusted when typed whole; typed in pieces (``PIECE_PX``) it is a trusted
    tensile."""
    lab = np.zeros((40, 1200), np.int32)
    lab[18:24, 5:1195] = 1
    t, types = classify_post(lab)
    assert t.loc[0, "type_post"] == "tensile" and bool(t.loc[0, "type_post_ok"]), t.iloc[0]
    assert t.loc[0, "frac_tensile"] == pytest.approx(1.0)
    assert (types[lab > 0] == POST["tensile"]).all()


def test_p_of_a_dense_image_typed_in_pieces():
    """A 1024 x 768 semkit.synth post-test image with 30 cracks joined into networks (the
    speed benchmark's image 3): typed whole, its P read 60 against the true 3.5 (flagged);
    typed in pieces it reads within 25 %, and the truth lies in its P band. (The piece side was
    chosen on the benchmark's 20 post-test images, this one among them: a regression check,
    not an accuracy.)"""
    from semkit.analysis import analyse_image
    from semkit.synth import make_sem_image
    s = make_sem_image((768, 1024), stage="post", widths=(2.0, 8.0), gradient=2.5,
                       n_cracks=30, seed=1003)
    code = {"tensile": 1, "shear": 2}
    kind = np.zeros(s.crack_labels.max() + 1, np.int8)
    for cid, t in zip(s.cracks.crack_id, s.cracks.type_post):
        kind[cid] = code.get(t, 0)
    tp = kind[s.crack_labels]
    p_true = (tp == 1).sum() / (tp == 2).sum()
    row = analyse_image(s.image, pixel_size_um=s.pixel_size_um, stage="failure").summary()
    assert abs(row["P"] / p_true - 1) < 0.25, (row["P"], p_true)
    high = np.nan_to_num(row["P_high"], nan=np.inf)   # NaN: some draws leave no shear, open
    assert row["P_low"] <= p_true <= high, (row["P_low"], p_true, row["P_high"])


def _groups(seeds):
    """Crack groups of analysed held-out images with their true majority type."""
    out = []
    for seed in seeds:
        _, a, truth = _post_sample(seed)
        th = a.thresholded
        out.append(image_samples(a.crack_labels, truth, image=a.smooth, skeleton=a.skeleton,
                                 background=th.background, crack_level=th.crack_level))
    return out


def test_post_probabilities_are_calibrated():
    """The built-in model's confidence matches the observed accuracy on images it was not
    fitted or calibrated on (semkit.synth seeds 200-205: crack groups, weighted by area),
    overall and among the groups below and above 0.8; and the temperature fit undoes a
    model made 4x overconfident."""
    samples = _groups(HELD_OUT_SEEDS)
    D, y, area = _group_rows(samples, DEFAULT_POST_MODEL)
    P = type_probabilities(D, DEFAULT_POST_MODEL)
    conf, hit = P.max(axis=1), (P.argmax(axis=1) == y).astype(float)
    for sel in (conf > 0, conf < 0.8, conf >= 0.8):
        gap = np.average(conf[sel], weights=area[sel]) - np.average(hit[sel],
                                                                     weights=area[sel])
        assert sel.sum() >= 10 and abs(gap) <= CALIBRATION_GAP_MAX, (sel.sum(), gap)
    base = calibrate(dict(DEFAULT_POST_MODEL), samples)["temperature"]
    sharp = dict(DEFAULT_POST_MODEL, temperature=1.0,
                 coef=(4 * np.asarray(DEFAULT_POST_MODEL["coef"])).tolist(),
                 intercept=(4 * np.asarray(DEFAULT_POST_MODEL["intercept"])).tolist())
    before = type_probabilities(D, sharp)
    fitted = calibrate(dict(sharp), samples)
    assert fitted["temperature"] == pytest.approx(4 * base, rel=0.02)
    after = type_probabilities(D, fitted)
    nll = [-np.mean(np.log(q[np.arange(len(y)), y])) for q in (before, after)]
    assert nll[1] < nll[0], nll


def test_typed_areas_partial_volume_unbiased_for_thin_lines():
    img = np.full((60, 200), 160.0)
    img[20, 10:190] = 40      # 1-px line
    img[40:44, 10:190] = 40   # 4-px line
    blurred = ndi.gaussian_filter(img, 0.8)
    lab, _ = ndi.label(blurred < 130, structure=np.ones((3, 3)))
    a = typed_areas(blurred, lab, core=40.0).set_index("crack_id")
    thin = a.loc[lab[20, 100], "area_pv_px"]
    wide = a.loc[lab[42, 100], "area_pv_px"]
    assert thin == pytest.approx(180, rel=0.05) and wide == pytest.approx(720, rel=0.05)
    # a midpoint threshold loses the thin line's area (this is why P uses the PV area)
    assert ((blurred < 100) & (lab == lab[20, 100])).sum() < 0.6 * 180
    types = np.where(lab == lab[20, 100], 2, np.where(lab > 0, 1, 0))
    b = typed_areas(blurred, lab, types, core=40.0).set_index("crack_id")
    assert b.loc[lab[20, 100], "area_S_px"] == pytest.approx(thin)
    assert b.loc[lab[42, 100], "area_T_px"] == pytest.approx(wide)
    with pytest.raises(InputError):
        typed_areas(blurred, lab[:10])


def test_train_save_load_and_user_labels(tmp_path):
    samples = []
    for seed in (100, 101, 102):
        s, a, truth = _post_sample(seed)
        lab = a.crack_labels
        samples.append((lab, np.where(lab > 0, truth, 0), a.smooth))
    model = train_post(samples[:2], seed=0, calibration=samples[2:])
    assert model["version"] == 3 and model["features"] == list(STAGE2_NAMES)
    assert model["temperature"] > 0 and model["n_calibration"] > 0
    save_model(model, tmp_path / "m.json")
    back = load_model(tmp_path / "m.json")
    lab = samples[0][0]
    t1, i1 = classify_post(lab, model=model)
    t2, i2 = classify_post(lab, model=back)
    assert (i1 == i2).all() and t1.type_post.tolist() == t2.type_post.tolist()
    assert train_post(samples[:2], seed=0)["coef"] == train_post(samples[:2], seed=0)["coef"]
    (tmp_path / "bad.json").write_text('{"coef": [1, 2]}')
    with pytest.raises(InputError, match="bad.json"):
        load_model(tmp_path / "bad.json")
    old = dict(model, version=2)
    (tmp_path / "old.json").write_text(__import__("json").dumps(old))
    with pytest.raises(InputError, match="retrain"):
        load_model(tmp_path / "old.json")
    with pytest.raises(InputError, match="tensile and shear"):
        train_post([(lab, {1: "tensile"})])
    # user labels override the model, with certainty
    cracks = t1.assign(image="a.png")
    first = int(cracks.crack_id.iloc[0])
    labels_csv = tmp_path / "labels.csv"
    pd.DataFrame(dict(image=["a.png"], crack_id=[first], type=["mixed"])).to_csv(labels_csv)
    out = apply_labels(cracks, read_labels(labels_csv))
    row = out[out.crack_id == first].iloc[0]
    assert row.type_post == "mixed" and row.confidence == 1.0 and row.type_source == "user"
    assert row.frac_mixed == 1.0 and row.frac_tensile == 0.0 and row.p_mixed == 1.0
    assert row.type_post_ok and row.type_note == ""
    assert (out[out.crack_id != first].type_source == "model").all()
    pd.DataFrame(dict(image=["a"], crack_id=[1], type=["bogus"])).to_csv(tmp_path / "x.csv")
    with pytest.raises(InputError, match="bogus"):
        read_labels(tmp_path / "x.csv")
    assert DEFAULT_POST_MODEL["version"] == 3 and "seed" in DEFAULT_POST_MODEL
