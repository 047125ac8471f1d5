"""semkit.ridge: fusing ridge lines with the threshold's masks."""
import numpy as np
import pytest

from semkit.ridge import add_ridge_lines
from semkit.robust import group_medians


def test_group_medians_are_numpys():
    rng = np.random.default_rng(0)
    groups = rng.integers(0, 6, 200)
    values = rng.normal(size=200)
    counts = np.bincount(groups, minlength=7)   # group 6 is empty
    got = group_medians(values, groups, counts)
    want = [np.median(values[groups == k]) if counts[k] else np.nan for k in range(7)]
    np.testing.assert_allclose(got, want, equal_nan=True)


def _line_half_found(depth_beyond, beyond_px=40):
    """A ridge line along row 20 from column 10; the threshold found columns 10-49 of it;
    the rest (``beyond_px`` px) lies ``depth_beyond`` deep."""
    shape = (40, 120)
    ridge = np.zeros(shape, bool)
    ridge[20, 10:50 + beyond_px] = True
    detect = np.zeros(shape, bool)
    detect[19:22, 10:50] = True
    depth = np.zeros(shape, np.float32)
    depth[20, 10:50] = 0.9
    depth[20, 50:50 + beyond_px] = depth_beyond
    return detect, detect.copy(), ridge, depth


@pytest.mark.parametrize("depth_beyond, beyond_px, added", [
    (0.3, 40, True),     # a faint continuation, deep enough: a crack found in part
    (0.15, 40, False),   # shallower than a line the detector starts on: a boundary, maybe
    (0.3, 6, False),     # too short to judge
])
def test_a_touching_lines_pieces_beyond_the_object_are_added_when_deep_and_long(
        depth_beyond, beyond_px, added):
    detect, area, ridge, depth = _line_half_found(depth_beyond, beyond_px)
    det, ar, cont = add_ridge_lines(detect, area, ridge, depth, return_continuations=True)
    beyond = np.zeros(ridge.shape, bool)
    beyond[20, 50:50 + beyond_px] = True
    assert (det[beyond]).all() == added and (cont == (beyond if added else False)).all()
    assert (det & ~beyond == detect).all()       # the object itself keeps its shape
    assert not (ar & beyond).any()               # thin and shallow: no midpoint area
    # without continuations the touching line adds nothing, as before
    det0, _ = add_ridge_lines(detect, area, ridge, depth, continuations=False)
    assert (det0 == detect).all()


def test_a_line_apart_from_every_object_is_added_whole():
    detect, area, ridge, depth = _line_half_found(0.3)
    ridge[5, 20:60] = True
    depth[5, 20:60] = 0.6
    det, ar = add_ridge_lines(detect, area, ridge, depth)
    assert det[5, 20:60].all() and ar[5, 20:60].all()   # 0.6 >= AUTO_AREA_FRACTION
