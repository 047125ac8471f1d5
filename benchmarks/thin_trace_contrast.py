"""Benchmark: are the thin traces semkit misses separable from grain boundaries by line contrast?

On the 24 development images (``benchmarks/semkit_dev_family.py``), every drawn trace at most
1.5 px wide (median width) is sampled every px and called *found* when the default analysis's
centreline passes within 2 px, else *missed*; the grain-boundary pixels of the rendering more
than 4 px from any crack are the third class. At each point (the maximum in its 3 x 3 box, as
a trace's drawn position and the response's peak may differ by a pixel) three measures are
read on the denoised image the analysis uses:

* ``ridge_snr`` — the per-pixel ridge response in its noise units
  (:func:`semkit.ridge.ridge_response`; seeds need 8, the hysteresis low level is 4);
* ``line_snr`` — the oriented line response, the valley strength averaged along the line
  under a Gaussian of sigma 8 px (:func:`semkit.link.line_response`), in its noise units:
  what a filter that integrates along the line gains;
* ``depth`` — depth below the local background as a share of the crack contrast
  (:func:`semkit.ridge.ridge_mask`; seeds need 0.2).

The table gives each class's quartiles and, for a few levels of the line response and depth,
the number of points of each class that pass: how many missed-trace points a line-response
stage would recover for how many grain-boundary points it would take in with them.

Writes ``benchmarks/semkit_results/thin_trace_contrast.json`` and prints a markdown table.

Run: ``python benchmarks/thin_trace_contrast.py [--jobs 2]``
"""
from __future__ import annotations

import argparse
import json
import pathlib
import platform
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from semkit_dev_family import appearance  # noqa: E402

OUT = pathlib.Path(__file__).resolve().parent / "semkit_results"
SHAPE = (768, 1024)
SEEDS = range(1, 25)  #: the development family's default set
THIN_PX = 1.5
CLASSES = ("thin_found", "thin_missed", "boundary")
LEVELS = ((4.0, 0.2), (6.0, 0.2), (6.0, 0.3), (8.0, 0.3))


def measure_image(seed):
    """Per class, the (ridge_snr, line_snr, depth) of every point of development image
    ``seed`` (a dict of (n, 3) float arrays)."""
    import cv2

    from semkit.analysis import analyse_image
    from semkit.link import line_response
    from semkit.ridge import ridge_mask, ridge_response
    from semkit.synth import make_sem_image
    s = make_sem_image(SHAPE, stage="post", seed=seed, **appearance(seed))
    a = analyse_image(s.image, pixel_size_um=s.pixel_size_um, stage="failure", classify=False)
    sm = np.ascontiguousarray(a.smooth, np.float32)
    r, noise = ridge_response(sm)
    _, depth = ridge_mask(sm, crack_level=a.thresholded.crack_level)
    lr, lnoise = line_response(sm)
    box = np.ones((3, 3), np.uint8)
    fields = [cv2.dilate(x, box) for x in (r / noise, lr / lnoise, depth)]
    near = cv2.dilate((np.asarray(a.skeleton) > 0).view(np.uint8), np.ones((5, 5), np.uint8))
    thin = np.zeros(SHAPE, np.uint8)
    cracks = s.crack_mask.astype(np.uint8)
    for traces in s.traces:
        for t in traces:
            pts = np.round(t[:, :2]).astype(np.int32)
            cv2.polylines(cracks, [pts], False, 1, 1)
            if np.median(t[:, 2]) <= THIN_PX:
                cv2.polylines(thin, [pts], False, 1, 1)
    far = cv2.dilate(cracks, np.ones((9, 9), np.uint8)) == 0
    masks = dict(thin_found=(thin > 0) & (near > 0), thin_missed=(thin > 0) & (near == 0),
                 boundary=s.boundary_mask.astype(bool) & far)
    return {k: np.stack([f[m] for f in fields], 1) for k, m in masks.items()}


def summarise(points):
    """Quartiles per class and measure, and the points passing each level of ``LEVELS``."""
    out = {}
    for k in CLASSES:
        p = points[k]
        out[k] = dict(n=int(len(p)), **{
            name: np.round(np.quantile(p[:, i], (0.25, 0.5, 0.75)), 3).tolist()
            for i, name in enumerate(("ridge_snr", "line_snr", "depth"))})
    out["passing"] = [dict(line_snr=a, depth=d, **{
        k: int(np.sum((points[k][:, 1] > a) & (points[k][:, 2] > d))) for k in CLASSES})
        for a, d in LEVELS]
    return out


def map_seeds(measure, argv=None, doc=__doc__):
    """``measure(seed)`` for every development image, on ``--jobs`` processes (the command
    line ``argv`` of a benchmark whose docstring is ``doc``)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    with ProcessPoolExecutor(args.jobs) as ex:
        return list(ex.map(measure, SEEDS))


def main(argv=None):
    per = map_seeds(measure_image, argv)
    points = {k: np.concatenate([p[k] for p in per]) for k in CLASSES}
    s = summarise(points)
    OUT.mkdir(exist_ok=True)
    (OUT / "thin_trace_contrast.json").write_text(json.dumps(dict(
        meta=dict(seeds=list(SEEDS), shape=list(SHAPE), thin_px=THIN_PX,
                  python=platform.python_version()), summary=s), indent=1))
    print("| class | points | ridge SNR (quartiles) | line SNR (quartiles) | depth (quartiles) |")
    print("|---|---|---|---|---|")
    for k in CLASSES:
        c = s[k]
        print(f"| {k} | {c['n']} | " + " | ".join(" / ".join(f"{v:.2f}" for v in c[m])
                                                   for m in ("ridge_snr", "line_snr", "depth"))
              + " |")
    print("\n| line SNR > | depth > | thin found | thin missed | boundary |")
    print("|---|---|---|---|---|")
    for row in s["passing"]:
        print(f"| {row['line_snr']:g} | {row['depth']:g} | {row['thin_found']} | "
              f"{row['thin_missed']} | {row['boundary']} |")


if __name__ == "__main__":
    main()
