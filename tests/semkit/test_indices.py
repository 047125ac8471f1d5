"""Tests of semkit.indices: P (Equ. 3-1), H (Equ. 4-1/4-2), MHI (Equ. 4-3); issue #3."""
import numpy as np
import pandas as pd
import pytest

from semkit.indices import (
    damage_ratio,
    heterogeneity_index,
    indices_from_table,
    mhi,
    split_range,
    table_with_ranges,
)

W = (0.5, 0.3, 0.2)
FREQ = {"pyroxene": (5, 89, 7), "plagioclase": (17, 68, 15), "biotite": (26, 63, 11)}
VOL = {"pyroxene": 50, "plagioclase": 30, "biotite": 20}
# Thesis Table 4-1 (SEM scale, um): fine / medium / coarse ranges
T41 = {"pyroxene": (9, 20, 140, 240), "plagioclase": (8, 20, 80, 200),
       "biotite": (8, 20, 80, 180)}
# Appendix A bins (model scale, as um so the table form applies; sizes 0.1..2.4 mm)
APPA = {"pyroxene": (100, 200, 1400, 2400), "plagioclase": (100, 200, 800, 1900),
        "biotite": (100, 200, 800, 2200)}
# Table 4-2 scenario ranges, mm
SCEN = {
    "S1": {"pyroxene": (0.1, 2.4), "plagioclase": (0.1, 1.9), "biotite": (0.1, 2.2)},
    "S2": {"pyroxene": (0.22, 1.24), "plagioclase": (0.16, 0.99), "biotite": (0.15, 0.80)},
    "S3": {"pyroxene": (0.35, 1.06), "plagioclase": (0.24, 0.71), "biotite": (0.21, 0.62)},
    "S4": {"pyroxene": (0.53, 0.88), "plagioclase": (0.35, 0.59), "biotite": (0.31, 0.52)},
}
N1_DOCUMENTED = {"S1": 2.69, "S2": 1.84, "S3": 1.34, "S4": 0.88}


def make_table(edges_by_mineral):
    rows = []
    for name, e in edges_by_mineral.items():
        for c, cls in enumerate(("fine", "medium", "coarse")):
            rows.append(dict(mineral=name, **{"class": cls}, d_min_um=e[c], d_max_um=e[c + 1],
                             frequency_pct=FREQ[name][c], volume_fraction_pct=VOL[name]))
    return pd.DataFrame(rows)


def scenario_table(s):
    rng = {k: (lo * 1000, hi * 1000) for k, (lo, hi) in SCEN[s].items()}
    return table_with_ranges(make_table(APPA), rng)


def test_h_reference_values():
    h, r_a = heterogeneity_index(W, (0.705, 0.473, 0.413))
    assert r_a == pytest.approx(0.5770, abs=5e-5)
    assert h == pytest.approx(0.4031, abs=5e-5)


@pytest.mark.parametrize("k", [1e-3, 0.75, 1.5, 10.0, 1234.5])
def test_h_and_mhi_scale_invariant(k):
    r = np.array([0.705, 0.473, 0.413])
    rc = np.array([[0.15, 0.8, 1.9], [0.15, 0.5, 1.35], [0.15, 0.5, 1.5]])
    h0, ra0 = heterogeneity_index(W, r)
    h1, ra1 = heterogeneity_index(W, k * r)
    assert h1 == pytest.approx(h0, rel=1e-12) and ra1 == pytest.approx(k * ra0, rel=1e-12)
    m0, _ = mhi(W, rc, frequencies=list(FREQ.values()))
    m1, _ = mhi(W, k * rc, frequencies=list(FREQ.values()))
    assert m1 == pytest.approx(m0, rel=1e-12)
    t = make_table(T41)
    t2 = t.assign(d_min_um=t.d_min_um * k, d_max_um=t.d_max_um * k)
    a, b = indices_from_table(t), indices_from_table(t2)
    assert b["MHI"] == pytest.approx(a["MHI"], rel=1e-12)
    assert b["H"] == pytest.approx(a["H"], rel=1e-12)
    assert b["R_a_um"] == pytest.approx(k * a["R_a_um"], rel=1e-12)


