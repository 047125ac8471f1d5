"""Micro-parameter files (YAML) and their application to a :class:`sim.Specimen`.

A parameter file names the mineral tables of ``specimen.npz`` (DESIGN.md §4) per mineral, plus
the single smooth-joint table. SI units throughout (Pa, Pa/m, kg/m³); angles in degrees::

    units: SI (Pa, Pa/m, kg/m3, deg)
    minerals:
      pyroxene: {density: 2500.0, emod: 5.8e+10, kratio: 1.5, ...}
      plagioclase: {...}
    default: {...}        # optional: applied to minerals not named above
    joint: {sj_kn: 4.0e+9, sj_ks: 2.0e+9, sj_ten: 1.0e+7, sj_coh: 6.0e+7, sj_fa: 32.0,
            sj_fric: 1.0}

:func:`thesis_parameters` returns the thesis Ch. 4 set (Tables 4-3/4-4).
"""
from __future__ import annotations

import copy
import dataclasses

import numpy as np

from ..errors import InputError
from ..specimen import JOINT_KEYS, MINERAL_KEYS
from .outputs import write_text_atomic

__all__ = ["thesis_parameters", "start_parameters", "load_parameters", "save_parameters",
           "apply_parameters", "parameters_from_specimen"]


def thesis_parameters() -> dict:
    """Thesis Ch. 4 micro-parameters (Tables 4-3/4-4; REFERENCE.md), as a parameter dict.

    Pyroxene / plagioclase / biotite: density 2500/2600/2800 kg/m³, particle friction 1.0,
    particle kn/ks 1.5, bond kn/ks 2.0/2.0/1.5, bond (and contact) modulus 58/65/61 GPa, bond
    tensile strength 300/330/320 MPa, cohesion 250/300/270 MPa, friction angle 35°. Smooth joint
    kn 4e9, ks 2e9 Pa/m (as tabled; REFERENCE.md flags them as suspiciously soft), tensile
    10 MPa, cohesion 60 MPa, friction angle 32°, friction coefficient 1.0.
    """
    minerals = {}
    for name, rho, kr, e, ten, coh in (("pyroxene", 2500.0, 2.0, 58e9, 300e6, 250e6),
                                       ("plagioclase", 2600.0, 2.0, 65e9, 330e6, 300e6),
                                       ("biotite", 2800.0, 1.5, 61e9, 320e6, 270e6)):
        minerals[name] = dict(density=rho, emod=e, kratio=1.5, fric=1.0, pb_emod=e,
                              pb_kratio=kr, pb_ten=ten, pb_coh=coh, pb_fa=35.0, pb_rmul=1.0)
    joint = dict(sj_kn=4e9, sj_ks=2e9, sj_ten=10e6, sj_coh=60e6, sj_fa=32.0, sj_fric=1.0)
    return {"units": "SI (Pa, Pa/m, kg/m3, deg)", "minerals": minerals, "joint": joint}


def start_parameters(specimen) -> dict:
    """Thesis Ch. 4 set with a usable smooth-joint stiffness: the calibration starting point.

    Table 4-4's joint stiffness (4e9 / 2e9) read as Pa/m gives joint contacts ~1e5 times
    softer than the bonds (REFERENCE.md flags this): a Scenario-1 specimen then has E ≈ 0.002
    GPa (measured). Here ``sj_kn`` = mean Ē / (2 r̄) of the specimen (a joint as stiff as a
    bond of the mean particle) and ``sj_ks = sj_kn / 2`` (the thesis kn/ks of 2); the
    calibration then scales all moduli together. Measured on a 5 x 10 mm Scenario-1 specimen:
    E 66.9 GPa, UCS 160 MPa, σt 8.3 MPa before calibration.
    """
    p = thesis_parameters()
    e = np.mean([m["pb_emod"] for m in p["minerals"].values()])
    kn = float(e / (2.0 * float(np.mean(specimen.r))))
    p["joint"].update(sj_kn=kn, sj_ks=kn / 2.0)
    p["note"] = ("thesis Ch. 4 (Tables 4-3/4-4) with sj_kn = mean pb_emod / (2 r_mean), "
                 "sj_ks = sj_kn / 2")
    return p


