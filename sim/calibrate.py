"""Automatic calibration of micro-parameters against macroscopic targets (E, UCS, σt).

The method (documented in ``docs/labtests.md``), written against a black box
``evaluate(params) -> {"E": Pa, "UCS": Pa, "sigma_t": Pa}``:

1. **Knobs are multipliers** on groups of micro-parameters, applied to every mineral alike so
   that the mineral contrasts of the starting set (thesis Tables 4-3/4-4) are kept:
   ``modulus`` scales ``emod, pb_emod, sj_kn, sj_ks``; ``tensile`` scales ``pb_ten, sj_ten``;
   ``cohesion`` scales ``pb_coh, sj_coh``.
2. **Scaling laws give the first Jacobian.** In the quasi-static limit of a bonded-particle
   model the macroscopic modulus is proportional to the contact moduli (E ∝ Ē) and independent
   of strengths, and the peak stresses are homogeneous of degree one in the strengths and
   independent of the moduli. In log variables ``u = log(multipliers)`` and log responses
   ``r = log(response / target)``, the Jacobian is therefore block-structured with unit row sums
   for the strengths::

        dlogE/du   = [1, 0,     0    ]
        dlogUCS/du = [0, a,     1 - a]     a = share of UCS carried by the tensile strength
        dlogσt/du  = [0, 1 - b, b    ]     b = share of σt carried by the tensile strength

   with ``a = 0.3, b = 0.9`` as a start (UCS of BPMs is cohesion dominated, σt tension
   dominated).
3. **Secant (Broyden) iteration** ``u ← clip(u − J⁻¹ r)`` within bounds; after every evaluation
   the Jacobian is corrected by Broyden's rank-one update, so the real model's sensitivities are
   learnt without finite differences (finite differences on a DEM are dominated by the discrete
   crack noise). One evaluation per iteration; the first step is the pure scaling-law step.
4. **Seeds at the end:** the set found on one specimen is evaluated on all seeds; if the seed
   mean misses a target by more than the tolerance, one correction step is taken on the mean
   responses and the seeds are run again (at most ``seed_rounds`` times); the round with the
   best seed mean is kept. The correction uses the learnt Jacobian projected back onto the
   structure of the scaling laws (:func:`project_jacobian`: the same non-zero pattern,
   sensitivities >= 0, each row summing as in step 2): the seed mean differs from the search
   point by specimen scatter, and secant sensitivities learnt across the search's
   failure-path jumps can be inflated (on the 10 x 20 mm calibration the learnt
   dlogUCS/dlog(cohesion) was 4.4, which would make the correction ~5x too small).

The module runs no simulation; :mod:`sim.protocols.calibration` supplies the DEM black box.
"""
from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Knob", "DEFAULT_KNOBS", "DEFAULT_TARGETS", "CalibrationResult", "calibrate",
           "correction_step", "scale_parameters", "initial_jacobian", "project_jacobian"]

#: Thesis laboratory targets (REFERENCE.md), Pa.
DEFAULT_TARGETS = {"E": 65e9, "UCS": 135e6, "sigma_t": 18e6}


@dataclass(frozen=True)
class Knob:
    """A multiplier on a group of micro-parameter fields.

    Attributes
    ----------
    name : str
    fields : tuple of str
        Mineral-table or joint-table keys (``specimen.npz`` names) scaled together.
    bounds : (float, float)
        Lower and upper bound of the multiplier.
    """

    name: str
    fields: tuple
    bounds: tuple = (0.05, 20.0)


DEFAULT_KNOBS = (
    Knob("modulus", ("emod", "pb_emod", "sj_kn", "sj_ks")),
    Knob("tensile", ("pb_ten", "sj_ten")),
    Knob("cohesion", ("pb_coh", "sj_coh")),
)


@dataclass
class CalibrationResult:
    """Outcome of :func:`calibrate`.

    Attributes
    ----------
    params : dict
        Calibrated parameter dict (same layout as the input).
    multipliers : dict
        Knob name -> multiplier relative to the starting set.
    converged : bool
        Every target met within ``accept`` by the seed mean (or by the search specimen when
        no seeds were given).
    evaluations : list of dict
        One record per black-box call: ``phase`` (search|seed), ``iteration``, ``multipliers``,
        ``responses``, ``errors`` (relative), ``seconds``.
    seed_summary : dict
        Per target: ``mean, std, min, max, rel_error_of_mean`` over the seeds (empty without
        seeds).
    final_errors : dict
        Relative error per target of the final answer (seed mean, else the search specimen).
    wall_s : float
    jacobian : (T, K) ndarray
        Last secant Jacobian (d log response / d log multiplier).
    """

    params: dict
    multipliers: dict
    converged: bool
    evaluations: list = field(default_factory=list)
    seed_summary: dict = field(default_factory=dict)
    final_errors: dict = field(default_factory=dict)
    wall_s: float = 0.0
    jacobian: np.ndarray = None

    @property
    def n_evaluations(self) -> int:
        return len(self.evaluations)

    @property
    def n_iterations(self) -> int:
        return sum(1 for e in self.evaluations if e["phase"] == "search")

    def to_dict(self) -> dict:
        """JSON-able report."""
        return {"converged": self.converged, "multipliers": self.multipliers,
                "n_iterations": self.n_iterations, "n_evaluations": self.n_evaluations,
                "wall_s": self.wall_s, "final_errors": self.final_errors,
                "seed_summary": self.seed_summary, "evaluations": self.evaluations,
                "jacobian": None if self.jacobian is None else self.jacobian.tolist()}


