"""Checkpoints of a simulation: the whole state in one npz file (no pickle), written atomically
and read back bit-identically."""
from __future__ import annotations

import json
import os

import numpy as np

from ._io import load_npz, save_npz_atomic
from .cracks import CrackLog
from .errors import InputError
from .specimen import Specimen
from .state import State

__all__ = ["FORMAT", "save_simulation", "load_simulation"]

FORMAT = "gbmsim-checkpoint-1"


def save_simulation(sim, path) -> None:
    """Write the full state of ``sim`` to ``path`` (npz, no pickle) atomically: temp file,
    fsync, rename. :func:`load_simulation` of the file continues bit-identically on the same
    machine at the same force-chunk count (any thread count).
    """
    meta = dict(format=FORMAT, step=sim.step, time=sim.time, dt=sim.dt,
                damping=sim.damping, timestep_factor=sim.timestep_factor,
                dashpot=list(sim.dashpot), density_scale=sim.density_scale,
                skin=sim.skin, pb_mcf=sim.pb_mcf, sj_dilation_deg=sim.sj_dilation_deg,
                damping_work=sim.damping_work, kspread=getattr(sim, "_kspread", None),
                refresh=bool(sim._refresh), sleep=sim.sleep, sleep_disp=sim.sleep_disp,
                sleep_force_ratio=sim.sleep_force_ratio, sleep_steps=sim.sleep_steps)
    arrays = {"sim_meta": np.array(json.dumps(meta))}
    arrays.update({"state__" + k: v for k, v in sim.state.to_dict().items()})
    arrays.update({"spec__" + k: v for k, v in sim.specimen.to_arrays().items()})
    arrays.update(sim.cracks.to_npz_dict())
    save_npz_atomic(path, arrays)


def load_simulation(cls, path):
    """A ``cls`` (Simulation) read from a checkpoint written by :func:`save_simulation`.

    Raises
    ------
    InputError
        Missing or unreadable file, or not a checkpoint of this format.
    """
    path = os.fspath(path)
    data = load_npz(path, "checkpoint")
    try:
        meta = json.loads(str(data["sim_meta"][()]))
    except (KeyError, json.JSONDecodeError):
        raise InputError(f"{path}: field 'sim_meta' missing or not JSON") from None
    if meta.get("format") != FORMAT:
        raise InputError(f"{path}: format {meta.get('format')!r}, expected {FORMAT!r}")
    spec = Specimen.from_arrays({k[6:]: v for k, v in data.items() if k.startswith("spec__")},
                                source=path)
    self = cls.__new__(cls)
    self.specimen = spec
    self.damping = meta["damping"]
    self.timestep_factor = meta["timestep_factor"]
    self.dashpot = tuple(meta["dashpot"])
    self.density_scale = meta["density_scale"]
    self.skin = meta["skin"]
    self.pb_mcf = meta["pb_mcf"]
    self.sj_dilation_deg = meta["sj_dilation_deg"]
    self.step = int(meta["step"])
    self.time = float(meta["time"])
    self.dt = float(meta["dt"])
    self.damping_work = float(meta["damping_work"])
    self._refresh = bool(meta["refresh"])
    self.sleep = bool(meta["sleep"])
    self.sleep_disp = float(meta["sleep_disp"])
    self.sleep_force_ratio = float(meta["sleep_force_ratio"])
    self.sleep_steps = int(meta["sleep_steps"])
    self._rmean = float(np.mean(spec.r))
    if meta.get("kspread") is not None:
        self._kspread = meta["kspread"]
    self.state = State.from_dict({k[7:]: v for k, v in data.items()
                                  if k.startswith("state__")})
    self.cracks = CrackLog.from_npz_dict(data)
    self._info = np.zeros(8)
    return self
