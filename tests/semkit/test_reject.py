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
