"""semkit.segmenter: the trainable crack pixel classifier and its skops file (issue 15)."""
import json
import zipfile

import numpy as np
import pytest

from semkit.errors import InputError
from semkit.evaluate import centreline_scores
from semkit.segmenter import labels_from_mask, segmenter_features, train_segmenter
from semkit.segmenter_file import TRUSTED_TYPES, load_segmenter, save_segmenter
from semkit.synth import make_sem_image

FAST = dict(n_trees=6, samples_per_class=1500, max_depth=10, seed=3)


@pytest.fixture(scope="module")
def synth_pair():
    a = make_sem_image((160, 200), n_cracks=6, widths=(2.0, 6.0), seed=21)
    b = make_sem_image((160, 200), n_cracks=6, widths=(2.0, 6.0), seed=22)
    return a, b


@pytest.fixture(scope="module")
def trained(synth_pair):
    a, _ = synth_pair
    lab = np.where(a.crack_mask, 1, 2).astype(np.uint8)  # a full mask: every pixel labelled
    return train_segmenter([a.image], [lab], names=["a.png"], **FAST)


def test_finds_the_cracks_of_an_unseen_image(synth_pair, trained):
    _, b = synth_pair
    s = centreline_scores(trained.crack_mask(b.image), b.crack_mask)
    assert s["recall"] >= 0.9 and s["precision"] >= 0.9, s


def test_sparse_scribbles_are_enough(synth_pair):
    """A few labelled lines (scribbles) instead of a full mask."""
    a, b = synth_pair
    lab = np.zeros(a.image.shape, np.uint8)
    skel = np.zeros_like(a.crack_mask)
    from semkit.skeleton import skeletonize
    skel = skeletonize(a.crack_mask)
    lab[skel] = 1
    lab[::9, :] = np.where(a.crack_mask[::9, :] | (lab[::9, :] == 1), lab[::9, :], 2)
    assert (lab > 0).mean() < 0.15
    seg = train_segmenter([a.image], [lab], **FAST)
    s = centreline_scores(seg.crack_mask(b.image), b.crack_mask)
    assert s["f1"] >= 0.85, s


def test_features_in_bands_equal_the_whole_image(trained):
    rng = np.random.default_rng(0)
    g = rng.integers(0, 255, (70, 50)).astype(np.uint8)
    whole = segmenter_features(g, trained.features, tile_rows=1000)
    banded = segmenter_features(g, trained.features, tile_rows=16)
    assert whole.shape == (70, 50, trained.features["n_features"])
    np.testing.assert_allclose(banded, whole, atol=1e-5)


def test_same_seed_same_model(synth_pair, trained):
    a, b = synth_pair
    lab = np.where(a.crack_mask, 1, 2).astype(np.uint8)
    again = train_segmenter([a.image], [lab], names=["a.png"], **FAST)
    assert np.array_equal(again.crack_probability(b.image), trained.crack_probability(b.image))


def test_file_round_trip_records_features_classes_images_scores(tmp_path, synth_pair, trained):
    _, b = synth_pair
    path = tmp_path / "seg.skops"
    save_segmenter(trained, path)
    seg = load_segmenter(path)
    assert np.array_equal(seg.crack_probability(b.image), trained.crack_probability(b.image))
    assert seg.features["function"] == "skimage.feature.multiscale_basic_features"
    assert seg.features["sigma_min"] == 0.5 and seg.features["sigma_max"] == 8.0
    assert seg.classes == ("unlabelled", "crack", "not_crack")
    assert seg.training_images == ["a.png"]
    assert 0.9 < seg.scores["accuracy"] <= 1 and seg.scores["kind"].startswith("out-of-bag")
    c = seg.label_counts
    assert c["crack_sampled"] == min(c["crack_labelled"], 1500) and seg.seed == 3
    assert not list(tmp_path.glob(".*tmp"))  # written atomically


def _rewrite_schema(src, dst, edit):
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "schema.json":
                data = json.dumps(edit(json.loads(data))).encode()
            zout.writestr(item, data)


