"""The report of ``gbmgen run``: ``report.html`` (self-contained) and ``report.md`` in the run's
folder.

It reads what the run wrote (``run.json``, ``semkit/``, ``specimen.npz``, ``<test>/``) and
shows: a table of the SEM measurement beside the simulation (damage ratio P, MHI, H) with the
test's numbers and their validity flags; the SEM overlays; measured against generated
grain-size histograms (one panel per mineral, both at model scale); the specimen; the
stress-strain curve; the crack map.
"""
from __future__ import annotations

import json
import pathlib

import numpy as np

from .report import Report

__all__ = ["write_run_report", "plot_grain_size_histograms"]

#: Overlays shown in the report at most (the rest are listed by name).
MAX_OVERLAYS = 12


def plot_grain_size_histograms(measured_mm: dict, generated_mm: dict, path, *, ks=None):
    """Histograms of grain equivalent diameters per mineral, measured against generated.

    Parameters
    ----------
    measured_mm, generated_mm : dict
        Mineral -> (n,) array of equivalent-circle diameters, mm (the measured ones already at
        model scale).
    path : path of the PNG
    ks : dict, optional
        Mineral -> Kolmogorov-Smirnov distance of the build (shown in the titles).
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = list(dict.fromkeys(list(generated_mm) + list(measured_mm)))
    fig, axes = plt.subplots(1, max(len(names), 1), figsize=(4.0 * max(len(names), 1), 3.2),
                             squeeze=False)
    for ax, name in zip(axes[0], names):
        m = np.asarray(measured_mm.get(name, []), float)
        g = np.asarray(generated_mm.get(name, []), float)
        both = np.concatenate([m, g])
        both = both[both > 0]
        if both.size:
            bins = np.geomspace(both.min(), both.max() * 1.0001, 16)
            if m.size:
                ax.hist(m, bins=bins, weights=np.full(m.size, 1.0 / m.size), alpha=0.5,
                        color="tab:blue", label=f"measured (SEM x model scale), n={m.size}")
            if g.size:
                ax.hist(g, bins=bins, weights=np.full(g.size, 1.0 / g.size), histtype="step",
                        lw=1.6, color="tab:red", label=f"generated (specimen), n={g.size}")
            ax.set_xscale("log")
        title = name if not ks or name not in ks else f"{name}: KS {ks[name]:.3f}"
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("equivalent diameter (mm)")
        ax.legend(fontsize=6)
    axes[0][0].set_ylabel("share of the mineral's grains")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def _grain_diameters(spec):
    from .tessellate import polygon_areas
    if spec.n_grains == 0:
        return {}
    d = 2e3 * np.sqrt(polygon_areas(spec.grain_xy, spec.grain_offsets) / np.pi)
    return {str(n): d[spec.grain_mineral == k] for k, n in enumerate(spec.mineral_names)}


def _measured_diameters(sem, model_scale):
    import pandas as pd
    path = pathlib.Path(sem) / "grains_per_grain.csv"
    if not path.exists():
        return {}
    g = pd.read_csv(path)
    return {str(n): g.loc[g["mineral"] == n, "eq_diameter_um"].to_numpy(float)
            * model_scale / 1e3 for n in g["mineral"].unique()}


def _flag(ok, reason):
    if ok is None:
        return "–"
    return "valid" if ok else f"INVALID: {reason}"


def write_run_report(out) -> tuple:
    """Write ``report.html`` and ``report.md`` for the ``gbmgen run`` in ``out``.

    Returns
    -------
    paths : (str, str)
        The HTML and Markdown files.
    """
    from sim.specimen import Specimen
    out = pathlib.Path(out)
    run = json.loads((out / "run.json").read_text(encoding="utf-8"))
    sem = out / "semkit"
    spec = Specimen.load(out / "specimen.npz")
    meta = spec.meta or {}
    ts = run.get("test_summary") or {}
    test = run.get("test", "none")
    rep = Report(f"gbmgen run: {run.get('images')}")
    rep.text(f"Specimen {spec.n_particles} particles, {spec.n_grains} grains, "
             f"{run.get('parallel_bonds')} parallel bonds, {run.get('smooth_joints')} smooth "
             f"joints; seed {run.get('seed')} ({run.get('seed_source')}); scenario "
             f"{run.get('scenario')}; test {test}.")

    rep.heading("SEM measurement beside the simulation")
    psem = run.get("P_sem") or {}
    p_sem = psem.get("P_pooled")
    p_sim = (ts.get("P_sim") or {})
    how = "SEM: pooled over the loaded stages; simulated: broken-bond area, tension/shear"
    if psem.get("P_status", "ok") != "ok":
        how += f". SEM P is {psem['P_status']}: {psem.get('P_note') or 'see damage.csv'}"
    from semkit.damage import band_text
    band = band_text(psem.get("P_pooled_low"), psem.get("P_pooled_high"))
    if band:
        how += f". SEM typing band (10-90 %): {band}"
    rows = [["damage ratio P = A_T/A_S (Equ. 3-1)", p_sem, p_sim.get("by_area"), how],
            ["MHI (Equ. 4-3)", run.get("MHI_target"), run.get("MHI_realised"),
             "measured: the grains.csv semkit wrote; simulated: the specimen's grains"],
            ["H (Equ. 4-1)", meta.get("H_target"), meta.get("H_realised"), ""]]
    rep.table(["quantity", "SEM (measured)", "simulated", "how"], rows)

    if test != "none":
        rep.heading(f"Laboratory test: {test}")
        rows = []
        for key, label, ok_key, reason_key in (
                ("E_gpa", "E (GPa)", "E_ok", "E_reason"),
                ("nu", "Poisson's ratio", "nu_ok", "nu_reason"),
                ("ucs_mpa", "UCS (MPa)", None, None), ("ci_mpa", "CI (MPa)", None, None),
                ("cd_mpa", "CD (MPa)", None, None),
                ("tensile_mpa", "tensile strength (MPa)", None, None)):
            if key in ts:
                ok = ts.get(ok_key) if ok_key else None
                rows.append([label, ts.get(key),
                             _flag(ok, ts.get(reason_key)) if ok_key else "–"])
        r = ts.get("representative") or {}
        rows.append(["specimen representative", r.get("ok"),
                     "; ".join(r.get("warnings") or []) or "rules met"])
        rows.append(["stop reason", ts.get("stop_reason"), "–"])
        rep.table(["result", "value", "validity"], rows)
        cr = ts.get("cracks") or {}
        if cr:
            rep.table(list(cr), [list(cr.values())], "cracks by kind (count)")

    by_stage = (run.get("P_sem") or {}).get("by_stage") or []
    if by_stage:
        rep.heading("SEM damage ratio by stage")
        cols = list(by_stage[0])
        rep.table(cols, [[r.get(c) for c in cols] for r in by_stage])

    rep.heading("Figures")
    overlays = sorted((sem / "overlays").glob("*.png")) if (sem / "overlays").exists() else []
    for path in overlays[:MAX_OVERLAYS]:
        rep.figure(path, f"SEM overlay {path.stem} (cracks coloured by type)")
    if len(overlays) > MAX_OVERLAYS:
        rep.text(f"{len(overlays) - MAX_OVERLAYS} more overlays in semkit/overlays/: "
                 + ", ".join(p.name for p in overlays[MAX_OVERLAYS:]), note=True)
    figures = out / "report_files"
    figures.mkdir(exist_ok=True)
    scale = float((meta.get("grains") or {}).get("model_scale") or 1.0)
    ks = {k: v.get("ks") for k, v in ((meta.get("fidelity") or {}).get("minerals")
                                      or {}).items()}
    hist = plot_grain_size_histograms(_measured_diameters(sem, scale), _grain_diameters(spec),
                                      figures / "grain_sizes.png", ks=ks)
    rep.figure(hist, f"grain sizes: measured (SEM, x model scale {scale:g}) and generated "
               "(specimen grains), equivalent-circle diameters")
    rep.figure(out / "specimen.png", "the specimen (grains by mineral)")
    if test != "none":
        rep.figure(out / test / "stress_strain.png", "stress-strain curve and crack counts")
        rep.figure(out / test / "crack_map.png", "crack map at the end of the test")
    rep.figure(sem / "P_by_stage.png", "SEM damage ratio P by stage")
    files = "run.json, specimen.npz, semkit/ (images.csv, cracks.csv, damage.csv, grains.csv)"
    if test != "none":
        files += f", {test}/ (summary.json, history.csv, cracks.csv)"
    rep.text(f"Files: {files}.", note=True)
    return rep.write(out)
