"""Result files of a laboratory test (DESIGN.md §4): summary.json, history.csv, cracks.csv, PNGs.

Every file is written atomically: to a temporary file in the same directory, then renamed, so a
reader (or a Ctrl-C) never sees half a file. Matplotlib is imported only when a figure is drawn.
"""
from __future__ import annotations

import json
import math
import os

import numpy as np

from .._io import write_atomic

__all__ = ["HISTORY_COLUMNS", "CRACK_COLUMNS", "write_text_atomic", "write_json_atomic",
           "write_csv_atomic", "write_results", "plot_history", "plot_crack_map",
           "json_ready"]

#: Minimum columns of ``history.csv`` (compression positive; stresses in MPa).
HISTORY_COLUMNS = ("step", "time_s", "axial_strain", "lateral_strain", "volumetric_strain",
                   "axial_stress_mpa", "confining_stress_mpa", "cracks_pb_tension",
                   "cracks_pb_shear", "cracks_sj_tension", "cracks_sj_shear", "cracks_total",
                   "kinetic_energy_j", "strain_energy_j")
#: Minimum columns of ``cracks.csv`` (one row per broken bond).
CRACK_COLUMNS = ("step", "time", "x", "y", "kind", "mode", "relation", "mineral_i",
                 "mineral_j", "grain_i", "grain_j", "size_m")

_KIND_COLOURS = {"pb_tension": "#d62728", "pb_shear": "#1f77b4",
                 "sj_tension": "#ff7f0e", "sj_shear": "#2ca02c"}


def write_text_atomic(path, text: str) -> str:
    """Write ``text`` to ``path`` atomically; returns the path."""
    def w(tmp):
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
    return write_atomic(path, w)


def json_ready(obj):
    """Convert numpy scalars/arrays to Python and non-finite floats to ``None`` (strict JSON).

    Examples
    --------
    >>> json_ready({"a": np.float64(1.5), "b": [float("inf"), np.int32(2)]})
    {'a': 1.5, 'b': [None, 2]}
    """
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_ready(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json_atomic(path, obj) -> str:
    """Write ``obj`` as indented strict JSON (NaN/inf become ``null``) atomically."""
    return write_text_atomic(path, json.dumps(json_ready(obj), indent=2, allow_nan=False) + "\n")


def write_csv_atomic(path, frame) -> str:
    """Write a pandas DataFrame as CSV (no index) atomically."""
    return write_atomic(path, lambda tmp: frame.to_csv(tmp, index=False))


def write_results(out_dir, *, summary: dict, history=None, cracks=None) -> dict:
    """Write ``summary.json``, ``history.csv`` and ``cracks.csv`` into ``out_dir``.

    Parameters
    ----------
    out_dir : path
    summary : dict
        JSON-able summary (numpy values and NaN are converted).
    history, cracks : pandas.DataFrame, optional

    Returns
    -------
    paths : dict
        File name -> path written.
    """
    paths = {}
    if history is not None:
        paths["history.csv"] = write_csv_atomic(os.path.join(out_dir, "history.csv"), history)
    if cracks is not None:
        paths["cracks.csv"] = write_csv_atomic(os.path.join(out_dir, "cracks.csv"), cracks)
    paths["summary.json"] = write_json_atomic(os.path.join(out_dir, "summary.json"), summary)
    return paths


def _save_figure(fig, path):
    import matplotlib.pyplot as plt
    try:
        write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=130, format="png"))
    finally:
        plt.close(fig)
    return os.fspath(path)


def _pyplot():
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    return plt


def plot_history(history, path, *, summary=None, stress_column="axial_stress_mpa",
                 strain_column="axial_strain", title=""):
    """Stress–strain curve with volumetric/lateral strain and the cumulative crack count.

    Top panel: stress against axial strain, with UCS, CI and CD marked when ``summary`` has
    them. Bottom panel: lateral and volumetric strain (left axis) and crack count by kind
    (right axis) against axial strain.

    Parameters
    ----------
    history : pandas.DataFrame
        Columns of :data:`HISTORY_COLUMNS` (those present are drawn).
    path : path of the PNG
    summary : dict, optional
        ``ucs_mpa``, ``ci_mpa``, ``cd_mpa`` (or ``tensile_mpa``) to mark.
    """
    plt = _pyplot()
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6.4, 7.2), sharex=True)
    e = np.asarray(history[strain_column]) * 1e3
    s = np.asarray(history[stress_column])
    ax1.plot(e, s, "k-", lw=1.4, label=stress_column)
    summary = summary or {}
    for key, colour in (("ucs_mpa", "k"), ("ci_mpa", "tab:orange"), ("cd_mpa", "tab:red"),
                        ("tensile_mpa", "k")):
        v = summary.get(key)
        if v is not None and np.isfinite(v):
            ax1.axhline(v, color=colour, ls=":", lw=0.9, label=f"{key} = {v:.1f}")
    ax1.set_ylabel("stress (MPa, compression +)" if "axial" in stress_column else "stress (MPa)")
    ax1.legend(fontsize=7, loc="lower right")
    ax1.set_title(title)
    for col, st in (("lateral_strain", "--"), ("volumetric_strain", "-")):
        if col in history:
            ax2.plot(e, np.asarray(history[col]) * 1e3, "b" + st, lw=1, label=col)
    ax2.set_xlabel(f"{strain_column} (10^-3)")
    ax2.set_ylabel("strain (10^-3)", color="b")
    ax2.legend(fontsize=7, loc="lower left")
    ax3 = ax2.twinx()
    for kind, colour in _KIND_COLOURS.items():
        col = f"cracks_{kind}"
        if col in history and np.any(np.asarray(history[col]) > 0):
            ax3.plot(e, history[col], color=colour, lw=1, label=kind)
    if "cracks_total" in history:
        ax3.plot(e, history["cracks_total"], color="0.4", lw=1.2, label="total")
    ax3.set_ylabel("cumulative cracks")
    ax3.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return _save_figure(fig, path)


