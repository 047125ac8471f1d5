"""``gbmgen build | run | info | plot | defect | export``: command-line interface (no maths here).

Exit codes (README "Exit codes"): 0 ok; 2 bad input, ours or semkit's or sim's (one line on
stderr naming the file or field); 3 numerical failure of the laboratory test (one line naming
cause, step and hint); 130 interrupted.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

from semkit.errors import InputError as SemkitInputError
from sim.errors import InputError as SimInputError
from sim.errors import InstabilityError

from . import __version__, config
from .errors import InputError

#: Errors of the chain reported as bad input (exit 2): ours, semkit's, sim's (its protocols
#: name a bad option in a ValueError) and a missing file.
BAD_INPUT = (InputError, SimInputError, SemkitInputError, ValueError, FileNotFoundError)
#: Text of the exit codes for the --help of every command.
EXIT_CODES = ("Exit codes: 0 ok; 2 bad input (one line naming the file or field); 3 numerical "
              "failure (one line naming cause, step and hint); 130 interrupted.")


def _seed(text):
    """``--seed``: a whole number >= 0 or 'random'."""
    from .run import resolve_seed
    try:
        resolve_seed(None if text is None else text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def _read_table(name):
    from .table import EXAMPLE_TABLES, example_table, read_table
    return example_table(name) if name in EXAMPLE_TABLES else read_table(name)


def _parse_ranges(text):
    """``"a:0.1:1.2,b:0.2:0.9"`` -> {"a": (0.1, 1.2), "b": (0.2, 0.9)} (mm)."""
    out = {}
    for part in str(text).split(","):
        bits = part.strip().split(":")
        try:
            out[bits[0].strip()] = (float(bits[1]), float(bits[2]))
            if len(bits) != 3:
                raise ValueError
        except (IndexError, ValueError):
            raise argparse.ArgumentTypeError(
                f"--ranges-mm: expected MINERAL:LO:HI[,...], got {part!r}") from None
    return out


def _add_model_options(b):
    """Options shared by build and run (size scenario, tessellation, particles, params)."""
    b.add_argument("--scenario", type=int, default=1, choices=(1, 2, 3, 4),
                   help="size range: 1 full, 2 10-90%% passing, 3 mean±½mean, 4 mean±¼mean")
    b.add_argument("--ranges-mm", type=_parse_ranges, default=None,
                   metavar="MINERAL:LO:HI,...",
                   help="explicit size ranges at model scale instead of --scenario, e.g. "
                        "pyroxene:0.22:1.24,plagioclase:0.16:0.99,biotite:0.15:0.80")
    b.add_argument("--scale", type=float, default=1.0, help="grain-size factor (e.g. 1.5)")
    b.add_argument("--model-scale", type=float, default=config.MODEL_SCALE,
                   help="model size / table size (thesis: 10 x SEM scale) [%(default)s]")
    b.add_argument("--width-mm", type=float, default=25.0)
    b.add_argument("--height-mm", type=float, default=50.0)
    b.add_argument("--tessellation", choices=("laguerre", "voronoi"), default="laguerre")
    b.add_argument("--no-fit-areas", dest="fit_areas", action="store_false",
                   help="Laguerre with weights r^2 only (no area fit)")
    b.add_argument("--particle-radius-mm", type=float, default=config.PARTICLE_RADIUS_MM,
                   help="mean particle radius [%(default)s]")
    b.add_argument("--radius-ratio", type=float, default=config.RADIUS_RATIO)
    b.add_argument("--porosity", type=float, default=config.POROSITY)
    b.add_argument("--no-seat-faces", dest="seat_faces", action="store_false",
                   help="leave the packing's dents along the box faces (earlier specimens)")
    b.add_argument("--bond-gap-mm", type=float, default=None,
                   help=f"default {config.BOND_GAP_PER_RADIUS} x mean particle radius")
    b.add_argument("--params", default=config.DEFAULT_PARAMS,
                   help="thesis-ch4 | thesis-ch5 | FILE.yaml/json [%(default)s]")
    b.add_argument("--seed", type=_seed, default=None,
                   help=f"random seed: a whole number, or 'random' for a fresh draw (default "
                        f"{config.DEFAULT_SEED}: the same command builds the same specimen); "
                        "recorded in the specimen's meta")


def _parser():
    from sim.protocols.cli import OneLineParser
    p = OneLineParser(prog="gbmgen", description="Grain-based model generator: "
                                "grain-size table -> bonded grain-based specimen.npz",
                                epilog=EXIT_CODES)
    p.add_argument("--version", action="version", version=f"gbmgen {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    b = sub.add_parser("build", help="build a specimen.npz from a grain-size table")
    b.add_argument("--config", metavar="FILE.yaml",
                   help="YAML mapping of option names (as below, - or _) to values")
    b.add_argument("--table", help="grains.csv (DESIGN.md §4), or 'table-4-1' (thesis example)")
    _add_model_options(b)
    b.add_argument("--shape", choices=("hexagon", "rectangle", "shield"),
                   help="controlled tessellation instead of seeds (thesis Ch. 5)")
    b.add_argument("--slenderness", type=float, default=1.0, help="H/W of controlled grains")
    b.add_argument("--grain-area-mm2", type=float, default=config.GRAIN_AREA_MM2)
    b.add_argument("--out", required=True, help="specimen.npz to write")
    b.add_argument("--geom", help="also write the PFC geometry file")
    b.add_argument("--vtk", metavar="PREFIX", help="also write PREFIX_particles/_grains.vtk")
    b.add_argument("--png", help="also write a PNG preview")
    b.add_argument("--json", action="store_true", help="print the summary as JSON")
    b.add_argument("--no-progress", action="store_true", help="print no stage lines")

    r = sub.add_parser("run", help="SEM images -> semkit grains.csv -> specimen.npz (end to end)",
                       description="SEM images -> semkit -> grains.csv -> specimen.npz -> "
                       "laboratory test (docs/gbmgen.md). " + EXIT_CODES)
    r.add_argument("images", nargs="?", default="sample_images",
                   help="folder of SEM images [%(default)s]")
    r.add_argument("--out", required=True, help="output folder")
    r.add_argument("--minerals", default="pyroxene,plagioclase,biotite",
                   help="mineral names brightest-first (semkit) [%(default)s]")
    r.add_argument("--classes", help="class edges in um for grains.csv, e.g. 20,140")
    r.add_argument("--pixel-size-um", type=float, help="fallback pixel size for semkit")
    r.add_argument("--no-cracks", dest="cracks", action="store_false",
                   help="skip semkit's crack pipeline (grains only)")
    r.add_argument("--jobs", type=int, help="semkit worker processes")
    from .run import test_names
    r.add_argument("--test", choices=test_names(), default="ucs",
                   help="laboratory test run on the specimen (gbmsim) [%(default)s]")
    r.add_argument("--post-peak", type=float, default=0.8,
                   help="stop the test when the stress falls below this fraction of the peak "
                        "[%(default)s]")
    r.add_argument("--no-progress", action="store_true")
    _add_model_options(r)

    i = sub.add_parser("info", help="summary of a specimen.npz (counts, fidelity)")
    i.add_argument("specimen")
    i.add_argument("--json", action="store_true", help="print counts and meta as JSON")

    q = sub.add_parser("plot", help="PNG of a specimen (grains by mineral)")
    q.add_argument("specimen")
    q.add_argument("--out", help="PNG path [specimen with .png]")
    q.add_argument("--particles", action="store_true")
    q.add_argument("--joints", action="store_true", help="draw smooth-joint bonds")

    d = sub.add_parser("defect", help="cut holes or a flaw into a specimen (thesis Ch. 6)")
    d.add_argument("specimen")
    d.add_argument("--out", required=True, help="specimen.npz to write")
    d.add_argument("--hole", choices=("intra", "inter", "trans3", "trans4"),
                   help="one hole placed automatically inside 1 grain / on a boundary of 2 / "
                        "across 3 or 4 grains")
    d.add_argument("--diameter-mm", type=float, default=3.0, help="hole diameter [%(default)s]")
    d.add_argument("--double-hole", action="store_true",
                   help="two holes of --diameter-mm, --bridge-mm apart at --angle-deg")
    d.add_argument("--bridge-mm", type=float, default=1.5, help="wall-to-wall distance")
    d.add_argument("--flaw", action="store_true", help="inclined flaw --length-mm x --width-mm")
    d.add_argument("--length-mm", type=float, default=10.0)
    d.add_argument("--width-mm", type=float, default=0.5)
    d.add_argument("--angle-deg", type=float, default=0.0, help="from horizontal")
    d.add_argument("--at-mm", type=float, nargs=2, metavar=("X", "Y"),
                   help="centre of a double hole / flaw / manual hole [specimen centre]")

    from .field.cli import register as register_field
    register_field(sub)

    e = sub.add_parser("export", help="PFC .geom and/or VTK of a specimen")
    e.add_argument("specimen")
    e.add_argument("--geom")
    e.add_argument("--vtk", metavar="PREFIX")
    return p


def _apply_config(parser, argv):
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--config")
    known, _ = pre.parse_known_args(argv)
    if not known.config:
        return
    import yaml
    try:
        with open(known.config, encoding="utf-8") as fh:
            data = yaml.safe_load(fh) or {}
    except OSError as exc:
        raise InputError(f"{known.config}: cannot read ({exc})") from None
    except yaml.YAMLError as exc:
        raise InputError(f"{known.config}: not valid YAML ({exc})") from None
    if not isinstance(data, dict):
        raise InputError(f"{known.config}: expected a mapping of option names to values")
    build = parser._subparsers._group_actions[0].choices["build"]
    dests = {a.dest for a in build._actions}
    clean = {}
    for k, v in data.items():
        d = str(k).replace("-", "_")
        if d not in dests or d in ("config", "help"):
            raise InputError(f"{known.config}: unknown option {k!r}")
        clean[d] = v
    build.set_defaults(**clean)
    for a in build._actions:
        if a.dest in clean:
            a.required = False


def _summary(spec):
    m = spec.meta or {}
    fid = m.get("fidelity", {})
    kinds = spec.bond_kind
    out = {"particles": spec.n_particles, "grains": spec.n_grains,
           "parallel_bonds": int((kinds == 0).sum()), "smooth_joints": int((kinds == 1).sum()),
           "minerals": [str(s) for s in spec.mineral_names],
           "box_mm": [float(v) * 1e3 for v in spec.box],
           "seed": m.get("seed"), "scenario": m.get("scenario"),
           "tessellation": m.get("tessellation"),
           "MHI_target": m.get("MHI_target"), "MHI_realised": m.get("MHI_realised"),
           "H_target": m.get("H_target"), "H_realised": m.get("H_realised"),
           "ks_max": fid.get("ks_max"),
           "area_fraction_error_max": fid.get("area_fraction_error_max"),
           "particles_per_grain": fid.get("particles_per_grain")}
    return out


def _print_summary(spec, out=None):
    out = sys.stdout if out is None else out
    s = _summary(spec)
    fid = (spec.meta or {}).get("fidelity", {})
    print(f"particles {s['particles']}  grains {s['grains']}  parallel bonds "
          f"{s['parallel_bonds']}  smooth joints {s['smooth_joints']}", file=out)
    print(f"box (mm) {s['box_mm']}  seed {s['seed']}  scenario {s['scenario']}  "
          f"tessellation {s['tessellation']}", file=out)

    def f(v, fmt=".3f"):
        return "-" if v is None else format(v, fmt)

    print(f"MHI target {f(s['MHI_target'])} realised {f(s['MHI_realised'])}   "
          f"H target {f(s['H_target'])} realised {f(s['H_realised'])}", file=out)
    minerals = fid.get("minerals")
    if minerals:
        print(f"{'mineral':<14}{'grains':>8}{'KS':>8}{'area %':>9}{'target %':>10}", file=out)
        for name, v in minerals.items():
            print(f"{name:<14}{v['n_grains']:>8}{v['ks']:>8.4f}{100 * v['area_fraction']:>9.2f}"
                  f"{100 * v['area_fraction_target']:>10.2f}", file=out)
    vor = ((spec.meta or {}).get("grains") or {}).get("voronoi_same_seeds")
    if vor:
        print("Voronoi on the same seeds: KS " + ", ".join(f"{k} {v:.4f}"
                                                           for k, v in vor["ks"].items())
              + f"; area-fraction error max {vor['area_fraction_error_max']:.4f}", file=out)
    ppg = s.get("particles_per_grain")
    if ppg:
        print(f"particles per grain: min {ppg['min']} median {ppg['median']:g} "
              f"(grains without particles {ppg['grains_without_particles']})", file=out)


def _build(a):
    from sim.specimen import Specimen  # noqa: F401  (fail early if sim is broken)

    from .build import build_specimen

    table = _read_table(a.table) if a.table else None
    if table is None and a.shape is None:
        raise InputError("--table: a grain-size table is needed (or give --shape)")
    t0 = time.perf_counter()
    spec, timing = build_specimen(
        table, width_mm=a.width_mm, height_mm=a.height_mm, scenario=a.scenario, scale=a.scale,
        model_scale=a.model_scale, tessellation=a.tessellation, fit_areas=a.fit_areas,
        shape=a.shape, slenderness=a.slenderness, grain_area_mm2=a.grain_area_mm2,
        ranges_mm=a.ranges_mm, particle_radius_mm=a.particle_radius_mm, radius_ratio=a.radius_ratio,
        porosity=a.porosity, seat_faces=a.seat_faces, bond_gap_mm=a.bond_gap_mm,
        params=a.params, seed=_resolved_seed(a.seed))
    t1 = time.perf_counter()
    spec.save(a.out)
    timing["save"] = time.perf_counter() - t1
    if a.geom:
        from .export import export_geom
        export_geom(spec, a.geom, name=os.path.basename(a.out))
    if a.vtk:
        from .export import export_vtk
        export_vtk(spec, a.vtk)
    if a.png:
        from .plot import plot_specimen
        plot_specimen(spec, a.png)
    if a.json:
        print(json.dumps({**_summary(spec), "out": a.out,
                          "timing_s": {k: round(v, 3) for k, v in timing.items()},
                          "total_s": round(time.perf_counter() - t0, 3)}))
    else:
        if not a.no_progress:
            print("stages (s): " + ", ".join(f"{k} {v:.2f}" for k, v in timing.items()),
                  file=sys.stderr)
        _print_summary(spec)
        print(f"wrote {a.out}")
    return 0


def _resolved_seed(seed):
    from .run import resolve_seed
    return resolve_seed(seed)[0]


def _run(a):
    from sim.protocols.cli import specimen_warnings

    from .run import run
    with specimen_warnings():
        summary = run(a.images, a.out, minerals=a.minerals, classes=a.classes,
                      pixel_size_um=a.pixel_size_um, cracks=a.cracks, jobs=a.jobs,
                      progress=not a.no_progress, seed=a.seed, scenario=a.scenario,
                      scale=a.scale, model_scale=a.model_scale, ranges_mm=a.ranges_mm,
                      width_mm=a.width_mm, height_mm=a.height_mm,
                      tessellation=a.tessellation, fit_areas=a.fit_areas,
                      particle_radius_mm=a.particle_radius_mm, radius_ratio=a.radius_ratio,
                      porosity=a.porosity, seat_faces=a.seat_faces, bond_gap_mm=a.bond_gap_mm,
                      params=a.params, test=a.test, test_options={"post_peak": a.post_peak})
    print(json.dumps(summary, indent=1, default=str))
    print(f"report: {os.path.join(a.out, 'report.html')} (and report.md)", file=sys.stderr)
    ts, ps = summary.get("test_summary") or {}, summary.get("P_sem") or {}
    if ts.get("P_sim") and ps.get("P_pooled") is not None:
        flag = "" if ps.get("P_status", "ok") == "ok" else f" [{ps['P_status']}]"
        from semkit.damage import band_text
        band = band_text(ps.get("P_pooled_low"), ps.get("P_pooled_high"))
        flag = (f" (band {band})" if band else "") + flag
        print(f"damage ratio P = A_T/A_S: SEM (pooled over loaded stages) {ps['P_pooled']:.2f}"
              f"{flag}   simulated {a.test} {ts['P_sim'].get('by_area', float('nan')):.2f}"
              " (by area)", file=sys.stderr)
    return 0


def _defect(a, spec):
    from . import defects
    box = spec.box
    at = np.array(a.at_mm) * 1e-3 if a.at_mm else \
        np.array([0.5 * (box[0] + box[1]), 0.5 * (box[2] + box[3])])
    r = 0.5 * a.diameter_mm * 1e-3
    n = sum(bool(v) for v in (a.hole, a.double_hole, a.flaw))
    if n != 1 and not (n == 0 and a.at_mm):
        raise InputError("defect: give exactly one of --hole KIND, --double-hole, --flaw "
                         "(or --at-mm X Y for one hole there)")
    if a.hole:
        c = defects.place_hole(spec, a.hole, r) if not a.at_mm else at
        out = defects.cut_holes(spec, [c], r, kind=a.hole)
    elif a.double_hole:
        out = defects.cut_holes(spec, defects.double_hole_centres(at, r, a.bridge_mm * 1e-3,
                                                                  a.angle_deg), r, kind="double")
    elif a.flaw:
        out = defects.cut_flaw(spec, at, a.length_mm * 1e-3, a.width_mm * 1e-3, a.angle_deg)
    else:
        out = defects.cut_holes(spec, [at], r, kind="manual")
    out.save(a.out)
    rec = out.meta["defects"][-1]
    print(f"wrote {a.out}: {rec['type']} removed {rec['particles_removed']} particles, "
          f"{rec['bonds_removed']} bonds" + (f", grains cut {rec['grains_cut']}"
                                             if "grains_cut" in rec else ""))
    return 0


def _load(path):
    from sim.specimen import Specimen
    return Specimen.load(path)


def main(argv=None) -> int:
    """Entry point of the ``gbmgen`` console script."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = _parser()
    created = _new_folder(argv)
    try:
        if argv and argv[0] == "build":
            _apply_config(parser, argv[1:])
        a = parser.parse_args(argv)
        if a.command == "build":
            return _build(a)
        if a.command == "run":
            return _run(a)
        if a.command == "field":
            from .field.cli import run_field_command
            return run_field_command(a)
        spec = _load(a.specimen)
        if a.command == "info":
            if a.json:
                print(json.dumps({**_summary(spec), "meta": spec.meta}, indent=1))
            else:
                _print_summary(spec)
            return 0
        if a.command == "plot":
            from .plot import plot_specimen
            out = a.out or os.path.splitext(a.specimen)[0] + ".png"
            plot_specimen(spec, out, particles=a.particles, joints=a.joints)
            print(f"wrote {out}")
            return 0
        if a.command == "defect":
            return _defect(a, spec)
        if a.command == "export":
            if not (a.geom or a.vtk):
                raise InputError("export: give --geom PATH and/or --vtk PREFIX")
            from .export import export_geom, export_vtk
            if a.geom:
                c = export_geom(spec, a.geom, name=os.path.basename(a.specimen))
                print(f"wrote {a.geom} ({c['polys']} grains, {c['nodes']} nodes, "
                      f"{c['edges']} edges)")
            if a.vtk:
                for p in export_vtk(spec, a.vtk):
                    print(f"wrote {p}")
            return 0
    except BAD_INPUT as exc:
        print(f"gbmgen: error: {_one_line(exc)}", file=sys.stderr)
        _remove_new(created)
        return 2
    except InstabilityError as exc:
        print(f"gbmgen: numerical failure: {_one_line(exc)}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("gbmgen: interrupted", file=sys.stderr)
        return 130
    return 0


def _one_line(exc) -> str:
    return " ".join(str(exc).split())


def _new_folder(argv):
    """The --out folder of ``gbmgen run`` when it does not exist yet (removed again on bad
    input, so that nothing half-written is left), else None."""
    if not argv or argv[0] != "run" or "--out" not in argv:
        return None
    k = argv.index("--out")
    path = argv[k + 1] if k + 1 < len(argv) else None
    return path if path and not os.path.exists(path) else None


def _remove_new(path):
    if path and os.path.isdir(path):
        import shutil
        shutil.rmtree(path, ignore_errors=True)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
