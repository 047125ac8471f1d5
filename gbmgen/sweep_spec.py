"""Sweep files: a YAML grid of specimens x tests, expanded into runs with an identity each.

A sweep file (docs/studies.md "Sweep file")::

    name: scenarios               # optional, names the progress bar and the report
    fixed:                        # options of every run
      table: table-4-1
      width_mm: 10
      height_mm: 20
      params: thesis-ch4-calibrated
    grid:                         # every combination of these lists (the last varies fastest)
      scenario: [1, 4]
      seed: [1, 2]
    cases:                        # optional: runs = cases x grid (a case may override fixed)
      - {test: ucs}
      - {test: brazilian, cut: true}

Every key is an option of one of three kinds, told apart by its name (:data:`BUILD_KEYS`,
:data:`DEFECT_KEYS`, and ``test`` with the test's options of
:mod:`sim.protocols.registry`). A run's identity (:func:`run_identity`) is a hash of its full,
normalised configuration: every build, defect and test option with the defaults filled in,
the content (not the path) of a table or parameter file, and the package version.
"""
from __future__ import annotations

import dataclasses
import hashlib
import inspect
import itertools
import json
import math
import pathlib

from . import __version__, config
from .errors import InputError

__all__ = ["BUILD_KEYS", "DEFECT_KEYS", "MANAGED_TEST_KEYS", "Run", "expand_sweep",
           "load_sweep", "run_identity", "canonical"]

#: Defect options of a sweep (``gbmgen defect``), with their defaults. ``hole``: none, intra,
#: inter, trans3, trans4 (one hole placed on the grains) or double (two holes
#: ``bridge_mm`` apart, wall to wall, at ``bridge_angle_deg`` from horizontal, about
#: ``hole_at_mm`` or the specimen centre); ``flaw_length_mm`` > 0 cuts an inclined flaw.
DEFECT_KEYS = {"hole": "none", "hole_diameter_mm": 3.0, "bridge_mm": 1.5,
               "bridge_angle_deg": 0.0, "hole_at_mm": None, "flaw_length_mm": 0.0,
               "flaw_width_mm": 0.5, "flaw_angle_deg": 0.0}
#: Test options the sweep sets itself (a sweep file may not give them).
MANAGED_TEST_KEYS = ("out", "progress", "resume", "checkpoint_every")
#: Keys of a sweep file.
TOP_KEYS = ("name", "description", "fixed", "grid", "cases")
#: Build size when a sweep gives none (the thesis specimen, REFERENCE.md).
DEFAULT_SIZE_MM = (25.0, 50.0)


def _build_defaults() -> dict:
    from .build import build_specimen
    out = {}
    for name, p in inspect.signature(build_specimen).parameters.items():
        out[name] = None if p.default is inspect.Parameter.empty else p.default
    out.update(width_mm=DEFAULT_SIZE_MM[0], height_mm=DEFAULT_SIZE_MM[1],
               seed=config.DEFAULT_SEED)
    return out


#: Build options of a sweep (:func:`gbmgen.build.build_specimen`) with their defaults.
BUILD_KEYS = _build_defaults()


