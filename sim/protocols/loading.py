"""Shared machinery of the laboratory protocols: platens, gauges, crack tallies, the loading loop.

Everything that touches the engine (:class:`sim.simulation.Simulation`) goes through the small
functions here, so that the protocols hold no engine details. Sign convention of everything
returned: **compression positive** (stress and strain).
"""
from __future__ import annotations

import contextlib
import math
import os
import signal
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..analysis import CRACK_KINDS, is_post_peak
from ..errors import InstabilityError
from .outputs import CRACK_COLUMNS, HISTORY_COLUMNS

__all__ = ["DEFAULT_PLATEN_VELOCITY", "DEFAULT_TIMESTEP_FACTOR", "loading_rate",
           "loop_steps", "relieve_overlaps", "DEFAULT_POST_PEAK", "RECORD_STRAIN", "GAUGE_FRACTION",
           "make_simulation", "add_platens", "gauge_indices", "side_indices",
           "gauge_strains", "side_lateral_strain", "crack_frame", "crack_tally", "energies",
           "LoadingLoop", "StopRule", "AdaptiveSpeed", "ADAPTIVE_DEFAULT",
           "ADAPTIVE_BASE_VELOCITY", "ADAPTIVE_BASE_STRAIN_RATE", "ADAPTIVE_FAST_VELOCITY",
           "adaptive_speeds"]

#: Default loading speed, m/s: each platen (grip, jaw) moves at this speed, so the loading
#: strain rate is 2 v / L. Quasi-static accuracy depends on v / c_p (the loading time to the peak
#: in P-wave transits is ε_peak c_p / (2 v), independent of the specimen size), so the default is
#: a speed, not a strain rate. Chosen by benchmarks/ucs_convergence.py (docs/labtests.md): on
#: three Scenario-1 specimens UCS and E at 0.0125 m/s are within 2.0 % / 2.2 % of 0.00625 m/s;
#: at 0.025 m/s E was 6.4 % off on one of them.
DEFAULT_PLATEN_VELOCITY = 0.0125
#: Default safety factor on the critical time step of the lab tests (the engine's is 0.5).
#: Accuracy would allow 0.8 (UCS and E within 0.7 % / 0.4 % of 0.3, benchmarks/ucs_convergence.py,
#: 1.6x cheaper), but a calibrated Scenario-1 specimen went unstable at 0.8 after the peak
#: (fragments form new contacts between time-step updates). 0.6 against 0.5 on four 10 x 20 mm
#: calibrated specimens (one thread): UCS +0.06/+0.05/+1.17/-0.01 %, E +0.03/+0.35/-0.43/+0.01 %,
#: every run stable to 80 % post-peak, 16-19 % fewer steps (docs/labtests.md).
DEFAULT_TIMESTEP_FACTOR = 0.6
#: Default post-peak stop: the run ends when the stress falls below this fraction of the peak.
DEFAULT_POST_PEAK = 0.8
#: Axial strain between two history records (the record interval is derived from it).
RECORD_STRAIN = 2e-5
#: The strain gauge is the central region spanning this fraction of the width and height.
GAUGE_FRACTION = 0.5


def loading_rate(strain_rate, platen_velocity, length):
    """Loading strain rate (1/s) and the speed of each platen (m/s) for a gauge ``length``.

    ``strain_rate`` wins when given; otherwise ``strain_rate = 2 platen_velocity / length``.

    Examples
    --------
    >>> loading_rate(None, 0.05, 0.05)
    (2.0, 0.05)
    >>> loading_rate(1.0, 0.05, 0.05)
    (1.0, 0.025)
    """
    if strain_rate is None:
        if not (platen_velocity > 0 and math.isfinite(platen_velocity)):
            raise ValueError(f"'platen_velocity' = {platen_velocity!r}, expected > 0 m/s")
        return 2.0 * platen_velocity / length, float(platen_velocity)
    if not (isinstance(strain_rate, (int, float)) and strain_rate > 0
            and math.isfinite(strain_rate)):
        raise ValueError(f"'strain_rate' = {strain_rate!r}, expected a positive number (1/s)")
    return float(strain_rate), 0.5 * strain_rate * length


