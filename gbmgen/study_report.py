"""Figures, findings and the report of a thesis study (:mod:`gbmgen.study`).

Every figure shows this model's case means with the seed spread (sample standard deviation)
as error bars, and the thesis's numbers from REFERENCE.md beside them where the thesis gives
numbers (Table 4-2 ranges; Ch. 6 damaged areas, on their own axis, since the thesis's damaged
area is not defined the same way). :func:`findings` states each of the thesis's findings
beside what this model gives, and whether they agree; nothing is adjusted to agree.
"""
from __future__ import annotations

import json
import math
import pathlib

import numpy as np

from .report import Report
from .study import (
    CH6_RADIUS_MM,
    THESIS_CH4,
    THESIS_CH5,
    THESIS_CH6_ANGLE,
    THESIS_CH6_BRIDGE_R,
    THESIS_SIZE_MM,
    _number,
    case_summary,
)

__all__ = ["findings", "draw_figures", "write_study_report", "seed_spread",
           "representativeness_note"]

#: what a finding says when the cases it compares have no valid value (E flagged invalid in
#: every run of a case, say): no order is read from missing numbers
_NO_VALID = "no valid values"

_LABEL = {"ucs_mpa": "UCS (MPa)", "E_gpa": "E (GPa)", "nu": "Poisson's ratio",
          "hole_damage_damaged_area_mm2": "damaged area (mm²)",
          "hole_damage_crack_joins_holes": "share of runs with a crack joining the holes",
          "hole_damage_max_displacement_mm": "max displacement (mm)",
          "MHI_realised": "MHI (realised)"}


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def seed_spread(frame, key, metric):
    """Mean over the other cases per (``key``, seed), then mean, sd and n over the seeds.

    Returns
    -------
    table : pandas.DataFrame
        Columns ``key``, ``mean``, ``sd``, ``n`` (sorted by ``key``).
    """
    import pandas as pd
    ok = frame[frame["status"] == "ok"] if "status" in frame else frame
    if metric not in ok or len(ok) == 0:
        return pd.DataFrame(columns=[key, "mean", "sd", "n"])
    v = ok.assign(_v=pd.to_numeric(ok[metric], errors="coerce")).dropna(subset=["_v"])
    per_seed = v.groupby([key, "seed"])["_v"].mean().reset_index()
    g = per_seed.groupby(key)["_v"]
    return pd.DataFrame({key: list(g.groups), "mean": g.mean().values,
                         "sd": g.std(ddof=1).values, "n": g.count().values})


def _extreme(s, key, metric, fn):
    s = s.dropna(subset=[f"{metric}_mean"])
    if s[key].nunique() < 2:            # no extreme among fewer than two cases
        return None
    return s.loc[getattr(s[f"{metric}_mean"], fn)(), key]


def _spread_text(s, metric) -> str:
    """How far the cases stand apart in seed sd, or why that is unknown.

    >>> import pandas as pd
    >>> _spread_text(pd.DataFrame({"u_mean": [1.0, 3.0], "u_sd": [1.0, 1.0]}), "u")
    'case means span 2.0 seed sd'
    >>> _spread_text(pd.DataFrame({"u_mean": [1.0, 3.0], "u_sd": [float("nan")] * 2}), "u")
    'one seed per case: no seed spread, the order may be noise'
    """
    r = _rel_spread(s, metric)
    if math.isnan(r):
        return "one seed per case: no seed spread, the order may be noise"
    return f"case means span {r:.1f} seed sd"


def _rel_spread(s, metric):
    """(largest - smallest case mean) / mean seed sd: how far the cases stand apart."""
    m, sd = s[f"{metric}_mean"].dropna(), s[f"{metric}_sd"].dropna()
    if len(m) < 2 or len(sd) == 0 or sd.mean() == 0:
        return float("nan")
    return float((m.max() - m.min()) / sd.mean())


