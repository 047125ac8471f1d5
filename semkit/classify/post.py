"""Post-test crack typing (tensile / shear / mixed) that says when it does not know.

Every crack group (a crack with the small fragments and debris near it,
:func:`semkit.classify.morphology.crack_groups`) is described by its morphology
(:mod:`semkit.classify.morphology`) and typed by the calibrated model
(:mod:`semkit.classify.model`). A group whose features lie outside the range the model was
trained on, or whose skeleton is too short to read, keeps the model's most probable type but
is marked ``type_post_ok = False`` with a note naming the reason, and the image's P is then
flagged (:func:`semkit.damage.image_damage`).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import InputError
from .model import DEFAULT_POST_MODEL, TYPES, group_design, out_of_range, type_probabilities
from .morphology import FEATURE_NAMES, crack_morphology

__all__ = ["classify_post", "MIN_SKELETON_PX", "POST_COLUMNS"]

#: groups with a shorter skeleton (px) are typed but not trusted (type_post_ok = False).
MIN_SKELETON_PX = 8
#: columns of the table of :func:`classify_post`, after ``crack_id``.
POST_COLUMNS = ("type_post", "confidence", "p_tensile", "p_shear", "p_mixed", "type_post_ok",
                "type_note", "frac_tensile", "frac_shear", "frac_mixed", "tensile_fraction",
                "group_id", "p_mean", *FEATURE_NAMES)


def classify_post(crack_labels, *, image=None, skeleton=None, background=None,
                  crack_level=None, model=None):
    """Type post-test cracks tensile, shear or mixed, with calibrated probabilities.

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects 1..n.
    image : (M, N) ndarray, optional
        Flattened, denoised grey image (``CrackAnalysis.smooth``); without it the ``fill``
        feature is not measured (neutral in the model).
    skeleton : (M, N) ndarray of bool, optional
    background, crack_level : ndarray, float, optional
        The threshold stage's local background and crack-core grey.
    model : dict, optional
        A model from :func:`semkit.classify.train_post` / :func:`semkit.classify.load_model`;
        default the built-in one.

    Returns
    -------
    table : pandas.DataFrame
        One row per object: ``crack_id`` and :data:`POST_COLUMNS`. ``type_post`` is its
        group's most probable type and ``confidence`` that type's calibrated probability;
        ``p_tensile, p_shear, p_mixed`` all three; ``type_post_ok`` False (with
        ``type_note``) when the group's features lie outside the trained range or its
        skeleton is shorter than ``MIN_SKELETON_PX``. ``frac_*`` are 1 for the type and 0
        otherwise; ``tensile_fraction`` = p_tensile / (p_tensile + p_shear) (how a mixed
        crack splits with ``image_damage(mixed="split")``); the features are the group's.
    type_image : (M, N) ndarray of int8
        0 none, 1 tensile, 2 shear, 3 mixed.

    Examples
    --------
    >>> lab = np.zeros((40, 80), np.int32); lab[18:24, 5:75] = 1
    >>> t, img = classify_post(lab)
    >>> t.loc[0, "type_post"], bool(t.loc[0, "type_post_ok"])
    ('tensile', True)
    """
    table, code = _post_table(crack_labels, image=image, skeleton=skeleton,
                              background=background, crack_level=crack_level, model=model)
    lab = np.asarray(crack_labels)
    return table, code[lab] if len(table) else np.zeros(lab.shape, np.int8)


def _post_table(crack_labels, *, image=None, skeleton=None, background=None, crack_level=None,
                model=None):
    """:func:`classify_post`'s table, and the type code (int8) of every label instead of the
    type image (the classification stage needs no image)."""
    model = DEFAULT_POST_MODEL if model is None else model
    if model is None:
        raise InputError("crack model: no built-in model found; pass one from "
                         "`semkit classify --train`")
    lab = np.asarray(crack_labels)
    if lab.ndim != 2:
        raise InputError(f"crack_labels: expected a 2-D array, got shape {lab.shape}")
    area = None
    if lab.dtype in (np.int32, np.int64) and lab.size and lab.min() >= 0:
        from .._kernels import label_counts
        area = np.zeros(int(lab.max()) + 1, np.int64)
        label_counts(np.ascontiguousarray(lab), area)
        ids = np.flatnonzero(area[1:]) + 1
    else:
        ids = np.unique(lab[lab > 0])
    if ids.size == 0:
        return pd.DataFrame(columns=["crack_id", *POST_COLUMNS]), np.zeros(1, np.int8)
    group_of, F, local = crack_morphology(lab, image=image, skeleton=skeleton,
                                          background=background, crack_level=crack_level,
                                          area=area)
    groups = np.unique(group_of[ids])
    D = group_design(F, local, model)[groups]
    Fg = F[groups]
    measured = np.isfinite(Fg[:, 0])
    P = np.full((len(groups), 3), np.nan)
    P[measured] = type_probabilities(D[measured], model)
    notes = np.array([""] * len(groups), dtype=object)
    notes[measured] = out_of_range(D[measured], model)
    short = ~measured | (np.exp(np.nan_to_num(Fg[:, FEATURE_NAMES.index("log_length")]))
                         < MIN_SKELETON_PX)
    notes[short & (notes == "")] = f"skeleton shorter than {MIN_SKELETON_PX} px"
    P[~measured] = 1.0 / 3
    k = P.argmax(axis=1)
    at = np.searchsorted(groups, group_of[ids])
    kg = k[at]
    code = np.zeros(int(ids[-1]) + 1, np.int8)
    code[ids] = kg + 1
    pg = P[at]
    ok = notes[at] == ""
    onehot = np.eye(3)[kg]
    table = pd.DataFrame({
        "crack_id": ids.astype(int), "type_post": np.array(TYPES)[kg],
        "confidence": pg[np.arange(len(ids)), kg], "p_tensile": pg[:, 0], "p_shear": pg[:, 1],
        "p_mixed": pg[:, 2], "type_post_ok": ok, "type_note": notes[at].astype(str),
        "frac_tensile": onehot[:, 0], "frac_shear": onehot[:, 1], "frac_mixed": onehot[:, 2],
        "tensile_fraction": pg[:, 0] / np.maximum(pg[:, 0] + pg[:, 1], 1e-12),
        "group_id": group_of[ids].astype(int), "p_mean": D[at, len(FEATURE_NAMES)]})
    for j, name in enumerate(FEATURE_NAMES):
        table[name] = Fg[at, j]
    return table, code
