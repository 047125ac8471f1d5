"""Resume of the direct tension, Brazilian and biaxial tests (sim.protocols.resume).

A run interrupted by Ctrl-C, or killed right after a periodic checkpoint, and continued with
``resume=True`` ends with the records and summary of the uninterrupted run (UCS: see
test_protocols.py). A results directory that cannot be resumed fails with a message naming the
file and what was expected, and is left as it was.
"""
import json
import math
import shutil

import pandas as pd
import pytest
from _interrupt import ctrl_c_at_step, kill_after_partial_writes
from _specimens import random_specimen

from sim.protocols.biaxial import run_biaxial
from sim.protocols.brazilian import run_brazilian
from sim.protocols.tension import run_tension

RATE = 20.0                     # as test_protocols.py: tiny specimens, quasi-static
RUN = {"tension": run_tension, "brazilian": run_brazilian, "biaxial": run_biaxial}
#: summary entries that measure the machine, not the test
TIMING = {"wall_s", "particle_steps_per_s", "consolidation_s"}
#: the numbers each test reports (must be present, and equal after a resume)
RESULTS = {"tension": ("tensile_mpa", "peak_tensile_strain", "E_tension_gpa"),
           "brazilian": ("tensile_mpa", "tensile_hondros_mpa", "peak_load_n_per_m"),
           "biaxial": ("ucs_mpa", "deviatoric_peak_mpa", "nu", "ci_mpa", "cd_mpa",
                       "consolidation_steps")}
# (the biaxial E of this 10-particle-wide packing is measured but flagged: gauge and platen
# moduli differ by more than 15 %; its measured value is checked instead)


@pytest.fixture(scope="module")
def reference(rock, tmp_path_factory):
    """Uninterrupted runs (results directory written), one per test, made on first use."""
    runs = {}

    def get(test):
        if test not in runs:
            out = tmp_path_factory.mktemp(f"ref_{test}")
            runs[test] = RUN[test](rock, strain_rate=RATE, progress=False, out=out,
                                   figures=False), out
        return runs[test]
    return get


def assert_same_summary(a, b):
    """Every entry of two summaries equal (numbers to 1e-12 relative) except timings."""
    assert set(a) == set(b)
    for k in sorted(set(a) - TIMING):
        x, y = a[k], b[k]
        if isinstance(x, float):
            assert y == pytest.approx(x, rel=1e-12, abs=1e-12, nan_ok=True), k
        else:
            assert y == x, k


