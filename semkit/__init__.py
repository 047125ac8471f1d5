"""semkit: SEM micro-crack and grain statistics for rock mechanics.

The public API is a flat index of functions (scikit-image style); each name is imported from its
module on first use (PEP 562), so importing this package does no work (no numba compilation, no
matplotlib, no OpenCV).

Stages (DESIGN.md §5): :func:`load_image` (1) -> :func:`flatten_illumination` (2) ->
:func:`crack_mask` (3) -> :func:`remove_specks` / :func:`fill_holes` (4) -> :func:`label_cracks`,
:func:`crack_table` (5) -> :func:`skeletonize`, :func:`skeleton_length` (6); all together in
:func:`analyse_image` (one :class:`CrackAnalysis` object) and :func:`analyse_folder` (the
folder loop, :mod:`semkit.workflow`). Synthetic images with ground truth:
:func:`make_sem_image`.
"""
from .errors import InputError

_LAZY = {
    # stage 1: io
    "load_image": "io", "read_image": "io", "resolve_pixel_size": "io",
    "tiff_pixel_size": "io", "magnification_pixel_size": "io", "read_manifest": "io",
    # stage 2
    "flatten_illumination": "illumination", "illumination_field": "illumination",
    # stage 3
    "crack_mask": "threshold", "threshold_otsu": "threshold", "threshold_local": "threshold",
    "threshold_auto": "threshold", "dark_class_levels": "threshold",
    # stage 4
    "denoise": "cleanup", "despeckle_median": "cleanup", "remove_specks": "cleanup",
    "remove_small_objects": "cleanup", "fill_holes": "cleanup", "bridge_gaps": "cleanup",
    # stages 5-6
    "label_cracks": "measure", "crack_table": "measure", "partial_volume_area": "measure",
    "skeletonize": "skeleton", "prune_spurs": "skeleton", "skeleton_length": "skeleton",
    "tip_extension": "skeleton",
    # the analysis object, the folder loop, figures, synthetic data
    "analyse_image": "analysis", "CrackAnalysis": "analysis", "AnalysisOptions": "options",
    "analyse_folder": "workflow", "analyse_grains_folder": "workflow",
    "train_from_folder": "workflow", "overlay_cracks": "plot", "plot_histograms": "plot",
    "make_sem_image": "synth", "SynthImage": "synth", "write_sample_set": "synth",
    # grains, crack types, indices, damage ratio
    "mineral_phases": "grains", "segment_grains": "grains", "grain_table": "grains",
    "grain_size_table": "grains", "slenderness": "grains", "grains_stage": "grains",
    "plot_grain_histograms": "grains", "plot_grain_map": "grains",
    "classify_pre": "classify", "classify_post": "classify", "crack_morphology": "classify",
    "classify_stage": "classify", "train_post": "classify", "save_model": "classify",
    "load_model": "classify", "apply_labels": "classify", "read_labels": "classify",
    "damage_ratio": "indices", "heterogeneity_index": "indices", "mhi": "indices",
    "indices_from_table": "indices", "split_range": "indices", "table_with_ranges": "indices",
    "image_damage": "damage", "damage_table": "damage", "flag_outliers": "damage",
    "typed_areas": "damage", "plot_p_by_stage": "damage",
    # trainable crack segmenter
    "train_segmenter": "segmenter", "Segmenter": "segmenter", "labels_from_mask": "segmenter",
    "load_segmenter": "segmenter_file", "save_segmenter": "segmenter_file",
}

__all__ = ["InputError", *_LAZY]


def __getattr__(name):
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module 'semkit' has no attribute {name!r}")
    import importlib
    value = getattr(importlib.import_module(f".{mod}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
