"""Defects (Ch. 6): holes placed intra/inter/trans grain cut 1/2/3/4 grains; double holes; flaws."""
import functools

import numpy as np
import pytest

from gbmgen.build import build_specimen
from gbmgen.cli import main
from gbmgen.defects import (
    HOLE_KINDS,
    cut_flaw,
    cut_holes,
    double_hole_centres,
    grains_cut,
    place_hole,
)
from gbmgen.errors import InputError
from sim.specimen import Specimen


@functools.lru_cache(maxsize=None)
def _hex_specimen():
    # homogeneous pyroxene, hexagonal grains of 4 mm equivalent diameter, 0.3 mm particles
    spec, _ = build_specimen(None, width_mm=12, height_mm=20, shape="hexagon",
                             grain_area_mm2=np.pi * 4.0, particle_radius_mm=0.3, seed=1)
    return spec


def _polygon_overlaps_disk(poly, c, r):
    """Independent check: disk overlaps polygon if centre inside or an edge within r."""
    a, b = poly, np.roll(poly, -1, axis=0)
    e = b - a
    t = np.clip(np.sum((c - a) * e, axis=1) / np.sum(e * e, axis=1), 0, 1)
    d = np.hypot(*(a + t[:, None] * e - c).T)
    x1, y1, x2, y2 = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    cond = (y1 > c[1]) != (y2 > c[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x1 + (c[1] - y1) * (x2 - x1) / (y2 - y1)
    inside = np.sum(cond & (c[0] < xc)) % 2 == 1
    return inside or d.min() < r


@pytest.mark.parametrize("kind, diameter_mm", [("intra", 3.0), ("inter", 2.0), ("trans3", 3.0),
                                               ("trans4", 3.0)])
def test_hole_cuts_the_right_number_of_grains(kind, diameter_mm):
    s = _hex_specimen()
    r = 0.5e-3 * diameter_mm
    c = place_hole(s, kind, r)
    hit = [g for g in range(s.n_grains) if _polygon_overlaps_disk(s.grain_polygon(g), c, r)]
    assert len(hit) == HOLE_KINDS[kind]
    assert grains_cut(s, c, r).tolist() == hit
    out = cut_holes(s, [c], r, kind=kind)
    removed = np.hypot(s.x - c[0], s.y - c[1]) < r
    assert out.n_particles == s.n_particles - removed.sum() and removed.sum() > 5
    assert np.all(np.hypot(out.x - c[0], out.y - c[1]) >= r)
    # bonds renumbered: every bond of the new specimen joins the same two (kept) particles
    keep = np.flatnonzero(~removed)
    old = set(zip(s.bond_i.tolist(), s.bond_j.tolist()))
    assert all((keep[i], keep[j]) in old for i, j in zip(out.bond_i[:200], out.bond_j[:200]))
    assert out.meta["defects"][-1]["grains_cut"] == [hit]


def test_double_hole_geometry_and_flaw():
    c = double_hole_centres([0.0, 0.0], 1.5, 0.75, 60.0)
    assert np.hypot(*(c[1] - c[0])) - 3.0 == pytest.approx(0.75)  # wall-to-wall bridge
    assert np.degrees(np.arctan2(*(c[1] - c[0])[::-1])) == pytest.approx(60.0)
    s = _hex_specimen()
    f = cut_flaw(s, [6e-3, 10e-3], 8e-3, 0.6e-3, 30.0)
    u = np.array([np.cos(np.radians(30)), np.sin(np.radians(30))])
    d = np.c_[f.x - 6e-3, f.y - 10e-3]
    inside = (np.abs(d @ u) <= 4e-3) & (np.abs(d @ np.array([-u[1], u[0]])) <= 0.3e-3)
    assert not inside.any() and s.n_particles - f.n_particles > 10


def test_hole_errors():
    s = _hex_specimen()
    with pytest.raises(InputError, match="hole kind"):
        place_hole(s, "quad", 1e-3)
    with pytest.raises(InputError, match="cuts exactly 1"):
        place_hole(s, "intra", 5e-3)  # larger than any grain


def test_cli_defect(tmp_path, capsys):
    p = tmp_path / "s.npz"
    _hex_specimen().save(p)
    out = tmp_path / "h.npz"
    assert main(["defect", str(p), "--hole", "trans3", "--diameter-mm", "3", "--out",
                 str(out)]) == 0
    assert len(Specimen.load(out).meta["defects"][0]["grains_cut"][0]) == 3
    assert main(["defect", str(p), "--double-hole", "--diameter-mm", "3", "--bridge-mm", "1.5",
                 "--angle-deg", "45", "--out", str(out)]) == 0
    assert Specimen.load(out).meta["defects"][0]["kind"] == "double"
    assert main(["defect", str(p), "--out", str(out)]) == 2