def test_tampered_or_unknown_types_are_refused(tmp_path, trained):
    import skops.io as sio
    good = tmp_path / "seg.skops"
    save_segmenter(trained, good)
    # a file whose schema was edited to build another class
    bad = tmp_path / "tampered.skops"

    def edit(schema):
        model = schema["content"]["model"]
        model["__module__"], model["__class__"] = "os", "system"
        return schema
    _rewrite_schema(good, bad, edit)
    with pytest.raises(InputError, match="untrusted type.*os.system"):
        load_segmenter(bad)
    # a well-formed skops file holding a type that skops itself trusts but semkit does not
    from sklearn.linear_model import LogisticRegression
    other = tmp_path / "other.skops"
    sio.dump({"format": "semkit.segmenter", "model": LogisticRegression()}, other)
    with pytest.raises(InputError, match="LogisticRegression"):
        load_segmenter(other)
    # not a zip at all; missing file
    junk = tmp_path / "junk.skops"
    junk.write_bytes(b"\x80\x04not a skops file")
    with pytest.raises(InputError, match="not a skops"):
        load_segmenter(junk)
    with pytest.raises(InputError, match="not found"):
        load_segmenter(tmp_path / "missing.skops")
    assert "sklearn.tree._tree.Tree" in TRUSTED_TYPES


def test_labels_from_painted_mask():
    g = np.full((40, 40), 200, np.uint8)
    g[:, 19:21] = 60                       # the dark crack, 2 px
    m = np.zeros((40, 40), bool)
    m[:, 16:24] = True                     # painted 8 px wide
    lab = labels_from_mask(g, m)
    assert (lab[:, 19:21] == 1).all()      # dark and painted
    assert (lab[:, 16:19] == 0).all() and (lab[:, 21:24] == 0).all()  # painted, not dark
    assert (lab[:, :13] == 2).all() and (lab[:, 27:] == 2).all()      # > 3 px from paint
    assert (lab[:, 13:16] == 0).all() and (lab[:, 24:27] == 0).all()  # near it: unlabelled


def test_bad_labels_are_refused(synth_pair):
    a, _ = synth_pair
    with pytest.raises(InputError, match="label values"):
        train_segmenter([a.image], [np.full(a.image.shape, 3, np.uint8)], **FAST)
    with pytest.raises(InputError, match="shape"):
        train_segmenter([a.image], [np.ones((5, 5), np.uint8)], **FAST)
    with pytest.raises(InputError, match="both classes"):
        train_segmenter([a.image], [np.ones(a.image.shape, np.uint8)], **FAST)


def test_cli_train_segmenter(tmp_path, synth_pair):
    from semkit.cli import main
    from semkit.io import write_image
    a, b = synth_pair
    (tmp_path / "img").mkdir()
    (tmp_path / "lab").mkdir()
    write_image(tmp_path / "img" / "a.png", a.image)
    write_image(tmp_path / "img" / "b.png", b.image)     # no label file: skipped
    write_image(tmp_path / "lab" / "a.png", (a.crack_mask * 255).astype(np.uint8))
    out = tmp_path / "seg.skops"
    rc = main(["train-segmenter", str(tmp_path / "img"), "--labels", str(tmp_path / "lab"),
               "--binary-masks", "--out", str(out), "--trees", "4", "--no-progress"])
    assert rc == 0 and load_segmenter(out).training_images == ["a.png"]
    # 0/255 masks without --binary-masks: one error line, exit 2, nothing written
    out2 = tmp_path / "seg2.skops"
    rc = main(["train-segmenter", str(tmp_path / "img"), "--labels", str(tmp_path / "lab"),
               "--out", str(out2), "--no-progress"])
    assert rc == 2 and not out2.exists()


