"""Self-checks of the gen3 truth contract.

Runs analytic tests of the exact supersampled rasteriser and of the mid-line
length (straight cracks of known width, linearly closing cracks, disks,
unions, holes, clipping at the image border), then internal-consistency checks
on generated images (coverage sum == ``area_px``, per-type split, mask
threshold, grey-level model, void darker than all rock, crack separation, pore
compactness, determinism).  With ``--dir OUT`` it also regenerates every row
of ``OUT/truth.csv`` and compares the stored truth and image.

Usage::

    python check_truth.py [--seeds 0 1 2 ...] [--dir OUTDIR]
"""
# ruff: noqa: E501
from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import time

import cv2
import numpy as np
from scipy import ndimage
from skimage.morphology import skeletonize

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gen3_generator import (  # noqa: E402
    MIN_OPEN,
    make_image,
    open_runs,
    polyline_length_in_rect,
    rasterize_coverage,
)

FAILS = []


def report(name, got, want, tol):
    """Print one numeric check and remember failures."""
    err = abs(got - want)
    rel = err / abs(want) if want else err
    ok = err <= tol
    if not ok:
        FAILS.append(name)
    print(f"  [{'ok' if ok else 'FAIL'}] {name:<58s} got {got:12.4f}  want {want:12.4f}  rel.err {rel:.2e}")


def straight_trace(x0, y0, ang_deg, L, du=0.5):
    """Straight path points and normals."""
    n = int(round(L / du)) + 1
    u = np.linspace(0, L, n)
    a = math.radians(ang_deg)
    P = np.stack([x0 + u * math.cos(a), y0 + u * math.sin(a)], 1)
    N = np.tile([-math.sin(a), math.cos(a)], (n, 1))
    return u, P, N


def crack_truth(runs, W, H):
    """Coverage sum and clipped mid-line length of open runs in a W x H image."""
    cov = rasterize_coverage([r["poly"] for r in runs], [], 0, 0, W, H)
    length = sum(polyline_length_in_rect(r["mid"], 0, 0, W, H) for r in runs)
    return float(cov.sum(dtype=np.float64)), length, cov


