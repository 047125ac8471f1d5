"""Write a gen3 blind test set of synthetic SEM rock micrographs with crack truth.

Usage::

    python make_set.py OUTDIR --n 40 --seed0 0 [--settings]

Image ``i`` uses seed ``seed0 + i``; two thirds of the images are 768 x 1024
(H x W) and every third one (``i % 3 == 2``) is 1536 x 2048.  Images are
written with ``cv2.imwrite`` as ``img_000.png`` (8-bit) or ``img_000.tif``
(16-bit).  ``truth.csv`` has the columns::

    image,seed,height,width,pixel_size_um,area_px,length_px,P,n_cracks,
    tensile_area_px,shear_area_px,has_bar

``P`` is ``nan`` when there is no shear area; ``has_bar`` is 1 or 0.  Truth
areas / lengths refer to the image rows above the information bar.  With
``--settings`` a ``settings.jsonl`` with the randomised appearance settings
of every image is written as well.
"""
# ruff: noqa: E501
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gen3_generator import make_image  # noqa: E402

COLUMNS = ["image", "seed", "height", "width", "pixel_size_um", "area_px", "length_px", "P", "n_cracks",
           "tensile_area_px", "shear_area_px", "has_bar"]


def image_shape(i):
    """Shape (H, W) of the i-th image of a set."""
    return (1536, 2048) if i % 3 == 2 else (768, 1024)


def _f(x, nd=4):
    """Format a float for the CSV ('nan' for NaN)."""
    return "nan" if (x is None or (isinstance(x, float) and math.isnan(x))) else f"{x:.{nd}f}"


def main(argv=None):
    """Generate the set; returns the process exit code."""
    ap = argparse.ArgumentParser(description="Write a gen3 synthetic SEM crack test set.")
    ap.add_argument("outdir")
    ap.add_argument("--n", type=int, default=40, help="number of images")
    ap.add_argument("--seed0", type=int, default=0, help="seed of the first image")
    ap.add_argument("--settings", action="store_true", help="also write settings.jsonl")
    a = ap.parse_args(argv)
    os.makedirs(a.outdir, exist_ok=True)
    rows = []
    settings = []
    for i in range(a.n):
        seed = a.seed0 + i
        H, W = image_shape(i)
        t0 = time.time()
        r = make_image((H, W), seed)
        ext = ".tif" if r["image"].dtype == np.uint16 else ".png"
        name = f"img_{i:03d}{ext}"
        if not cv2.imwrite(os.path.join(a.outdir, name), r["image"]):
            raise RuntimeError(f"could not write {name}")
        rows.append({
            "image": name, "seed": seed, "height": H, "width": W,
            "pixel_size_um": f"{r['pixel_size_um']:.6g}", "area_px": _f(r["area_px"]),
            "length_px": _f(r["length_px"]), "P": _f(r["P"], 6), "n_cracks": int(r["n_cracks"]),
            "tensile_area_px": _f(r["tensile_area_px"]), "shear_area_px": _f(r["shear_area_px"]),
            "has_bar": int(bool(r["has_bar"])),
        })
        settings.append({"image": name, **r["settings"]})
        print(f"{name}: {H}x{W} {r['settings']['rock']:<9s} {r['image'].dtype} n_cracks={r['n_cracks']:3d} "
              f"area={r['area_px']:9.1f} length={r['length_px']:8.1f} P={r['P']:.3f} bar={int(r['has_bar'])} "
              f"({time.time() - t0:.2f} s)", flush=True)
    with open(os.path.join(a.outdir, "truth.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    if a.settings:
        with open(os.path.join(a.outdir, "settings.jsonl"), "w") as f:
            for s in settings:
                f.write(json.dumps(s, default=float) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
