"""Ring plans and opening geometry (issue 17)."""
import numpy as np
import pytest

from gbmgen.errors import InputError
from gbmgen.field import openings as op
from gbmgen.field.plan import load_plan, plan_from_dict
from sim.field_geometry import polygon_area, ray_exit_distance


def test_thesis_plan_is_table_7_4_and_fills_40_m():
    p = load_plan("thesis-ch7")
    assert p.n_rings == 9
    assert np.allclose(1e3 * p.particle_r, [23, 40, 58, 88, 123, 164, 210, 261, 317])
    assert np.allclose(1e3 * p.grain_rmin[[0, 8]], [80, 1204])
    assert np.allclose(1e3 * p.grain_rmax[[0, 8]], [100, 1399])
    # core (4.5 m) + the nine thicknesses on each side = the 40 m domain
    assert 2 * (p.core_half + p.outer[-1]) == pytest.approx(40.0, abs=1e-9)
    # ring of points along the x axis: edges at 2.25 + cumulative thickness
    edges = p.core_half + p.outer
    x = np.r_[0.0, edges[:-1] - 1e-6, edges[:-1] + 1e-6]
    k = p.ring_of(x, np.zeros_like(x), [[0.0, 0.0]])
    assert k[0] == 1
    assert np.array_equal(k[1:9], np.arange(1, 9))
    assert np.array_equal(k[9:], np.arange(2, 10))
    # square rings: the corner point (e, e) is in the same ring as (e, 0)
    assert p.ring_of([3.0], [3.0], [[0, 0]])[0] == p.ring_of([3.0], [0.0], [[0, 0]])[0]


def test_plan_from_csv_and_named_errors(tmp_path):
    f = tmp_path / "plan.csv"
    f.write_text("thickness_m,grain_rmin_mm,grain_rmax_mm,particle_radius_mm\n1,80,100,20\n"
                 "2,160,200,40\n")
    p = load_plan(str(f))
    assert p.n_rings == 2 and np.allclose(p.particle_r, [0.02, 0.04])
    with pytest.raises(InputError, match="ring 2 grain_rmax_mm"):
        plan_from_dict({"rings": [[1, 80, 100, 20], [1, 200, 100, 40]]})
    with pytest.raises(InputError, match="ring 1 particle_radius_mm"):
        plan_from_dict({"rings": [[1, 80, 100, -2]]})
    with pytest.raises(InputError, match="mineral_fractions sum"):
        plan_from_dict({"rings": [[1, 80, 100, 20]], "mineral_fractions": {"a": 0.5}})


def test_drive_profile_is_appendix_d():
    d = op.drive()
    p = np.asarray(d["polygon"])
    for corner in ([-2.25, -2.5], [2.25, -2.5], [2.25, 0.25], [-2.25, 0.25]):
        assert np.min(np.hypot(*(p - corner).T)) < 1e-12
    assert p[:, 0].min() == pytest.approx(-2.25) and p[:, 0].max() == pytest.approx(2.25)
    assert p[:, 1].min() == pytest.approx(-2.5) and p[:, 1].max() == pytest.approx(2.5)
    # area = box 4.5 x 2.75 + half circle r 2.25 (sampled arch: 1e-4 relative)
    assert polygon_area(p) == pytest.approx(4.5 * 2.75 + 0.5 * np.pi * 2.25 ** 2, rel=1e-4)
    # arch points lie on the circle r = 2.25 about (0, 0.25)
    arch = p[p[:, 1] > 0.25 + 1e-9]
    assert np.allclose(np.hypot(arch[:, 0], arch[:, 1] - 0.25), 2.25, atol=1e-12)
    # crown from the origin along +y: 2.5 m; sidewall along +x: 2.25 m
    assert ray_exit_distance(p, (0, 0), np.radians([90.0, 0.0])) == pytest.approx([2.5, 2.25])


@pytest.mark.parametrize("dip", [55.0, 65.0, 75.0])
def test_two_drives_dip_spacing_and_stope_width(dip):
    lo, up = op.two_drives(dip_deg=dip, spacing_m=20.0)
    (xl, yl), (xu, yu) = lo["origin"], up["origin"]
    assert yu - yl == pytest.approx(20.0, abs=1e-12)
    assert np.degrees(np.arctan2(yu - yl, xu - xl)) == pytest.approx(dip, abs=1e-12)
    s = op.stope(lo, up, width_m=3.0)
    q = np.asarray(s["polygon"])
    # the two long sides are parallel to the dip, 3.0 m apart normal to it
    t = np.array([np.cos(np.radians(dip)), np.sin(np.radians(dip))])
    nrm = np.array([-t[1], t[0]])
    for a, b in ((0, 3), (1, 2)):
        e = (q[b] - q[a]) / np.linalg.norm(q[b] - q[a])
        assert abs(abs(e @ t) - 1) < 1e-12
    assert abs((q[1] - q[0]) @ nrm) == pytest.approx(3.0, abs=1e-12)
    # the stope ends on the two levels
    assert sorted({round(v, 9) for v in q[:, 1]}) == pytest.approx([yl, yu])
    with pytest.raises(InputError, match="dip"):
        op.two_drives(dip_deg=95)
