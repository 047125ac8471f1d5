"""sim._io: atomic writes leave either the old file or the new one, never a partial file."""
import numpy as np
import pytest

from sim._io import save_npz_atomic, write_atomic


def test_failed_write_keeps_the_old_file_and_no_temporary(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")

    def bad(tmp):
        with open(tmp, "w") as f:
            f.write("half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_atomic(p, bad)
    assert p.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.txt"]


@pytest.mark.parametrize("compressed", [False, True])
def test_npz_round_trip(tmp_path, compressed):
    a = {"x": np.arange(5.0), "s": np.array("meta")}
    p = save_npz_atomic(tmp_path / "sub" / "c.npz", a, compressed=compressed)
    with np.load(p, allow_pickle=False) as z:
        np.testing.assert_array_equal(z["x"], a["x"])
        assert str(z["s"]) == "meta"
    assert sorted(x.name for x in (tmp_path / "sub").iterdir()) == ["c.npz"]


def test_write_atomic_gives_the_permissions_of_a_plain_file(tmp_path):
    """mkstemp creates 0600 files; results written through it follow the umask like open()."""
    import os
    old = os.umask(0o022)
    try:
        p = write_atomic(tmp_path / "a.txt", lambda t: open(t, "w").write("x"))
        with open(tmp_path / "b.txt", "w") as f:
            f.write("x")
    finally:
        os.umask(old)
    assert os.stat(p).st_mode & 0o777 == os.stat(tmp_path / "b.txt").st_mode & 0o777 == 0o644
