"""Perturbation ensembles (sim.protocols.ensemble, ``gbmsim TEST SPEC --ensemble N``).

Member 0 is the plain test; perturbed members differ once the response is non-smooth (local
damping's sign(v), bond breakage), and only by the perturbation's size when it is smooth. The
statistics are those of the members; Ctrl-C and a resume give the uninterrupted ensemble; a
resume with other options is refused before anything is written.
"""
import json
import math

import numpy as np
import pandas as pd
import pytest
from _interrupt import kill_after_partial_writes
from _specimens import random_specimen

from sim import Specimen
from sim.protocols.ensemble import ensemble_stats, member_dir, perturb, result_numbers, run_ensemble
from sim.protocols.ucs import run_ucs

RATE = 20.0                     # as test_protocols.py: tiny specimens, quasi-static
RESULTS = ("ucs_mpa", "elastic.E_measured_gpa", "elastic.nu_measured", "ci_mpa", "cd_mpa",
           "cracks.total", "steps")


@pytest.fixture(scope="module")
def ensemble3(rock, tmp_path_factory):
    """A 3-member UCS ensemble of ``rock`` written to a directory (made once)."""
    out = tmp_path_factory.mktemp("ens3")
    return run_ensemble("ucs", rock, runs=3, strain_rate=RATE, out=out, progress=False,
                        figures=False), out