def snapshot(folder):
    """File name -> bytes of everything in ``folder`` (None when it does not exist)."""
    if not folder.exists():
        return None
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("how", ["ctrl_c", "killed"])
@pytest.mark.parametrize("test", ["tension", "brazilian", "biaxial"])
def test_interrupted_and_resumed_gives_the_uninterrupted_result(rock, reference, tmp_path,
                                                                monkeypatch, test, how):
    """Ctrl-C half way (checkpoint and partial outputs written by the handler), or a kill
    right after the 2nd periodic checkpoint (every 3 records), then ``resume=True``: the
    same records (every column), cracks and summary as the uninterrupted run."""
    run = RUN[test]
    ref, _ = reference(test)
    out = tmp_path / "run"
    if how == "ctrl_c":
        fired, orig = ctrl_c_at_step(monkeypatch, int(ref.history["step"].iloc[
            len(ref.history) // 2]))
        with pytest.raises(KeyboardInterrupt):
            run(rock, strain_rate=RATE, progress=False, out=out, figures=False)
        monkeypatch.setattr("sim.simulation.Simulation.cycle", orig)
        status, n_records = "interrupted", len(ref.history) // 2 + 1
    else:
        calls, orig = kill_after_partial_writes(monkeypatch, 2)
        with pytest.raises(SystemExit):
            run(rock, strain_rate=RATE, progress=False, out=out, figures=False,
                checkpoint_every=3)
        monkeypatch.setattr("sim.protocols.report.TestResult.write", orig)
        status, n_records = "running", 7                        # records 0..6
    part = json.loads((out / "summary.json").read_text())
    assert part["status"] == status and part["test"] == test
    assert len(pd.read_csv(out / "history.csv")) == n_records
    assert 0 < part["steps"] < ref.summary["steps"]

    res = run(rock, strain_rate=RATE, progress=False, out=out, figures=False, resume=True)
    a, b = ref.summary, res.summary
    assert b["status"] == "complete" and b["stop_reason"] == a["stop_reason"] == "post_peak"
    assert b["steps"] == a["steps"] and b["cracks"] == a["cracks"] and b["cracks"]["total"] > 0
    for k in RESULTS[test]:
        assert math.isfinite(b[k]), k
    if test == "biaxial":
        assert math.isfinite(b["elastic"]["E_measured_gpa"])
    assert_same_summary(a, b)
    pd.testing.assert_frame_equal(res.history, ref.history, rtol=1e-12)
    pd.testing.assert_frame_equal(res.cracks.reset_index(drop=True),
                                  ref.cracks.reset_index(drop=True), rtol=1e-12)
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["status"] == "complete" and on_disk["steps"] == a["steps"]
    assert len(pd.read_csv(out / "history.csv")) == len(ref.history)


@pytest.mark.parametrize("how", ["ctrl_c", "killed"])
def test_biaxial_interrupted_in_consolidation_resumes(rock, reference, tmp_path, monkeypatch,
                                                      how):
    """Stopped in stage 1 (Ctrl-C inside a servo interval, or killed after a periodic
    checkpoint), the biaxial test leaves a checkpoint and a summary of stage ``consolidation``;
    ``resume=True`` finishes stage 1 on the same servo updates and runs stage 2: the result
    equals the uninterrupted run."""
    from sim.protocols.biaxial import CONSOLIDATION_CHECK
    from sim.simulation import Simulation
    ref, _ = reference("biaxial")
    assert ref.summary["consolidation_steps"] >= 2 * CONSOLIDATION_CHECK
    out = tmp_path / "bx"
    if how == "ctrl_c":
        orig = Simulation.cycle

        def cycle(self, n, **kw):
            if self.step == CONSOLIDATION_CHECK:       # 70 steps into the 2nd interval
                monkeypatch.setattr(Simulation, "cycle", orig)
                orig(self, 70)
                raise KeyboardInterrupt
            return orig(self, n, **kw)

        monkeypatch.setattr(Simulation, "cycle", cycle)
        with pytest.raises(KeyboardInterrupt):
            run_biaxial(rock, strain_rate=RATE, progress=False, out=out, figures=False)
        status, done = "interrupted", CONSOLIDATION_CHECK + 70
    else:
        from sim.protocols import biaxial
        real = biaxial.write_results

        def write_then_die(folder, **kw):               # killed after the first partial write
            real(folder, **kw)
            raise SystemExit("killed")

        monkeypatch.setattr(biaxial, "write_results", write_then_die)
        with pytest.raises(SystemExit):
            run_biaxial(rock, strain_rate=RATE, progress=False, out=out, figures=False,
                        checkpoint_every=1)
        monkeypatch.setattr(biaxial, "write_results", real)
        status, done = "running", CONSOLIDATION_CHECK
    part = json.loads((out / "summary.json").read_text())
    assert (part["status"], part["stage"], part["consolidation_steps"]) == (status, "consolidation",
                                                                          done)
    assert Simulation.load(out / "checkpoint.npz").step == done
    assert not (out / "consolidated.npz").exists() and (out / "cracks.csv").exists()
    kw = dict(strain_rate=RATE, progress=False, figures=False, resume=True, out=out)
    before = snapshot(out)
    with pytest.raises(ValueError, match=r"options\.confinement_mpa = 20\.0, this run 10\.0"):
        run_biaxial(rock, confinement=10e6, **kw)
    assert snapshot(out) == before
    res = run_biaxial(rock, **kw)
    assert res.summary["status"] == "complete"
    assert_same_summary(ref.summary, res.summary)
    pd.testing.assert_frame_equal(res.history, ref.history, rtol=1e-12)
    assert (out / "consolidated.npz").exists()


@pytest.fixture
def interrupted_tension(rock, reference, tmp_path, monkeypatch):
    """A tension run stopped by Ctrl-C half way: its results directory."""
    ref, _ = reference("tension")
    _, orig = ctrl_c_at_step(monkeypatch, int(ref.history["step"].iloc[len(ref.history) // 2]))
    out = tmp_path / "tension"
    with pytest.raises(KeyboardInterrupt):
        run_tension(rock, strain_rate=RATE, progress=False, out=out, figures=False)
    monkeypatch.setattr("sim.simulation.Simulation.cycle", orig)
    return out


def test_resume_errors_name_the_file_and_leave_the_directory_as_it_was(
        rock, reference, interrupted_tension, tmp_path):
    out = interrupted_tension
    before = snapshot(out)
    kw = dict(strain_rate=RATE, progress=False, figures=False, resume=True)
    with pytest.raises(ValueError, match=r"summary\.json is not a resumable Brazilian run "
                                         r"\(test 'tension', expected 'brazilian'"):
        run_brazilian(rock, out=out, **kw)
    with pytest.raises(ValueError, match="not a resumable biaxial run"):
        run_biaxial(rock, out=out, **kw)
    other = random_specimen(0.005, 0.010, 0.3e-3, seed=2)
    assert other.n_particles != rock.n_particles
    with pytest.raises(ValueError, match=rf"checkpoint\.npz holds {rock.n_particles} "
                                         rf"particles, expected {other.n_particles}"):
        run_tension(other, out=out, **kw)
    with pytest.raises(ValueError, match=r"options\.grip_depth_m = None, this run 0\.002"):
        run_tension(rock, out=out, grip_depth=0.002, **kw)
    with pytest.raises(ValueError, match=r"options\.strain_rate_per_s"):
        run_tension(rock, out=out, **{**kw, "strain_rate": 2 * RATE})
    assert snapshot(out) == before
    # a missing file is named; a missing directory is not created
    none = tmp_path / "none"
    with pytest.raises(FileNotFoundError, match=r"cannot resume: missing .*checkpoint\.npz, "
                                                r".*history\.csv, .*summary\.json"):
        run_tension(rock, out=none, **kw)
    assert snapshot(none) is None
    part = tmp_path / "part"
    shutil.copytree(out, part)
    (part / "history.csv").unlink()
    before = snapshot(part)
    with pytest.raises(FileNotFoundError, match=r"missing \S*part/history\.csv$"):
        run_tension(rock, out=part, **kw)
    assert snapshot(part) == before
    # a finished run has nothing to continue
    _, done = reference("tension")
    before = snapshot(done)
    with pytest.raises(ValueError, match=r"summary\.json is a finished tension run "
                                         r"\(stop_reason 'post_peak'\)"):
        run_tension(rock, out=done, **kw)
    assert snapshot(done) == before


def test_brazilian_resume_checks_the_loading_and_the_disc(rock, tmp_path, monkeypatch):
    out = tmp_path / "b"
    kill_after_partial_writes(monkeypatch, 1)
    with pytest.raises(SystemExit):
        run_brazilian(rock, strain_rate=RATE, progress=False, out=out, figures=False,
                      checkpoint_every=2)
    before = snapshot(out)
    kw = dict(strain_rate=RATE, progress=False, figures=False, resume=True, out=out)
    with pytest.raises(ValueError, match=r"options\.loading = 'jaws', this run 'platens'"):
        run_brazilian(rock, loading="platens", **kw)
    with pytest.raises(ValueError, match=r"checkpoint\.npz holds \d+ particles, expected "
                                         r"\d+ \(the disc\)"):
        run_brazilian(rock, diameter=0.004, **kw)
    assert snapshot(out) == before


def test_biaxial_resume_needs_the_consolidated_state(rock, tmp_path, monkeypatch):
    """The biaxial test keeps its stage-2 reference (the consolidated state) beside the
    results; without it, or with one of another run, it does not resume."""
    out = tmp_path / "bx"
    kill_after_partial_writes(monkeypatch, 1)
    with pytest.raises(SystemExit):
        run_biaxial(rock, strain_rate=RATE, progress=False, out=out, figures=False,
                    checkpoint_every=2)
    assert (out / "consolidated.npz").exists()
    kw = dict(strain_rate=RATE, progress=False, figures=False, resume=True)
    with pytest.raises(ValueError, match=r"options\.confinement_mpa = 20\.0, this run 10\.0"):
        run_biaxial(rock, out=out, confinement=10e6, **kw)
    (out / "consolidated.npz").rename(tmp_path / "consolidated.npz")
    before = snapshot(out)
    with pytest.raises(FileNotFoundError, match=r"missing \S*bx/consolidated\.npz"):
        run_biaxial(rock, out=out, **kw)
    assert snapshot(out) == before
    from sim.simulation import Simulation
    sim = Simulation.load(tmp_path / "consolidated.npz")
    sim.cycle(3)                                  # a state of another moment
    sim.save(out / "consolidated.npz")
    before = snapshot(out)
    h0 = int(pd.read_csv(out / "history.csv")["step"].iloc[0])
    with pytest.raises(ValueError, match=rf"consolidated\.npz is at step {h0 + 3}, expected "
                                         rf"{h0} \(the first record of \S*history\.csv\)"):
        run_biaxial(rock, out=out, **kw)
    assert snapshot(out) == before


def test_cli_resumes_tension_brazilian_biaxial(rock, reference, tmp_path, monkeypatch,
                                               capsys, gbmsim_parser):
    """``gbmsim TEST SPEC --out DIR --resume`` for the three tests; bad resumes exit 2 with
    the message and write nothing."""
    spec = tmp_path / "rock.npz"
    rock.save(spec)
    def gbmsim(*argv):
        args = gbmsim_parser.parse_args([*argv, "--strain-rate", str(RATE), "--no-progress",
                                  "--no-figures"])
        return args.func(args)

    for test in ("tension", "brazilian", "biaxial"):
        out = tmp_path / test
        calls, orig = kill_after_partial_writes(monkeypatch, 1)
        with pytest.raises(SystemExit):
            gbmsim(test, str(spec), "--out", str(out), "--checkpoint-every", "2")
        monkeypatch.setattr("sim.protocols.report.TestResult.write", orig)
        assert json.loads((out / "summary.json").read_text())["status"] == "running"
        assert gbmsim(test, str(spec), "--out", str(out), "--resume") == 0
        d = json.loads((out / "summary.json").read_text())
        ref, _ = reference(test)
        assert d["status"] == "complete" and d["steps"] == ref.summary["steps"] > calls[0]
        key = "ucs_mpa" if test == "biaxial" else "tensile_mpa"
        assert d[key] == pytest.approx(ref.summary[key], rel=1e-12)
    capsys.readouterr()
    before = snapshot(tmp_path / "tension")
    assert gbmsim("brazilian", str(spec), "--out", str(tmp_path / "tension"), "--resume") == 2
    assert "not a resumable Brazilian run" in capsys.readouterr().err
    assert snapshot(tmp_path / "tension") == before
    assert gbmsim("tension", str(spec), "--out", str(tmp_path / "none"), "--resume") == 2
    assert "cannot resume: missing" in capsys.readouterr().err
    assert not (tmp_path / "none").exists()