def scale_parameters(params: dict, knobs, multipliers) -> dict:
    """A copy of ``params`` with each knob's fields multiplied by its multiplier.

    Fields are scaled in every mineral table, in ``default`` and in ``joint``.

    Examples
    --------
    >>> p = {"minerals": {"a": {"pb_ten": 2.0, "emod": 1.0}}, "joint": {"sj_ten": 3.0}}
    >>> q = scale_parameters(p, [Knob("t", ("pb_ten", "sj_ten"))], [10.0])
    >>> q["minerals"]["a"]["pb_ten"], q["joint"]["sj_ten"], p["minerals"]["a"]["pb_ten"]
    (20.0, 30.0, 2.0)
    """
    out = copy.deepcopy(params)
    tables = list((out.get("minerals") or {}).values())
    tables += [t for t in (out.get("default"), out.get("joint")) if t]
    for knob, m in zip(knobs, multipliers):
        for t in tables:
            for f in knob.fields:
                if f in t:
                    t[f] = float(t[f]) * float(m)
    return out


def initial_jacobian(targets, knobs, *, a: float = 0.3, b: float = 0.9) -> np.ndarray:
    """Scaling-law Jacobian d log(response) / d log(multiplier) (see the module notes).

    Unknown target/knob pairs start at 0, except a target and knob of the same position when
    nothing else is known (identity fallback).

    Examples
    --------
    >>> initial_jacobian(["E", "UCS", "sigma_t"], DEFAULT_KNOBS).round(6).tolist()
    [[1.0, 0.0, 0.0], [0.0, 0.3, 0.7], [0.0, 0.9, 0.1]]
    """
    table = {("E", "modulus"): 1.0,
             ("UCS", "tensile"): a, ("UCS", "cohesion"): 1.0 - a,
             ("sigma_t", "tensile"): b, ("sigma_t", "cohesion"): 1.0 - b}
    J = np.zeros((len(targets), len(knobs)))
    for i, t in enumerate(targets):
        for j, k in enumerate(knobs):
            J[i, j] = table.get((t, k.name), 0.0)
        if not np.any(J[i]) and i < len(knobs):
            J[i, i] = 1.0
    return J


def project_jacobian(J, J0) -> np.ndarray:
    """The learnt Jacobian ``J`` projected onto the structure of the scaling-law ``J0``.

    Entries where ``J0`` is zero are set to zero, the others clipped to >= 0 and each row
    rescaled to the row sum of ``J0`` (degree-one homogeneity: scaling every strength by s
    scales a peak stress by s). A row with no positive learnt entry falls back to ``J0``.

    Examples
    --------
    >>> J0 = initial_jacobian(["E", "UCS", "sigma_t"], DEFAULT_KNOBS)
    >>> project_jacobian([[0.98, -0.12, -0.02], [0.31, 0.45, 4.35], [0.08, 0.92, 0.26]],
    ...                  J0).round(3).tolist()
    [[1.0, 0.0, 0.0], [0.0, 0.094, 0.906], [0.0, 0.78, 0.22]]
    """
    J0 = np.asarray(J0, float)
    P = np.where(J0 != 0.0, np.clip(np.asarray(J, float), 0.0, None), 0.0)
    s = P.sum(axis=1)
    ok = s > 0
    P[ok] *= (J0.sum(axis=1)[ok] / s[ok])[:, None]
    P[~ok] = J0[~ok]
    return P


def _errors(resp, targets):
    return {k: float(resp[k]) / v - 1.0 for k, v in targets.items()}