def loop_steps(strain_rate, dt, *, record_strain, ramp_records, max_strain, limit_strain,
               resumed=None):
    """Steps between two records and the step limit of a strain-controlled loading loop.

    A record every ``record_strain`` of loading strain; the limit is the stop strain
    (``max_strain``, at most ``limit_strain``) plus the ramp's lag, and one record more.
    ``resumed`` (the state read back by :mod:`sim.protocols.resume`) keeps the interrupted
    run's ``chunk_steps`` and ``max_steps``.

    Returns
    -------
    chunk, max_steps : int

    Examples
    --------
    >>> loop_steps(1.0, 1e-6, record_strain=2e-5, ramp_records=5, max_strain=None,
    ...            limit_strain=0.01)
    (20, 10120)
    """
    if resumed is not None:
        return resumed.chunk_steps, resumed.max_steps
    chunk = max(1, int(round(record_strain / (strain_rate * dt))))
    stop_strain = max_strain if max_strain is not None else limit_strain
    max_steps = int(math.ceil((min(stop_strain, limit_strain) + ramp_records * record_strain)
                              / (strain_rate * dt))) + chunk
    return chunk, max_steps


def relieve_overlaps(specimen):
    """A copy of ``specimen`` whose particles do not overlap, and what was changed.

    PFC bonds a packing and then zeroes the linear contact forces (thesis App. E: ``lin_mode 1``
    with the forces reset after bonding), so the initial overlaps of a packing carry no force.
    The engine's linear law is overlap based (``lin_mode 0``): a packing with overlaps of 0.2 %
    of a radius starts with tens of MPa of locked-in stress and breaks bonds before loading.
    This removes the overlaps geometrically instead: each particle's radius shrinks by half of
    its largest overlap (so that r_i + r_j <= d_ij for every pair), and ``box`` is set to the
    particles' extent so that the platens start touching.

    Returns
    -------
    specimen : sim.Specimen
    info : dict
        ``n_overlaps``, ``max_overlap_rel`` (largest overlap / smaller radius before) and
        ``max_radius_change_rel``.

    Examples
    --------
    >>> from sim import Specimen
    >>> s = Specimen.lattice(nx=3, ny=2, radius=1e-3, gap=-1e-3)   # 0.2 % overlaps
    >>> t, info = relieve_overlaps(s)
    >>> info["n_overlaps"], round(info["max_radius_change_rel"], 6)
    (9, 0.001)
    """
    import dataclasses

    from scipy.spatial import cKDTree
    x, y, r = specimen.x, specimen.y, specimen.r
    pairs = cKDTree(np.c_[x, y]).query_pairs(2.0 * float(r.max()), output_type="ndarray")
    cut = np.zeros_like(r)
    n_ov, worst = 0, 0.0
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        ov = r[i] + r[j] - np.hypot(x[j] - x[i], y[j] - y[i])
        hit = ov > 0
        n_ov = int(hit.sum())
        if n_ov:
            i, j, ov = i[hit], j[hit], ov[hit] * (1.0 + 1e-9)
            worst = float(np.max(ov / np.minimum(r[i], r[j])))
            np.maximum.at(cut, i, 0.5 * ov)
            np.maximum.at(cut, j, 0.5 * ov)
    r2 = r - cut
    box = np.array([(x - r2).min(), (x + r2).max(), (y - r2).min(), (y + r2).max()])
    meta = dict(specimen.meta)
    info = {"n_overlaps": n_ov, "max_overlap_rel": worst,
            "max_radius_change_rel": float(np.max(cut / r))}
    meta["relieved_overlaps"] = info
    return dataclasses.replace(specimen, r=r2, box=box, meta=meta), info


def make_simulation(specimen, **options):
    """Build the engine's Simulation from a specimen (keyword options passed through)."""
    from ..simulation import Simulation
    return Simulation(specimen, **options)


def add_platens(sim, box, *, axis: int = 1, fric: float = 0.0, emod=None):
    """Two rigid frictionless platens on the faces of ``box`` normal to ``axis`` (1 = y).

    Returns
    -------
    lo, hi : int
        Wall indices of the platen at the low and at the high face; normals point inwards.
    """
    xmin, xmax, ymin, ymax = (float(v) for v in box)
    kw = dict(fric=fric) if emod is None else dict(fric=fric, emod=emod)
    if axis == 1:
        lo = sim.add_wall((0.5 * (xmin + xmax), ymin), (0.0, 1.0), **kw)
        hi = sim.add_wall((0.5 * (xmin + xmax), ymax), (0.0, -1.0), **kw)
    else:
        lo = sim.add_wall((xmin, 0.5 * (ymin + ymax)), (1.0, 0.0), **kw)
        hi = sim.add_wall((xmax, 0.5 * (ymin + ymax)), (-1.0, 0.0), **kw)
    return lo, hi


