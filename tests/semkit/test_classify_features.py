"""Tests of the post-test typing parts: per-pixel layer/fill features, traces, model file."""
import json

import numpy as np
import pytest
from scipy import ndimage as ndi

from semkit.classify.features import FEATURE_NAMES, post_features
from semkit.classify.model import load_model
from semkit.classify.traces import trace_features, traces
from semkit.errors import InputError


def _image(draw):
    img = np.full((60, 160), 160.0)
    draw(img)
    return ndi.gaussian_filter(img, 0.6) + np.random.default_rng(0).normal(0, 2, img.shape)


def test_layer_and_fill_features_tell_a_filled_layered_pair_from_an_opening():
    lab = np.zeros((60, 160), np.int32)
    lab[25:32, 20:140] = 1  # the same 7-px mask for both

    def opening(img):
        img[25:32, 20:140] = 30

    def layered(img):  # two thin dark layers 5 px apart, lighter between (mask fills it)
        img[25:27, 20:140] = 30
        img[30:32, 20:140] = 30
        img[27:30, 20:140] = 120

    col = {n: i for i, n in enumerate(FEATURE_NAMES)}
    feats = {}
    for name, draw in (("opening", opening), ("layered", layered)):
        rr, cc, X = post_features(lab, image=_image(draw))
        mid = (cc > 40) & (cc < 120)
        feats[name] = X[mid].mean(axis=0)
    assert feats["layered"][col["layer_lift"]] > 0.2 > feats["opening"][col["layer_lift"]]
    assert feats["opening"][col["fill_9"]] > 0.85 > 0.75 > feats["layered"][col["fill_9"]]
    # without a grey image the grey-level features are not measured
    _, _, X = post_features(lab)
    assert np.isnan(X[:, col["dark_fill"]:]).all() and np.isfinite(X[:, :col["dark_fill"]]).all()


def test_traces_join_continuations_and_gaps_not_crossings():
    sk = np.zeros((80, 120), bool)
    sk[40, 5:115] = True          # a horizontal crack ...
    sk[5:75, 60] = True           # ... crossed by a vertical one
    sk[40, 50:53] = False         # and broken by a 3-px gap on the left
    coords, trace, short = traces(sk)
    long_tr = {int(trace[i]) for i in range(len(coords)) if not short[i]}
    rows = {int(trace[i]): set(np.unique(coords[i][:, 0])) for i in range(len(coords))
            if not short[i]}
    horiz = {t for t, r in rows.items() if r == {40}}
    assert len(long_tr) == 2 and len(horiz) == 1  # one horizontal, one vertical trace
    lab = ndi.binary_dilation(sk, iterations=1).astype(np.int32)
    lab, _ = ndi.label(lab > 0, structure=np.ones((3, 3)))
    rr, cc = np.nonzero(sk)
    pix, F, area = trace_features(lab, rr, cc, np.full(len(rr), 0.9), skeleton=sk)
    assert (pix[lab > 0] >= 0).all() and area.sum() == (lab > 0).sum()
    used = np.unique(pix[lab > 0])
    assert np.allclose(F[used, 0], 1.0)  # every skeleton px has p > 0.5: tensile share 1


def test_load_model_refuses_an_old_model(tmp_path):
    old = {"mean": [0] * 8, "scale": [1] * 8, "coef": [0] * 8, "intercept": 0,
           "mixed_share": 0.1}
    (tmp_path / "old.json").write_text(json.dumps(old))
    with pytest.raises(InputError, match="retrain"):
        load_model(tmp_path / "old.json")
