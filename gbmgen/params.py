"""Mineral and smooth-joint property tables (``--params``): named presets or a YAML/JSON file.

File layout (SI units; angles in degrees)::

    name: my-rock
    minerals:
      pyroxene: {density: 2500, emod: 58.0e+9, kratio: 1.5, fric: 1.0, pb_emod: 58.0e+9,
                 pb_kratio: 2.0, pb_ten: 300.0e+6, pb_coh: 250.0e+6, pb_fa: 35, pb_rmul: 1.0}
    joint: {sj_kn: bond, sj_ks: bond, sj_ten: 10.0e+6, sj_coh: 60.0e+6, sj_fa: 32, sj_fric: 1.0}

The key names are those of ``specimen.npz`` (DESIGN.md §4). This is the same layout that
``gbmsim calibrate`` writes (:mod:`sim.protocols.parameters`), so a calibrated file can be
passed back to ``gbmgen build --params``. ``smooth_joint`` is read as a synonym of ``joint``.

``sj_kn: bond`` and ``sj_ks: bond`` ask for a joint as stiff as a parallel bond between two
particles of the mean radius r̄: ``sj_kn = mean(pb_emod) / (2 r̄)`` (Pa/m) and
``sj_ks = sj_kn / 2`` (the thesis's tabled joint kn/ks of 2). The thesis presets use it because
Table 4-4's 4e9 / 2e9 Pa/m, read literally, makes every joint contact ~1e5 times softer than the
bonds and a Scenario-1 specimen ~1e4 times too soft (E ≈ 0.005 GPa measured; REFERENCE.md
flags the value). Write numbers instead to use the table literally. Presets ``thesis-ch4`` and
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

__all__ = ["Params", "load_params", "PRESETS", "bond_like_joint_stiffness"]

#: Value of ``sj_kn`` / ``sj_ks`` that asks for a bond-like joint stiffness.
BOND = "bond"


def bond_like_joint_stiffness(pb_emod, r_mean):
    """Joint stiffnesses per area equal to a parallel bond's between two mean particles.

    Parameters
    ----------
    pb_emod : (M,) array_like of float, Pa
        Bond moduli of the minerals (their plain mean is used).
    r_mean : float, m
        Mean particle radius.

    Returns
    -------
    sj_kn, sj_ks : float, Pa/m
        ``mean(pb_emod) / (2 r_mean)`` and half of it.

    Examples
    --------
    >>> bond_like_joint_stiffness([60e9], 1e-4)
    (300000000000000.0, 150000000000000.0)
    """
    kn = float(np.mean(pb_emod)) / (2.0 * float(r_mean))
    return kn, kn / 2.0

#: Named presets shipped as package data.
PRESETS = ("thesis-ch4", "thesis-ch5", "thesis-ch4-calibrated", "thesis-ch4-calibrated-25x50",
           "thesis-ch7")


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

    def joint_arrays(self, *, pb_emod=None, r_mean=None) -> dict:
        """{key: (1,) float64}; ``bond`` stiffnesses need ``pb_emod`` and ``r_mean`` (m)."""
        joint = dict(self.joint)
        if BOND in (joint["sj_kn"], joint["sj_ks"]):
            if pb_emod is None or r_mean is None:
                raise InputError(f"{self.source}: 'joint.sj_kn: bond' needs the bond moduli and "
                                 "the mean particle radius")
            kn, ks = bond_like_joint_stiffness(pb_emod, r_mean)
            joint["sj_kn"] = kn if joint["sj_kn"] == BOND else joint["sj_kn"]
            joint["sj_ks"] = ks if joint["sj_ks"] == BOND else joint["sj_ks"]
        return {k: np.array([joint[k]], float) for k in JOINT_KEYS}


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
        raise InputError(f"{source}: expected a mapping with 'minerals' and 'joint'")
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
    jkey = "joint" if "joint" in data else "smooth_joint"
    joint = data.get(jkey)
    if not isinstance(joint, dict):
        raise InputError(f"{source}: field 'joint' missing, expected "
                         f"{{{', '.join(JOINT_KEYS)}}}")
    jrow = {}
    for k in JOINT_KEYS:
        if k not in joint:
            raise InputError(f"{source}: field '{jkey}.{k}' missing")
        if k in ("sj_kn", "sj_ks") and joint[k] == BOND:
            jrow[k] = BOND
            continue
        jrow[k] = _number(joint[k], f"{source}: field '{jkey}.{k}'")
        if jrow[k] < 0 or (k in ("sj_kn", "sj_ks") and jrow[k] <= 0):
            raise InputError(f"{source}: field '{jkey}.{k}' = {jrow[k]:g}, expected > 0"
                             + (" (or 'bond')" if k in ("sj_kn", "sj_ks") else ""))
    return Params(name=str(data.get("name", source)), minerals=out, joint=jrow, source=source)


def read_preset_or_file(name_or_path, presets, what="parameter file"):
    """(data, source): a preset of ``gbmgen/presets`` by name, or a YAML/JSON file, parsed.

    Raises
    ------
    InputError
        Missing file (``what`` names it) or text that is not YAML/JSON.
    """
    import yaml

    if name_or_path in presets:
        text = resources.files("gbmgen").joinpath("presets", f"{name_or_path}.yaml").read_text()
        source = f"preset {name_or_path}"
    else:
        path = os.fspath(name_or_path)
        if not os.path.exists(path):
            raise InputError(f"{path}: no such {what} (presets: {', '.join(presets)})")
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
    return data, source


def load_params(name_or_path="thesis-ch4") -> Params:
    """A named preset (``thesis-ch4``, ``thesis-ch5``) or a YAML/JSON file.

    Raises
    ------
    InputError
        Unknown preset, unreadable file, or a missing/invalid field (named).
    """
    data, source = read_preset_or_file(name_or_path, PRESETS)
    return params_from_dict(data, source)
