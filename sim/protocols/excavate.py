"""Excavation of a field model (thesis Ch. 7): in-situ stress by servo walls, then the openings
removed, cycling to equilibrium with breakage on.

Phases (each resumable from ``OUT/checkpoint.npz`` + ``OUT/run_state.json``):

1. ``insitu`` — four frictionless walls on the box faces servo-held at σH (sides) and σv
   (ends) from the depth (:mod:`sim.protocols.insitu`), bonds intact, cycled until the wall
   stresses are within ``STRESS_TOL`` of the targets and the unbalanced-force ratio is below
   ``ratio``. The particle positions are then kept as the reference of the displacement field.
2. ``excavate`` — the particles inside the openings recorded in the specimen
   (``meta["field"]["openings"]``) are removed: all at once (``stages=1``, instantaneous
   relaxation) or in ``stages`` enlargements of the profile about its centroid (size k/N,
   k = 1..N, each to equilibrium: staged relaxation). The walls keep their servo stress (a
   constant far field). Settled particles sleep (``sleep=True``) and wake when a neighbour or
   wall contact moves; the particles around a removed one are woken at removal.

Equilibrium is the PFC ratio (mean unbalanced force / mean contact force) with sleeping
particles counted as balanced (their forces are below ``sleep_force_ratio`` of their contact
sum when they fall asleep), checked every ``interval`` steps, or the step budget ``max_steps``
per stage.
"""
from __future__ import annotations

import json
import os
import time

import numpy as np

from .. import config
from .._io import save_npz_atomic
from ..errors import InputError
from ..field_geometry import points_in_polygon, polygon_centroid
from ..measure import pair_forces
from ..simulation import Simulation
from ..specimen import Specimen
from ..state import FX, FY
from . import insitu as ins
from .outputs import write_json_atomic

__all__ = ["run_excavate", "equilibrium_ratio", "field_openings", "STRESS_TOL"]

#: Wall stresses must be within this fraction of the targets before excavation.
STRESS_TOL = 0.01
#: Default equilibrium target (mean unbalanced / mean contact force).
RATIO = 1e-5
#: Default step budget per phase or stage.
MAX_STEPS = 300_000
#: Steps between equilibrium checks, history rows and servo re-targeting.
INTERVAL = 1000
#: Wall-clock seconds between checkpoints.
CHECKPOINT_S = 300.0
#: Sleep threshold of the excavation phase: displacement per step / mean radius (docs/field.md,
#: "Sleeping": measured against the awake run).
SLEEP_DISP = 1e-8


def field_openings(specimen) -> list:
    """The openings recorded by ``gbmgen field`` (``meta["field"]["openings"]``)."""
    ops = (specimen.meta.get("field") or {}).get("openings") or []
    if not ops:
        raise InputError("specimen: meta['field']['openings'] missing: expected a field "
                         "specimen written by 'gbmgen field'")
    return ops


def equilibrium_ratio(sim) -> float:
    """Mean unbalanced force over mean contact force, sleeping particles counted as balanced."""
    st = sim.state
    awake = ((st.fix & 3) == 0) & ((st.fix & 8) == 0)
    unb = np.sum(np.hypot(st.pf[FX][awake], st.pf[FY][awake])) / max(st.n, 1)
    mags = np.concatenate([np.hypot(fx, fy) for _i, _j, fx, fy in pair_forces(st)])
    mags = mags[mags > 0]
    return float(unb / mags.mean()) if mags.size else 0.0


def _scaled(poly, frac):
    p = np.asarray(poly, float)
    c = polygon_centroid(p)
    return c + frac * (p - c)


