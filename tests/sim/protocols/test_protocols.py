"""Physics of the laboratory protocols on tiny specimens (numbers asserted, issue #6)."""
import json
import math
import os
import sys

import numpy as np
import pandas as pd
import pytest

from sim import Specimen
from sim.protocols.biaxial import run_biaxial
from sim.protocols.brazilian import cut_disc, run_brazilian
from sim.protocols.tension import run_tension
from sim.protocols.ucs import run_ucs

sys.path.insert(0, os.path.dirname(__file__))
from _interrupt import ctrl_c_at_step, kill_after_partial_writes  # noqa: E402
from _specimens import random_specimen  # noqa: E402

# tiny specimens load fast: 10 mm high, ~20-35 particle rows. The rate keeps the loading time
# to the peak at > 50 P-wave transits of the specimen (quasi-static; see docs/labtests.md).
RATE = 20.0


def lattice_formula(kn, ks):
    """REFERENCE.md §6.2: E (per unit thickness) and ν of a bonded triangular lattice."""
    return 2 * np.sqrt(3) * kn * (kn + ks) / (3 * kn + ks), (kn - ks) / (3 * kn + ks)


@pytest.mark.parametrize("settings", [{}, {"platen_velocity": 0.0125, "adaptive": False}])
def test_ucs_lattice_with_unbreakable_bonds_matches_lattice_formula(settings):
    """E and ν within 1 % of the lattice formula with the default settings (adaptive speed,
    fast and accelerating through the window E and ν are read in) and at a constant speed.

    A 40 x 79 lattice of 0.1 mm disks, neighbours 2e-3 apart (only the bonds act, kn = Ē t,
    ks = kn / κ̄). The gauge reads stress and strain of the same particles, so the readings do
    not depend on the platen speed; the platen modulus (force over the box width) is 2.5 %
    lower (the zig-zag free edges carry load over 39.5 of the 40.5 spacings of the box).
    """
    s = Specimen.lattice(nx=40, ny=79, radius=1e-4, gap=2e-3)
    res = run_ucs(s, max_strain=5e-4, post_peak=None, progress=False, figures=False,
                  **settings)
    sm = res.summary
    assert sm["stop_reason"] == "max_strain" and sm["cracks"]["total"] == 0
    E_ref, nu_ref = lattice_formula(60e9, 30e9)       # kn = Ē t, ks = kn / κ̄
    assert sm["E_ok"] and sm["nu_ok"] and sm["elastic"]["E_source"] == "gauge"
    assert sm["E_gpa"] * 1e9 == pytest.approx(E_ref, rel=0.01)
    assert sm["nu"] == pytest.approx(nu_ref, rel=0.01)
    assert sm["representative"]["ok"] and "plane stress" in sm["elastic"]["convention"]
    if settings:            # constant speed: every window record is steady
        assert sm["elastic"]["boundary_on_steady_records"]
        assert sm["elastic"]["nu_source"] == "boundary"
        assert sm["elastic"]["nu_boundary"] == pytest.approx(nu_ref, rel=0.01)
    else:                   # the platens accelerate through the window
        v = res.history["platen_velocity_m_per_s"].to_numpy()
        assert v.max() > 5 * v[5] and not sm["elastic"]["boundary_on_steady_records"]
        assert sm["elastic"]["nu_source"] == "gauge"
    # the history reached the requested strain and is compression positive
    h = res.history
    assert h["axial_strain"].iloc[-1] >= 5e-4 and h["axial_stress_mpa"].iloc[-1] > 0
    assert (h["lateral_strain"].iloc[-1] < 0) and (h["gauge_lateral_strain"].iloc[-1] < 0)


@pytest.mark.parametrize("factor, sign", [(0.1, -1), (10.0, +1)])
def test_more_grain_boundary_lowers_e_with_soft_joints_and_raises_it_with_stiff(factor, sign):
    """E follows the joint share monotonically, its direction set by the joint stiffness.

    One packing, unbreakable bonds and joints, cut into 6 or 40 Voronoi grains: more grains
    means more smooth joints. Joints 10x softer than the default (pb_emod / 2 r) lower E as
    they multiply; 10x stiffer, they raise it (benchmarks/joint_stiffness_trend.py measures
    the same on gbmgen specimens).
    """
    base = 60e9 / (2 * 0.25e-3)
    e = []
    for n_grains in (6, 40):
        s = random_specimen(0.005, 0.010, 0.25e-3, seed=1, n_grains=n_grains, pb_ten=1e12,
                            pb_coh=1e12, sj_ten=1e12, sj_coh=1e12, sj_kn=factor * base,
                            sj_ks=factor * base / 2)
        sm = run_ucs(s, max_strain=1e-3, post_peak=None, strain_rate=RATE, adaptive=False,
                     progress=False, figures=False).summary
        assert sm["cracks"]["total"] == 0
        e.append(sm["elastic"]["E_gauge_gpa"])     # 10 particles across: no E_ok here
    assert sign * (e[1] / e[0] - 1) > 0.05


