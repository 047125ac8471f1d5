"""PNG preview of a specimen: grains coloured by mineral, boundaries, optional particles/joints."""
from __future__ import annotations

import os

import numpy as np

__all__ = ["plot_specimen"]

_COLOURS = ["#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3", "#937860", "#da8bc3"]


def plot_specimen(spec, path, *, particles=False, joints=False, dpi=150):
    """Draw a specimen to ``path`` (PNG).

    Parameters
    ----------
    spec : sim.Specimen
    path : str or path-like
    particles : bool
        Also draw the particles (outlines).
    joints : bool
        Also draw the smooth-joint bonds (short lines across the boundaries).
    dpi : int

    Returns
    -------
    path : str
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import EllipseCollection, LineCollection, PolyCollection
    from matplotlib.patches import Patch

    box = spec.box * 1e3
    w, h = box[1] - box[0], box[3] - box[2]
    fig, ax = plt.subplots(figsize=(6.0 * w / max(w, h) + 1.5, 6.0 * h / max(w, h) + 0.5))
    names = [str(s) for s in spec.mineral_names]
    if spec.n_grains:
        polys = [spec.grain_polygon(g) * 1e3 for g in range(spec.n_grains)]
        cols = [_COLOURS[int(m) % len(_COLOURS)] for m in spec.grain_mineral]
        ax.add_collection(PolyCollection(polys, facecolors=cols, edgecolors="k",
                                         linewidths=0.3, alpha=0.85))
    if particles or spec.n_grains == 0:
        d = 2e3 * spec.r
        cols = [_COLOURS[int(m) % len(_COLOURS)] for m in spec.mineral]
        ax.add_collection(EllipseCollection(d, d, np.zeros_like(d), units="x",
                                            offsets=np.c_[spec.x, spec.y] * 1e3,
                                            transOffset=ax.transData,
                                            facecolors="none" if spec.n_grains else cols,
                                            edgecolors="k", linewidths=0.2))
    if joints and spec.n_bonds:
        sj = spec.bond_kind == 1
        i, j = spec.bond_i[sj], spec.bond_j[sj]
        seg = np.stack([np.c_[spec.x[i], spec.y[i]], np.c_[spec.x[j], spec.y[j]]], axis=1) * 1e3
        ax.add_collection(LineCollection(seg, colors="r", linewidths=0.4))
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(handles=[Patch(color=_COLOURS[k % len(_COLOURS)], label=n)
                       for k, n in enumerate(names)], loc="upper left",
              bbox_to_anchor=(1.01, 1.0), fontsize=8)
    meta = spec.meta or {}
    ax.set_title(f"{meta.get('tessellation', '')} scenario {meta.get('scenario', '-')} "
                 f"seed {meta.get('seed', '-')}: {spec.n_grains} grains, "
                 f"{spec.n_particles} particles", fontsize=8)
    path = os.fspath(path)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return path
