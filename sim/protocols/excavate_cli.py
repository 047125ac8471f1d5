"""``gbmsim excavate``: the field-scale excavation test (no maths here; flags map 1:1 to the
keywords of :func:`sim.protocols.excavate.run_excavate`).

Exit codes: 0 done (``summary.json`` says whether each phase reached equilibrium), 2 bad input
(one line naming the file or field), 3 numerical failure (one line: cause, step, hint; the last
checkpoint is kept for ``--resume``), 130 interrupted (checkpoint written).
"""
from __future__ import annotations

import sys

__all__ = ["register", "run_excavate_command"]


def register(subparsers):
    """Add the ``excavate`` subcommand to ``gbmsim``'s subparsers."""
    from . import excavate as ex
    p = subparsers.add_parser(
        "excavate", help="field model: in-situ stress by servo walls, then excavation",
        description="In-situ stress from depth applied by four servo walls, equilibrium with "
                    "bonds intact, then the specimen's openings removed and the model cycled "
                    "to equilibrium with breakage on (docs/field.md).")
    p.add_argument("specimen", help="field specimen.npz written by 'gbmgen field'")
    p.add_argument("--depth-m", type=float, required=True, help="depth below surface, m")
    p.add_argument("--out", required=True, help="results directory")
    p.add_argument("--k-ratio", type=float, default=None,
                   help="sigma_H / sigma_v (default 2.0; sigma_v = 2700 kg/m3 x g x depth)")
    p.add_argument("--gradients-mpa-per-m", type=float, nargs=2, metavar=("H", "V"),
                   help="horizontal and vertical stress gradients instead of --k-ratio")
    p.add_argument("--elastic", action="store_true",
                   help="bonds cannot break (check of the set-up against Kirsch)")
    p.add_argument("--stages", type=int, default=1,
                   help="1: instantaneous excavation; N: N enlargements of the profile, each "
                        "to equilibrium (staged relaxation) [%(default)s]")
    p.add_argument("--no-sleep", dest="sleep", action="store_false",
                   help="keep every particle awake during the excavation")
    p.add_argument("--sleep-disp", type=float, default=ex.SLEEP_DISP,
                   help="a particle sleeps after moving less than this x the mean radius per "
                        "step (and a force ratio below 1e-3) for 200 steps [%(default)s]")
    p.add_argument("--ratio", type=float, default=ex.RATIO,
                   help="equilibrium: mean unbalanced / mean contact force [%(default)s]")
    p.add_argument("--max-steps", type=int, default=ex.MAX_STEPS,
                   help="step budget per phase and stage [%(default)s]")
    p.add_argument("--checkpoint-minutes", type=float, default=ex.CHECKPOINT_S / 60.0,
                   help="wall minutes between checkpoints [%(default)s]")
    p.add_argument("--resume", action="store_true", help="continue from OUT/checkpoint.npz")
    p.add_argument("--timestep-factor", type=float, default=None)
    p.add_argument("--no-figures", action="store_true")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=run_excavate_command)


def run_excavate_command(a) -> int:
    from .. import config
    from ..errors import InputError, InstabilityError
    from ..specimen import Specimen
    from .excavate import run_excavate
    try:
        spec = Specimen.load(a.specimen)
        s = run_excavate(spec, depth_m=a.depth_m, out=a.out, k_ratio=a.k_ratio,
                         gradients_mpa_per_m=a.gradients_mpa_per_m, elastic=a.elastic,
                         stages=a.stages, sleep=a.sleep, sleep_disp=a.sleep_disp,
                         ratio=a.ratio, max_steps=a.max_steps,
                         checkpoint_s=60.0 * a.checkpoint_minutes, resume=a.resume,
                         progress=not a.no_progress, figures=not a.no_figures,
                         timestep_factor=a.timestep_factor or config.TIMESTEP_FACTOR)
    except InputError as exc:
        print(f"gbmsim excavate: {exc}", file=sys.stderr)
        return 2
    except InstabilityError as exc:
        msg = " ".join(str(exc).split())
        print(f"gbmsim excavate: numerical failure: {msg} (checkpoint kept in {a.out}; "
              "--resume, or a smaller --timestep-factor)", file=sys.stderr)
        return 3
    not_conv = [k for k, v in s["phases"].items() if not v.get("converged")]
    for o in s["openings"]:
        print(f"{o['name']}: max D/R {o['max_D_over_R']:.3f} at {o['max_D_over_R_angle_deg']:g}"
              f" deg, {len(o['notches'])} notch(es)")
    print(f"wrote {a.out}/summary.json ({s['steps']} steps, {s['wall_s']:.0f} s"
          + (f"; not at equilibrium within --max-steps: {', '.join(not_conv)}" if not_conv
             else "") + ")")
    return 0
