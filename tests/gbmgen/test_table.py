"""GrainSizeTable: validation messages name row and field; scenario ranges; MHI targets."""
import numpy as np
import pandas as pd
import pytest

from gbmgen import config
from gbmgen.errors import InputError
from gbmgen.table import GrainSizeTable, read_table
from semkit.indices import indices_from_table


def _frame():
    return pd.DataFrame({
        "mineral": ["a", "a", "a", "b", "b", "b"],
        "class": ["fine", "medium", "coarse"] * 2,
        "d_min_um": [10.0, 20.0, 40.0, 10.0, 30.0, 60.0],
        "d_max_um": [20.0, 40.0, 80.0, 30.0, 60.0, 90.0],
        "frequency_pct": [20.0, 60.0, 20.0, 50.0, 25.0, 25.0],
        "volume_fraction_pct": [60.0] * 3 + [40.0] * 3,
    })


def test_reads_table_4_1(table41):
    assert table41.minerals == ("pyroxene", "plagioclase", "biotite")
    np.testing.assert_allclose(table41.volume_fractions, [0.5, 0.3, 0.2])
    # pyroxene frequencies 5/89/7 sum to 101 %: accepted and normalised
    np.testing.assert_allclose(table41.frequencies[0], np.array([5, 89, 7]) / 101)
    np.testing.assert_allclose(table41.range_um(), [[9, 240], [8, 200], [8, 180]])


@pytest.mark.parametrize("row, field, value, words", [
    (1, "d_min_um", -5.0, ["row 2", "line 3", "'d_min_um'", "-5"]),
    (0, "d_max_um", 5.0, ["row 1", "'d_max_um'"]),
    (4, "class", "huge", ["row 5", "'class'", "fine|medium|coarse"]),
    (2, "frequency_pct", "abc", ["row 3", "'frequency_pct'", "finite number"]),
    (3, "frequency_pct", -1.0, ["row 4", "'frequency_pct'", ">= 0"]),
])
def test_bad_field_names_row_and_field(row, field, value, words):
    df = _frame()
    df[field] = df[field].astype(object)
    df.loc[row, field] = value
    with pytest.raises(InputError) as e:
        GrainSizeTable.from_frame(df, source="grains.csv")
    msg = str(e.value)
    assert msg.startswith("grains.csv")
    for w in words:
        assert w in msg


def test_overlapping_classes_named():
    df = _frame()
    df.loc[1, "d_min_um"] = 15.0  # a/medium starts below a/fine's d_max 20
    with pytest.raises(InputError, match=r"row 2 .*'d_min_um' = 15 of 'a' medium overlaps"):
        GrainSizeTable.from_frame(df, source="grains.csv")


def test_frequency_sum():
    df = _frame()
    df.loc[0, "frequency_pct"] = 30.0  # a sums to 110 %
    with pytest.raises(InputError, match=r"'frequency_pct' of 'a' sums to 110 %"):
        GrainSizeTable.from_frame(df)
    df.loc[0, "frequency_pct"] = 21.5  # 101.5 % is within the tolerance
    assert GrainSizeTable.from_frame(df).frequencies[0].sum() == pytest.approx(1.0)


def test_volume_fraction_sum_and_consistency():
    df = _frame()
    df["volume_fraction_pct"] = [60.0] * 3 + [30.0] * 3
    with pytest.raises(InputError, match=r"'volume_fraction_pct' sums to 90 %"):
        GrainSizeTable.from_frame(df)
    df["volume_fraction_pct"] = [60.0, 60.0, 50.0] + [40.0] * 3
    with pytest.raises(InputError, match=r"row 3 .*differs"):
        GrainSizeTable.from_frame(df)


def test_missing_class_and_column(tmp_path):
    df = _frame().drop(index=2)
    with pytest.raises(InputError, match=r"'a' has 0 'coarse' rows"):
        GrainSizeTable.from_frame(df)
    p = tmp_path / "g.csv"
    _frame().drop(columns=["frequency_pct"]).to_csv(p, index=False)
    with pytest.raises(InputError, match="missing column.*frequency_pct"):
        read_table(p)
    with pytest.raises(InputError, match="file not found"):
        read_table(tmp_path / "nope.csv")