def test_mhi_unit_checks_from_reference():
    # Equ. 4-3 with R_a = 0.618 mm and Table 4-1 midpoints (x10 -> mm) gives 3.01
    mids = np.array([[(e[c] + e[c + 1]) / 200 for c in range(3)] for e in T41.values()])
    m, r_a = mhi(W, mids, r_a=0.618)
    assert r_a == 0.618 and m == pytest.approx(3.01, abs=0.005)
    # Appendix A bins, class midpoints, R_a = 0.56 mm gives 3.51
    mids_a = np.array([[(e[c] + e[c + 1]) / 2000 for c in range(3)] for e in APPA.values()])
    m, _ = mhi(W, mids_a, r_a=0.56)
    assert m == pytest.approx(3.51, abs=0.005)


def test_mhi_convention_n1_documented_values():
    got = {s: indices_from_table(scenario_table(s))["MHI"] for s in SCEN}
    for s, want in N1_DOCUMENTED.items():
        assert got[s] == pytest.approx(want, abs=0.01), (s, got)


def test_mhi_ordering_over_scenarios():
    for conv in ("N1", "geometric"):
        vals = [indices_from_table(scenario_table(s), convention=conv)["MHI"] for s in SCEN]
        assert vals[0] > vals[1] > vals[2] > vals[3], (conv, vals)


def test_indices_from_table_r_a_units_and_mineral_means():
    res = indices_from_table(make_table(T41))
    # pyroxene mean: (5*14.5 + 89*80 + 7*190) / 101
    assert res["mineral_mean_um"]["pyroxene"] == pytest.approx(
        (5 * 14.5 + 89 * 80 + 7 * 190) / 101)
    assert res["R_a_mm"] == pytest.approx(res["R_a_um"] / 1000)
    r_i = np.array(list(res["mineral_mean_um"].values()))
    assert res["R_a_um"] == pytest.approx(np.dot(W, r_i))


def test_measured_convention_uses_d_mean():
    t = make_table(T41)
    t["d_mean_um"] = 0.5 * (t.d_min_um + t.d_max_um)
    assert indices_from_table(t, convention="measured")["MHI"] == pytest.approx(
        indices_from_table(t)["MHI"], rel=1e-12)
    t.loc[0, "d_mean_um"] = 11.0
    assert indices_from_table(t, convention="measured")["MHI"] != pytest.approx(
        indices_from_table(t)["MHI"], rel=1e-6)


def test_split_range_maps_edges_linearly():
    e = split_range([100, 200, 1400, 2400], 530, 880)
    assert e[0] == 530 and e[-1] == 880
    assert e[1] == pytest.approx(530 + 100 * 350 / 2300)


def test_bad_tables_and_inputs_raise():
    t = make_table(T41)
    with pytest.raises(ValueError, match="missing column"):
        indices_from_table(t.drop(columns="frequency_pct"))
    with pytest.raises(ValueError, match="convention"):
        indices_from_table(t, convention="X")
    with pytest.raises(ValueError, match="coarse"):
        indices_from_table(t[t["class"] != "coarse"])
    with pytest.raises(ValueError, match="radii"):
        heterogeneity_index(W, (1.0, 0.0, 2.0))
    with pytest.raises(ValueError, match="weights"):
        heterogeneity_index((-1, 1, 1), (1.0, 1.0, 2.0))
    with pytest.raises(ValueError, match="class_means"):
        mhi(W, np.ones((3, 2)))


def test_damage_ratio_values_and_zero_shear():
    assert damage_ratio(6.0, 2.0) == pytest.approx(3.0)
    p = damage_ratio(np.array([1.0, 0.0, 5.0]), np.array([0.0, 0.0, 2.0]))
    assert np.isnan(p[0]) and np.isnan(p[1]) and p[2] == pytest.approx(2.5)
    assert np.isnan(damage_ratio(3.0, 0.0))
    with pytest.raises(ValueError, match="area_shear"):
        damage_ratio(1.0, -1.0)
