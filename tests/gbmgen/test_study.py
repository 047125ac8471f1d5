"""Thesis studies: presets expand into the thesis's designs, the Ch. 6 geometry scales with the
specimen, findings read the right extremes, and gbmsim finds the subcommands gbmgen adds."""
import doctest

import pandas as pd
import pytest
import yaml

from gbmgen import study as study_module
from gbmgen import study_report
from gbmgen.study import STUDIES, study
from gbmgen.study_report import findings
from gbmgen.sweep_spec import expand_sweep
from sim.cli import build_parser
from sim.cli import main as gbmsim


@pytest.mark.parametrize("mod", [study_module, study_report])
def test_docstring_examples(mod):
    res = doctest.testmod(mod)
    assert res.failed == 0 and res.attempted > 0


@pytest.mark.parametrize("name, cases", [("thesis-ch4-scenarios", 5),
                                         ("thesis-ch4-grain-size", 6),
                                         ("thesis-ch5-shapes", 27), ("thesis-ch6-holes", 4),
                                         ("thesis-ch6-double-holes", 32)])
def test_presets_expand_to_cases_times_seeds(name, cases):
    runs = expand_sweep(study(name).make(3, (25.0, 50.0)))
    assert len(runs) == 3 * cases
    assert sorted({r.config["build"]["seed"] for r in runs}) == [1, 2, 3]


def test_ch5_ratios_span_the_thesis_ranges_and_hold_its_extremes():
    runs = expand_sweep(study("thesis-ch5-shapes").make(1, (10.0, 20.0)))
    by_shape = {}
    for r in runs:
        b = r.config["build"]
        by_shape.setdefault(b["shape"], []).append(b["slenderness"])
        assert b["grain_area_mm2"] == 1.78 and b["width_mm"] == 10
    assert [min(v) for v in by_shape.values()] == [0.47, 0.5, 0.67]
    assert [max(v) for v in by_shape.values()] == [2.13, 3, 1.43]
    assert 1 in by_shape["rectangle"] and 1 in by_shape["hexagon"]
    assert 1.14 in by_shape["shield"] and all(len(v) == 9 for v in by_shape.values())


def test_ch6_geometry_scales_with_the_specimen():
    full = expand_sweep(study("thesis-ch6-double-holes").make(1, (25.0, 50.0)))
    half = expand_sweep(study("thesis-ch6-double-holes").make(1, (12.5, 25.0)))
    bridges = sorted({r.config["defect"]["bridge_mm"] for r in full})
    assert bridges == [0.75, 1.5, 3, 6]                       # 0.5R .. 4R, R = 1.5 mm
    assert sorted({r.config["defect"]["bridge_mm"] for r in half}) == [b / 2 for b in bridges]
    assert {r.config["defect"]["hole_diameter_mm"] for r in half} == {1.5}
    assert {r.config["build"]["scale"] for r in half} == {0.5}          # grains 2 mm
    assert sorted({r.config["defect"]["bridge_angle_deg"] for r in full}) == [
        0, 30, 45, 60, 90, 120, 135, 150]
    holes = expand_sweep(study("thesis-ch6-holes").make(1, (25.0, 50.0)))
    assert {r.config["defect"]["hole"]: r.config["defect"]["hole_diameter_mm"]
            for r in holes} == {"intra": 3, "inter": 2, "trans3": 3, "trans4": 3}


def _frame(rows):
    return pd.DataFrame([{"status": "ok", **r} for r in rows])


def test_findings_read_the_extremes():
    rows = []
    for shape, best in (("rectangle", 1.0), ("hexagon", 2.13), ("shield", 1.14)):
        for s in (0.67, 1.0, 1.14, 2.13):
            for seed in (1, 2):
                ucs = 100.0 + (20.0 if (s == best) == (shape == "rectangle") else 0.0) + seed
                rows.append({"shape": shape, "slenderness": s, "seed": seed, "ucs_mpa": ucs})
    got = {r[0].split(":")[0]: r[3] for r in findings("thesis-ch5-shapes", _frame(rows))}
    assert got == {"rectangle": True, "hexagon": False, "shield": True}
    rows = [{"scenario": sc, "scale": sc_scale, "seed": 1, "ucs_mpa": u, "E_gpa": e}
            for sc, sc_scale, u, e in ((1, 1.0, 130, 60), (2, 1.0, 140, 70), (3, 1.0, 150, 65),
                                       (4, 1.0, 160, 80), (1, 1.5, 120, 61))]
    f = findings("thesis-ch4-scenarios", _frame(rows))
    assert [r[3] for r in f] == [True, False, False, True]
    one_seed = _frame([{"hole": h, "seed": 1, "hole_damage_damaged_area_mm2": a}
                       for h, a in (("intra", 3.0), ("inter", 1.0), ("trans3", 2.0))])
    f = findings("thesis-ch6-holes", one_seed)
    assert [r[2] for r in f] == ["intra (one seed: no seed spread, the order may be noise)",
                                 "inter (one seed: no seed spread, the order may be noise)"]
    assert [r[3] for r in f] == [True, True]


