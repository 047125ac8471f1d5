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
from .errors import InputError
from .indices import damage_ratio

__all__ = ["p_status", "image_damage", "typed_areas", "darkness_fraction", "flag_outliers", "damage_table", "plot_p_by_stage",
           "STAGE_ORDER", "OUTLIER_Z", "OUTLIER_MIN_N"]

#: Order of the loading stages on the P-by-stage plot and in ``damage.csv``.
STAGE_ORDER = config.STAGE_ORDER
#: Modified z-score above which an image's P is flagged as an outlier.
OUTLIER_Z = config.OUTLIER_Z
#: Fewest finite P values in a test for the outlier rule to apply.
OUTLIER_MIN_N = config.OUTLIER_MIN_N
#: band (px) around the crack objects over which partial-volume darkness is summed.
PV_BAND_PX = config.PV_BAND_PX
#: Gaussian sigma (px) of the local-background estimate for the partial-volume area.
PV_BACKGROUND_SIGMA_PX = config.PV_BACKGROUND_SIGMA_PX
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
        One row per image: ``image, area_T_um2, area_S_um2, area_mixed_um2, P, P_status``.

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
    return out


def darkness_fraction(image, crack_labels, *, core=None, band_px=PV_BAND_PX,
                      background_sigma_px=PV_BACKGROUND_SIGMA_PX):
    """Partial-volume darkness of each pixel near the cracks (0 background .. 1 crack core).

    Parameters
    ----------
    image : (M, N) ndarray
    crack_labels : (M, N) ndarray of int
    core : float, optional
        Grey level of a fully dark crack pixel; default the 2nd percentile inside the objects.
    band_px, background_sigma_px : float
        See :func:`typed_areas`.

    Returns
    -------
    f : (M, N) ndarray of float64
        clip((B - I) / (B - I_core), 0, 1) within ``band_px`` of an object, else 0.
    nearest : tuple of two (M, N) ndarrays of int
        Row and column of the nearest object pixel (for ownership).
    """
    from scipy import ndimage as ndi
    img = np.asarray(image, dtype=np.float64)
    obj = np.asarray(crack_labels) > 0
    dist, (ir, ic) = ndi.distance_transform_edt(~obj, return_indices=True)
    region = dist <= band_px
    bg_mask = dist > band_px + 1
    num = ndi.gaussian_filter(np.where(bg_mask, img, 0.0), background_sigma_px)
    den = ndi.gaussian_filter(bg_mask.astype(np.float64), background_sigma_px)
    fill = np.median(img[bg_mask]) if bg_mask.any() else img.max()
    bg = np.where(den > 1e-3, num / np.maximum(den, 1e-3), fill)
    if core is None:
        core = float(np.percentile(img[obj], 2)) if obj.any() else float(img.min())
    f = np.clip((bg - img) / np.maximum(bg - float(core), 1e-6), 0.0, 1.0)
    f[~region] = 0.0
    return f, (ir, ic)


def typed_areas(image, crack_labels, type_image=None, *, core=None, band_px=PV_BAND_PX,
                background_sigma_px=PV_BACKGROUND_SIGMA_PX):
    """Partial-volume crack areas per object, split by post-test type.

    Thin cracks (1-2 px, typical of shear) lose about half their area to any pixel threshold
    once blurred; the partial-volume area sums each pixel's darkness fraction instead, which
    is unbiased for thin and wide cracks alike.

    Parameters
    ----------
    image : (M, N) ndarray
        Grey image, cracks dark (flattened if the lighting is uneven).
    crack_labels : (M, N) ndarray of int
        Crack objects 1..n.
    type_image : (M, N) ndarray of int, optional
        Type per pixel (1 tensile, 2 shear, 3 mixed; :func:`semkit.classify.classify_post`).
    core : float, optional
        Grey level of a fully dark crack pixel; default the 2nd percentile inside the objects.
    band_px : int
        Pixels within this distance of an object count (blur spreads darkness beyond it).
    background_sigma_px : float
        Scale of the local background (normalised convolution over non-crack pixels).

    Returns
    -------
    table : pandas.DataFrame
        ``crack_id, area_pv_px, area_T_px, area_S_px, area_M_px``.

    Notes
    -----
    f = clip((B - I) / (B - I_core), 0, 1) with B the local background; area = sum f over the
    object and its band (band pixels belong to the nearest object and take its pixel type).
    """
    img = np.asarray(image, dtype=np.float64)
    lab = np.asarray(crack_labels)
    if img.shape != lab.shape or img.ndim != 2:
        raise InputError(f"crack_labels: expected shape {img.shape}, got {lab.shape}")
    from scipy import ndimage as ndi
    n = int(lab.max())
    cols = ["crack_id", "area_pv_px", "area_T_px", "area_S_px", "area_M_px"]
    if n == 0:
        return pd.DataFrame(columns=cols)
    obj = lab > 0
    f, (ir, ic) = darkness_fraction(img, lab, core=core, band_px=band_px,
                                    background_sigma_px=background_sigma_px)
    owner = lab[ir, ic]
    types = np.zeros(lab.shape, np.int64) if type_image is None else \
        np.asarray(type_image).astype(np.int64)[ir, ic]
    out = {"crack_id": np.arange(1, n + 1),
           "area_pv_px": np.bincount(owner.ravel(), f.ravel(), minlength=n + 1)[1:]}
    for k, name in ((1, "area_T_px"), (2, "area_S_px"), (3, "area_M_px")):
        w = np.where(types == k, f, 0.0)
        out[name] = np.bincount(owner.ravel(), w.ravel(), minlength=n + 1)[1:]
    t = pd.DataFrame(out)
    present = np.zeros(n + 1, bool)
    present[lab[obj]] = True
    return t[present[1:]].reset_index(drop=True)


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