def findings(name, frame):
    """Rows ``[finding, thesis, this model, agree]`` for the study ``name``."""
    from .study import STUDIES
    st = STUDIES[name]
    s = case_summary(st, frame)
    rows = []
    if len(s) == 0:
        return rows
    if name == "thesis-ch4-scenarios":
        base = s[s["scale"] == 1.0].sort_values("scenario")
        for metric in ("ucs_mpa", "E_gpa"):
            valid = base.dropna(subset=[f"{metric}_mean"])
            missing = sorted(set(base["scenario"]) - set(valid["scenario"]))
            if missing or len(valid) < 2:
                rows.append([f"{_LABEL[metric]} rises as MHI falls (S1 < S2 < S3 < S4)",
                             "S1 < S2 < S3 < S4", _NO_VALID + " for "
                             + ", ".join(f"S{k}" for k in missing or base["scenario"]), None])
                continue
            order = valid.sort_values(f"{metric}_mean")["scenario"].tolist()
            rows.append([f"{_LABEL[metric]} rises as MHI falls (S1 < S2 < S3 < S4)",
                         "S1 < S2 < S3 < S4", " < ".join(f"S{k}" for k in order),
                         order == sorted(order)])
        for metric in ("ucs_mpa", "E_gpa"):
            one = s[(s["scenario"] == 1) & (s["scale"] == 1.0)][f"{metric}_mean"]
            big = s[(s["scenario"] == 1) & (s["scale"] == 1.5)][f"{metric}_mean"]
            if len(one) and len(big):
                d = float(big.iloc[0] - one.iloc[0])
                rows.append([f"grain size x1.5 raises {_LABEL[metric]} (S1)", "raises",
                             _NO_VALID if math.isnan(d) else f"{d:+.1f}",
                             None if math.isnan(d) else d > 0])
        _flag_one_seed(rows, frame)
    elif name == "thesis-ch4-grain-size":
        for sc, g in s.groupby("scenario"):
            g = g.sort_values("scale")
            for metric in ("ucs_mpa", "E_gpa"):
                g_ok = g.dropna(subset=[f"{metric}_mean"])
                label = f"S{sc}: {_LABEL[metric]} rises with the grain-size scale"
                if len(g_ok) < 2:
                    rows.append([label, "rises", _NO_VALID + " at two scales or more", None])
                    continue
                slope = np.polyfit(g_ok["scale"].to_numpy(float),
                                   g_ok[f"{metric}_mean"].to_numpy(float), 1)[0]
                rows.append([label, "rises", f"slope {slope:+.1f} per unit scale",
                             bool(slope > 0)])
        _flag_one_seed(rows, frame)
    elif name == "thesis-ch5-shapes":
        for shape, (word, ratio) in THESIS_CH5.items():
            g = s[s["shape"] == shape]
            fn = "idxmax" if word == "strongest" else "idxmin"
            at = _extreme(g, "slenderness", "ucs_mpa", fn)
            rows.append([f"{shape}: {word} at slenderness", f"{ratio:g}",
                         f"{at:g} ({_spread_text(g, 'ucs_mpa')})"
                         if at is not None else "–",
                         None if at is None else bool(math.isclose(at, ratio))])
    elif name == "thesis-ch6-holes":
        m = "hole_damage_damaged_area_mm2"
        for word, fn, kind in (("largest", "idxmax", "intra"), ("smallest", "idxmin", "inter")):
            at = _extreme(s, "hole", m, fn)
            rows.append([f"{word} damaged area", kind, at or "–",
                         None if at is None else at == kind])
        _flag_one_seed(rows, frame)
    elif name == "thesis-ch6-double-holes":
        m = "hole_damage_damaged_area_mm2"
        f = frame.assign(bridge_r=frame["bridge_mm"] / (0.5 * frame["hole_diameter_mm"]))
        br = seed_spread(f, "bridge_r", m)
        an = seed_spread(f, "bridge_angle_deg", m)
        th_br = max(THESIS_CH6_BRIDGE_R, key=THESIS_CH6_BRIDGE_R.get)
        for word, fn, th in (("largest", "idxmax", th_br),
                             ("smallest", "idxmin",
                              min(THESIS_CH6_BRIDGE_R, key=THESIS_CH6_BRIDGE_R.get))):
            at = float(br.loc[getattr(br["mean"], fn)(), "bridge_r"]) if len(br) > 1 else None
            rows.append([f"{word} damaged area at bridge length (R)", f"{th:g}",
                         "–" if at is None else f"{at:g}",
                         None if at is None else math.isclose(at, th)])
        for word, fn, th in (("largest", "idxmax", 60.0), ("smallest", "idxmin", 150.0)):
            at = (float(an.loc[getattr(an["mean"], fn)(), "bridge_angle_deg"]) if len(an) > 1
                  else None)
            rows.append([f"{word} damaged area at bridge angle (deg)", f"{th:g}",
                         "–" if at is None else f"{at:g}",
                         None if at is None else math.isclose(at, th)])
        _flag_one_seed(rows, frame)
    return rows


