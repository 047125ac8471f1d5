"""Benchmark: default ``semkit analyse`` on plain polyline scenes (as test images are often made).

A scene as a user might script one with NumPy and OpenCV, nothing of ``semkit.synth``: Voronoi
grains of 2-4 flat greys (90-230) with a smooth texture, in half the scenes grain boundaries
darkened by 3-15 %; 5-19 cracks drawn with ``cv2.polylines`` (2-7 segments of 15-60 px, a
random walk in direction; thickness 1-6 px) at one crack grey (10-50) over the grains; a
Gaussian blur of 0.3-1.2 px and Gaussian noise of 1-8 grey; 8 bit, 768 x 1024, 1 px = 1 um.

Truth is what was drawn: the area is the count of drawn pixels, the length the length of the
polylines (crossing and touching cracks counted each). The bent-lone-line case of
``semkit.reject`` (a crack bent through a darker grain, seed 23) was found on this family, so it
is a development family, not a held-out one. A *confidently wrong* image is valid with area or
length off by more than 25 % (``benchmarks/heldout_semkit.confidently_wrong``).

Writes ``benchmarks/semkit_results/polyline_family.json`` and prints a markdown table.

Run: ``python benchmarks/semkit_polyline_family.py [--n 24] [--jobs 2]``
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from semkit_dev_family import print_table, summarise

OUT = pathlib.Path(__file__).resolve().parent / "semkit_results"
SHAPE = (768, 1024)


def polyline_scene(seed, shape=SHAPE):
    """Scene ``seed``: ``(image uint8, truth mask, truth length px)`` (see the module doc)."""
    import cv2
    from scipy.spatial import cKDTree
    r = np.random.default_rng(seed)
    h, w = shape
    n = int(r.integers(40, 200))
    pts = r.uniform([0, 0], [w, h], (n, 2))
    yy, xx = np.mgrid[:h, :w]
    lab = cKDTree(pts).query(np.column_stack([xx.ravel(), yy.ravel()]))[1].reshape(h, w)
    greys = r.choice(r.uniform(90, 230, int(r.integers(2, 5))), n)
    img = greys[lab].astype(np.float64)
    img += cv2.GaussianBlur(r.normal(0, r.uniform(0, 8), shape), (0, 0), 2)
    if r.random() < 0.5:
        edge = (np.diff(lab, axis=0, prepend=lab[:1]) != 0) \
            | (np.diff(lab, axis=1, prepend=lab[:, :1]) != 0)
        img[edge] *= r.uniform(0.85, 0.97)
    crack = np.zeros(shape, np.uint8)
    length = 0.0
    grey = r.uniform(10, 50)
    for _ in range(int(r.integers(5, 20))):
        k = int(r.integers(2, 8))
        p = [r.uniform([50, 50], [w - 50, h - 50])]
        ang = r.uniform(0, np.pi)
        for _ in range(k):
            ang += r.normal(0, 0.3)
            p.append(p[-1] + r.uniform(15, 60) * np.array([np.cos(ang), np.sin(ang)]))
        p = np.array(p)
        p[:, 0] = np.clip(p[:, 0], 5, w - 6)
        p[:, 1] = np.clip(p[:, 1], 5, h - 6)
        cv2.polylines(crack, [np.rint(p).astype(np.int32)], False, 1, int(r.integers(1, 7)))
        length += float(np.hypot(*np.diff(p, axis=0).T).sum())
    img[crack > 0] = grey
    img = cv2.GaussianBlur(img, (0, 0), r.uniform(0.3, 1.2))
    img += r.normal(0, r.uniform(1, 8), shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), crack > 0, length


def score_image(seed):
    """Analyse scene ``seed``; its truth, semkit's numbers and the errors (a dict)."""
    from semkit.analysis import analyse_image
    img, truth, length_true = polyline_scene(seed)
    row = analyse_image(img, pixel_size_um=1.0, name=f"polyline_{seed}",
                        classify=False).summary()
    at = float(truth.sum())
    return dict(seed=seed, area_true_px=at, area_px=row["crack_area_um2"],
                area_err=row["crack_area_um2"] / at - 1, length_true_px=length_true,
                length_px=row["crack_length_um"],
                length_err=row["crack_length_um"] / length_true - 1,
                n_cracks=row["n_cracks"], valid=bool(row["valid"]),
                valid_note=row["valid_note"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=24, help="scenes (seeds 0..N-1)")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    with ProcessPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(score_image, range(args.n)))
    s = summarise(rows)
    OUT.mkdir(parents=True, exist_ok=True)
    meta = dict(machine=platform.machine(), cpus=os.cpu_count(), load=os.getloadavg())
    (OUT / "polyline_family.json").write_text(
        json.dumps(dict(meta=meta, summary=s, per_image=rows), indent=1, default=float))
    print_table(s, rows, (("area", "area"), ("length", "length")), worst=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
