"""Result files of an excavation (``gbmsim excavate``): summary.json, history.csv, cracks.csv,
damage_depth.csv, stress_profile.csv, displacement.csv and the figures (model by ring, crack
map with the damage envelope, D/R polar plot). Written atomically; matplotlib on demand."""
from __future__ import annotations

import os

import numpy as np
import pandas as pd

from ..field_geometry import ring_index
from ..field_measures import (
    BIN_DEG,
    NOTCH_MIN_DEPTH_SIZES,
    damage_depth,
    notches,
    stress_profile,
)
from .outputs import _pyplot, _save_figure, write_csv_atomic, write_json_atomic
from .report import crack_summary

__all__ = ["write_field_results", "plot_rings", "plot_crack_envelope", "plot_dr_polar"]


def _rings(specimen, x, y):
    f = specimen.meta.get("field") or {}
    plan = f.get("plan")
    if not plan:
        return np.ones(np.size(x), np.int8)
    outer = np.cumsum([r[0] for r in plan["rings"]])
    return ring_index(x, y, f["foci"], plan["core_half_m"], outer)


def _reference_radius(o):
    """Radius a of the Kirsch comparison: the circle's, or half the drive's width."""
    if o["kind"] == "circle":
        return o["radius_m"], o["centre"]
    if o["kind"] == "drive":
        return o["arch_radius_m"], o["centroid"]
    return float(np.sqrt(o["area_m2"] / np.pi)), o["centroid"]


def write_field_results(out, sim, specimen, stress, state, *, figures=True) -> dict:
    """Measure and write everything; returns the summary (also ``summary.json``)."""
    openings = specimen.meta["field"]["openings"]
    cracks = sim.cracks.to_frame()
    n_ins = int(state.get("cracks_insitu", 0))
    exc = cracks.iloc[n_ins:] if len(cracks) else cracks
    if len(cracks):
        cracks = cracks.assign(ring=_rings(specimen, cracks["x"].to_numpy(),
                                           cracks["y"].to_numpy()),
                               phase=np.where(np.arange(len(cracks)) < n_ins, "insitu",
                                              "excavate"))
    write_csv_atomic(os.path.join(out, "cracks.csv"), cracks)
    write_csv_atomic(os.path.join(out, "history.csv"), pd.DataFrame(state.get("history", [])))
    size = float(exc["size_m"].mean()) if len(exc) else 0.0
    dd_rows, per_opening, envelopes = [], [], {}
    polys = [np.asarray(o["polygon"]) for o in openings]
    for k, o in enumerate(openings):
        c = o["centre"] if o["kind"] == "circle" else o["centroid"]
        rows, conn = damage_depth(exc, polys[k], c, others=polys[:k] + polys[k + 1:])
        nt = notches(rows, c, NOTCH_MIN_DEPTH_SIZES * size) if size > 0 else []
        for r in rows:
            dd_rows.append({"opening": o["name"], "angle_deg": r["angle_deg"], "R_m": r["R_m"],
                            "D_m": r["D_m"], "D_over_R": r["D_over_R"],
                            "n_cracks": r["n_cracks"]})
        dr = np.array([r["D_over_R"] for r in rows])
        imax = int(np.nanargmax(dr)) if np.isfinite(dr).any() else 0
        per_opening.append({"name": o["name"], "kind": o["kind"], "centroid": c,
                            "max_D_over_R": float(np.nanmax(dr)) if np.isfinite(dr).any()
                            else None, "max_D_over_R_angle_deg": rows[imax]["angle_deg"],
                            "max_depth_m": float(np.nanmax([r["D_m"] - r["R_m"] for r in rows])),
                            "connected_cracks": int(conn.sum()), "notches": nt})
        envelopes[o["name"]] = (c, rows)
    write_csv_atomic(os.path.join(out, "damage_depth.csv"), pd.DataFrame(dd_rows))
    sp_rows = []
    for o in openings:
        a, c = _reference_radius(o)
        for r in stress_profile(sim, c, a, stress.sxx, stress.syy, profile=o["polygon"]):
            sp_rows.append({"opening": o["name"], "a_m": a, **r})
    sp = pd.DataFrame(sp_rows)
    write_csv_atomic(os.path.join(out, "stress_profile.csv"), sp)
    disp = _displacements(out, sim)
    if disp is not None:
        write_csv_atomic(os.path.join(out, "displacement.csv"), disp)
    ring_counts = {}
    if len(exc):
        g = cracks.iloc[n_ins:].groupby(["ring", "kind", "mode"]).size()
        for (ring, kind, mode), v in g.items():
            ring_counts.setdefault(str(int(ring)), {})[f"{kind}_{mode}"] = int(v)
    phases = state.get("phases", {})
    summary = {
        "test": "excavate", "specimen": specimen.meta, "insitu": stress.to_dict(),
        "options": state.get("options", {}), "phases": phases,
        "particles_removed": state.get("removed", []),
        "openings": per_opening, "damage_definition": (
            "bond breaks (pb or sj, tension or shear) during excavation, clustered at links of "
            "2 crack sizes and connected to the design profile; D = farthest connected break "
            f"from the centroid in {BIN_DEG:g} deg bins"),
        "cracks_insitu": n_ins, "cracks_by_ring": ring_counts,
        **crack_summary(exc),
        "steps": sim.step, "particles": sim.n_particles,
        "wall_s": float(sum(p.get("wall_s", 0.0) for p in phases.values())),
    }
    summary["kirsch"] = _kirsch_check(sp)
    if disp is not None and len(disp):
        summary["displacement_max_mm"] = float(np.hypot(disp["ux_mm"], disp["uy_mm"]).max())
    write_json_atomic(os.path.join(out, "summary.json"), summary)
    if figures:
        plot_rings(specimen, os.path.join(out, "model_rings.png"))
        plot_crack_envelope(sim, exc, polys, envelopes, os.path.join(out, "crack_map.png"))
        plot_dr_polar(envelopes, os.path.join(out, "dr_polar.png"))
    return summary


