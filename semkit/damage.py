"""Damage ratio P per image and per specimen x test x stage (``damage.csv``), with outlier flags.

P = A_T / A_S (thesis Equ. 3-1, :func:`semkit.indices.damage_ratio`). Per image, A_T and A_S
are the summed areas of the cracks typed ``tensile`` and ``shear`` in ``cracks.csv``; a
``mixed`` crack is split by its measured tensile share (column ``tensile_fraction``) when
present, otherwise it is left out of both sums (``mixed="exclude"``, the default).

Outlier rule (documented, not tuned per data set): within one test (all specimens and stages
of, e.g., ``triaxial``), an image's P is flagged when its modified z-score
``0.6745 |P - median| / MAD`` exceeds :data:`OUTLIER_Z` = 3.5 (Iglewicz & Hoaglin 1993). At
least :data:`OUTLIER_MIN_N` finite values are needed, otherwise nothing is flagged. Flagged
images stay in ``images.csv`` and in ``P_mean_all``; ``P_mean`` and ``P_pooled`` leave them out.
On thesis Table 3-3 this flags exactly the triaxial 6.05.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from . import config
from .damage_areas import darkness_fraction, typed_areas
from .errors import InputError
from .indices import damage_ratio

__all__ = ["p_status", "image_damage", "typed_areas", "darkness_fraction", "flag_outliers",
           "damage_table", "p_band", "band_text", "plot_p_by_stage", "STAGE_ORDER", "OUTLIER_Z",
           "OUTLIER_MIN_N"]

#: Order of the loading stages on the P-by-stage plot and in ``damage.csv``.
STAGE_ORDER = config.STAGE_ORDER
#: Modified z-score above which an image's P is flagged as an outlier.
OUTLIER_Z = config.OUTLIER_Z
#: Fewest finite P values in a test for the outlier rule to apply.
OUTLIER_MIN_N = config.OUTLIER_MIN_N
#: ``mixed`` crack handling in A_T / A_S.
MIXED_MODES = ("exclude", "split", "tensile", "shear")


def p_status(area_tensile, area_shear):
    """Why P is or is not defined for each image.

    Parameters
    ----------
    area_tensile, area_shear : array_like of float
        A_T and A_S (same unit), >= 0.

    Returns
    -------
    status : ndarray of str
        ``"ok"`` (A_S > 0), ``"no_shear"`` (A_S = 0 < A_T: P undefined, reported as NaN, not
        inf) or ``"no_cracks"`` (A_T = A_S = 0).

    Examples
    --------
    >>> p_status([1.0, 2.0, 0.0], [1.0, 0.0, 0.0]).tolist()
    ['ok', 'no_shear', 'no_cracks']
    """
    a_t, a_s = np.broadcast_arrays(np.asarray(area_tensile, float),
                                   np.asarray(area_shear, float))
    out = np.where(a_s > 0, "ok", np.where(a_t > 0, "no_shear", "no_cracks"))
    return out.astype(object).astype(str)


def image_damage(cracks, *, mixed="exclude", area_column=None):
    """Per-image A_T, A_S, P and status from a ``cracks.csv`` table.

    Parameters
    ----------
    cracks : pandas.DataFrame
        Columns ``image, area_um2, type_post`` (optional ``tensile_fraction`` in [0, 1]).
        When ``frac_tensile, frac_shear, frac_mixed`` are present (per-pixel typing by
        :func:`semkit.classify.classify_post`), each crack's area is split by them.
    mixed : {"exclude", "split", "tensile", "shear"}
        How a mixed crack's area counts (module docstring). ``split`` uses
        ``tensile_fraction`` (0.5 where it is missing).
    area_column : str, optional
        Area column to use; default ``area_pv_um2`` (partial-volume area, unbiased for thin
        cracks) when present, else ``area_um2``.

    Returns
    -------
    table : pandas.DataFrame
        One row per image: ``image, area_T_um2, area_S_um2, area_mixed_um2, P, P_status``;
        with the typing's probabilities (``p_tensile, p_shear, p_mixed``) also ``P_low,
        P_high, P_note`` and ``P_status = low_confidence`` when the typing cannot support P
        (:mod:`semkit.damage_confidence`).

    Raises
    ------
    InputError
        Missing columns or unknown ``mixed``.

    Notes
    -----
    P = A_T / A_S (Equ. 3-1); NaN with ``P_status`` ``no_shear``/``no_cracks`` when A_S = 0.
    """
    for col in ("image", "area_um2", "type_post"):
        if col not in cracks.columns:
            raise InputError(f"cracks table: missing column {col!r}")
    if mixed not in MIXED_MODES:
        raise InputError(f"mixed: expected one of {MIXED_MODES}, got {mixed!r}")
    c = cracks
    if area_column is None:
        area_column = "area_pv_um2" if "area_pv_um2" in c.columns else "area_um2"
    if area_column not in c.columns:
        raise InputError(f"cracks table: missing column {area_column!r}")
    area = np.nan_to_num(c[area_column].to_numpy(float))
    kind = c["type_post"].astype(str).to_numpy()
    if "tensile_fraction" in c.columns:
        ft = np.nan_to_num(c["tensile_fraction"].to_numpy(float), nan=0.5)
    else:
        ft = np.full(len(c), 0.5)
    ft_mixed = {"exclude": 0.0, "tensile": 1.0, "shear": 0.0}
    if {"frac_tensile", "frac_shear", "frac_mixed"} <= set(c.columns):
        # per-pixel typing (classify_post): an object may hold a tensile and a shear crack
        f_t, f_s, f_m = (np.nan_to_num(c[k].to_numpy(float))
                         for k in ("frac_tensile", "frac_shear", "frac_mixed"))
    else:
        f_t = (kind == "tensile").astype(float)
        f_s = (kind == "shear").astype(float)
        f_m = (kind == "mixed").astype(float)
    is_m = f_m > 0
    a_t = area * f_t
    a_s = area * f_s
    area = area * f_m  # the mixed part below
    if mixed == "split":
        a_t = a_t + np.where(is_m, area * ft, 0.0)
        a_s = a_s + np.where(is_m, area * (1.0 - ft), 0.0)
    elif mixed != "exclude":
        a_t = a_t + np.where(is_m, area * ft_mixed[mixed], 0.0)
        a_s = a_s + np.where(is_m, area * (1.0 - ft_mixed[mixed]), 0.0)
    df = pd.DataFrame({"image": c["image"].to_numpy(), "area_T_um2": a_t, "area_S_um2": a_s,
                       "area_mixed_um2": area})
    out = df.groupby("image", sort=False, as_index=False).sum()
    out["P"] = damage_ratio(out["area_T_um2"].to_numpy(), out["area_S_um2"].to_numpy())
    out["P_status"] = p_status(out["area_T_um2"], out["area_S_um2"])
    if {"p_tensile", "p_shear", "p_mixed"} <= set(c.columns):
        _confidence(out, c, np.nan_to_num(c[area_column].to_numpy(float)), mixed)
    return out


def _typing_inputs(c, area):
    """Per-crack inputs of :mod:`semkit.damage_confidence` from a typed cracks table: areas,
    probabilities (one-hot for user labels, which are certain), trust, group, note, tensile
    share and the typing model's lean spread."""
    prob = c[["p_tensile", "p_shear", "p_mixed"]].to_numpy(float, copy=True)
    trusted = c["type_post_ok"].fillna(True).astype(bool).to_numpy() \
        if "type_post_ok" in c.columns else np.ones(len(c), bool)
    if "type_source" in c.columns:  # user labels are certain
        user = (c["type_source"] == "user").to_numpy()
        kinds = c["type_post"].astype(str).to_numpy()
        for j, k in enumerate(("tensile", "shear", "mixed")):
            prob[user, j] = (kinds[user] == k).astype(float)
        trusted = trusted | user
    n = len(c)
    return dict(
        area=area, prob=prob, trusted=trusted,
        group=c["group_id"].to_numpy() if "group_id" in c else None,
        notes=c["type_note"].astype(str).to_numpy() if "type_note" in c else None,
        tensile_fraction=c["tensile_fraction"].to_numpy() if "tensile_fraction" in c
        else None,
        shift_sd=np.nan_to_num(c["type_shift_sd"].to_numpy(float)) if "type_shift_sd" in c
        else np.zeros(n))


