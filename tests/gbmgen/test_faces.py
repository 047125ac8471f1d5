"""Face seating: the packing touches every stretch of the box faces (flat specimen ends)."""
import numpy as np
import pytest

from gbmgen import config
from gbmgen.faces import face_openings, seat_faces
from gbmgen.packing import pack_particles, particle_radii
from sim.relax import max_overlap

R = 1e-4


def test_face_openings_measures_the_longest_untouched_stretch():
    box = np.array([0.0, 10e-3, 0.0, 10e-3])
    # three particles on the bottom face at x = 1, 2, 5 mm, one deep inside
    x = np.array([1e-3, 2e-3, 5e-3, 5e-3])
    y = np.array([R, R, R + 1e-7, 5e-3])
    r = np.full(4, R)
    got = face_openings(x, y, r, box)
    np.testing.assert_allclose(got, [10e-3, 10e-3, 5e-3, 10e-3])
    # a particle 3 um off the face does not touch it (tolerance 2 % of 0.1 mm)
    y[2] = R + 3e-6
    assert face_openings(x, y, r, box)[2] == pytest.approx(8e-3)


@pytest.fixture(scope="module")
def dented():
    """A relaxed 4 x 4 mm packing with a 2 mm long, 0.3 mm deep dent cut in its top face."""
    box = np.array([0.0, 4e-3, 0.0, 4e-3])
    x, y, r, _ = pack_particles(box, radius_mean_m=R, rng=np.random.default_rng(3),
                                seat_faces=False)
    cut = (x > 1e-3) & (x < 3e-3) & (y + r > box[3] - 0.3e-3)
    return box, x[~cut], y[~cut], r[~cut], int(cut.sum())


def test_seat_faces_closes_a_dent_without_overlap(dented):
    box, x, y, r, n_cut = dented
    before = face_openings(x, y, r, box)
    assert before[3] > 2e-3                     # the dent: nothing touches the top for 2 mm
    rmin, rmax = particle_radii(R, config.RADIUS_RATIO)
    xs, ys, rs, info = seat_faces(x, y, r, box, rmin=rmin, rmax=rmax,
                                  rng=np.random.default_rng(0))
    limit = config.SEAT_MAX_OPEN_DIAMETERS * (rmin + rmax)
    after = face_openings(xs, ys, rs, box)
    assert np.all(after <= limit + 1e-12), after
    np.testing.assert_allclose(info["longest_open_m"]["before"], before)
    np.testing.assert_allclose(info["longest_open_m"]["after"], after)
    # the dent is filled by new particles drawn from the packing's radius range
    assert 1 <= info["added"] <= n_cut + 10 and xs.size == x.size + info["added"]
    assert np.all((rs[x.size:] >= rmin) & (rs[x.size:] <= rmax))
    assert info["converged"]
    assert max_overlap(xs, ys, rs, box) <= config.PARTICLE_OVERLAP_TOL + 1e-9
    # the interior is not rearranged: the relaxation settles its overlaps by micrometres
    inner = (np.minimum.reduce([x - box[0], box[1] - x, y - box[2], box[3] - y]) > 1e-3)
    moved = np.hypot(xs[:x.size] - x, ys[:x.size] - y)
    assert np.median(moved[inner]) < 0.1 * R and moved[inner].max() < 0.5 * R


def test_build_specimen_seats_faces_by_default(table41):
    from gbmgen.build import build_specimen
    kw = dict(width_mm=4, height_mm=8, scenario=4, particle_radius_mm=0.1, seed=11)
    on, _ = build_specimen(table41, **kw)
    off, _ = build_specimen(table41, seat_faces=False, **kw)
    rmin, rmax = particle_radii(R, config.RADIUS_RATIO)
    limit = config.SEAT_MAX_OPEN_DIAMETERS * (rmin + rmax)
    seat = on.meta["particles"]["seating"]
    assert seat is not None and off.meta["particles"]["seating"] is None
    assert np.all(face_openings(on.x, on.y, on.r, on.box) <= limit + 1e-12)
    assert face_openings(off.x, off.y, off.r, off.box).max() > limit
    assert on.n_particles == off.n_particles + seat["added"]
    # the grains do not change with the particle settings
    np.testing.assert_array_equal(on.grain_xy, off.grain_xy)
