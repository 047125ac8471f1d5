"""In-situ stress of a field model: far-field stresses from depth, four servo walls, per-joint
stiffness of ring-graded specimens and the unbreakable (elastic) variant.

Defaults (docs/field.md, "In-situ stress"): σv = ρ g z with ρ = 2700 kg/m³ (0.0265 MPa/m) and
σ1 = σH = k σv horizontal with k = 2.0; or gradients in MPa/m. Compression positive.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .. import config
from ..errors import InputError
from ..state import KNA, KSA, R

__all__ = ["InsituStress", "insitu_stress", "add_boundary_walls", "wall_stresses",
           "update_servo_lengths", "apply_per_joint_stiffness", "unbreakable", "G",
           "ROCK_DENSITY", "K_RATIO"]

#: Gravity, m/s².
G = 9.81
#: Overburden density, kg/m³ (σv = 0.0265 MPa/m).
ROCK_DENSITY = 2700.0
#: Default horizontal-to-vertical stress ratio (σ1 horizontal).
K_RATIO = 2.0
#: Strength given to every bond by :func:`unbreakable`, Pa.
UNBREAKABLE = 1e100


@dataclasses.dataclass(frozen=True)
class InsituStress:
    """Far-field stresses, Pa, compression positive: ``sxx`` horizontal (σ1), ``syy`` vertical."""

    depth_m: float
    sxx: float
    syy: float
    source: str

    def to_dict(self):
        return {"depth_m": self.depth_m, "sigma_h_mpa": self.sxx / 1e6,
                "sigma_v_mpa": self.syy / 1e6, "source": self.source}


def insitu_stress(depth_m, *, k_ratio=None, density=ROCK_DENSITY, gradients_mpa_per_m=None):
    """Far-field stresses at ``depth_m``.

    Parameters
    ----------
    depth_m : float
        Depth below surface, m (> 0).
    k_ratio : float, optional
        σH / σv (default ``K_RATIO``).
    density : float
        Overburden density for σv = ρ g z, kg/m³.
    gradients_mpa_per_m : (float, float), optional
        (horizontal, vertical) gradients in MPa/m instead of ρ g z and ``k_ratio``.

    Returns
    -------
    InsituStress
    """
    z = float(depth_m)
    if not (np.isfinite(z) and z > 0):
        raise InputError(f"depth_m = {depth_m!r}: expected a depth > 0 m")
    if gradients_mpa_per_m is not None:
        gh, gv = (float(v) for v in gradients_mpa_per_m)
        if not (gh > 0 and gv > 0):
            raise InputError(f"gradients = {gradients_mpa_per_m!r}: expected two values > 0 "
                             "MPa/m (horizontal, vertical)")
        return InsituStress(z, gh * z * 1e6, gv * z * 1e6,
                            f"gradients {gh:g} (horizontal), {gv:g} (vertical) MPa/m")
    k = K_RATIO if k_ratio is None else float(k_ratio)
    if not (k > 0 and density > 0):
        raise InputError(f"k_ratio = {k_ratio!r}, density = {density!r}: expected > 0")
    sv = density * G * z
    return InsituStress(z, k * sv, sv, f"sigma_v = rho g z (rho {density:g} kg/m3), "
                                      f"sigma_h = {k:g} sigma_v")


def add_boundary_walls(sim, box, stress: InsituStress, *, vmax=config.SERVO_VMAX):
    """Four frictionless walls on the box faces, servo-held at the far-field stresses.

    Returns
    -------
    walls : (4,) tuple of int
        left, right, bottom, top.
    """
    b = np.asarray(box, float)
    w, h = b[1] - b[0], b[3] - b[2]
    cx, cy = 0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3])
    walls = (sim.add_wall((b[0], cy), (1.0, 0.0)), sim.add_wall((b[1], cy), (-1.0, 0.0)),
             sim.add_wall((cx, b[2]), (0.0, 1.0)), sim.add_wall((cx, b[3]), (0.0, -1.0)))
    for i in walls[:2]:
        sim.set_servo(i, stress.sxx, h, vmax=vmax)
    for i in walls[2:]:
        sim.set_servo(i, stress.syy, w, vmax=vmax)
    return walls


def wall_stresses(sim, walls):
    """(σxx, σyy), Pa: mean normal stress of the side and of the end walls over the current
    spans (compression positive)."""
    lx = sim.wall_position(walls[1])[0] - sim.wall_position(walls[0])[0]
    ly = sim.wall_position(walls[3])[1] - sim.wall_position(walls[2])[1]
    sxx = 0.5 * (sim.wall_stress(walls[0], ly) + sim.wall_stress(walls[1], ly))
    syy = 0.5 * (sim.wall_stress(walls[2], lx) + sim.wall_stress(walls[3], lx))
    return sxx, syy


def update_servo_lengths(sim, walls, stress: InsituStress):
    """Re-target the servos on the current spans (they shorten as the walls close in)."""
    lx = sim.wall_position(walls[1])[0] - sim.wall_position(walls[0])[0]
    ly = sim.wall_position(walls[3])[1] - sim.wall_position(walls[2])[1]
    for i in walls[:2]:
        sim.set_servo(i, stress.sxx, ly)
    for i in walls[2:]:
        sim.set_servo(i, stress.syy, lx)


def apply_per_joint_stiffness(sim) -> int:
    """Give every smooth joint a bond-like stiffness of its own pair: sj_kn = mean(pb_emod) /
    (r_i + r_j), sj_ks = sj_kn × (specimen sj_ks / sj_kn).

    ``gbmgen``'s ``sj_kn: bond`` resolves one per-area stiffness at the mean radius; in a
    ring-graded specimen (radii 17-397 mm) that would make the joints of the outer rings up to
    ~8x stiffer than their bonds and of the inner ones ~2x softer, and each ring a different
    rock. Per joint, every ring has the same modulus (specimen ``meta["field"]
    ["joint_stiffness"] == "per_joint_bond"``). Call before any loading (joint forces 0);
    rebuilds the lists and the time step. Returns the number of joints changed.
    """
    st = sim.state
    sp = sim.specimen
    sj = np.flatnonzero(st.bkind == 1)
    if sj.size == 0:
        return 0
    r = st.pf[R]
    ri, rj = r[st.bi[sj]], r[st.bj[sj]]
    kn = float(np.mean(sp.pb_emod)) / (ri + rj)
    ks = kn * float(sp.sj_ks[0] / sp.sj_kn[0])
    area = 2.0 * np.minimum(ri, rj) * config.THICKNESS
    st.bf[KNA, sj] = kn * area
    st.bf[KSA, sj] = ks * area
    sim.rebuild()
    return int(sj.size)


def unbreakable(specimen):
    """A copy of ``specimen`` whose bonds and joints cannot break (``--elastic``)."""
    kw = {f.name: getattr(specimen, f.name) for f in dataclasses.fields(specimen)}
    for k in ("pb_ten", "pb_coh"):
        kw[k] = np.full_like(kw[k], UNBREAKABLE)
    for k in ("sj_ten", "sj_coh"):
        kw[k] = np.array([UNBREAKABLE])
    kw["meta"] = dict(specimen.meta, elastic=True)
    return type(specimen)(**kw)
