"""Mineral phases, grain segmentation, per-grain shape and the grain-size table (``grains.csv``).

Pipeline (each step a function on arrays):

1. :func:`mineral_phases` — grey-level classes of the denoised, crack-masked image by
   multi-Otsu (default) or a 1-D Gaussian mixture; phase 1 is the brightest, names are given
   brightest-first (``--minerals pyroxene,plagioclase,biotite``).
2. :func:`segment_grains` — boundary-strength watershed: strength = grey gradient + dark-ridge
   response (faint boundaries between grains of one phase) + phase changes; markers are the
   h-maxima of the distance to the strong-boundary pixels.
3. :func:`grain_table` — per grain: area, equivalent diameter, aspect ratio, orientation,
   slenderness H/W (Equ. 5-2), mineral by majority vote of the phase map.
4. :func:`grain_size_table` — ``grains.csv`` (DESIGN.md §4): volume (area) fraction per mineral
   and fine/medium/coarse classes from user edges (``--classes 20,140``) or the automatic rule
   (10th and 90th count percentiles of the mineral's equivalent diameters).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .errors import InputError
from .grains_phases import (
    GMM_ITERATIONS,
    PHASE_MEDIAN_PX,
    PHASE_SIGMA_PX,
    mineral_phases,
    phase_separability,
)
from .grains_segment import (
    BOUNDARY_LEVEL,
    GRAIN_DENOISE_SIGMA_PX,
    MARKER_H_PX,
    RIDGE_SIGMA_PX,
    segment_grains,
)
from .grains_table import (
    AUTO_CLASS_PERCENTILES,
    _parse_classes,  # noqa: F401  (semkit.cli imports it from here)
    grain_size_table,
    grain_table,
    slenderness,
)

__all__ = ["mineral_phases", "phase_separability", "segment_grains", "grain_table",
           "grain_size_table", "slenderness", "plot_grain_histograms", "plot_grain_map",
           "grains_stage", "parse_minerals", "analyse_grains_folder", "AUTO_CLASS_PERCENTILES",
           "GRAIN_DENOISE_SIGMA_PX", "PHASE_MEDIAN_PX", "PHASE_SIGMA_PX", "RIDGE_SIGMA_PX",
           "MARKER_H_PX", "BOUNDARY_LEVEL", "GMM_ITERATIONS"]


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


def grains_stage(image, *, mask=None, pixel_size_um=1.0, names=None, n_phases=3,
                 min_diameter_um=None, seed=None, alt_image=None):
    """Phases, grains and the per-grain table of one image (the ``--grains`` stage).

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image (flattened if the lighting is uneven).
    mask : (M, N) ndarray of bool, optional
        Cracks and pores, excluded.
    pixel_size_um : float
    names : sequence of str, optional
        Mineral names brightest-first; their number sets the number of phases.
    n_phases : int
        Number of phases when ``names`` is not given.
    min_diameter_um : float, optional
        Smallest grain resolved; default 8 px.
    seed : int, optional
    alt_image : (M, N) ndarray, optional
        A second version of the image (e.g. raw when ``image`` is flattened); the one whose
        phases separate better (:func:`phase_separability`) is used.

    Returns
    -------
    grain_labels, phase_labels : (M, N) ndarray of int32
    grains : pandas.DataFrame
        :func:`grain_table` output.
    """
    n = len(names) if names else int(n_phases)
    if alt_image is not None and phase_separability(alt_image, n, mask=mask) > \
            phase_separability(image, n, mask=mask):
        image = alt_image
    ph, _ = mineral_phases(image, n, mask=mask, seed=seed)
    dmin = 8.0 if min_diameter_um is None else max(min_diameter_um / pixel_size_um, 2.0)
    lab = segment_grains(image, phase_labels=ph, mask=mask, min_diameter_px=dmin)
    return lab, ph, grain_table(lab, ph, pixel_size_um=pixel_size_um, names=names)


def parse_minerals(value):
    """``"pyroxene,plagioclase,biotite"`` -> names; ``"3"`` -> 3 unnamed phases."""
    if value is None:
        return None, 3
    v = str(value).strip()
    if v.isdigit():
        if int(v) < 2:
            raise InputError(f"--minerals: expected >= 2 phases, got {v}")
        return None, int(v)
    names = [s.strip() for s in v.split(",") if s.strip()]
    if len(names) < 2 or len(set(names)) != len(names):
        raise InputError(f"--minerals: expected >= 2 distinct names brightest-first, got {v!r}")
    return names, len(names)


def analyse_grains_folder(folder, out, *, minerals=None, classes=None, pixel_size_um=None,
                          progress=False, seed=None, **options):
    """``semkit grains DIR``: grain map, per-grain table and ``grains.csv`` for a folder.

    Writes ``grains_per_grain.csv`` (every grain of every image), ``grains.csv`` (the
    grain-size table over all images), ``grain_maps/<name>_grains.png`` and
    ``grain_histograms.png`` to ``out``.

    Parameters
    ----------
    folder, out : path
    minerals : str, optional
        ``--minerals`` value (names brightest-first, or a number of phases).
    classes : str, optional
        ``--classes`` value (``"20,140"``); default the automatic rule.
    pixel_size_um : float, optional
        Fallback pixel size.
    **options
        Crack-pipeline options (cracks are masked out before grains are measured).

    Returns
    -------
    table : pandas.DataFrame
        The grain-size table written to ``grains.csv``.
    """
    import pathlib

    from .io import list_images, load_image, read_manifest, write_csv_atomic
    from .pipeline import AnalysisOptions, CrackAnalysis
    folder, out = pathlib.Path(folder), pathlib.Path(out)
    names, n = parse_minerals(minerals)
    files = list_images(folder)
    if not files:
        raise InputError(f"{folder}: no image files found")
    man = read_manifest(folder)
    mrows = {} if man is None else {str(r["image"]): r for r in man.to_dict("records")}
    opts = AnalysisOptions(**options)
    (out / "grain_maps").mkdir(parents=True, exist_ok=True)
    tables = []
    it = files
    if progress:
        from tqdm import tqdm
        it = tqdm(files, unit="img", desc="semkit grains")
    for p in it:
        li = load_image(p, manifest_row=mrows.get(p.name), pixel_size_um=pixel_size_um)
        a = CrackAnalysis(li.image, pixel_size_um=li.pixel_size_um, name=p.name, options=opts)
        lab, ph, g = grains_stage(a.flat, mask=a.object_mask, pixel_size_um=li.pixel_size_um,
                                  names=names, n_phases=n, seed=seed, alt_image=a.image)
        g.insert(0, "image", p.name)
        tables.append(g)
        import matplotlib.pyplot as plt
        fig = plot_grain_map(lab, ph, out / "grain_maps" / f"{p.stem}_grains.png")
        plt.close(fig)
    allg = pd.concat(tables, ignore_index=True)
    table = grain_size_table(allg, classes=classes)
    write_csv_atomic(allg, out / "grains_per_grain.csv")
    write_csv_atomic(table, out / "grains.csv")
    import matplotlib.pyplot as plt
    plt.close(plot_grain_histograms(allg, out / "grain_histograms.png"))
    return table
