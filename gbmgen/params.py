"""Mineral and smooth-joint property tables (``--params``): named presets or a YAML/JSON file.

File layout (SI units; angles in degrees)::

    name: my-rock
    minerals:
      pyroxene: {density: 2500, emod: 58.0e+9, kratio: 1.5, fric: 1.0, pb_emod: 58.0e+9,
                 pb_kratio: 2.0, pb_ten: 300.0e+6, pb_coh: 250.0e+6, pb_fa: 35, pb_rmul: 1.0}
    smooth_joint: {sj_kn: 4.0e+9, sj_ks: 2.0e+9, sj_ten: 10.0e+6, sj_coh: 60.0e+6,
                   sj_fa: 32, sj_fric: 1.0}

The key names are those of ``specimen.npz`` (DESIGN.md §4). Presets ``thesis-ch4`` and
``thesis-ch5`` ship in ``gbmgen/presets``.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from importlib import resources

import numpy as np

from sim.specimen import JOINT_KEYS, MINERAL_KEYS

from .errors import InputError

__all__ = ["Params", "load_params", "PRESETS"]

#: Named presets shipped as package data.
PRESETS = ("thesis-ch4", "thesis-ch5")


@dataclass(frozen=True)
class Params:
    """Property tables. ``minerals`` maps name -> {key: float}; ``joint`` {key: float}."""

    name: str
    minerals: dict
    joint: dict
    source: str

    def mineral_arrays(self, names) -> dict:
        """{key: (M,) float64} for the minerals ``names`` in that order.

        Raises
        ------
        InputError
            A mineral of the table has no entry in the parameter file.
        """
        out = {k: np.zeros(len(names)) for k in MINERAL_KEYS}
        lower = {k.lower(): k for k in self.minerals}
        for i, name in enumerate(names):
            key = lower.get(str(name).lower())
            if key is None:
                raise InputError(f"{self.source}: no properties for mineral {name!r} under "
                                 f"'minerals' (has {sorted(self.minerals)})")
            for k in MINERAL_KEYS:
                out[k][i] = self.minerals[key][k]
        return out

    def joint_arrays(self) -> dict:
        return {k: np.array([self.joint[k]], float) for k in JOINT_KEYS}


def _number(value, where):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected a number, got {value!r}") from None
    if not np.isfinite(v):
        raise InputError(f"{where}: expected a finite number, got {value!r}")
    return v


def params_from_dict(data: dict, source: str = "params") -> Params:
    """Validate a parameter mapping (see the module docstring)."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a mapping with 'minerals' and 'smooth_joint'")
    minerals = data.get("minerals")
    if not isinstance(minerals, dict) or not minerals:
        raise InputError(f"{source}: field 'minerals' missing or empty, expected "
                         "{name: {density: ..., emod: ..., ...}}")
    out = {}
    for name, props in minerals.items():
        if not isinstance(props, dict):
            raise InputError(f"{source}: field 'minerals.{name}' is not a mapping")
        row = {}
        for k in MINERAL_KEYS:
            if k not in props:
                raise InputError(f"{source}: field 'minerals.{name}.{k}' missing")
            row[k] = _number(props[k], f"{source}: field 'minerals.{name}.{k}'")
            positive = k in ("density", "emod", "kratio", "pb_kratio", "pb_rmul")
            if (positive and row[k] <= 0) or row[k] < 0:
                raise InputError(f"{source}: field 'minerals.{name}.{k}' = {row[k]:g}, "
                                 f"expected {'> 0' if positive else '>= 0'}")
        out[str(name)] = row
    joint = data.get("smooth_joint")
    if not isinstance(joint, dict):
        raise InputError(f"{source}: field 'smooth_joint' missing, expected "
                         f"{{{', '.join(JOINT_KEYS)}}}")
    jrow = {}
    for k in JOINT_KEYS:
        if k not in joint:
            raise InputError(f"{source}: field 'smooth_joint.{k}' missing")
        jrow[k] = _number(joint[k], f"{source}: field 'smooth_joint.{k}'")
        if jrow[k] < 0 or (k in ("sj_kn", "sj_ks") and jrow[k] <= 0):
            raise InputError(f"{source}: field 'smooth_joint.{k}' = {jrow[k]:g}, expected > 0")
    return Params(name=str(data.get("name", source)), minerals=out, joint=jrow, source=source)


def load_params(name_or_path="thesis-ch4") -> Params:
    """A named preset (``thesis-ch4``, ``thesis-ch5``) or a YAML/JSON file.

    Raises
    ------
    InputError
        Unknown preset, unreadable file, or a missing/invalid field (named).
    """
    import yaml

    if name_or_path in PRESETS:
        text = resources.files("gbmgen").joinpath("presets", f"{name_or_path}.yaml").read_text()
        source = f"preset {name_or_path}"
    else:
        path = os.fspath(name_or_path)
        if not os.path.exists(path):
            raise InputError(f"{path}: no such parameter file (presets: {', '.join(PRESETS)})")
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
        source = path
    try:
        if str(name_or_path).endswith(".json"):
            data = json.loads(text)
        else:
            data = yaml.safe_load(text)
    except (yaml.YAMLError, json.JSONDecodeError) as exc:
        raise InputError(f"{source}: not valid YAML/JSON ({exc})") from None
    return params_from_dict(data, source)