def analytic_tests():
    """Analytic checks of area and length."""
    print("Analytic tests (supersampling %dx%d, closure threshold %.2f px)" % (8, 8, MIN_OPEN))
    W, H = 1024, 768
    for w, ang, L in [(3.0, 27.0, 200.0), (1.0, 0.0, 300.0), (0.5, 90.0, 150.0), (2.5, 45.0, 400.0),
                      (7.3, 161.0, 250.0), (1.37, 13.0, 611.0), (10.0, 71.3, 333.3)]:
        u, P, N = straight_trace(300.37, 250.61, ang, L)
        runs = open_runs(P, N, np.full(len(u), w / 2), np.full(len(u), -w / 2))
        a, length, _ = crack_truth(runs, W, H)
        report(f"straight crack w={w} ang={ang} L={L}: area", a, w * L, 2e-3 * w * L + 0.5)
        report(f"straight crack w={w} ang={ang} L={L}: mid-line length", length, L, 1e-6)
    # angle sweep of straight cracks: worst-case relative area error
    for w in (0.5, 1.0, 3.0):
        errs = []
        for ang in np.arange(0.0, 180.0, 0.5):
            a = math.radians(ang)
            u, P, N = straight_trace(512.37 - 150 * math.cos(a), 384.61 - 150 * math.sin(a), ang, 300.0)
            runs = open_runs(P, N, np.full(len(u), w / 2), np.full(len(u), -w / 2))
            errs.append(crack_truth(runs, W, H)[0] / 300.0 - w)
        errs = np.abs(errs)
        report(f"angle sweep 0..180 deg (360 cracks) w={w} L=300: max |area/L - w| px", float(errs.max()), 0.0, 0.01)
    # rough tensile crack: walls = same profile shifted -> area = w * L exactly (shear of a band)
    u, P, N = straight_trace(100.2, 400.9, 8.0, 700.0)
    rng = np.random.default_rng(1)
    prof = np.cumsum(rng.normal(0, 0.2, len(u)))
    prof = ndimage.gaussian_filter1d(prof, 6)
    runs = open_runs(P, N, prof + 2.0, prof - 2.0)
    a, length, _ = crack_truth(runs, W, H)
    report("rough matching walls (opening 4 along N): area = 4*L", a, 4.0 * 700.0, 2e-3 * 2800)
    mid = P + prof[:, None] * N
    report("rough matching walls: mid-line length = profile length", length, float(np.sum(np.hypot(*np.diff(mid, axis=0).T))), 1e-6)
    # linearly opening crack: opening g(u) = u/100 over L=200 -> closed for u < 30
    u, P, N = straight_trace(400.0, 100.5, 33.0, 200.0)
    g = u / 100.0
    runs = open_runs(P, N, g / 2, -g / 2)
    a, length, _ = crack_truth(runs, W, H)
    report("wedge 0->2 px, L=200: open length (g>=0.3) = 170", length, 170.0, 1e-6)
    report("wedge 0->2 px, L=200: area = (200^2-30^2)/200 = 195.5", a, 195.5, 0.5)
    # bridged crack: opening 2 px with a closed bridge 100<u<150
    u, P, N = straight_trace(200.0, 600.25, -12.0, 400.0)
    g = np.where((u > 100) & (u < 150), 0.0, 2.0)
    runs = open_runs(P, N, g / 2, -g / 2)
    a, length, _ = crack_truth(runs, W, H)
    report("bridge: two open runs", len(runs), 2, 0)
    # the step is sampled at du = 0.5, so each run end lies within 0.5 px of the ideal one
    report("bridge: length (interpolated run ends) ~ 350", length, 350.0, 1.0)
    report("bridge: area ~ 2*350", a, 700.0, 2.0)
    # disk
    phi = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    for r in (2.0, 10.0, 37.5):
        disk = np.stack([500.3 + r * np.cos(phi), 300.7 + r * np.sin(phi)], 1)
        a = float(rasterize_coverage([disk], [], 0, 0, W, H).sum())
        report(f"disk r={r}: area = pi r^2", a, math.pi * r * r, 2e-3 * math.pi * r * r + 0.2)
    # union of two crossing straight cracks (same orientation -> union, not sum)
    u1, P1, N1 = straight_trace(300.0, 400.0, 0.0, 300.0)
    u2, P2, N2 = straight_trace(450.0, 250.0, 90.0, 300.0)
    r1 = open_runs(P1, N1, np.full(len(u1), 2.0), np.full(len(u1), -2.0))
    r2 = open_runs(P2, N2, np.full(len(u2), 1.5), np.full(len(u2), -1.5))
    a, _, cov = crack_truth(r1 + r2, W, H)
    report("union of crossing 4x300 and 3x300 cracks = 2100 - 12", a, 2100.0 - 12.0, 1.0)
    report("union: max coverage <= 1", float(cov.max()), 1.0, 1e-9)
    # hole (gouge fragment) inside a crack
    sq = np.array([[350.0, 399.0], [352.0, 399.0], [352.0, 401.0], [350.0, 401.0]])
    cov = rasterize_coverage([r["poly"] for r in r1], [sq], 0, 0, W, H)
    report("crack 4x300 minus 2x2 fragment = 1196", float(cov.sum()), 1196.0, 0.3)
    # clipping at image border: crack from x=-50 to x=150 inside a 100-px wide image
    u, P, N = straight_trace(-50.0, 40.3, 0.0, 200.0)
    runs = open_runs(P, N, np.full(len(u), 1.5), np.full(len(u), -1.5))
    a, length, _ = crack_truth(runs, 100, 80)
    report("border-clipped crack: length = 100", length, 100.0, 1e-6)
    report("border-clipped crack: area = 3*100", a, 300.0, 0.5)


def min_separation(crack_id):
    """Smallest pixel-centre distance between void pixels of different cracks."""
    ids = np.unique(crack_id[crack_id > 0])
    best = np.inf
    objs = ndimage.find_objects(crack_id)
    for k in ids:
        sl = objs[k - 1]
        y0, y1 = max(sl[0].start - 12, 0), min(sl[0].stop + 12, crack_id.shape[0])
        x0, x1 = max(sl[1].start - 12, 0), min(sl[1].stop + 12, crack_id.shape[1])
        sub = crack_id[y0:y1, x0:x1]
        others = (sub > 0) & (sub != k)
        if not others.any():
            continue
        d = ndimage.distance_transform_edt(~others)
        best = min(best, float(d[sub == k].min()))
    return best


