"""``gbmsim``: command line of the DEM engine (info, bench, verify) and of the lab-test protocols.

No maths here: each subcommand calls the API (STYLE.md §4). Exit codes: 0 ok, 1 a check
failed, 2 bad input, 3 numerical failure, 130 interrupted (README "Exit codes").
"""
from __future__ import annotations

import argparse
import json
import sys
import time

__version__ = "0.1.0"


def _info(args) -> int:
    import numpy as np

    from .simulation import Simulation
    from .specimen import Specimen
    s = Specimen.load(args.specimen)
    kinds = np.bincount(s.bond_kind, minlength=2)
    out = {"file": args.specimen, "particles": s.n_particles, "parallel_bonds": int(kinds[0]),
           "smooth_joints": int(kinds[1]), "grains": s.n_grains,
           "minerals": s.mineral_names.tolist(),
           "radius_min_mm": float(s.r.min() * 1e3), "radius_max_mm": float(s.r.max() * 1e3),
           "box_mm": (s.box * 1e3).tolist(),
           "bonds_per_particle": 2.0 * s.n_bonds / s.n_particles, "meta": s.meta}
    if not args.no_timestep:
        sim = Simulation(s, timestep_factor=args.timestep_factor)
        out.update(dt_s=sim.dt, timestep_factor=sim.timestep_factor, contacts=sim.state.nc)
    if args.json:
        print(json.dumps(out, indent=2, default=str))
    else:
        for k, v in out.items():
            if k != "meta":
                print(f"{k:20s} {v}")
    return 0


def _bench(args) -> int:
    import numba
    import numpy as np

    from .simulation import Simulation
    from .specimen import Specimen
    if args.threads:
        numba.set_num_threads(args.threads)
    s = Specimen.random_packing(args.n, seed=args.seed)
    sim = Simulation(s)
    sim.cycle(50)  # compile (cached) and settle the initial overlaps a little
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        sim.cycle(args.steps)
        times.append(time.perf_counter() - t0)
    med = float(np.median(times))
    out = {"particles": s.n_particles, "bonds": s.n_bonds, "threads": numba.get_num_threads(),
           "steps": args.steps, "median_s": med,
           "particle_steps_per_s": s.n_particles * args.steps / med,
           "contact_steps_per_s": (sim.state.n_bonds + sim.state.nc) * args.steps / med}
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"{out['particles']} particles, {out['threads']} thread(s): "
              f"{out['particle_steps_per_s'] / 1e6:.2f} M particle-steps/s "
              f"({out['contact_steps_per_s'] / 1e6:.2f} M pair-steps/s), median of "
              f"{args.repeat} x {args.steps} steps")
    return 0


def _verify(args) -> int:
    from .verify import verification_cases
    rows = verification_cases()
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        for r in rows:
            print(f"{'ok  ' if r['ok'] else 'FAIL'} {r['check']:45s} measured {r['measured']:.6g}"
                  f"  expected {r['expected']:.6g}  error {100 * r['rel_error']:.3f} %"
                  f" (tolerance {100 * r['tolerance']:.2f} %)")
    return 0 if all(r["ok"] for r in rows) else 1


def build_parser() -> argparse.ArgumentParser:
    from .protocols.cli import EXIT_CODES, OneLineParser
    p = OneLineParser(prog="gbmsim", description="2D bonded-particle DEM (PFC2D style)",
                      epilog=EXIT_CODES)
    p.add_argument("--version", action="version", version=f"gbmsim {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    q = sub.add_parser("info", help="summarise a specimen.npz and its time step")
    q.add_argument("specimen")
    q.add_argument("--timestep-factor", type=float, default=None,
                   help="safety factor on the critical step (default: sim.config)")
    q.add_argument("--no-timestep", action="store_true", help="skip building the simulation")
    q.add_argument("--json", action="store_true")
    q.set_defaults(func=_info)
    q = sub.add_parser("bench", help="measure throughput on a bonded random packing")
    q.add_argument("--n", type=int, default=20000, help="particles (default 20000)")
    q.add_argument("--steps", type=int, default=500)
    q.add_argument("--repeat", type=int, default=3)
    q.add_argument("--threads", type=int, default=0, help="numba threads (default: all)")
    q.add_argument("--seed", type=int, default=1)
    q.add_argument("--json", action="store_true")
    q.set_defaults(func=_bench)
    q = sub.add_parser("verify", help="run the analytic checks (REFERENCE.md §6) and report errors")
    q.add_argument("--json", action="store_true")
    q.set_defaults(func=_verify)
    from .protocols.cli import register
    register(sub)
    from .protocols.excavate_cli import register as register_excavate
    register_excavate(sub)
    add_plugin_commands(sub)
    return p


#: Entry-point group through which installed packages add ``gbmsim`` subcommands (gbmgen adds
#: ``sweep`` and ``study``); each entry point is a function ``register(subparsers)``.
PLUGIN_GROUP = "rockkit.gbmsim"


def add_plugin_commands(sub) -> list:
    """Add the subcommands of the :data:`PLUGIN_GROUP` entry points; returns their names.

    ``sim`` imports nothing of the other packages: they register themselves in their package
    metadata. A plugin that fails to load is reported in one stderr line and left out.
    """
    from importlib.metadata import entry_points
    names = []
    for ep in sorted(entry_points(group=PLUGIN_GROUP), key=lambda e: e.name):
        try:
            ep.load()(sub)
        except Exception as exc:          # a broken plugin must not break gbmsim
            print(f"gbmsim: warning: subcommand {ep.name!r} ({ep.value}) not loaded: "
                  f"{type(exc).__name__}: {exc}", file=sys.stderr)
            continue
        names.append(ep.name)
    return names


def main(argv=None) -> int:
    """Entry point of ``gbmsim`` and ``python -m sim``; returns the exit code."""
    from .errors import InputError, InstabilityError
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "timestep_factor", 0) is None:
        from . import config
        args.timestep_factor = config.TIMESTEP_FACTOR
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"gbmsim: {exc}", file=sys.stderr)
        return 2
    except InstabilityError as exc:
        print(f"gbmsim: numerical failure: {exc}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("gbmsim: interrupted", file=sys.stderr)
        return 130