@pytest.mark.parametrize("fraction", [0.8, 0.5])
def test_ucs_stops_after_peak_at_requested_fraction(rock, fraction, tmp_path):
    res = run_ucs(rock, post_peak=fraction, strain_rate=RATE, progress=False,
                  out=tmp_path / "ucs")
    s = res.history["axial_stress_mpa"].to_numpy()
    ip = int(np.argmax(s))
    assert res.summary["stop_reason"] == "post_peak"
    assert s[-1] < fraction * s[ip]                 # stopped below the fraction ...
    assert np.all(s[ip:-1] >= fraction * s[ip])     # ... at the first record below it
    assert ip < len(s) - 1
    sm = res.summary
    assert sm["ucs_mpa"] == pytest.approx(s[ip])
    assert 0 < sm["ci_mpa"] <= sm["ucs_mpa"] and 0 < sm["cd_mpa"] <= sm["ucs_mpa"]
    el = sm["elastic"]
    assert 10 < el["E_measured_gpa"] < 200 and 0 < el["nu_measured"] < 0.5
    assert isinstance(sm["E_ok"], bool) and sm["E_reason"] and sm["nu_reason"]
    c = sm["cracks"]
    assert c["total"] == len(res.cracks) > 0
    assert c["total"] == c["pb_tension"] + c["pb_shear"] + c["sj_tension"] + c["sj_shear"]
    # outputs of DESIGN.md §4 on disk
    d = json.loads((tmp_path / "ucs" / "summary.json").read_text())
    assert d["test"] == "ucs" and d["ucs_mpa"] == pytest.approx(sm["ucs_mpa"])
    for k in ("E_gpa", "nu", "E_ok", "nu_ok", "elastic", "ci_mpa", "cd_mpa", "cracks", "P_sim",
              "steps", "wall_s", "particle_steps_per_s", "representative"):
        assert k in d
    h = pd.read_csv(tmp_path / "ucs" / "history.csv")
    assert len(h) == len(res.history) and h["cracks_total"].is_monotonic_increasing
    cr = pd.read_csv(tmp_path / "ucs" / "cracks.csv")
    assert len(cr) == c["total"] and set(cr["relation"]) == {"intra"}
    for f in ("stress_strain.png", "crack_map.png"):
        assert (tmp_path / "ucs" / f).stat().st_size > 1000


def test_brazilian_matches_direct_tension_on_homogeneous_material():
    """σt = 2P/(πDt) of discs within 20 % of the direct-tension σt (mean of 3 seeds each)."""
    bt, dt = [], []
    for seed in (1, 2, 3):
        rect = random_specimen(0.005, 0.010, 0.15e-3, seed=seed)
        square = random_specimen(0.008, 0.008, 0.15e-3, seed=seed + 100)
        t = run_tension(rect, strain_rate=RATE, progress=False).summary
        b = run_brazilian(square, strain_rate=RATE, progress=False).summary
        assert t["stop_reason"] == b["stop_reason"] == "post_peak"
        dt.append(t["tensile_mpa"])
        bt.append(b["tensile_mpa"])
    ratio = np.mean(bt) / np.mean(dt)
    assert ratio == pytest.approx(1.0, abs=0.20), (bt, dt)
    assert 0.2 < np.mean(dt) / 100.0 < 0.8      # σt a fraction of the bond strength (100 MPa)


