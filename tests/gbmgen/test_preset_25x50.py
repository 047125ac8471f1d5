"""The thesis-size preset ``thesis-ch4-calibrated-25x50`` is the 25 x 50 mm calibration's result."""
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from gbmgen.params import PRESETS, load_params
from sim.calibrate import DEFAULT_KNOBS, scale_parameters

CAL = Path(__file__).resolve().parents[2] / "benchmarks" / "ucs_results" / "calibration_25x50"
NAME = "thesis-ch4-calibrated-25x50"


def test_preset_is_the_accepted_point_of_the_25x50_calibration():
    """The preset holds the start file times the multipliers of the logged evaluation whose
    errors are all within the 3 % acceptance (6 significant digits)."""
    log = [json.loads(line) for line in (CAL / "calibration_log.jsonl").read_text().splitlines()]
    accepted = [e for e in log if max(abs(v) for v in e["errors"].values()) <= 0.03]
    assert len(accepted) == 1 and accepted[0]["iteration"] == 1
    m = accepted[0]["multipliers"]
    start = yaml.safe_load((CAL / "start_params.yaml").read_text())
    want = scale_parameters(start, DEFAULT_KNOBS, [m[k.name] for k in DEFAULT_KNOBS])
    p = load_params(NAME)
    assert p.name == NAME and p.source == f"preset {NAME}"
    assert set(p.minerals) == set(want["minerals"])
    for mineral, fields in want["minerals"].items():
        for k, v in fields.items():
            assert p.minerals[mineral][k] == pytest.approx(v, rel=1e-5), (mineral, k)
    for k, v in want["joint"].items():
        assert p.joint[k] == pytest.approx(v, rel=1e-5), k


def test_preset_is_chosen_by_name_and_differs_from_the_10x20_one():
    assert NAME in PRESETS
    small, big = load_params("thesis-ch4-calibrated"), load_params(NAME)
    ratio = {k: big.minerals["pyroxene"][k] / small.minerals["pyroxene"][k]
             for k in ("pb_emod", "pb_ten", "pb_coh")}
    # the 25 x 50 mm specimens needed softer bonds and stronger tension than the 10 x 20 mm ones
    assert ratio["pb_emod"] == pytest.approx(0.9668, rel=1e-3)
    assert ratio["pb_ten"] == pytest.approx(1.4783, rel=1e-3)
    assert ratio["pb_coh"] == pytest.approx(1.0420, rel=1e-3)
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
