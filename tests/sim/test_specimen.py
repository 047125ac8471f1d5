import json

import numpy as np
import pytest

from sim import InputError, Specimen


def test_lattice_counts_and_bond_lengths():
    s = Specimen.lattice(nx=5, ny=4, radius=1e-3)
    assert s.n_particles == 20
    # interior rows: 4 horizontal per row x4 rows + 2 diagonals per particle between rows
    assert s.n_bonds == 4 * 4 + 3 * (5 + 4)
    d = np.hypot(s.x[s.bond_j] - s.x[s.bond_i], s.y[s.bond_j] - s.y[s.bond_i])
    np.testing.assert_allclose(d, 2e-3, rtol=1e-12)


def test_round_trip_is_exact(tmp_path):
    s = Specimen.lattice(nx=3, ny=3, radius=2e-3, gap=1e-3)
    s.meta["seed"] = 7
    p = tmp_path / "s.npz"
    s.save(p)
    t = Specimen.load(p)
    for k, v in s.to_arrays().items():
        if k == "meta":
            assert json.loads(str(v)) == json.loads(str(t.to_arrays()["meta"]))
        else:
            np.testing.assert_array_equal(v, getattr(t, k), err_msg=k)
    assert t.meta["seed"] == 7 and t.meta["schema_version"] == 1


def test_hand_written_minimal_file_loads(tmp_path):
    """DESIGN.md §4: particle, mineral-table, bond and box keys only -> loads, no grains."""
    s = Specimen.lattice(nx=3, ny=2, radius=1e-3)
    keep = ["x", "y", "r", "mineral", "mineral_names", "density", "emod", "kratio", "fric",
            "pb_emod", "pb_kratio", "pb_ten", "pb_coh", "pb_fa", "pb_rmul",
            "bond_i", "bond_j", "box"]
    p = tmp_path / "min.npz"
    np.savez(p, **{k: getattr(s, k) for k in keep})
    t = Specimen.load(p)
    assert t.n_grains == 0 and np.all(t.grain == -1) and not t.has_joints
    assert np.all(t.bond_kind == 0) and t.n_bonds == s.n_bonds


@pytest.mark.parametrize("field,value,word", [
    ("r", lambda s: -s.r, "'r'"),
    ("bond_j", lambda s: s.bond_j * 0, "'bond_i'"),
    ("box", lambda s: s.box[[1, 0, 2, 3]], "'box'"),
    ("emod", lambda s: s.emod * np.nan, "'emod'"),
])
def test_bad_fields_are_named(tmp_path, field, value, word):
    s = Specimen.lattice(nx=3, ny=2, radius=1e-3)
    arrays = s.to_arrays()
    arrays[field] = value(s)
    p = tmp_path / "bad.npz"
    np.savez(p, **arrays)
    with pytest.raises(InputError, match=word):
        Specimen.load(p)


def test_missing_and_corrupt_files(tmp_path):
    with pytest.raises(InputError, match="not found"):
        Specimen.load(tmp_path / "nope.npz")
    p = tmp_path / "junk.npz"
    p.write_bytes(b"not a zip")
    with pytest.raises(InputError, match="junk.npz"):
        Specimen.load(p)


def test_failed_save_leaves_nothing(tmp_path):
    s = Specimen.lattice(nx=3, ny=2, radius=1e-3)
    s.r[0] = -1.0
    with pytest.raises(InputError):
        s.save(tmp_path / "s.npz")
    assert list(tmp_path.iterdir()) == []
