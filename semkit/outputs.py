"""Folder-level outputs of ``semkit analyse``: ``images.csv``, ``cracks.csv``, user labels,
``damage.csv`` and ``P_by_stage.png``, ``grains_per_grain.csv``, ``grains.csv`` and histograms.

Every table is written atomically (temporary file, then rename).
"""
from __future__ import annotations

import pathlib

import pandas as pd

from .analysis import EXTRA_IMAGE_COLUMNS, IMAGE_COLUMNS
from .io import write_csv_atomic

__all__ = ["write_tables", "write_science_outputs"]


def write_tables(out, rows, cracks, order):
    """Write ``images.csv`` and ``cracks.csv`` from per-image rows and crack tables.

    Parameters
    ----------
    out : path
    rows : dict of str -> dict
        ``images.csv`` row per image name.
    cracks : dict of str -> DataFrame or None
        ``cracks.csv`` rows per image name.
    order : list of str
        Image names in output order.

    Returns
    -------
    images, cracks : pandas.DataFrame
    """
    from .measure import CRACK_COLUMNS
    out = pathlib.Path(out)
    imgs = pd.DataFrame([rows[k] for k in order if k in rows])
    cols = IMAGE_COLUMNS + [c for c in EXTRA_IMAGE_COLUMNS if c in imgs.columns]
    cols += [c for c in imgs.columns if c not in cols]
    imgs = imgs.reindex(columns=cols)
    frames = [cracks[k] for k in order if cracks.get(k) is not None and len(cracks[k])]
    cr = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=CRACK_COLUMNS)
    write_csv_atomic(imgs, out / "images.csv")
    write_csv_atomic(cr, out / "cracks.csv")
    return imgs, cr


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
    grain_tables : sequence of pandas.DataFrame
        Per-image grain tables (``--grains``).
    classes : str, optional
        ``--classes`` value for ``grains.csv``.

    Returns
    -------
    images, cracks : pandas.DataFrame
        The (possibly relabelled) tables, rewritten atomically when changed.
    """
    from .damage import damage_table, image_damage, plot_p_by_stage
    out = pathlib.Path(out)
    if labels is not None and len(cracks) and "type_post" in cracks.columns:
        from .classify import apply_labels
        cracks = apply_labels(cracks, labels)
        if "frac_tensile" in cracks.columns:
            kept = cracks["rejected_as"].fillna("").astype(str) == "" \
                if "rejected_as" in cracks.columns else True
            d = image_damage(cracks[kept & cracks["image"].isin(labels["image"])]
                             ).set_index("image")
            images = images.copy()
            for name, r in d.iterrows():
                sel = images["image"] == name
                images.loc[sel, ["area_T_um2", "area_S_um2", "P"]] = \
                    [r.area_T_um2, r.area_S_um2, r.P]
                images.loc[sel, "P_status"] = r.P_status
                for k in ("P_low", "P_high", "P_note"):
                    if k in d.columns:
                        images.loc[sel, k] = r[k]
        write_csv_atomic(images, out / "images.csv")
        write_csv_atomic(cracks, out / "cracks.csv")
    if manifest is not None and {"specimen", "test", "stage"} <= set(manifest.columns) \
            and "P" in images.columns and len(images):
        ok = images[images["image"].isin(manifest["image"].astype(str))]
        if len(ok):
            flagged, dmg = damage_table(ok, manifest, cracks=cracks if len(cracks) else None)
            write_csv_atomic(dmg, out / "damage.csv")
            if "P_outlier" in flagged.columns:
                images = images.drop(columns=["P_outlier"], errors="ignore").merge(
                    flagged[["image", "P_outlier"]], on="image", how="left")
                write_csv_atomic(images, out / "images.csv")
            import matplotlib.pyplot as plt
            plt.close(plot_p_by_stage(dmg, out / "P_by_stage.png"))
    tables = [t for t in grain_tables if t is not None and len(t)]
    if tables:
        from .grains import grain_size_table, plot_grain_histograms
        allg = pd.concat(tables, ignore_index=True)
        write_csv_atomic(allg, out / "grains_per_grain.csv")
        write_csv_atomic(grain_size_table(allg, classes=classes), out / "grains.csv")
        import matplotlib.pyplot as plt
        plt.close(plot_grain_histograms(allg, out / "grain_histograms.png"))
    return images, cracks
