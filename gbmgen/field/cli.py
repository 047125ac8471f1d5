"""``gbmgen field``: the ring-graded field specimen (no maths here; flags map 1:1 to
:func:`gbmgen.field.build.build_field` and :mod:`gbmgen.field.openings`).

Exit codes: 0 ok, 2 bad input (one line on stderr naming the file or field).
"""
from __future__ import annotations

import json
import time

__all__ = ["register", "run_field_command", "openings_from_args"]

OPENINGS = ("drive", "circle", "polygon", "two-drives")


def _polygon(text):
    import argparse
    try:
        pts = [[float(v) for v in p.split(",")] for p in str(text).split(";") if p.strip()]
        if len(pts) < 3 or any(len(p) != 2 for p in pts):
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--polygon-m: expected 'x,y;x,y;x,y[;...]' (m), got {text!r}") from None
    return pts


def register(sub):
    """Add ``field`` to ``gbmgen``'s subparsers."""
    f = sub.add_parser("field", help="ring-graded field-scale specimen around openings "
                                     "(thesis Ch. 7)")
    f.add_argument("--opening", choices=OPENINGS, default="drive",
                   help="drive (4.5 x 5 m arched), circle, polygon, or two drives at a dip "
                        "(with --stope-width-m: the stope joining them) [%(default)s]")
    f.add_argument("--radius-m", type=float, default=2.25, help="circle radius [%(default)s]")
    f.add_argument("--drive-width-m", type=float, default=4.5)
    f.add_argument("--drive-height-m", type=float, default=5.0)
    f.add_argument("--polygon-m", type=_polygon, help="polygon vertices 'x,y;x,y;...' (m)")
    f.add_argument("--dip-deg", type=float, default=65.0,
                   help="two drives: dip of the line through them [%(default)s]")
    f.add_argument("--spacing-m", type=float, default=20.0,
                   help="two drives: level spacing [%(default)s]")
    f.add_argument("--stope-width-m", type=float, default=None,
                   help="two drives: add a stope of this true width joining them")
    f.add_argument("--domain-m", type=float, default=None,
                   help="side of the square domain (default: the plan's, 40 m)")
    f.add_argument("--plan", default="thesis-ch7",
                   help="ring plan: thesis-ch7 | FILE.yaml | FILE.csv [%(default)s]")
    f.add_argument("--params", default="thesis-ch7",
                   help="micro-parameters: thesis-ch7 | thesis-ch5 | FILE.yaml [%(default)s]")
    f.add_argument("--seed", type=int, default=None, help="default: drawn and recorded")
    f.add_argument("--out", required=True, help="specimen.npz to write")
    f.add_argument("--png", help="also write a PNG of the model by ring")
    f.add_argument("--json", action="store_true", help="print the ring report as JSON")
    f.add_argument("--no-progress", action="store_true")


def openings_from_args(a):
    """The openings the flags ask for (list of dicts)."""
    from ..errors import InputError
    from . import openings as op
    if a.opening == "circle":
        return [op.circle(radius_m=a.radius_m)]
    if a.opening == "drive":
        return [op.drive(width_m=a.drive_width_m, height_m=a.drive_height_m)]
    if a.opening == "polygon":
        if not a.polygon_m:
            raise InputError("--opening polygon: give --polygon-m 'x,y;x,y;x,y'")
        return [op.polygon(a.polygon_m)]
    lo, up = op.two_drives(dip_deg=a.dip_deg, spacing_m=a.spacing_m, width_m=a.drive_width_m,
                           height_m=a.drive_height_m)
    out = [lo, up]
    if a.stope_width_m is not None:
        out.append(op.stope(lo, up, width_m=a.stope_width_m))
    return out


def run_field_command(a) -> int:
    import sys

    from .build import build_field
    t0 = time.perf_counter()

    def say(stage):
        if not a.no_progress:
            print(f"gbmgen field: {stage} ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)

    spec, timing = build_field(plan=a.plan, openings=openings_from_args(a),
                               domain_m=a.domain_m, params=a.params, seed=a.seed, progress=say)
    spec.save(a.out)
    rings = spec.meta["field"]["rings"]
    if a.png:
        from sim.protocols.field_outputs import plot_rings
        plot_rings(spec, a.png)
    if a.json:
        print(json.dumps({"file": a.out, "particles": spec.n_particles,
                          "bonds": spec.n_bonds, "grains": spec.n_grains, "rings": rings,
                          "seconds": timing}, indent=1))
    else:
        print(f"wrote {a.out}: {spec.n_particles} particles, {spec.n_bonds} bonds, "
              f"{spec.n_grains} grains in {len(rings)} rings "
              f"({time.perf_counter() - t0:.1f} s)")
        for r in rings:
            ppg = r["particles_per_grain"] or {}
            print(f"  ring {r['ring']}: {r['particles']} particles, r {r['radius_mm'][1]:.1f} mm"
                  f" mean, {r['grains']} grains, grain/particle radius "
                  f"{r['grain_to_particle_radius'] or float('nan'):.2f}, particles per grain "
                  f"min {ppg.get('min')} median {ppg.get('median')}, "
                  f"{ppg.get('below_10')} grain(s) below 10")
    return 0
