"""semkit.reject: the rules on measured evidence rows."""
import pandas as pd

from semkit.reject import RULES, reject_objects


def _row(**kw):
    base = dict(area_px=400.0, side_depth=0.9, encloses_px=0.0, hole_lift=float("nan"),
                elongation=10.0, width_px=3.0, slenderness=40.0, background_rel=1.0,
                density=0.05, neighbours=0.0, texture=1.0)
    return {**base, **kw}


def test_grain_rim_is_a_ring_not_a_network_with_a_small_loop():
    """A halo is a ring whose hole holds about its own area (micro-CT tuning slices: 0.8-1.0);
    a crack network that closes one small loop (a development image: 140 px of 7 267) is kept
    as a crack, however bright the loop's inside."""
    ev = pd.DataFrame([
        _row(area_px=377, side_depth=0.55, encloses_px=379, hole_lift=0.49, slenderness=40),
        _row(area_px=150, side_depth=0.39, encloses_px=154, hole_lift=0.66, slenderness=20),
        _row(area_px=7267, side_depth=0.77, encloses_px=140, hole_lift=0.81, slenderness=160,
             width_px=6.75),
    ], index=[1, 2, 3])
    why = reject_objects(ev)
    assert list(why) == ["grain_rim", "grain_rim", ""]


def test_an_open_crack_is_never_rejected_for_its_zone():
    ev = pd.DataFrame([_row(side_depth=0.9, background_rel=0.2, encloses_px=500,
                            hole_lift=0.9, slenderness=2.0, width_px=8.0)], index=[1])
    assert list(reject_objects(ev)) == [""]
    assert {name for name, _ in RULES} >= {"phase_rim", "grain_rim", "compact_dark",
                                           "dark_phase", "mottled"}


def test_an_image_whose_figures_rest_on_the_rules_is_flagged():
    """Development image 12 (``benchmarks/semkit_dev_family.py``): a major mineral at 86 grey
    is darker than 0.4 of the rock's contrast, so ``dark_phase`` removes the cracks in it
    (23 % of the dark area; the area reads -47 %). The row must not be marked valid."""
    from semkit.analysis import analyse_image
    from semkit.synth import make_sem_image
    s = make_sem_image(
        (768, 1024), stage="post", seed=12,
        minerals=[("m0", 100.93435153635961, 0.19269235188258926),
                  ("m1", 201.97193674146888, 0.34511476154827647),
                  ("m2", 86.0016029281838, 0.22482049782902208)],
        gradient=1.0, n_pores=15, noise_sigma=2.941663974418888,
        blur_sigma=0.9339025928519272, boundary_depth=0.23583599329837657, bit_depth=16,
        widths=(2.127437174298544, 4.179943696396233), mean_grain_px=84.5177518053529)
    a = analyse_image(s.image, pixel_size_um=s.pixel_size_um, classify=False)
    row = a.summary()
    assert not row["valid"] and "dark_phase" in row["valid_note"]
    assert row["crack_area_um2"] / s.pixel_size_um ** 2 < 0.75 * s.cracks["area_cov_px"].sum()


def test_an_image_whose_length_is_mostly_faint_lines_is_flagged():
    """Development image 20: grain boundaries darkened by a third of the grain grey are
    outlined as cracks (length +38 %); a quarter of the reported length lies less than 0.2 of
    the crack contrast below its surroundings, so the row must not be marked valid. The
    standard synthetic 1-px cracks (7-8 % of their length that faint) are not flagged so."""
    from _synth_cases import case

    from semkit.analysis import analyse_image
    from semkit.synth import make_sem_image
    s = make_sem_image(
        (768, 1024), stage="post", seed=20,
        minerals=[("m0", 221.22255037416485, 0.14980318553628452),
                  ("m1", 129.87637575889366, 0.13291188624051392)],
        gradient=1.0, n_pores=24, noise_sigma=3.8751548095782713,
        blur_sigma=0.6909760711470674, boundary_depth=0.32631852138325074, bit_depth=8,
        widths=(1.788613710282272, 6.47893099293689), mean_grain_px=111.17095517860974)
    row = analyse_image(s.image, pixel_size_um=s.pixel_size_um, classify=False).summary()
    assert row["crack_length_um"] / s.pixel_size_um > 1.25 * s.cracks["length_px"].sum()
    assert not row["valid"] and "faint lines" in row["valid_note"]
    thin = case(21, widths=(1.0, 1.0), n_cracks=12)
    assert "faint lines" not in analyse_image(thin.image).summary()["valid_note"]
