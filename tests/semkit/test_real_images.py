"""Issue 15: the default analysis on real images it was not built from (skipped without
``shared/real_sem`` beside the repository or ``$ROCKKIT_SHARED``).

The scoring lives in ``benchmarks/real_images.py`` (one definition for the test and the
benchmark). The micro-CT figures are asserted on the 30 slices held out from choosing the
method's parameters (the first 10 by index were used).
"""
import importlib.util
import pathlib

import numpy as np
import pytest

from semkit import config

ROOT = pathlib.Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("real_images", ROOT / "benchmarks" /
                                               "real_images.py")
real = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(real)
SHARED = real.shared_dir()
pytestmark = pytest.mark.skipif(not (SHARED / "rock_microct_311H").is_dir(),
                                reason=f"real images not present ({SHARED}; set ROCKKIT_SHARED)")

#: measured 0.872 on the 30 held-out slices (0.868 before the ``faint_texture`` rule, 0.848
#: before the void grey was read below plateaus that the fracture's cores undercut)
MICROCT_F1_MEDIAN_MIN = 0.86
#: the issue's target on all 40 slices, reached: 0.867 (0.845 before the ``faint_texture``
#: rule)
MICROCT_F1_MEDIAN_MIN_ALL = 0.85
#: the issue's targets, reached: length within 15 % (median), no area above 2x the painting
MICROCT_LENGTH_TOL = 0.15
MICROCT_AREA_RATIO_MAX = 2.0
#: the issue's target, reached: < 10 % of a marked dark grain called crack
GRANITE_DARK_GRAIN_MAX = 0.10
#: measured: 3 of the 7 marked faint cracks found by default, 4 with the opt-in linking of
#: beaded cracks (semkit.link, ``--link``); the issue's target, 80 %, is not reached
GRANITE_FOUND_MIN = 3
GRANITE_FOUND_MIN_LINKED = 4


@pytest.fixture(scope="module")
def microct():
    return real.microct_scores(SHARED / "rock_microct_311H")


def test_microct_held_out_slices(microct):
    held = microct.iloc[10:]
    assert len(held) == 30
    assert held.f1.median() >= MICROCT_F1_MEDIAN_MIN, held.f1.median()
    assert abs(held.reported_length_ratio.median() - 1) <= MICROCT_LENGTH_TOL
    assert held.reported_area_ratio.max() <= MICROCT_AREA_RATIO_MAX
    assert microct.f1.median() >= MICROCT_F1_MEDIAN_MIN_ALL, microct.f1.median()


def test_microct_surround_is_never_a_crack(microct):
    """Before: the black surround became a crack in 26 of 40 slices, threshold_ok False on all
    40 and numbers written anyway (issue 15)."""
    assert (microct.roi == "surround").all()
    assert microct.outside_region_px.sum() == 0
    # every slice is flagged for its bright crack walls (phase-contrast fringes: 0.057-0.16
    # of the contrast above the rock); besides, at most three slices are flagged, each for a
    # reason the slice shows: noise (slice 176 while its void was read on the fracture's
    # plateaus: contrast 10.4 noise sigmas), faint lines (slices 0 and 5: a fifth or more of
    # their length in the dark rims of bright inclusions, F1 0.78 and 0.78, length 1.27x and
    # 1.32x the truth) or a darkest "mineral" lying largely in long narrow objects (slice 504's
    # wide fracture); two more for thin cracks, 30-31 % of their length under 2 px wide: slices
    # 163 and 176, whose reported length is 0.62x and 0.68x the truth (a lower bound, as said)
    assert microct.valid_note.str.contains("bright walls: ").all()
    notes = microct.valid_note.str.split("; ").map(
        lambda ns: "; ".join(n for n in ns if not n.startswith("bright walls: ")))
    flagged = microct.assign(valid_note=notes)[notes != ""]
    thin = flagged.valid_note.str.contains("thin cracks: ")
    assert len(flagged[~thin]) <= 3, flagged.image.tolist()
    assert (flagged.reported_length_ratio[thin] < 0.75).all(), flagged[thin].image.tolist()
    noisy = flagged.valid_note.str.startswith("noise:")
    assert (flagged.contrast_to_noise[noisy] < config.MIN_CONTRAST_TO_NOISE).all()
    assert (noisy | thin | flagged.valid_note.str.contains("long objects")
            | flagged.valid_note.str.startswith("faint lines:")).all()
    assert microct.reported_area_ratio.max() <= MICROCT_AREA_RATIO_MAX
    assert np.isfinite(microct.f1).all()


