"""Result writers and parameter files: atomic, strict JSON, round trips, figures drawn."""
import json
import math

import numpy as np
import pandas as pd
import pytest

from sim import InputError, Specimen
from sim.protocols import outputs, parameters


def _history(n=50):
    e = np.linspace(0, 3e-3, n)
    s = 60e3 * e * (1 - e / 6e-3)
    return pd.DataFrame({"step": np.arange(n) * 100, "time_s": np.arange(n) * 1e-6,
                         "axial_strain": e, "lateral_strain": -0.2 * e,
                         "volumetric_strain": 0.8 * e, "axial_stress_mpa": s,
                         "confining_stress_mpa": 0.0, "cracks_pb_tension": np.arange(n) // 5,
                         "cracks_pb_shear": 0, "cracks_sj_tension": 0, "cracks_sj_shear": 0,
                         "cracks_total": np.arange(n) // 5, "kinetic_energy_j": 0.0,
                         "strain_energy_j": 0.0})


def test_results_are_written_as_strict_json_and_csv(tmp_path):
    summary = {"test": "ucs", "ucs_mpa": np.float64(135.0), "P_sim": {"by_area": math.inf},
               "ci_mpa": float("nan"), "cracks": {"pb_tension": np.int64(3)}}
    paths = outputs.write_results(tmp_path / "r", summary=summary, history=_history(),
                                  cracks=pd.DataFrame({c: [] for c in outputs.CRACK_COLUMNS}))
    d = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert d["ucs_mpa"] == 135.0 and d["P_sim"]["by_area"] is None and d["ci_mpa"] is None
    assert d["cracks"]["pb_tension"] == 3
    h = pd.read_csv(paths["history.csv"])
    assert list(h.columns) == list(outputs.HISTORY_COLUMNS) and len(h) == 50
    assert list(pd.read_csv(paths["cracks.csv"]).columns) == list(outputs.CRACK_COLUMNS)
    assert not [p for p in (tmp_path / "r").iterdir() if p.name.startswith(".tmp-")]


def test_failed_write_leaves_old_file_and_no_temp(tmp_path):
    p = tmp_path / "summary.json"
    outputs.write_json_atomic(p, {"a": 1})
    with pytest.raises(TypeError):
        outputs.write_json_atomic(p, {"a": object()})
    assert json.loads(p.read_text()) == {"a": 1}
    assert [q.name for q in tmp_path.iterdir()] == ["summary.json"]


def test_figures_are_png(tmp_path):
    s = Specimen.lattice(nx=6, ny=6, radius=1e-3)
    cracks = pd.DataFrame({"x": [2e-3, 4e-3], "y": [2e-3, 5e-3], "kind": ["pb", "sj"],
                           "mode": ["tension", "shear"], "size_m": [2e-3, 2e-3],
                           "nx": [1.0, 0.0], "ny": [0.0, 1.0]})
    p1 = outputs.plot_history(_history(), tmp_path / "h.png", summary={"ucs_mpa": 90.0})
    p2 = outputs.plot_crack_map(s, cracks, tmp_path / "c.png", x=s.x + 1e-5, y=s.y, magnify=10)
    for p in (p1, p2):
        head = open(p, "rb").read(8)
        assert head == b"\x89PNG\r\n\x1a\n"


def test_parameters_round_trip_and_apply(tmp_path):
    p = parameters.thesis_parameters()
    path = tmp_path / "params.yaml"
    parameters.save_parameters(path, p, header="thesis Ch. 4")
    q = parameters.load_parameters(path)
    assert q["minerals"] == p["minerals"] and q["joint"] == p["joint"]
    assert path.read_text().startswith("# thesis Ch. 4")
    s = Specimen.lattice(nx=4, ny=4, radius=1e-3)
    t = parameters.apply_parameters(s, {"default": p["minerals"]["plagioclase"],
                                        "joint": p["joint"]})
    assert t.pb_ten[0] == 330e6 and t.kratio[0] == 1.5 and t.sj_kn[0] == 4e9
    assert s.pb_ten[0] == 1e100                      # input unchanged
    back = parameters.parameters_from_specimen(t)
    assert back["minerals"]["lattice"]["pb_coh"] == 300e6


def test_bad_parameter_files_are_named(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("minerals:\n  pyroxene: {pb_ten: lots}\n")
    with pytest.raises(InputError, match="pyroxene.pb_ten"):
        parameters.load_parameters(path)
    path.write_text("minerals:\n  pyroxene: {pb_tensile: 1.0}\n")
    with pytest.raises(InputError, match="unknown field 'pb_tensile'"):
        parameters.load_parameters(path)
    s = Specimen.lattice(nx=3, ny=3, radius=1e-3)
    with pytest.raises(InputError, match="match none"):
        parameters.apply_parameters(s, parameters.thesis_parameters())
    with pytest.raises(InputError, match="not found"):
        parameters.load_parameters(tmp_path / "none.yaml")
