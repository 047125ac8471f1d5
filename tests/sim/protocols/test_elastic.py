"""E and ν read-out and its validity flags, and the representativeness rules (no engine)."""
import math

import numpy as np
import pandas as pd
import pytest

from sim import Specimen
from sim.protocols import elastic, gauges
from sim.protocols.representative import representativeness


def test_cell_area_of_a_lattice_gauge_is_exact():
    s = Specimen.lattice(nx=12, ny=14, radius=1e-3, gap=2e-3)
    idx = gauges.gauge_indices(s.x, s.y, s.box)
    spacing = s.meta["spacing_m"]
    assert gauges.cell_area(s.x, s.y, idx) == pytest.approx(
        idx.size * math.sqrt(3) / 2 * spacing ** 2, rel=1e-12)
    with pytest.raises(ValueError, match="edge of the packing"):
        gauges.cell_area(s.x, s.y, np.array([0]))


def _history(E=50e9, nu=0.25, n=40, *, speed=None, peak_at=30, sxx=0.0, nu_b=None):
    """A linear elastic compression history up to a peak, then a drop."""
    s = np.r_[np.linspace(0, 100e6, peak_at + 1), np.linspace(95e6, 60e6, n - peak_at - 1)]
    ga = (s - nu * sxx * s) / E                  # plane stress, sigma_xx = sxx * sigma_yy
    gl = (sxx * s - nu * s) / E
    nb = nu if nu_b is None else nu_b
    h = pd.DataFrame({
        "step": np.arange(n) * 100, "axial_stress_mpa": s / 1e6, "axial_strain": 1.05 * s / E,
        "gauge_stress_yy_mpa": s / 1e6, "gauge_stress_xx_mpa": sxx * s / 1e6,
        "gauge_axial_strain": ga, "gauge_lateral_strain": gl, "end_axial_strain": s / E,
        "lateral_strain": -nb * s / E, "kinetic_energy_j": np.full(n, 1e-9),
        "strain_energy_j": np.ones(n),
        "platen_velocity_m_per_s": np.full(n, 0.01) if speed is None else speed})
    return h


def test_gauge_reading_is_exact_and_flags_are_set():
    r = elastic.elastic_constants(_history(sxx=0.05))
    assert r["E_gpa"] == pytest.approx(50.0, rel=1e-9) and r["nu"] == pytest.approx(0.25)
    assert r["E_ok"] and r["nu_ok"] and r["elastic"]["source"] == "gauge"
    # platen strain 5 % larger than the gauge's: platen modulus 4.8 % lower, still valid
    assert r["elastic"]["E_platen_gpa"] == pytest.approx(50.0 / 1.05, rel=1e-9)
    assert "plane stress" in r["elastic"]["convention"]


def test_invalid_numbers_are_null_with_a_reason():
    h = _history(nu=0.6)
    r = elastic.elastic_constants(h)
    assert r["nu"] is None and not r["nu_ok"] and "outside [0, 0.5)" in r["nu_reason"]
    assert r["elastic"]["nu_measured"] == pytest.approx(0.6)
    h = _history()
    h["axial_strain"] *= 1.3                     # platen modulus 23 % below the gauge's
    r = elastic.elastic_constants(h)
    assert r["E_gpa"] is None and not r["E_ok"] and "15 %" in r["E_reason"]
    r = elastic.elastic_constants(_history(n=6, peak_at=3))
    assert not r["E_ok"] and "records between 40 % and 60 %" in r["E_reason"]


def test_a_crack_across_the_gauge_switches_to_the_steady_boundary_reading():
    h = _history(nu_b=0.2)
    gbox = np.array([0.0, 1.0, 0.0, 2.0])
    cracks = pd.DataFrame({"step": np.zeros(12), "x": np.linspace(0.02, 0.98, 12),
                           "y": np.full(12, 1.0)})
    r = elastic.elastic_constants(h, cracks, gauge_box=gbox, link=0.1)
    assert r["elastic"]["gauge_crossed_by_crack"] and r["elastic"]["source"] == "boundary"
    assert r["nu"] == pytest.approx(0.2) and r["nu_ok"]
    # the same with the platens changing speed every record: no steady record, invalid
    h["platen_velocity_m_per_s"] = 0.01 * (1 + np.arange(len(h)) % 2)
    r = elastic.elastic_constants(h, cracks, gauge_box=gbox, link=0.1)
    assert not r["E_ok"] and not r["nu_ok"] and "steady records" in r["E_reason"]
    # scattered cracks that do not span the gauge leave the gauge reading in use
    r = elastic.elastic_constants(_history(), cracks.iloc[::3], gauge_box=gbox, link=0.1)
    assert r["elastic"]["source"] == "gauge"


def test_steady_records_need_a_constant_speed_and_small_kinetic_energy():
    h = _history(speed=np.r_[np.linspace(0, 0.01, 5), np.full(35, 0.01)])
    ok = elastic.steady_records(h, first=5)
    assert not ok[:7].any() and ok[8:].all()
    h.loc[20, "kinetic_energy_j"] = 2e-3
    assert not elastic.steady_records(h, first=5)[20]


def test_representativeness_rules():
    from gbmgen.build import build_specimen
    from gbmgen.table import example_table
    small, _ = build_specimen(example_table("table-4-1"), width_mm=3, height_mm=6, seed=1,
                              particle_radius_mm=0.2)
    r = representativeness(small)
    assert not r["ok"] and len(r["warnings"]) == 2
    assert r["particles_per_grain"] < 10 and r["grains_across_width"] < 10
    assert "particle-radius" in r["warnings"][0] and "wider" in r["warnings"][1]
    assert representativeness(Specimen.lattice(nx=4, ny=4, radius=1e-3))["ok"]
