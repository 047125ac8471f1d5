"""Results do not depend on the thread count: the step loop's chunk count fixes the order in
which the forces on a particle are summed (``config.FORCE_CHUNKS``, ``SIM_FORCE_CHUNKS``)."""
import numba
import numpy as np
import pytest

from sim import InputError, Simulation, Specimen, config


def _fracturing_scene(n=4500):
    # weak bonds in an overlapping random packing under a servo-held wall: bonds break
    s = Specimen.random_packing(n, seed=4, pb_ten=3e7, pb_coh=6e7, pb_fa=30.0)
    sim = Simulation(s, damping=0.7)
    b = s.box
    sim.add_wall((0.0, b[2]), (0.0, 1.0), fric=0.3)
    top = sim.add_wall((0.0, b[3]), (0.0, -1.0), fric=0.3)
    sim.set_servo(top, 4e8, b[1] - b[0])
    return sim


def _run(threads, steps=400):
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        sim = _fracturing_scene()
        assert sim.state.n >= config.PARALLEL_MIN_PARTICLES
        sim.cycle(steps)
    finally:
        numba.set_num_threads(before)
    return sim


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two numba threads")
def test_one_and_two_threads_are_bit_identical_through_fracture():
    one, two = _run(1), _run(2)
    assert one.force_chunks == two.force_chunks == config.FORCE_CHUNKS
    broken = np.count_nonzero(one.state.bstate)
    assert broken > 10                     # the scene fractures, so it amplifies any rounding
    np.testing.assert_array_equal(one.state.bstate, two.state.bstate)
    np.testing.assert_array_equal(one.state.pf, two.state.pf)
    np.testing.assert_array_equal(one.state.wf, two.state.wf)


def test_chunk_count_from_environment(monkeypatch):
    elastic = Specimen.random_packing(4200, seed=2)
    ref = Simulation(elastic)
    ref.cycle(150)
    monkeypatch.setenv("SIM_FORCE_CHUNKS", "3")
    three = Simulation(elastic)
    assert three.force_chunks == 3
    three.cycle(150)
    assert three.state.acc.shape[0] >= 3
    # no bond breaks: another summation order changes only the rounding
    assert not ref.state.bstate.any() and not three.state.bstate.any()
    scale = np.abs(ref.state.pf[:2]).max()
    np.testing.assert_allclose(three.state.pf[:2], ref.state.pf[:2], rtol=0, atol=1e-12 * scale)
    small = Simulation(Specimen.random_packing(300, seed=2))
    assert small.force_chunks == 1          # small scenes: one chunk, one thread
    for bad in ("0", "two", "1000"):
        monkeypatch.setenv("SIM_FORCE_CHUNKS", bad)
        with pytest.raises(InputError, match="SIM_FORCE_CHUNKS"):
            Simulation(elastic).cycle(1)
