"""``gbmsim sweep SWEEP.yaml --out DIR``: every run of a sweep file, one row each in results.csv.

Writes into ``out``:

* ``sweep.yaml`` — the sweep file as given;
* ``runs/<run_id>/`` — one folder per finished run: ``config.json`` (the full normalised
  configuration), ``specimen.npz``, ``<test>/summary.json``, ``history.csv``, ``cracks.csv``,
  figures, and ``row.json`` (its results.csv row, written last: a folder with ``row.json`` is
  a finished run);
* ``results.csv`` (and ``results.parquet`` when pyarrow is installed) — one row per finished
  run in sweep order, rewritten atomically after each one, so that Ctrl-C or a lost machine
  leaves a consistent table;
* ``sweep.json`` — counts (runs, done before, computed, failed, lost), executor, times.

A run whose ``row.json`` exists is skipped on restart (a failed one too, unless
``retry_failed``: the same configuration fails the same way). The run identity is a hash of
the full configuration (:func:`gbmgen.sweep_spec.run_identity`), so an edited sweep file
reuses the runs it still holds.
"""
from __future__ import annotations

import json
import os
import pathlib
import shutil
import time
from dataclasses import dataclass, field

from .errors import InputError

__all__ = ["SweepReport", "run_sweep", "read_rows", "results_frame", "write_results_table"]


@dataclass
class SweepReport:
    """What a sweep did (also ``sweep.json``)."""

    out: str
    runs: int
    done_before: int = 0
    computed: int = 0
    failed: int = 0
    lost: int = 0
    interrupted: bool = False
    executor: str = ""
    wall_s: float = 0.0
    parquet: str = ""
    lost_errors: list = field(default_factory=list)

    @property
    def exit_code(self) -> int:
        """0 all runs ok; 1 some failed or lost; 130 interrupted."""
        if self.interrupted:
            return 130
        return 1 if (self.failed or self.lost) else 0


def _write_atomic_text(path, text):
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, path)


def _json(obj):
    from sim.protocols.outputs import json_ready
    return json.dumps(json_ready(obj), indent=1, allow_nan=False) + "\n"


def read_rows(out, runs) -> dict:
    """``run_id -> row`` of the runs of ``runs`` finished in ``out`` (their ``row.json``)."""
    rows = {}
    for run in runs:
        path = pathlib.Path(out) / "runs" / run.run_id / "row.json"
        if path.exists():
            rows[run.run_id] = json.loads(path.read_text(encoding="utf-8"))
    return rows


def results_frame(runs, rows):
    """The results table: one row per finished run, in sweep order; the options the sweep
    file gave first, then the outcome."""
    import pandas as pd
    records = []
    for run in runs:
        if run.run_id in rows:
            row = rows[run.run_id]
            given = {k: (json.dumps(v) if isinstance(v, (list, dict)) else v)
                     for k, v in run.given.items()}
            given.setdefault("test", run.config["test"])
            head = {"run_id": row["run_id"], "status": row["status"], "error": row["error"]}
            records.append({**head, **given, **row})
    return pd.DataFrame.from_records(records, columns=None if records else
                                     ["run_id", "status", "error"])


def write_results_table(out, frame) -> str:
    """Write ``results.csv`` and, with pyarrow, ``results.parquet`` atomically; returns the
    Parquet path or the reason there is none."""
    out = pathlib.Path(out)
    tmp = out / f"results.csv.tmp{os.getpid()}"
    frame.to_csv(tmp, index=False)
    os.replace(tmp, out / "results.csv")
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return "not written: pyarrow is not installed (pip install 'rockkit[sweep]')"
    tmp = out / f"results.parquet.tmp{os.getpid()}"
    _typed(frame).to_parquet(tmp, index=False)
    os.replace(tmp, out / "results.parquet")
    return str(out / "results.parquet")


def _typed(frame):
    """``frame`` with its object columns as nullable booleans or text (for Parquet)."""
    out = frame.copy()
    for c in out.columns:
        if out[c].dtype == object:
            v = out[c].dropna()
            flags = len(v) and all(isinstance(x, bool) or type(x).__name__ == "bool_"
                                   for x in v)
            out[c] = out[c].astype("boolean" if flags else "string")
    return out


