"""Benchmark: where the development family's crack length is lost, by crack type and trace width.

On the 24 development images (``benchmarks/semkit_dev_family.py``, typing off) every centreline
pixel of the default analysis's accepted cracks is given to the nearest drawn crack within
``NEAR_PX`` (or to none: a false line). Per post-test type (tensile / mixed / shear):

* ``centreline_over_path`` — the centreline length given to the type's cracks over their path
  length (a layered or stepped crack's path once): whether the crack is found along its course;
* ``centreline_over_traces`` — the same over the drawn traces (each layer and step), before the
  trace count of merged layers (``n_traces``) multiplies it;
* ``counted_over_traces`` — after it, each piece times its object's ``n_traces`` (the mean
  over the object's centreline: a network's layered branch shares its count with the rest).

And per width class of the traces of the shear cracks (each a layer or a step; a mixed crack's
shear segments are left out, as its tensile segments are traces too), the share of their length
more than 1 px from every detected object (accepted or rejected): what no trace count can
recover, since nothing was outlined there.

Writes ``benchmarks/semkit_results/length_by_type.json`` and prints two markdown tables.

Run: ``python benchmarks/semkit_length_by_type.py [--jobs 2]``
"""
from __future__ import annotations

import json
import pathlib
import platform
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from semkit_dev_family import OUT, appearance  # noqa: E402
from thin_trace_contrast import SEEDS, SHAPE, map_seeds  # noqa: E402  (the family's images)

NEAR_PX = 4.0
TYPES = ("tensile", "mixed", "shear")
WIDTHS = (0.0, 1.2, 1.5, 2.0, np.inf)  #: trace width classes, px (the last open)


def measure_image(seed):
    """Centreline length per type and shear-trace length outside the objects per width class
    for development image ``seed`` (a dict of sums)."""
    import cv2

    from semkit.analysis import analyse_image
    from semkit.skeleton import skeleton_length
    from semkit.synth import make_sem_image
    s = make_sem_image(SHAPE, stage="post", seed=seed, **appearance(seed))
    a = analyse_image(s.image, pixel_size_um=s.pixel_size_um, stage="failure", classify=False)
    lab = np.asarray(a.full_size(a.crack_labels))
    sk = np.asarray(a.full_size(a.skeleton), bool) & (lab > 0)
    truth = s.crack_labels
    dist, near = cv2.distanceTransformWithLabels((truth == 0).view(np.uint8), cv2.DIST_L2, 5,
                                                 labelType=cv2.DIST_LABEL_PIXEL)
    of_pixel = np.zeros(near.max() + 1, np.int32)
    on = truth > 0
    of_pixel[near[on]] = truth[on]
    owner = np.where(dist <= NEAR_PX, of_pixel[near], 0)
    # centreline length per (true crack, object) piece: a piece's chain code stays whole
    n_obj = int(lab.max()) + 1
    key = owner.astype(np.int64) * n_obj + lab
    pieces, inv = np.unique(key[sk], return_inverse=True)
    piece_lab = np.zeros(lab.shape, np.int32)
    piece_lab[sk] = inv + 1
    length = skeleton_length(sk, piece_lab, len(pieces) + 1)[1:]
    n_truth = int(truth.max()) + 1
    per_crack = np.bincount(pieces // n_obj, weights=length, minlength=n_truth)
    factor = np.ones(n_obj)
    factor[a.cracks.crack_id.to_numpy()] = a.cracks.n_traces.to_numpy()
    counted = np.bincount(pieces // n_obj, weights=length * factor[pieces % n_obj],
                          minlength=n_truth)
    c = s.cracks
    out = {"false_px": float(per_crack[0])}
    for t in TYPES:
        ids = c.crack_id[c.type_post == t].to_numpy()
        out[t] = dict(centreline=float(per_crack[ids].sum()), counted=float(counted[ids].sum()),
                      path=float(c.length_px[c.type_post == t].sum()),
                      traces=float(c.trace_length_px[c.type_post == t].sum()))
    objects = cv2.dilate((np.asarray(a.full_size(a.labels)) > 0).view(np.uint8),
                         np.ones((3, 3), np.uint8)) > 0
    h, w = lab.shape
    missed = np.zeros(len(WIDTHS) - 1)
    total = np.zeros(len(WIDTHS) - 1)
    for cid in c.crack_id[c.type_post == "shear"]:  # every trace a layer or a step
        for t in s.traces[cid - 1]:
            if len(t) < 2:  # debris
                continue
            seg = np.hypot(*np.diff(t[:, :2], axis=0).T)
            mid = 0.5 * (t[1:, :2] + t[:-1, :2])
            r = np.clip(np.rint(mid[:, 1]).astype(int), 0, h - 1)
            q = np.clip(np.rint(mid[:, 0]).astype(int), 0, w - 1)
            k = np.searchsorted(WIDTHS, np.median(t[:, 2]), side="right") - 1
            total[k] += seg.sum()
            missed[k] += seg[~objects[r, q]].sum()
    out["shear_traces"] = dict(total=total.tolist(), missed=missed.tolist())
    return out


def summarise(per):
    """Sums over the images: the length ratios per type and the missed share per width."""
    s = {"false_centreline_px": float(sum(p["false_px"] for p in per))}
    for t in TYPES:
        cl, co, pa, tr = (sum(p[t][k] for p in per)
                          for k in ("centreline", "counted", "path", "traces"))
        s[t] = dict(centreline_px=cl, counted_px=co, path_px=pa, traces_px=tr,
                    centreline_over_path=cl / pa if pa else None,
                    centreline_over_traces=cl / tr if tr else None,
                    counted_over_traces=co / tr if tr else None)
    tot = np.sum([p["shear_traces"]["total"] for p in per], axis=0)
    mis = np.sum([p["shear_traces"]["missed"] for p in per], axis=0)
    s["shear_traces"] = [dict(width_px=[WIDTHS[i], WIDTHS[i + 1] if i + 2 < len(WIDTHS)
                                        else None], length_px=float(tot[i]),
                              missed_share=float(mis[i] / tot[i]) if tot[i] else None)
                         for i in range(len(tot))]
    return s


def main(argv=None):
    per = map_seeds(measure_image, argv, __doc__)
    s = summarise(per)
    OUT.mkdir(exist_ok=True)
    (OUT / "length_by_type.json").write_text(json.dumps(dict(
        meta=dict(seeds=list(SEEDS), shape=list(SHAPE), near_px=NEAR_PX,
                  python=platform.python_version()), summary=s), indent=1, allow_nan=False))
    print("| type | path px | traces px | centreline / path | centreline / traces | "
          "counted / traces |")
    print("|---|---|---|---|---|---|")
    for t in TYPES:
        r = s[t]
        print(f"| {t} | {r['path_px']:.0f} | {r['traces_px']:.0f} | "
              f"{r['centreline_over_path']:.3f} | {r['centreline_over_traces']:.3f} | "
              f"{r['counted_over_traces']:.3f} |")
    print(f"\ncentreline on no drawn crack: {s['false_centreline_px']:.0f} px\n")
    print("| shear-trace width, px | length px | share outside every object |")
    print("|---|---|---|")
    for r in s["shear_traces"]:
        lo, hi = r["width_px"]
        share = "—" if r["missed_share"] is None else f"{r['missed_share']:.1%}"
        print(f"| {lo:g}–{'' if hi is None else f'{hi:g}'} | {r['length_px']:.0f} | {share} |")


if __name__ == "__main__":
    main()