def platen_gap(sim, lo: int, hi: int, axis: int = 1) -> float:
    """Distance between two parallel platens, m."""
    return float(np.asarray(sim.wall_position(hi))[axis] - np.asarray(sim.wall_position(lo))[axis])


def platen_force(sim, lo: int, hi: int, axis: int = 1) -> float:
    """Mean compressive force of the particles on two facing platens, N (compression +)."""
    f_lo = np.asarray(sim.wall_force(lo), float)[axis]     # pushed towards -axis: negative
    f_hi = np.asarray(sim.wall_force(hi), float)[axis]     # pushed towards +axis: positive
    return 0.5 * (f_hi - f_lo)


def gauge_indices(x, y, box, *, fraction: float = GAUGE_FRACTION, min_count: int = 6):
    """Particles whose centres lie in the central ``fraction`` of the box in x and in y.

    Returns
    -------
    idx : (G,) ndarray of int64
    """
    xmin, xmax, ymin, ymax = box
    cx, cy = 0.5 * (xmin + xmax), 0.5 * (ymin + ymax)
    hx, hy = 0.5 * fraction * (xmax - xmin), 0.5 * fraction * (ymax - ymin)
    idx = np.nonzero((np.abs(x - cx) <= hx) & (np.abs(y - cy) <= hy))[0]
    if idx.size < min_count:
        raise ValueError(f"strain gauge holds {idx.size} particles, expected >= {min_count}: "
                         "the specimen is too small for gauge fraction {fraction}")
    return idx


def side_indices(x, r, box, *, depth=None):
    """Particles touching the left and the right face of ``box`` (within ``depth``, m).

    ``depth`` defaults to one mean diameter.
    """
    d = 2.0 * float(np.mean(r)) if depth is None else depth
    left = np.nonzero(x - r <= box[0] + d)[0]
    right = np.nonzero(x + r >= box[1] - d)[0]
    return left, right


def gauge_strains(x0, y0, x, y, idx):
    """Mean strain of a particle region by a least-squares affine fit of the displacements.

    Fits ``u = c + A (X - X̄)`` to the displacements of the particles ``idx`` (like strain gauges
    glued on the central part of a lab specimen: platen contact compliance is excluded).

    Parameters
    ----------
    x0, y0, x, y : (N,) ndarray of float64, m
        Reference and current positions.
    idx : (G,) ndarray of int

    Returns
    -------
    eps_xx, eps_yy : float
        Normal strains, **compression positive** (``-du_x/dX``, ``-du_y/dY``).

    Examples
    --------
    >>> X, Y = np.meshgrid(np.arange(3.0), np.arange(3.0))
    >>> X, Y = X.ravel(), Y.ravel()
    >>> exx, eyy = gauge_strains(X, Y, X * 1.001, Y * 0.998, np.arange(9))
    >>> round(exx, 12), round(eyy, 12)
    (-0.001, 0.002)
    """
    X, Y = x0[idx], y0[idx]
    M = np.c_[np.ones(idx.size), X - X.mean(), Y - Y.mean()]
    ux, uy = x[idx] - X, y[idx] - Y
    cx = np.linalg.lstsq(M, ux, rcond=None)[0]
    cy = np.linalg.lstsq(M, uy, rcond=None)[0]
    return -float(cx[1]), -float(cy[2])


def side_lateral_strain(x0, x, left, right) -> float:
    """Lateral strain from the mean positions of the side particles (compression +)."""
    w0 = x0[right].mean() - x0[left].mean()
    w = x[right].mean() - x[left].mean()
    return float((w0 - w) / w0)


def _cracks_obj(sim):
    return getattr(sim, "cracks", None)


def crack_frame(sim) -> pd.DataFrame:
    """The engine's crack log as a DataFrame with at least :data:`CRACK_COLUMNS`."""
    log = _cracks_obj(sim)
    frame = log.to_frame() if log is not None else pd.DataFrame()
    frame = frame.copy()
    for c in CRACK_COLUMNS:
        if c not in frame:
            frame[c] = pd.Series(dtype=float)
    rest = [c for c in frame.columns if c not in CRACK_COLUMNS]
    return frame[list(CRACK_COLUMNS) + rest]


