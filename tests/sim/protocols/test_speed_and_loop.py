"""Loading speed, loop, rig and gauge helpers: exact checks without the engine."""
import doctest

import numpy as np
import pytest

from sim import Specimen
from sim.protocols import elastic, gauges, loop, representative, rig, speed


@pytest.mark.parametrize("mod", [speed, loop, rig, gauges, elastic, representative])
def test_docstring_examples(mod):
    r = doctest.testmod(mod)
    assert r.attempted >= 1 and r.failed == 0


def test_gauge_strains_recover_an_affine_field_exactly():
    rng = np.random.default_rng(3)
    x0, y0 = rng.uniform(0, 1, 50), rng.uniform(0, 2, 50)
    F = np.array([[1 + 3e-4, 1e-4], [2e-4, 1 - 1e-3]])         # small strain + rotation part
    x = F[0, 0] * x0 + F[0, 1] * y0 + 0.01
    y = F[1, 0] * x0 + F[1, 1] * y0 - 0.02
    exx, eyy = gauges.gauge_strains(x0, y0, x, y, np.arange(50))
    assert exx == pytest.approx(-3e-4, abs=1e-15) and eyy == pytest.approx(1e-3, abs=1e-15)


def test_relieve_overlaps_leaves_no_overlap_and_changes_little():
    s = Specimen.lattice(nx=6, ny=5, radius=1e-3, gap=-4e-3)        # 0.8 % overlaps
    t, info = rig.relieve_overlaps(s)
    d = np.hypot(t.x[t.bond_j] - t.x[t.bond_i], t.y[t.bond_j] - t.y[t.bond_i])
    assert np.all(t.r[t.bond_i] + t.r[t.bond_j] <= d)
    assert info["max_overlap_rel"] == pytest.approx(0.008, rel=1e-6)
    assert info["max_radius_change_rel"] == pytest.approx(0.004, rel=1e-6)
    assert t.box[0] == pytest.approx((t.x - t.r).min()) and s.r[0] == 1e-3   # input unchanged
    u, info2 = rig.relieve_overlaps(Specimen.lattice(nx=3, ny=3, radius=1e-3, gap=1e-3))
    assert info2["n_overlaps"] == 0 and info2["max_radius_change_rel"] == 0.0


def test_loading_rate_and_stop_rule():
    assert speed.loading_rate(None, 0.0125, 0.05) == (0.5, 0.0125)
    with pytest.raises(ValueError, match="strain_rate"):
        speed.loading_rate(-1.0, 0.01, 0.05)
    rule = loop.StopRule(post_peak=0.8)
    e = [0, 1, 2, 3, 4]
    s = [0, 50e6, 100e6, 90e6, 70e6]
    assert rule.reason(e, s, n_cracks=0) is None           # no crack: wave noise, not failure
    assert rule.reason(e, s, n_cracks=5) == "post_peak"
    assert rule.reason(e, [0, 0.5e6, 0.1e6, 0, 0], n_cracks=5) is None   # peak below 1 MPa
    assert loop.StopRule(post_peak=None, max_strain=4).reason(e, s) == "max_strain"
    with pytest.raises(ValueError, match="never stop"):
        loop.StopRule(post_peak=None, max_strain=None)


def _rows(stress, cracks, ke=1e-9, se=1.0, de=2e-5):
    return [{"axial_stress_mpa": s, "axial_strain": i * de, "cracks_total": c,
             "kinetic_energy_j": ke, "strain_energy_j": se}
            for i, (s, c) in enumerate(zip(stress, cracks))]