def test_analyse_applies_the_segmenter_to_the_image_it_was_trained_on(synth_pair, trained):
    """With a black surround, ``analyse --segmenter`` decides on the unfilled image (as in
    training) and keeps only the sample region; a filled surround would shift the wide-scale
    features far into the sample and change the decision there."""
    from semkit.analysis import analyse_image
    _, b = synth_pair
    img = b.image.copy()
    yy, xx = np.mgrid[:img.shape[0], :img.shape[1]]
    outside = (yy - 80) ** 2 + (xx - 100) ** 2 > 75 ** 2
    img[outside] = 0
    a = analyse_image(img, segmenter=trained)
    assert 0.5 < a.region.fraction < 0.95
    want = trained.crack_mask(img) & a.region.mask
    np.testing.assert_array_equal(a.detection[0], want)
    filled = trained.crack_mask(a._work_image) & a.region.mask
    assert (filled != want).sum() > 0  # the test can tell the two apart


def test_threshold_override_moves_the_decision_and_is_reported(synth_pair, trained):
    """``segmenter_threshold`` replaces the model's decision level: the crack pixels are
    exactly those with P(crack) at or above it, fewer at a higher level, and images.csv
    reports the level used."""
    from semkit.analysis import analyse_image
    _, b = synth_pair
    p = trained.crack_probability(b.image)
    got = {}
    for t in (0.3, 0.5, 0.8):
        a = analyse_image(b.image, segmenter=trained, segmenter_threshold=t, roi="none")
        np.testing.assert_array_equal(a.detection[0], p >= t)
        assert a.summary()["threshold_value"] == t
        got[t] = int(a.detection[0].sum())
    assert got[0.3] > got[0.5] > got[0.8] > 0
    default = analyse_image(b.image, segmenter=trained, roi="none")
    assert default.summary()["threshold_value"] == trained.threshold
    np.testing.assert_array_equal(default.detection[0], p >= trained.threshold)


@pytest.mark.parametrize("kw, match", [
    (dict(segmenter_threshold=0.5), "needs a segmenter"),
    (dict(segmenter_threshold=1.0, segmenter="model"), r"in \(0, 1\)"),
    (dict(segmenter_threshold=0.0, segmenter="model"), r"in \(0, 1\)")])
def test_bad_segmenter_threshold_is_refused(trained, kw, match):
    from semkit.options import AnalysisOptions
    if kw.get("segmenter") == "model":
        kw = dict(kw, segmenter=trained)
    with pytest.raises(InputError, match=match):
        AnalysisOptions(**kw)


def test_cli_threshold_recorded_at_training_and_overridden_at_analysis(tmp_path, synth_pair):
    import pandas as pd

    from semkit.cli import main
    from semkit.io import write_image
    a, b = synth_pair
    for d in ("img", "lab", "new"):
        (tmp_path / d).mkdir()
    write_image(tmp_path / "img" / "a.png", a.image)
    write_image(tmp_path / "lab" / "a.png", (a.crack_mask * 255).astype(np.uint8))
    write_image(tmp_path / "new" / "b.png", b.image)
    out = tmp_path / "seg.skops"
    assert main(["train-segmenter", str(tmp_path / "img"), "--labels", str(tmp_path / "lab"),
                 "--binary-masks", "--out", str(out), "--trees", "4", "--threshold", "0.35",
                 "--no-progress"]) == 0
    assert load_segmenter(out).threshold == 0.35
    for extra, want in (([], 0.35), (["--segmenter-threshold", "0.7"], 0.7)):
        res = tmp_path / f"res{want}"
        assert main(["analyse", str(tmp_path / "new"), "--out", str(res), "--segmenter",
                     str(out), "--no-progress", *extra]) == 0
        assert pd.read_csv(res / "images.csv").threshold_value.tolist() == [want]
    # a level outside (0, 1): one error line, exit 2, no training done
    bad = tmp_path / "bad.skops"
    assert main(["train-segmenter", str(tmp_path / "img"), "--labels", str(tmp_path / "lab"),
                 "--binary-masks", "--out", str(bad), "--threshold", "1.5",
                 "--no-progress"]) == 2
    assert not bad.exists()
