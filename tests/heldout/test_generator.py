"""The held-out generator (benchmarks/heldout): exact, deterministic truth, apart from semkit."""
import ast
import pathlib
import sys

import numpy as np

HELDOUT = pathlib.Path(__file__).resolve().parents[2] / "benchmarks" / "heldout"
sys.path.insert(0, str(HELDOUT))
import cracks as ck  # noqa: E402
import generator  # noqa: E402


def test_imports_nothing_of_semkit():
    for f in HELDOUT.glob("*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            assert not any(n.split(".")[0] in ("semkit", "gbmgen", "sim") for n in names), f


def test_same_seed_same_image_and_truth():
    a = generator.make_heldout_image((192, 256), seed=5)
    b = generator.make_heldout_image((192, 256), seed=5)
    c = generator.make_heldout_image((192, 256), seed=6)
    assert np.array_equal(a.image, b.image) and a.cracks.equals(b.cracks)
    assert not np.array_equal(a.image, c.image)


def test_truth_is_consistent():
    h = generator.make_heldout_image((256, 320), seed=11)
    assert len(h.cracks) >= 3
    assert np.isclose(h.area_px, h.coverage.sum(), rtol=1e-5)
    assert h.coverage.max() <= 1.0 + 1e-6
    for _, c in h.cracks.iterrows():
        assert (h.crack_labels == c.crack_id).sum() == c.area_mask_px
    assert np.array_equal(h.crack_mask, h.coverage >= 0.5)
    a_t, a_s = h.typed_area_px("tensile"), h.typed_area_px("shear")
    assert np.isnan(h.P) if a_s == 0 else np.isclose(h.P, a_t / a_s)


def test_band_coverage_and_midline_length_are_exact():
    """A straight band 4 px wide and 60 px long: area 240 px, mid-line 60 px."""
    p = np.stack([np.arange(61) + 10.0, np.full(61, 20.3)], 1)
    w1, w2 = np.full(61, -2.0), np.full(61, 2.0)
    c = ck.CoverageCanvas((40, 90))
    c.quad_strip(p, w1, w2)
    assert abs(c.coverage().sum() - 240) < 240 * 0.02
    assert np.isclose(ck.midline_length(p, w1, w2, np.ones(61, bool)), 60.0)


def test_matching_walls_for_tensile_closing_walls_for_shear():
    rng = np.random.default_rng(0)
    g = generator.draw_crack_settings(rng, "shear")
    g.update(aperture=5.0, tip_px=1.0, rough_amp=1.0, rough_wl=20.0, shear_open=1.0,
             slip=10.0)
    w1, w2 = ck.crack_walls(np.random.default_rng(1), "tensile", 200, g)
    ap = (w2 - w1)[20:-20]
    assert np.allclose(ap, 5.0)                      # tensile: the same aperture everywhere
    w1, w2 = ck.crack_walls(np.random.default_rng(1), "shear", 200, g)
    ap = w2 - w1
    assert ap.std() > 0.3 and (ap <= 0).any()        # shear: varies and closes (incomplete)