def test_scenario_ranges_hand_computed():
    t = GrainSizeTable.from_frame(_frame())
    np.testing.assert_allclose(t.scenario_ranges_um(1), [[10, 80], [10, 90]])
    # mineral a: CDF 0.2 at 20; q=0.1 -> 10 + 0.5*10 = 15; q=0.9 -> 40 + 0.5*40 = 60
    # mineral b: q=0.1 -> 10 + 0.2*20 = 14; q=0.9 -> 60 + 0.6*30 = 78
    np.testing.assert_allclose(t.scenario_ranges_um(2), [[15, 60], [14, 78]])
    mean = np.array([0.2 * 15 + 0.6 * 30 + 0.2 * 60, 0.5 * 20 + 0.25 * 45 + 0.25 * 75])
    np.testing.assert_allclose(t.scenario_ranges_um(3), np.c_[0.5 * mean, 1.5 * mean])
    np.testing.assert_allclose(t.scenario_ranges_um(4), np.c_[0.75 * mean, 1.25 * mean])
    s = t.scenario(4, scale=10.0)
    np.testing.assert_allclose(s.range_um(), 10 * np.c_[0.75 * mean, 1.25 * mean])
    # class edges mapped linearly (N1 split): a fine/medium edge 20 sits at 1/7 of 10..80
    lo, hi = 7.5 * mean[0], 12.5 * mean[0]
    assert s.hi_um[0, 0] == pytest.approx(lo + (hi - lo) / 7)
    with pytest.raises(InputError, match="scenario"):
        t.scenario_ranges_um(5)


def test_table_4_1_model_scale_s1_and_mhi_order(table41):
    s1 = table41.scenario(1, scale=config.MODEL_SCALE)
    np.testing.assert_allclose(s1.range_um() / 1000, [[0.09, 2.4], [0.08, 2.0], [0.08, 1.8]])
    mhi = [indices_from_table(table41.scenario(k, scale=10).to_frame())["MHI"]
           for k in (1, 2, 3, 4)]
    assert mhi[0] > mhi[1] > mhi[2] > mhi[3]
    np.testing.assert_allclose(mhi, [2.63, 1.87, 1.31, 0.86], atol=0.01)
    # size scaling leaves the target MHI unchanged
    assert indices_from_table(table41.scenario(1, scale=15).to_frame())["MHI"] == \
        pytest.approx(mhi[0], rel=1e-12)


def test_shipped_csv_equals_packaged_yaml(table41):
    from gbmgen.table import example_table
    y = example_table("table-4-1")
    assert y.minerals == table41.minerals
    for k in ("lo_um", "hi_um", "frequencies", "volume_fractions"):
        np.testing.assert_array_equal(getattr(y, k), getattr(table41, k))
    with pytest.raises(InputError, match="unknown example"):
        example_table("table-9")


def test_roundtrip_frame(table41):
    again = GrainSizeTable.from_frame(table41.to_frame())
    np.testing.assert_allclose(again.lo_um, table41.lo_um)
    np.testing.assert_allclose(again.frequencies, table41.frequencies)


def test_explicit_ranges(table41):
    r = table41.with_ranges({"pyroxene": (220, 1240), "plagioclase": (160, 990),
                             "biotite": (150, 800)})
    np.testing.assert_allclose(r.range_um(), [[220, 1240], [160, 990], [150, 800]])
    np.testing.assert_allclose(r.frequencies, table41.frequencies)
    with pytest.raises(InputError, match="no range for mineral"):
        table41.with_ranges({"pyroxene": (1, 2)})
    with pytest.raises(InputError, match="0 < d_min < d_max"):
        table41.with_ranges({"pyroxene": (2, 1), "plagioclase": (1, 2), "biotite": (1, 2)})
