"""Figures: crack overlays (cv2, fast) and histograms (matplotlib, imported lazily)."""
from __future__ import annotations

import numpy as np

__all__ = ["TYPE_COLOURS", "overlay_cracks", "plot_histograms"]

#: RGB colour of each crack type in overlays.
TYPE_COLOURS = {"unknown": (255, 40, 40), "inter": (40, 200, 255), "intra": (255, 200, 0),
                "trans": (255, 40, 200), "tensile": (255, 40, 40), "shear": (40, 255, 80),
                "mixed": (255, 160, 0), "pore": (60, 90, 255), "rejected": (0, 220, 220),
                "region": (255, 255, 255)}


def _to_u8(image):
    a = np.asarray(image)
    if a.dtype == np.uint8:
        return a
    lo, hi = np.percentile(a, [0.1, 99.9])
    return np.clip((a.astype(np.float32) - lo) * (255.0 / max(hi - lo, 1e-9)), 0, 255).astype(
        np.uint8)


def overlay_cracks(image, labels, *, crack_types=None, pore_ids=(), rejected_ids=(),
                   region=None):
    """Outline crack objects on the grey image.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image (any dtype; stretched to 8 bits).
    labels : (M, N) ndarray of int32
        Object labels.
    crack_types : mapping label -> type name, optional
        Colours by :data:`TYPE_COLOURS`; default all ``unknown`` (red).
    pore_ids : sequence of int
        Labels drawn as pores (blue).
    rejected_ids : sequence of int
        Labels rejected as not cracks (:mod:`semkit.reject`), drawn in
        ``TYPE_COLOURS["rejected"]`` (cyan).
    region : (M, N) ndarray of bool, optional
        Sample region; its outline is drawn in ``TYPE_COLOURS["region"]`` (white).

    Returns
    -------
    rgb : (M, N, 3) ndarray of uint8
    """
    import cv2
    g = _to_u8(image)
    rgb = np.repeat(g[..., None], 3, axis=2)
    lab = np.asarray(labels, np.int32)
    m = (lab > 0).astype(np.uint8)
    edge = (m - cv2.erode(m, np.ones((3, 3), np.uint8))).astype(bool)
    n = int(lab.max())
    colour = np.zeros((n + 1, 3), np.uint8)
    colour[:] = TYPE_COLOURS["unknown"]
    if crack_types:
        for k, t in crack_types.items():
            colour[int(k)] = TYPE_COLOURS.get(t, TYPE_COLOURS["unknown"])
    for k in pore_ids:
        colour[int(k)] = TYPE_COLOURS["pore"]
    for k in rejected_ids:
        colour[int(k)] = TYPE_COLOURS["rejected"]
    rgb[edge] = colour[lab[edge]]
    if region is not None and not np.all(region):
        r = np.asarray(region, np.uint8)
        rgb[(r - cv2.erode(r, np.ones((3, 3), np.uint8))).astype(bool)] = TYPE_COLOURS["region"]
    return rgb


def plot_histograms(cracks, path, *, bins=30):
    """Histograms of crack length and mean aperture (µm) over a crack table; writes a PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.5))
    for a, col, lab in ((ax[0], "length_um", "crack length (µm)"),
                        (ax[1], "mean_aperture_um", "mean aperture (µm)")):
        v = np.asarray(cracks[col], float)
        v = v[np.isfinite(v)]
        if v.size:
            a.hist(v, bins=bins, color="0.3")
        a.set_xlabel(lab)
        a.set_ylabel("cracks")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
