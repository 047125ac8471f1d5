"""sim.analysis on constructed stress-strain-crack histories with exact answers."""
import doctest
import math

import numpy as np
import pytest

import sim.analysis as an


def _constructed_curve():
    """Linear to 60 % of a 150 MPa peak (E = 60 GPa, nu = 0.2), then softening, then post-peak.

    Cracks start at exactly 90 MPa (record index known), volumetric strain peaks at 120 MPa.
    """
    E, nu, peak = 60e9, 0.2, 150e6
    eps = np.linspace(0, 4e-3, 401)
    e_lin = 0.6 * peak / E                      # end of the linear part
    s = np.where(eps <= e_lin, E * eps, 0.0)
    # quadratic hardening to the peak at eps_p, continuous slope at e_lin
    eps_p = 3e-3
    a = (E * (eps_p - e_lin) - 0.4 * peak) / (eps_p - e_lin) ** 2
    hard = (eps > e_lin) & (eps <= eps_p)
    de = eps[hard] - e_lin
    s[hard] = 0.6 * peak + E * de - a * de ** 2
    post = eps > eps_p
    s[post] = peak - 1e11 * (eps[post] - eps_p)        # 100 MPa per 1e-3
    s[eps_p == eps] = peak
    lat = -nu * eps                                    # elastic lateral strain
    # dilation after the CD point: lateral strain grows faster than -eps_a
    i_cd = int(np.argmax(s >= 120e6))
    lat[i_cd:] = lat[i_cd] - 2.0 * (eps[i_cd:] - eps[i_cd])
    i_ci = int(np.argmax(s >= 90e6))
    n = np.zeros(eps.size)
    n[i_ci:] = 100 + np.arange(eps.size - i_ci) * 3
    return eps, lat, s, n, dict(E=E, nu=nu, peak=peak, ci=s[i_ci], cd=s[i_cd], eps_p=eps_p)


def test_docstring_examples():
    r = doctest.testmod(an)
    assert r.attempted >= 12 and r.failed == 0


def test_tangent_and_secant_modulus_on_linear_segment():
    eps, lat, s, n, ref = _constructed_curve()
    # window 40-60 % of 150 MPa lies in the exact linear part
    assert an.young_modulus(eps, s) == pytest.approx(ref["E"], rel=1e-9)
    # secant at 50 %: 75 MPa / (75 MPa / E) exactly
    assert an.young_modulus(eps, s, method="secant") == pytest.approx(ref["E"], rel=1e-9)
    # secant at 90 % lies on the curved part: strictly below E
    assert an.young_modulus(eps, s, method="secant", fraction=0.9) < 0.97 * ref["E"]


def test_poisson_ratio_and_summary():
    eps, lat, s, n, ref = _constructed_curve()
    assert an.poisson_ratio(eps, lat, s) == pytest.approx(ref["nu"], rel=1e-9)
    out = an.summarize_compression(eps, lat, s, n)
    assert out["E_gpa"] == pytest.approx(60.0, rel=1e-9)
    assert out["ucs_mpa"] == pytest.approx(150.0, rel=1e-12)
    assert out["peak_strain"] == pytest.approx(ref["eps_p"], abs=1e-12)
    assert out["ci_mpa"] == pytest.approx(ref["ci"] / 1e6, rel=1e-12)
    assert out["cd_mpa"] == pytest.approx(ref["cd"] / 1e6, rel=1e-12)
    assert 90.0 <= out["ci_mpa"] < 91.0 and 120.0 <= out["cd_mpa"] < 121.0


def test_ci_fraction_threshold():
    s = np.array([0, 10, 20, 30, 40, 50, 45.0])
    n = np.array([0, 1, 2, 20, 60, 100, 150])
    assert an.crack_initiation(s, n) == 10.0           # ceil(1 % of 100) = 1 crack
    assert an.crack_initiation(s, n, fraction=0.1) == 30.0   # 10 cracks
    assert math.isnan(an.crack_initiation(s, np.zeros(7)))


def test_cd_without_reversal_is_peak():
    s = np.array([0, 1, 2, 3, 2.0])
    v = np.array([0, 1, 2, 3, 4.0])
    assert an.crack_damage(s, v) == 3.0


def test_post_peak_stop_rule():
    s = [0, 40, 80, 100, 90, 81]
    assert not an.is_post_peak(s, fraction=0.8)
    assert an.is_post_peak(s + [79.9], fraction=0.8)
    assert not an.is_post_peak(s + [79.9], fraction=0.7)
    assert an.is_post_peak(s + [69.0], fraction=0.7)
    # still rising: never post-peak even if far below an earlier tiny blip with min_peak
    assert not an.is_post_peak([0, 1e3, 0.0], fraction=0.8, min_peak=1e6)
    with pytest.raises(ValueError, match="fraction"):
        an.is_post_peak(s, fraction=1.2)


def test_tension_and_brazilian_strengths():
    f = np.array([0, 1e6, 1.8e6, 0.5e6])
    assert an.tensile_strength(f, 0.1) == pytest.approx(18e6, rel=1e-12)
    # sigma_t = 2 P / (pi D t): P = 18e6 * pi * 0.05 / 2
    P = 18e6 * math.pi * 0.05 / 2
    assert an.brazilian_strength([0, P, 0.3 * P], 0.05) == pytest.approx(18e6, rel=1e-12)
    strain = np.linspace(0, 1e-3, 11)
    force = np.r_[np.linspace(0, 1.8e6, 10), 0.2e6]      # linear to the peak at 9e-4
    out = an.summarize_tension(strain, force, width=0.1)
    assert out["tensile_mpa"] == pytest.approx(18.0) and out["peak_strain"] == pytest.approx(9e-4)
    assert out["E_tension_gpa"] == pytest.approx(18e6 / 9e-4 / 1e9, rel=1e-9)
    with pytest.raises(ValueError, match="diameter"):
        an.brazilian_strength(f, 0.0)


def test_crack_counts_and_damage_ratio():
    kind = ["pb", "pb", "sj", "sj", "pb", "sj"]
    mode = ["tension", "shear", "tension", "shear", "tension", "tension"]
    rel = ["intra", "intra", "inter", "inter", "intra", "inter"]
    size = [2e-4, 1e-4, 3e-4, 1e-4, 2e-4, 1e-4]
    c = an.crack_counts(kind, mode, rel)
    assert c == {"pb_tension": 2, "pb_shear": 1, "sj_tension": 2, "sj_shear": 1, "total": 6,
                 "intra": 3, "inter": 3}
    d = an.damage_ratio(mode, size)
    assert d["by_count"] == 2.0
    assert d["by_area"] == pytest.approx(8e-4 / 2e-4, rel=1e-12)
    assert d["area_tension_m2"] == pytest.approx(8e-4) and d["n_shear"] == 2
    assert an.damage_ratio(["tension"], [1e-4])["by_area"] == math.inf
    assert math.isnan(an.damage_ratio([], [])["by_count"])


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="'strain'"):
        an.young_modulus([0, 1], [0, 1, 2])
    with pytest.raises(ValueError, match="'method'"):
        an.young_modulus([0, 1], [0, 1], method="chord")
    with pytest.raises(ValueError, match="empty"):
        an.peak_index([])
