"""sim.calibrate on cheap analytic surrogates of the DEM with known optima."""
import doctest
import math

import numpy as np
import pytest

import sim.calibrate as cal
from sim.protocols.parameters import thesis_parameters

TARGETS = cal.DEFAULT_TARGETS


def _mean_field(p, f):
    return np.mean([t[f] for t in p["minerals"].values()])


def _surrogate(p, seed_factor=1.0):
    """A smooth, non-separable stand-in for the DEM.

    E follows the moduli and softens slightly with weak bonds (pre-peak cracking); UCS and σt
    are non-power-law mixtures of bond tension and cohesion. With the thesis start values the
    optimum lies at multipliers far from 1 (about 1.5 on the modulus, 0.1-0.6 on strengths).
    """
    emod = _mean_field(p, "pb_emod")
    ten, coh = _mean_field(p, "pb_ten"), _mean_field(p, "pb_coh")
    E = 0.75 * emod * (1.0 - 0.03 / (1.0 + coh / 50e6))
    ucs = (0.25 * ten + 0.55 * coh) * (1.0 + 0.1 * ten / (ten + coh)) * 0.5
    sigt = 0.12 * ten * (1.0 + 0.1 * coh / (ten + coh)) * (1.0 + 0.02 * emod / 60e9)
    return {"E": E * seed_factor, "UCS": ucs * seed_factor, "sigma_t": sigt / seed_factor}


def test_docstring_examples():
    r = doctest.testmod(cal)
    assert r.attempted >= 4 and r.failed == 0


def test_reaches_every_target_within_tolerance_with_few_evaluations():
    calls = []

    def evaluate(p):
        calls.append(1)
        return _surrogate(p)

    res = cal.calibrate(evaluate, thesis_parameters(), tol=0.01, max_evaluations=12)
    assert res.converged
    out = _surrogate(res.params)
    for k, v in TARGETS.items():
        assert out[k] == pytest.approx(v, rel=0.01), k
    assert res.n_evaluations == len(calls) <= 8
    # the multipliers agree with an independent root-find of the same surrogate
    from scipy.optimize import fsolve

    def miss(logm):
        o = _surrogate(cal.scale_parameters(thesis_parameters(), cal.DEFAULT_KNOBS, np.exp(logm)))
        return [np.log(o[k] / TARGETS[k]) for k in ("E", "UCS", "sigma_t")]

    m_ref = np.exp(fsolve(miss, np.zeros(3), xtol=1e-12))
    m = [res.multipliers[k] for k in ("modulus", "tensile", "cohesion")]
    np.testing.assert_allclose(m, m_ref, rtol=0.03)
    assert m_ref[1] < 0.6 and m_ref[0] > 1.3      # the optimum is far from the start
    # mineral contrasts are kept: ratios between minerals unchanged
    p0, p1 = thesis_parameters()["minerals"], res.params["minerals"]
    r0 = p0["plagioclase"]["pb_coh"] / p0["pyroxene"]["pb_coh"]
    r1 = p1["plagioclase"]["pb_coh"] / p1["pyroxene"]["pb_coh"]
    assert r1 == pytest.approx(r0, rel=1e-12)
    assert p1["pyroxene"]["pb_emod"] / p1["pyroxene"]["emod"] == pytest.approx(1.0)
    # the report records every evaluation with its errors
    d = res.to_dict()
    assert d["n_evaluations"] == res.n_evaluations and d["wall_s"] >= 0
    assert abs(d["evaluations"][-1]["errors"]["UCS"]) <= 0.01


def test_exact_power_law_needs_one_step_for_stiffness_and_few_for_strength():
    """A model that obeys the scaling laws exactly: E hit after the first step."""
    def evaluate(p):
        e = _mean_field(p, "pb_emod")
        t, c = _mean_field(p, "pb_ten"), _mean_field(p, "pb_coh")
        return {"E": 0.5 * e, "UCS": 0.4 * t ** 0.3 * c ** 0.7,
                "sigma_t": 0.05 * t ** 0.9 * c ** 0.1}

    res = cal.calibrate(evaluate, thesis_parameters(), tol=1e-6, max_evaluations=10)
    assert res.converged
    e_errors = [abs(r["errors"]["E"]) for r in res.evaluations]
    assert e_errors[1] < 1e-12          # the scaling-law step fixes E exactly
    assert res.n_evaluations == 2       # the initial Jacobian is exact for this model


def test_seed_averaging_reports_spread_and_corrects_the_mean():
    factors = [1.06, 1.05, 1.07]        # seeds all stiffer/stronger than the search specimen

    def seeds(p):
        return [_surrogate(p, f) for f in factors]

    res = cal.calibrate(_surrogate, thesis_parameters(), tol=0.01, evaluate_seeds=seeds)
    s = res.seed_summary
    assert set(s) == {"E", "UCS", "sigma_t"} and s["E"]["n"] == 3
    # after the correction round the seed means are back within tolerance
    for k in TARGETS:
        assert abs(s[k]["rel_error_of_mean"]) <= 0.01, k
    assert res.converged
    assert sum(1 for e in res.evaluations if e["phase"] == "seed") == 6   # two rounds x 3 seeds
    # spread is the known one: std of the factors times the mean response
    rel_spread = s["E"]["std"] / s["E"]["mean"]
    assert rel_spread == pytest.approx(np.std(factors, ddof=1) / np.mean(factors), rel=1e-6)