def plot_crack_map(specimen, cracks, path, *, x=None, y=None, magnify: float = 0.0,
                   title=""):
    """Final crack map over the grains, cracks coloured by kind.

    Parameters
    ----------
    specimen : sim.Specimen
        Grain polygons (if any) are drawn filled by mineral, particles as outlines otherwise.
    cracks : pandas.DataFrame
        Columns ``x, y, kind, mode, size_m``; ``nx, ny`` or ``angle_deg`` (crack-plane normal)
        when present turn the markers into segments of length ``size_m`` along the crack plane.
    path : path of the PNG
    x, y : (N,) ndarray, m, optional
        Final particle positions: grains are drawn displaced by the mean displacement of their
        particles times ``magnify`` (0: undeformed).
    """
    plt = _pyplot()
    from matplotlib.collections import LineCollection, PolyCollection

    fig, ax = plt.subplots(figsize=(5.0, 7.2))
    cmap = plt.get_cmap("Pastel1")
    if specimen.n_grains > 0:
        polys, colours = [], []
        for g in range(specimen.n_grains):
            p = specimen.grain_polygon(g).copy()
            if magnify and x is not None:
                sel = specimen.grain == g
                if np.any(sel):
                    p[:, 0] += magnify * np.mean(np.asarray(x)[sel] - specimen.x[sel])
                    p[:, 1] += magnify * np.mean(np.asarray(y)[sel] - specimen.y[sel])
            polys.append(p)
            colours.append(cmap(int(specimen.grain_mineral[g]) % 9))
        ax.add_collection(PolyCollection(polys, facecolors=colours, edgecolors="0.6",
                                         linewidths=0.3))
        for m, name in enumerate(specimen.mineral_names):
            ax.plot([], [], "s", color=cmap(m % 9), label=str(name))
    else:
        from matplotlib.collections import EllipseCollection
        px = specimen.x if x is None else np.asarray(x)
        py = specimen.y if y is None else np.asarray(y)
        d = 2.0 * specimen.r
        ax.add_collection(EllipseCollection(d, d, 0.0, units="xy", offsets=np.c_[px, py],
                                            offset_transform=ax.transData, facecolors="0.9",
                                            edgecolors="0.7", linewidths=0.2))
    from ..hole_damage import holes_in_meta  # holes cut after the grains were drawn
    for cx, cy, rad in holes_in_meta(specimen.meta):
        ax.add_patch(plt.Circle((cx, cy), rad, facecolor="white", edgecolor="k", lw=0.6))
    if cracks is not None and len(cracks):
        key = np.char.add(np.char.add(np.asarray(cracks["kind"]).astype(str), "_"),
                          np.asarray(cracks["mode"]).astype(str))
        cx, cy = np.asarray(cracks["x"], float), np.asarray(cracks["y"], float)
        if "nx" in cracks and "ny" in cracks:
            nx, ny = np.asarray(cracks["nx"], float), np.asarray(cracks["ny"], float)
        elif "angle_deg" in cracks:
            a = np.radians(np.asarray(cracks["angle_deg"], float))
            nx, ny = np.cos(a), np.sin(a)
        else:
            nx = ny = None
        has_normal = nx is not None
        for kind, colour in _KIND_COLOURS.items():
            sel = key == kind
            if not np.any(sel):
                continue
            if has_normal:
                h = 0.5 * np.asarray(cracks["size_m"], float)[sel]
                tx, ty = -ny[sel], nx[sel]
                seg = np.stack([np.c_[cx[sel] - h * tx, cy[sel] - h * ty],
                                np.c_[cx[sel] + h * tx, cy[sel] + h * ty]], axis=1)
                ax.add_collection(LineCollection(seg, colors=colour, linewidths=1.2))
                ax.plot([], [], "-", color=colour, label=f"{kind} ({int(sel.sum())})")
            else:
                ax.plot(cx[sel], cy[sel], ".", ms=3, color=colour,
                        label=f"{kind} ({int(sel.sum())})")
    b = specimen.box
    pad = 0.02 * (b[1] - b[0])
    ax.set_xlim(b[0] - pad, b[1] + pad)
    ax.set_ylim(b[2] - pad, b[3] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=6, loc="upper right", framealpha=0.8)
    fig.tight_layout()
    return _save_figure(fig, path)