def representativeness_note(frame) -> str:
    """One line saying how many finished runs are on specimens that fail the
    representativeness rules (``representative_ok`` of the test summary), or ``""``.

    Examples
    --------
    >>> import pandas as pd
    >>> f = pd.DataFrame({"status": ["ok", "ok", "failed"],
    ...                   "representative_ok": [False, True, None],
    ...                   "representative_warnings": ['["3.2 grains across"]', "[]", None]})
    >>> print(representativeness_note(f))  # doctest: +NORMALIZE_WHITESPACE
    1 of 2 finished runs are on specimens that fail the representativeness rules
    (e.g. 3.2 grains across): their numbers say little about the rock.
    """
    ok = frame[frame["status"] == "ok"] if "status" in frame else frame
    if "representative_ok" not in ok or len(ok) == 0:
        return ""
    bad = ok[ok["representative_ok"].map(_number) == 0]
    if len(bad) == 0:
        return ""
    example = ""
    if "representative_warnings" in bad:
        try:
            first = json.loads(str(bad["representative_warnings"].iloc[0]))
            example = f" (e.g. {first[0]})" if first else ""
        except ValueError:
            example = ""
    return (f"{len(bad)} of {len(ok)} finished runs are on specimens that fail the "
            f"representativeness rules{example}: their numbers say little about the rock.")


def _flag_one_seed(rows, frame):
    """With one seed the order of the cases has no seed spread to stand against: say so."""
    ok = frame[frame["status"] == "ok"] if "status" in frame else frame
    if "seed" in ok and ok["seed"].nunique() == 1:
        for r in rows:
            if r[2] != "–" and r[3] is not None and "one seed" not in str(r[2]):
                r[2] = f"{r[2]} (one seed: no seed spread, the order may be noise)"


def _errorbar(ax, x, s, metric, **kw):
    ax.errorbar(x, s[f"{metric}_mean"], yerr=s[f"{metric}_sd"].fillna(0.0), fmt="o-",
                capsize=3, **kw)


def _thesis_ch4(ax, metric, xkey):
    for sc, ref in THESIS_CH4.items():
        lo, hi = ref[metric]
        x = ref["MHI"] if xkey == "MHI" else 1.0
        ax.plot([x, x], [lo, hi], color="0.3", lw=4, alpha=0.5,
                label="thesis Table 4-2 (7-seed range)" if sc == 1 else None)