def crack_tally(sim) -> dict:
    """Cumulative crack counts by kind (:data:`sim.analysis.CRACK_KINDS`) and total."""
    log = _cracks_obj(sim)
    out = dict.fromkeys(CRACK_KINDS, 0)
    if log is None:
        out["total"] = 0
        return out
    counts = getattr(log, "counts", None)
    if callable(counts):
        c = counts()
        out.update({k: int(c.get(k, 0)) for k in CRACK_KINDS})
    else:
        f = log.to_frame()
        if len(f):
            key = f["kind"].astype(str) + "_" + f["mode"].astype(str)
            out.update({k: int((key == k).sum()) for k in CRACK_KINDS})
    out["total"] = int(sum(out[k] for k in CRACK_KINDS))
    return out


def energies(sim) -> tuple:
    """(kinetic, strain) energy, J, from ``sim.energy()`` when the engine provides them."""
    e = sim.energy() if hasattr(sim, "energy") else {}
    if not isinstance(e, dict):
        return math.nan, math.nan
    kin = e.get("kinetic", e.get("kinetic_j", math.nan))
    strain = e.get("strain", e.get("strain_j", e.get("bond_strain", math.nan)))
    if "strain" not in e and "strain_j" not in e:
        parts = [v for k, v in e.items() if "strain" in k]
        strain = float(sum(parts)) if parts else strain
    return float(kin), float(strain)


#: The adaptive platen speed is the default of the UCS (see :class:`AdaptiveSpeed`).
ADAPTIVE_DEFAULT = True
#: Base (slowest) speed of the adaptive rule, m/s: the speed while cracks form, the specimen
#: softens and after the peak. benchmarks/ucs_adaptive.py: with base 0.0125 m/s (and up to
#: 8x) E missed the 0.00625 m/s constant-speed reference by 6.4 % on one of three 4 x 8 mm
#: Scenario-1 specimens; with base 0.00625 m/s and up to 16x (0.1 m/s) UCS is within 0.8 %
#: and E within 0.32 % on three of four specimens, +2.29 % on the fourth (its reference repeat
#: with a 10 % smaller step differs by 2.36 %; docs/labtests.md).
ADAPTIVE_BASE_VELOCITY = 0.00625
#: Base (cracking-phase) strain rate of the adaptive rule, 1/s: the rate of the base speed on
#: the 8 mm specimens where it was validated (2 x 0.00625 / 0.008). Cracking is a local
#: process (a bond break relaxes over a few particle transits, whatever the specimen size), so
#: its error is set by the strain gained during that relaxation, i.e. by the strain rate; a
#: longer specimen may crack at a proportionally higher platen speed
#: (benchmarks/ucs_adaptive.py on 10 x 20 mm specimens, docs/labtests.md "Size-aware base
#: speed"). See :func:`adaptive_speeds`.
ADAPTIVE_BASE_STRAIN_RATE = 2.0 * ADAPTIVE_BASE_VELOCITY / 0.008
#: Fastest platen speed of the adaptive rule, m/s (16 x the 8 mm base speed): quasi-staticity of
#: the elastic phase depends on v / c_p, not on the size.
ADAPTIVE_FAST_VELOCITY = 16.0 * ADAPTIVE_BASE_VELOCITY


def adaptive_speeds(length):
    """Base platen speed (m/s) and largest speed factor of the adaptive rule for a specimen
    of loaded ``length`` (m).

    The base speed is the larger of :data:`ADAPTIVE_BASE_VELOCITY` and the speed that loads at
    :data:`ADAPTIVE_BASE_STRAIN_RATE` (both platens moving); the largest factor brings the
    fast phase to :data:`ADAPTIVE_FAST_VELOCITY` (at least 1).

    Examples
    --------
    >>> adaptive_speeds(0.008)                 # the validated size: 0.00625 m/s, 16x
    (0.00625, 16.0)
    >>> v, f = adaptive_speeds(0.05)           # thesis scale: cracks at 0.039 m/s
    >>> round(v, 6), round(f, 3)
    (0.039062, 2.56)
    """
    v = max(ADAPTIVE_BASE_VELOCITY, 0.5 * ADAPTIVE_BASE_STRAIN_RATE * float(length))
    return v, max(1.0, ADAPTIVE_FAST_VELOCITY / v)


