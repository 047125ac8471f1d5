"""The classification stage of the analysis: types, confidences, features and
partial-volume areas added to one image's ``cracks.csv`` rows."""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..damage_areas import typed_areas
from .post import POST_COLUMNS, _post_table
from .pre import classify_pre

__all__ = ["classify_stage"]


def classify_stage(cracks, crack_labels, *, grey=None, pixel_size_um=1.0, model=None,
                   post=True, grain_labels=None, skeleton=None, background=None,
                   crack_level=None, void_level=None):
    """Add crack types, confidences, features and partial-volume areas to ``cracks.csv`` rows.

    Parameters
    ----------
    cracks : pandas.DataFrame
        Rows of one image (``crack_id`` matches ``crack_labels``).
    crack_labels : (M, N) ndarray of int
    grey : (M, N) ndarray, optional
        Flattened, denoised grey image: gives ``area_pv_um2`` (partial-volume area), which
        :func:`semkit.damage.image_damage` uses for A_T and A_S.
    pixel_size_um : float
    model : dict, optional
        Post-test model (default :data:`DEFAULT_POST_MODEL`).
    post : bool
        Classify tensile/shear/mixed (False for pre-test images: ``type_post`` "unknown").
    grain_labels : (M, N) ndarray of int, optional
        Grain map: classify inter/intra/trans (``type_pre``).
    skeleton, background, crack_level : optional
        The analysis's skeleton and threshold background / crack-core grey (re-estimated
        when not given); the typing features read ``crack_level``.
    void_level : float, optional
        Void grey the partial-volume areas are measured against
        (``ThresholdResult.void_level``); default ``crack_level``.

    Returns
    -------
    cracks : pandas.DataFrame
        Copy with ``type_pre, type_post, confidence`` (post-test confidence, or the pre-existing
        one when only that was classified), ``confidence_pre``, the post-test columns of
        :func:`semkit.classify.classify_post` (probabilities, ``type_post_ok``, ``type_note``,
        ``frac_*``, the morphology) and ``area_pv_um2``.
    """
    out = cracks.copy()
    lab = np.asarray(crack_labels)
    ids = out["crack_id"].to_numpy() if len(out) else np.zeros(0, int)
    if grey is not None and len(out):
        core = void_level if void_level is not None else crack_level
        ok_level = core is not None and np.isfinite(core)
        a = typed_areas(grey, lab, background=background if ok_level else None,
                        core=core if ok_level else None).set_index("crack_id")
        out["area_pv_um2"] = a["area_pv_px"].reindex(ids).to_numpy() * pixel_size_um ** 2
    if grain_labels is not None and len(out):
        t, _ = classify_pre(lab, grain_labels)
        t = t.set_index("crack_id").reindex(ids)
        out["type_pre"] = t["type_pre"].fillna("unknown").to_numpy()
        out["confidence_pre"] = t["confidence"].to_numpy()
        out["confidence"] = out["confidence_pre"]
    if post and len(out):
        t, _ = _post_table(lab, image=grey, skeleton=skeleton, background=background,
                           crack_level=crack_level, model=model)
        t = t.set_index("crack_id").reindex(ids)
        new = {c: t[c].to_numpy() for c in POST_COLUMNS}
        new["type_post"] = t["type_post"].fillna("unknown").to_numpy()
        for c in [c for c in new if c in out.columns]:   # keep their place
            out[c] = new.pop(c)
        out = pd.concat([out, pd.DataFrame(new, index=out.index)], axis=1)
    elif len(out):
        out["type_post"] = "unknown"
    return out
