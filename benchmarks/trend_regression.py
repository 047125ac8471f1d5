"""Does grain-size heterogeneity change UCS and E once the grain-boundary share is held fixed?

Fits the per-seed rows of ``ucs_scenarios.py`` runs (one parameter file, many scenarios and
grain-size factors) by least squares, for UCS and for E:

    y = a + b J            (J = joint share of the bonds)
    y = a + b J + c MHI    (MHI = the realised heterogeneity index)

``c`` is the change of y per unit MHI at a fixed joint share. The thesis (Table 4-2) has UCS
and E rising as MHI falls from 3.01 (S1) to 0.85 (S4); its slope dy/dMHI over the four
scenarios is printed beside ``c`` (the thesis reports no joint shares, so its slope is the total
one). The table gives ``c`` with its standard error and 95 % interval, b per 0.1 of joint share,
and the residual sd of both fits.

    python benchmarks/trend_regression.py \\
        benchmarks/ucs_results/scenarios_10x20_chunks.json,benchmarks/ucs_results/... --out DIR
"""
from __future__ import annotations

import argparse
from pathlib import Path

from ucs_scenarios import THESIS, read_rows, write_rows

THESIS_MHI = {1: 3.01, 2: 1.78, 3: 1.37, 4: 0.85}


def params_name(path):
    """A parameter file named by its folder and file (runs were started from different dirs)."""
    return "/".join(Path(path).parts[-2:]) if path else None


def unique_rows(rows):
    """One row per (scenario, scale, seed, size, params, seating): the last one read wins.

    Rows written before face seating existed have no ``seat_faces`` and count as unseated.
    """
    keep = {}
    for r in rows:
        key = (r["scenario"], round(float(r["scale"]), 4), r["seed"], r["width_mm"],
               r["height_mm"], params_name(r.get("params")), bool(r.get("seat_faces", False)))
        keep[key] = r
    return list(keep.values())


def ols(X, y):
    """Least-squares coefficients, their standard errors and the residual sd.

    Parameters
    ----------
    X : (n, p) ndarray of float64
        Design matrix (a column of ones for the intercept).
    y : (n,) ndarray of float64

    Returns
    -------
    coef, se : (p,) ndarray of float64
    resid_sd : float
    """
    import numpy as np
    X = np.asarray(X, float)
    y = np.asarray(y, float)
    n, p = X.shape
    if n <= p:
        raise SystemExit(f"trend_regression: {n} rows cannot fit {p} coefficients")
    coef = np.linalg.lstsq(X, y, rcond=None)[0]
    e = y - X @ coef
    s2 = float(e @ e) / (n - p)
    se = np.sqrt(np.diag(s2 * np.linalg.inv(X.T @ X)))
    return coef, se, float(np.sqrt(s2))


def thesis_slope(which):
    """The thesis's dy/dMHI over Scenarios 1-4 (Table 4-2 mid-ranges; 0 UCS, 1 E)."""
    import numpy as np
    m = np.array([THESIS_MHI[s] for s in (1, 2, 3, 4)])
    y = np.array([np.mean(THESIS[s][which]) for s in (1, 2, 3, 4)])
    return float(np.polyfit(m, y, 1)[0])


def fit(rows):
    """Both fits for UCS and E. Returns one result dict per quantity."""
    import numpy as np
    from scipy import stats
    J = np.array([r["joint_fraction"] for r in rows], float)
    M = np.array([r["mhi_realised"] for r in rows], float)
    out = []
    for which, key, unit in ((0, "ucs_mpa", "MPa"), (1, "E_gpa", "GPa")):
        y = np.array([r[key] for r in rows], float)
        c1, se1, sd1 = ols(np.c_[np.ones_like(J), J], y)
        c2, se2, sd2 = ols(np.c_[np.ones_like(J), J, M], y)
        t = float(stats.t.ppf(0.975, len(y) - 3))
        out.append({"quantity": key, "unit": unit, "n": int(len(y)),
                    "J_only": {"intercept": c1[0], "per_J": c1[1], "se_per_J": se1[1],
                               "resid_sd": sd1},
                    "J_and_MHI": {"intercept": c2[0], "per_J": c2[1], "se_per_J": se2[1],
                                  "per_MHI": c2[2], "se_per_MHI": se2[2],
                                  "ci95_per_MHI": [c2[2] - t * se2[2], c2[2] + t * se2[2]],
                                  "resid_sd": sd2},
                    "thesis_per_MHI": thesis_slope(which),
                    "mhi_range": [float(M.min()), float(M.max())],
                    "J_range": [float(J.min()), float(J.max())]})
    return out


def markdown_table(res):
    lines = ["| quantity | n | per 0.1 joint share (J only) | resid sd (J only) | "
             "per unit MHI at fixed J (± se) | 95 % interval | resid sd (J, MHI) | "
             "thesis per unit MHI |",
             "|---|---|---|---|---|---|---|---|"]
    for q in res:
        a, b = q["J_only"], q["J_and_MHI"]
        u = q["unit"]
        lines.append(f"| {q['quantity']} | {q['n']} | {0.1 * a['per_J']:+.1f} {u} | "
                     f"{a['resid_sd']:.1f} | {b['per_MHI']:+.1f} ± {b['se_per_MHI']:.1f} {u} | "
                     f"{b['ci95_per_MHI'][0]:+.1f} to {b['ci95_per_MHI'][1]:+.1f} | "
                     f"{b['resid_sd']:.1f} | {q['thesis_per_MHI']:+.1f} {u} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("results", help="comma-separated ucs_scenarios.json files (one parameter "
                                   "file throughout)")
    p.add_argument("--out", default="benchmarks/results")
    a = p.parse_args(argv)
    rows = unique_rows(read_rows(a.results))
    params = {(params_name(r.get("params")), bool(r.get("seat_faces", False))) for r in rows}
    if len(params) > 1:
        raise SystemExit(f"trend_regression: rows come from several (parameter file, face "
                         f"seating) settings {params}; fit one at a time")
    missing = [r for r in rows if r.get("mhi_realised") is None or "joint_fraction" not in r]
    if missing:
        raise SystemExit(f"trend_regression: {len(missing)} rows lack mhi_realised or "
                         "joint_fraction (a tessellation specimen is needed)")
    res = fit(rows)
    write_rows(a.out, "trend_regression", res, markdown_table(res))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
