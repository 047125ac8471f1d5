"""semkit.synth: seeded synthetic SEM images and their ground truth."""
import numpy as np
import pytest
from _synth_cases import case

from semkit.synth import make_sem_image


def test_same_seed_same_image_bit_for_bit():
    a = make_sem_image((96, 128), n_cracks=3, stage="post", gradient=2.0, n_pores=1, seed=5)
    b = make_sem_image((96, 128), n_cracks=3, stage="post", gradient=2.0, n_pores=1, seed=5)
    c = make_sem_image((96, 128), n_cracks=3, stage="post", gradient=2.0, n_pores=1, seed=6)
    assert np.array_equal(a.image, b.image) and np.array_equal(a.crack_labels, b.crack_labels)
    assert a.cracks.equals(b.cracks)
    assert not np.array_equal(a.image, c.image)


def test_truth_tables_are_consistent():
    s = case(11)
    assert s.image.dtype == np.uint8 and s.image.shape == (576, 768)
    assert s.crack_labels.dtype == np.int32 and s.grain_labels.dtype == np.int32
    assert s.mineral_labels.dtype == np.int32
    # labels <-> mask <-> per-crack areas
    assert np.array_equal(s.crack_mask, s.crack_labels > 0)
    assert s.cracks["area_px"].sum() == s.crack_mask.sum()
    counts = np.bincount(s.crack_labels.ravel(), minlength=len(s.cracks) + 1)[1:]
    assert np.array_equal(counts, s.cracks["area_px"].to_numpy())
    # grains: ids 1..G cover the image; the table matches the label image
    g = s.grains
    assert s.grain_labels.min() == 1 and s.grain_labels.max() == len(g)
    assert g["area_px"].sum() == s.image.size
    assert np.allclose(g["eq_diameter_px"], np.sqrt(4 * g["area_px"] / np.pi))
    # mineral labels follow the grains
    gm = dict(zip(g["grain_id"], g["mineral_idx"]))
    assert all(s.mineral_labels[s.grain_labels == k][0] == m for k, m in list(gm.items())[:20])
    assert set(g["mineral"]) <= set(s.mineral_names)


def test_crack_types_by_construction():
    s = case(12)
    c = s.cracks
    assert set(c["type_pre"]) == {"inter", "intra", "trans"}
    assert (c.loc[c.type_pre == "intra", "n_grains"] == 1).all()
    assert (c.loc[c.type_pre == "trans", "n_grains"] >= 2).all()
    # inter cracks run on grain boundaries: their centre pixels are (near) boundary pixels
    from scipy import ndimage as ndi
    near_boundary = ndi.binary_dilation(s.boundary_mask, iterations=2)
    for k in c.loc[c.type_pre == "inter", "crack_id"]:
        tr = s.traces[k - 1][0]
        ij = np.round(tr[:, 1::-1]).astype(int)
        assert near_boundary[ij[:, 0], ij[:, 1]].mean() > 0.9
    assert (c["type_post"] == "unknown").all()


def test_post_stage_morphologies():
    s = make_sem_image((400, 500), stage="post", n_cracks=24, seed=3)
    c = s.cracks
    assert set(c["type_post"]) == {"tensile", "shear", "mixed"}
    # tensile: one smooth trace per branch, no debris; shear: several narrow traces + debris
    t, sh = c[c.type_post == "tensile"], c[c.type_post == "shear"]
    assert (t["debris_px"] == 0).all() and (sh["debris_px"] > 0).all()
    assert (sh["n_traces"] >= 2).all()
    for k in sh["crack_id"]:
        widths = np.concatenate([tr[:, 2] for tr in s.traces[k - 1] if len(tr) > 1])
        assert widths.max() <= 2.5
    # tensile: the path is the drawn trace; shear: layers / overlapping steps draw more
    from semkit.synth import _polylen
    k = int(t["crack_id"].iloc[0])
    drawn = sum(_polylen(tr) for tr in s.traces[k - 1])
    assert np.isclose(t["trace_length_px"].iloc[0], drawn)
    assert np.isclose(t["length_px"].iloc[0], drawn, rtol=0.01)
    assert (sh["trace_length_px"] > 1.05 * sh["length_px"]).all()


def test_grey_levels_speckles_and_gradient():
    s = make_sem_image((300, 400), n_cracks=4, widths=(6, 8), gradient=2.5, n_pores=2, seed=9)
    assert np.isclose(s.illumination.max() / s.illumination.min(), 2.5, rtol=0.01)
    assert s.speckle_mask.any() and s.pore_mask.any()
    assert not (s.pore_mask & s.crack_mask).any()
    flat = s.image / s.illumination
    # cracks are darker than every mineral; boundaries are faint (not crack-dark)
    from scipy import ndimage as ndi
    core = ndi.binary_erosion(s.crack_mask, iterations=2)
    far = ~ndi.binary_dilation(s.crack_mask | s.speckle_mask | s.pore_mask, iterations=4)
    assert np.median(flat[core]) < 45
    assert np.median(flat[s.boundary_mask & far]) > 80


def test_bad_arguments():
    with pytest.raises(ValueError, match="stage"):
        make_sem_image((64, 64), stage="during")
    with pytest.raises(ValueError, match="bit_depth"):
        make_sem_image((64, 64), bit_depth=12)


def test_sixteen_bit():
    s = make_sem_image((64, 80), n_cracks=1, bit_depth=16, seed=1)
    assert s.image.dtype == np.uint16 and s.image.max() > 255


