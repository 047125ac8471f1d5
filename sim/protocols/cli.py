"""Subcommands of ``gbmsim`` for the laboratory tests (one per entry of
:data:`sim.protocols.registry.TESTS`) and ``calibrate``.

``sim.cli`` calls :func:`register` with its argparse subparsers object; each subcommand sets
``func(args) -> int`` (exit codes: 0 ok, 1 a calibration target missed, 2 bad input, 3
numerical failure, 130 interrupted; the top-level ``gbmsim`` turns errors into codes). No maths
here: flags map 1:1 to the options of :func:`sim.protocols.registry.run_test`.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import warnings

__all__ = ["EXIT_CODES", "OneLineParser", "specimen_warnings", "register", "run_test_command",
           "run_calibrate_command"]

#: The exit codes of every command (README "Exit codes").
EXIT_CODES = ("Exit codes: 0 ok; 1 a batch with some failures or a check/target missed; 2 bad "
              "input (one line naming the file or field); 3 numerical failure (one line naming "
              "cause, step and hint); 130 interrupted.")



class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one stderr line (exit 2)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


@contextlib.contextmanager
def specimen_warnings():
    """Print each representativeness warning of the tests run inside as one stderr line."""
    from .skeleton import RepresentativenessWarning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RepresentativenessWarning)
        try:
            yield
        finally:
            seen = []
            for c in caught:
                if issubclass(c.category, RepresentativenessWarning) \
                        and str(c.message) not in seen:
                    seen.append(str(c.message))
            for w in seen:
                print(f"warning: {w}", file=sys.stderr)


def _common(p, *, rate=True):
    from ..config import DAMPING
    from .speed import DEFAULT_PLATEN_VELOCITY, DEFAULT_POST_PEAK, DEFAULT_TIMESTEP_FACTOR
    p.add_argument("specimen", help="specimen.npz (DESIGN.md §4)")
    p.add_argument("--out", required=True, help="results directory")
    p.add_argument("--params", metavar="FILE.yaml",
                   help="micro-parameter file applied to the specimen's minerals by name")
    if rate:
        p.add_argument("--platen-velocity", type=float, default=None,
                       help="constant speed of each platen/grip/jaw, m/s (default "
                            f"{DEFAULT_PLATEN_VELOCITY}, from the convergence study; for the "
                            "UCS, giving it selects the constant-speed mode, see --adaptive)")
        p.add_argument("--strain-rate", type=float, default=None,
                       help="loading strain rate, 1/s (overrides --platen-velocity)")
    p.add_argument("--post-peak", type=float, default=DEFAULT_POST_PEAK,
                   help="stop when the stress falls below this fraction of the peak "
                        f"(default {DEFAULT_POST_PEAK})")
    p.add_argument("--max-strain", type=float, default=None,
                   help="stop at this strain instead (elastic checks); disables --post-peak")
    p.add_argument("--damping", type=float, default=DAMPING,
                   help=f"local damping alpha (default {DAMPING})")
    p.add_argument("--timestep-factor", type=float, default=DEFAULT_TIMESTEP_FACTOR,
                   help="safety factor on the critical time step "
                        f"(default {DEFAULT_TIMESTEP_FACTOR}, from the convergence study)")
    p.add_argument("--checkpoint-every", type=int, default=0,
                   help="also write checkpoint.npz and the partial results every N "
                        "records (always on Ctrl-C); --resume continues from them")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted test from --out (checkpoint.npz, history.csv, "
                        "summary.json written on Ctrl-C or by --checkpoint-every; biaxial: "
                        "also consolidated.npz); same specimen and options")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--no-progress", action="store_true", help="no tqdm progress bar")
    p.add_argument("--ensemble", type=int, default=0, metavar="N",
                   help="run the test N times on one specimen, the particle centres of runs "
                        "1..N-1 perturbed (run 0 as given), and report every number as mean "
                        "+- sd: the failure-path scatter of a single run (--out gets "
                        "ensemble.json, ensemble.csv, member_KK/; --resume continues)")
    p.add_argument("--ensemble-amplitude", type=float, default=None, metavar="A",
                   help="perturbation of the centres relative to the mean radius "
                        "(default 1e-9)")


def register(subparsers):
    """Add one subcommand per laboratory test and ``calibrate`` to ``subparsers``."""
    from .registry import TESTS
    for name, cls in TESTS.items():
        p = subparsers.add_parser(name, help=cls.help, description=cls.help + ". " + EXIT_CODES)
        _common(p)
        p.set_defaults(func=run_test_command, test=name)
        if name == "ucs":
            p.add_argument("--adaptive", dest="adaptive", action="store_true", default=None,
                           help="adaptive platen speed (the default unless --platen-velocity "
                                "or --strain-rate is given): up to 0.1 m/s while elastic and "
                                "crack-free, the base speed when cracking, softening and "
                                "post-peak: 0.00625 m/s up to 8 mm long, a strain rate of "
                                "1.5625/s beyond; with --platen-velocity V: base V, up to 16 V "
                                "(docs/labtests.md)")
            p.add_argument("--constant-speed", dest="adaptive", action="store_false",
                           help="constant platen speed (--platen-velocity, default 0.0125 m/s)")
        if name == "tension":
            p.add_argument("--grip-depth-mm", type=float, default=None,
                           help="depth of each pulled end group, mm (default 10 %% of H)")
        if name == "brazilian":
            p.add_argument("--diameter-mm", type=float, default=None,
                           help="disc diameter, mm (default: the smaller side of the box)")
            p.add_argument("--no-cut", action="store_true",
                           help="the specimen already is a disc")
            p.add_argument("--loading", choices=("jaws", "platens"), default="jaws")
        if name == "biaxial":
            p.add_argument("--confinement-mpa", type=float, default=20.0,
                           help="confining stress sigma3, MPa (default 20, the thesis)")
    p = subparsers.add_parser("calibrate", help="fit micro-parameters to E, UCS, sigma_t",
                              description="Automatic calibration (docs/labtests.md). "
                              + EXIT_CODES)
    p.add_argument("specimens", nargs="+",
                   help="specimen.npz files: the first is used for the search, all for the "
                        "seed average at the end")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--params", metavar="FILE.yaml",
                   help="starting parameters (default: thesis Ch. 4 Tables 4-3/4-4)")
    p.add_argument("--target-e-gpa", type=float, default=65.0)
    p.add_argument("--target-ucs-mpa", type=float, default=135.0)
    p.add_argument("--target-tensile-mpa", type=float, default=18.0)
    p.add_argument("--tol", type=float, default=0.03, help="search tolerance (0.03)")
    p.add_argument("--accept", type=float, default=0.05, help="acceptance of the seed mean")
    p.add_argument("--max-evaluations", type=int, default=10)
    p.add_argument("--platen-velocity", type=float, default=None,
                   help="loading speed, m/s (default: the protocols' default)")
    p.add_argument("--tension-test", choices=("direct", "brazilian"), default="direct")
    p.add_argument("--search-on", choices=("first", "mean"), default="first",
                   help="search on the first specimen (seeds at the end) or on the seed mean")
    p.add_argument("--extra", nargs="+", default=(), metavar="SPECIMEN",
                   help="specimens used only in the seed rounds at the end (held out from "
                        "the search; the mean over all specimens drives the correction)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted calibration in --out: finished tests under "
                        "OUT/runs/ are read back instead of run again")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=run_calibrate_command)
    return subparsers


def _load(args):
    from ..specimen import Specimen
    from .parameters import apply_parameters, load_parameters
    spec = Specimen.load(args.specimen)
    if args.params:
        spec = apply_parameters(spec, load_parameters(args.params))
    return spec


def run_test_command(args) -> int:
    """Run one laboratory test (or an ensemble) from parsed arguments; print its numbers."""
    from ..errors import InputError, InstabilityError
    try:
        spec = _load(args)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    kw = dict(strain_rate=args.strain_rate, platen_velocity=args.platen_velocity,
              max_strain=args.max_strain,
              post_peak=None if args.max_strain is not None else args.post_peak,
              damping=args.damping, timestep_factor=args.timestep_factor,
              progress=not args.no_progress, checkpoint_every=args.checkpoint_every,
              figures=not args.no_figures)
    if args.test == "ucs":
        adaptive = args.adaptive
        if adaptive is None:        # default: adaptive unless a constant speed/rate was given
            adaptive = args.platen_velocity is None and args.strain_rate is None
        kw["adaptive"] = adaptive
    elif args.test == "tension":
        if args.grip_depth_mm is not None:
            kw["grip_depth"] = args.grip_depth_mm * 1e-3
    elif args.test == "brazilian":
        kw.update(cut=not args.no_cut, loading=args.loading,
                  diameter=None if args.diameter_mm is None else args.diameter_mm * 1e-3)
    else:
        kw["confinement"] = args.confinement_mpa * 1e6
    if args.ensemble_amplitude is not None and not args.ensemble:
        print("error: --ensemble-amplitude needs --ensemble N", file=sys.stderr)
        return 2
    if not args.resume:             # resuming writes nothing before its files are checked
        os.makedirs(args.out, exist_ok=True)
    try:
        with specimen_warnings():
            if args.ensemble:
                res = _run_ensemble(args, spec, kw)
            else:
                from .registry import run_test
                res = run_test(args.test, spec, out=args.out, resume=args.resume, **kw)
    except KeyboardInterrupt:
        what = ("finished members and the checkpoint of the running one"
                if args.ensemble else "checkpoint and partial results")
        print(f"interrupted: {what} in {args.out}; continue with --resume", file=sys.stderr)
        return 130
    except InstabilityError as exc:
        print(f"numerical failure: {exc}", file=sys.stderr)
        return 3
    except (InputError, ValueError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    from .outputs import json_ready
    if args.ensemble:
        st = res.stats
        report = {"runs": len(res.members), **{
            k: {"mean": st.loc[k, "mean"], "sd": st.loc[k, "sd"], "ci95": st.loc[k, "ci95"]}
            for k in _ENSEMBLE_KEYS if k in st.index}}
    else:
        report = {k: res.summary[k] for k in _KEYS if k in res.summary}
        for k in ("E", "nu"):
            if res.summary.get(f"{k}_ok") is False:
                print(f"warning: {k} not valid: {res.summary[f'{k}_reason']}", file=sys.stderr)
    print(json.dumps(json_ready(report)))
    return 0


#: Numbers the test command prints.
_KEYS = ("E_gpa", "nu", "E_ok", "nu_ok", "ucs_mpa", "ci_mpa", "cd_mpa", "tensile_mpa",
         "steps", "wall_s")
#: Numbers the ensemble command prints (mean, sd, ci95 of those the test reports).
_ENSEMBLE_KEYS = ("E_gpa", "nu", "ucs_mpa", "ci_mpa", "cd_mpa", "tensile_mpa",
                  "deviatoric_peak_mpa", "P_sim.by_area", "cracks.total", "steps", "wall_s")


def _run_ensemble(args, spec, kw):
    """``--ensemble N``: :func:`sim.protocols.ensemble.run_ensemble` with the test's options."""
    from .ensemble import DEFAULT_AMPLITUDE, run_ensemble
    amp = DEFAULT_AMPLITUDE if args.ensemble_amplitude is None else args.ensemble_amplitude
    test_kw = {k: v for k, v in kw.items() if k not in ("out", "resume", "progress", "figures")}
    return run_ensemble(args.test, spec, runs=args.ensemble, amplitude=amp, out=args.out,
                        resume=args.resume, progress=kw["progress"], figures=kw["figures"],
                        **test_kw)