def _setup(targets, knobs, jacobian):
    """Checked targets and knobs, the response names, the Jacobian and the log bounds."""
    targets = dict(DEFAULT_TARGETS if targets is None else targets)
    knobs = tuple(knobs)
    _check(targets, knobs)
    names = list(targets)
    J = initial_jacobian(names, knobs) if jacobian is None else np.array(jacobian, float)
    if J.shape != (len(names), len(knobs)):
        raise ValueError(f"'jacobian' has shape {J.shape}, expected {(len(names), len(knobs))}")
    lo = np.log([k.bounds[0] for k in knobs])
    hi = np.log([k.bounds[1] for k in knobs])
    return targets, knobs, names, J, lo, hi


def _newton_step(u, r, J, lo, hi, max_log_step):
    """``clip(u - J⁺ r)``: one least-squares step in log variables, within the bounds."""
    du = np.linalg.lstsq(J, -r, rcond=None)[0]
    du = np.clip(du, -max_log_step, max_log_step)
    return np.clip(u + du, lo, hi)


def correction_step(responses, *, targets=None, knobs=DEFAULT_KNOBS, jacobian=None,
                    max_log_step: float = math.log(4.0)) -> dict:
    """Multipliers that move the mean of ``responses`` onto ``targets``: one step, not run.

    The Newton step of :func:`calibrate`'s seed rounds on its own, for responses measured
    elsewhere (for example a preset's results on specimens pooled from its calibration and
    from a held-out check). The step is ``u = clip(-J⁺ log(mean / target))`` in log
    multipliers, with the scaling-law Jacobian (:func:`initial_jacobian`) unless one is given
    (the seed rounds pass the learnt Jacobian projected onto that structure,
    :func:`project_jacobian`). It is a prediction: evaluate the scaled set on specimens it has
    not seen.

    Parameters
    ----------
    responses : sequence of dict
        One dict per specimen with (at least) the keys of ``targets``, SI units.
    targets : dict, optional
        Default :data:`DEFAULT_TARGETS`.
    knobs : sequence of Knob
    jacobian : (T, K) array_like, optional
    max_log_step : float

    Returns
    -------
    multipliers : dict
        Knob name -> multiplier relative to the set the responses were measured at.

    Examples
    --------
    >>> m = correction_step([{"E": 65e9, "UCS": 135e6, "sigma_t": 19e6},
    ...                      {"E": 65e9, "UCS": 135e6, "sigma_t": 17.5e6}])
    >>> {k: round(v, 4) for k, v in m.items()}
    {'modulus': 1.0, 'tensile': 0.984, 'cohesion': 1.0069}
    """
    targets, knobs, names, J, lo, hi = _setup(targets, knobs, jacobian)
    if len(responses) == 0:
        raise ValueError("'responses' is empty: expected one dict per specimen")
    for i, resp in enumerate(responses):
        bad = [k for k in names if not (k in resp and float(resp[k]) > 0)]
        if bad:
            raise ValueError(f"responses[{i}] has no positive '{bad[0]}' (expected {names})")
    mean = np.array([[float(resp[k]) for k in names] for resp in responses]).mean(axis=0)
    u = _newton_step(np.zeros(len(knobs)), np.log(mean / np.array([targets[k] for k in names])),
                     J, lo, hi, max_log_step)
    return {k.name: float(m) for k, m in zip(knobs, np.exp(u))}


def _check(targets, knobs):
    if not targets:
        raise ValueError("'targets' is empty: expected e.g. {'E': 65e9, 'UCS': 135e6}")
    for k, v in targets.items():
        if not (isinstance(v, (int, float)) and v > 0 and math.isfinite(v)):
            raise ValueError(f"target '{k}' = {v!r}: expected a positive number (SI)")
    for k in knobs:
        lo, hi = k.bounds
        if not 0 < lo <= 1.0 <= hi:
            raise ValueError(f"knob '{k.name}' bounds {k.bounds}: expected 0 < lo <= 1 <= hi")


