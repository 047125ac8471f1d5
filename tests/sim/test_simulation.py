"""Simulation: energy conservation, stress tests, instability reports, walls and servo."""
import numpy as np
import pytest
from _sim_fixtures import disks

from sim import InputError, InstabilityError, Simulation, Specimen, config
from sim.state import KNA


def test_undamped_lattice_energy_drift_at_default_step(rng):
    s = Specimen.lattice(nx=14, ny=14, radius=1e-3, gap=2e-3, pb_emod=50e9, pb_kratio=1.5)
    sim = Simulation(s, damping=0.0)
    assert sim.timestep_factor == config.TIMESTEP_FACTOR
    n = sim.n_particles
    sim.set_velocity(np.arange(n), rng.normal(0, 1e-3, n), rng.normal(0, 1e-3, n),
                     rng.normal(0, 1.0, n))
    e0 = sim.energy()["total"]
    es = []
    for _ in range(100):
        sim.cycle(100)
        e = sim.energy()
        assert e["strain_contact"] == 0.0  # the gap keeps the linear part out
        es.append(e["total"])
    assert sim.step == 10_000
    drift = np.max(np.abs(np.array(es) - e0)) / e0
    assert drift < config.TOL_ENERGY_DRIFT
    assert sim.energy()["strain_bond"] > 0.1 * e0  # energy really moved into the bonds


def test_damped_energy_is_dissipated_and_accounted(rng):
    s = Specimen.lattice(nx=8, ny=8, radius=1e-3, gap=2e-3)
    sim = Simulation(s, damping=0.7)
    n = sim.n_particles
    sim.set_velocity(np.arange(n), rng.normal(0, 1e-3, n), rng.normal(0, 1e-3, n))
    e0 = sim.energy()["total"]
    sim.cycle(3000)
    e = sim.energy()
    assert e["total"] < 1e-3 * e0
    # work of local damping ~ the energy lost (discrete estimate of the work, so 5 %)
    assert e["damping"] == pytest.approx(e0 - e["total"], rel=0.05)


def test_random_packing_with_20pct_overlaps_relaxes_without_nan():
    s = Specimen.random_packing(1500, overlap=0.12, bond_gap=-1.0, seed=3)
    assert s.n_bonds == 0
    sim = Simulation(s, damping=0.7)
    st = sim.state
    ov0 = np.max((sim.radius[st.ci] + sim.radius[st.cj] - np.hypot(
        sim.x[st.cj] - sim.x[st.ci], sim.y[st.cj] - sim.y[st.ci]))
        / (sim.radius[st.ci] + sim.radius[st.cj]))
    assert ov0 > 0.20
    e0 = sim.energy()["total"]
    sim.cycle(4000)
    assert np.all(np.isfinite(sim.x)) and np.all(np.isfinite(sim.vx))
    st = sim.state
    nc = st.nc
    d = np.hypot(sim.x[st.cj[:nc]] - sim.x[st.ci[:nc]], sim.y[st.cj[:nc]] - sim.y[st.ci[:nc]])
    ov = np.max((sim.radius[st.ci[:nc]] + sim.radius[st.cj[:nc]] - d)
                / (sim.radius[st.ci[:nc]] + sim.radius[st.cj[:nc]]))
    assert ov < 0.01          # overlaps relaxed below 1 % of the pair diameter
    e = sim.energy()
    assert e["total"] < 0.5 * e0      # no energy created; much of it dissipated by damping
    assert e["damping"] > 0.5 * e0


def test_sixty_to_one_stiffness_contrast_is_stable_at_default_step(rng):
    """Thesis App. E: biotite emod 1e9 next to 61e9 (bond and contact moduli alike)."""
    s = Specimen.random_packing(1200, n_minerals=2, emod=[1e9, 61e9], pb_emod=[1e9, 61e9],
                                overlap=-0.05, bond_gap=0.3, seed=5)
    sim = Simulation(s, damping=0.0)
    ks = sim.state.bf[KNA, : sim.state.npb]
    assert ks.max() / ks.min() > 30
    n = sim.n_particles
    sim.set_velocity(np.arange(n), rng.normal(0, 1e-3, n), rng.normal(0, 1e-3, n))
    sim.cycle(200)          # the initial overlaps push the packing apart a little
    e1 = sim.energy()["total"]
    sim.cycle(5000)
    e2 = sim.energy()["total"]
    assert np.all(np.isfinite(sim.x))
    # undamped: bounded energy (contacts that open and close within a step cost O(dt) each,
    # ~0.3 % per 1000 steps here; an unstable step grows exponentially instead)
    assert abs(e2 - e1) / e1 < 1e-2


