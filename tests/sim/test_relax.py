"""sim.relax: overlap relaxation of disk packings (the packing step gbmgen uses)."""
import numpy as np
import pytest

from sim.errors import InputError
from sim.relax import max_overlap, relax_overlaps


def _brute_worst(x, y, r, box):
    d = np.hypot(x[:, None] - x[None], y[:, None] - y[None])
    rel = (r[:, None] + r[None] - d) / np.minimum(r[:, None], r[None])
    np.fill_diagonal(rel, -np.inf)
    pen = np.max(np.c_[box[0] + r - x, x + r - box[1], box[2] + r - y, y + r - box[3]], axis=1)
    return max(rel.max(), (pen / r).max(), 0.0)


def test_two_disks_pushed_apart_mass_weighted():
    # radii 1 and 2 overlapping by 1.5; the small disk moves ~4x as far as the large one
    x, y, info = relax_overlaps([0.0, 1.5], [0.0, 0.0], [1.0, 2.0], [-20, 20, -20, 20],
                                tol=1e-6)
    assert info["converged"]
    d = x[1] - x[0]
    assert 3.0 * (1 - 1e-6) <= d <= 3.0 + 0.1 * 1.5  # momentum may overshoot a little
    np.testing.assert_allclose(y, 0.0)
    assert (0.0 - x[0]) / (x[1] - 1.5) == pytest.approx(4.0, rel=0.05)


def test_walls_push_inside():
    x, y, info = relax_overlaps([0.2, 9.9], [5.0, 0.5], [1.0, 1.0], [0, 10, 0, 10], tol=1e-6)
    assert info["converged"]
    assert x[0] >= 1.0 - 1e-6 and x[1] <= 9.0 + 1e-6 and y[1] >= 1.0 - 1e-6


def test_random_packing_reaches_tol_and_matches_brute_force():
    rng = np.random.default_rng(3)
    n, box = 600, np.array([0.0, 1.0, 0.0, 2.0])
    r = rng.uniform(0.015, 0.025, n)
    r *= np.sqrt(0.78 * 2.0 / np.sum(np.pi * r * r))
    x = rng.uniform(r, 1 - r)
    y = rng.uniform(r, 2 - r)
    assert _brute_worst(x, y, r, box) > 0.5
    X, Y, info = relax_overlaps(x, y, r, box, tol=0.02, max_iter=20000)
    assert info["converged"] and info["max_overlap"] <= 0.02
    worst = _brute_worst(X, Y, r, box)
    assert worst <= 0.02 + 1e-12
    assert max_overlap(X, Y, r, box) == pytest.approx(worst, abs=1e-12)
    # inputs untouched; deterministic
    assert _brute_worst(x, y, r, box) > 0.5
    X2, Y2, _ = relax_overlaps(x, y, r, box, tol=0.02, max_iter=20000)
    assert np.array_equal(X, X2) and np.array_equal(Y, Y2)


def test_wide_size_ratio():
    rng = np.random.default_rng(5)
    r = np.exp(rng.uniform(np.log(0.005), np.log(0.12), 400))
    r *= np.sqrt(0.75 * 4.0 / np.sum(np.pi * r * r))
    box = np.array([0.0, 2.0, 0.0, 2.0])
    x = rng.uniform(r, 2 - r)
    y = rng.uniform(r, 2 - r)
    X, Y, info = relax_overlaps(x, y, r, box, tol=0.05, max_iter=20000)
    assert info["converged"]
    assert _brute_worst(X, Y, r, box) <= 0.05 + 1e-12


def test_no_overlap_no_move():
    x, y, info = relax_overlaps([0.0, 3.0], [0.0, 0.0], [1.0, 1.0], [-5, 5, -5, 5])
    assert info["iterations"] == 0 and x.tolist() == [0.0, 3.0]


@pytest.mark.parametrize("kw, match", [
    (dict(r=[1.0, -1.0]), "r:"), (dict(box=[0, -1, 0, 1]), "box"),
    (dict(x=[0.0, np.nan]), "x:"), (dict(y=[0.0]), "y:"),
])
def test_bad_input(kw, match):
    args = dict(x=[0.0, 1.0], y=[0.0, 0.0], r=[0.4, 0.4], box=[-5, 5, -5, 5])
    args.update(kw)
    with pytest.raises(InputError, match=match):
        relax_overlaps(args["x"], args["y"], args["r"], args["box"])
