"""The grain-size table (``grains.csv``, DESIGN.md §4): read, validate, size scenarios 1-4.

One row per (mineral, class): ``mineral, class`` (fine|medium|coarse), ``d_min_um, d_max_um``
(equivalent-circle diameters), ``frequency_pct`` (share of the mineral's grains by count) and
``volume_fraction_pct`` (of the mineral, repeated on its rows).

Within a class the diameter is taken uniform on [d_min, d_max] (the same reading as semkit's N1
convention, whose class mean is the class midpoint), so a mineral's size distribution is a
piecewise-uniform mixture with the class frequencies as weights.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import pandas as pd

from . import config
from .errors import InputError

__all__ = ["GrainSizeTable", "read_table", "example_table", "EXAMPLE_TABLES", "SCENARIOS"]

#: Example tables shipped in ``gbmgen/presets`` (name -> YAML file).
EXAMPLE_TABLES = {"table-4-1": "table_4_1.yaml",
                  "thesis-ch6-pyroxene": "thesis_ch6_pyroxene.yaml"}

#: Scenario number -> description (REFERENCE.md Ch. 4, Table 4-2).
SCENARIOS = {1: "full observed range", 2: "10-90 % passing", 3: "mean +- 1/2 mean",
             4: "mean +- 1/4 mean"}


@dataclass(frozen=True)
class GrainSizeTable:
    """A validated grain-size table.

    Notation: M minerals, 3 classes (fine, medium, coarse).

    Attributes
    ----------
    minerals : tuple of str
        Mineral names in order of first appearance in the file.
    edges_um : (M, 4) ndarray of float64, um
        Class edges per mineral: fine d_min, fine d_max, medium d_max, coarse d_max
        (with ``lo_um``/``hi_um`` when the classes are not contiguous).
    lo_um, hi_um : (M, 3) ndarray of float64, um
        d_min and d_max of every class.
    frequencies : (M, 3) ndarray of float64
        Share of each class by grain count within its mineral (rows sum to 1).
    volume_fractions : (M,) ndarray of float64
        Volume (area) fraction of each mineral (sums to 1).
    source : str
        File name or description, for messages and ``meta``.
    """

    minerals: tuple
    lo_um: np.ndarray
    hi_um: np.ndarray
    frequencies: np.ndarray
    volume_fractions: np.ndarray
    source: str = "table"

    # ------------------------------------------------------------------ build
    @classmethod
    def from_frame(cls, df: pd.DataFrame, source: str = "table") -> "GrainSizeTable":
        """Validate a DataFrame in ``grains.csv`` form.

        Raises
        ------
        InputError
            Naming the row (1-based data row, and the file line) and the field: missing
            columns, unknown class, non-numeric / negative sizes, d_max < d_min, a class missing
            or repeated, overlapping classes, frequencies not summing to ~100 % per mineral,
            volume fractions inconsistent within a mineral or not summing to 100 %.
        """
        missing = [c for c in config.TABLE_COLUMNS if c not in df.columns]
        if missing:
            raise InputError(f"{source}: missing column(s) {missing}; expected "
                             f"{list(config.TABLE_COLUMNS)}")
        if len(df) == 0:
            raise InputError(f"{source}: no rows; expected one row per (mineral, class)")

        def where(i):
            return f"{source}: row {i + 1} (line {i + 2})"

        numeric = {}
        for col in ("d_min_um", "d_max_um", "frequency_pct", "volume_fraction_pct"):
            vals = pd.to_numeric(df[col], errors="coerce").to_numpy(float)
            for i in np.flatnonzero(~np.isfinite(vals)):
                raise InputError(f"{where(i)}: field '{col}' = {df[col].iloc[i]!r}, "
                                 "expected a finite number")
            numeric[col] = vals
        names = df["mineral"].astype(str).str.strip().to_numpy()
        classes = df["class"].astype(str).str.strip().str.lower().to_numpy()
        for i in range(len(df)):
            if names[i] in ("", "nan"):
                raise InputError(f"{where(i)}: field 'mineral' is empty, expected a name")
            if classes[i] not in config.CLASSES:
                raise InputError(f"{where(i)}: field 'class' = {df['class'].iloc[i]!r}, "
                                 "expected fine|medium|coarse")
            if numeric["d_min_um"][i] <= 0:
                raise InputError(f"{where(i)}: field 'd_min_um' = {numeric['d_min_um'][i]:g}, "
                                 "expected a size > 0 um")
            if numeric["d_max_um"][i] <= numeric["d_min_um"][i]:
                raise InputError(f"{where(i)}: field 'd_max_um' = {numeric['d_max_um'][i]:g}, "
                                 f"expected > d_min_um = {numeric['d_min_um'][i]:g}")
            for col in ("frequency_pct", "volume_fraction_pct"):
                if numeric[col][i] < 0:
                    raise InputError(f"{where(i)}: field '{col}' = {numeric[col][i]:g}, "
                                     "expected >= 0")
        minerals = tuple(dict.fromkeys(names))
        m = len(minerals)
        lo = np.zeros((m, 3))
        hi = np.zeros((m, 3))
        freq = np.zeros((m, 3))
        vol = np.zeros(m)
        for k, name in enumerate(minerals):
            rows = np.flatnonzero(names == name)
            v = numeric["volume_fraction_pct"][rows]
            if np.ptp(v) > 1e-9:
                i = rows[np.argmax(np.abs(v - v[0]))]
                raise InputError(f"{where(i)}: field 'volume_fraction_pct' = "
                                 f"{numeric['volume_fraction_pct'][i]:g} differs from "
                                 f"{v[0]:g} on the other rows of {name!r}; expected the "
                                 "mineral's fraction repeated")
            vol[k] = v[0]
            for c, cls_name in enumerate(config.CLASSES):
                hit = rows[classes[rows] == cls_name]
                if hit.size != 1:
                    at = f"{where(hit[1])}" if hit.size > 1 else f"{source}"
                    raise InputError(f"{at}: mineral {name!r} has {hit.size} {cls_name!r} rows "
                                     "in field 'class', expected exactly one (a class without "
                                     "grains gets frequency_pct 0)")
                i = hit[0]
                lo[k, c] = numeric["d_min_um"][i]
                hi[k, c] = numeric["d_max_um"][i]
                freq[k, c] = numeric["frequency_pct"][i]
            for c in range(2):
                if hi[k, c] > lo[k, c + 1] + config.CLASS_OVERLAP_TOL_UM:
                    i = rows[classes[rows] == config.CLASSES[c + 1]][0]
                    raise InputError(
                        f"{where(i)}: field 'd_min_um' = {lo[k, c + 1]:g} of {name!r} "
                        f"{config.CLASSES[c + 1]} overlaps the {config.CLASSES[c]} class "
                        f"(d_max_um {hi[k, c]:g}); expected classes in increasing, "
                        "non-overlapping order")
            s = freq[k].sum()
            if abs(s - 100.0) > config.FREQ_SUM_TOL_PCT:
                raise InputError(f"{source}: field 'frequency_pct' of {name!r} sums to {s:g} %, "
                                 f"expected 100 +- {config.FREQ_SUM_TOL_PCT:g} %")
            freq[k] /= s
        total = vol.sum()
        if abs(total - 100.0) > config.VOLUME_SUM_TOL_PCT:
            raise InputError(f"{source}: field 'volume_fraction_pct' sums to {total:g} % over "
                             f"the minerals, expected 100 +- {config.VOLUME_SUM_TOL_PCT:g} %")
        return cls(minerals=minerals, lo_um=lo, hi_um=hi, frequencies=freq,
                   volume_fractions=vol / total, source=source)

    # --------------------------------------------------------------- export
    def to_frame(self) -> pd.DataFrame:
        """The table in ``grains.csv`` form (frequencies and fractions in %)."""
        rows = []
        for k, name in enumerate(self.minerals):
            for c, cls_name in enumerate(config.CLASSES):
                rows.append({"mineral": name, "class": cls_name,
                             "d_min_um": float(self.lo_um[k, c]),
                             "d_max_um": float(self.hi_um[k, c]),
                             "frequency_pct": float(100.0 * self.frequencies[k, c]),
                             "volume_fraction_pct": float(100.0 * self.volume_fractions[k])})
        return pd.DataFrame(rows, columns=list(config.TABLE_COLUMNS))

    @property
    def n_minerals(self) -> int:
        return len(self.minerals)

    # ------------------------------------------------------ size statistics
    def mean_um(self) -> np.ndarray:
        """(M,) count-mean diameter of each mineral, um (class midpoints weighted by frequency)."""
        return (self.frequencies * 0.5 * (self.lo_um + self.hi_um)).sum(axis=1)

    def quantile_um(self, q) -> np.ndarray:
        """(M,) diameter below which a fraction ``q`` of each mineral's grains lie (by count), um.

        Piecewise-uniform within the classes (classes with zero frequency are skipped).
        """
        q = float(q)
        out = np.zeros(self.n_minerals)
        for k in range(self.n_minerals):
            cum = 0.0
            out[k] = self.hi_um[k][self.frequencies[k] > 0][-1]
            for c in range(3):
                f = self.frequencies[k, c]
                if f > 0 and cum + f >= q:
                    lo, hi = self.lo_um[k, c], self.hi_um[k, c]
                    out[k] = lo + (q - cum) / f * (hi - lo)
                    break
                cum += f
        return out

    def cdf(self, k: int, d_um) -> np.ndarray:
        """Target cumulative distribution (by count) of mineral ``k`` at diameters ``d_um``."""
        d = np.asarray(d_um, dtype=float)
        out = np.zeros_like(d)
        for c in range(3):
            lo, hi, f = self.lo_um[k, c], self.hi_um[k, c], self.frequencies[k, c]
            out += f * np.clip((d - lo) / (hi - lo), 0.0, 1.0)
        return out

    def range_um(self) -> np.ndarray:
        """(M, 2) full range (smallest d_min, largest d_max) of each mineral, um."""
        return np.c_[self.lo_um[:, 0], self.hi_um[:, 2]]

    # ----------------------------------------------------------- scenarios
    def scenario_ranges_um(self, scenario: int) -> np.ndarray:
        """(M, 2) size range of each mineral for scenario 1-4 (REFERENCE.md Table 4-2).

        1 full observed range; 2 the 10-90 % passing range (by count); 3 mean +- 1/2 mean;
        4 mean +- 1/4 mean (count-mean of the piecewise-uniform distribution).
        """
        if scenario == 1:
            return self.range_um()
        if scenario == 2:
            return np.c_[self.quantile_um(config.S2_PASSING[0]),
                         self.quantile_um(config.S2_PASSING[1])]
        if scenario in (3, 4):
            h = config.S3_HALF_WIDTH if scenario == 3 else config.S4_HALF_WIDTH
            m = self.mean_um()
            return np.c_[m * (1.0 - h), m * (1.0 + h)]
        raise InputError(f"scenario: expected 1, 2, 3 or 4 ({SCENARIOS}), got {scenario!r}")

    def scenario(self, scenario: int = 1, *, scale: float = 1.0) -> "GrainSizeTable":
        """The table of a size scenario, every size multiplied by ``scale``.

        The class edges of each mineral are mapped linearly from its full range onto the
        scenario range; frequencies and volume fractions are kept (the N1 split of
        REFERENCE.md, the convention of :func:`semkit.indices.table_with_ranges`).

        Parameters
        ----------
        scenario : {1, 2, 3, 4}
        scale : float
            Size factor (``--scale`` times ``--model-scale``), > 0.

        Returns
        -------
        table : GrainSizeTable
        """
        return self.with_ranges(self.scenario_ranges_um(int(scenario)), scale=scale,
                                label=f"scenario {int(scenario)}")

    def with_ranges(self, ranges_um, *, scale: float = 1.0, label="ranges") -> "GrainSizeTable":
        """The table with each mineral's size range replaced (class edges mapped linearly).

        Parameters
        ----------
        ranges_um : (M, 2) array_like or dict
            New [d_min, d_max] per mineral, um (a dict maps mineral name -> (lo, hi); every
            mineral of the table must be given).
        scale : float
            Size factor applied after the mapping.

        Returns
        -------
        table : GrainSizeTable

        Raises
        ------
        InputError
            A mineral missing from ``ranges_um``, or a range with not 0 < lo < hi.
        """
        if not (np.isfinite(scale) and scale > 0):
            raise InputError(f"scale: expected a positive factor, got {scale!r}")
        if isinstance(ranges_um, dict):
            missing = [m for m in self.minerals if m not in ranges_um]
            if missing:
                raise InputError(f"ranges: no range for mineral(s) {missing}")
            extra = [m for m in ranges_um if m not in self.minerals]
            if extra:
                raise InputError(f"ranges: mineral(s) {extra} are not in {self.source}")
            ranges_um = [ranges_um[m] for m in self.minerals]
        rng_um = np.asarray(ranges_um, float).reshape(self.n_minerals, 2)
        for k, (lo_k, hi_k) in enumerate(rng_um):
            if not (np.isfinite(lo_k) and np.isfinite(hi_k) and 0 < lo_k < hi_k):
                raise InputError(f"ranges: {self.minerals[k]!r} has [{lo_k:g}, {hi_k:g}] um, "
                                 "expected 0 < d_min < d_max")
        full = self.range_um()
        a = (rng_um[:, 1] - rng_um[:, 0]) / (full[:, 1] - full[:, 0])
        lo = (rng_um[:, :1] + (self.lo_um - full[:, :1]) * a[:, None]) * scale
        hi = (rng_um[:, :1] + (self.hi_um - full[:, :1]) * a[:, None]) * scale
        src = f"{self.source} [{label}, x{scale:g}]"
        return GrainSizeTable(minerals=self.minerals, lo_um=lo, hi_um=hi,
                              frequencies=self.frequencies.copy(),
                              volume_fractions=self.volume_fractions.copy(), source=src)


def read_table(path) -> GrainSizeTable:
    """Read and validate ``grains.csv``.

    Parameters
    ----------
    path : str or path-like
        CSV with the columns of DESIGN.md §4 (extra columns are ignored).

    Returns
    -------
    table : GrainSizeTable

    Raises
    ------
    InputError
        File missing or unreadable, or a row/field invalid (the message names both).
    """
    path = os.fspath(path)
    try:
        df = pd.read_csv(path, skipinitialspace=True)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except Exception as exc:  # pandas parser errors, empty file
        raise InputError(f"{path}: not a readable CSV ({exc})") from None
    df.columns = [str(c).strip() for c in df.columns]
    return GrainSizeTable.from_frame(df, source=path)


def example_table(name="table-4-1") -> GrainSizeTable:
    """A shipped example table: ``table-4-1`` is thesis Table 4-1 (SEM scale, um);
    ``thesis-ch6-pyroxene`` the one-mineral, 4 mm-grain model of the thesis's defect chapter.

    The same rows are in ``gbmgen/presets/table_4_1.csv`` (a ``grains.csv`` to copy).

    Raises
    ------
    InputError
        Unknown name.
    """
    from importlib import resources

    import yaml

    if name not in EXAMPLE_TABLES:
        raise InputError(f"table: unknown example {name!r}, expected one of {list(EXAMPLE_TABLES)}")
    text = resources.files("gbmgen").joinpath("presets", EXAMPLE_TABLES[name]).read_text()
    data = yaml.safe_load(text)
    df = pd.DataFrame(data["rows"], columns=data["columns"])
    return GrainSizeTable.from_frame(df, source=name)