def test_gbmsim_finds_the_subcommands_of_gbmgen():
    sub = build_parser()._subparsers._group_actions[0].choices
    assert {"sweep", "study"} <= set(sub)


def test_print_sweep_is_a_sweep_file(tmp_path, capsys):
    assert gbmsim(["study", "thesis-ch6-holes", "--seeds", "2", "--size-mm", "10", "20",
                   "--print-sweep"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("# gbmsim study thesis-ch6-holes --seeds 2 --size-mm 10 20")
    runs = expand_sweep(yaml.safe_load(text))
    assert [r.run_id for r in runs] == [r.run_id for r in
                                        expand_sweep(STUDIES["thesis-ch6-holes"].make(2, (10,
                                                                                         20)))]
    assert gbmsim(["study", "thesis-ch6-holes", "--seeds", "0", "--out", str(tmp_path)]) == 2
    assert "--seeds 0" in capsys.readouterr().err


def test_findings_read_no_order_from_invalid_values():
    """A case whose E is flagged invalid in every run has no E: the finding says so and
    claims neither agreement nor disagreement (the order of missing numbers is no order)."""
    nan = float("nan")
    rows = [{"scenario": sc, "scale": scale, "seed": seed, "ucs_mpa": 100.0 + sc + seed,
             "E_gpa": nan if sc in (2, 3) or scale == 1.5 else 60.0 + sc}
            for sc, scale in ((1, 1.0), (2, 1.0), (3, 1.0), (4, 1.0), (1, 1.5))
            for seed in (1, 2)]
    f = {r[0]: r for r in findings("thesis-ch4-scenarios", _frame(rows))}
    e_order = f["E (GPa) rises as MHI falls (S1 < S2 < S3 < S4)"]
    assert e_order[2] == "no valid values for S2, S3" and e_order[3] is None
    assert f["grain size x1.5 raises E (GPa) (S1)"][2:] == ["no valid values", None]
    assert f["UCS (MPa) rises as MHI falls (S1 < S2 < S3 < S4)"][3] is True
    grain = [{"scenario": 1, "scale": s, "seed": 1, "ucs_mpa": 100.0 * s,
              "E_gpa": nan if s > 1 else 60.0} for s in (1.0, 1.25, 1.5)]
    g = {r[0]: r for r in findings("thesis-ch4-grain-size", _frame(grain))}
    assert g["S1: E (GPa) rises with the grain-size scale"][3] is None
    assert g["S1: UCS (MPa) rises with the grain-size scale"][3] is True


def test_study_end_to_end_on_tiny_specimens(tmp_path):
    """`gbmsim study` runs its five Ch. 4 cases for real (2.5 x 5 mm, ~320 particles), writes
    the table, the figure and the report, and says that such specimens are not
    representative; findings claim nothing from values flagged invalid."""
    out = tmp_path / "st"
    assert gbmsim(["study", "thesis-ch4-scenarios", "--seeds", "1", "--size-mm", "2.5", "5",
                   "--out", str(out), "--workers", "0", "--no-progress"]) == 0
    frame = pd.read_csv(out / "results.csv")
    assert len(frame) == 5 and (frame["status"] == "ok").all()
    assert sorted(zip(frame["scenario"], frame["scale"])) == [(1, 1.0), (1, 1.5), (2, 1.0),
                                                             (3, 1.0), (4, 1.0)]
    assert (frame["ucs_mpa"] > 0).all() and not frame["representative_ok"].any()
    md = (out / "report.md").read_text()
    assert "fail the representativeness rules" in md and "Findings beside the thesis" in md
    png = out / "report_files" / "thesis-ch4-scenarios.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "report.html").stat().st_size > png.stat().st_size
    rows = {r[0]: r for r in findings("thesis-ch4-scenarios", frame)}
    e_row = rows["E (GPa) rises as MHI falls (S1 < S2 < S3 < S4)"]
    by_case = frame[frame["scale"] == 1.0].groupby("scenario")["E_ok"].any()
    assert (e_row[3] is None) == (not by_case.all())
