"""The specimen file, ``specimen.npz`` schema version 1 (DESIGN.md §4).

A specimen is the seam between :mod:`gbmgen` (which writes it) and :mod:`sim` (which runs it).
Everything is SI: m, kg, Pa; angles in the file are degrees.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, fields

import numpy as np

from ._io import load_npz, save_npz_atomic
from .errors import InputError

SCHEMA_VERSION = 1

MINERAL_KEYS = ("density", "emod", "kratio", "fric",
                "pb_emod", "pb_kratio", "pb_ten", "pb_coh", "pb_fa", "pb_rmul")
JOINT_KEYS = ("sj_kn", "sj_ks", "sj_ten", "sj_coh", "sj_fa", "sj_fric")
_DEFAULT_JOINT = dict(sj_kn=0.0, sj_ks=0.0, sj_ten=0.0, sj_coh=0.0, sj_fa=0.0, sj_fric=0.0)


@dataclass
class Specimen:
    """A 2D bonded-particle specimen (disks of unit thickness).

    Notation: N particles, M minerals, B bonds, G grains, K grain-polygon vertices.

    Attributes
    ----------
    x, y, r : (N,) ndarray of float64, m
        Particle centres and radii.
    mineral : (N,) ndarray of int32
        Index into the mineral tables.
    grain : (N,) ndarray of int32
        Grain index, -1 where none.
    mineral_names : (M,) ndarray of str
    density, emod, kratio, fric : (M,) ndarray of float64
        kg/m³; linear contact E* (Pa), kn/ks, friction coefficient.
    pb_emod, pb_kratio, pb_ten, pb_coh, pb_fa, pb_rmul : (M,) ndarray of float64
        Parallel bond: Ē (Pa), kn/ks, tensile and cohesive strength (Pa), friction angle (deg),
        radius multiplier.
    sj_kn, sj_ks, sj_ten, sj_coh, sj_fa, sj_fric : (1,) ndarray of float64
        Smooth joint: stiffness per area (Pa/m), strengths (Pa), friction angle (deg),
        friction coefficient.
    bond_i, bond_j : (B,) ndarray of int32
        Bonded pairs at generation, ``bond_i < bond_j``.
    bond_kind : (B,) ndarray of int8
        0 parallel bond, 1 smooth joint.
    joint_nx, joint_ny : (B,) ndarray of float64
        Unit joint normal for kind 1 (NaN for kind 0).
    box : (4,) ndarray of float64, m
        xmin, xmax, ymin, ymax.
    grain_xy : (K, 2) ndarray of float64, m
    grain_offsets : (G+1,) ndarray of int64
    grain_mineral : (G,) ndarray of int32
    grain_class : (G,) ndarray of int8
        0 fine, 1 medium, 2 coarse.
    meta : dict
        Free JSON metadata (schema version, units, seed, generator, ...).

    Examples
    --------
    >>> s = Specimen.lattice(nx=4, ny=3, radius=1e-3)
    >>> s.n_particles, s.n_bonds
    (12, 23)
    """

    x: np.ndarray
    y: np.ndarray
    r: np.ndarray
    mineral: np.ndarray
    grain: np.ndarray
    mineral_names: np.ndarray
    density: np.ndarray
    emod: np.ndarray
    kratio: np.ndarray
    fric: np.ndarray
    pb_emod: np.ndarray
    pb_kratio: np.ndarray
    pb_ten: np.ndarray
    pb_coh: np.ndarray
    pb_fa: np.ndarray
    pb_rmul: np.ndarray
    sj_kn: np.ndarray
    sj_ks: np.ndarray
    sj_ten: np.ndarray
    sj_coh: np.ndarray
    sj_fa: np.ndarray
    sj_fric: np.ndarray
    bond_i: np.ndarray
    bond_j: np.ndarray
    bond_kind: np.ndarray
    joint_nx: np.ndarray
    joint_ny: np.ndarray
    box: np.ndarray
    grain_xy: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    grain_offsets: np.ndarray = field(default_factory=lambda: np.zeros(1, np.int64))
    grain_mineral: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    grain_class: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int8))
    meta: dict = field(default_factory=dict)

    _DTYPES = {
        "x": np.float64, "y": np.float64, "r": np.float64,
        "mineral": np.int32, "grain": np.int32,
        **{k: np.float64 for k in MINERAL_KEYS + JOINT_KEYS},
        "bond_i": np.int32, "bond_j": np.int32, "bond_kind": np.int8,
        "joint_nx": np.float64, "joint_ny": np.float64, "box": np.float64,
        "grain_xy": np.float64, "grain_offsets": np.int64,
        "grain_mineral": np.int32, "grain_class": np.int8,
    }

    def __post_init__(self):
        for k, dt in self._DTYPES.items():
            setattr(self, k, np.ascontiguousarray(getattr(self, k), dtype=dt))
        self.mineral_names = np.asarray(self.mineral_names, dtype=str)
        if self.grain_xy.size == 0:
            self.grain_xy = self.grain_xy.reshape(0, 2)

    # ------------------------------------------------------------------ sizes
    @property
    def n_particles(self) -> int:
        return int(self.x.size)

    @property
    def n_bonds(self) -> int:
        return int(self.bond_i.size)

    @property
    def n_minerals(self) -> int:
        return int(self.mineral_names.size)

    @property
    def n_grains(self) -> int:
        return int(self.grain_offsets.size - 1)

    @property
    def has_joints(self) -> bool:
        return bool(np.any(self.bond_kind == 1))

    def grain_polygon(self, g: int) -> np.ndarray:
        """Vertices (K_g, 2) of grain ``g``, m."""
        return self.grain_xy[self.grain_offsets[g]:self.grain_offsets[g + 1]]

    # ------------------------------------------------------------ validation
    def validate(self, source: str = "specimen") -> "Specimen":
        """Check shapes, ranges and references; raise :class:`InputError` naming the field.

        Returns the specimen itself so that calls can be chained.
        """
        def bad(key, what):
            raise InputError(f"{source}: field '{key}' {what}")

        n, m, b = self.n_particles, self.n_minerals, self.n_bonds
        if n == 0:
            bad("x", "is empty: expected at least one particle")
        for k in ("y", "r", "mineral", "grain"):
            if getattr(self, k).shape != (n,):
                bad(k, f"has shape {getattr(self, k).shape}, expected ({n},) like 'x'")
        if m == 0:
            bad("mineral_names", "is empty: expected at least one mineral")
        for k in MINERAL_KEYS:
            if getattr(self, k).shape != (m,):
                bad(k, f"has shape {getattr(self, k).shape}, expected ({m},) like 'mineral_names'")
        for k in JOINT_KEYS:
            if getattr(self, k).shape != (1,):
                bad(k, f"has shape {getattr(self, k).shape}, expected (1,)")
        for k in ("bond_j", "bond_kind", "joint_nx", "joint_ny"):
            if getattr(self, k).shape != (b,):
                bad(k, f"has shape {getattr(self, k).shape}, expected ({b},) like 'bond_i'")
        if self.box.shape != (4,) or not (self.box[0] < self.box[1] and self.box[2] < self.box[3]):
            bad("box", f"= {self.box.tolist()}, expected [xmin, xmax, ymin, ymax] with min < max")
        for k in ("x", "y", "r") + MINERAL_KEYS + JOINT_KEYS:
            if not np.all(np.isfinite(getattr(self, k))):
                bad(k, "has NaN or inf values, expected finite numbers")
        if np.any(self.r <= 0):
            bad("r", f"has {int(np.sum(self.r <= 0))} non-positive radii, expected > 0 m")
        if np.any((self.mineral < 0) | (self.mineral >= m)):
            bad("mineral", f"has indices outside 0..{m - 1}")
        for k in ("density", "emod", "kratio", "pb_kratio", "pb_rmul"):
            if np.any(getattr(self, k) <= 0):
                bad(k, "has non-positive values, expected > 0")
        for k in ("fric", "pb_emod", "pb_ten", "pb_coh", "pb_fa") + JOINT_KEYS:
            if np.any(getattr(self, k) < 0):
                bad(k, "has negative values, expected >= 0")
        if b:
            ends = np.concatenate([self.bond_i, self.bond_j])
            if np.any((ends < 0) | (ends >= n)):
                bad("bond_i", f"references particles outside 0..{n - 1}")
            if np.any(self.bond_i >= self.bond_j):
                bad("bond_i", "is not < bond_j for every bond, expected i < j")
            if np.any((self.bond_kind != 0) & (self.bond_kind != 1)):
                bad("bond_kind", "has values other than 0 (parallel bond) and 1 (smooth joint)")
            sj = self.bond_kind == 1
            if np.any(sj):
                norm = np.hypot(self.joint_nx[sj], self.joint_ny[sj])
                if not np.all(np.abs(norm - 1.0) < 1e-6):
                    bad("joint_nx", "is not a unit normal (with joint_ny) for every smooth joint")
                if self.sj_kn[0] <= 0 or self.sj_ks[0] <= 0:
                    bad("sj_kn", "must be > 0 (Pa/m) when the specimen has smooth joints")
        g = self.n_grains
        if self.grain_offsets.size < 1 or self.grain_offsets[0] != 0 \
                or np.any(np.diff(self.grain_offsets) < 0) \
                or self.grain_offsets[-1] != self.grain_xy.shape[0]:
            bad("grain_offsets", "is not a non-decreasing index from 0 to len(grain_xy)")
        if self.grain_mineral.shape != (g,) or self.grain_class.shape != (g,):
            bad("grain_mineral", f"expected ({g},) entries like grain_offsets - 1")
        if np.any(self.grain >= max(g, 0)) and g > 0:
            bad("grain", f"has indices >= number of grains {g}")
        if g == 0 and np.any(self.grain >= 0):
            bad("grain", "references grains but the file has no grain polygons")
        return self

    # ------------------------------------------------------------------ I/O
    def to_arrays(self) -> dict:
        """All schema keys as arrays (``meta`` as a 0-d JSON string)."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "meta"}
        meta = {"schema_version": SCHEMA_VERSION, "units": "SI", **self.meta}
        out["meta"] = np.array(json.dumps(meta, default=_json_default))
        return out

    def save(self, path) -> None:
        """Write ``specimen.npz`` atomically (temporary file, then rename)."""
        self.validate(str(path))
        save_npz_atomic(path, self.to_arrays(), compressed=True)

    @classmethod
    def load(cls, path) -> "Specimen":
        """Read and validate a ``specimen.npz`` (no pickle).

        Grain keys may be missing (no grains); ``joint_nx/ny`` and ``bond_kind`` default to
        parallel bonds; the smooth-joint table defaults to zeros.

        Raises
        ------
        InputError
            If the file is missing, unreadable, or a field is absent or malformed.
        """
        path = os.fspath(path)
        return cls.from_arrays(load_npz(path, "specimen.npz"), source=path)

    @classmethod
    def from_arrays(cls, data: dict, source: str = "specimen") -> "Specimen":
        """Build from a mapping of schema keys, filling optional keys with their defaults."""
        data = dict(data)
        required = ("x", "y", "r", "mineral_names", "box") + MINERAL_KEYS
        for k in required:
            if k not in data:
                raise InputError(f"{source}: missing field '{k}'")
        n = np.asarray(data["x"]).size
        m = np.asarray(data["mineral_names"]).size
        data.setdefault("mineral", np.zeros(n, np.int32) if m == 1 else None)
        if data["mineral"] is None:
            raise InputError(f"{source}: missing field 'mineral' (needed with {m} minerals)")
        data.setdefault("grain", np.full(n, -1, np.int32))
        data.setdefault("bond_i", np.zeros(0, np.int32))
        data.setdefault("bond_j", np.zeros(0, np.int32))
        b = np.asarray(data["bond_i"]).size
        data.setdefault("bond_kind", np.zeros(b, np.int8))
        data.setdefault("joint_nx", np.full(b, np.nan))
        data.setdefault("joint_ny", np.full(b, np.nan))
        for k, v in _DEFAULT_JOINT.items():
            data.setdefault(k, np.array([v]))
        meta = data.pop("meta", None)
        if meta is None:
            meta = {}
        else:
            try:
                meta = json.loads(str(np.asarray(meta)[()]))
            except json.JSONDecodeError as exc:
                raise InputError(f"{source}: field 'meta' is not JSON ({exc})") from None
        known = {f.name for f in fields(cls)}
        kwargs = {k: v for k, v in data.items() if k in known}
        try:
            spec = cls(**kwargs, meta=meta)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{source}: {exc}") from None
        return spec.validate(source)

    # -------------------------------------------------------------- factories
    @classmethod
    def lattice(cls, nx: int, ny: int, radius: float, *, gap: float = 0.0, emod: float = 60e9,
                kratio: float = 2.0, density: float = 2650.0, fric: float = 0.5,
                pb_emod: float = 60e9, pb_kratio: float = 2.0, pb_ten: float = 1e100,
                pb_coh: float = 1e100, pb_fa: float = 0.0, pb_rmul: float = 1.0) -> "Specimen":
        """A regular triangular lattice of equal disks, every neighbour pair parallel-bonded.

        Parameters
        ----------
        nx, ny : int
            Particles per row and number of rows.
        radius : float, m
        gap : float
            Relative gap between neighbours: spacing = 2 R (1 + gap).

        Returns
        -------
        specimen : Specimen
            One mineral named ``lattice``; ``box`` encloses the particles exactly.
        """
        s = 2.0 * radius * (1.0 + gap)
        j, i = np.mgrid[0:ny, 0:nx]
        x = (i * s + (j % 2) * 0.5 * s).ravel().astype(float)
        y = (j * s * np.sqrt(3) / 2).ravel().astype(float)
        n = x.size
        from scipy.spatial import cKDTree
        pairs = cKDTree(np.c_[x, y]).query_pairs(s * 1.01, output_type="ndarray")
        pairs = np.sort(pairs, axis=1)
        pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
        r = np.full(n, radius)
        box = np.array([x.min() - radius, x.max() + radius, y.min() - radius, y.max() + radius])
        one = lambda v: np.array([v], float)  # noqa: E731
        return cls(x=x, y=y, r=r, mineral=np.zeros(n), grain=np.full(n, -1),
                   mineral_names=np.array(["lattice"]), density=one(density), emod=one(emod),
                   kratio=one(kratio), fric=one(fric), pb_emod=one(pb_emod),
                   pb_kratio=one(pb_kratio), pb_ten=one(pb_ten), pb_coh=one(pb_coh),
                   pb_fa=one(pb_fa), pb_rmul=one(pb_rmul),
                   **{k: one(v) for k, v in _DEFAULT_JOINT.items()},
                   bond_i=pairs[:, 0], bond_j=pairs[:, 1], bond_kind=np.zeros(len(pairs)),
                   joint_nx=np.full(len(pairs), np.nan), joint_ny=np.full(len(pairs), np.nan),
                   box=box, meta={"generator": "sim.Specimen.lattice", "spacing_m": s})

    @classmethod
    def random_packing(cls, n: int, *, radius: float = 1e-3, spread: float = 0.2,
                       jitter: float = 0.1, overlap: float = 0.1, bond_gap: float = 0.05,
                       n_minerals: int = 1, emod=60e9, pb_emod=60e9, kratio: float = 2.0,
                       pb_kratio: float = 2.0, density: float = 2650.0, fric: float = 0.5,
                       pb_ten: float = 1e100, pb_coh: float = 1e100, pb_fa: float = 0.0,
                       seed=None) -> "Specimen":
        """A disordered, polydisperse, parallel-bonded packing (tests and benchmarks).

        Centres are a triangular lattice of spacing 2·radius jittered by ``jitter``·radius;
        radii are uniform in radius·[1 − spread, 1] and then scaled by (1 + overlap), so that
        ``overlap`` = 0.2 gives neighbour overlaps up to about 20 % of the diameter. Pairs whose
        gap is below ``bond_gap`` × (r_i + r_j) are parallel-bonded. The defaults give about
        4.3 bonds per particle, overlaps of 2 % of the diameter on average and up to ~19 %
        (a quick stand-in for a relaxed packing, for tests and benchmarks). With ``n_minerals`` > 1
        particles get random minerals whose ``emod``/``pb_emod`` (scalars or one per mineral)
        differ.

        Parameters
        ----------
        n : int
            Number of particles.
        seed : int, optional

        Returns
        -------
        specimen : Specimen
            Particles sorted along a space-filling curve (see :meth:`sort_spatial`).
        """
        rng = np.random.default_rng(seed)
        s = 2.0 * radius
        nx = int(np.ceil(np.sqrt(n * 2.0 / np.sqrt(3.0))))
        ny = int(np.ceil(n / nx))
        j, i = np.mgrid[0:ny, 0:nx]
        x = (i * s + (j % 2) * 0.5 * s).ravel()[:n].astype(float)
        y = (j * s * np.sqrt(3) / 2).ravel()[:n].astype(float)
        x += rng.uniform(-jitter, jitter, n) * radius
        y += rng.uniform(-jitter, jitter, n) * radius
        r = radius * rng.uniform(1.0 - spread, 1.0, n) * (1.0 + overlap)
        from scipy.spatial import cKDTree
        pairs = cKDTree(np.c_[x, y]).query_pairs(2.0 * r.max() * (1 + bond_gap),
                                                 output_type="ndarray")
        rs = r[pairs[:, 0]] + r[pairs[:, 1]]
        d = np.hypot(x[pairs[:, 1]] - x[pairs[:, 0]], y[pairs[:, 1]] - y[pairs[:, 0]])
        pairs = np.sort(pairs[d - rs < bond_gap * rs], axis=1)
        m = int(n_minerals)
        mineral = rng.integers(0, m, n) if m > 1 else np.zeros(n, np.int64)
        tab = lambda v: np.broadcast_to(np.asarray(v, float), (m,)).copy()  # noqa: E731
        one = lambda v: np.array([v], float)  # noqa: E731
        box = np.array([(x - r).min(), (x + r).max(), (y - r).min(), (y + r).max()])
        spec = cls(x=x, y=y, r=r, mineral=mineral, grain=np.full(n, -1),
                   mineral_names=np.array([f"mineral{k}" for k in range(m)]),
                   density=tab(density), emod=tab(emod), kratio=tab(kratio), fric=tab(fric),
                   pb_emod=tab(pb_emod), pb_kratio=tab(pb_kratio), pb_ten=tab(pb_ten),
                   pb_coh=tab(pb_coh), pb_fa=tab(pb_fa), pb_rmul=tab(1.0),
                   **{k: one(v) for k, v in _DEFAULT_JOINT.items()},
                   bond_i=pairs[:, 0], bond_j=pairs[:, 1], bond_kind=np.zeros(len(pairs)),
                   joint_nx=np.full(len(pairs), np.nan), joint_ny=np.full(len(pairs), np.nan),
                   box=box, meta={"generator": "sim.Specimen.random_packing", "seed": seed})
        return spec.sort_spatial()

    def sort_spatial(self) -> "Specimen":
        """The same specimen with particles in Morton (Z-curve) order, bonds remapped.

        Neighbours then sit close in memory, which the DEM step loop needs to run fast
        (STYLE.md §7.6). Returns a new Specimen; grains, minerals and the box are unchanged.
        """
        n = self.n_particles
        span = max(self.box[1] - self.box[0], self.box[3] - self.box[2])
        cell = max(float(np.median(self.r)) * 2.0, span / 65535.0)
        ix = np.clip(((self.x - self.box[0]) / cell).astype(np.int64), 0, 65535)
        iy = np.clip(((self.y - self.box[2]) / cell).astype(np.int64), 0, 65535)
        key = np.zeros(n, np.int64)
        for b in range(16):
            key |= ((ix >> b) & 1) << (2 * b)
            key |= ((iy >> b) & 1) << (2 * b + 1)
        order = np.argsort(key, kind="stable")
        new_of_old = np.empty(n, np.int64)
        new_of_old[order] = np.arange(n)
        bi, bj = new_of_old[self.bond_i], new_of_old[self.bond_j]
        lo, hi = np.minimum(bi, bj), np.maximum(bi, bj)
        flip = bi > bj
        jnx = np.where(flip, -self.joint_nx, self.joint_nx)
        jny = np.where(flip, -self.joint_ny, self.joint_ny)
        border = np.lexsort((hi, lo))
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        for k in ("x", "y", "r", "mineral", "grain"):
            kw[k] = kw[k][order]
        kw.update(bond_i=lo[border], bond_j=hi[border], bond_kind=self.bond_kind[border],
                  joint_nx=jnx[border], joint_ny=jny[border], meta=dict(self.meta))
        return type(self)(**kw)


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"meta value of type {type(o).__name__} is not JSON serialisable")
