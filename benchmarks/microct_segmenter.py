"""Benchmark: the trainable crack segmenter on real micro-CT slices with hand-drawn masks.

Data: ``shared/real_sem/rock_microct_311H`` (40 slices 256 x 256 of one fractured core, masks
0/1 painted by hand; Apache-2.0; read in place, never copied). Found through
``ROCKKIT_SHARED`` or ``shared/real_sem`` beside the repository (``real_images.shared_dir``).

Neighbouring slices are correlated, so the 40 slices (sorted by slice number) are cut into
four contiguous blocks of 10; the segmenter is trained on one block and scored on the other 30.
Training labels come from the painted masks through ``semkit.segmenter.labels_from_mask``
(crack = painted and >= 15 % darker than the local background; not crack = > 3 px from any
painted pixel). Scoring (the data set's README): both masks skeletonised, a skeleton pixel is
found within 2 px of the other mask; precision, recall, F1 of centreline pixels and the
skeleton length ratio, per test slice; medians and minima over the 30.

The segmenter's mask is also scored at the decision levels ``SWEEP`` on P(crack) (what
``semkit analyse --segmenter-threshold`` sets), each on the same 30 slices.

Two predictions are scored: the segmenter's own mask (``P(crack) >= threshold``, isolated
specks of <= 15 px removed) and the crack objects of ``semkit analyse --segmenter`` (the
analysis with the segmenter in place of threshold and ridge lines: sample region, cleaning,
rejections).

Writes ``benchmarks/semkit_results/microct_segmenter.json`` and prints a markdown table.

Run: ``python benchmarks/microct_segmenter.py [--block auto|0-3] [--all-blocks] [--trees 50]``
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "semkit_results"
SPECK_PX = 15
#: decision levels on P(crack) scored besides the model's own (segmenter mask only)
SWEEP = (0.2, 0.3, 0.4, 0.5, 0.6)


def microct_folder():
    """The micro-CT data folder, or None when it is not on this machine."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from real_images import shared_dir
    d = shared_dir() / "rock_microct_311H"
    return d if (d / "images").is_dir() else None


def load_slices(folder):
    """(names, images, masks) sorted by slice number."""
    from semkit.io import read_image
    files = sorted((folder / "images").glob("slice_*.png"))
    names = [f.stem for f in files]
    images = [read_image(f) for f in files]
    masks = [read_image(folder / "masks" / f.name) > 0 for f in files]
    return names, images, masks


def auto_block(masks):
    """The block of 10 slices holding the most painted crack pixels (chosen from the training
    labels alone, before any scoring)."""
    return int(np.argmax([sum(m.sum() for m in masks[10 * b:10 * b + 10]) for b in range(4)]))


def predicted_mask(segmenter, grey, *, probability=None, threshold=None):
    """P(crack) >= threshold (default the segmenter's), isolated specks <= SPECK_PX removed."""
    from skimage.morphology import remove_small_objects
    p = segmenter.crack_probability(grey) if probability is None else probability
    t = segmenter.threshold if threshold is None else threshold
    return remove_small_objects(p >= t, max_size=SPECK_PX)