def test_adaptive_speed_rises_while_elastic_and_keeps_the_base_speed_from_the_first_crack():
    sp = speed.AdaptiveSpeed()
    assert sp.f_max == 16.0 and speed.ADAPTIVE_BASE_VELOCITY == 0.00625
    lin = [float(i) for i in range(20)]
    f = [sp.update(_rows(lin[:n], [0] * n)) for n in range(1, 15)]
    # base speed for the first window + 1 records, then x1.5 per record up to 16
    assert f[:4] == [1.0] * 4
    assert f[4:9] == pytest.approx([1.5, 2.25, 3.375, 5.0625, 7.59375])
    assert f[11] == 16.0 and max(f) == 16.0
    # a crack: the base speed, and it stays there although no crack follows
    cracks = [0] * 12 + [1] * 8
    g = [sp.update(_rows(lin[:n], cracks[:n])) for n in range(13, 21)]
    assert g == [1.0] * 8
    # a crack during the start-up records counts too
    early = speed.AdaptiveSpeed()
    assert [early.update(_rows(lin[:n], [1] * n)) for n in range(1, 15)] == [1.0] * 14
    # softening: tangent at half of the largest seen -> base speed
    sp3 = speed.AdaptiveSpeed(factor=16.0)
    soft = lin[:10] + [9.5, 10.0, 10.5]
    assert sp3.update(_rows(soft[:10], [0] * 10)) == 16.0
    assert sp3.update(_rows(soft, [0] * 13)) == 1.0
    # after the peak (stress below 0.995 x the running maximum) -> base speed
    sp4 = speed.AdaptiveSpeed(factor=16.0)
    assert sp4.update(_rows(lin[:10] + [8.9], [0] * 11)) == 1.0


def test_adaptive_speed_kinetic_energy_cap():
    """KE/SE = 4 x ke_ratio caps the factor at half of the current one (KE grows as v^2)."""
    sp = speed.AdaptiveSpeed(factor=8.0)
    lin = [float(i) for i in range(12)]
    assert sp.update(_rows(lin, [0] * 12, ke=4e-3, se=1.0)) == pytest.approx(4.0)
    # never below the base speed
    sp = speed.AdaptiveSpeed(factor=1.5)
    assert sp.update(_rows(lin, [0] * 12, ke=1.0, se=1.0)) == 1.0


def test_adaptive_speeds_keep_the_8mm_rule_and_fix_the_cracking_strain_rate_beyond():
    # up to 8 mm: the validated base speed and 16x; beyond: strain rate 1.5625/s, fast <= 0.1
    assert speed.adaptive_speeds(0.004) == (0.00625, 16.0)
    assert speed.adaptive_speeds(0.008) == (0.00625, 16.0)
    for L in (0.02, 0.05, 0.2):
        v, f = speed.adaptive_speeds(L)
        assert 2 * v / L == pytest.approx(speed.ADAPTIVE_BASE_STRAIN_RATE)
        assert v * f == pytest.approx(max(v, 0.1))
    assert speed.adaptive_speeds(0.05)[0] == pytest.approx(0.0390625)
    assert speed.adaptive_speeds(0.2) == (pytest.approx(0.15625), 1.0)


def test_adaptive_speed_option_slows_below_the_base_near_and_after_the_peak():
    """f_peak < 1 caps the factor while the tangent is below tan_peak x its maximum and after
    the peak; f_peak = 1 (the default) keeps the rule as it was."""
    lin = [float(i) for i in range(20)]
    # tangent ratio 0.7: between tan_slow (0.6) and tan_peak (0.75)
    near = lin[:10] + [9.7, 10.4, 11.1]

    def last(sp, stress):               # feed the records one by one (the rule keeps a max)
        return [sp.update(_rows(stress[:n], [0] * n)) for n in range(1, len(stress) + 1)][-1]

    assert last(speed.AdaptiveSpeed(), near) == pytest.approx(1 + 15 * (0.7 - 0.6) / (0.85 - 0.6))
    assert last(speed.AdaptiveSpeed(f_peak=0.5), near) == 0.5
    after = lin[:10] + [8.9]
    assert speed.AdaptiveSpeed(factor=2.0, f_peak=0.5).update(_rows(after, [0] * 11)) == 0.5
    assert speed.AdaptiveSpeed(factor=2.0).update(_rows(after, [0] * 11)) == 1.0
    # the elastic phase is untouched; the KE cap never lifts the factor back above f_peak
    el = speed.AdaptiveSpeed(factor=16.0, f_peak=0.5)
    assert el.update(_rows(lin[:12], [0] * 12)) == 16.0
    assert speed.AdaptiveSpeed(factor=1.0, f_peak=0.5).update(
        _rows(after, [0] * 11, ke=1.0, se=1.0)) == 0.5
