"""Figures of the grain stage: grain-size histograms per mineral and the segmented grain map."""
from __future__ import annotations

import numpy as np

__all__ = ["plot_grain_histograms", "plot_grain_map"]


def _save(fig, path):
    import os
    path = str(path)
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def plot_grain_histograms(grains, path=None, *, bins=20):
    """Grain-size histograms per mineral (thesis Fig. 4-4 form); returns the Figure."""
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    minerals = list(dict.fromkeys(grains["mineral"]))
    fig, axes = plt.subplots(1, max(len(minerals), 1), figsize=(3.2 * max(len(minerals), 1), 3),
                             squeeze=False)
    for ax, name in zip(axes[0], minerals):
        d = grains.loc[grains["mineral"] == name, "eq_diameter_um"]
        ax.hist(d, bins=bins, color="0.4")
        ax.set_title(str(name))
        ax.set_xlabel("equivalent diameter (um)")
    axes[0][0].set_ylabel("grains")
    fig.tight_layout()
    if path is not None:
        _save(fig, path)
    return fig


def plot_grain_map(grain_labels, phase_labels=None, path=None, *, seed=0):
    """Segmented grain map: grains in random colours, boundaries in black; returns the Figure."""
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from skimage.segmentation import find_boundaries
    lab = np.asarray(grain_labels)
    rng = np.random.default_rng(seed)
    colours = rng.uniform(0.3, 1.0, (lab.max() + 1, 3))
    colours[0] = 0
    if phase_labels is not None:
        base = np.array([[0, 0, 0], [0.9, 0.5, 0.3], [0.4, 0.7, 0.9], [0.6, 0.9, 0.5],
                         [0.9, 0.9, 0.4], [0.7, 0.5, 0.9]])
        ph = np.asarray(phase_labels) % len(base)
        rgb = base[ph] * (0.75 + 0.25 * colours[lab][..., :1])
    else:
        rgb = colours[lab]
    rgb[find_boundaries(lab)] = 0
    fig = plt.figure(figsize=(6, 6 * lab.shape[0] / max(lab.shape[1], 1)))
    ax = fig.add_axes([0, 0, 1, 1])
    ax.imshow(rgb, interpolation="nearest")
    ax.axis("off")
    if path is not None:
        _save(fig, path)
    return fig
