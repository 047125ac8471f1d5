"""Post-test crack typing (tensile / shear / mixed) that says when it does not know.

Every crack group (a crack with the small fragments and debris near it,
:func:`semkit.classify.morphology.crack_groups`) is described by its morphology
(:mod:`semkit.classify.morphology`) and typed by the calibrated model
(:mod:`semkit.classify.model`). A group whose features lie outside the range the model was
trained on, or whose skeleton is too short to read, keeps the model's most probable type but
is marked ``type_post_ok = False`` with a note naming the reason, and the image's P is then
flagged (:func:`semkit.damage.image_damage`). A group longer than any trained crack (a network
of many cracks) is typed in pieces of :data:`PIECE_PX` px instead, its objects taking their
pieces' type shares (``frac_*``).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import InputError
from .model import (
    DEFAULT_POST_MODEL,
    STAGE2_NAMES,
    TYPES,
    group_design,
    out_of_range,
    type_probabilities,
)
from .morphology import FEATURE_NAMES, crack_morphology, group_features

__all__ = ["classify_post", "MIN_SKELETON_PX", "PIECE_PX", "POST_COLUMNS"]

#: groups with a shorter skeleton (px) are typed but not trusted (type_post_ok = False).
MIN_SKELETON_PX = 8
#: a group longer than any crack the model was trained on (a network joining many cracks,
#: common on large dense images) is typed in pieces: its objects are cut by a grid of squares
#: of this side (px) and each piece typed on its own. On the 20 post-test images of
#: ``benchmarks/sem_pipeline.py`` (``semkit.synth``, 1024 x 768 and 2048 x 1536, where the
#: networks reach 1 000-30 000 px against the trained 720) the median P error was 772 % typed
#: whole, 265 / 135 / 35 / 12 / 28 % in pieces of 256 / 192 / 128 / 96 / 64 px.
PIECE_PX = 96
#: ... and such an object is trusted unless pieces holding more than this share of its pixels
#: are untrusted themselves.
PIECE_UNTRUSTED_MAX = 0.2
#: columns of the table of :func:`classify_post`, after ``crack_id``.
POST_COLUMNS = ("type_post", "confidence", "p_tensile", "p_shear", "p_mixed", "type_post_ok",
                "type_note", "frac_tensile", "frac_shear", "frac_mixed", "tensile_fraction",
                "type_shift_sd", "group_id", "p_mean", *FEATURE_NAMES)


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
        otherwise, or, for an object of a group typed in pieces (longer than the trained
        range), its pixel shares of the pieces' types, with ``type_post`` the largest and the
        probabilities the pieces' pixel-weighted mean; ``tensile_fraction`` = p_tensile /
        (p_tensile + p_shear) (how a mixed crack splits with
        ``image_damage(mixed="split")``); ``type_shift_sd`` the model's ``image_shift_sd``
        (the spread of an image's common tensile-versus-shear lean, which widens the P band;
        0 when the model has none); the features are the group's.
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
    note_obj = notes[at].astype(object)
    j = FEATURE_NAMES.index("log_length")
    hi = float(np.asarray(model["range_hi"])[STAGE2_NAMES.index("log_length")])
    long_groups = groups[measured & (Fg[:, j] > hi)]
    if long_groups.size:  # networks longer than any trained crack: typed piece by piece
        pg, onehot, ok, note_obj = _type_by_pieces(lab, ids, group_of, long_groups, local, pg,
                                                   onehot, ok, note_obj, model=model)
        kg = onehot.argmax(axis=1)
        code[ids] = kg + 1
    cols = {
        "crack_id": ids.astype(int), "type_post": np.array(TYPES)[kg],
        "confidence": pg[np.arange(len(ids)), kg], "p_tensile": pg[:, 0], "p_shear": pg[:, 1],
        "p_mixed": pg[:, 2], "type_post_ok": ok, "type_note": note_obj.astype(str),
        "frac_tensile": onehot[:, 0], "frac_shear": onehot[:, 1], "frac_mixed": onehot[:, 2],
        "tensile_fraction": pg[:, 0] / np.maximum(pg[:, 0] + pg[:, 1], 1e-12),
        "type_shift_sd": np.full(len(ids), float(model.get("image_shift_sd", 0.0))),
        "group_id": group_of[ids].astype(int), "p_mean": D[at, len(FEATURE_NAMES)]}
    cols.update({name: Fg[at, j] for j, name in enumerate(FEATURE_NAMES)})
    return pd.DataFrame(cols), code


def _type_by_pieces(lab, ids, group_of, long_groups, local, pg, onehot, ok, notes, *, model,
                    tile=PIECE_PX):
    """Re-type the objects of ``long_groups`` piece by piece (see :data:`PIECE_PX`).

    A piece is the part of a group inside one ``tile``-px square of a grid; its features are
    those of a group made of its skeleton and mask pixels (the local measures of the whole
    analysis, :func:`semkit.classify.morphology.group_features`). An object takes the
    pixel-weighted mean of its pieces' probabilities, their types' pixel shares as ``frac_*``,
    and ``type_post_ok`` unless pieces holding more than :data:`PIECE_UNTRUSTED_MAX` of its
    pixels are untrusted themselves.

    Returns
    -------
    pg, onehot, ok, notes : ndarray
        Copies of the inputs (rows of ``ids``) with the rows of the re-typed objects replaced.
    """
    h, w = lab.shape
    ntx = (w + tile - 1) // tile
    nt = ((h + tile - 1) // tile) * ntx
    lab_at = lab.ravel()[local["at"]]
    sel_m = np.isin(group_of[lab_at], long_groups)
    r_m, c_m = np.divmod(local["at"][sel_m], w)
    key_m = group_of[lab_at[sel_m]] * nt + (r_m // tile) * ntx + c_m // tile
    sel_s = np.isin(local["group"], long_groups)
    key_s = local["group"][sel_s] * nt + (local["rr"][sel_s] // tile) * ntx \
        + local["cc"][sel_s] // tile
    uk = np.unique(key_m)            # skeleton pixels are mask pixels: every key is in uk
    m = len(uk)
    piece_m = np.searchsorted(uk, key_m)
    piece_s = np.searchsorted(uk, key_s)
    obj_piece, n_px = np.unique(lab_at[sel_m].astype(np.int64) * m + piece_m, return_counts=True)
    obj, piece = np.divmod(obj_piece, m)
    dark = local["dark"]
    F = group_features(m, piece_s, local["aperture"][sel_s], local["end"][sel_s],
                       local["X"][sel_s], np.bincount(piece, minlength=m), piece_m,
                       None if dark is None else dark[sel_m])
    D = group_design(F, dict(X=local["X"][sel_s], group=piece_s), model)
    measured = np.isfinite(F[:, 0])
    P = np.full((m, 3), 1.0 / 3)
    P[measured] = type_probabilities(D[measured], model)
    note = np.full(m, "piece without skeleton", dtype=object)
    note[measured] = out_of_range(D[measured], model)
    kind = P.argmax(axis=1)
    bad = note != ""
    u, rows = np.unique(np.searchsorted(ids, obj), return_inverse=True)
    wgt = n_px / np.bincount(rows, weights=n_px)[rows]
    pg, onehot, ok, notes = pg.copy(), onehot.copy(), ok.copy(), notes.copy()
    for k in range(3):
        pg[u, k] = np.bincount(rows, weights=wgt * P[piece, k], minlength=len(u))
        onehot[u, k] = np.bincount(rows, weights=wgt * (kind[piece] == k), minlength=len(u))
    share = np.bincount(rows, weights=wgt * bad[piece], minlength=len(u))
    ok[u] = share <= PIECE_UNTRUSTED_MAX
    notes[u] = ""
    for i in np.flatnonzero(~ok[u]):  # the reason of the object's largest untrusted piece
        q = np.flatnonzero((rows == i) & bad[piece])
        worst = note[piece[q[np.argmax(wgt[q])]]]
        notes[u[i]] = f"typed in {tile}-px pieces, {share[i]:.0%} of it untrusted ({worst})"
    return pg, onehot, ok, notes
