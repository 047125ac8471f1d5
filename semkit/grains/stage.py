"""The grain stage of the analysis: phases, grains and the per-grain table of one image."""
from __future__ import annotations

from ..errors import InputError
from .phases import mineral_phases, phase_separability
from .segment import segment_grains
from .table import grain_table

__all__ = ["grains_stage", "parse_minerals"]


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