def snapshot(folder):
    """Relative path -> bytes of every file under ``folder``."""
    return {str(p.relative_to(folder)): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_docstring_examples():
    import doctest

    from sim.protocols import ensemble
    r = doctest.testmod(ensemble)
    assert r.attempted >= 8 and r.failed == 0


def test_perturb_moves_every_centre_by_the_amplitude(rock):
    p0 = perturb(rock, 0)
    assert np.array_equal(p0.x, rock.x) and np.array_equal(p0.y, rock.y)
    p1 = perturb(rock, 1, 1e-6)
    d2 = (p1.x - rock.x) ** 2 + (p1.y - rock.y) ** 2
    scale = 1e-6 * float(np.mean(rock.r))
    # 2 n standard normals: the rms displacement is sqrt(2) x scale within a few per cent
    assert math.sqrt(d2.mean()) == pytest.approx(math.sqrt(2) * scale, rel=0.1)
    assert np.all(d2 > 0) and math.sqrt(d2.max()) < 8 * scale
    assert np.array_equal(perturb(rock, 1, 1e-6).x, p1.x)          # seeded by the member
    assert not np.array_equal(perturb(rock, 2, 1e-6).x, p1.x)
    assert p1.meta["perturbation"]["member"] == 1
    assert p1.meta["perturbation"]["rms_displacement_m"] == pytest.approx(
        math.sqrt(d2.mean()), rel=1e-12)
    assert np.array_equal(p1.r, rock.r) and p1.n_bonds == rock.n_bonds
    for bad in ({"member": -1}, {"member": 1.5}, {"member": 1, "amplitude": 0.0},
                {"member": 1, "amplitude": float("nan")}):
        with pytest.raises(ValueError, match="member|amplitude"):
            perturb(rock, **bad)


def test_stats_are_those_of_the_members():
    m = pd.DataFrame({"member": [0, 1, 2, 3], "ucs_mpa": [100.0, 110.0, 120.0, np.nan],
                      "one": [1.0, np.nan, np.nan, np.nan], "none": [np.nan] * 4})
    t = ensemble_stats(m)
    assert "member" not in t.index and "none" not in t.index
    r = t.loc["ucs_mpa"]
    assert (r["n"], r["mean"], r["sd"], r["min"], r["max"]) == (3, 110.0, 10.0, 100.0, 120.0)
    assert r["sem"] == pytest.approx(10.0 / math.sqrt(3), rel=1e-12)
    assert r["ci95"] == pytest.approx(4.302652729911275 * 10.0 / math.sqrt(3), rel=1e-9)
    assert r["cv_pct"] == pytest.approx(100.0 * 10.0 / 110.0, rel=1e-12)
    assert t.loc["one", "n"] == 1 and math.isnan(t.loc["one", "sd"])


def test_result_numbers_flattens_the_outcome_only():
    s = {"test": "ucs", "ucs_mpa": 150.0, "nu": None, "n_particles": 10, "threads": 2,
         "status": "complete", "options": {"damping": 0.7}, "specimen": {"seed": 3},
         "cracks": {"total": 4, "intra": 1}, "P_sim": {"by_area": 2.0, "by_count": None},
         "engine_error": None, "steps": 100, "flag": True}
    n = result_numbers(s)
    assert set(n) == {"ucs_mpa", "nu", "cracks.total", "cracks.intra", "P_sim.by_area",
                      "P_sim.by_count", "engine_error", "steps"}
    assert n["ucs_mpa"] == 150.0 and math.isnan(n["nu"]) and n["cracks.total"] == 4.0


def test_member_zero_is_the_plain_test_and_the_members_scatter(rock, ensemble3):
    """Member 0 reproduces ``run_ucs`` exactly; the perturbed members fail along other paths
    (distinct UCS) within a few per cent; ensemble.json/csv hold the members' numbers."""
    res, out = ensemble3
    plain = run_ucs(rock, strain_rate=RATE, progress=False)
    row0 = res.members.iloc[0]
    for k in RESULTS:
        assert row0[k] == pytest.approx(result_numbers(plain.summary)[k], rel=1e-12), k
    ucs = res.members["ucs_mpa"].to_numpy()
    assert len(set(ucs)) == 3                                # three failure paths
    assert res.sd("ucs_mpa") / res.mean("ucs_mpa") < 0.05
    assert res.mean("ucs_mpa") == pytest.approx(ucs.mean(), rel=1e-12)
    d = json.loads((out / "ensemble.json").read_text())
    assert d["status"] == "complete" and d["finished"] == d["runs"] == 3
    assert d["stats"]["ucs_mpa"]["sd"] == pytest.approx(float(np.std(ucs, ddof=1)), rel=1e-12)
    assert [m["member"] for m in d["members"]] == [0, 1, 2]
    assert pd.read_csv(out / "ensemble.csv")["ucs_mpa"].tolist() == pytest.approx(list(ucs))
    for k in range(3):
        s = json.loads((out / f"member_{k:02d}" / "summary.json").read_text())
        assert s["specimen"]["perturbation"]["member"] == k
        assert s["ucs_mpa"] == pytest.approx(ucs[k], rel=1e-12)


def test_elastic_scatter_comes_from_local_damping():
    """Unbreakable bonds, loaded elastically: without damping the members' stresses differ by
    about the perturbation (smooth response); local damping (force along -sign(v)) makes the
    response non-smooth, so the same 1e-9 perturbation moves the stress by far more, yet the
    elastic numbers stay within 1 %."""
    s = random_specimen(0.005, 0.010, 0.25e-3, seed=1, pb_ten=1e12, pb_coh=1e12)
    spread = {}
    for damping in (0.0, 0.7):
        res = run_ensemble("ucs", s, runs=3, strain_rate=RATE, max_strain=1e-3,
                           adaptive=False, damping=damping, progress=False)
        h = [x["axial_stress_mpa"].to_numpy() for x in res.histories]
        assert all(len(x) == len(h[0]) for x in h)
        spread[damping] = max(np.max(np.abs(x - h[0])) for x in h[1:]) / np.max(h[0])
        assert res.members["cracks.total"].max() == 0
        e = "elastic.E_measured_gpa"        # 10 particles across: E_ok false (gauge/platen)
        assert res.sd(e) / res.mean(e) < 0.01
    assert spread[0.0] < 1e-6
    assert spread[0.7] > 1e3 * spread[0.0]


def test_ctrl_c_then_resume_gives_the_uninterrupted_ensemble_and_extends_it(
        rock, ensemble3, tmp_path, monkeypatch):
    from sim.simulation import Simulation
    ref, ref_out = ensemble3
    out = tmp_path / "ens"
    orig, seen, fired = Simulation.cycle, [], []
    stop = int(ref.histories[1]["step"].iloc[len(ref.histories[1]) // 2])

    def cycle(self, n, **kw):                    # Ctrl-C half way through member 1
        if not any(self is x for x in seen):
            seen.append(self)
        if len(seen) == 2 and self.step >= stop and not fired:
            fired.append(int(self.step))
            raise KeyboardInterrupt
        return orig(self, n, **kw)

    monkeypatch.setattr(Simulation, "cycle", cycle)
    with pytest.raises(KeyboardInterrupt):
        run_ensemble("ucs", rock, runs=3, strain_rate=RATE, out=out, progress=False,
                     figures=False)
    monkeypatch.setattr(Simulation, "cycle", orig)
    d = json.loads((out / "ensemble.json").read_text())
    assert fired and d["status"] == "interrupted" and d["finished"] == 1
    m1 = json.loads((out / "member_01" / "summary.json").read_text())
    assert m1["status"] == "interrupted" and (out / "member_01" / "checkpoint.npz").exists()
    before = (out / "member_00" / "summary.json").read_bytes()

    res = run_ensemble("ucs", rock, runs=3, strain_rate=RATE, out=out, resume=True,
                       progress=False, figures=False)
    assert (out / "member_00" / "summary.json").read_bytes() == before    # read, not re-run
    for k in RESULTS:
        assert res.members[k].tolist() == pytest.approx(ref.members[k].tolist(),
                                                        rel=1e-12), k
    assert json.loads((out / "ensemble.json").read_text())["status"] == "complete"

    member2 = snapshot(out / "member_02")
    more = run_ensemble("ucs", rock, runs=4, strain_rate=RATE, out=out, resume=True,
                        progress=False, figures=False)
    assert snapshot(out / "member_02") == member2
    assert len(more.members) == 4 and more.summary["finished"] == 4
    assert more.members["ucs_mpa"].iloc[:3].tolist() == res.members["ucs_mpa"].tolist()


def test_killed_in_the_first_member_resumes(rock, ensemble3, tmp_path, monkeypatch):
    """A kill right after member 0's first periodic checkpoint: ensemble.json (written before
    the first member) and the member's partial files are enough to resume."""
    ref, _ = ensemble3
    out = tmp_path / "ens"
    calls, orig = kill_after_partial_writes(monkeypatch, 1)
    with pytest.raises(SystemExit):
        run_ensemble("ucs", rock, runs=3, strain_rate=RATE, out=out, progress=False,
                     figures=False, checkpoint_every=3)
    monkeypatch.setattr("sim.protocols.report.TestResult.write", orig)
    d = json.loads((out / "ensemble.json").read_text())
    assert calls and d["status"] == "running" and d["finished"] == 0
    res = run_ensemble("ucs", rock, runs=3, strain_rate=RATE, out=out, resume=True,
                       progress=False, figures=False, checkpoint_every=3)
    for k in RESULTS:
        assert res.members[k].tolist() == pytest.approx(ref.members[k].tolist(),
                                                        rel=1e-12), k


def test_a_fresh_run_replaces_the_ensemble_in_out(rock, tmp_path):
    """Without resume, an earlier ensemble's members go first: a later resume with more runs
    must not read a member of the old ensemble (here: of another amplitude) as its own."""
    kw = dict(strain_rate=RATE, out=tmp_path, progress=False, figures=False)
    run_ensemble("ucs", rock, runs=3, amplitude=1e-6, **kw)
    run_ensemble("ucs", rock, runs=2, **kw)
    assert sorted(p.name for p in tmp_path.glob("member_*")) == ["member_00", "member_01"]
    assert len(pd.read_csv(tmp_path / "ensemble.csv")) == 2
    res = run_ensemble("ucs", rock, runs=3, resume=True, **kw)
    m2 = json.loads((tmp_path / "member_02" / "summary.json").read_text())
    assert m2["specimen"]["perturbation"]["amplitude_rel"] == 1e-9
    assert len(res.members) == 3


def test_resume_with_other_options_is_refused_and_writes_nothing(rock, ensemble3, tmp_path):
    _, out = ensemble3
    before = snapshot(out)
    cases = [({"amplitude": 1e-8}, "config.amplitude_rel"),
             ({"platen_velocity": 0.02}, "config.test_options"),
             ({"specimen": perturb(rock, 5)}, "another specimen")]
    for change, match in cases:
        kw = {"runs": 3, "strain_rate": RATE, "out": out, "resume": True, "progress": False}
        spec = change.pop("specimen", rock)
        kw.update(change)
        with pytest.raises(ValueError, match=match) as exc:
            run_ensemble("ucs", spec, **kw)
        assert "ensemble.json" in str(exc.value)
    with pytest.raises(ValueError, match="ensemble.json"):
        run_ensemble("tension", rock, runs=3, out=out, resume=True, progress=False)
    with pytest.raises(ValueError, match="unknown option 'platen_speed'"):
        run_ensemble("ucs", rock, runs=3, out=out, resume=True, platen_speed=1.0)
    assert snapshot(out) == before
    # the test's defaults given explicitly are the same options: all members are read
    same = run_ensemble("ucs", rock, runs=3, strain_rate=RATE, post_peak=0.8, damping=0.7,
                        out=out, resume=True, progress=False, figures=False)
    assert same.members["ucs_mpa"].tolist() == ensemble3[0].members["ucs_mpa"].tolist()
    assert {k: v for k, v in snapshot(out).items() if k.startswith("member")} == {
        k: v for k, v in before.items() if k.startswith("member")}
    with pytest.raises(FileNotFoundError, match="ensemble.json"):
        run_ensemble("ucs", rock, runs=3, out=tmp_path, resume=True, progress=False)
    with pytest.raises(ValueError, match="runs >= 2"):
        run_ensemble("ucs", rock, runs=1, progress=False)
    with pytest.raises(ValueError, match="unknown test"):
        run_ensemble("shear", rock, runs=2)


def test_cli_ensemble(tmp_path, capsys, gbmsim_parser):
    s = Specimen.lattice(nx=16, ny=24, radius=1e-3, gap=2e-3)
    s.save(tmp_path / "lat.npz")
    out = tmp_path / "res"

    def gbmsim(*argv):
        args = gbmsim_parser.parse_args(["ucs", str(tmp_path / "lat.npz"), "--out", str(out),
                                  "--max-strain", "5e-4", "--strain-rate", "2",
                                  "--no-progress", *argv])
        return args.func(args)

    assert gbmsim("--ensemble", "2") == 0
    printed = json.loads(capsys.readouterr().out)
    d = json.loads((out / "ensemble.json").read_text())
    assert printed["runs"] == 2 and printed["E_gpa"]["mean"] == pytest.approx(
        d["stats"]["E_gpa"]["mean"]) and printed["E_gpa"]["mean"] > 50
    assert (out / "ensemble_curves.png").stat().st_size > 1000
    assert (out / "member_01" / "stress_strain.png").exists()
    assert gbmsim("--ensemble", "3", "--resume", "--no-figures") == 0
    assert json.loads((out / "ensemble.json").read_text())["finished"] == 3
    assert gbmsim("--ensemble", "3", "--resume", "--ensemble-amplitude", "1e-6") == 2
    assert "config.amplitude_rel" in capsys.readouterr().err
    assert gbmsim("--ensemble", "1") == 2
    assert gbmsim("--ensemble-amplitude", "1e-6") == 2
    assert "--ensemble N" in capsys.readouterr().err
    assert member_dir(out, 3).endswith("member_03")


@pytest.mark.parametrize("test, key", [("tension", "tensile_mpa"),
                                       ("brazilian", "tensile_mpa"), ("biaxial", "ucs_mpa")])
def test_the_other_tests_run_as_ensembles(rock, tmp_path, test, key):
    """Member 0 is the plain test; the curves figure finds each test's columns."""
    from sim.protocols.registry import protocol, run_test
    res = run_ensemble(test, rock, runs=2, strain_rate=RATE, out=tmp_path, progress=False)
    plain = run_test(test, rock, strain_rate=RATE, progress=False)
    assert res.members[key].iloc[0] == pytest.approx(plain.summary[key], rel=1e-12)
    assert np.all(np.isfinite(res.members[key])) and res.mean(key) > 1
    cls = protocol(test)
    assert all(c in h for h in res.histories for c in (cls.strain_key, cls.stress_key))
    assert cls.peak == key
    assert (tmp_path / "ensemble_curves.png").exists()
    assert (tmp_path / "member_01" / "summary.json").exists()
