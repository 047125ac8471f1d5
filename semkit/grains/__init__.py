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
from .phases import (
           GMM_ITERATIONS,
           PHASE_MEDIAN_PX,
           PHASE_SIGMA_PX,
           mineral_phases,
           phase_separability,
)
from .plot import plot_grain_histograms, plot_grain_map
from .segment import (
           BOUNDARY_LEVEL,
           GRAIN_DENOISE_SIGMA_PX,
           MARKER_H_PX,
           RIDGE_SIGMA_PX,
           segment_grains,
)
from .stage import grains_stage, parse_minerals
from .table import AUTO_CLASS_PERCENTILES, grain_size_table, grain_table, parse_classes, slenderness

__all__ = ["mineral_phases", "phase_separability", "segment_grains", "grain_table",
           "grain_size_table", "slenderness", "plot_grain_histograms", "plot_grain_map",
           "grains_stage", "parse_minerals", "parse_classes", "AUTO_CLASS_PERCENTILES",
           "GRAIN_DENOISE_SIGMA_PX", "PHASE_MEDIAN_PX", "PHASE_SIGMA_PX", "RIDGE_SIGMA_PX",
           "MARKER_H_PX", "BOUNDARY_LEVEL", "GMM_ITERATIONS"]