@dataclass
class AdaptiveSpeed:
    """Adaptive loading speed: fast while the response is elastic and crack-free, slow when
    cracks form, near the peak and after it. Returns a factor f >= 1 on the base (converged
    constant) speed, decided before each record from the history recorded so far.

    Rule (per record; records are equally spaced in strain, so rates are per unit strain):

    - ``c`` = new cracks in the last record (a count, not a fraction of the bonds: a crack
      burst is a local event that needs the same relaxation time in a large specimen, and a
      per-bond rate let a 8 x 16 mm specimen load at 3-7x while cracking and read E 3.7 %
      low); ``g_crack = exp(-c / crack_scale)`` (1 when crack-free, -> 0 as cracks come);
    - ``T`` = tangent stiffness over the last ``window`` records / the largest tangent seen
      so far; ``g_tan = clip((T - tan_slow) / (tan_fast - tan_slow), 0, 1)`` (softening of the
      stress-strain curve: damage and the approach to the peak slow the platens down);
    - after the peak (stress below ``peak_drop`` x the running maximum), f = 1, or ``f_peak``
      when that is below 1; with ``f_peak`` < 1 also f <= ``f_peak`` while ``T`` <
      ``tan_peak`` (an option, off by default: on the 25 x 50 mm thesis-scale specimen
      ``f_peak`` = 0.5 cost 47 % more steps and moved UCS by +0.4 %, docs/labtests.md);
    - quasi-static check: the kinetic energy of the particles must stay below ``ke_ratio`` x
      their strain energy. Loading a quasi-static elastic body at a steady speed gives
      KE/SE ~ 1/(24 N^2), N = ε c_p / (2 v) the loading time in P-wave transits, and KE grows
      as v^2, so the factor is capped at ``f sqrt(ke_ratio / (KE/SE))`` (1e-3: N >~ 6.5; a
      crack burst raises KE too, and slows the platens). This makes the fast phase slow at
      the very start (small strain) and on specimens whose transit time is long;
    - target ``f* = 1 + (f_max - 1) g_crack g_tan``; the factor falls to f* at once and rises
      by at most ``rise`` per record (no sudden acceleration).

    Attributes
    ----------
    f_max : float
        Largest speed factor (the fast speed is ``f_max`` x the base speed).
    f_peak : float
        Largest factor near the peak and after it (<= 1; default 1 = the base speed).
    """

    f_max: float = 16.0
    crack_scale: float = 1.0
    tan_fast: float = 0.85
    tan_slow: float = 0.6
    peak_drop: float = 0.995
    window: int = 3
    rise: float = 1.5
    ke_ratio: float = 1e-3
    f_peak: float = 1.0
    tan_peak: float = 0.75
    stress_key: str = "axial_stress_mpa"
    strain_key: str = "axial_strain"
    factor: float = 1.0
    _tmax: float = 0.0
    _cracking: bool = False

    def _ke_cap(self, row, target):
        ke, se = row.get("kinetic_energy_j"), row.get("strain_energy_j")
        if ke is not None and se is not None and math.isfinite(ke) and math.isfinite(se) \
                and se > 0 and ke > 0:
            return min(target, max(1.0, self.factor * math.sqrt(self.ke_ratio * se / ke)))
        return target

    def update(self, rows) -> float:
        """New speed factor from the recorded rows (dicts with stress, strain, cracks_total)."""
        n = len(rows)
        if n < self.window + 2:         # too few records for a tangent: the base speed
            self.factor = 1.0
            return self.factor
        s = np.array([r[self.stress_key] for r in rows[-(self.window + 1):]], float)
        e = np.array([r[self.strain_key] for r in rows[-(self.window + 1):]], float)
        smax = max(r[self.stress_key] for r in rows)
        de = e[-1] - e[0]
        tan = (s[-1] - s[0]) / de if de > 0 else 0.0
        self._tmax = max(self._tmax, tan)
        T = tan / self._tmax if self._tmax > 0 else 1.0
        c = max(0.0, rows[-1].get("cracks_total", 0) - rows[-2].get("cracks_total", 0))
        g_crack = math.exp(-c / self.crack_scale)
        g_tan = min(1.0, max(0.0, (T - self.tan_slow) / (self.tan_fast - self.tan_slow)))
        target = 1.0 + (self.f_max - 1.0) * g_crack * g_tan
        self._cracking = self._cracking or c > 0
        if self._cracking:              # the fast phase ends at the first crack
            target = 1.0
        if s[-1] < self.peak_drop * smax:
            target = min(1.0, self.f_peak)
        elif self.f_peak < 1.0 and T < self.tan_peak:
            target = min(target, self.f_peak)
        target = self._ke_cap(rows[-1], target)
        self.factor = target if target < self.factor else min(target, self.factor * self.rise)
        return self.factor


