"""Benchmark: default ``semkit analyse`` on development images under imaging conditions it was
not tuned for — does it stay right, and where it does not, does it say so?

Nine development-family images (``benchmarks/semkit_dev_family.py``: randomised
``semkit.synth`` appearance; seeds 0, 1, 4, 5, 11, 14, 19, 21, 23) are rendered again or
altered as a microscope or a file format would, one condition at a time:

* ``noise 24``, ``noise 30`` — Gaussian pixel noise raised to 24 / 30 grey (the family draws
  2-12);
* ``shot noise`` — Poisson noise of 4 grey units per count (signal-dependent; sigma ~24 at
  grey 150);
* ``scan lines`` — row-to-row grey offsets of 5 grey (sigma), as a raster scan makes;
* ``crack grey 55``, ``crack grey 80`` — epoxy-filled cracks lighter than the void grey 30 the
  generator uses;
* ``saturated`` — grey x1.4 and clipped at the top (a bright mineral saturates);
* ``bright walls`` — a bright rim of a quarter of the grey range along every crack wall (the
  edge effect of secondary-electron images);
* ``JPEG 50`` — saved as JPEG at quality 50 (8 bit);
* ``half size`` — shrunk by 2 (a lower magnification: cracks 1-4 px wide);
* ``float 0..1``, ``signed`` — the same pixels as float32 in 0..1, and as int16 shifted by
  -100.

Each image is scored against its exact truth (crack area by partial-volume coverage; length
of every drawn trace, each layer and step of a shear crack, as semkit measures a crack, and
for reference of the crack paths, a layered crack once; for ``half size`` the truth in the
original pixels). A *confidently wrong* image is marked ``valid`` but off by more than 25 % in
area or length (against the traces). These conditions were chosen to find failures, and some
of semkit's rules were set on them (the noise units and flag, scan lines, saturation, the
working grey scale): the table shows what each condition does and whether semkit flags it,
not an accuracy for unseen images.

Writes ``benchmarks/semkit_results/stress.json`` and prints a markdown table.

Run: ``python benchmarks/semkit_stress.py [--jobs 2]``
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
from heldout_semkit import WRONG  # noqa: E402  (one rule for every family)

OUT = pathlib.Path(__file__).resolve().parent / "semkit_results"
SEEDS = (0, 1, 4, 5, 11, 14, 19, 21, 23)
CONDITIONS = ("none", "noise 24", "noise 30", "shot noise", "scan lines", "crack grey 55",
              "crack grey 80", "saturated", "bright walls", "JPEG 50", "half size", "float 0..1",
              "signed")


def _scene(seed, condition):
    """The development scene ``seed`` rendered for ``condition`` (its truth unchanged)."""
    from semkit_dev_family import appearance

    from semkit.synth import make_sem_image
    ap = appearance(seed)
    if condition.startswith("noise "):
        ap["noise_sigma"] = float(condition.split()[1])
    if condition.startswith("crack grey"):
        ap["crack_grey"] = float(condition.split()[2])
    return make_sem_image((768, 1024), stage="post", seed=seed, **ap)


def _alter(s, seed, condition):
    """The image of ``s`` as the condition makes it, and the factor on the pixel size."""
    import cv2
    img = s.image
    top = 255.0 if img.dtype == np.uint8 else 65535.0
    rng = np.random.default_rng(seed)
    a = img.astype(np.float64)
    if condition == "shot noise":
        a = rng.poisson(a / top * 255.0 / 4.0) * 4.0 * top / 255.0
    elif condition == "scan lines":
        a = a + rng.normal(0.0, 5.0 * top / 255.0, (a.shape[0], 1))
    elif condition == "saturated":
        a = a * 1.4
    elif condition == "bright walls":
        m = (s.crack_labels > 0).astype(np.uint8)
        ring = cv2.dilate(m, np.ones((5, 5), np.uint8)).astype(bool) & (m == 0)
        a = a + cv2.GaussianBlur(ring.astype(np.float32), (0, 0), 1.0) * 0.25 * top
    elif condition in ("JPEG 50", "half size"):
        g8 = np.clip(np.rint(a / top * 255.0), 0, 255).astype(np.uint8)
        if condition == "JPEG 50":
            return cv2.imdecode(cv2.imencode(".jpg", g8, [cv2.IMWRITE_JPEG_QUALITY, 50])[1],
                                cv2.IMREAD_GRAYSCALE), 1.0
        return cv2.resize(g8, (g8.shape[1] // 2, g8.shape[0] // 2),
                          interpolation=cv2.INTER_AREA), 2.0
    elif condition == "float 0..1":
        return (a / top).astype(np.float32), 1.0
    elif condition == "signed":
        g8 = np.clip(np.rint(a / top * 255.0), 0, 255)
        return (g8 - 100).astype(np.int16), 1.0
    return np.clip(np.rint(a), 0, top).astype(img.dtype), 1.0


def score(args):
    """Analyse development image ``seed`` under ``condition``; errors and the flags."""
    seed, condition = args
    from semkit.analysis import analyse_image
    s = _scene(seed, condition)
    img, f = _alter(s, seed, condition)
    row = analyse_image(img, pixel_size_um=s.pixel_size_um * f, name=f"{condition}_{seed}",
                        stage="failure", classify=False).summary()
    px2 = s.pixel_size_um ** 2
    area = row["crack_area_um2"] / px2 / float(s.cracks["area_cov_px"].sum()) - 1
    length = row["crack_length_um"] / s.pixel_size_um
    return dict(seed=seed, condition=condition, area_err=area,
                length_err=length / float(s.cracks["trace_length_px"].sum()) - 1,
                path_length_err=length / float(s.cracks["length_px"].sum()) - 1,
                valid=bool(row["valid"]), valid_note=row["valid_note"],
                contrast_to_noise=row["contrast_to_noise"], n_cracks=int(row["n_cracks"]))


def summarise(rows):
    out = {}
    for c in CONDITIONS:
        r = [x for x in rows if x["condition"] == c]
        wrong = [x["seed"] for x in r if x["valid"] and max(abs(x["area_err"]),
                                                             abs(x["length_err"])) > WRONG]
        out[c] = dict(area_err_median=float(np.median([abs(x["area_err"]) for x in r])),
                      length_err_median=float(np.median([abs(x["length_err"]) for x in r])),
                      path_length_err_median=float(np.median([abs(x["path_length_err"])
                                                              for x in r])),
                      n=len(r), n_valid=sum(x["valid"] for x in r), confidently_wrong=wrong)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    tasks = [(s, c) for c in CONDITIONS for s in SEEDS]
    with ProcessPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(score, tasks))
    summary = summarise(rows)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "stress.json").write_text(json.dumps(dict(
        meta=dict(seeds=SEEDS, machine=platform.machine()), summary=summary,
        per_image=rows), indent=1, default=float))
    print(f"| condition | area error, median | length error, median (traces; paths) "
          f"| valid (of {len(SEEDS)}) | confidently wrong (off by > {WRONG:.0%}, valid) |")
    print("|---|---|---|---|---|")
    for c, v in summary.items():
        print(f"| {c} | {v['area_err_median']:.1%} | {v['length_err_median']:.1%}; "
              f"{v['path_length_err_median']:.1%} | {v['n_valid']} | "
              f"{', '.join(map(str, v['confidently_wrong'])) or 'none'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