def draw_figures(name, frame, folder) -> list:
    """Draw the study's figures into ``folder``; returns ``[(path, caption), ...]``."""
    from .study import STUDIES
    plt = _plt()
    st = STUDIES[name]
    s = case_summary(st, frame)
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    if len(s) == 0:
        return out

    def save(fig, fname, caption):
        fig.tight_layout()
        fig.savefig(folder / fname, dpi=110)
        plt.close(fig)
        out.append((str(folder / fname), caption))

    if name in ("thesis-ch4-scenarios", "thesis-ch4-grain-size"):
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        for ax, metric in zip(axes, ("ucs_mpa", "E_gpa")):
            if name == "thesis-ch4-scenarios":
                ax.errorbar(s["MHI_realised_mean"], s[f"{metric}_mean"],
                            yerr=s[f"{metric}_sd"].fillna(0.0), fmt="o", capsize=3,
                            color="tab:red", label="this model (mean ± seed sd)")
                for _, r in s.iterrows():
                    ax.annotate(f"S{r['scenario']:g} x{r['scale']:g}",
                                (r["MHI_realised_mean"], r[f"{metric}_mean"]), fontsize=7,
                                xytext=(4, 4), textcoords="offset points")
                _thesis_ch4(ax, metric, "MHI")
                ax.set_xlabel("MHI")
            else:
                for sc, g in s.groupby("scenario"):
                    _errorbar(ax, g["scale"], g, metric, label=f"S{sc} (this model)")
                _thesis_ch4(ax, metric, "scale")
                ax.set_xlabel("grain-size scale")
            ax.set_ylabel(_LABEL[metric])
            ax.legend(fontsize=7)
        save(fig, f"{name}.png", f"{st.title}: UCS and E, this model beside the thesis")
    elif name == "thesis-ch5-shapes":
        for metric in ("ucs_mpa", "E_gpa"):
            fig, axes = plt.subplots(1, 3, figsize=(12, 3.8))
            for ax, (shape, (word, ratio)) in zip(axes, THESIS_CH5.items()):
                g = s[s["shape"] == shape].sort_values("slenderness")
                _errorbar(ax, g["slenderness"], g, metric, color="tab:red",
                          label="this model (mean ± seed sd)")
                ax.axvline(ratio, color="0.3", ls="--",
                           label=f"thesis: {word} at {ratio:g}" if metric == "ucs_mpa"
                           else f"thesis UCS {word} at {ratio:g}")
                ax.set_title(shape)
                ax.set_xlabel("slenderness H/W")
                ax.set_ylabel(_LABEL[metric])
                ax.legend(fontsize=7)
            save(fig, f"{name}_{metric}.png", f"{_LABEL[metric]} against grain slenderness")
    elif name == "thesis-ch6-holes":
        fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
        for ax, metric in zip(axes, ("hole_damage_damaged_area_mm2", "ucs_mpa")):
            x = np.arange(len(s))
            ax.bar(x, s[f"{metric}_mean"], yerr=s[f"{metric}_sd"].fillna(0.0), capsize=3,
                   color="tab:red", alpha=0.7, label="this model (mean ± seed sd)")
            ax.set_xticks(x, [str(h) for h in s["hole"]])
            ax.set_ylabel(_LABEL[metric])
        axes[0].set_title("thesis: intra-grain largest, inter-grain smallest", fontsize=8)
        axes[0].legend(fontsize=7)
        save(fig, f"{name}.png", "damaged area and UCS by hole placement")
    elif name == "thesis-ch6-double-holes":
        m = "hole_damage_damaged_area_mm2"
        f = frame.assign(bridge_r=frame["bridge_mm"] / (0.5 * frame["hole_diameter_mm"]))
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
        for ax, key, ref, xlabel in (
                (axes[0], "bridge_r", THESIS_CH6_BRIDGE_R, "bridge length (hole radii R)"),
                (axes[1], "bridge_angle_deg", THESIS_CH6_ANGLE, "bridge angle (deg)")):
            t = seed_spread(f, key, m)
            ax.errorbar(t[key], t["mean"], yerr=t["sd"].fillna(0.0), fmt="o-", capsize=3,
                        color="tab:red", label="this model (mean over the other cases ± seed sd)")
            ax.set_xlabel(xlabel)
            ax.set_ylabel("damaged area, this model (mm²)", color="tab:red")
            ax2 = ax.twinx()
            ax2.plot(list(ref), list(ref.values()), "s--" if len(ref) > 2 else "s",
                     color="0.3", label="thesis (REFERENCE.md)" if len(ref) > 2 else
                     "thesis: largest and smallest (REFERENCE.md)")
            ax2.set_ylabel("damaged area, thesis (mm², its definition)", color="0.3")
            h1, l1 = ax.get_legend_handles_labels()
            h2, l2 = ax2.get_legend_handles_labels()
            ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper center",   # below: no
                      bbox_to_anchor=(0.5, -0.14), ncol=1)                # point hidden
        save(fig, f"{name}.png", "damaged area by bridge length and by bridge angle")
        fig, ax = plt.subplots(figsize=(6, 4))
        for b, g in f.groupby("bridge_r"):
            t = seed_spread(g, "bridge_angle_deg", "ucs_mpa")
            ax.errorbar(t["bridge_angle_deg"], t["mean"], yerr=t["sd"].fillna(0.0), fmt="o-",
                        capsize=3, label=f"bridge {b:g}R")
        ax.set_xlabel("bridge angle (deg)")
        ax.set_ylabel("UCS (MPa)")
        ax.legend(fontsize=7)
        save(fig, f"{name}_ucs.png", "UCS by bridge angle, one line per bridge length")
    return out