@pytest.mark.skipif(not (SHARED / "granite_griffiths2017").is_dir(), reason="no granite image")
def test_granite_dark_grains_and_faint_cracks():
    g = real.granite_scores(SHARED)
    assert set(g["dark_grain_crack_fraction"]) == {"biotite", "mottled_top_right",
                                                   "mottled_left"}
    for name, frac in g["dark_grain_crack_fraction"].items():
        assert frac < GRANITE_DARK_GRAIN_MAX, (name, frac)
    assert g["n_found"] >= GRANITE_FOUND_MIN, g["crack_coverage"]
    assert {"dark_phase", "mottled"} <= set(g["rejected_as"])
    linked = real.granite_scores(SHARED, link=True)
    for name, frac in linked["dark_grain_crack_fraction"].items():
        assert frac < GRANITE_DARK_GRAIN_MAX, (name, frac)
    assert linked["n_found"] >= GRANITE_FOUND_MIN_LINKED, linked["crack_coverage"]


#: measured agreement with the published method's crack maps (its output, not hand-made
#: truth): dolomite plane light 0.842, fluorescent sandstone (bright cracks) 0.665
OBARA_DOLOMITE_F1_MIN = 0.80
OBARA_SANDSTONE_F1_MIN = 0.60


@pytest.mark.skipif(not (SHARED / "obara_sandstone_dolomite_cracks").is_dir(),
                    reason="no Obara micrographs")
def test_optical_micrographs_agree_with_a_published_method_and_bright_cracks_need_the_flag():
    o = real.obara_scores(SHARED / "obara_sandstone_dolomite_cracks")
    assert o["dolomite_ppl"]["valid"]
    assert o["dolomite_ppl"]["f1"] >= OBARA_DOLOMITE_F1_MIN, o["dolomite_ppl"]
    assert o["sandstone_fluorescence"]["f1"] >= OBARA_SANDSTONE_F1_MIN, o
    # read as dark cracks, the fluorescent cracks are missed, and the image says so
    nope = o["sandstone_fluorescence_not_inverted"]
    assert nope["f1"] < 0.2 and not nope["valid"], nope


@pytest.mark.skipif(not (SHARED / "sandstone_thinsection_minerals").is_dir(),
                    reason="sandstone thin sections not present")
def test_a_dusty_plane_light_thin_section_is_not_a_valid_crack_measurement():
    """Sandstone in plane light (1600 x 1200 RGB): the dust in its feldspars and the grain
    outlines give ~1 000 "cracks", 2.6 % of the image; the row was marked valid. 19 % of the
    crack length lies in short, crowded objects (0.15-0.36 on the five images), so it is
    flagged; the cracked dolomite micrograph (0.015) is not."""
    from semkit.analysis import analyse_image
    from semkit.io import read_image
    a = analyse_image(read_image(SHARED / "sandstone_thinsection_minerals" / "ppl" /
                                 "image047_ppl.jpg"), pixel_size_source="default")
    row = a.summary()
    assert row["n_cracks"] > 500
    assert a._speckle_length_share() >= 0.15
    assert not row["valid"] and "specks: " in row["valid_note"], row["valid_note"]
    d = analyse_image(read_image(SHARED / "obara_sandstone_dolomite_cracks" /
                                 "dolomite_ppl_image12.png"), pixel_size_source="default")
    assert d._speckle_length_share() < config.SPECKLE_MAX_LENGTH_SHARE