class _Run:
    """Bookkeeping of one excavation run: phases, history, checkpoints, progress bar."""

    def __init__(self, out, sim, walls, stress, opts, state):
        self.out, self.sim, self.walls, self.stress = out, sim, walls, stress
        self.opts, self.state = opts, state
        self.history = state.setdefault("history", [])
        self.t_ckpt = time.perf_counter()
        self.bar = None

    def record(self, phase, ratio):
        sxx, syy = ins.wall_stresses(self.sim, self.walls)
        c = self.sim.cracks
        self.history.append({"step": self.sim.step, "time_s": self.sim.time, "phase": phase,
                             "sigma_xx_mpa": sxx / 1e6, "sigma_yy_mpa": syy / 1e6,
                             "ratio": ratio, "cracks_total": len(c),
                             "asleep_fraction": float(np.mean(self.sim.asleep)),
                             "particles": self.sim.n_particles})
        if self.bar is not None:
            self.bar.set_postfix_str(f"{phase} ratio {ratio:.1e} cracks {len(c)} "
                                     f"asleep {100 * np.mean(self.sim.asleep):.0f}%")

    def checkpoint(self, force=False):
        if not force and time.perf_counter() - self.t_ckpt < self.opts["checkpoint_s"]:
            return
        self.sim.save(os.path.join(self.out, "checkpoint.npz"))
        write_json_atomic(os.path.join(self.out, "run_state.json"), self.state)
        self.t_ckpt = time.perf_counter()

    def cycle_to_equilibrium(self, phase, *, need_stress=False):
        """Cycle until equilibrium (or the budget); returns (ratio, steps, converged)."""
        o = self.opts
        done = self.state.get("phase_steps", 0)
        ratio = float("inf")
        while done < o["max_steps"]:
            k = min(o["interval"], o["max_steps"] - done)
            t0 = time.perf_counter()
            c0 = time.process_time()
            self.sim.cycle(k)
            done += k
            self.state["phase_steps"] = done
            ins.update_servo_lengths(self.sim, self.walls, self.stress)
            ratio = equilibrium_ratio(self.sim)
            self.record(phase, ratio)
            if self.bar is not None:
                self.bar.update(k)
            ok = ratio <= o["ratio"]
            if need_stress:
                sxx, syy = ins.wall_stresses(self.sim, self.walls)
                ok &= abs(sxx / self.stress.sxx - 1) <= STRESS_TOL
                ok &= abs(syy / self.stress.syy - 1) <= STRESS_TOL
            self.state["phase_wall_s"] = self.state.get("phase_wall_s", 0.0) + (
                time.perf_counter() - t0)
            self.state["phase_cpu_s"] = self.state.get("phase_cpu_s", 0.0) + (
                time.process_time() - c0)
            self.checkpoint()
            if ok:
                return ratio, done, True
        return ratio, done, False


def _wake_around(sim, gone_mask):
    """Wake the particles bonded or in contact with the particles about to be removed."""
    st = sim.state
    g = gone_mask
    near = np.zeros(st.n, bool)
    for a, b in ((st.bi, st.bj), (st.ci[:st.nc], st.cj[:st.nc])):
        near[b[g[a]]] = True
        near[a[g[b]]] = True
    idx = np.flatnonzero(near & ~g & ((st.fix & 8) != 0))
    if idx.size:
        sim.free(idx)