@pytest.mark.parametrize("factor", [2.5, 20.0])
def test_over_large_step_factor_is_reported(rng, factor):
    s = Specimen.random_packing(400, seed=2)
    sim = Simulation(s, damping=0.0, timestep_factor=factor)
    n = sim.n_particles
    sim.set_velocity(np.arange(n), rng.normal(0, 1e-2, n), rng.normal(0, 1e-2, n))
    with pytest.raises(InstabilityError) as err:
        sim.cycle(20000)
    e = err.value
    assert e.cause in ("nan", "energy", "overlap")
    assert 0 <= e.step < 20000 and e.index >= 0
    assert "timestep_factor" in str(e) and f"step {e.step}" in str(e)


def test_default_step_runs_the_same_scene_stably(rng):
    s = Specimen.random_packing(400, seed=2)
    sim = Simulation(s, damping=0.0)
    n = sim.n_particles
    sim.set_velocity(np.arange(n), rng.normal(0, 1e-2, n), rng.normal(0, 1e-2, n))
    sim.cycle(3000)
    assert np.all(np.isfinite(sim.x))


def test_wall_force_sign_and_servo_holds_stress():
    s = Specimen.lattice(nx=8, ny=9, radius=1e-3, fric=0.5)
    sim = Simulation(s)
    b = s.box
    width = b[1] - b[0]
    bottom = sim.add_wall((0.0, b[2]), (0.0, 1.0))
    top = sim.add_wall((0.0, b[3]), (0.0, -1.0))
    sim.set_servo(top, 2e6, width)
    sim.cycle(4000)
    assert sim.wall_stress(top, width) == pytest.approx(2e6, rel=1e-3)
    fx, fy = sim.wall_force(bottom)
    assert fy == pytest.approx(-2e6 * width, rel=2e-3)   # particles push the floor down
    fx, fy = sim.wall_force(top)
    assert fy == pytest.approx(2e6 * width, rel=2e-3)
    assert sim.wall_position(top)[1] < b[3]               # the top wall moved down
    sim.clear_servo(top)
    y = sim.wall_position(top)[1]
    sim.cycle(100)
    assert sim.wall_position(top)[1] == y
    sim.set_wall_velocity(top, 0.0, -1e-3)
    sim.cycle(10)
    assert sim.wall_position(top)[1] == pytest.approx(y - 10 * sim.dt * 1e-3, rel=1e-12)


def test_single_particle_on_wall_force_and_stiffness():
    """Wall contact: linear law with r = R, L = R -> kn = 2 t E*."""
    s = disks([0.0], [0.001], 1e-3, emod=(1e9,))
    sim = Simulation(s, damping=0.0)
    w = sim.add_wall((0.0, 0.0), (0.0, 1.0), emod=2e9)
    sim.fix_velocity([0], 0.0, -1e-3, 0.0)
    k = 100
    sim.cycle(k)
    ov = 1e-3 - sim.y[0]
    assert sim.wall_force(w)[1] == pytest.approx(-2 * 2e9 * ov, rel=1e-9)
    assert sim.group_force([0])[1] == pytest.approx(2 * 2e9 * ov, rel=1e-9)


def test_fix_and_free_and_bad_input():
    s = Specimen.lattice(nx=3, ny=3, radius=1e-3, gap=2e-3)
    sim = Simulation(s, damping=0.0)
    sim.fix_velocity([0, 1], 1e-3, None)
    sim.cycle(10)
    assert np.all(sim.vx[[0, 1]] == 1e-3)
    sim.free([0, 1])
    sim.cycle(10)
    assert np.all(sim.vx[[0, 1]] != 1e-3)
    with pytest.raises(InputError, match="idx"):
        sim.fix_velocity([99], 0.0, 0.0)
    with pytest.raises(InputError, match="damping"):
        Simulation(s, damping=1.5)
    with pytest.raises(InputError, match="sleep_steps"):
        Simulation(s, sleep=True, sleep_steps=0)
    with pytest.raises(InputError, match="normal"):
        sim.add_wall((0, 0), (0, 0))
    with pytest.raises(InputError, match="wall 5"):
        sim.wall_force(5)