def _select(inputs, sel):
    return {k: (v[sel] if v is not None else None) for k, v in inputs.items()}


def _confidence(out, c, area, mixed):
    """P_low, P_high, P_note and the low_confidence status (semkit.damage_confidence)."""
    from .damage_confidence import p_confidence
    inputs = _typing_inputs(c, area)
    cols = {k: [] for k in ("P_low", "P_high", "P_note")}
    for img in out["image"]:
        x = _select(inputs, (c["image"] == img).to_numpy())
        sd = float(x.pop("shift_sd").max()) if len(x["area"]) else 0.0
        r = p_confidence(x.pop("area"), x.pop("prob"), mixed=mixed, shift_sd=sd, **x)
        cols["P_low"].append(r["P_low"])
        cols["P_high"].append(r["P_high"])
        cols["P_note"].append(r["note"])
    for k, v in cols.items():
        out[k] = v
    low = (out["P_status"] == "ok") & (out["P_note"] != "")
    out.loc[low, "P_status"] = "low_confidence"


def p_band(cracks, images, *, statistic="mean", mixed="exclude"):
    """The typing's 10-90 % band of the mean P (``statistic="mean"``, as ``P_mean``) or of the
    pooled sum A_T / sum A_S (``"pooled"``, as ``P_pooled``) of some images.

    Parameters
    ----------
    cracks : pandas.DataFrame
        A typed ``cracks.csv`` table (``image``, ``area_um2`` or ``area_pv_um2``, ``p_tensile,
        p_shear, p_mixed`` and the typing columns); rejected objects (``rejected_as``) and
        untyped rows are left out.
    images : sequence of str
        The images taken together.
    statistic, mixed : str
        As :func:`semkit.damage_confidence.stage_band`.

    Returns
    -------
    low, high : float
        NaN without typed cracks of these images.
    """
    return _bands(cracks, [list(images)], mixed, statistic)[0]