def calibrate(evaluate, params: dict, *, targets=None, knobs=DEFAULT_KNOBS, tol: float = 0.03,
              accept: float = 0.05, max_evaluations: int = 12, evaluate_seeds=None,
              seed_rounds: int = 2,
              jacobian=None, max_log_step: float = math.log(4.0),
              progress=None) -> CalibrationResult:
    """Find knob multipliers so that ``evaluate`` meets every target within ``tol``.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(params) -> dict`` with (at least) the keys of ``targets``, SI units.
    params : dict
        Starting parameter set (layout of :mod:`sim.protocols.parameters`).
    targets : dict, optional
        Response name -> target value; default :data:`DEFAULT_TARGETS`.
    knobs : sequence of Knob
        Default :data:`DEFAULT_KNOBS`.
    tol : float
        Relative tolerance of the search (default 3 %, inside the 5 % acceptance so that the
        seed mean has room); a seed mean further off than ``tol`` triggers a correction step.
    accept : float
        Acceptance: ``converged`` means every final error is within ``accept`` (default 5 %,
        the issue's criterion).
    max_evaluations : int
        Budget of search evaluations.
    evaluate_seeds : callable, optional
        ``evaluate_seeds(params) -> list of dict``: the same responses on several seeds, used
        at the end (mean, spread, one correction step if needed).
    seed_rounds : int
        Maximum number of seed evaluations rounds.
    jacobian : (T, K) array_like, optional
        Starting Jacobian in log variables; default :func:`initial_jacobian`. Its non-zero
        pattern and row sums constrain the seed correction steps (:func:`project_jacobian`).
    max_log_step : float
        Largest change of a log multiplier per iteration (default log 4).
    progress : callable, optional
        Called with each evaluation record (for logs and progress bars).

    Returns
    -------
    result : CalibrationResult

    Notes
    -----
    The best search point (smallest maximum relative error) is kept even when the budget runs
    out; ``converged`` then says False and ``final_errors`` gives the misses.
    """
    targets, knobs, names, J0, lo, hi = _setup(targets, knobs, jacobian)
    tvec = np.array([targets[k] for k in names], float)
    J = J0
    t0 = time.perf_counter()
    records = []

    def run(u, phase, it, fn):
        mult = np.exp(u)
        p = scale_parameters(params, knobs, mult)
        ts = time.perf_counter()
        out = fn(p)
        sec = time.perf_counter() - ts
        resps = out if isinstance(out, list) else [out]
        for s, resp in enumerate(resps):
            missing = [k for k in names if k not in resp]
            if missing:
                raise KeyError(f"evaluate() returned no '{missing[0]}' (expected {names})")
            seed = resp.get("specimen_index", s) if phase == "seed" else None
            rec = {"phase": phase, "iteration": it, "seed": seed,
                   "multipliers": {k.name: float(m) for k, m in zip(knobs, mult)},
                   "responses": {k: float(resp[k]) for k in names},
                   "errors": _errors(resp, targets),
                   "seconds": float(resp.get("seconds", sec / len(resps)))}
            records.append(rec)
            if progress is not None:
                progress(rec)
        return p, resps

    def logr(resp):
        v = np.array([resp[k] for k in names], float)
        return np.log(np.maximum(v, 1e-300) / tvec)

    def step(u, r, J):
        return _newton_step(u, r, J, lo, hi, max_log_step)

    u = np.zeros(len(knobs))
    best = None
    r_prev = u_prev = None
    for it in range(max_evaluations):
        p, (resp,) = run(u, "search", it, evaluate)
        r = logr(resp)
        err = float(np.max(np.abs(np.exp(r) - 1.0)))
        if best is None or err < best[0]:
            best = (err, u.copy(), p, resp)
        if u_prev is not None:
            du, dr = u - u_prev, r - r_prev
            if du @ du > 1e-14:
                J = J + np.outer(dr - J @ du, du) / (du @ du)
        if err <= tol:
            break
        u_next = step(u, r, J)
        if np.allclose(u_next, u, atol=1e-12):   # stuck at a bound
            break
        u_prev, r_prev, u = u, r, u_next

    err, u, p, resp = best
    final = _errors(resp, targets)
    seed_summary = {}
    best_round = None
    if evaluate_seeds is not None:
        for rnd in range(max(1, seed_rounds)):
            p, resps = run(u, "seed", rnd, evaluate_seeds)
            vals = np.array([[r_[k] for k in names] for r_ in resps], float)
            mean = vals.mean(axis=0)
            seed_summary = {k: {"mean": float(mean[i]), "std": float(vals[:, i].std(ddof=1))
                                if len(vals) > 1 else 0.0,
                                "min": float(vals[:, i].min()), "max": float(vals[:, i].max()),
                                "n": int(len(vals)),
                                "rel_error_of_mean": float(mean[i] / tvec[i] - 1.0)}
                            for i, k in enumerate(names)}
            final = {k: seed_summary[k]["rel_error_of_mean"] for k in names}
            worst = max(abs(v) for v in final.values())
            if best_round is None or worst < best_round[0]:
                best_round = (worst, u.copy(), p, seed_summary, final)
            if worst <= tol or rnd + 1 >= seed_rounds:
                break
            u = step(u, np.log(mean / tvec), project_jacobian(J, J0))
        # a correction round that made the seed mean worse is not kept
        _, u, p, seed_summary, final = best_round
    converged = max(abs(v) for v in final.values()) <= accept
    mult = {k.name: float(m) for k, m in zip(knobs, np.exp(u))}
    return CalibrationResult(params=p, multipliers=mult, converged=bool(converged),
                             evaluations=records, seed_summary=seed_summary,
                             final_errors=final, wall_s=time.perf_counter() - t0, jacobian=J)
