"""Perturbation ensembles: one specimen, N runs of a test, each result as mean ± sd.

Near the peak a bonded-particle specimen is chaotic: which bond breaks first among many loaded
close to their strength decides the failure path, so a rounding-level change (summing the
forces in another order) moves one specimen's UCS by several per cent (docs/labtests.md,
"Thesis-scale time"). A single run's strength is therefore one draw. This module makes the
draw explicit: member 0 is the specimen as given (the plain test), member k >= 1 has every
particle centre moved by ``amplitude`` × the mean radius × a standard normal number (seeded by
k; 1e-9 by default, far below any physical tolerance and far above the rounding of the
coordinates). The spread of the members is the failure-path scatter of that one specimen; the
spread over gbmgen seeds adds the scatter of the microstructure.

Results directory (``out``)::

    ensemble.json        config, per-member numbers, statistics (status running/interrupted/
                         complete); written after every member
    ensemble.csv         one row per finished member (the numbers of its summary.json)
    ensemble_curves.png  every member's stress-strain curve
    member_00/ ...       each member's full test output (summary.json, history.csv, ...)

Ctrl-C stops inside a member, which writes its checkpoint as a single test does; ``resume=True``
(``--resume``) skips the finished members, continues the interrupted one and runs the rest. A
larger ``runs`` on resume extends the ensemble.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .options import split_options
from .outputs import json_ready, write_csv_atomic, write_json_atomic
from .registry import protocol, run_test

__all__ = ["DEFAULT_AMPLITUDE", "EnsembleResult", "perturb", "result_numbers",
           "ensemble_stats", "run_ensemble"]

#: Default perturbation of the particle centres, relative to the mean radius.
DEFAULT_AMPLITUDE = 1e-9
#: Summary entries that describe the set-up or the machine, not the test's outcome.
NOT_RESULTS = frozenset({"n_particles", "n_bonds", "dt_s", "particle_steps_per_s",
                         "force_chunks", "threads", "representative"})
#: Test keywords that change neither the numbers nor the files' meaning (not checked on resume).
PRESENTATION = frozenset({"progress", "figures", "checkpoint_every"})
_FILE = "ensemble.json"


def member_dir(out, k: int) -> str:
    """Results directory of member ``k`` inside ``out``."""
    return os.path.join(out, f"member_{k:02d}")


def perturb(specimen, member: int, amplitude: float = DEFAULT_AMPLITUDE):
    """Copy of ``specimen`` with its particle centres perturbed for ensemble member ``member``.

    Parameters
    ----------
    specimen : sim.Specimen
    member : int
        0 leaves the centres as they are; k >= 1 adds ``amplitude`` × mean radius ×
        N(0, 1) to every x and y, drawn from ``numpy.random.default_rng(k)``.
    amplitude : float
        Size of the perturbation relative to the mean radius (> 0).

    Returns
    -------
    specimen : sim.Specimen
        ``meta["perturbation"]`` records ``member``, ``amplitude_rel`` and the rms
        displacement in m.

    Examples
    --------
    >>> from sim import Specimen
    >>> s = Specimen.lattice(nx=4, ny=4, radius=1e-3)
    >>> p = perturb(s, 1, 1e-6)
    >>> bool(np.all(p.x != s.x)), float(np.abs(p.x - s.x).max()) < 1e-8
    (True, True)
    >>> perturb(s, 0).meta["perturbation"]["rms_displacement_m"]
    0.0
    """
    if not (isinstance(member, (int, np.integer)) and member >= 0):
        raise ValueError(f"ensemble member must be an integer >= 0, got {member!r}")
    if not (math.isfinite(amplitude) and amplitude > 0):
        raise ValueError(f"perturbation amplitude must be a positive number, got {amplitude!r}")
    x, y = np.array(specimen.x, float), np.array(specimen.y, float)
    rms = 0.0
    if member > 0:
        scale = amplitude * float(np.mean(specimen.r))
        d = np.random.default_rng(int(member)).standard_normal((2, x.size)) * scale
        x, y = x + d[0], y + d[1]
        rms = float(np.sqrt(np.mean(d[0] ** 2 + d[1] ** 2)))
    meta = dict(specimen.meta)
    meta["perturbation"] = {"member": int(member), "amplitude_rel": float(amplitude),
                            "rms_displacement_m": rms}
    return dataclasses.replace(specimen, x=x, y=y, meta=meta)


def result_numbers(summary: dict) -> dict:
    """The outcome numbers of one test's summary, flattened (``cracks.total``, ``P_sim.by_area``).

    Leaves out set-up and machine entries (:data:`NOT_RESULTS`), texts and options; keeps the
    step count and wall time (cost). ``None`` (a JSON NaN) becomes NaN.
    """
    def number(v):
        return v is None or (isinstance(v, (int, float, np.number)) and not isinstance(v, bool))

    out = {}
    for k, v in summary.items():
        if k in NOT_RESULTS or k in ("specimen", "options"):
            continue
        if isinstance(v, dict):
            out.update({f"{k}.{kk}": (math.nan if vv is None else float(vv))
                        for kk, vv in v.items() if number(vv)})
        elif number(v):
            out[k] = math.nan if v is None else float(v)
    return out


def ensemble_stats(members: pd.DataFrame) -> pd.DataFrame:
    """Mean, sd, standard error, 95 % interval of the mean, min, max per numeric column.

    Parameters
    ----------
    members : pandas.DataFrame
        One row per member (columns of :func:`result_numbers`; ``member`` is skipped).

    Returns
    -------
    stats : pandas.DataFrame
        Index the quantity (columns without a finite value are left out); columns
        ``n, mean, sd, sem, ci95, min, max, cv_pct``. ``sd`` has
        ddof 1 (NaN for one member); ``ci95`` is the half-width t(0.975, n-1) × sem.

    Examples
    --------
    >>> t = ensemble_stats(pd.DataFrame({"member": [0, 1, 2], "ucs_mpa": [100.0, 110.0, 120.0]}))
    >>> t.loc["ucs_mpa", ["n", "mean", "sd"]].tolist()
    [3.0, 110.0, 10.0]
    """
    from scipy.stats import t as student_t
    cols = [c for c in members.columns if c != "member"
            and pd.api.types.is_numeric_dtype(members[c])]
    rows = {}
    for c in cols:
        v = members[c].to_numpy(float)
        v = v[np.isfinite(v)]
        n = v.size
        if n == 0:                      # never a number (e.g. engine_error: null)
            continue
        mean = float(v.mean()) if n else math.nan
        sd = float(v.std(ddof=1)) if n > 1 else math.nan
        sem = sd / math.sqrt(n) if n > 1 else math.nan
        rows[c] = {"n": float(n), "mean": mean, "sd": sd, "sem": sem,
                   "ci95": float(student_t.ppf(0.975, n - 1)) * sem if n > 1 else math.nan,
                   "min": float(v.min()) if n else math.nan,
                   "max": float(v.max()) if n else math.nan,
                   "cv_pct": 100.0 * sd / abs(mean) if n > 1 and mean != 0 else math.nan}
    return pd.DataFrame.from_dict(rows, orient="index",
                                  columns=["n", "mean", "sd", "sem", "ci95", "min", "max",
                                           "cv_pct"])


@dataclass
class EnsembleResult:
    """Outcome of a perturbation ensemble.

    Attributes
    ----------
    members : pandas.DataFrame
        One row per finished member: ``member`` and the numbers of its summary.
    stats : pandas.DataFrame
        :func:`ensemble_stats` of ``members``.
    summary : dict
        The ``ensemble.json`` content.
    histories : list of pandas.DataFrame
        Each finished member's history, in member order.
    files : dict
        Paths written (empty without ``out``).
    """

    members: pd.DataFrame
    stats: pd.DataFrame
    summary: dict
    histories: list = field(default_factory=list)
    files: dict = field(default_factory=dict)

    def mean(self, key: str) -> float:
        """Ensemble mean of ``key`` (e.g. ``"ucs_mpa"``)."""
        return float(self.stats.loc[key, "mean"])

    def sd(self, key: str) -> float:
        """Ensemble standard deviation (ddof 1) of ``key``."""
        return float(self.stats.loc[key, "sd"])


def _fingerprint(specimen) -> str:
    h = hashlib.sha256()
    for a in (specimen.x, specimen.y, specimen.r):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(str(specimen.n_bonds).encode())
    return h.hexdigest()


def _config(test, specimen, amplitude, test_kw) -> dict:
    """What fixes the members' numbers: test, amplitude, specimen, every test option (the
    defaults filled in, so equal runs compare equal however they were called)."""
    cls = protocol(test)
    shared, own = split_options(cls, test_kw)
    skip = PRESENTATION | {"out", "resume"}
    opts = {k: v for k, v in dataclasses.asdict(shared).items() if k not in skip}
    opts.update(dataclasses.asdict(cls(**own)))
    return json_ready({"test": test, "amplitude_rel": float(amplitude),
                       "specimen_sha256": _fingerprint(specimen),
                       "n_particles": specimen.n_particles,
                       "test_options": dict(sorted(opts.items()))})


def _check_resume(path, config) -> None:
    """Check the ``ensemble.json`` at ``path`` against ``config`` (ValueError names it)."""
    if not os.path.exists(path):
        raise FileNotFoundError(f"cannot resume: missing {path}")
    try:
        with open(path, encoding="utf-8") as f:
            old = json.load(f)
    except json.JSONDecodeError as exc:
        raise ValueError(f"cannot resume: {path} is not JSON ({exc})") from None
    if not isinstance(old, dict) or "config" not in old:
        raise ValueError(f"cannot resume: {path} is not an ensemble file (no 'config')")
    for k in ("test", "amplitude_rel", "specimen_sha256", "test_options"):
        if old["config"].get(k) != config[k]:
            what = ("another specimen" if k == "specimen_sha256" else
                    f"{old['config'].get(k)!r}, this run {config[k]!r}")
            raise ValueError(f"cannot resume: {path} has config.{k} = {what}; give the "
                             "interrupted ensemble's specimen and options")


def _clear(out) -> None:
    """Remove a previous ensemble's members and files from ``out`` (a fresh run replaces it,
    so that a later resume cannot take a member of the old one for its own)."""
    import re
    import shutil
    if not os.path.isdir(out):
        return
    for name in os.listdir(out):
        p = os.path.join(out, name)
        if re.fullmatch(r"member_\d{2,}", name) and os.path.isdir(p):
            shutil.rmtree(p)
        elif name in ("ensemble.csv", "ensemble_curves.png"):
            os.remove(p)


def _member_state(d) -> str:
    """``complete``, ``partial`` (resumable files) or ``new`` for a member directory."""
    path = os.path.join(d, "summary.json")
    if not os.path.exists(path):
        return "new"
    try:
        with open(path, encoding="utf-8") as f:
            s = json.load(f)
    except (json.JSONDecodeError, OSError):
        return "new"
    if s.get("status") == "complete":
        return "complete"
    return "partial" if os.path.exists(os.path.join(d, "checkpoint.npz")) else "new"


def plot_curves(histories, path, *, test: str, title: str = "", peak=None) -> str:
    """Every member's stress-strain curve in one figure (member 0 in black, on top).

    ``peak``: (mean, sd) of the peak stress, drawn as a line and a band.
    """
    from .outputs import _pyplot, _save_figure
    plt = _pyplot()
    cls = protocol(test)
    xcol, ycol = cls.strain_key, cls.stress_key
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    n = len(histories)
    for k in [*range(1, n), 0][:n]:
        h = histories[k]
        if xcol in h and ycol in h:
            ax.plot(np.asarray(h[xcol]) * 1e3, h[ycol], lw=1.2 if k == 0 else 0.8,
                    color="k" if k == 0 else plt.cm.viridis(k / max(1, n - 1)),
                    label="member 0 (unperturbed)" if k == 0 else None,
                    alpha=1 if k == 0 else 0.8)
    if peak is not None and np.all(np.isfinite(peak)):
        mean, sd = peak
        ax.axhline(mean, color="tab:red", ls=":", lw=0.9,
                   label=f"peak {mean:.1f} ± {sd:.1f} (mean ± sd)")
        ax.axhspan(mean - sd, mean + sd, color="tab:red", alpha=0.12, lw=0)
    ax.set_xlabel(f"{xcol} (10^-3)")
    ax.set_ylabel(f"{ycol}")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return _save_figure(fig, path)


def run_ensemble(test: str, specimen, *, runs: int, amplitude: float = DEFAULT_AMPLITUDE,
                 out=None, resume: bool = False, progress: bool = True, figures: bool = True,
                 **test_kw) -> EnsembleResult:
    """Run ``test`` on ``runs`` perturbed copies of ``specimen``; mean ± sd of every number.

    Parameters
    ----------
    test : {"ucs", "tension", "brazilian", "biaxial"}
    specimen : sim.Specimen
    runs : int
        Members (>= 2): member 0 unperturbed, members 1.. perturbed (:func:`perturb`).
    amplitude : float
        Perturbation of the centres relative to the mean radius (default 1e-9).
    out : path, optional
        Results directory (layout in the module docstring); each member writes the full
        outputs of the test into ``member_KK/``.
    resume : bool
        Continue an ensemble in ``out``: finished members are read, not run; an interrupted
        member resumes from its checkpoint; the rest run. ``test``, ``amplitude``, the
        specimen and the test options must be those of ``ensemble.json`` (checked before
        anything runs); ``runs`` may be larger. Without it, an ensemble already in ``out``
        is replaced (its ``member_KK/`` directories are removed first).
    progress, figures : bool
        Progress bars (one over the members, one per member); PNG figures.
    **test_kw
        Options of the test (:func:`sim.protocols.registry.run_test`: shared ones such as
        ``platen_velocity``, ``max_strain``, and the test's own such as ``confinement``), the
        same for every member.

    Returns
    -------
    result : EnsembleResult

    Raises
    ------
    ValueError
        ``runs`` < 2, an unknown test; with ``resume``, an
        ``ensemble.json`` of another test, amplitude, specimen or options (FileNotFoundError:
        none). KeyboardInterrupt is re-raised after the interrupted member's checkpoint and
        ``ensemble.json`` (status ``interrupted``) are written.

    Examples
    --------
    An elastic check on a bonded lattice (unbreakable bonds, E = 89.07 GPa by the lattice
    formula): the damped response differs between members by far less than a per cent.

    >>> from sim import Specimen
    >>> s = Specimen.lattice(nx=16, ny=24, radius=1e-3, gap=2e-3)
    >>> res = run_ensemble("ucs", s, runs=2, max_strain=5e-4, strain_rate=2.0, progress=False)
    >>> round(res.mean("E_gpa")), bool(0 < res.sd("E_gpa") < 0.01 * res.mean("E_gpa"))
    (89, True)
    """
    peak = protocol(test).peak
    if not (isinstance(runs, (int, np.integer)) and runs >= 2):
        raise ValueError(f"an ensemble needs runs >= 2, got {runs!r}")
    specimen = specimen.validate("specimen")
    config = _config(test, specimen, amplitude, test_kw)
    path = None if out is None else os.path.join(out, _FILE)
    if resume:
        if out is None:
            raise ValueError("'resume' needs 'out' (the interrupted ensemble's directory)")
        _check_resume(path, config)
    elif out is not None:
        _clear(out)
    histories, rows = [], []
    status = "running"

    def write():
        members = pd.DataFrame(rows)
        stats = ensemble_stats(members) if len(rows) else ensemble_stats(pd.DataFrame())
        summary = {"test": test, "status": status, "runs": int(runs),
                   "finished": len(rows), "config": config,
                   "stats": {k: stats.loc[k].to_dict() for k in stats.index},
                   "members": rows}
        files = {}
        if out is not None:
            files[_FILE] = write_json_atomic(path, summary)
            if len(rows):
                files["ensemble.csv"] = write_csv_atomic(os.path.join(out, "ensemble.csv"),
                                                         members)
        return members, stats, json_ready(summary), files

    if out is not None:                 # config on disk before the first member runs
        write()
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=runs, desc=f"{test} ensemble", unit="run")
    try:
        for k in range(runs):
            d = None if out is None else member_dir(out, k)
            state = _member_state(d) if (resume and d is not None) else "new"
            if state == "complete":
                with open(os.path.join(d, "summary.json"), encoding="utf-8") as f:
                    s = json.load(f)
                h = pd.read_csv(os.path.join(d, "history.csv"))
            else:
                if d is not None and state == "new":
                    os.makedirs(d, exist_ok=True)
                r = run_test(test, perturb(specimen, k, amplitude), out=d,
                             resume=state == "partial", progress=progress, figures=figures,
                             **test_kw)
                s, h = json_ready(r.summary), r.history
            rows.append({"member": k, **result_numbers(s)})
            histories.append(h)
            if out is not None:
                write()
            if bar is not None:
                bar.update(1)
                if peak in rows[-1]:
                    bar.set_postfix({peak: f"{rows[-1][peak]:.1f}"})
    except KeyboardInterrupt:
        if out is not None:
            from .loop import second_ctrl_c_waits
            status = "interrupted"
            with second_ctrl_c_waits():
                write()
        raise
    finally:
        if bar is not None:
            bar.close()
    status = "complete"
    members, stats, summary, files = write()
    if out is not None and figures:
        key = peak
        files["ensemble_curves.png"] = plot_curves(
            histories, os.path.join(out, "ensemble_curves.png"), test=test,
            title=f"{test}: {runs} members, centres perturbed by {amplitude:g} x mean radius",
            peak=(stats.loc[key, "mean"], stats.loc[key, "sd"]) if key in stats.index else None)
    return EnsembleResult(members=members, stats=stats, summary=summary,
                          histories=histories, files=files)
