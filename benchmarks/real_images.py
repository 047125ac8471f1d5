"""Accuracy of the default ``semkit analyse`` on real images it was not built from.

* Micro-CT slices of a fractured core (``shared/real_sem/rock_microct_311H``: 40 raw 256 x 256
  slices with hand-painted fracture masks, pixel size unknown, so 1 px = 1 um nominal): per
  slice the centreline precision / recall / F1 (skeletons matched within 2 px of the other
  mask, both ways; :func:`semkit.evaluate.centreline_scores`), the reported crack length over
  the truth skeleton's length (both by semkit's skeleton and length estimator), and the
  reported crack area over the painted area. Medians over all 40 slices, over the first 10 by
  index (the slices the method's generic parameters were chosen on) and over the other 30.
* The granite micrograph (``shared/real_sem/granite_griffiths2017``, 2.02 um/px) against the
  hand marks in ``tests/semkit/data/granite_griffiths2017_marks.json``: share of the marked
  dark-grain pixels called crack; share of each marked faint crack's polyline within 3 px of a
  detected crack (found: >= 70 % of its length).

* Two optical micrographs of B. Obara (``shared/real_sem/obara_sandstone_dolomite_cracks``,
  Apache-2.0): a plane-light dolomite thin section (dark cracks and grain-boundary cracks) and
  a fluorescent-dye impregnated sandstone (bright green cracks, analysed with
  ``bright_cracks=True`` and, to show the flag, without). Their reference crack maps are the
  *output of the author's published algorithms*, not hand-made truth, so the figure is the
  centreline agreement with a published method (precision / recall / F1 within 2 px), not an
  accuracy; pixel size unknown (1 px = 1 um nominal).

All are scored with the default options and again with ``link=True`` (``--link``: the
opt-in linking of faint, beaded cracks, :mod:`semkit.link`).

Writes ``benchmarks/semkit_results/real_images.json`` and prints markdown tables.

Run: ``python benchmarks/real_images.py [--shared PATH]`` (default ``../shared/real_sem`` beside
the repository, or ``$ROCKKIT_SHARED``).
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys

import numpy as np
import pandas as pd

ROOT = pathlib.Path(__file__).resolve().parents[1]
MARKS = ROOT / "tests" / "semkit" / "data" / "granite_griffiths2017_marks.json"
#: a marked crack counts as found when this share of its polyline is near a detected crack
FOUND_COVERAGE = 0.7
#: "near": within this many px
FOUND_TOL_PX = 3.0


def shared_dir(path=None):
    """``shared/real_sem``: the argument, ``$ROCKKIT_SHARED`` (the shared folder or its
    ``real_sem``), or the first ``shared/real_sem`` beside the repository or a folder above."""
    if path:
        return pathlib.Path(path)
    env = os.environ.get("ROCKKIT_SHARED")
    if env:
        e = pathlib.Path(env)
        return e / "real_sem" if (e / "real_sem").is_dir() else e
    for up in ROOT.parents:
        cand = up / "shared" / "real_sem"
        if cand.is_dir():
            return cand
    return ROOT.parent / "shared" / "real_sem"


def microct_scores(folder, **options):
    """Per-slice scores of the default analysis on the micro-CT slices (a DataFrame)."""
    from semkit.analysis import analyse_image
    from semkit.evaluate import centreline_scores
    from semkit.io import read_image
    rows = []
    for f in sorted((folder / "images").glob("slice_*.png")):
        img = read_image(f)
        truth = read_image(folder / "masks" / f.name) > 0
        # scored in pixels: the pixel size is given as 1 (not stated for these slices), so
        # ``valid`` speaks of the detection, not of an unknown scale
        a = analyse_image(img, name=f.name, pixel_size_um=1.0, pixel_size_source="cli",
                          **options)
        row = a.summary()
        pred = a.full_size(a.crack_labels) > 0
        s = centreline_scores(pred, truth)
        s.update(image=f.name, reported_length_ratio=row["crack_length_um"] / s["length_truth_px"],
                 reported_area_ratio=row["crack_area_um2"] / s["area_truth_px"],
                 outside_region_px=int((pred & ~a.full_size(a.region.mask)).sum()),
                 valid=bool(row["valid"]), valid_note=row["valid_note"],
                 contrast_to_noise=row["contrast_to_noise"], roi=row["roi"],
                 n_rejected=row["n_rejected"])
        rows.append(s)
    return pd.DataFrame(rows)


def microct_summary(d):
    """Medians over all slices, the first 10 (tuning) and the other 30 (held out)."""
    out = {}
    for name, sub in (("all_40", d), ("first_10", d.iloc[:10]), ("other_30", d.iloc[10:])):
        out[name] = dict(n=len(sub), f1_median=float(sub.f1.median()),
                         precision_median=float(sub.precision.median()),
                         recall_median=float(sub.recall.median()),
                         length_ratio_median=float(sub.reported_length_ratio.median()),
                         area_ratio_max=float(sub.reported_area_ratio.max()),
                         outside_region_px=int(sub.outside_region_px.sum()),
                         valid=int(sub.valid.sum()))
    return out


def granite_scores(folder, marks=MARKS, **options):
    """Dark-grain and faint-crack scores on the granite micrograph (a dict); ``folder`` is
    ``real_sem`` (the marks name the image relative to it)."""
    import cv2

    from semkit.analysis import analyse_image
    from semkit.evaluate import polyline_coverage
    from semkit.io import read_image
    m = json.loads(pathlib.Path(marks).read_text())
    img = read_image(folder / m["image"])
    a = analyse_image(img, pixel_size_um=m["pixel_size_um"], **options)
    det = a.full_size(a.crack_labels) > 0
    grains = {}
    for name, poly in m["dark_grains"].items():
        mask = np.zeros(img.shape, np.uint8)
        cv2.fillPoly(mask, [np.array(poly, np.int32)], 1)
        grains[name] = float(det[mask > 0].mean())
    cover = {k: polyline_coverage(p, det, tol_px=FOUND_TOL_PX)
             for k, p in m["faint_cracks"].items()}
    return dict(dark_grain_crack_fraction=grains, crack_coverage=cover,
                n_found=int(sum(v >= FOUND_COVERAGE for v in cover.values())),
                n_marked=len(cover), n_rejected=int(len(a.rejected)),
                rejected_as=a.rejected["rejected_as"].value_counts().to_dict())


#: the Obara micrographs: (name, image, reference map, bright_cracks)
OBARA = (("dolomite_ppl", "dolomite_ppl_image12.png", "dolomite_cracks_reference_output.png",
          False),
         ("sandstone_fluorescence", "sandstone_fluorescence.png",
          "sandstone_cracks_reference_output.png", True),
         ("sandstone_fluorescence_not_inverted", "sandstone_fluorescence.png",
          "sandstone_cracks_reference_output.png", False))


def obara_scores(folder, **options):
    """Centreline agreement with the published method's crack maps on the Obara micrographs
    (a dict per image; ``folder`` is ``obara_sandstone_dolomite_cracks``)."""
    from semkit.analysis import analyse_image
    from semkit.evaluate import centreline_scores
    from semkit.io import read_image
    out = {}
    for name, image, ref, bright in OBARA:
        # scored in pixels: the pixel size (not stated) is given as 1
        a = analyse_image(read_image(folder / image), name=image, pixel_size_source="cli",
                          bright_cracks=bright, **options)
        row = a.summary()
        s = centreline_scores(a.full_size(a.crack_labels) > 0, read_image(folder / ref) > 0)
        out[name] = dict(precision=float(s["precision"]), recall=float(s["recall"]),
                         f1=float(s["f1"]), bright_cracks=bright, valid=bool(row["valid"]),
                         valid_note=row["valid_note"])
    return out


def _print_tables(label, ct, gr, ob=None):
    print(f"\n{label}\n\n| micro-CT slices | F1 median | precision | recall | "
          "length ratio median | area ratio max | valid |")
    print("|---|---|---|---|---|---|---|")
    for k, v in ct.items():
        print(f"| {k} | {v['f1_median']:.3f} | {v['precision_median']:.3f} | "
              f"{v['recall_median']:.3f} | {v['length_ratio_median']:.3f} | "
              f"{v['area_ratio_max']:.2f} | {v['valid']}/{v['n']} |")
    print("\n| granite | value |\n|---|---|")
    for k, v in gr["dark_grain_crack_fraction"].items():
        print(f"| {k}: share called crack | {v:.1%} |")
    print(f"| faint cracks found (>= {FOUND_COVERAGE:.0%} within {FOUND_TOL_PX:g} px) | "
          f"{gr['n_found']} of {gr['n_marked']} "
          f"({', '.join(f'{k} {v:.2f}' for k, v in gr['crack_coverage'].items())}) |")
    if ob:
        print("\n| Obara micrograph (agreement with the published method's map) | precision | "
              "recall | F1 | valid |\n|---|---|---|---|---|")
        for k, v in ob.items():
            print(f"| {k} | {v['precision']:.3f} | {v['recall']:.3f} | {v['f1']:.3f} | "
                  f"{v['valid']} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shared", default=None, help="the real_sem folder")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "semkit_results"))
    args = ap.parse_args(argv)
    base = shared_dir(args.shared)
    if not base.is_dir():
        print(f"real_images: {base}: no such folder (give --shared or ROCKKIT_SHARED)",
              file=sys.stderr)
        return 2
    d = microct_scores(base / "rock_microct_311H")
    ct = microct_summary(d)
    gr = granite_scores(base)
    # the same with the (opt-in) linking of faint, beaded cracks
    ct_link = microct_summary(microct_scores(base / "rock_microct_311H", link=True))
    gr_link = granite_scores(base, link=True)
    ob_dir = base / "obara_sandstone_dolomite_cracks"
    ob = obara_scores(ob_dir) if ob_dir.is_dir() else None
    ob_link = obara_scores(ob_dir, link=True) if ob_dir.is_dir() else None
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "real_images.json").write_text(json.dumps(dict(
        microct=ct, microct_slices=d.round(4).to_dict("records"), granite=gr,
        microct_linked=ct_link, granite_linked=gr_link, obara=ob, obara_linked=ob_link),
        indent=1))
    for label, c, g, o in (("default", ct, gr, ob), ("with --link", ct_link, gr_link, ob_link)):
        _print_tables(label, c, g, o)
    return 0


if __name__ == "__main__":
    sys.exit(main())