def image_tests(seeds):
    """Consistency checks on generated images."""
    print("\nGenerated-image checks")
    for seed in seeds:
        shape = (1536, 2048) if seed % 3 == 2 else (768, 1024)
        t = time.time()
        r = make_image(shape, seed, return_layers=True)
        dt = time.time() - t
        st = r["settings"]
        H, W = shape
        hc = H - r["bar_rows"]
        cov = r["coverage"]
        print(f" seed {seed} {H}x{W} {st['rock']:<9s} {r['image'].dtype} bar={r['has_bar']} ps={r['pixel_size_um']:.3f}um "
              f"n_cracks={r['n_cracks']} area={r['area_px']:.1f} ({100 * st['crack_area_frac']:.2f}%) length={r['length_px']:.1f} P={r['P']:.3f} ({dt:.2f}s)")
        report("  area_px == sum(coverage)", r["area_px"], float(cov.sum(dtype=np.float64)), 1e-3)
        report("  area_px == tensile + shear + mixed", r["area_px"], r["tensile_area_px"] + r["shear_area_px"] + r["mixed_area_px"], 1e-2)
        report("  length_px == sum of per-crack mid-line lengths", r["length_px"], sum(c["length"] for c in r["cracks"]), 1e-6)
        report("  crack_mask == (coverage >= 0.5) mismatches", float(np.sum(r["crack_mask"] != (cov >= 0.5))), 0.0, 0)
        report("  max(crack + pore coverage) <= 1 (no overlaps)", float((cov + r["pore_cov"]).max() <= 1.0 + 1e-6), 1.0, 0)
        report("  coverage below info bar", float(cov[hc:].sum()), 0.0, 0)
        model = r["background"] * (1 - r["void_cov"]) + np.float32(r["void_grey"]) * r["void_cov"]
        report("  clean grey == B(1-c) + void*c (max abs diff)", float(np.abs(model - r["clean"]).max()), 0.0, 1e-6)
        report("  void_grey below darkest rock (margin)", float(r["background"].min() - r["void_grey"] >= 0.05), 1.0, 0)
        if np.isfinite(r["P"]):
            report("  P == tensile/shear", r["P"], r["tensile_area_px"] / r["shear_area_px"], 1e-9)
        sep = min_separation(r["crack_id"])
        print(f"    min distance between void pixels of different cracks: {sep:.2f} px")
        if sep < 3.9:
            FAILS.append(f"seed {seed} separation {sep:.2f}")
        lab, n = ndimage.label(r["pore_cov"] >= 0.5)
        if n:
            sl = ndimage.find_objects(lab)
            ar = []
            for i, s in enumerate(sl):
                m = lab[s] == i + 1
                if m.sum() < 12:
                    continue
                ys, xs = np.nonzero(m)
                ev = np.linalg.eigvalsh(np.cov(np.stack([xs, ys]).astype(float)))
                ar.append(math.sqrt(max(ev[1], 1e-9) / max(ev[0], 1e-9)))
            print(f"    pores: {n}, max axis ratio of pores >= 12 px: {max(ar) if ar else float('nan'):.2f}")
        # crack opening statistics (2 x distance at skeleton)
        m = r["crack_mask"]
        sk = skeletonize(m)
        dtm = ndimage.distance_transform_edt(m)
        wv = 2 * dtm[sk]
        if wv.size:
            print(f"    opening (2*EDT on skeleton) percentiles 5/50/95: {np.percentile(wv, 5):.1f}/{np.percentile(wv, 50):.1f}/{np.percentile(wv, 95):.1f} px; "
                  f"skeleton px / length_px = {sk.sum() / max(r['length_px'], 1):.3f}")
        r2 = make_image(shape, seed)
        report("  deterministic (identical image on re-run)", float(np.array_equal(r2["image"], r["image"])), 1.0, 0)


def dir_tests(d):
    """Regenerate each row of truth.csv and compare."""
    print(f"\nRe-checking {d}/truth.csv")
    with open(os.path.join(d, "truth.csv")) as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        seed = int(row["seed"])
        shape = (int(row["height"]), int(row["width"]))
        r = make_image(shape, seed)
        img = cv2.imread(os.path.join(d, row["image"]), cv2.IMREAD_UNCHANGED)
        same = img is not None and img.dtype == r["image"].dtype and np.array_equal(img, r["image"])
        report(f"  {row['image']}: stored image identical", float(same), 1.0, 0)
        report(f"  {row['image']}: area_px", float(row["area_px"]), r["area_px"], 1e-2)
        report(f"  {row['image']}: length_px", float(row["length_px"]), r["length_px"], 1e-2)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2, 3, 4, 5])
    ap.add_argument("--dir", default=None)
    a = ap.parse_args()
    analytic_tests()
    image_tests(a.seeds)
    if a.dir:
        dir_tests(a.dir)
    print("\nALL CHECKS PASSED" if not FAILS else f"\nFAILED: {FAILS}")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