def test_unreachable_target_is_reported_not_hidden():
    knobs = (cal.Knob("modulus", ("emod", "pb_emod", "sj_kn", "sj_ks"), bounds=(0.5, 1.2)),
             cal.Knob("tensile", ("pb_ten", "sj_ten")), cal.Knob("cohesion", ("pb_coh", "sj_coh")))
    res = cal.calibrate(_surrogate, thesis_parameters(), knobs=knobs,
                        targets={"E": 200e9, "UCS": 135e6, "sigma_t": 18e6}, max_evaluations=6)
    assert not res.converged
    assert res.multipliers["modulus"] == pytest.approx(1.2)
    assert res.final_errors["E"] < -0.05
    assert res.n_evaluations <= 6


def test_bad_arguments():
    with pytest.raises(ValueError, match="target 'E'"):
        cal.calibrate(_surrogate, thesis_parameters(), targets={"E": -1.0})
    with pytest.raises(ValueError, match="bounds"):
        cal.calibrate(_surrogate, thesis_parameters(), knobs=(cal.Knob("m", ("emod",), (2, 3)),))
    with pytest.raises(KeyError, match="sigma_t"):
        cal.calibrate(lambda p: {"E": 1.0, "UCS": 1.0}, thesis_parameters())
    assert math.isclose(cal.initial_jacobian(["UCS"], cal.DEFAULT_KNOBS).sum(), 1.0)


def test_report_and_parameter_file_of_a_calibration(tmp_path):
    from sim.protocols.calibration import report_markdown
    from sim.protocols.parameters import load_parameters, save_parameters

    def seeds(p):
        return [_surrogate(p, f) for f in (0.99, 1.01)]

    res = cal.calibrate(_surrogate, thesis_parameters(), tol=0.01, evaluate_seeds=seeds)
    md = report_markdown(res, TARGETS, specimens=["a.npz", "b.npz"])
    assert f"evaluations in all: {res.n_evaluations}" in md
    assert md.count("\n| search |") == res.n_iterations and md.count("\n| seed |") == 2
    assert "| E | 65 GPa |" in md and "| sigma_t | 18 MPa |" in md
    save_parameters(tmp_path / "p.yaml", res.params, header="calibrated")
    back = load_parameters(tmp_path / "p.yaml")
    assert back["minerals"]["pyroxene"]["pb_ten"] == pytest.approx(
        res.params["minerals"]["pyroxene"]["pb_ten"], rel=1e-15)


def test_a_worse_correction_round_is_not_kept():
    calls = {"n": 0}

    def seeds(p):
        calls["n"] += 1
        f = 1.03 if calls["n"] == 1 else 1.3          # the second round scatters badly
        return [_surrogate(p, f), _surrogate(p, f)]

    res = cal.calibrate(_surrogate, thesis_parameters(), tol=0.01, evaluate_seeds=seeds)
    assert calls["n"] == 2
    assert abs(res.final_errors["E"]) == pytest.approx(0.03, rel=0.1)   # the first round
    assert res.seed_summary["E"]["mean"] == pytest.approx(
        _surrogate(res.params, 1.03)["E"], rel=1e-12)


def test_correction_step_lands_a_scaling_law_model_on_the_targets():
    """Responses that follow the scaling laws exactly (E ∝ m, UCS ∝ t^0.3 c^0.7,
    σt ∝ t^0.9 c^0.1) are put on the targets by one step, whatever the scatter between
    specimens (the Newton step of calibrate's seed rounds, with the scaling-law Jacobian)."""
    def model(m, t, c, f):
        return {"E": 63e9 * m * f, "UCS": 132e6 * t ** 0.3 * c ** 0.7 * f,
                "sigma_t": 19.5e6 * t ** 0.9 * c ** 0.1 / f}
    factors = [0.93, 1.0, 1.08]
    mean_f = {k: np.mean([model(1, 1, 1, f)[k] for f in factors]) for k in TARGETS}
    step = cal.correction_step([model(1, 1, 1, f) for f in factors])
    after = {k: np.mean([model(step["modulus"], step["tensile"], step["cohesion"], f)[k]
                         for f in factors]) for k in TARGETS}
    for k in TARGETS:
        assert after[k] == pytest.approx(TARGETS[k], rel=1e-9), k
    assert step["modulus"] == pytest.approx(65e9 / mean_f["E"], rel=1e-12)
    assert step["tensile"] < 1.0 < step["cohesion"]   # σt high, UCS low: trade tension for cohesion


def test_correction_step_rejects_missing_or_bad_responses():
    with pytest.raises(ValueError, match="empty"):
        cal.correction_step([])
    with pytest.raises(ValueError, match=r"responses\[1\].*sigma_t"):
        cal.correction_step([{"E": 1e9, "UCS": 1e6, "sigma_t": 1e6}, {"E": 1e9, "UCS": 1e6}])
    with pytest.raises(ValueError, match="shape"):
        cal.correction_step([TARGETS], jacobian=np.eye(2))
