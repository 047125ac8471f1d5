"""``gbmgen field`` and ``gbmsim excavate``: files, exit codes, a killed run resumes."""
import json

import numpy as np
import pandas as pd
import pytest

from gbmgen.cli import main as gbmgen_main
from sim import Simulation, Specimen
from sim.cli import main as gbmsim_main
from sim.protocols.excavate import run_excavate


def test_gbmgen_field_cli(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    plan.write_text("thickness_m,grain_rmin_mm,grain_rmax_mm,particle_radius_mm\n"
                    "0.5,200,240,50\n1.0,400,480,100\n")
    out = tmp_path / "f.npz"
    rc = gbmgen_main(["field", "--opening", "circle", "--radius-m", "0.5", "--domain-m", "3",
                      "--plan", str(plan), "--seed", "2", "--out", str(out), "--no-progress"])
    assert rc == 0
    s = Specimen.load(out)
    f = s.meta["field"]
    assert f["openings"][0]["radius_m"] == 0.5 and f["box"] == [-1.5, 1.5, -1.5, 1.5]
    assert "ring 1:" in capsys.readouterr().out
    rc = gbmgen_main(["field", "--opening", "polygon", "--out", str(tmp_path / "g.npz")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--polygon-m" in err[0]
    assert not (tmp_path / "g.npz").exists()


def test_gbmsim_excavate_cli_files_and_bad_input(tiny_drive, tmp_path, capsys):
    spec = tmp_path / "f.npz"
    tiny_drive.save(spec)
    out = tmp_path / "d"
    rc = gbmsim_main(["excavate", str(spec), "--depth-m", "400", "--out", str(out),
                      "--max-steps", "1000", "--no-progress", "--no-figures"])
    assert rc == 0
    sp = pd.read_csv(out / "stress_profile.csv")
    for c in ("r_over_a", "theta_deg", "sigma_rr_mpa", "sigma_tt_mpa", "kirsch_rr_mpa",
              "kirsch_tt_mpa"):
        assert c in sp.columns
    dd = pd.read_csv(out / "damage_depth.csv")
    assert list(dd.columns[1:5]) == ["angle_deg", "R_m", "D_m", "D_over_R"]
    assert len(dd) == 72 and (dd["D_over_R"] >= 1).all()
    s = json.loads((out / "summary.json").read_text())
    assert s["insitu"]["sigma_v_mpa"] == pytest.approx(2700 * 9.81 * 400 / 1e6)
    assert s["particles_removed"][0] > 0
    capsys.readouterr()
    rc = gbmsim_main(["excavate", str(spec), "--depth-m", "-5", "--out", str(tmp_path / "e")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "depth_m" in err[0]
    lat = tmp_path / "lat.npz"
    Specimen.lattice(4, 4, 1e-3).save(lat)
    rc = gbmsim_main(["excavate", str(lat), "--depth-m", "400", "--out", str(tmp_path / "e")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "openings" in err[0]


def test_killed_excavation_resumes_bit_identically(tiny_drive, tmp_path, monkeypatch):
    kw = dict(depth_m=600, max_steps=1500, interval=500, ratio=1e-12, progress=False,
              figures=False, sleep=True, sleep_disp=1e-6)
    run_excavate(tiny_drive, out=tmp_path / "a", **kw)
    real = Simulation.cycle
    calls = {"n": 0}

    def dying(self, n, **k):
        calls["n"] += 1
        if calls["n"] == 5:                      # in the excavation phase
            raise KeyboardInterrupt
        return real(self, n, **k)

    monkeypatch.setattr(Simulation, "cycle", dying)
    with pytest.raises(KeyboardInterrupt):
        run_excavate(tiny_drive, out=tmp_path / "b", **kw)
    monkeypatch.setattr(Simulation, "cycle", real)
    state = json.loads((tmp_path / "b" / "run_state.json").read_text())
    assert state["phase"] == "excavate" and state["phase_steps"] == 500
    run_excavate(tiny_drive, out=tmp_path / "b", resume=True, **kw)
    a = Simulation.load(tmp_path / "a" / "checkpoint.npz")
    b = Simulation.load(tmp_path / "b" / "checkpoint.npz")
    assert a.step == b.step == 3000
    assert np.array_equal(a.x, b.x) and np.array_equal(a.y, b.y)
    assert np.array_equal(a.bond_state, b.bond_state)
    ha = pd.read_csv(tmp_path / "a" / "history.csv")
    hb = pd.read_csv(tmp_path / "b" / "history.csv")
    assert np.array_equal(ha["ratio"].to_numpy(), hb["ratio"].to_numpy())


def test_gbmsim_excavate_numerical_failure_exits_3(tiny_drive, tmp_path, capsys, monkeypatch):
    from sim.errors import InstabilityError
    from sim.protocols import excavate

    def unstable(*a, **k):
        raise InstabilityError("step 17: particle 3 moved more than 0.25 R\nhint: smaller dt",
                               step=17, cause="energy")

    monkeypatch.setattr(excavate, "run_excavate", unstable)
    spec = tmp_path / "f.npz"
    tiny_drive.save(spec)
    rc = gbmsim_main(["excavate", str(spec), "--depth-m", "400", "--out", str(tmp_path / "d")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 3 and len(err) == 1
    assert "numerical failure" in err[0] and "step 17" in err[0] and "--resume" in err[0]


def test_staged_excavation_enlarges_the_profile(tiny_drive, tmp_path):
    """--stages 2: half-size profile first, then the design profile; together = all of it."""
    from sim.field_geometry import points_in_polygon
    s = run_excavate(tiny_drive, depth_m=400, out=tmp_path / "s", stages=2, max_steps=500,
                     interval=500, ratio=1e-12, progress=False, figures=False)
    first, second = s["particles_removed"]
    inside = points_in_polygon(tiny_drive.x, tiny_drive.y,
                               tiny_drive.meta["field"]["openings"][0]["polygon"]).sum()
    assert first + second == inside
    assert 0.15 * inside < first < 0.35 * inside         # ~ (1/2)^2 of the area
    assert set(s["phases"]) == {"insitu", "excavate_1", "excavate_2"}