def _record(out, run, outcome):
    """Write a finished run's folder (files, config.json, then row.json) atomically."""
    runs = pathlib.Path(out) / "runs"
    final = runs / run.run_id
    tmp = runs / f".{run.run_id}.tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    for rel, data in outcome["files"].items():
        path = tmp / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "config.json").write_text(_json({"run_id": run.run_id, "given": run.given,
                                            "config": run.config}), encoding="utf-8")
    (tmp / "row.json").write_text(_json(outcome["row"]), encoding="utf-8")
    shutil.rmtree(final, ignore_errors=True)
    os.replace(tmp, final)


def run_sweep(runs, out, *, sweep_text=None, name="sweep", workers=None, scheduler=None,
              progress=True, retry_failed=False) -> SweepReport:
    """Compute the runs of a sweep that ``out`` does not hold yet.

    Parameters
    ----------
    runs : list of gbmgen.sweep_spec.Run
        From :func:`gbmgen.sweep_spec.load_sweep` or a study preset.
    out : path
        Sweep folder (created; an earlier sweep there is continued).
    sweep_text : str, optional
        The sweep file's text, kept as ``sweep.yaml``.
    name : str
        Label of the progress bar.
    workers : int, optional
        Processes of the local pool (default all cores; 0 runs in this process).
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a Dask distributed scheduler (instead of the pool).
    progress : bool
        tqdm bar counting runs.
    retry_failed : bool
        Compute failed runs again.

    Returns
    -------
    report : SweepReport

    Raises
    ------
    InputError
        ``out`` is a file, or the executor cannot start.
    """
    from tqdm.auto import tqdm

    from .executors import make_executor
    out = pathlib.Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: a file, expected a folder")
    (out / "runs").mkdir(parents=True, exist_ok=True)
    for stale in (out / "runs").glob(".*.tmp"):        # a run cut off while being written
        shutil.rmtree(stale, ignore_errors=True)
    if sweep_text is not None:
        _write_atomic_text(out / "sweep.yaml", sweep_text)
    rows = read_rows(out, runs)
    todo = [r for r in runs if r.run_id not in rows
            or (retry_failed and rows[r.run_id].get("status") != "ok")]
    report = SweepReport(out=str(out), runs=len(runs), done_before=len(runs) - len(todo))
    report.failed = failed_before = sum(1 for k, r in rows.items() if r.get("status") != "ok"
                                        and k not in {t.run_id for t in todo})
    started = time.time()

    def table():
        report.parquet = write_results_table(out, results_frame(runs, rows))

    table()
    t0 = time.perf_counter()
    executor = make_executor(workers=workers, scheduler=scheduler) if todo else None
    report.executor = "" if executor is None else executor.name
    by_id = {r.run_id: r for r in todo}
    bar = tqdm(total=len(runs), initial=report.done_before, unit="run", desc=name,
               disable=not progress, dynamic_ncols=True)
    try:
        if executor is not None:
            for outcome in executor.run([r.payload() for r in todo]):
                if "lost" in outcome:
                    report.lost += 1
                    report.lost_errors.append(f"{outcome['lost']}: {outcome['error']}")
                    continue
                run = by_id[outcome["row"]["run_id"]]
                _record(out, run, outcome)
                rows[run.run_id] = outcome["row"]
                report.computed += 1
                report.failed += outcome["row"]["status"] != "ok"
                table()
                bar.update(1)
                bar.set_postfix(failed=report.failed, refresh=False)
            executor.close()
    except KeyboardInterrupt:
        report.interrupted = True
        executor.abort()
        rows = read_rows(out, runs)      # a run recorded just before Ctrl-C joins the table
        new = [rows[r.run_id] for r in todo if r.run_id in rows
               and (out / "runs" / r.run_id / "row.json").stat().st_mtime >= started]
        report.computed = len(new)
        report.failed = failed_before + sum(r["status"] != "ok" for r in new)
        table()
    finally:
        bar.close()
        report.wall_s = time.perf_counter() - t0
        _write_atomic_text(out / "sweep.json", _json(report.__dict__))
    return report