def band_text(low, high, digits=3):
    """``"low-high"`` of a P band to ``digits`` significant digits, ``"low-open"`` when its top
    is undefined (too many draws without shear), ``""`` without a band (None or NaN).

    Examples
    --------
    >>> band_text(1.0567, 58.9), band_text(2.1, float("nan")), band_text(None, None)
    ('1.06-58.9', '2.1-open', '')
    """
    def given(v):
        return v is not None and bool(np.isfinite(v))
    if not given(low):
        return ""
    return f"{low:.{digits}g}-" + (f"{high:.{digits}g}" if given(high) else "open")


def _bands(cracks, groups, mixed, statistic="mean"):
    """(low, high) of each list of images in ``groups`` (see :func:`p_band`)."""
    from .damage_confidence import stage_band
    nan = (float("nan"), float("nan"))
    if cracks is None or not {"image", "area_um2", "p_tensile", "p_shear", "p_mixed"} <= set(
            cracks.columns):
        return [nan] * len(groups)
    c = cracks
    if "rejected_as" in c.columns:
        c = c[c["rejected_as"].fillna("").astype(str) == ""]
    c = c[c[["p_tensile", "p_shear", "p_mixed"]].notna().all(axis=1)]
    col = "area_pv_um2" if "area_pv_um2" in c.columns else "area_um2"
    inputs = _typing_inputs(c, np.nan_to_num(c[col].to_numpy(float)))
    names = c["image"].astype(str).to_numpy()
    out = []
    for used in groups:
        ims = [_select(inputs, names == str(n)) for n in used]
        ims = [x for x in ims if len(x["area"])]
        if not ims:
            out.append(nan)
            continue
        sd = float(max(x["shift_sd"].max() for x in ims))
        out.append(stage_band(ims, mixed=mixed, shift_sd=sd, statistic=statistic))
    return out


def flag_outliers(values, *, z=OUTLIER_Z, min_n=OUTLIER_MIN_N):
    """Flag outliers by the modified z-score (median / MAD) rule.

    Parameters
    ----------
    values : (N,) array_like of float
        NaN entries are ignored (never flagged).
    z : float
        Threshold on ``0.6745 |v - median| / MAD``.
    min_n : int
        With fewer finite values nothing is flagged.

    Returns
    -------
    flags : (N,) ndarray of bool

    Notes
    -----
    Iglewicz & Hoaglin (1993). When MAD = 0 (over half the values equal), any value differing
    from the median is flagged.

    Examples
    --------
    >>> flag_outliers([0.66, 1.12, 0.81, 0.76, 1.67, 6.05, 1.09, 2.17]).tolist()
    [False, False, False, False, False, True, False, False]
    """
    v = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(v)
    flags = np.zeros(v.shape, dtype=bool)
    if ok.sum() < min_n:
        return flags
    med = np.median(v[ok])
    mad = np.median(np.abs(v[ok] - med))
    if mad == 0:
        flags[ok] = v[ok] != med
    else:
        flags[ok] = 0.6745 * np.abs(v[ok] - med) / mad > z
    return flags


def _stage_key(stage):
    s = str(stage)
    return (STAGE_ORDER.index(s), s) if s in STAGE_ORDER else (len(STAGE_ORDER), s)