def _mean_sd(mean, sd) -> str:
    """``"12.3 ± 0.4"`` (4 significant digits; '–' for no value).

    Examples
    --------
    >>> _mean_sd(135.04, 2.345), _mean_sd(1.0, float("nan")), _mean_sd(float("nan"), 1.0)
    ('135 ± 2.345', '1', '–')
    """
    from .report import format_value
    if mean is None or math.isnan(mean):
        return "–"
    return format_value(mean) + ("" if sd is None or math.isnan(sd) else
                                 f" ± {format_value(sd)}")


def write_study_report(out, name, frame, *, seeds, size_mm, command="") -> tuple:
    """Write ``report.html`` and ``report.md`` of a study into ``out``."""
    from .study import STUDIES
    st = STUDIES[name]
    rep = Report(st.title)
    n_ok = int((frame["status"] == "ok").sum()) if len(frame) else 0
    rep.text(f"Study {name}: {seeds} seed(s), specimen {size_mm[0]:g} x {size_mm[1]:g} mm "
             f"(thesis {THESIS_SIZE_MM[0]:g} x {THESIS_SIZE_MM[1]:g} mm); {len(frame)} runs "
             f"recorded, {n_ok} ok, {len(frame) - n_ok} failed.")
    if command:
        rep.text(f"Command: {command}", note=True)
    warning = representativeness_note(frame)
    if warning:
        rep.text(warning)
    if name.startswith("thesis-ch6"):
        k = min(size_mm[0] / THESIS_SIZE_MM[0], size_mm[1] / THESIS_SIZE_MM[1])
        rep.text(f"Holes, bridges and grains at {k:g} x the thesis's (R = "
                 f"{CH6_RADIUS_MM * k:g} mm). Damaged area: the disk area of the particles "
                 "with a broken bond within 2R of a hole centre (sim.hole_damage).", note=True)
    rep.heading("Findings beside the thesis")
    rows = findings(name, frame)
    rep.table(["finding", "thesis", "this model", "agree"], rows)
    rep.heading("Cases: mean ± sample sd over the seeds")
    s = case_summary(st, frame)
    rep.table(list(st.case_keys) + ["runs", "ok"] + [_LABEL.get(m, m) for m in st.metrics],
              [[r[k] for k in st.case_keys] + [r["runs"], r["ok"]]
               + [_mean_sd(r[f"{m}_mean"], r[f"{m}_sd"])
                  + (f" (n={r[f'{m}_n']})" if 0 < r[f"{m}_n"] < r["ok"] else "")
                  for m in st.metrics]
               for _, r in s.iterrows()], "n: runs with a valid value, where fewer than ok")
    if name == "thesis-ch4-scenarios" and len(s):
        rep.table(["scenario", "thesis MHI", "thesis UCS (MPa)", "thesis E (GPa)"],
                  [[f"S{k}", v["MHI"], "–".join(map(str, v["ucs_mpa"])),
                    "–".join(map(str, v["E_gpa"]))] for k, v in THESIS_CH4.items()],
                  "thesis Table 4-2 (7 seeds, 25 x 50 mm)")
    rep.heading("Figures")
    for path, caption in draw_figures(name, frame, pathlib.Path(out) / "report_files"):
        rep.figure(path, caption)
    failed = frame[frame["status"] != "ok"] if len(frame) else frame
    if len(failed):
        rep.heading("Failed runs")
        keys = [k for k in st.case_keys if k in failed] + ["seed", "run_id", "error"]
        rep.frame(failed[[k for k in keys if k in failed]])
    rep.text("Table of every run: results.csv (and results.parquet); each run's files: runs/.",
             note=True)
    return rep.write(out)
