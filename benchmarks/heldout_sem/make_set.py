"""Write a set of synthetic SEM images and truth.csv.

Usage: python make_set.py OUTDIR --n 40 --seed0 0
Two thirds of the images are 768x1024, one third 1536x2048.
"""
# ruff: noqa: E501  (kept as written apart from semkit)
import argparse
import csv
import os
import sys

import cv2

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sem_generator import make_image  # noqa: E402


def main():
    """Parse arguments, generate the images and write truth.csv."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('outdir')
    ap.add_argument('--n', type=int, default=40)
    ap.add_argument('--seed0', type=int, default=0)
    a = ap.parse_args()
    os.makedirs(a.outdir, exist_ok=True)
    cols = ['image', 'seed', 'height', 'width', 'pixel_size_um', 'area_px', 'length_px', 'P',
            'n_cracks', 'tensile_area_px', 'shear_area_px', 'has_bar']
    with open(os.path.join(a.outdir, 'truth.csv'), 'w', newline='') as fh:
        wr = csv.DictWriter(fh, fieldnames=cols)
        wr.writeheader()
        for i in range(a.n):
            seed = a.seed0 + i
            shape = (1536, 2048) if i % 3 == 2 else (768, 1024)
            r = make_image(shape, seed)
            ext = 'tif' if r['image'].dtype.itemsize == 2 else 'png'
            name = f'img_{i:03d}.{ext}'
            if not cv2.imwrite(os.path.join(a.outdir, name), r['image']):
                raise IOError(name)
            wr.writerow(dict(image=name, seed=seed, height=shape[0], width=shape[1],
                             pixel_size_um=f"{r['pixel_size_um']:.6f}",
                             area_px=f"{r['area_px']:.3f}", length_px=f"{r['length_px']:.3f}",
                             P=f"{r['P']:.5f}", n_cracks=len(r['cracks']),
                             tensile_area_px=f"{sum(c['tensile_area_px'] for c in r['cracks']):.3f}",
                             shear_area_px=f"{sum(c['shear_area_px'] for c in r['cracks']):.3f}",
                             has_bar=int(r['settings']['bar'])))
            print(name, shape, len(r['cracks']), f"area={r['area_px']:.0f} len={r['length_px']:.0f}",
                  flush=True)


if __name__ == '__main__':
    main()