def _stage_status(used, group, checked):
    """``(P_status, P_note, n_low_confidence)`` of a stage from the images in its P_mean
    (``used``) among all its images (``group``)."""
    if not len(used):
        why = ""
        if checked:
            counts = group["P_status"].astype(str).value_counts()
            why = " (images: " + ", ".join(f"{n} {k}" for k, n in counts.items()) + ")"
        return "no_p", f"no image of this stage gives a finite P{why}", 0
    if not checked:
        return "unchecked", "the images table has no P_status column", 0
    low = used.loc[used["P_status"].astype(str) == "low_confidence", "image"].astype(str)
    if not len(low):
        return "ok", "", 0
    names = ", ".join(low.iloc[:5]) + (", ..." if len(low) > 5 else "")
    return ("low_confidence",
            f"{len(low)} of the {len(used)} images in P_mean have a low_confidence P "
            f"(their P_note says why): {names}", int(len(low)))


def damage_table(images, manifest=None, *, z=OUTLIER_Z, min_n=OUTLIER_MIN_N, cracks=None,
                 mixed="exclude"):
    """Aggregate per-image P into ``damage.csv`` rows (specimen x test x stage).

    Parameters
    ----------
    images : pandas.DataFrame
        Per-image table with ``image`` and ``P``; optionally ``area_T_um2, area_S_um2`` (for
        the pooled ratio) and ``specimen, test, stage`` (else taken from ``manifest``).
    manifest : pandas.DataFrame, optional
        ``manifest.csv`` (``image, specimen, test, stage``), joined on ``image``.
    z, min_n : float, int
        Outlier rule (:func:`flag_outliers`), applied per ``test``.
    cracks : pandas.DataFrame, optional
        The typed ``cracks.csv`` table (``image``, areas, ``p_tensile, p_shear, p_mixed`` and
        the typing columns): gives each stage's ``P_mean_low, P_mean_high``.
    mixed : str
        As :func:`image_damage`, for the band.

    Returns
    -------
    images_flagged : pandas.DataFrame
        ``images`` with ``specimen, test, stage`` and a boolean ``P_outlier``.
    damage : pandas.DataFrame
        One row per (specimen, test, stage): ``n_images, n_no_shear, n_outliers,
        outlier_images, P_mean`` (mean of finite per-image P, outliers left out),
        ``P_mean_all`` (outliers kept), ``P_median, P_pooled`` (sum A_T / sum A_S over the
        non-outlier images, including those with A_S = 0; NaN without areas),
        ``area_T_um2, area_S_um2, n_low_confidence, P_status, P_note``, and ``P_mean_low,
        P_mean_high``: the 10-90 % band of ``P_mean`` from its images' typing
        (:func:`semkit.damage_confidence.stage_band`, one common lean per draw for the whole
        stage; NaN without ``cracks``).

    Notes
    -----
    A stage's P is only as sure as the images it averages. ``P_status`` is
    ``low_confidence`` when any image whose P enters ``P_mean`` (finite, not an outlier) has
    ``P_status`` ``low_confidence`` in ``images`` (``P_note`` names up to five of them, so
    their own ``P_note`` says why), ``no_p`` when no image gives a finite P, ``unchecked``
    when ``images`` has no ``P_status`` column, else ``ok``.

    Raises
    ------
    InputError
        Missing columns, or images absent from the manifest.
    """
    df = images.copy()
    if "image" not in df.columns or "P" not in df.columns:
        raise InputError("images table: expected columns 'image' and 'P'")
    keys = ("specimen", "test", "stage")
    if manifest is not None:
        miss = [k for k in ("image",) + keys if k not in manifest.columns]
        if miss:
            raise InputError(f"manifest.csv: missing column(s) {miss}")
        df = df.drop(columns=[k for k in keys if k in df.columns])
        df = df.merge(manifest[["image", *keys]], on="image", how="left")
    for k in keys:
        if k not in df.columns:
            raise InputError(f"images table: no {k!r} column and no manifest given")
    lost = df.loc[df[list(keys)].isna().any(axis=1), "image"].tolist()
    if lost:
        raise InputError(f"manifest.csv: no specimen/test/stage for image(s) {lost[:5]}")
    df["P"] = df["P"].astype(float)
    df["P_outlier"] = False
    for _, idx in df.groupby("test", sort=False).groups.items():
        df.loc[idx, "P_outlier"] = flag_outliers(df.loc[idx, "P"].to_numpy(), z=z, min_n=min_n)
    has_area = "area_T_um2" in df.columns and "area_S_um2" in df.columns
    rows, used = [], []
    for (spec, test, stage), g in df.groupby(list(keys), sort=False):
        keep = g[~g["P_outlier"]]
        p_keep = keep["P"].to_numpy()
        p_all = g["P"].to_numpy()
        a_t = keep["area_T_um2"].sum() if has_area else np.nan
        a_s = keep["area_S_um2"].sum() if has_area else np.nan
        fin = np.isfinite(p_keep)
        status, note, n_low = _stage_status(keep[fin], g, "P_status" in df.columns)
        rows.append(dict(
            specimen=spec, test=test, stage=stage, n_images=len(g),
            n_no_shear=int((~np.isfinite(p_all)).sum()),
            n_outliers=int(g["P_outlier"].sum()),
            outlier_images=";".join(map(str, g.loc[g["P_outlier"], "image"])),
            P_mean=float(p_keep[fin].mean()) if fin.any() else np.nan,
            P_mean_all=float(np.nanmean(p_all)) if np.isfinite(p_all).any() else np.nan,
            P_median=float(np.median(p_keep[fin])) if fin.any() else np.nan,
            P_pooled=float(damage_ratio(a_t, a_s)) if has_area else np.nan,
            area_T_um2=a_t, area_S_um2=a_s, n_low_confidence=n_low, P_status=status,
            P_note=note))
        used.append(keep.loc[fin, "image"].tolist())
    for r, (lo, hi) in zip(rows, _bands(cracks, used, mixed)):
        r.update(P_mean_low=lo, P_mean_high=hi)
    dmg = pd.DataFrame(rows)
    if len(dmg):
        order = sorted(range(len(dmg)), key=lambda i: (str(dmg.specimen[i]), str(dmg.test[i]),
                                                       _stage_key(dmg.stage[i])))
        dmg = dmg.iloc[order].reset_index(drop=True)
    return df, dmg