def test_crack_grey_sets_the_void_grey_and_nothing_else():
    """The cracks (and the pores and specks, voids too) take the grey; the rock keeps its own."""
    import cv2

    from semkit.synth import make_sem_image
    a = make_sem_image((192, 256), stage="post", seed=3)
    b = make_sem_image((192, 256), stage="post", seed=3, crack_grey=80.0)
    core = a.crack_labels > 0
    assert np.array_equal(a.crack_labels, b.crack_labels)
    assert b.image[core].astype(float).mean() > a.image[core].astype(float).mean() + 20
    rock = cv2.dilate(core.astype(np.uint8), np.ones((9, 9), np.uint8)) == 0
    diff = np.abs(a.image[rock].astype(float) - b.image[rock].astype(float))
    assert np.percentile(diff, 99) <= 1


def test_scene_elements_leave_the_rest_of_the_image_as_it_was():
    """Lenses draw from their own stream: the cracks and every pixel more than 4 px from a
    lens are those of the image made without them (a draw from the main stream would move
    the noise everywhere); the defaults are no satellites and no lenses."""
    import cv2
    kw = dict(stage="post", n_cracks=8, widths=(2.0, 5.0), seed=4)
    a = make_sem_image((256, 320), **kw)
    b = make_sem_image((256, 320), satellite=0.0, n_lenses=0, **kw)
    assert np.array_equal(a.image, b.image) and a.cracks.equals(b.cracks)
    assert not a.lens_mask.any()
    c = make_sem_image((256, 320), n_lenses=6, **kw)
    assert c.lens_mask.any() and not (c.lens_mask & c.crack_mask).any()
    assert np.array_equal(a.crack_labels, c.crack_labels) and a.cracks.equals(c.cracks)
    far = cv2.dilate(c.lens_mask.astype(np.uint8), np.ones((9, 9), np.uint8)) == 0
    assert np.array_equal(a.image[far], c.image[far])
    assert (a.image[~far] != c.image[~far]).mean() > 0.2  # the lenses are drawn


def test_satellites_are_thin_parallel_traces_that_belong_to_their_crack():
    kw = dict(stage="post", n_cracks=6, widths=(3.0, 6.0), type_mix=(("tensile", 1.0),),
              seed=9)
    a = make_sem_image((256, 320), **kw)
    c = make_sem_image((256, 320), satellite=1.0, **kw)
    ta, tc = a.cracks, c.cracks
    assert np.array_equal(ta["length_px"], tc["length_px"])  # the same paths (this seed)
    more = tc["n_traces"] > ta["n_traces"]
    assert more.sum() == 3 and (more == (ta["length_px"] >= 24)).all()  # every path >= 24 px
    extra_len = (tc["trace_length_px"] - ta["trace_length_px"])[more] / ta["length_px"][more]
    assert ((extra_len > 0.35) & (extra_len < 0.85)).all()  # 40-80 % of the path
    extra_area = (tc["area_cov_px"] - ta["area_cov_px"])[more]
    assert (extra_area > 0.7 * (tc["trace_length_px"] - ta["trace_length_px"])[more]).all()
    # apart from the crack: the satellite pixels are not the crack's wall pixels
    sat = c.crack_mask & ~a.crack_mask
    from scipy import ndimage as ndi
    d = ndi.distance_transform_edt(~a.crack_mask)[sat]
    assert np.median(d) >= 1.5 and d.max() <= 6.5


def test_lenses_are_crack_dark_and_no_cracks():
    """Lenses take the crack grey + 0-20 (cores of the cracks: 32, lenses 41 median here),
    far below the rock (151), and are not part of the crack truth."""
    import cv2
    from scipy import ndimage as ndi
    s = make_sem_image((256, 320), stage="post", n_cracks=4, n_lenses=8, seed=2)
    _, n = ndi.label(s.lens_mask)
    assert 5 <= n <= 8
    assert not (s.lens_mask & s.crack_mask).any()
    m = s.crack_mask.astype(np.uint8)
    core = cv2.distanceTransform(m, cv2.DIST_L2, 3) >= 1.5
    dark = s.crack_mask | s.lens_mask | s.pore_mask | s.speckle_mask
    rock = cv2.dilate(dark.astype(np.uint8), np.ones((9, 9), np.uint8)) == 0
    lens, crack = np.median(s.image[s.lens_mask]), np.median(s.image[core])
    assert crack - 5 <= lens <= crack + 25
    assert lens < np.percentile(s.image[rock], 1) - 30


def test_the_sample_set_truth_p_is_tensile_over_shear_area(tmp_path, monkeypatch):
    """``truth.csv``'s P is the damage ratio semkit reports (A_T / A_S of the tensile and shear
    cracks, mixed left out), not the crack area fraction, which has its own column."""
    import pandas as pd

    import semkit.synth as synth
    # a pre-test and a failure image of the set, small
    monkeypatch.setattr(synth, "SAMPLE_SET", synth.SAMPLE_SET[:1] + synth.SAMPLE_SET[-1:])
    truth = synth.write_sample_set(tmp_path, shape=(144, 192))
    cracks = pd.read_csv(tmp_path / "truth_cracks.csv")
    pre, post = truth.iloc[0], truth.iloc[1]
    assert pre.stage == "pre" and np.isnan(pre.P) and np.isnan(pre.area_T_px)
    c = cracks[cracks.image == post.image]
    a_t = c.loc[c.type_post == "tensile", "area_cov_px"].sum()
    a_s = c.loc[c.type_post == "shear", "area_cov_px"].sum()
    assert a_t > 0 and a_s > 0 and post.P == pytest.approx(a_t / a_s)
    assert post.crack_area_fraction == pytest.approx(post.crack_area_px / (144 * 192))