def test_cut_disc_keeps_bonds_inside():
    s = random_specimen(0.008, 0.008, 0.25e-3, seed=5)
    d = cut_disc(s, diameter=0.006)
    r_out = np.hypot(d.x - 0.5 * (s.box[0] + s.box[1]), d.y - 0.5 * (s.box[2] + s.box[3])) + d.r
    assert np.all(r_out <= 0.003 + 1e-15) and d.n_particles < s.n_particles
    assert d.n_bonds > 0 and d.bond_j.max() < d.n_particles
    # every kept bond joins the same two particles as before
    keep = np.nonzero(np.hypot(s.x - 0.004, s.y - 0.004) + s.r <= 0.003)[0]
    pairs_old = {(keep_i, keep_j) for keep_i, keep_j in zip(s.bond_i, s.bond_j)
                 if keep_i in set(keep) and keep_j in set(keep)}
    pairs_new = {(keep[i], keep[j]) for i, j in zip(d.bond_i, d.bond_j)}
    assert pairs_new == pairs_old


def _two_grain_lattice(*, weak):
    """Lattice 8 x 12 in two grains (bottom: grain 0, mineral 0; top: grain 1, mineral 1);
    bonds across the middle are smooth joints with normal +y. ``weak`` = "joint" or "grain1"."""
    nx, ny, rad = 8, 12, 1e-3
    s = Specimen.lattice(nx=nx, ny=ny, radius=rad, gap=2e-3, pb_emod=60e9, emod=60e9)
    row = np.rint((s.y - s.y.min()) / (s.meta["spacing_m"] * np.sqrt(3) / 2)).astype(int)
    grain = (row >= ny // 2).astype(np.int32)
    cross = grain[s.bond_i] != grain[s.bond_j]
    kind = cross.astype(np.int8)
    jn = np.where(cross, 0.0, np.nan), np.where(cross, 1.0, np.nan)
    b = s.box
    ymid = 0.5 * (s.y[row == ny // 2 - 1].mean() + s.y[row == ny // 2].mean())
    polys = [np.array([[b[0], b[2]], [b[1], b[2]], [b[1], ymid], [b[0], ymid]]),
             np.array([[b[0], ymid], [b[1], ymid], [b[1], b[3]], [b[0], b[3]]])]
    big = 1e100
    pb_ten = [big, 5e6] if weak == "grain1" else [big, big]
    sj_ten = 2e6 if weak == "joint" else big
    t = Specimen(x=s.x, y=s.y, r=s.r, mineral=grain, grain=grain,
                 mineral_names=["hard", "soft"], density=[2650.0] * 2, emod=[60e9] * 2,
                 kratio=[2.0] * 2, fric=[0.5] * 2, pb_emod=[60e9] * 2, pb_kratio=[2.0] * 2,
                 pb_ten=pb_ten, pb_coh=pb_ten, pb_fa=[30.0] * 2, pb_rmul=[1.0] * 2,
                 sj_kn=[60e9 / (2 * rad)], sj_ks=[30e9 / (2 * rad)], sj_ten=[sj_ten],
                 sj_coh=[sj_ten], sj_fa=[30.0], sj_fric=[0.5], bond_i=s.bond_i,
                 bond_j=s.bond_j, bond_kind=kind, joint_nx=jn[0], joint_ny=jn[1], box=s.box,
                 grain_xy=np.concatenate(polys), grain_offsets=[0, 4, 8],
                 grain_mineral=[0, 1], grain_class=[1, 1])
    return t.validate(), ymid


def test_joint_breaks_are_inter_granular_on_the_boundary():
    s, ymid = _two_grain_lattice(weak="joint")
    res = run_tension(s, strain_rate=RATE, progress=False)
    c = res.cracks
    assert len(c) >= 7          # the boundary row of joints (2 nx − 1 = 15) opens
    assert set(c["kind"]) == {"sj"} and set(c["relation"]) == {"inter"}
    assert set(c["mode"]) == {"tension"}
    assert np.all(c["grain_i"] != c["grain_j"])
    assert np.all(np.abs(c["y"] - ymid) < 1e-4)
    assert set(zip(c["mineral_i"], c["mineral_j"])) == {(0, 1)}


def test_bond_breaks_inside_a_grain_are_intra_granular():
    s, ymid = _two_grain_lattice(weak="grain1")
    res = run_tension(s, strain_rate=RATE, progress=False)
    c = res.cracks
    assert len(c) >= 7
    assert set(c["kind"]) == {"pb"} and set(c["relation"]) == {"intra"}
    assert np.all(c["grain_i"] == 1) and np.all(c["grain_j"] == 1)
    assert np.all(c["y"] > ymid)
    sm = res.summary
    assert sm["cracks"]["pb_tension"] + sm["cracks"]["pb_shear"] == len(c)
    assert sm["cracks"]["intra"] == len(c) and sm["cracks"]["inter"] == 0


def test_biaxial_holds_confinement_and_is_stronger_than_ucs(rock):
    conf = 10e6
    res = run_biaxial(rock, confinement=conf, strain_rate=RATE, progress=False)
    sm = res.summary
    assert sm["consolidation_converged"]
    h = res.history
    s3 = h["confining_stress_mpa"].to_numpy()
    assert np.mean(s3) == pytest.approx(10.0, rel=0.01)
    assert np.all(np.abs(s3[:-1] - 10.0) < 0.5)        # servo holds σ3 up to the failure
    ucs = run_ucs(rock, strain_rate=RATE, progress=False).summary["ucs_mpa"]
    # a tiny bonded packing fails by bond tension, so confinement helps only a little (BPMs
    # are known for low friction angles); measured 130.8 -> 137.8 MPa at 10 MPa
    assert sm["ucs_mpa"] > 1.03 * ucs
    assert sm["deviatoric_peak_mpa"] == pytest.approx(
        float(np.max(h["axial_stress_mpa"] - h["confining_stress_mpa"])), rel=1e-9)


def test_ctrl_c_leaves_checkpoint_and_partial_outputs(rock, tmp_path, monkeypatch):
    from sim.simulation import Simulation
    calls = {"n": 0}
    orig = Simulation.cycle

    def cycle(self, n, **kw):
        calls["n"] += 1
        if calls["n"] == 6:
            raise KeyboardInterrupt
        return orig(self, n, **kw)

    monkeypatch.setattr(Simulation, "cycle", cycle)
    with pytest.raises(KeyboardInterrupt):
        run_ucs(rock, strain_rate=RATE, progress=False, out=tmp_path)
    monkeypatch.setattr(Simulation, "cycle", orig)
    d = json.loads((tmp_path / "summary.json").read_text())
    assert d["status"] == "interrupted" and d["stop_reason"] == "interrupted"
    h = pd.read_csv(tmp_path / "history.csv")
    assert len(h) == 6                                  # initial record + 5 chunks
    sim = Simulation.load(tmp_path / "checkpoint.npz")
    assert sim.step == h["step"].iloc[-1] == d["steps"]
    sim.cycle(10)                                       # the checkpoint runs on
    assert math.isfinite(float(sim.x.sum()))


def test_cli_runs_ucs_and_reports_bad_input(tmp_path, capsys, gbmsim_parser):
    parser = gbmsim_parser
    s = Specimen.lattice(nx=16, ny=24, radius=1e-3, gap=2e-3)
    s.save(tmp_path / "lat.npz")
    out = tmp_path / "res"
    args = parser.parse_args(["ucs", str(tmp_path / "lat.npz"), "--out", str(out),
                              "--max-strain", "5e-4", "--strain-rate", "2", "--no-progress",
                              "--no-figures"])
    assert args.func(args) == 0
    d = json.loads((out / "summary.json").read_text())
    assert d["stop_reason"] == "max_strain" and d["E_gpa"] > 50
    assert not (out / "crack_map.png").exists()
    args = parser.parse_args(["ucs", str(tmp_path / "missing.npz"), "--out", str(out)])
    assert args.func(args) == 2
    assert "missing.npz" in capsys.readouterr().err


def test_engine_instability_after_the_peak_ends_the_test_with_its_answer(rock, monkeypatch):
    """An InstabilityError among the fragments after the peak stops the test like the
    post-peak rule (UCS already known) and is reported; before the peak it propagates."""
    from sim.errors import InstabilityError
    from sim.simulation import Simulation
    ref = run_ucs(rock, strain_rate=RATE, post_peak=0.3, progress=False)
    h = ref.history
    ip = int(np.argmax(h["axial_stress_mpa"]))
    s = h["axial_stress_mpa"].to_numpy()
    k = ip + int(np.argmax(s[ip:] < 0.95 * s[ip]))    # first record 5 % below the peak
    late = int(h["step"].iloc[k])
    orig = Simulation.cycle

    def cycle(self, n, **kw):
        if self.step >= late:
            raise InstabilityError("unstable (test)", step=self.step, cause="energy")
        return orig(self, n, **kw)

    monkeypatch.setattr(Simulation, "cycle", cycle)
    res = run_ucs(rock, strain_rate=RATE, post_peak=0.3, progress=False)
    sm = res.summary
    assert sm["stop_reason"] == "instability_after_peak" and "unstable" in sm["engine_error"]
    assert sm["ucs_mpa"] == pytest.approx(ref.summary["ucs_mpa"], rel=1e-12)
    # before any crack (a pre-peak crack burst can drop the stress by several %, which the
    # rule cannot tell from the peak): the first record at 30 % of the peak
    early = int(h["step"].iloc[int(np.argmax(s >= 0.3 * s[ip]))])
    assert h["cracks_total"].iloc[int(np.argmax(s >= 0.3 * s[ip]))] == 0

    def cycle_early(self, n, **kw):
        if self.step >= early:
            raise InstabilityError("unstable (test)", step=self.step, cause="energy")
        return orig(self, n, **kw)

    monkeypatch.setattr(Simulation, "cycle", cycle_early)
    with pytest.raises(InstabilityError):
        run_ucs(rock, strain_rate=RATE, post_peak=0.3, progress=False)


def test_ucs_adaptive_speed_fast_before_cracks_base_after_peak(rock):
    """The default adaptive rule loads faster than the base rate while crack-free, at the
    base rate after the peak, and takes fewer steps than the constant base rate."""
    ad = run_ucs(rock, strain_rate=RATE, progress=False)
    const = run_ucs(rock, strain_rate=RATE, adaptive=False, progress=False)
    assert ad.summary["options"]["adaptive"] and not const.summary["options"]["adaptive"]
    h = ad.history
    v0 = const.summary["options"]["platen_velocity_m_per_s"]
    v = h["platen_velocity_m_per_s"].to_numpy()
    free = h["cracks_total"].to_numpy() == 0
    assert v[free].max() > 4 * v0
    ip = int(np.argmax(h["axial_stress_mpa"]))
    assert np.allclose(v[ip + 2:], v0)
    assert np.all(v[5:] >= v0 * (1 - 1e-12))          # after the start-up ramp
    first = int(np.argmax(h["cracks_total"].to_numpy() > 0))
    assert np.allclose(v[first + 1:], v0)             # the base speed from the first crack
    assert ad.summary["steps"] < const.summary["steps"]
    assert np.allclose(const.history["platen_velocity_m_per_s"].iloc[5:], v0)


def test_ucs_interrupted_and_resumed_gives_the_uninterrupted_result(rock, tmp_path,
                                                                    monkeypatch):
    """Ctrl-C (KeyboardInterrupt) between two records leaves checkpoint.npz + partial outputs;
    ``resume=True`` continues the protocol loop and ends with the same records and summary."""
    ref = run_ucs(rock, strain_rate=RATE, progress=False, out=tmp_path / "ref", figures=False)
    cut = int(ref.history["step"].iloc[len(ref.history) // 2])
    fired, _ = ctrl_c_at_step(monkeypatch, cut)
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        run_ucs(rock, strain_rate=RATE, progress=False, out=out, figures=False)
    assert len(fired) == 1
    part = json.loads((out / "summary.json").read_text())
    assert part["stop_reason"] == "interrupted" and (out / "checkpoint.npz").exists()
    assert 0 < part["steps"] < ref.summary["steps"]
    files = {p.name: p.read_bytes() for p in out.iterdir()}
    for other, name in (({"strain_rate": 2 * RATE}, "strain_rate_per_s"),
                        ({"strain_rate": RATE, "adaptive": False}, "adaptive"),
                        ({"strain_rate": RATE, "damping": 0.5}, "damping")):
        with pytest.raises(ValueError, match=f"options.{name}"):   # checked, nothing written
            run_ucs(rock, progress=False, out=out, figures=False, resume=True, **other)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == files
    res = run_ucs(rock, strain_rate=RATE, progress=False, out=out, figures=False, resume=True)
    a, b = ref.summary, res.summary
    assert b["stop_reason"] == "post_peak" and b["steps"] == a["steps"]
    for k in ("ucs_mpa", "ci_mpa", "cd_mpa", "peak_axial_strain"):
        assert b[k] == pytest.approx(a[k], rel=1e-12, abs=1e-12), k
    assert b["elastic"] == a["elastic"] and b["E_gpa"] == a["E_gpa"] and b["nu"] == a["nu"]
    assert b["cracks"] == a["cracks"]
    cols = ["step", "axial_strain", "axial_stress_mpa", "cracks_total", "gauge_axial_strain"]
    pd.testing.assert_frame_equal(res.history[cols].reset_index(drop=True),
                                  ref.history[cols].reset_index(drop=True), rtol=1e-12)
    with pytest.raises(FileNotFoundError, match="cannot resume"):
        run_ucs(rock, strain_rate=RATE, progress=False, out=tmp_path / "none", resume=True)


def test_ucs_killed_after_a_periodic_checkpoint_resumes_to_the_uninterrupted_result(
        rock, tmp_path, monkeypatch):
    """``checkpoint_every`` writes history.csv and summary.json (status running) beside each
    checkpoint, so a run killed without Ctrl-C (no partial outputs of its own) resumes from the
    last checkpoint and ends with the uninterrupted records and summary."""
    ref = run_ucs(rock, strain_rate=RATE, progress=False, out=tmp_path / "ref", figures=False)
    calls, orig = kill_after_partial_writes(monkeypatch, 2)
    out = tmp_path / "run"
    with pytest.raises(SystemExit):
        run_ucs(rock, strain_rate=RATE, progress=False, out=out, figures=False,
                checkpoint_every=3)
    part = json.loads((out / "summary.json").read_text())
    assert part["status"] == "running" and part["steps"] == calls[-1] > 0
    assert len(pd.read_csv(out / "history.csv")) == 7           # records 0..6
    monkeypatch.setattr(type(ref), "write", orig)
    res = run_ucs(rock, strain_rate=RATE, progress=False, out=out, figures=False, resume=True)
    a, b = ref.summary, res.summary
    assert b["status"] == "complete" and b["steps"] == a["steps"]
    for k in ("ucs_mpa", "peak_axial_strain"):
        assert b[k] == pytest.approx(a[k], rel=1e-12, abs=1e-12), k
    assert b["elastic"] == a["elastic"] and b["E_gpa"] == a["E_gpa"] and b["nu"] == a["nu"]
    assert b["cracks"] == a["cracks"]


def test_ucs_default_speed_is_size_aware():
    """Without a rate, the adaptive UCS takes its base speed and largest factor from the loaded
    length (sim.protocols.speed.adaptive_speeds): 0.00625 m/s x 16 for 8 mm and shorter, a
    fixed cracking strain rate beyond."""
    from sim.protocols import speed as ld
    for ny, r in ((8, 0.25e-3), (60, 0.25e-3)):
        s = Specimen.lattice(nx=4, ny=ny, radius=r, gap=0.0, emod=60e9, pb_emod=60e9)
        res = run_ucs(s, max_strain=1e-4, post_peak=None, progress=False, figures=False)
        o = res.summary["options"]
        h = s.box[3] - s.box[2]
        v, f = ld.adaptive_speeds(h)
        assert o["platen_velocity_m_per_s"] == pytest.approx(v, rel=1e-3)
        assert o["adaptive_rule"]["f_max"] == pytest.approx(f, rel=1e-3)
        if h > 0.008:
            assert o["strain_rate_per_s"] == pytest.approx(ld.ADAPTIVE_BASE_STRAIN_RATE, rel=1e-3)
        else:
            assert o["platen_velocity_m_per_s"] == pytest.approx(0.00625, rel=1e-3)


@pytest.mark.parametrize("test", ["tension", "brazilian", "biaxial"])
def test_periodic_checkpoints_leave_partial_results_in_every_protocol(rock, tmp_path,
                                                                       monkeypatch, test):
    """A run killed right after a periodic checkpoint (no Ctrl-C handler runs) leaves
    checkpoint.npz with history.csv, cracks.csv and summary.json (status running) beside it."""
    run = {"tension": run_tension, "brazilian": run_brazilian, "biaxial": run_biaxial}[test]
    kill_after_partial_writes(monkeypatch, 1)
    out = tmp_path / test
    with pytest.raises(SystemExit):
        run(rock, strain_rate=RATE, progress=False, out=out, figures=False, checkpoint_every=2)
    s = json.loads((out / "summary.json").read_text())
    assert s["test"] == test and s["status"] == "running" and s["steps"] > 0
    assert len(pd.read_csv(out / "history.csv")) == 3            # records 0, 1, 2
    assert (out / "checkpoint.npz").exists() and (out / "cracks.csv").exists()