def run_calibrate_command(args) -> int:
    """Calibrate from parsed arguments (see :mod:`sim.protocols.calibration`)."""
    from ..errors import InputError, InstabilityError
    from .calibration import calibrate_specimens
    targets = {"E": args.target_e_gpa * 1e9, "UCS": args.target_ucs_mpa * 1e6,
               "sigma_t": args.target_tensile_mpa * 1e6}
    try:
        res = calibrate_specimens(args.specimens, out=args.out, params=args.params,
                                  targets=targets, tol=args.tol, accept=args.accept,
                                  max_evaluations=args.max_evaluations,
                                  platen_velocity=args.platen_velocity,
                                  tension_test=args.tension_test, search_on=args.search_on,
                                  extra=args.extra, resume=args.resume,
                                  progress=not args.no_progress)
    except KeyboardInterrupt:
        print(f"interrupted: evaluations so far in {args.out}; continue with --resume",
              file=sys.stderr)
        return 130
    except InstabilityError as exc:
        print(f"numerical failure: {exc}", file=sys.stderr)
        return 3
    except (InputError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    from .outputs import json_ready
    print(json.dumps(json_ready({"converged": res.converged, "final_errors": res.final_errors,
                      "n_evaluations": res.n_evaluations,
                      "wall_s": round(res.wall_s, 1)})))
    return 0 if res.converged else 1


def main(argv=None) -> int:
    """Stand-alone entry (``python -m sim.protocols.cli``) for when ``sim.cli`` is absent."""
    parser = OneLineParser(prog="gbmsim")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":   # pragma: no cover
    raise SystemExit(main())
