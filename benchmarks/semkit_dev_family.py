"""Benchmark: default ``semkit analyse`` on the development family (randomised ``semkit.synth``).

The development family is where detection changes are looked at and tried: ``semkit.synth``
post-test images whose appearance is drawn at random per image (2-4 minerals of random grey,
in 60 % of images a dark mineral at 45-75 grey, grain size, pores, noise, blur, boundary depth
0.05-0.35, crack widths, illumination ramp, 8 or 16 bit). It is the generator semkit is tuned
on, so its errors here are not a general accuracy figure: that is the held-out generator's job
(``benchmarks/heldout_semkit.py``, never tuned on). Each image is scored against its exact
truth: total crack area (partial-volume coverage) and length errors, and whether semkit flags
the image (``valid``). Length is scored against every drawn trace (``trace_length_px``: each
layer and step, as semkit measures a crack, as the drawn-crack family and the held-out
generator count it, and as a skeleton of a perfect segmentation does) and, for reference,
against the crack paths (``length_px``: a layered or stepped shear crack counted once, as
``semkit.synth``'s path counts it). A *confidently wrong* image is one marked valid whose
area or length (against the traces) is off by more than 25 %.

With ``--scene`` each image also carries scene elements the plain family lacks, drawn from
the same seed: in half the images thin satellite traces 1-4 px beside the crack walls (a
second microcrack of a crack array, or a third layer), in 40 % of them 4-20 lens-shaped grains
as dark as the cracks (organic matter, void-filled lenses), which are not cracks.

Writes ``benchmarks/semkit_results/dev_family.json`` (``dev_family_scene.json`` with
``--scene``) and prints a markdown table.

Run: ``python benchmarks/semkit_dev_family.py [--n 24] [--jobs 2] [--scene]``
"""
from __future__ import annotations

import argparse
import functools
import json
import os
import pathlib
import platform
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from heldout_semkit import WRONG, confidently_wrong  # one rule for both families

OUT = pathlib.Path(__file__).resolve().parent / "semkit_results"


def appearance(seed, scene=False):
    """The randomised ``make_sem_image`` keywords of development image ``seed``; with
    ``scene`` also its scene elements (satellite traces beside cracks in half the images,
    4-20 crack-dark lenses in 40 %), drawn after the rest so the other keys do not change."""
    r = np.random.default_rng(10_000 + seed)
    nm = int(r.integers(2, 5))
    minerals = [(f"m{i}", float(g), float(r.uniform(0.1, 0.5)))
                for i, g in enumerate(r.uniform(70, 225, nm))]
    if r.random() < 0.6:
        minerals.append(("dark", float(r.uniform(45, 75)), float(r.uniform(0.05, 0.15))))
    widths = (float(r.uniform(1, 2.5)), float(r.uniform(4, 10)))
    a = dict(minerals=minerals, gradient=float(r.choice([1.0, r.uniform(1.2, 2.5)])),
             n_pores=int(r.integers(0, 25)), noise_sigma=float(r.uniform(2, 12)),
             blur_sigma=float(r.uniform(0.4, 1.4)),
             boundary_depth=float(r.uniform(0.05, 0.35)), bit_depth=int(r.choice([8, 16])),
             widths=widths, mean_grain_px=float(r.uniform(50, 160)))
    if scene:  # drawn after the rest: the keys above stay as they were
        a.update(satellite=float(r.uniform(0.2, 0.6)) if r.random() < 0.5 else 0.0,
                 n_lenses=int(r.integers(4, 21)) if r.random() < 0.4 else 0)
    return a


def score_image(seed, shape=(768, 1024), scene=False):
    """Analyse development image ``seed`` (with its scene elements when ``scene``); its
    truth, semkit's numbers and the errors."""
    from semkit.analysis import analyse_image
    from semkit.synth import make_sem_image
    s = make_sem_image(shape, stage="post", seed=seed, **appearance(seed, scene=scene))
    row = analyse_image(s.image, pixel_size_um=s.pixel_size_um, name=f"dev_{seed}",
                        stage="failure", classify=False).summary()
    area = row["crack_area_um2"] / s.pixel_size_um ** 2
    length = row["crack_length_um"] / s.pixel_size_um
    at, lt = float(s.cracks["area_cov_px"].sum()), float(s.cracks["length_px"].sum())
    tt = float(s.cracks["trace_length_px"].sum())
    return dict(seed=seed, area_true_px=at, area_px=area, area_err=area / at - 1,
                length_true_px=tt, length_px=length, length_err=length / tt - 1,
                path_length_true_px=lt, path_length_err=length / lt - 1,
                n_cracks_true=len(s.cracks), n_cracks=row["n_cracks"],
                valid=bool(row["valid"]), valid_note=row["valid_note"])


def summarise(rows, measures=("area", "length")):
    """Counts and, per measure ``k`` of ``measures`` (rows hold ``k + "_err"``), the median
    |error| over all and over valid images and the signed median."""
    ok = np.array([r["valid"] for r in rows])
    s = dict(n_images=len(rows), n_valid=int(ok.sum()))
    for k in measures:
        e = np.array([r[f"{k}_err"] for r in rows])
        s.update({f"{k}_err_median": float(np.median(np.abs(e))),
                  f"{k}_err_signed_median": float(np.median(e)),
                  f"{k}_err_median_valid": float(np.median(np.abs(e[ok]))) if ok.any()
                  else None})
    s["confidently_wrong"] = confidently_wrong(rows)
    return s


def print_table(s, rows, measures, *, worst=False, note=""):
    """The markdown table of :func:`summarise`'s ``s``: a row per ``(label, measure)`` of
    ``measures``; with ``worst`` the largest |error| of a valid image too. Then the valid
    count and the confidently wrong images, after ``note``."""
    def pct(v, sign=""):
        return "—" if v is None else f"{v:{sign}.1%}"
    ok = [r for r in rows if r["valid"]]
    cols = ["measure", "median |error| (all)", "median |error| (valid)", "signed median"]
    cols += ["max (valid)"] if worst else []
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for label, k in measures:
        cells = [label, pct(s[f"{k}_err_median"]), pct(s[f"{k}_err_median_valid"]),
                 pct(s[f"{k}_err_signed_median"], "+")]
        if worst:
            cells.append(pct(max((abs(r[f"{k}_err"]) for r in ok), default=None)))
        print("| " + " | ".join(cells) + " |")
    print(f"\n{note}valid: {s['n_valid']} of {s['n_images']}; confidently wrong (valid, off "
          f"by > {WRONG:.0%}): {s['confidently_wrong'] or 'none'}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=24, help="images (seeds 1..N)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--scene", action="store_true",
                    help="add the scene elements (satellite traces, crack-dark lenses); "
                         "writes dev_family_scene.json")
    args = ap.parse_args(argv)
    with ProcessPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(functools.partial(score_image, scene=args.scene),
                           range(1, args.n + 1)))
    s = summarise(rows, ("area", "length", "path_length"))
    OUT.mkdir(parents=True, exist_ok=True)
    meta = dict(machine=platform.machine(), cpus=os.cpu_count(), load=os.getloadavg())
    name = "dev_family_scene.json" if args.scene else "dev_family.json"
    (OUT / name).write_text(json.dumps(dict(meta=meta, summary=s, per_image=rows), indent=1,
                                       default=float))
    print_table(s, rows, (("area", "area"), ("length (drawn traces)", "length"),
                          ("length (crack paths)", "path_length")))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