def _kirsch_check(sp):
    """Largest relative hoop-stress error at r/a = 1.5 and 2 (circle openings), and the
    wall value of σ_rr by linear extrapolation from r/a = 1.1 and 1.25."""
    out = {}
    for name, g in sp.groupby("opening"):
        sel = g[g["r_over_a"].isin([1.5, 2.0])]
        err = (sel["sigma_tt_mpa"] / sel["kirsch_tt_mpa"] - 1.0).abs()
        near = g[g["r_over_a"].isin([1.1, 1.25])].pivot(index="theta_deg", columns="r_over_a",
                                                          values="sigma_rr_mpa")
        wall = near[1.1] - (near[1.25] - near[1.1]) / 0.15 * 0.1 if len(near.columns) == 2 \
            else pd.Series(dtype=float)
        out[name] = {"hoop_rel_error_max_r1.5_2": float(err.max()) if len(err) else None,
                     "hoop_rel_error_by_theta": {f"{r.theta_deg:g}@{r.r_over_a:g}": float(e)
                                                 for r, e in zip(sel.itertuples(), err)},
                     "sigma_rr_wall_extrapolated_mpa": {f"{t:g}": float(v)
                                                        for t, v in wall.items()}}
    return out


def _displacements(out, sim):
    path = os.path.join(out, "insitu_positions.npz")
    if not os.path.exists(path):
        return None
    with np.load(path) as z:
        pid, x0, y0 = z["particle_id"], z["x"], z["y"]
    pos = {int(p): k for k, p in enumerate(pid)}
    k = np.array([pos[int(p)] for p in sim.particle_id])
    return pd.DataFrame({"particle_id": sim.particle_id, "x_m": sim.x, "y_m": sim.y,
                         "ux_mm": 1e3 * (sim.x - x0[k]), "uy_mm": 1e3 * (sim.y - y0[k])})


def plot_rings(specimen, path):
    """The model by ring: particles coloured by ring, openings outlined."""
    plt = _pyplot()
    from matplotlib.collections import EllipseCollection
    ring = _rings(specimen, specimen.x, specimen.y)
    fig, ax = plt.subplots(figsize=(7, 7))
    d = 2 * specimen.r
    ec = EllipseCollection(d, d, np.zeros_like(d), units="x", offsets=np.c_[specimen.x,
                           specimen.y], offset_transform=ax.transData, cmap="viridis")
    ec.set_array(ring.astype(float))
    ax.add_collection(ec)
    for o in specimen.meta["field"]["openings"]:
        p = np.asarray(o["polygon"])
        ax.plot(np.r_[p[:, 0], p[0, 0]], np.r_[p[:, 1], p[0, 1]], "r-", lw=1)
    b = specimen.box
    ax.set_xlim(b[0], b[1])
    ax.set_ylim(b[2], b[3])
    ax.set_aspect("equal")
    fig.colorbar(ec, ax=ax, label="ring")
    ax.set_title(f"{specimen.n_particles} particles by ring")
    return _save_figure(fig, path)


def plot_crack_envelope(sim, cracks, polys, envelopes, path):
    """Cracks over the design profile with the damage envelope D(θ), zoomed on the openings."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 7))
    colours = {"tension": "#d62728", "shear": "#1f77b4"}
    for mode, g in cracks.groupby("mode") if len(cracks) else []:
        ax.plot(g["x"], g["y"], ".", ms=2, color=colours.get(mode, "k"), label=f"{mode}")
    allp = np.vstack(polys)
    for p in polys:
        ax.plot(np.r_[p[:, 0], p[0, 0]], np.r_[p[:, 1], p[0, 1]], "k-", lw=1)
    for name, (c, rows) in envelopes.items():
        th = np.radians([r["angle_deg"] for r in rows])
        D = np.array([r["D_m"] for r in rows])
        ax.plot(c[0] + np.r_[D, D[:1]] * np.cos(np.r_[th, th[:1]]),
                c[1] + np.r_[D, D[:1]] * np.sin(np.r_[th, th[:1]]), "g-", lw=1)
    span = max(np.ptp(allp[:, 0]), np.ptp(allp[:, 1]))
    m = 0.5 * (allp.min(0) + allp.max(0))
    ax.set_xlim(m[0] - span, m[0] + span)
    ax.set_ylim(m[1] - span, m[1] + span)
    ax.set_aspect("equal")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"{len(cracks)} cracks; damage envelope D(θ) (green)")
    return _save_figure(fig, path)


def plot_dr_polar(envelopes, path):
    """D/R against direction for each opening (thesis Fig. 7-11)."""
    plt = _pyplot()
    fig = plt.figure(figsize=(6, 6))
    ax = fig.add_subplot(projection="polar")
    for name, (_c, rows) in envelopes.items():
        th = np.radians([r["angle_deg"] for r in rows])
        dr = np.array([r["D_over_R"] for r in rows])
        ax.plot(np.r_[th, th[:1]], np.r_[dr, dr[:1]], label=name)
    ax.set_rmin(0.0)
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title("D/R by direction")
    return _save_figure(fig, path)
