"""Elastic excavation against Kirsch, and sleeping particles against the awake run (issue 17).

One small elastic model (a = 0.75 m in an 8 m domain of the mini plan, ~7.6 k particles,
σ_H = 21.2, σ_v = 10.6 MPa at 400 m) excavated twice: awake and with sleeping particles.
Full-resolution numbers (the 20 m model, r/a = 1.5 and 2 in eight directions): docs/field.md.
"""
import numpy as np
import pandas as pd
import pytest

from gbmgen.field import openings as op
from gbmgen.field.build import build_field
from sim import Simulation
from sim.protocols import insitu as ins
from sim.protocols.excavate import SLEEP_DISP, run_excavate

#: Hoop-stress tolerance at r/a = 1.5 and 2 (issue 17), on direction pairs averaged by the
#: symmetry of the Kirsch field (θ, θ + 180°): ~200 particles per circle in this small model.
TOL_HOOP = 0.15
#: Sidewall (θ = 0°, 180°): there σθθ ≈ 3σv − σH is the difference of two large terms, so the
#: finite domain (walls at ±5.3 a) and the particle noise weigh 2-3x more (docs/field.md).
TOL_HOOP_SIDEWALL = 0.25
#: Sleeping vs awake: displacements and stresses within this fraction (docs/field.md).
TOL_SLEEP = 0.01


@pytest.fixture(scope="module")
def runs(mini_plan, tmp_path_factory):
    spec, _ = build_field(plan=mini_plan, openings=[op.circle(radius_m=0.75)], domain_m=8.0,
                          seed=3)
    out = {}
    for sleep in (False, True):
        d = tmp_path_factory.mktemp(f"sleep{sleep}")
        s = run_excavate(spec, depth_m=400, out=d, elastic=True, sleep=sleep, progress=False,
                         figures=False)
        out[sleep] = (s, d)
    return out


def test_elastic_circle_reproduces_kirsch(runs):
    s, d = runs[False]
    assert all(p["converged"] for p in s["phases"].values())
    assert s["cracks"]["total"] == 0
    sp = pd.read_csv(d / "stress_profile.csv")
    sp["pair"] = sp["theta_deg"] % 180
    g = sp[sp["r_over_a"].isin([1.5, 2.0])].groupby(["r_over_a", "pair"])[
        ["sigma_tt_mpa", "kirsch_tt_mpa"]].mean()
    err = (g["sigma_tt_mpa"] / g["kirsch_tt_mpa"] - 1).abs()
    side = err.index.get_level_values("pair") == 0
    assert err[~side].max() <= TOL_HOOP                  # crown (90) and diagonals (45, 135)
    assert err[side].max() <= TOL_HOOP_SIDEWALL
    # the crown's hoop stress is the largest, the sidewall's the smallest, as Kirsch
    g15 = g.loc[1.5, "sigma_tt_mpa"]
    assert g15[90] > g15[45] > g15[0]
    # sigma_rr -> 0 at the wall: extrapolated from r/a = 1.1 and 1.25, mean over directions
    wall = np.mean(list(s["kirsch"]["circle"]["sigma_rr_wall_extrapolated_mpa"].values()))
    p = 0.5 * (s["insitu"]["sigma_h_mpa"] + s["insitu"]["sigma_v_mpa"])
    assert abs(wall) <= 0.1 * p
    # far field held by the servo walls
    assert s["phases"]["insitu"]["sigma_xx_mpa"] == pytest.approx(s["insitu"]["sigma_h_mpa"],
                                                                  rel=0.01)


def test_sleeping_particles_give_the_awake_result(runs):
    (_, da), (sb, db) = runs[False], runs[True]
    h = pd.read_csv(db / "history.csv")
    assert h.loc[h["phase"] != "insitu", "asleep_fraction"].max() > 0.1   # sleep did engage
    ua, ub = pd.read_csv(da / "displacement.csv"), pd.read_csv(db / "displacement.csv")
    du = np.hypot(ua["ux_mm"] - ub["ux_mm"], ua["uy_mm"] - ub["uy_mm"])
    assert du.max() <= TOL_SLEEP * np.hypot(ua["ux_mm"], ua["uy_mm"]).max()
    pa, pb = pd.read_csv(da / "stress_profile.csv"), pd.read_csv(db / "stress_profile.csv")
    sel = pa["r_over_a"] >= 1.5
    rel = ((pa["sigma_tt_mpa"] - pb["sigma_tt_mpa"]).abs() / pa["sigma_tt_mpa"].abs())[sel]
    assert rel.max() <= TOL_SLEEP
    assert sb["options"]["sleep_disp"] == SLEEP_DISP


def test_sleeping_particles_wake_on_load(runs):
    _, d = runs[True]
    sim = Simulation.load(d / "checkpoint.npz")
    sim.sleep = True
    sim.cycle(300)
    before = sim.asleep.mean()
    assert before > 0.5
    st = sim.specimen
    walls = (0, 1, 2, 3)
    stress = ins.InsituStress(400, 1.2 * 21.19e6, 10.59e6, "test")
    ins.update_servo_lengths(sim, walls, stress)              # raise sigma_H by 20 %
    x0 = sim.x.copy()
    sim.cycle(2000)
    assert sim.asleep.mean() < before - 0.3                  # the load woke them
    side = np.abs(x0) > 0.8 * (st.box[1])
    assert np.all(np.abs(sim.x - x0)[side] > 0)             # and the far side moved in
    assert np.mean(np.sign(x0[side]) * (sim.x - x0)[side] < 0) > 0.95