def _floats(table, where):
    out = {}
    for k, v in (table or {}).items():
        if k not in MINERAL_KEYS and k not in JOINT_KEYS:
            raise InputError(f"{where}: unknown field '{k}', expected one of "
                             f"{', '.join(MINERAL_KEYS + JOINT_KEYS)}")
        try:
            out[k] = float(v)
        except (TypeError, ValueError):
            raise InputError(f"{where}.{k} = {v!r}: expected a number") from None
        if not np.isfinite(out[k]) or out[k] < 0:
            raise InputError(f"{where}.{k} = {v!r}: expected a finite number >= 0")
    return out


def _validate(params, source):
    if not isinstance(params, dict):
        raise InputError(f"{source}: expected a mapping with 'minerals' and/or 'joint'")
    out = {"units": params.get("units", "SI (Pa, Pa/m, kg/m3, deg)"), "minerals": {}}
    for name, table in (params.get("minerals") or {}).items():
        out["minerals"][str(name)] = _floats(table, f"{source}: minerals.{name}")
    if params.get("default") is not None:
        out["default"] = _floats(params["default"], f"{source}: default")
    joint = _floats(params.get("joint"), f"{source}: joint")
    bad = [k for k in joint if k not in JOINT_KEYS]
    if bad:
        raise InputError(f"{source}: joint.{bad[0]} is a mineral field, not a joint field")
    out["joint"] = joint
    for k, v in params.items():
        if k not in ("units", "minerals", "default", "joint"):
            out[k] = v
    return out


def load_parameters(path) -> dict:
    """Read and check a parameter YAML file (``yaml.safe_load``).

    Raises
    ------
    InputError
        Missing file, not YAML, unknown field or non-numeric value (named).
    """
    import yaml
    try:
        with open(path, encoding="utf-8") as f:
            data = yaml.safe_load(f)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except yaml.YAMLError as exc:
        raise InputError(f"{path}: not YAML ({exc})") from None
    return _validate(data, str(path))


def save_parameters(path, params: dict, *, header: str = "") -> str:
    """Write a parameter dict as YAML atomically (floats written so that YAML reads floats)."""
    import yaml
    p = _validate(copy.deepcopy(params), "parameters")
    text = yaml.safe_dump(p, sort_keys=False, default_flow_style=False)
    if header:
        text = "".join(f"# {line}\n" for line in header.splitlines()) + text
    return write_text_atomic(path, text)


def parameters_from_specimen(specimen) -> dict:
    """The mineral and joint tables of a specimen as a parameter dict."""
    minerals = {str(n): {k: float(getattr(specimen, k)[m]) for k in MINERAL_KEYS}
                for m, n in enumerate(specimen.mineral_names)}
    joint = {k: float(getattr(specimen, k)[0]) for k in JOINT_KEYS}
    return {"units": "SI (Pa, Pa/m, kg/m3, deg)", "minerals": minerals, "joint": joint}


def apply_parameters(specimen, params: dict, *, strict: bool = False):
    """A copy of ``specimen`` with its mineral and joint tables taken from ``params``.

    Minerals are matched by name; ``params["default"]`` fills minerals not named. The input
    specimen is not changed.

    Parameters
    ----------
    specimen : sim.Specimen
    params : dict
        As returned by :func:`load_parameters` or :func:`thesis_parameters`.
    strict : bool
        If true, every mineral of the specimen must be covered by a name or ``default``.

    Returns
    -------
    specimen : sim.Specimen

    Raises
    ------
    InputError
        With ``strict``, a specimen mineral without parameters; always, a parameter set that
        matches no mineral of the specimen and has no ``default``.
    """
    p = _validate(params, "parameters")
    names = [str(n) for n in specimen.mineral_names]
    tables = {k: np.array(getattr(specimen, k), dtype=float, copy=True)
              for k in MINERAL_KEYS + JOINT_KEYS}
    matched = 0
    for m, name in enumerate(names):
        table = p["minerals"].get(name, p.get("default"))
        if table is None:
            if strict:
                raise InputError(f"parameters: no entry for mineral '{name}' and no 'default'")
            continue
        matched += 1
        for k, v in table.items():
            if k in MINERAL_KEYS:
                tables[k][m] = v
    if p["minerals"] and matched == 0 and "default" not in p:
        raise InputError(f"parameters: minerals {sorted(p['minerals'])} match none of the "
                         f"specimen's {names}")
    for k, v in p["joint"].items():
        tables[k][0] = v
    return dataclasses.replace(specimen, **tables, meta=dict(specimen.meta)).validate("parameters")