def damage_table(images, manifest=None, *, z=OUTLIER_Z, min_n=OUTLIER_MIN_N):
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

    Returns
    -------
    images_flagged : pandas.DataFrame
        ``images`` with ``specimen, test, stage`` and a boolean ``P_outlier``.
    damage : pandas.DataFrame
        One row per (specimen, test, stage): ``n_images, n_no_shear, n_outliers,
        outlier_images, P_mean`` (mean of finite per-image P, outliers left out),
        ``P_mean_all`` (outliers kept), ``P_median, P_pooled`` (sum A_T / sum A_S over the
        non-outlier images, including those with A_S = 0; NaN without areas),
        ``area_T_um2, area_S_um2``.

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
    rows = []
    for (spec, test, stage), g in df.groupby(list(keys), sort=False):
        keep = g[~g["P_outlier"]]
        p_keep = keep["P"].to_numpy()
        p_all = g["P"].to_numpy()
        a_t = keep["area_T_um2"].sum() if has_area else np.nan
        a_s = keep["area_S_um2"].sum() if has_area else np.nan
        fin = np.isfinite(p_keep)
        rows.append(dict(
            specimen=spec, test=test, stage=stage, n_images=len(g),
            n_no_shear=int((~np.isfinite(p_all)).sum()),
            n_outliers=int(g["P_outlier"].sum()),
            outlier_images=";".join(map(str, g.loc[g["P_outlier"], "image"])),
            P_mean=float(p_keep[fin].mean()) if fin.any() else np.nan,
            P_mean_all=float(np.nanmean(p_all)) if np.isfinite(p_all).any() else np.nan,
            P_median=float(np.median(p_keep[fin])) if fin.any() else np.nan,
            P_pooled=float(damage_ratio(a_t, a_s)) if has_area else np.nan,
            area_T_um2=a_t, area_S_um2=a_s))
    dmg = pd.DataFrame(rows)
    if len(dmg):
        order = sorted(range(len(dmg)), key=lambda i: (str(dmg.specimen[i]), str(dmg.test[i]),
                                                       _stage_key(dmg.stage[i])))
        dmg = dmg.iloc[order].reset_index(drop=True)
    return df, dmg


