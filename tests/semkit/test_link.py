"""Linking of faint, beaded cracks (semkit.link): beads joined by a faint line become one crack;
a fainter line (a grain boundary's depth) between the same beads does not join them. Linking
is opt-in (``link=True``, ``--link``)."""
import numpy as np
import pytest

from semkit.analysis import analyse_image
from semkit.link import add_link_lines, line_response


def _beaded(line_grey, width, seed=3):
    """Six dark elongated beads on a line from (20, 110) to (200, 50), joined by a line of
    ``line_grey`` (background 120), plus one clear crack (the crack core grey)."""
    import cv2
    rng = np.random.default_rng(seed)
    img = np.full((160, 220), 120.0)
    cv2.line(img, (20, 110), (200, 50), line_grey, width, cv2.LINE_AA)
    for t in np.linspace(0.1, 0.9, 6):
        cv2.ellipse(img, (int(20 + t * 180), int(110 - t * 60)), (5, 2), -18.4, 0, 360, 30.0,
                    -1)
    cv2.rectangle(img, (60, 130), (140, 134), 10.0, -1)
    img += rng.normal(0, 2, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def test_beads_joined_by_a_faint_line_become_one_crack():
    img = _beaded(106.0, 2)
    pieces = analyse_image(img, pixel_size_um=1.0, flatten="none", link=False).cracks
    linked = analyse_image(img, pixel_size_um=1.0, flatten="none", link=True).cracks
    assert len(pieces) >= 7 and pieces.length_px.max() < 100  # beads, the clear crack
    assert len(linked) == 2
    assert linked.length_px.max() == pytest.approx(np.hypot(180, 60), rel=0.1)


@pytest.mark.parametrize("line_grey", [104.0, 112.0])
def test_a_boundary_deep_line_does_not_join_beads(line_grey):
    img = _beaded(line_grey, 1)
    a = analyse_image(img, pixel_size_um=1.0, flatten="none", link=True)
    b = analyse_image(img, pixel_size_um=1.0, flatten="none", link=False)
    assert sorted(a.cracks.length_px) == pytest.approx(sorted(b.cracks.length_px))


def test_line_response_prefers_lines_to_dots():
    img = np.full((60, 60), 100, np.float32)
    img[20, 5:55] = 70
    img[45, 30] = 70
    r, noise = line_response(img)
    assert r[20, 30] > 3 * r[45, 30] and noise > 0


def test_added_piece_closing_a_loop_is_left_out():
    d = np.zeros((30, 30), bool)
    d[5, 5:25] = d[25, 5:25] = d[5:26, 5] = True
    ring = d.copy()
    ring[5:26, 24] = True
    grey = np.where(ring, 20.0, 100.0).astype(np.float32)
    out, _ = add_link_lines(d, d, ring, grey, np.zeros(d.shape, np.float32), crack_level=0.0)
    assert not out[15, 24] and (out == d).all()