def canonical(value):
    """A JSON-ready value with one spelling per number: a whole float becomes an int, a
    tuple a list, mapping keys strings (so ``5`` and ``5.0`` name the same run).

    Examples
    --------
    >>> canonical({"a": 5.0, "b": (0.5, True), "c": float("inf")})
    {'a': 5, 'b': [0.5, True], 'c': 'inf'}
    """
    if isinstance(value, dict):
        return {str(k): canonical(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [canonical(v) for v in value]
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            return str(value)
        return int(value) if value.is_integer() and abs(value) < 2 ** 53 else value
    if hasattr(value, "item"):            # numpy scalar
        return canonical(value.item())
    raise InputError(f"value {value!r}: expected a number, string, boolean, list or mapping")


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def run_identity(config_: dict) -> str:
    """The run's identity: the first 16 hex digits of the SHA-256 of its canonical JSON.

    Examples
    --------
    >>> run_identity({"b": 1.0, "a": [2]}) == run_identity({"a": [2], "b": 1})
    True
    """
    text = json.dumps(canonical(config_), sort_keys=True, separators=(",", ":"))
    return _digest(text)[:16]


@dataclasses.dataclass
class Run:
    """One run of a sweep.

    Attributes
    ----------
    run_id : str
        :func:`run_identity` of ``config``.
    given : dict
        The options the sweep file gave this run (results.csv columns).
    config : dict
        Full normalised configuration: ``build``, ``defect``, ``test``, ``test_options``,
        ``inputs`` (content hashes of a table or parameter file), ``version``.
    files : dict
        Text of the input files the worker needs (``table``, ``params``), by role.
    """

    run_id: str
    given: dict
    config: dict
    files: dict

    def payload(self) -> dict:
        """What a worker receives (plain data: no paths of this machine)."""
        return {"run_id": self.run_id, "config": self.config, "files": self.files}


def _test_defaults(name, where):
    from sim.protocols.options import TestOptions
    from sim.protocols.registry import protocol
    try:
        cls = protocol(name)
    except ValueError as exc:
        raise InputError(f"{where}: test: {exc}") from None
    shared = {f.name: f.default for f in dataclasses.fields(TestOptions)
              if f.name not in MANAGED_TEST_KEYS}
    own = {f.name: (f.default if f.default is not dataclasses.MISSING else
                    f.default_factory() if f.default_factory is not dataclasses.MISSING
                    else None) for f in dataclasses.fields(cls)}
    return cls, shared, own


def _input_file(value, role, base, files, inputs, where):
    """A table or parameter file: its text goes to the worker, its hash into the identity."""
    from .params import PRESETS
    from .table import EXAMPLE_TABLES
    names = EXAMPLE_TABLES if role == "table" else PRESETS
    if value is None or value in names:
        return value
    path = pathlib.Path(value)
    path = path if path.is_absolute() else base / path
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        raise InputError(f"{where}: {role}: {value!r} is neither a file nor one of "
                         f"{', '.join(names)}") from None
    files[role] = text
    files[role + "_suffix"] = path.suffix
    inputs[role] = {"sha256": _digest(text), "name": path.name}
    return f"file:{path.name}"


def _normalise(options: dict, base: pathlib.Path, where: str) -> Run:
    build, defect, test_given = {}, {}, {}
    test = options.get("test", "ucs")
    cls, shared, own = _test_defaults(test, where)
    for key, value in options.items():
        if key == "test":
            continue
        if key in BUILD_KEYS:
            build[key] = value
        elif key in DEFECT_KEYS:
            defect[key] = value
        elif key in shared or key in own:
            test_given[key] = value
        elif key in MANAGED_TEST_KEYS:
            raise InputError(f"{where}: option {key!r} is set by the sweep itself")
        else:
            raise InputError(f"{where}: unknown option {key!r} (build: {', '.join(BUILD_KEYS)};"
                             f" defect: {', '.join(DEFECT_KEYS)}; test: test, "
                             f"{', '.join(sorted(set(shared) | set(own)))})")
    files, inputs = {}, {}
    build = {**BUILD_KEYS, **build}
    build["table"] = _input_file(build["table"], "table", base, files, inputs, where)
    build["params"] = _input_file(build["params"], "params", base, files, inputs, where)
    if build["table"] is None and build["shape"] is None:
        raise InputError(f"{where}: give 'table' (a grains.csv or table-4-1) or 'shape'")
    defect = {**DEFECT_KEYS, **defect}
    if defect["hole"] not in ("none", "intra", "inter", "trans3", "trans4", "double"):
        raise InputError(f"{where}: hole = {defect['hole']!r}, expected none, intra, inter, "
                         "trans3, trans4 or double")
    test_options = {**shared, **own, **test_given}
    try:                                   # the test's own checks, before anything runs
        from sim.protocols.options import split_options
        opts, own_given = split_options(cls, test_given)
        cls(**own_given)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: {exc}") from None
    del opts
    cfg = canonical({"build": build, "defect": defect, "test": test,
                     "test_options": test_options, "inputs": inputs, "version": __version__})
    return Run(run_id=run_identity(cfg), given=dict(options), config=cfg, files=files)


def expand_sweep(doc: dict, *, base=".", where="sweep") -> list:
    """The runs of a sweep document (the mapping a sweep file holds), in sweep order.

    Parameters
    ----------
    doc : dict
        ``fixed``, ``grid``, ``cases`` (module docstring).
    base : path
        Folder that relative table and parameter paths are read from.
    where : str
        How messages name the document.

    Returns
    -------
    runs : list of Run
        One per distinct configuration (a repeated one is kept once).

    Raises
    ------
    InputError
        A bad key or value (named).
    """
    if not isinstance(doc, dict):
        raise InputError(f"{where}: expected a mapping with keys {', '.join(TOP_KEYS)}")
    bad = [k for k in doc if k not in TOP_KEYS]
    if bad:
        raise InputError(f"{where}: unknown key {bad[0]!r}, expected {', '.join(TOP_KEYS)}")
    fixed = doc.get("fixed") or {}
    grid = doc.get("grid") or {}
    cases = doc.get("cases") or [{}]
    if not isinstance(fixed, dict) or not isinstance(grid, dict):
        raise InputError(f"{where}: 'fixed' and 'grid' must be mappings of option names")
    if not isinstance(cases, list) or not all(isinstance(c, dict) for c in cases):
        raise InputError(f"{where}: 'cases' must be a list of mappings of option names")
    for k, v in grid.items():
        if not isinstance(v, list) or not v:
            raise InputError(f"{where}: grid.{k}: expected a non-empty list of values")
        clash = k in fixed or any(k in c for c in cases)
        if clash:
            raise InputError(f"{where}: grid.{k}: also given in 'fixed' or 'cases'")
    runs, seen = [], set()
    keys = list(grid)
    for n, case in enumerate(cases):
        for values in itertools.product(*(grid[k] for k in keys)):
            options = {**fixed, **case, **dict(zip(keys, values))}
            label = f"{where}: case {n + 1}" if len(cases) > 1 else where
            run = _normalise({str(k).replace("-", "_"): v for k, v in options.items()},
                             pathlib.Path(base), label)
            if run.run_id not in seen:
                seen.add(run.run_id)
                runs.append(run)
    if not runs:
        raise InputError(f"{where}: the sweep has no runs")
    return runs


def load_sweep(path) -> tuple:
    """Read a sweep file: ``(doc, runs)`` (:func:`expand_sweep`).

    Raises
    ------
    InputError
        Unreadable or invalid file (named).
    """
    import yaml
    path = pathlib.Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"{path}: cannot read the sweep file ({exc.strerror})") from None
    except yaml.YAMLError as exc:
        raise InputError(f"{path}: not valid YAML ({' '.join(str(exc).split())})") from None
    return doc, expand_sweep(doc, base=path.parent, where=str(path))