def plot_p_by_stage(damage, path=None, *, ax=None):
    """Plot P (mean per stage, outliers left out) by loading stage, one line per test.

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
    for (spec, test), g in damage.groupby(["specimen", "test"], sort=False):
        g = g.iloc[sorted(range(len(g)), key=lambda i: _stage_key(g.stage.iloc[i]))]
        ax.plot(g["stage"].astype(str), g["P_mean"], "o-", label=f"{test} ({spec})")
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


# ----------------------------------------------------------------------------- pipeline glue
def science_stage(analysis, cracks, row, *, manifest_row=None, overlay_dir=None):
    """Run the issue-#3 stages on one analysed image (called by the pipeline).

    Parameters
    ----------
    analysis : semkit.pipeline.CrackAnalysis
        The analysed image; its options say which stages run (``classify``, ``crack_model``,
        ``grains``, ``minerals``).
    cracks : pandas.DataFrame
        Its ``cracks.csv`` rows.
    row : dict
        Its ``images.csv`` row; ``area_T_um2, area_S_um2, area_M_um2, P, P_status`` are set.
    manifest_row : dict, optional
        Its ``manifest.csv`` row: stage ``pre-test`` means no post-test typing (P undefined,
        status ``pre-test``).
    overlay_dir : path, optional
        Where the grain map PNG goes (``<name>_grains.png``) when grains are measured.

    Returns
    -------
    cracks : pandas.DataFrame
        With types, confidences, features, ``area_pv_um2``; ``cracks.attrs["grains"]`` holds
        the per-grain table (as a dict of columns) when grains were measured.
    row : dict
    """
    from .classify import classify_stage, load_model
    opts = analysis.options
    stage = None if manifest_row is None else manifest_row.get("stage")
    stage = None if stage is None or (isinstance(stage, float) and np.isnan(stage)) else str(stage)
    post = bool(getattr(opts, "classify", True)) and stage != "pre-test"
    model = load_model(opts.crack_model) if getattr(opts, "crack_model", None) else None
    grain_labels = None
    grains_df = None
    if getattr(opts, "grains", False):
        from .grains import grains_stage, parse_minerals, plot_grain_map
        names, n = parse_minerals(getattr(opts, "minerals", None))
        grain_labels, ph, grains_df = grains_stage(
            analysis.flat, mask=analysis.object_mask, pixel_size_um=analysis.pixel_size_um,
            names=names, n_phases=n, alt_image=analysis.image)
        grains_df.insert(0, "image", analysis.name)
        if overlay_dir is not None:
            import pathlib

            import matplotlib.pyplot as plt
            pathlib.Path(overlay_dir).mkdir(parents=True, exist_ok=True)
            stem = pathlib.Path(analysis.name).stem
            plt.close(plot_grain_map(grain_labels, ph,
                                     pathlib.Path(overlay_dir) / f"{stem}_grains.png"))
    if not (post or grain_labels is not None):
        row = dict(row)
        row.update(area_T_um2=np.nan, area_S_um2=np.nan, area_M_um2=np.nan, P=np.nan,
                   P_status="pre-test" if stage == "pre-test" else "not_classified")
        return cracks, row
    out = classify_stage(cracks, analysis.crack_labels, grey=analysis.smooth,
                         pixel_size_um=analysis.pixel_size_um, model=model, post=post,
                         grain_labels=grain_labels)
    if grains_df is not None:  # a plain dict: DataFrame attrs must stay comparable
        out.attrs["grains"] = grains_df.to_dict("list")
    row = dict(row)
    if post and len(out):
        d = image_damage(out.assign(image=analysis.name)).iloc[0]
        row.update(area_T_um2=float(d.area_T_um2), area_S_um2=float(d.area_S_um2),
                   area_M_um2=float(d.area_mixed_um2), P=float(d.P), P_status=d.P_status)
    else:
        row.update(area_T_um2=0.0, area_S_um2=0.0, area_M_um2=0.0, P=np.nan,
                   P_status="pre-test" if stage == "pre-test" else "no_cracks")
    return out, row


def write_science_outputs(out, images, cracks, *, manifest=None, labels=None, grain_tables=(),
                          classes=None):
    """Folder-level outputs: user labels, ``damage.csv``, ``P_by_stage.png``, ``grains.csv``.

    Parameters
    ----------
    out : path
        Output folder of ``semkit analyse``.
    images, cracks : pandas.DataFrame
        The folder's ``images.csv`` and ``cracks.csv`` tables.
    manifest : pandas.DataFrame, optional
        ``manifest.csv``; with ``specimen, test, stage`` it gives ``damage.csv``.
    labels : pandas.DataFrame, optional
        User labels (``image, crack_id, type``): override the types and recompute P.
    grain_tables : sequence of pandas.DataFrame or dict of columns
        Per-image grain tables (``--grains``).
    classes : str, optional
        ``--classes`` value for ``grains.csv``.

    Returns
    -------
    images, cracks : pandas.DataFrame
        The (possibly relabelled) tables, rewritten atomically when changed.
    """
    import pathlib

    from .io import write_csv_atomic
    out = pathlib.Path(out)
    if labels is not None and len(cracks) and "type_post" in cracks.columns:
        from .classify import apply_labels
        cracks = apply_labels(cracks, labels)
        if "frac_tensile" in cracks.columns:
            d = image_damage(cracks[cracks["image"].isin(labels["image"])]).set_index("image")
            images = images.copy()
            for name, r in d.iterrows():
                sel = images["image"] == name
                images.loc[sel, ["area_T_um2", "area_S_um2", "P"]] = \
                    [r.area_T_um2, r.area_S_um2, r.P]
                images.loc[sel, "P_status"] = r.P_status
        write_csv_atomic(images, out / "images.csv")
        write_csv_atomic(cracks, out / "cracks.csv")
    if manifest is not None and {"specimen", "test", "stage"} <= set(manifest.columns) \
            and "P" in images.columns and len(images):
        ok = images[images["image"].isin(manifest["image"].astype(str))]
        if len(ok):
            flagged, dmg = damage_table(ok, manifest)
            write_csv_atomic(dmg, out / "damage.csv")
            if "P_outlier" in flagged.columns:
                images = images.drop(columns=["P_outlier"], errors="ignore").merge(
                    flagged[["image", "P_outlier"]], on="image", how="left")
                write_csv_atomic(images, out / "images.csv")
            import matplotlib.pyplot as plt
            plt.close(plot_p_by_stage(dmg, out / "P_by_stage.png"))
    tables = [pd.DataFrame(t) for t in grain_tables if t is not None]
    tables = [t for t in tables if len(t)]
    if tables:
        from .grains import grain_size_table, plot_grain_histograms
        allg = pd.concat(tables, ignore_index=True)
        write_csv_atomic(allg, out / "grains_per_grain.csv")
        write_csv_atomic(grain_size_table(allg, classes=classes), out / "grains.csv")
        import matplotlib.pyplot as plt
        plt.close(plot_grain_histograms(allg, out / "grain_histograms.png"))
    return images, cracks
