"""Checkpoint/restart: a run killed with SIGKILL resumes bit-identically (DESIGN.md §7)."""
import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from sim import InputError, Simulation, Specimen

SCRIPT = textwrap.dedent('''
    import sys, time
    import numpy as np
    from sim import Simulation, Specimen

    def make():
        s = Specimen.random_packing(700, seed=4, pb_ten=3e7, pb_coh=6e7, pb_fa=30.0)
        sim = Simulation(s, damping=0.7)
        b = s.box
        sim.add_wall((0.0, b[2]), (0.0, 1.0), fric=0.3)
        top = sim.add_wall((0.0, b[3]), (0.0, -1.0), fric=0.3)
        sim.set_servo(top, 4e8, b[1] - b[0])
        left = np.argsort(sim.x)[:10]
        sim.fix_velocity(left, 0.0, None)
        return sim

    mode, path, total, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    if mode == "fresh":
        sim = make()
        while sim.step < total:
            sim.cycle(250)
            sim.save(path)
            print(sim.step, flush=True)
            time.sleep(0.3)            # give the parent time to kill us mid-run
    elif mode == "resume":
        sim = Simulation.load(path)
        print("resumed", sim.step, flush=True)
        sim.cycle(total - sim.step)
    else:
        sim = make()
        sim.cycle(total)
    c = sim.cracks.arrays()
    np.savez(out, x=sim.x, y=sim.y, vx=sim.vx, vy=sim.vy, w=sim.w, fx=sim.fx,
             bond_state=sim.bond_state, top=np.array(sim.wall_position(1)),
             crack_step=c["step"], crack_x=c["x"], step=sim.step, time=sim.time)
''')


def _run(tmp_path, *args):
    return subprocess.Popen([sys.executable, str(tmp_path / "run.py"), *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_sigkill_and_resume_is_bit_identical(tmp_path):
    (tmp_path / "run.py").write_text(SCRIPT)
    ck = tmp_path / "ck.npz"
    total = 2000
    ref = _run(tmp_path, "plain", ck, total, tmp_path / "ref.npz")
    fresh = _run(tmp_path, "fresh", ck, total, tmp_path / "unused.npz")
    seen = 0
    t0 = time.time()
    while seen < 750 and time.time() - t0 < 120:
        line = fresh.stdout.readline()
        if not line:
            break
        seen = int(line)
    os.kill(fresh.pid, signal.SIGKILL)
    fresh.wait()
    assert fresh.returncode == -signal.SIGKILL and 750 <= seen < total
    # the file on disk is a complete checkpoint (written atomically), no temporary left behind
    assert sorted(p.name for p in tmp_path.iterdir() if "ck" in p.name) == ["ck.npz"]
    res = _run(tmp_path, "resume", ck, total, tmp_path / "res.npz")
    out, err = res.communicate(timeout=300)
    assert res.returncode == 0, err
    assert out.startswith("resumed")
    out, err = ref.communicate(timeout=300)
    assert ref.returncode == 0, err
    a, b = np.load(tmp_path / "ref.npz"), np.load(tmp_path / "res.npz")
    assert int(a["step"]) == int(b["step"]) == total
    assert len(a["crack_step"]) > 0            # bonds broke, and the logs agree too
    for k in a.files:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_save_load_round_trip_and_errors(tmp_path):
    s = Specimen.lattice(nx=5, ny=5, radius=1e-3, gap=2e-3)
    sim = Simulation(s, damping=0.3, dashpot_ratio=0.2, timestep_factor=0.3)
    sim.add_wall((0, s.box[2]), (0, 1), fric=0.2, emod=1e9)
    sim.cycle(10)
    p = tmp_path / "c.npz"
    sim.save(p)
    with np.load(p, allow_pickle=False) as z:        # no pickle inside
        meta = json.loads(str(z["sim_meta"][()]))
    assert meta["step"] == 10
    t = Simulation.load(p)
    assert (t.damping, t.dashpot, t.timestep_factor, t.dt) == (0.3, (0.2, 0.2), 0.3, sim.dt)
    assert t.n_walls == 1 and t.step == 10 and t.time == sim.time
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(InputError, match="bad.npz"):
        Simulation.load(bad)
    with pytest.raises(InputError, match="not found"):
        Simulation.load(tmp_path / "missing.npz")


def test_ctrl_c_during_the_compiled_loop_leaves_a_consistent_state(monkeypatch):
    """A real SIGINT that arrives while the compiled loop runs is raised only once the step,
    time and crack log match the particles: the interrupted engine equals a fresh one run for
    the steps it reports."""
    import sim.simulation as simulation

    def make():
        s = Specimen.random_packing(700, seed=4, pb_ten=3e7, pb_coh=6e7, pb_fa=30.0)
        return Simulation(s, damping=0.7)

    orig, calls = simulation.run_steps, []

    def run_steps(*args):
        out = orig(*args)
        calls.append(int(out[0]))
        if sum(1 for c in calls if c > 0) == 2 and out[0] > 0:
            os.kill(os.getpid(), signal.SIGINT)      # lands right after the kernel moved
        return out

    monkeypatch.setattr(simulation, "run_steps", run_steps)
    # a shell that starts jobs in the background ignores SIGINT: give Ctrl-C its Python default
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    hit = make()
    try:
        with pytest.raises(KeyboardInterrupt):
            hit.cycle(5000)
    finally:
        signal.signal(signal.SIGINT, previous)
    monkeypatch.setattr(simulation, "run_steps", orig)
    assert 0 < hit.step == sum(calls) < 5000           # the steps the kernel made, all counted
    ref = make()
    ref.cycle(hit.step)
    assert len(ref.cracks) == len(hit.cracks) > 0
    np.testing.assert_array_equal(ref.state.pf, hit.state.pf)
    assert ref.time == hit.time
    hit.cycle(100)                                     # and it goes on
    assert hit.step == ref.step + 100
