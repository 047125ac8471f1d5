"""The thesis-size preset ``thesis-ch4-calibrated-25x50`` is the 25 x 50 mm calibration's result."""
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from gbmgen.params import PRESETS, load_params
from sim.calibrate import DEFAULT_KNOBS, correction_step, scale_parameters

CAL = Path(__file__).resolve().parents[2] / "benchmarks" / "ucs_results" / "calibration_25x50"
NAME = "thesis-ch4-calibrated-25x50"


def _log(path):
    return [json.loads(line) for line in path.read_text().splitlines()]


def _accepted(log):
    """The one search evaluation whose errors are all within the 3 % acceptance."""
    ok = [e for e in log if e["phase"] == "search"
          and max(abs(v) for v in e["errors"].values()) <= 0.03]
    assert len(ok) == 1 and ok[0]["iteration"] == 1
    return ok[0]["multipliers"]


def _scaled(start, m):
    return scale_parameters(start, DEFAULT_KNOBS, [m[k.name] for k in DEFAULT_KNOBS])


def _assert_same(p, want):
    assert set(p["minerals"]) == set(want["minerals"])
    for mineral, fields in want["minerals"].items():
        for k, v in fields.items():
            assert p["minerals"][mineral][k] == pytest.approx(v, rel=1e-5), (mineral, k)
    for k, v in want["joint"].items():
        assert p["joint"][k] == pytest.approx(v, rel=1e-5), k


def test_preset_is_the_accepted_point_of_the_25x50_calibrations():
    """The preset is the start file times the multipliers of the three logged steps (6
    significant digits at each stage): a search on seed 1, a search on the mean of seeds 1-3
    starting where the first stopped, one correction step on the pooled mean of seeds 1-9
    (the second search's seed rows and the held-out seeds 4-9) at that point, and one more on
    the pooled mean of seeds 4-18."""
    first = _scaled(yaml.safe_load((CAL / "start_params.yaml").read_text()),
                    _accepted(_log(CAL / "calibration_log.jsonl")))
    start2 = yaml.safe_load((CAL / "mean_search" / "start_params.yaml").read_text())
    _assert_same(start2, first)
    log2 = _log(CAL / "mean_search" / "calibration_log.jsonl")
    second = _scaled(start2, _accepted(log2))
    # the accepted point is the seed mean's: three seed rows at the same multipliers
    seeds = [e for e in log2 if e["phase"] == "seed"]
    assert len(seeds) == 3 and all(e["multipliers"] == _accepted(log2) for e in seeds)
    # third step: the pooled responses are those of the log and of the held-out file, and
    # the multipliers are the calibration's correction step on their mean
    pooled = CAL / "pooled_correction"
    start3 = yaml.safe_load((pooled / "start_params.yaml").read_text())
    _assert_same(start3, second)
    corr = json.loads((pooled / "correction.json").read_text())
    held = json.loads((CAL / "mean_search" / "held_out.json").read_text())["held_out"]
    want = ([[e["responses"][k] for k in ("E", "UCS", "sigma_t")] for e in seeds]
            + [[h["E_gpa"] * 1e9, h["ucs_mpa"] * 1e6, h["tensile_mpa"] * 1e6] for h in held])
    got = [[r[k] for k in ("E", "UCS", "sigma_t")] for r in corr["responses"]]
    np.testing.assert_allclose(got, want, rtol=1e-12)
    step = correction_step(corr["responses"])
    assert step == pytest.approx(corr["multipliers"], rel=1e-12)
    assert step["tensile"] == pytest.approx(0.946139, rel=1e-6)
    third = _scaled(start3, step)
    # fourth step: the pooled responses are the held-out seeds 10-18 at the third point and
    # seeds 4-9 mapped from the second point by the paired tension ratio (sigma_t) and the
    # third step's prediction (E, UCS)
    pooled2 = CAL / "pooled_correction_2"
    start4 = yaml.safe_load((pooled2 / "start_params.yaml").read_text())
    _assert_same(start4, third)
    corr2 = json.loads((pooled2 / "correction.json").read_text())
    held3 = json.loads((pooled / "held_out.json").read_text())["held_out"]
    paired = json.loads((pooled / "paired_tension.json").read_text())
    ratio = {"E": 65e9 / corr["mean"]["E"], "UCS": 135e6 / corr["mean"]["UCS"],
             "sigma_t": paired["ratio_mean"]}
    want = ([[h["E_gpa"] * 1e9, h["ucs_mpa"] * 1e6, h["tensile_mpa"] * 1e6] for h in held3]
            + [[h["E_gpa"] * 1e9 * ratio["E"], h["ucs_mpa"] * 1e6 * ratio["UCS"],
                h["tensile_mpa"] * 1e6 * ratio["sigma_t"]] for h in held])
    got = [[r[k] for k in ("E", "UCS", "sigma_t")] for r in corr2["responses"]]
    np.testing.assert_allclose(got, want, rtol=1e-5)  # ratios written to 6 digits
    step2 = correction_step(corr2["responses"])
    assert step2 == pytest.approx(corr2["multipliers"], rel=1e-12)
    assert step2["tensile"] == pytest.approx(0.939721, rel=1e-6)
    p = load_params(NAME)
    assert p.name == NAME and p.source == f"preset {NAME}"
    _assert_same({"minerals": p.minerals, "joint": p.joint}, _scaled(start4, step2))


def test_preset_is_chosen_by_name_and_differs_from_the_10x20_one():
    assert NAME in PRESETS
    small, big = load_params("thesis-ch4-calibrated"), load_params(NAME)
    ratio = {k: big.minerals["pyroxene"][k] / small.minerals["pyroxene"][k]
             for k in ("pb_emod", "pb_ten", "pb_coh")}
    # the 25 x 50 mm specimens needed stronger tension than the 10 x 20 mm ones, about the
    # same moduli and cohesions (products of the four steps' multipliers)
    assert ratio["pb_emod"] == pytest.approx(0.9668 * 1.02956 * 0.994907 * 0.991945, rel=1e-3)
    assert ratio["pb_ten"] == pytest.approx(1.4783 * 0.940017 * 0.946139 * 0.939721, rel=1e-3)
    assert ratio["pb_coh"] == pytest.approx(1.0420 * 0.960495 * 1.04 * 1.0672, rel=1e-3)
    a = big.joint_arrays()                     # numeric joint stiffness: no radius needed
    assert np.isclose(a["sj_ks"][0], a["sj_kn"][0] / 2)


def test_build_accepts_the_preset_name():
    from gbmgen.build import build_specimen
    from gbmgen.table import example_table
    spec, _ = build_specimen(example_table("table-4-1"), width_mm=2.0, height_mm=4.0,
                             scenario=1, seed=1, params=NAME)
    p = load_params(NAME)
    assert spec.meta["params"]["name"] == NAME
    # per-mineral tables in the table's order: pyroxene, plagioclase, biotite
    np.testing.assert_allclose(spec.pb_emod, [p.minerals[m]["pb_emod"] for m in
                                              ("pyroxene", "plagioclase", "biotite")])
    np.testing.assert_allclose(spec.pb_ten, [p.minerals[m]["pb_ten"] for m in
                                             ("pyroxene", "plagioclase", "biotite")])