@contextlib.contextmanager
def second_ctrl_c_waits():
    """Ignore Ctrl-C while the checkpoint and partial results of an interrupted test are
    written (a second Ctrl-C would leave them half-written)."""
    prev = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, prev)


@dataclass
class StopRule:
    """When a strain-controlled test ends.

    Attributes
    ----------
    post_peak : float or None
        Stop once the stress has fallen below this fraction of the peak (after the peak).
    max_strain : float or None
        Stop at this loading strain (elastic checks).
    min_peak_pa : float
        A peak below this stress does not count (start-up noise), default 1 MPa.
    require_cracks : bool
        A post-peak drop counts only once at least one bond has broken (a bonded specimen
        cannot soften without cracking; wave noise at the start of loading can).
    """

    post_peak: float | None = DEFAULT_POST_PEAK
    max_strain: float | None = None
    min_peak_pa: float = 1e6
    require_cracks: bool = True

    def __post_init__(self):
        if self.post_peak is None and self.max_strain is None:
            raise ValueError("give 'post_peak' or 'max_strain': the test would never stop")
        if self.post_peak is not None and not 0.0 < self.post_peak < 1.0:
            raise ValueError(f"'post_peak' = {self.post_peak}, expected in (0, 1)")
        if self.max_strain is not None and not self.max_strain > 0:
            raise ValueError(f"'max_strain' = {self.max_strain}, expected > 0")

    def reason(self, strain, stress, n_cracks=None):
        """``"post_peak"``, ``"max_strain"`` or None."""
        if self.max_strain is not None and strain[-1] >= self.max_strain:
            return "max_strain"
        if self.require_cracks and n_cracks is not None and n_cracks <= 0:
            return None
        if self.post_peak is not None and is_post_peak(stress, fraction=self.post_peak,
                                                       min_peak=self.min_peak_pa):
            return "post_peak"
        return None


