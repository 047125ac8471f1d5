"""The issue-#3 stages inside ``semkit analyse``: crack types, P and grains per image, and
the folder-level outputs (user labels, ``damage.csv``, ``P_by_stage.png``, ``grains.csv``).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .damage import damage_table, image_damage, plot_p_by_stage

__all__ = ["science_stage", "write_science_outputs"]


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
