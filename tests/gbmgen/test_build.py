"""build_specimen: the file loads with sim.Specimen, meta, packing quality, seeds."""
import numpy as np
import pytest
from _gbmgen_builds import small_specimen, table_4_1_path

from gbmgen import config
from gbmgen.build import build_specimen
from gbmgen.errors import InputError
from gbmgen.packing import particle_radii
from gbmgen.table import read_table
from sim.relax import max_overlap
from sim.specimen import Specimen


def test_specimen_roundtrip_and_meta(tmp_path):
    s = small_specimen()
    p = tmp_path / "s.npz"
    s.save(p)
    t = Specimen.load(p)
    for k in ("x", "y", "r", "grain", "mineral", "bond_i", "bond_kind", "grain_xy",
              "grain_offsets", "grain_mineral", "grain_class", "pb_ten", "sj_kn"):
        assert np.array_equal(getattr(t, k), getattr(s, k))
    m = t.meta
    assert m["schema_version"] == 1 and m["units"] == "SI" and m["seed"] == 7
    assert m["generator"] == "gbmgen" and m["generator_version"]
    assert m["source_table"].endswith("table_4_1.csv") and m["scenario"] == 1
    assert m["tessellation"] == "laguerre"
    assert m["MHI_target"] == pytest.approx(2.6308, abs=1e-3)
    assert m["MHI_realised"] > 0 and "minerals" in m["fidelity"]
    assert [str(v) for v in t.mineral_names] == ["pyroxene", "plagioclase", "biotite"]
    # thesis-ch4 preset values (REFERENCE.md Tables 4-3/4-4)
    np.testing.assert_allclose(t.pb_ten, [300e6, 330e6, 320e6])
    np.testing.assert_allclose(t.density, [2500, 2600, 2800])
    # joint stiffness 'bond': mean(pb_emod) / (2 r_mean), see gbmgen.params
    assert t.sj_kn[0] == pytest.approx(np.mean(t.pb_emod) / (2 * np.mean(t.r)), rel=1e-12)
    assert t.sj_fa[0] == 32.0


def test_packing_porosity_radius_range_overlap():
    s = small_specimen()
    rmin, rmax = particle_radii(1e-4, config.RADIUS_RATIO)
    assert s.r.min() >= rmin and s.r.max() <= rmax
    assert s.r.mean() == pytest.approx(1e-4, rel=0.03)
    area = 5e-3 * 10e-3
    assert 1 - np.sum(np.pi * s.r ** 2) / area == pytest.approx(config.POROSITY, abs=0.005)
    assert max_overlap(s.x, s.y, s.r, s.box) <= config.PARTICLE_OVERLAP_TOL + 1e-12
    # isotropic: contact normals have no preferred direction (second-moment fabric ~ I/2)
    i, j = s.bond_i, s.bond_j
    u = np.c_[s.x[j] - s.x[i], s.y[j] - s.y[i]]
    u /= np.linalg.norm(u, axis=1)[:, None]
    fabric = u.T @ u / len(u)
    assert abs(fabric[0, 0] - 0.5) < 0.05 and abs(fabric[0, 1]) < 0.05


def test_same_seed_same_specimen_other_seed_other_layout(tmp_path):
    a = small_specimen(7)
    t = read_table(table_4_1_path())
    b, _ = build_specimen(t, width_mm=5.0, height_mm=10.0, scenario=1, seed=7)
    for k in ("x", "y", "r", "grain", "mineral", "bond_i", "bond_j", "bond_kind", "joint_nx",
              "grain_xy", "grain_mineral"):
        assert np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True), k
    assert a.meta == b.meta
    a.save(tmp_path / "a.npz")
    b.save(tmp_path / "b.npz")
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    c = small_specimen(8)
    assert not np.array_equal(a.grain_mineral, c.grain_mineral[:a.n_grains]) \
        or a.n_grains != c.n_grains
    assert not np.allclose(a.x[:100], c.x[:100])


def test_controlled_specimen():
    s = small_specimen(3, shape="hexagon")
    assert s.meta["tessellation"] == "controlled" and s.meta["grains"]["shape"] == "hexagon"
    assert s.n_grains > 20 and np.all(s.grain >= 0)
    assert np.sum(s.bond_kind == 1) > 0


def test_build_errors():
    t = read_table(table_4_1_path())
    with pytest.raises(InputError, match="does not fit"):
        build_specimen(t, width_mm=5.0, height_mm=10.0, scale=10.0, seed=1)
    with pytest.raises(InputError, match="tessellation"):
        build_specimen(t, width_mm=5, height_mm=10, tessellation="delaunay", seed=1)
    with pytest.raises(InputError, match="width_mm"):
        build_specimen(t, width_mm=-5, height_mm=10, seed=1)
    with pytest.raises(InputError, match="no properties for mineral 'quartz'"):
        df = t.to_frame()
        df.loc[df.mineral == "biotite", "mineral"] = "quartz"
        from gbmgen.table import GrainSizeTable
        build_specimen(GrainSizeTable.from_frame(df), width_mm=5, height_mm=10, seed=1)