def plot_p_by_stage(damage, path=None, *, ax=None):
    """Plot P (mean per stage, outliers left out) by loading stage, one line per test; a
    stage whose ``P_status`` is ``low_confidence`` is drawn hollow, and its ``P_mean_low``..
    ``P_mean_high`` band, where given, as a light bar.

    Parameters
    ----------
    damage : pandas.DataFrame
        Output of :func:`damage_table`.
    path : str or Path, optional
        Write a PNG here (written to a temporary name, then renamed).
    ax : matplotlib Axes, optional

    Returns
    -------
    fig : matplotlib Figure
    """
    import os

    import matplotlib
    if ax is None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    fig = ax.figure if ax is not None else plt.figure(figsize=(5, 3.5))
    ax = ax if ax is not None else fig.add_subplot(111)
    any_low = any_band = False
    lines = list(damage.groupby(["specimen", "test"], sort=False))
    for n, ((spec, test), g) in enumerate(lines):
        g = g.iloc[sorted(range(len(g)), key=lambda i: _stage_key(g.stage.iloc[i]))]
        line, = ax.plot(g["stage"].astype(str), g["P_mean"], "o-", label=f"{test} ({spec})")
        if {"P_mean_low", "P_mean_high"} <= set(g.columns):
            lo, hi = g["P_mean_low"].to_numpy(float), g["P_mean_high"].to_numpy(float)
            ok = np.isfinite(lo) & np.isfinite(hi)
            if ok.any():  # the typing's 10-90 % band of P_mean, the lines side by side
                any_band = True
                pos = ax.xaxis.convert_units(g["stage"].astype(str).to_numpy()[ok])
                ax.vlines(np.asarray(pos, float) + 0.06 * (n - (len(lines) - 1) / 2), lo[ok],
                          hi[ok], color=line.get_color(), lw=3, alpha=0.35)
        if "P_status" in g.columns:
            low = (g["P_status"] == "low_confidence").to_numpy()
            if low.any():  # hollow markers over the stages whose P is low_confidence
                any_low = True
                ax.plot(g["stage"].astype(str)[low], g["P_mean"][low], "o", ms=9,
                        mfc="white", mec=line.get_color(), mew=1.5)
    if any_low:
        ax.plot([], [], "o", mfc="white", mec="0.3", label="low_confidence (hollow)")
    if any_band:
        ax.plot([], [], "-", color="0.3", lw=3, alpha=0.35, label="10-90 % band (typing)")
    ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("stage")
    ax.set_ylabel("P = A_T / A_S (Equ. 3-1)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    if path is not None:
        path = str(path)
        tmp = path + ".tmp.png"
        fig.savefig(tmp, dpi=120)
        os.replace(tmp, path)
    return fig
