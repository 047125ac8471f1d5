"""Benchmark: default ``semkit analyse`` on the drawn-crack family (other crack morphologies).

The scenes are the ``drawn`` renderings of the crack-typing training family
(``benchmarks/typing/render.py``, settings ``TRAIN``) at 768 x 1024 with 14-24 cracks: a
crack-free ``semkit.synth`` background with cracks drawn from centrelines in morphologies
``semkit.synth`` does not have: tensile openings of constant aperture with matching walls and
tapered tips; shear traces that are stepped (en-echelon pieces, linked or overlapping),
layered (2-3 thin parallel traces 2.5-6 px apart) or offset (beaded), with dark chips
alongside, bright debris inside and closures; mixed cracks changing from one to the other.
The ``phase_edge`` rejection rule was set on it (both settings, see below); nothing else in
detection and measurement was tuned on it, so it checks how the development family's accuracy
carries over to other morphologies.

Each image is scored against its exact truth: total area (the coverage sum, chips and debris
included) and length in two conventions, since a layered or stepped shear crack is one crack
path drawn as several traces:

* ``length_err``: against every drawn trace (each layer, step and link; the stretches closed
  by closures are not drawn and do not count): the visible cracks;
* ``path_length_err``: against the crack paths, each crack once as ``semkit.synth`` counts
  it, closed stretches included (so it counts length no image shows).

Also the centreline recall and precision of the detected objects against the coverage
(``semkit.evaluate.centreline_scores``, 2 px): recall says how much of the drawn cracks was
found at all. A *confidently wrong* image is valid with area or length (traces) off by more
than 25 % (``benchmarks/heldout_semkit.confidently_wrong``).

Writes ``benchmarks/semkit_results/drawn_family.json`` and prints a markdown table.

Run: ``python benchmarks/semkit_drawn_family.py [--n 16] [--jobs 2]``
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from semkit_dev_family import print_table, summarise

ROOT = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "typing"))
OUT = ROOT / "semkit_results"
SHAPE = (768, 1024)
#: scene seeds start here (apart from the typing model's training and calibration seeds)
SEED0 = 50_000


def family(settings="train"):
    """The rendering settings: the typing family's ``TRAIN`` (or ``HELDOUT``) settings, more
    cracks for the larger frame."""
    import render
    base = render.HELDOUT if settings == "heldout" else render.TRAIN
    return dict(base, n_cracks=(14, 24), drawn_share=1.0)


def paint_laths(image, keep_out, n, rng, *, blur, crack_grey, share=(0.35, 0.6),
                noise=0.0, size=((30, 100), (5, 12))):
    """``image`` with ``n`` dark laths (not cracks): rectangles of ``size`` (length, width
    ranges, px) at random angles, outside ``keep_out``, blurred by ``blur`` px, at a grey a
    share drawn from ``share`` of the way from ``crack_grey`` (8-bit units) to the rock around
    them (a 15-px median), with ``noise`` grey of noise on them."""
    import cv2
    from scipy import ndimage as ndi
    scale = 257.0 if image.dtype == np.uint16 else 1.0
    g = image.astype(np.float64) / scale
    lath = np.zeros(image.shape, np.float32)
    placed = tries = 0
    while placed < n and tries < 20 * n:
        tries += 1
        cy, cx = rng.uniform(30, image.shape[0] - 30), rng.uniform(30, image.shape[1] - 30)
        box = cv2.boxPoints(((cx, cy), (rng.uniform(*size[0]), rng.uniform(*size[1])),
                             rng.uniform(0, 180))).astype(np.int32)
        m = np.zeros(image.shape, np.uint8)
        cv2.fillPoly(m, [box], 1)
        if (m.view(bool) & keep_out).any():
            continue
        np.maximum(lath, m.astype(np.float32), out=lath)
        placed += 1
    lath = ndi.gaussian_filter(lath, blur)
    grey = crack_grey + rng.uniform(*share) * (ndi.median_filter(g, 15) - crack_grey)
    g = g * (1 - lath) + (grey + rng.normal(0, noise, g.shape)) * lath
    top = 65535 if scale > 1 else 255
    return np.clip(np.rint(g * scale), 0, top).astype(image.dtype)


def add_laths(image, truth, n, seed):
    """``image`` with ``n`` dark laths (not cracks, :func:`paint_laths`): 30-100 x 5-12 px,
    away from the cracks, blurred like them, at a grey 35-60 % of the way from the crack grey
    to the rock around them (a dark mineral's laths, e.g. biotite), with a third of the
    image's noise on them."""
    from scipy import ndimage as ndi
    st = truth["settings"]
    keep_out = ndi.binary_dilation(truth["coverage"] > 0, iterations=6)
    return paint_laths(image, keep_out, n, np.random.default_rng(seed), blur=st["blur"],
                       crack_grey=st["crack_grey"], noise=st["noise"] / 3)


def score_image(k, settings="train", laths=0):
    """Analyse drawn scene ``k``; its truth, semkit's numbers and the errors (a dict)."""
    import render

    from semkit.analysis import analyse_image
    from semkit.evaluate import centreline_scores
    image, truth = render.drawn_scene(SHAPE, family(settings), seed=SEED0 + k)
    if laths:
        image = add_laths(image, truth, laths, seed=k)
    a = analyse_image(image, pixel_size_um=1.0, name=f"drawn_{k}", stage="failure",
                      classify=False)
    row = a.summary()
    cov = truth["coverage"]
    at = float(cov.sum())
    lp, lt = truth["path_length_px"], truth["trace_length_px"]
    sc = centreline_scores(a.crack_labels > 0, cov >= 0.5)
    st = truth["settings"]
    return dict(seed=SEED0 + k, area_true_px=at, area_px=row["crack_area_um2"],
                area_err=row["crack_area_um2"] / at - 1, length_true_px=lt,
                path_length_true_px=lp, length_px=row["crack_length_um"],
                length_err=row["crack_length_um"] / lt - 1,
                path_length_err=row["crack_length_um"] / lp - 1,
                recall=sc["recall"], precision=sc["precision"], n_cracks=row["n_cracks"],
                valid=bool(row["valid"]), valid_note=row["valid_note"],
                noise=st["noise"], blur=st["blur"], crack_grey=st["crack_grey"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=16, help="scenes (seeds SEED0 .. SEED0 + N - 1)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--laths", type=int, default=0,
                    help="add this many dark laths (not cracks) to each scene")
    ap.add_argument("--settings", choices=["train", "heldout"], default="train",
                    help="the typing family's settings to render with (heldout: noise 7-10, "
                         "blur 0.9-1.3 px, 2-3x gradient, grains 20-40 px, crack grey 40-60)")
    args = ap.parse_args(argv)
    with ProcessPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(score_image, range(args.n), [args.settings] * args.n,
                           [args.laths] * args.n))
    s = summarise(rows, ("area", "length", "path_length"))
    s.update(recall_median=float(np.median([r["recall"] for r in rows])),
             precision_median=float(np.median([r["precision"] for r in rows])))
    OUT.mkdir(parents=True, exist_ok=True)
    meta = dict(machine=platform.machine(), cpus=os.cpu_count(), load=os.getloadavg(),
                shape=SHAPE, seed0=SEED0, settings=args.settings, laths=args.laths,
                family=family(args.settings))
    name = "drawn_family" + ("" if args.settings == "train" else "_heldout") \
        + (f"_laths{args.laths}" if args.laths else "") + ".json"
    (OUT / name).write_text(json.dumps(dict(meta=meta, summary=s, per_image=rows),
                                                      indent=1, default=float))
    print_table(s, rows, (("area", "area"), ("length (drawn traces)", "length"),
                          ("length (crack paths)", "path_length")),
                note=f"centreline recall {s['recall_median']:.3f}, precision "
                     f"{s['precision_median']:.3f} (median); ")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