def test_remove_particles_excavates_a_hole():
    s = Specimen.lattice(nx=16, ny=16, radius=1e-3, gap=2e-3)
    sim = Simulation(s, damping=0.7)
    b = s.box
    sim.add_wall((0.0, b[2]), (0.0, 1.0))
    top = sim.add_wall((0.0, b[3]), (0.0, -1.0))
    sim.set_servo(top, 1e6, b[1] - b[0])
    sim.cycle(2000)
    cx, cy = sim.x.mean(), sim.y.mean()
    hole = np.hypot(sim.x - cx, sim.y - cy) < 4e-3
    kept_ids = sim.particle_id[~hole]
    n_bonds_hole = int(np.sum(hole[s.bond_i] | hole[s.bond_j]))
    assert sim.remove_particles(hole) == hole.sum() > 5
    assert sim.n_particles == s.n_particles - hole.sum()
    np.testing.assert_array_equal(sim.particle_id, kept_ids)
    assert np.sum(sim.bond_state == 3) == n_bonds_hole
    assert sim.bond_state.shape == (s.n_bonds,)
    sim.cycle(2000)
    assert np.all(np.isfinite(sim.x))
    # the servo still holds the platen stress around the hole
    assert sim.wall_stress(top, b[1] - b[0]) == pytest.approx(1e6, rel=1e-2)
    # nothing sits inside the hole any more
    assert np.min(np.hypot(sim.x - cx, sim.y - cy)) > 2e-3
    with pytest.raises(InputError, match="every particle"):
        sim.remove_particles(np.ones(sim.n_particles, bool))


def test_sleeping_particles_settle_wake_and_stay_close_to_the_exact_run():
    """Sleep is off by default; when on, settled particles sleep, a moving wall wakes those it
    reaches, and the result stays close to the run without sleep."""
    def run(sleep):
        s = Specimen.lattice(nx=30, ny=12, radius=1e-3, gap=2e-3)
        sim = Simulation(s, damping=0.7, sleep=sleep, sleep_disp=1e-7, sleep_steps=50)
        b = s.box
        sim.add_wall((0.0, b[2]), (0.0, 1.0))
        left = sim.add_wall((b[0], 0.0), (1.0, 0.0))
        sim.fix_velocity(np.nonzero(sim.x > sim.x.max() - 1e-3)[0], 0.0, 0.0, 0.0)
        sim.set_velocity(np.nonzero(sim.x < sim.x.max() - 1e-3)[0], 1e-4, 1e-4)
        sim.cycle(9000)                    # settles
        settled = sim.asleep.mean()
        sim.set_wall_velocity(left, 1.0, 0.0)
        sim.cycle(600)
        sim.set_wall_velocity(left, 0.0, 0.0)
        sim.cycle(9000)
        return sim, settled

    a, _ = run(False)
    b, settled = run(True)
    assert not a.asleep.any()
    assert settled > 0.8                       # the free particles fell asleep
    assert b.asleep.mean() > 0.5               # and most sleep again after the push
    disp_a = a.x - a.specimen.x
    disp_b = b.x - b.specimen.x
    scale = np.abs(disp_a).max()
    assert scale > 2e-6                        # the wall really pushed the lattice
    assert np.max(np.abs(disp_b - disp_a)) < 0.05 * scale
    fa, fb = a.wall_force(1)[0], b.wall_force(1)[0]
    assert fb == pytest.approx(fa, rel=0.05)


def test_critical_step_and_density_scaling():
    """dt = f min sqrt(m/k); density scaling sets dt = 1 and m = k/f^2 (PFC timestep scale)."""
    from sim.integrate import critical_timestep
    s = Specimen.random_packing(300, seed=6)
    sim = Simulation(s, timestep_factor=0.4)
    dt_p, ktr, krot = critical_timestep(sim.state)
    assert sim.dt == pytest.approx(0.4 * dt_p.min(), rel=1e-12)
    assert np.all(dt_p <= np.sqrt(sim.mass / ktr) + 1e-30)
    ds = Simulation(s, density_scale=True, timestep_factor=0.4)
    assert ds.dt == 1.0
    np.testing.assert_allclose(ds.mass[ktr > 0], ktr[ktr > 0] / 0.4 ** 2, rtol=1e-12)
    assert ds.solve(1e-4, max_steps=20000) <= 1e-4    # packs to equilibrium, stably


def test_hand_written_minimal_specimen_runs(tmp_path):
    """DESIGN.md §4: only particle, mineral-table, bond and box keys -> loads and runs."""
    s = Specimen.lattice(nx=4, ny=4, radius=1e-3, gap=2e-3)
    keep = ["x", "y", "r", "mineral_names", "density", "emod", "kratio", "fric", "pb_emod",
            "pb_kratio", "pb_ten", "pb_coh", "pb_fa", "pb_rmul", "bond_i", "bond_j", "box"]
    p = tmp_path / "min.npz"
    np.savez(p, **{k: getattr(s, k) for k in keep})
    sim = Simulation(Specimen.load(p), damping=0.0)
    sim.set_velocity([0], 1e-3, 0.0)
    sim.cycle(200)
    assert sim.state.n_bonds == s.n_bonds and np.all(sim.bond_intact)
    assert sim.energy()["strain_bond"] > 0