@dataclass
class LoadingLoop:
    """Cycle, record, check the stop rule; Ctrl-C leaves a checkpoint and partial outputs.

    Attributes
    ----------
    sim : Simulation
    record : callable
        ``record() -> dict`` one history row (keys of :data:`HISTORY_COLUMNS` and more).
    chunk : int
        Steps between records.
    max_steps : int
        Safety limit on the number of loading steps.
    stop : StopRule
    stress_key, strain_key : str
        History columns the stop rule looks at (stress in MPa).
    on_chunk : callable, optional
        Called before each chunk with the chunk index (velocity ramps, servo updates); it
        should multiply the loading speed by ``loop.factor``.
    speed : AdaptiveSpeed, optional
        Adaptive loading speed: before each chunk ``factor = speed.update(rows)`` and the
        chunk is ``chunk / factor`` steps (records stay equally spaced in strain).
    checkpoint : path, optional
        Where ``sim.save`` writes on Ctrl-C (and every ``checkpoint_every`` records).
    on_checkpoint : callable, optional
        Called after each periodic checkpoint; :func:`run_and_finish` sets it to write the
        partial results there (so that a run killed without Ctrl-C leaves them).
    progress : bool
        tqdm progress bar on stderr.
    """

    sim: object
    record: object
    chunk: int
    max_steps: int
    stop: StopRule
    stress_key: str = "axial_stress_mpa"
    strain_key: str = "axial_strain"
    on_chunk: object = None
    checkpoint: object = None
    checkpoint_every: int = 0
    on_checkpoint: object = None
    speed: object = None
    factor: float = 1.0
    progress: bool = True
    desc: str = "loading"
    rows: list = field(default_factory=list)
    stop_reason: str = ""
    engine_error: str = ""
    interrupted: bool = False
    wall_s: float = 0.0
    steps: int = 0

    def history(self) -> pd.DataFrame:
        """Recorded rows as a DataFrame, :data:`HISTORY_COLUMNS` first."""
        h = pd.DataFrame(self.rows)
        for c in HISTORY_COLUMNS:
            if c not in h:
                h[c] = pd.Series(np.nan, index=h.index, dtype=float)
        rest = [c for c in h.columns if c not in HISTORY_COLUMNS]
        return h[list(HISTORY_COLUMNS) + rest]

    def save_checkpoint(self):
        if self.checkpoint is not None:
            os.makedirs(os.path.dirname(os.path.abspath(self.checkpoint)), exist_ok=True)
            self.sim.save(self.checkpoint)

    def run(self):
        """Run until the stop rule fires, ``max_steps`` pass, or Ctrl-C (re-raised after the
        checkpoint is written: the caller writes the partial outputs)."""
        bar = None
        if self.progress:
            from tqdm import tqdm
            bar = tqdm(total=self.max_steps, desc=self.desc, unit="step", leave=False,
                       dynamic_ncols=True, mininterval=0.5)
        t0, wall_before = time.perf_counter(), self.wall_s
        strain, stress = [], []
        if not self.rows:
            self.rows.append(self.record())
        strain.extend(r[self.strain_key] for r in self.rows)
        stress.extend(r[self.stress_key] * 1e6 for r in self.rows)
        k = len(self.rows) - 1          # chunks done (> 0 when resuming)
        try:
            while self.steps < self.max_steps:
                if self.speed is not None:
                    self.factor = float(self.speed.update(self.rows))
                if self.on_chunk is not None:
                    self.on_chunk(k)
                n = min(max(1, int(round(self.chunk / self.factor))),
                        self.max_steps - self.steps)
                self.sim.cycle(n)
                self.steps += n
                row = self.record()
                self.rows.append(row)
                strain.append(row[self.strain_key])
                stress.append(row[self.stress_key] * 1e6)
                k += 1
                if bar is not None:
                    bar.update(n)
                    bar.set_postfix_str(f"{self.stress_key}={row[self.stress_key]:.1f} "
                                        f"peak={max(stress) / 1e6:.1f} "
                                        f"{self.strain_key}={row[self.strain_key]:.3e} "
                                        f"speed=x{self.factor:.2f}")
                if self.checkpoint_every and k % self.checkpoint_every == 0:
                    self.save_checkpoint()
                    if self.on_checkpoint is not None:
                        self.wall_s = wall_before + time.perf_counter() - t0
                        self.on_checkpoint()
                why = self.stop.reason(strain, stress, row.get("cracks_total"))
                if why:
                    self.stop_reason = why
                    break
            else:
                self.stop_reason = "max_steps"
        except InstabilityError as exc:
            # after the peak the test has given its answer (peak, E, CI, CD): an engine
            # instability among the fragments ends it like the post-peak rule, and is reported
            ip = int(np.argmax(stress))
            if ip < len(stress) - 1 and stress[-1] < 0.98 * stress[ip] \
                    and self.rows[-1].get("cracks_total", 1) > 0:
                self.stop_reason = "instability_after_peak"
                self.engine_error = str(exc)
            else:
                raise
        except KeyboardInterrupt:
            self.interrupted = True
            self.stop_reason = "interrupted"
            with second_ctrl_c_waits():
                self.save_checkpoint()
            raise
        finally:
            self.wall_s = wall_before + time.perf_counter() - t0
            if bar is not None:
                bar.close()
        return self


def run_and_finish(loop, finish):
    """Run ``loop`` and return ``finish()``; on Ctrl-C call ``finish()`` (partial outputs) first.

    Parameters
    ----------
    loop : LoadingLoop
    finish : callable
        ``finish(figures=...)`` builds (and, with ``out``, writes) the test's result from what
        was recorded. With periodic checkpoints (``loop.checkpoint_every``) it is also called
        after each of them with ``figures=False``: the partial history and summary (status
        ``running``) lie beside every checkpoint, so a run killed without Ctrl-C (SIGKILL, power
        loss) leaves results, and the test can be resumed (:mod:`sim.protocols.resume`).

    Returns
    -------
    result : TestResult

    Raises
    ------
    KeyboardInterrupt
        Re-raised after ``finish()`` has written the partial results.
    """
    if loop.checkpoint_every and loop.checkpoint is not None and loop.on_checkpoint is None:
        loop.on_checkpoint = lambda: finish(figures=False)
    try:
        loop.run()
    except KeyboardInterrupt:
        finish()
        raise
    return finish()