def run_excavate(specimen: Specimen, *, depth_m, out, k_ratio=None, gradients_mpa_per_m=None,
                 elastic=False, stages=1, sleep=True, sleep_disp=SLEEP_DISP,
                 sleep_force_ratio=config.SLEEP_FORCE_RATIO, sleep_steps=config.SLEEP_STEPS,
                 ratio=RATIO, max_steps=MAX_STEPS,
                 interval=INTERVAL, checkpoint_s=CHECKPOINT_S, resume=False, progress=True,
                 figures=True, timestep_factor=config.TIMESTEP_FACTOR):
    """In-situ stress, excavation and the field measures; writes the results into ``out``.

    Parameters
    ----------
    specimen : Specimen
        A field specimen (``gbmgen field``) with its openings in ``meta["field"]``.
    depth_m : float
        Depth, m; far field from :func:`sim.protocols.insitu.insitu_stress` with ``k_ratio`` or
        ``gradients_mpa_per_m``.
    out : path
        Results directory (created).
    elastic : bool
        Bonds cannot break (a check of the set-up against Kirsch).
    stages : int
        1: instantaneous removal; N > 1: N enlargements of the profile (staged relaxation).
    sleep : bool
        Settled particles sleep during the excavation phase (the in-situ phase runs awake).
    sleep_disp, sleep_force_ratio, sleep_steps
        Sleep thresholds (:class:`sim.Simulation`): displacement per step / mean radius,
        unbalanced / contact force, consecutive quiet steps.
    ratio, max_steps, interval
        Equilibrium target, step budget per phase/stage, check interval (steps).
    checkpoint_s : float
        Wall seconds between checkpoints (``OUT/checkpoint.npz``); ``resume`` continues.

    Returns
    -------
    summary : dict
        Also written as ``OUT/summary.json`` with the CSVs and figures
        (:mod:`sim.protocols.field_outputs`).
    """
    from .field_outputs import write_field_results

    if not (isinstance(stages, int | np.integer) and stages >= 1):
        raise InputError(f"stages = {stages!r}: expected a whole number >= 1")
    openings = field_openings(specimen)
    stress = ins.insitu_stress(depth_m, k_ratio=k_ratio, gradients_mpa_per_m=gradients_mpa_per_m)
    os.makedirs(out, exist_ok=True)
    opts = dict(ratio=float(ratio), max_steps=int(max_steps), interval=int(interval),
                checkpoint_s=float(checkpoint_s))
    ckpt = os.path.join(out, "checkpoint.npz")
    t0 = time.perf_counter()
    if resume and os.path.exists(ckpt):
        with open(os.path.join(out, "run_state.json"), encoding="utf-8") as fh:
            state = json.load(fh)
        sim = Simulation.load(ckpt)
        walls = tuple(state["walls"])
        stress = ins.InsituStress(**state["stress"])
    else:
        spec = ins.unbreakable(specimen) if elastic else specimen
        sim = Simulation(spec, sleep=False, timestep_factor=timestep_factor)
        if (spec.meta.get("field") or {}).get("joint_stiffness") == "per_joint_bond":
            ins.apply_per_joint_stiffness(sim)
        walls = ins.add_boundary_walls(sim, spec.box, stress)
        state = {"phase": "insitu", "stage": 0, "phase_steps": 0, "walls": list(walls),
                 "stress": {"depth_m": stress.depth_m, "sxx": stress.sxx, "syy": stress.syy,
                            "source": stress.source},
                 "options": {"elastic": bool(elastic), "stages": int(stages),
                             "sleep": bool(sleep), "sleep_disp": float(sleep_disp),
                             "sleep_force_ratio": float(sleep_force_ratio),
                             "sleep_steps": int(sleep_steps), "depth_m": float(depth_m), **opts},
                 "phases": {}}
    run = _Run(out, sim, walls, stress, opts, state)
    if progress:
        from tqdm import tqdm
        run.bar = tqdm(total=None, unit="step", desc="excavate", mininterval=2.0)
    try:
        if state["phase"] == "insitu":
            sim.sleep = False
            r, n, okk = run.cycle_to_equilibrium("insitu", need_stress=True)
            sxx, syy = ins.wall_stresses(sim, walls)
            state["phases"]["insitu"] = {"steps": n, "ratio": r, "converged": okk,
                                         "wall_s": state.pop("phase_wall_s", 0.0),
                                         "cpu_s": state.pop("phase_cpu_s", 0.0),
                                         "sigma_xx_mpa": sxx / 1e6, "sigma_yy_mpa": syy / 1e6}
            save_npz_atomic(os.path.join(out, "insitu_positions.npz"),
                            {"particle_id": sim.particle_id.copy(), "x": sim.x.copy(),
                             "y": sim.y.copy()})
            state.update(phase="excavate", stage=0, phase_steps=0, cracks_insitu=len(sim.cracks))
            run.checkpoint(force=True)
        sim.sleep_disp = float(sleep_disp)
        sim.sleep_force_ratio = float(sleep_force_ratio)
        sim.sleep_steps = int(sleep_steps)
        while state["phase"] == "excavate" and state["stage"] < stages:
            sim.sleep = bool(sleep)
            k = state["stage"] + 1
            if state["phase_steps"] == 0:
                frac = k / stages
                gone = np.zeros(sim.n_particles, bool)
                for o in openings:
                    gone |= points_in_polygon(sim.x, sim.y, _scaled(o["polygon"], frac))
                _wake_around(sim, gone)
                removed = sim.remove_particles(gone)
                # added, not appended: a stage resumed from a checkpoint taken right after its
                # removal repeats it and removes nothing more
                state.setdefault("removed", [0] * stages)[k - 1] += int(removed)
            r, n, okk = run.cycle_to_equilibrium(f"excavate_{k}")
            state["phases"][f"excavate_{k}"] = {"steps": n, "ratio": r, "converged": okk,
                                                "wall_s": state.pop("phase_wall_s", 0.0),
                                                "cpu_s": state.pop("phase_cpu_s", 0.0)}
            state.update(stage=k, phase_steps=0)
            run.checkpoint(force=True)
        state["phase"] = "done"
    except KeyboardInterrupt:
        run.checkpoint(force=True)
        raise
    finally:
        if run.bar is not None:
            run.bar.close()
    state["wall_s_this_call"] = time.perf_counter() - t0
    summary = write_field_results(out, sim, specimen, stress, state, figures=figures)
    run.checkpoint(force=True)
    return summary
