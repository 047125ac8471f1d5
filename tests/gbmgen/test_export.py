"""PFC .geom round trip through our reader; VTK files; PNG preview."""
import numpy as np
import pytest
from _gbmgen_builds import small_specimen

from gbmgen.errors import InputError
from gbmgen.export import export_geom, export_vtk, read_geom
from sim.specimen import Specimen


def test_geom_roundtrip(tmp_path):
    s = small_specimen()
    p = tmp_path / "g.geom"
    counts = export_geom(s, p, name="test")
    text = p.read_text().splitlines()
    assert text[0] == "ITASCA GEOMETRY3D"
    assert text[3].startswith("1 (") and "POLYS" in text and "EDGES" in text
    g = read_geom(p)
    assert g["offsets"].size - 1 == s.n_grains == counts["polys"]
    np.testing.assert_array_equal(g["offsets"], s.grain_offsets)
    np.testing.assert_allclose(g["xy"], s.grain_xy, rtol=0, atol=1e-12 * 10e-3)
    names = [str(v) for v in s.mineral_names]
    assert g["groups"] == [names[m] for m in s.grain_mineral]
    # nodes are shared between neighbouring grains; edges counted once (Euler: V - E + F = 1)
    assert counts["nodes"] < s.grain_xy.shape[0]
    assert counts["nodes"] - counts["edges"] + counts["polys"] == 1
    assert g["edges"].shape == (counts["edges"], 2)


def test_geom_reader_errors(tmp_path):
    p = tmp_path / "bad.geom"
    p.write_text("ITASCA GEOMETRY3D\nNODES\n1 (0,0,0)\nPOLYS\n1 NODE 1 7\n")
    with pytest.raises(InputError, match="line 5: unknown node"):
        read_geom(p)
    p.write_text("something else\n")
    with pytest.raises(InputError, match="line 1"):
        read_geom(p)


def test_geom_needs_grains(tmp_path):
    with pytest.raises(InputError, match="grain_offsets"):
        export_geom(Specimen.lattice(3, 3, 1e-3), tmp_path / "x.geom")


def test_vtk_files(tmp_path):
    s = small_specimen()
    paths = export_vtk(s, tmp_path / "s")
    part = open(paths[0]).read().split("\n")
    assert part[4] == f"POINTS {s.n_particles} double"
    assert f"CELLS {s.n_particles} {2 * s.n_particles}" in part
    i = part.index("SCALARS radius double 1")
    np.testing.assert_allclose(np.array(part[i + 2:i + 2 + s.n_particles], float), s.r)
    grains = open(paths[1]).read().split("\n")
    assert f"CELLS {s.n_grains} {s.grain_xy.shape[0] + s.n_grains}" in grains
    import meshio
    m = meshio.read(paths[1])
    assert m.points.shape == (s.grain_xy.shape[0], 3)
    assert sum(len(c.data) for c in m.cells) == s.n_grains  # meshio splits by vertex count
    i = grains.index("SCALARS mineral int 1")
    np.testing.assert_array_equal(np.array(grains[i + 2:i + 2 + s.n_grains], int),
                                  s.grain_mineral)
    mp = meshio.read(paths[0])
    np.testing.assert_allclose(mp.point_data["radius"].ravel(), s.r)
    np.testing.assert_array_equal(mp.point_data["grain"].ravel(), s.grain)


def test_plot_writes_png(tmp_path):
    from gbmgen.plot import plot_specimen
    p = plot_specimen(small_specimen(), tmp_path / "s.png", particles=True, joints=True)
    data = open(p, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