def run_block(block, names, images, masks, *, trees, seed=0, n_jobs=None, progress=False):
    """Train on block ``block`` (slices 10 block .. 10 block + 9), score the rest."""
    from semkit.evaluate import centreline_scores
    from semkit.segmenter import labels_from_mask, train_segmenter
    train = list(range(10 * block, 10 * block + 10))
    test = [i for i in range(len(images)) if i not in train]
    t0 = time.perf_counter()
    seg = train_segmenter([images[i] for i in train],
                          [labels_from_mask(images[i], masks[i]) for i in train],
                          names=[names[i] for i in train], n_trees=trees, n_jobs=n_jobs,
                          progress=progress, seed=seed)
    t_train = time.perf_counter() - t0
    from semkit.analysis import analyse_image
    rows, t_pred = [], 0.0
    sweep = {t: [] for t in SWEEP}
    for i in test:
        t0 = time.perf_counter()
        p = seg.crack_probability(images[i])
        pred = predicted_mask(seg, images[i], probability=p)
        t_pred += time.perf_counter() - t0
        for t in SWEEP:
            sweep[t].append(centreline_scores(predicted_mask(seg, images[i], probability=p,
                                                             threshold=t), masks[i]))
        a = analyse_image(images[i], segmenter=seg, name=names[i])
        s_an = centreline_scores(a.full_size(a.crack_labels) > 0, masks[i])
        rows.append(dict(slice=names[i], **centreline_scores(pred, masks[i]),
                         analyse_f1=s_an["f1"], analyse_precision=s_an["precision"],
                         analyse_recall=s_an["recall"]))

    def med(k):
        return float(np.median([r[k] for r in rows]))
    return seg, rows, dict(
        block=block, train_slices=[names[i] for i in train], n_test=len(test),
        median_precision=med("precision"), median_recall=med("recall"), median_f1=med("f1"),
        min_f1=float(min(r["f1"] for r in rows)), median_length_ratio=med("length_ratio"),
        analyse_median_f1=med("analyse_f1"), analyse_median_precision=med("analyse_precision"),
        analyse_median_recall=med("analyse_recall"),
        analyse_min_f1=float(min(r["analyse_f1"] for r in rows)),
        train_s=t_train, predict_mp_per_s=len(test) * images[0].size / 1e6 / t_pred,
        oob=seg.scores,
        threshold_sweep=[dict(threshold=t, **{f"median_{k}": float(np.median([r[k] for r in v]))
                                             for k in ("precision", "recall", "f1")},
                              min_f1=float(min(r["f1"] for r in v)))
                         for t, v in sweep.items()])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--block", default="auto",
                    help="training block 0-3, or auto (default): the block with the most "
                         "painted crack pixels")
    ap.add_argument("--all-blocks", action="store_true", help="train on each block in turn")
    ap.add_argument("--trees", type=int, default=50)
    ap.add_argument("--jobs", type=int, default=None, help="threads (default: all cores)")
    args = ap.parse_args(argv)
    folder = microct_folder()
    if folder is None:
        print("rock_microct_311H not found (set ROCKKIT_SHARED)", file=sys.stderr)
        return 2
    names, images, masks = load_slices(folder)
    blocks = range(4) if args.all_blocks else [auto_block(masks) if args.block == "auto"
                                               else int(args.block)]
    results = []
    for b in blocks:
        _, rows, summary = run_block(b, names, images, masks, trees=args.trees,
                                     n_jobs=args.jobs, progress=True)
        summary["per_slice"] = rows
        results.append(summary)
    OUT.mkdir(parents=True, exist_ok=True)
    meta = dict(machine=platform.machine(), cpus=os.cpu_count(), load=os.getloadavg(),
                trees=args.trees, speck_px=SPECK_PX, data=str(folder.name))
    name = "microct_segmenter_all_blocks.json" if args.all_blocks else "microct_segmenter.json"
    (OUT / name).write_text(json.dumps(dict(meta=meta, results=results), indent=1))
    print(f"load average {meta['load'][0]:.1f} (timings provisional on a shared machine)")
    print("| train block (slices) | scored | median P | median R | median F1 | min F1 | "
          "train s | predict MP/s |")
    print("|---|---|---|---|---|---|---|---|")
    for r in results:
        s = r["train_slices"]
        blk = f"{r['block']} ({s[0][6:]}-{s[-1][6:]})"
        print(f"| {blk} | segmenter mask | {r['median_precision']:.3f} | "
              f"{r['median_recall']:.3f} | {r['median_f1']:.3f} | {r['min_f1']:.3f} | "
              f"{r['train_s']:.0f} | {r['predict_mp_per_s']:.2f} |")
        print(f"| {blk} | analyse --segmenter | {r['analyse_median_precision']:.3f} | "
              f"{r['analyse_median_recall']:.3f} | {r['analyse_median_f1']:.3f} | "
              f"{r['analyse_min_f1']:.3f} | | |")
    print("\nsegmenter mask, median F1 (min) by decision level on P(crack):\n")
    print("| train block | " + " | ".join(f"{t:g}" for t in SWEEP) + " |")
    print("|---" * (len(SWEEP) + 1) + "|")
    for r in results:
        print(f"| {r['block']} | " + " | ".join(
            f"{s['median_f1']:.3f} ({s['min_f1']:.2f})" for s in r["threshold_sweep"]) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
