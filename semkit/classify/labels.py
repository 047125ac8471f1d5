"""User crack labels: read ``labels.csv`` and let its types override the classified ones."""
from __future__ import annotations

import pandas as pd

from ..errors import InputError

__all__ = ["read_labels", "apply_labels"]


def read_labels(path):
    """Read user crack labels ``image, crack_id, type`` (CSV); checks columns and types."""
    try:
        df = pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot read labels ({exc})") from None
    miss = [c for c in ("image", "crack_id", "type") if c not in df.columns]
    if miss:
        raise InputError(f"{path}: missing column(s) {miss}; expected image, crack_id, type")
    bad = sorted(set(df["type"].astype(str)) - {"tensile", "shear", "mixed", "inter", "intra",
                                                 "trans"})
    if bad:
        raise InputError(f"{path}: column 'type' has {bad}; expected tensile|shear|mixed or "
                         f"inter|intra|trans")
    return df


def apply_labels(cracks, labels):
    """Override classified types with user labels (user labels win, confidence 1).

    Parameters
    ----------
    cracks : pandas.DataFrame
        ``cracks.csv`` rows with ``image, crack_id`` and ``type_post``/``type_pre``.
    labels : pandas.DataFrame
        ``image, crack_id, type``; a post-test type overrides ``type_post``, a pre-existing one
        ``type_pre``.

    Returns
    -------
    cracks : pandas.DataFrame
        Copy with overridden types, ``confidence`` 1 and ``type_source`` "user" on those rows
        (``model`` elsewhere). The fractions and probabilities of an overridden post type are
        set to it, and it is trusted (``type_post_ok``).
    """
    out = cracks.copy()
    if "type_source" not in out.columns:
        out["type_source"] = "model"
    key = out["image"].astype(str) + "\x00" + out["crack_id"].astype(int).astype(str)
    lk = labels["image"].astype(str) + "\x00" + labels["crack_id"].astype(int).astype(str)
    lab = dict(zip(lk, labels["type"].astype(str)))
    for i, k in zip(out.index, key):
        t = lab.get(k)
        if t is None:
            continue
        col = "type_post" if t in ("tensile", "shear", "mixed") else "type_pre"
        out.loc[i, col] = t
        out.loc[i, "confidence"] = 1.0
        out.loc[i, "type_source"] = "user"
        if col == "type_post":
            for name, f, p in (("tensile", "frac_tensile", "p_tensile"),
                               ("shear", "frac_shear", "p_shear"),
                               ("mixed", "frac_mixed", "p_mixed")):
                for c in (f, p):
                    if c in out.columns:
                        out.loc[i, c] = 1.0 if t == name else 0.0
            if "type_post_ok" in out.columns:
                out.loc[i, "type_post_ok"] = True
                out.loc[i, "type_note"] = ""
    return out
