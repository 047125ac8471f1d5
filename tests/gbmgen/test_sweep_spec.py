"""Sweep files: expansion into runs, run identity (normalised configuration), bad input."""
import doctest

import pytest

from gbmgen import sweep_spec
from gbmgen.errors import InputError
from gbmgen.sweep_spec import expand_sweep, load_sweep


def test_docstring_examples():
    res = doctest.testmod(sweep_spec)
    assert res.failed == 0 and res.attempted > 0


BASE = {"fixed": {"table": "table-4-1", "width_mm": 3, "height_mm": 6, "max_strain": 0.001},
        "grid": {"scenario": [1, 4], "seed": [1, 2]}}


def test_grid_times_cases_in_sweep_order():
    runs = expand_sweep({**BASE, "cases": [{"test": "ucs"}, {"test": "brazilian"}]})
    assert len(runs) == 8 and len({r.run_id for r in runs}) == 8
    assert [(r.config["test"], r.config["build"]["scenario"], r.config["build"]["seed"])
            for r in runs[:4]] == [("ucs", 1, 1), ("ucs", 1, 2), ("ucs", 4, 1), ("ucs", 4, 2)]
    assert runs[4].config["test"] == "brazilian"
    assert runs[0].given == {"table": "table-4-1", "width_mm": 3, "height_mm": 6,
                             "max_strain": 0.001, "test": "ucs", "scenario": 1, "seed": 1}


def test_identity_is_the_normalised_configuration():
    """Defaults written out, 5 vs 5.0 and key order do not change a run; any value does."""
    a = expand_sweep({"fixed": {"table": "table-4-1", "width_mm": 5}})[0]
    b = expand_sweep({"fixed": {"width_mm": 5.0, "table": "table-4-1", "scenario": 1,
                                "test": "ucs", "post_peak": 0.8, "hole": "none"}})[0]
    c = expand_sweep({"fixed": {"table": "table-4-1", "width_mm": 5, "post_peak": 0.7}})[0]
    assert a.run_id == b.run_id != c.run_id
    assert a.config["build"]["height_mm"] == 50 and a.config["test_options"]["damping"] == 0.7
    assert a.config["version"]


def test_table_file_identity_is_its_content(tmp_path):
    from gbmgen.table import example_table
    csv = example_table("table-4-1").to_frame().to_csv(index=False)
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "grains.csv").write_text(csv)
    (tmp_path / "b" / "other.csv").write_text(csv)
    ra = expand_sweep({"fixed": {"table": "a/grains.csv"}}, base=tmp_path)[0]
    rb = expand_sweep({"fixed": {"table": "b/other.csv"}}, base=tmp_path)[0]
    assert ra.config["inputs"]["table"]["sha256"] == rb.config["inputs"]["table"]["sha256"]
    (tmp_path / "b" / "other.csv").write_text(csv.replace("50", "51", 1))
    rc = expand_sweep({"fixed": {"table": "b/other.csv"}}, base=tmp_path)[0]
    assert rc.run_id != ra.run_id
    assert ra.payload()["files"]["table"] == csv      # the worker gets the text, not a path


@pytest.mark.parametrize("doc, words", [
    ({"fixed": {"table": "table-4-1", "colour": 1}}, ["unknown option 'colour'"]),
    ({"fixed": {"table": "table-4-1", "out": "x"}}, ["'out'", "set by the sweep"]),
    ({"fixed": {"table": "table-4-1"}, "grid": {"seed": 3}}, ["grid.seed", "list"]),
    ({"fixed": {"table": "table-4-1", "seed": 1}, "grid": {"seed": [1]}}, ["grid.seed",
                                                                          "also given"]),
    ({"fixed": {"table": "table-4-1", "test": "shear"}}, ["unknown test 'shear'"]),
    ({"fixed": {"table": "table-4-1", "strain_rate": -1}}, ["strain_rate"]),
    ({"fixed": {"width_mm": 3}}, ["'table'", "'shape'"]),
    ({"fixed": {"table": "nofile.csv"}}, ["nofile.csv"]),
    ({"fixed": {"table": "table-4-1", "hole": "square"}}, ["hole = 'square'"]),
    ({"grids": {}}, ["unknown key 'grids'"]),
])
def test_bad_sweeps_name_the_field(doc, words):
    with pytest.raises(InputError) as exc:
        expand_sweep(doc, where="s.yaml")
    msg = str(exc.value)
    assert msg.startswith("s.yaml") and all(w in msg for w in words), msg


def test_load_sweep_names_the_file(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text("fixed: [1, 2")
    with pytest.raises(InputError, match="s.yaml: not valid YAML"):
        load_sweep(p)
    with pytest.raises(InputError, match="cannot read"):
        load_sweep(tmp_path / "none.yaml")
