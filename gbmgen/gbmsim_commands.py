"""``gbmsim sweep`` and ``gbmsim study``: subcommands gbmgen adds to ``gbmsim``.

``sim`` imports nothing of ours, yet a sweep builds specimens with gbmgen. So gbmgen
registers these subcommands in its package metadata (entry-point group ``rockkit.gbmsim``,
pyproject.toml) and ``sim.cli`` adds whatever that group holds. No maths here: flags map 1:1
to :func:`gbmgen.sweep.run_sweep` and the study presets. Exit codes: 0 every run ok; 1 some
runs failed or were lost; 2 bad input (one line); 130 interrupted (the table holds every
finished run; the same command continues).
"""
from __future__ import annotations

import sys

__all__ = ["register_sweep", "register_study"]


def _executor_options(p, *, out_required=True):
    p.add_argument("--out", required=out_required,
                   help="output folder (an earlier sweep there is continued: finished runs are "
                        "skipped)")
    p.add_argument("--workers", type=int, default=None,
                   help="processes of the local pool (default: all cores; 0: in this process)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="run on this Dask distributed cluster instead (pip install "
                        "'rockkit[sweep]'; start workers with --nthreads 1)")
    p.add_argument("--retry-failed", action="store_true",
                   help="compute the runs recorded as failed again")
    p.add_argument("--no-progress", action="store_true")


def register_sweep(sub):
    """Add ``gbmsim sweep SWEEP.yaml --out DIR``."""
    from sim.protocols.cli import EXIT_CODES
    p = sub.add_parser("sweep", help="a YAML grid of specimens x tests (docs/studies.md)",
                       description="Run every configuration of a sweep file; one row per run "
                       "in results.csv. " + EXIT_CODES)
    p.add_argument("sweep", metavar="SWEEP.yaml")
    _executor_options(p)
    p.set_defaults(func=_sweep)


def register_study(sub):
    """Add ``gbmsim study NAME --out DIR [--seeds N] [--size-mm W H]``."""
    from sim.protocols.cli import EXIT_CODES

    from .study import STUDIES
    p = sub.add_parser("study", help="a thesis study as a preset sweep, with its report",
                       description="Run a thesis study (a preset sweep) and write its table, "
                       "figures and report.html. " + EXIT_CODES)
    p.add_argument("name", choices=tuple(STUDIES), metavar="NAME",
                   help="one of: " + ", ".join(STUDIES))
    p.add_argument("--seeds", type=int, default=None,
                   help="seeds per case (default: the thesis's, see docs/studies.md)")
    p.add_argument("--size-mm", type=float, nargs=2, metavar=("W", "H"), default=None,
                   help="specimen width and height (default the thesis's 25 x 50 mm)")
    p.add_argument("--print-sweep", action="store_true",
                   help="print the study's sweep file (to edit and run with gbmsim sweep) "
                        "and stop")
    _executor_options(p, out_required=False)
    p.set_defaults(func=_study)


def _guarded(fn, args) -> int:
    from sim.errors import InputError as SimInputError

    from .errors import InputError
    try:
        return fn(args)
    except (InputError, SimInputError, ValueError) as exc:
        print(f"gbmsim {args.command}: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2


def _finish(report, what) -> int:
    r = report
    print(f"gbmsim {what}: {r.runs} runs: {r.done_before} done before, {r.computed} computed,"
          f" {r.failed} failed, {r.lost} lost ({r.executor or 'nothing to compute'}, "
          f"{r.wall_s:.1f} s); table {r.out}/results.csv", file=sys.stderr)
    for line in r.lost_errors[:5]:
        print(f"gbmsim {what}: lost {line}", file=sys.stderr)
    if r.interrupted:
        print(f"gbmsim {what}: interrupted: {r.done_before + r.computed} of {r.runs} runs "
              "recorded; run the same command again to compute the rest", file=sys.stderr)
    return r.exit_code


def _sweep(args) -> int:
    def go(a):
        import pathlib

        from .sweep import run_sweep
        from .sweep_spec import load_sweep
        doc, runs = load_sweep(a.sweep)
        report = run_sweep(runs, a.out, sweep_text=pathlib.Path(a.sweep).read_text("utf-8"),
                           name=str(doc.get("name") or "sweep"), workers=a.workers,
                           scheduler=a.scheduler, progress=not a.no_progress,
                           retry_failed=a.retry_failed)
        return _finish(report, "sweep")
    return _guarded(go, args)


def _study(args) -> int:
    def go(a):
        import pandas as pd
        import yaml

        from .study import THESIS_SIZE_MM, study
        from .study_report import write_study_report
        from .sweep import run_sweep
        from .sweep_spec import expand_sweep
        st = study(a.name)
        seeds = st.default_seeds if a.seeds is None else a.seeds
        if seeds < 1:
            raise ValueError(f"--seeds {seeds}: expected a whole number >= 1")
        size = tuple(a.size_mm) if a.size_mm else THESIS_SIZE_MM
        doc = st.make(seeds, size)
        text = (f"# gbmsim study {a.name} --seeds {seeds} --size-mm {size[0]:g} {size[1]:g}\n"
                + yaml.safe_dump(doc, sort_keys=False))
        if a.print_sweep:
            print(text, end="")
            return 0
        if not a.out:
            raise ValueError("--out: an output folder is needed (or give --print-sweep)")
        runs = expand_sweep(doc, where=f"study {a.name}")
        report = run_sweep(runs, a.out, sweep_text=text, name=a.name, workers=a.workers,
                           scheduler=a.scheduler, progress=not a.no_progress,
                           retry_failed=a.retry_failed)
        frame = pd.read_csv(f"{a.out}/results.csv")
        command = " ".join(["gbmsim", "study", a.name, "--seeds", str(seeds), "--size-mm",
                            f"{size[0]:g}", f"{size[1]:g}", "--out", str(a.out)])
        html, _ = write_study_report(a.out, a.name, frame, seeds=seeds, size_mm=size,
                                     command=command)
        print(f"gbmsim study: report {html}", file=sys.stderr)
        return _finish(report, "study")
    return _guarded(go, args)
