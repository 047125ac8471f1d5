"""gbmgen CLI: build / info / plot / export; bad input -> exit 2 and one line naming the field."""
import json

import numpy as np

from gbmgen.cli import main
from sim.specimen import Specimen


def test_build_info_plot_export(tmp_path, capsys):
    out = tmp_path / "s.npz"
    rc = main(["build", "--table", "table-4-1", "--scenario", "2", "--width-mm", "5",
               "--height-mm", "10", "--seed", "3", "--out", str(out), "--json"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["grains"] > 20 and summary["smooth_joints"] > 0
    assert set(summary["timing_s"]) >= {"seeds", "tessellation", "particles", "bonds"}
    s = Specimen.load(out)
    assert s.meta["scenario"] == 2 and s.meta["seed"] == 3
    assert main(["info", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["particles"] == s.n_particles and info["meta"]["scenario"] == 2
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "pyroxene" in text and "MHI target" in text
    assert main(["plot", str(out)]) == 0
    assert (tmp_path / "s.png").stat().st_size > 10_000
    assert main(["export", str(out), "--geom", str(tmp_path / "s.geom"),
                 "--vtk", str(tmp_path / "v")]) == 0
    assert (tmp_path / "s.geom").exists() and (tmp_path / "v_grains.vtk").exists()


def test_config_file_and_controlled(tmp_path, capsys):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("shape: rectangle\nslenderness: 2.0\nwidth-mm: 5\nheight_mm: 10\nseed: 1\n")
    out = tmp_path / "r.npz"
    assert main(["build", "--config", str(cfg), "--out", str(out), "--json"]) == 0
    s = Specimen.load(out)
    assert s.meta["grains"]["shape"] == "rectangle"
    assert np.all(np.diff(s.grain_offsets) <= 4)


def test_bad_table_exit_2(tmp_path, capsys):
    bad = tmp_path / "g.csv"
    bad.write_text("mineral,class,d_min_um,d_max_um,frequency_pct,volume_fraction_pct\n"
                   "a,fine,-1,2,100,100\na,medium,2,3,0,100\na,coarse,3,4,0,100\n")
    rc = main(["build", "--table", str(bad), "--out", str(tmp_path / "x.npz")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert "row 1" in err[0] and "'d_min_um'" in err[0] and str(bad) in err[0]
    assert not (tmp_path / "x.npz").exists()
    assert main(["info", str(tmp_path / "missing.npz")]) == 2


def test_build_with_thesis_ranges(tmp_path, capsys):
    out = tmp_path / "r.npz"
    rc = main(["build", "--table", "table-4-1", "--ranges-mm",
               "pyroxene:0.22:1.24,plagioclase:0.16:0.99,biotite:0.15:0.80",
               "--width-mm", "5", "--height-mm", "10", "--seed", "4", "--out", str(out),
               "--json"])
    assert rc == 0
    s = Specimen.load(out)
    np.testing.assert_allclose(s.meta["grains"]["scenario_ranges_mm"]["plagioclase"],
                               [0.16, 0.99])
    assert s.meta["scenario"] is None
