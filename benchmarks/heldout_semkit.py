"""Benchmark: default ``semkit analyse`` on the held-out generator (``benchmarks/heldout``).

The held-out images come from a generator written apart from ``semkit.synth`` and never used
to tune semkit. Each image is analysed with the default options as a post-test (loaded) image,
so cracks are typed and P = A_T/A_S is reported, and compared with the exact truth:

* total crack area and skeleton length: error per image (median, max of |error|) and over the
  whole set; the area split into objects lying on true cracks (at least half their pixels
  within 2 px of one) and the others;
* P: relative error per image; how many P carry ``P_status = low_confidence``; how many
  confident P (status ``ok``) are off by more than 2x (must be none);
* crack-type accuracy by area on the pixels both truth and semkit call crack (for information;
  the typing model is not tuned on these images);
* how many images semkit marks ``valid``, and which of those are off by more than 25 % in
  area or length (confidently wrong).

Writes ``benchmarks/semkit_results/heldout_semkit.json`` and prints a markdown table.

Run: ``python benchmarks/heldout_semkit.py [--n 24] [--jobs 2] [--seed0 N]``
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "heldout"))
OUT = ROOT / "semkit_results"
TYPE_CODE = {"tensile": 1, "shear": 2, "mixed": 3}
#: an image marked valid whose area or length is off by more than this is confidently wrong
WRONG = 0.25


def score_image(seed, shape, **options):
    """Analyse one held-out image; its truth, semkit's numbers and the errors (a dict)."""
    import generator

    from semkit.analysis import analyse_image
    h = generator.make_heldout_image(shape, seed=seed)
    t0 = time.perf_counter()
    a = analyse_image(h.image, pixel_size_um=h.pixel_size_um, name=f"heldout_{seed}",
                      stage="failure", **options)
    row = a.summary()
    seconds = time.perf_counter() - t0
    px2 = h.pixel_size_um ** 2
    area = row["crack_area_um2"] / px2
    length = row["crack_length_um"] / h.pixel_size_um
    out = dict(seed=seed, shape=list(shape), seconds=seconds, megapixels=h.image.size / 1e6,
               area_true_px=h.area_px, area_px=area, area_err=area / h.area_px - 1,
               length_true_px=h.length_px, length_px=length,
               length_err=length / h.length_px - 1, P_true=h.P, P=row["P"],
               P_low=row.get("P_low", float("nan")), P_high=row.get("P_high", float("nan")),
               P_status=row.get("P_status", ""), n_cracks_true=len(h.cracks),
               n_cracks=row["n_cracks"], valid=bool(row["valid"]),
               valid_note=row["valid_note"])
    # the area of objects lying on true cracks (>= half their pixels within 2 px of one) and of
    # the others: is an area error the estimator's or the detector's?
    from scipy import ndimage as ndi
    lab = a.full_size(a.crack_labels)
    ids = a.cracks["crack_id"].to_numpy()
    near = ndi.binary_dilation(h.crack_mask, iterations=2)
    on = ndi.sum(near, lab, ids) / np.maximum(ndi.sum(lab > 0, lab, ids), 1) >= 0.5
    px = a.cracks["area_um2"].to_numpy() / px2
    out.update(area_on_cracks_px=float(px[on].sum()), area_false_px=float(px[~on].sum()),
               n_false_objects=int((~on).sum()))
    out["P_err"] = (out["P"] / out["P_true"] - 1 if np.isfinite(out["P"])
                    and np.isfinite(out["P_true"]) and out["P_true"] > 0 else float("nan"))
    c = a.typed_cracks
    if "type_post" in c:
        code = np.zeros(int(a.crack_labels.max()) + 1, int)
        code[c["crack_id"].to_numpy()] = [TYPE_CODE.get(t, 0) for t in c["type_post"]]
        tcode = np.zeros(len(h.cracks) + 1, int)
        tcode[h.cracks["crack_id"].to_numpy()] = [TYPE_CODE[t] for t in h.cracks["type"]]
        pred, true = code[a.full_size(a.crack_labels)], tcode[h.crack_labels]
        both = (pred > 0) & (true > 0)
        out["type_acc_by_area"] = float((pred[both] == true[both]).mean()) if both.any() else \
            float("nan")
    return out


def confidently_wrong(rows, key="seed"):
    """``key`` of the rows marked ``valid`` whose area or length error exceeds ``WRONG``."""
    return [r[key] for r in rows
            if r["valid"] and max(abs(r["area_err"]), abs(r["length_err"])) > WRONG]


def summarise(rows):
    ae = np.array([r["area_err"] for r in rows])
    le = np.array([r["length_err"] for r in rows])
    pe = np.array([r["P_err"] for r in rows])
    st = [r["P_status"] for r in rows]
    ok = np.array([s == "ok" for s in st])
    conf_off = [r for r, o in zip(rows, ok) if o and np.isfinite(r["P_err"])
                and max(r["P"] / r["P_true"], r["P_true"] / r["P"]) > 2]
    within = np.isfinite(pe) & (np.abs(pe) <= 0.15)
    mp = sum(r["megapixels"] for r in rows)
    return dict(
        n_images=len(rows),
        area_err_median=float(np.median(np.abs(ae))), area_err_max=float(np.abs(ae).max()),
        area_err_total=float(sum(r["area_px"] for r in rows)
                             / sum(r["area_true_px"] for r in rows) - 1),
        length_err_median=float(np.median(np.abs(le))), length_err_max=float(np.abs(le).max()),
        length_err_total=float(sum(r["length_px"] for r in rows)
                               / sum(r["length_true_px"] for r in rows) - 1),
        P_err_median=float(np.nanmedian(np.abs(pe))) if np.isfinite(pe).any() else None,
        P_err_median_confident=float(np.nanmedian(np.abs(pe[ok]))) if np.isfinite(
            pe[ok]).any() else None,
        area_on_cracks_over_true=float(sum(r["area_on_cracks_px"] for r in rows)
                                       / sum(r["area_true_px"] for r in rows)),
        area_false_over_true=float(sum(r["area_false_px"] for r in rows)
                                   / sum(r["area_true_px"] for r in rows)),
        n_valid=int(sum(r["valid"] for r in rows)),
        confidently_wrong=confidently_wrong(rows),
        n_P_within_15pct=int(within.sum()),
        n_P_low_confidence=int(sum(s == "low_confidence" for s in st)),
        n_P_within_or_flagged=int(sum(w or s == "low_confidence" for w, s in zip(within, st))),
        n_confident_P_off_2x=len(conf_off),
        n_P_band_holds_true=int(sum(bool(r["P_low"] <= r["P_true"] <= r["P_high"])
                                    for r in rows)),
        n_P_band_defined=int(sum(bool(np.isfinite([r["P_true"], r["P_low"],
                                                   r["P_high"]]).all()) for r in rows)),
        type_acc_by_area_median=float(np.nanmedian([r.get("type_acc_by_area", np.nan)
                                                    for r in rows])),
        seconds_total=float(sum(r["seconds"] for r in rows)), megapixels=mp,
        mp_per_s_per_process=mp / sum(r["seconds"] for r in rows))


def _one(args):
    seed, shape, options = args
    return score_image(seed, shape, **options)


def run(n=None, *, jobs=2, seed0=None, **options):
    import generator
    cases = generator.heldout_set(len(generator.SET_SHAPES) if n is None else n,
                                  seed0=generator.SET_SEED if seed0 is None else seed0)
    with ProcessPoolExecutor(jobs) as ex:
        rows = list(ex.map(_one, [(s, sh, options) for s, sh in cases]))
    return rows, summarise(rows)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=None, help="images (default: the 24 of the set)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--no-classify", action="store_true", help="typing off (no P)")
    ap.add_argument("--seed0", type=int, default=None,
                    help="first seed of the set (default the set's, 7000); another range gives "
                         "images no one has looked at, written to heldout_semkit_seed<N>.json")
    args = ap.parse_args(argv)
    opts = {"classify": False} if args.no_classify else {}
    rows, s = run(args.n, jobs=args.jobs, seed0=args.seed0, **opts)
    OUT.mkdir(parents=True, exist_ok=True)
    meta = dict(machine=platform.machine(), cpus=os.cpu_count(), load=os.getloadavg(),
                options=opts, seed0=args.seed0)
    name = "heldout_semkit" + ("_no_classify" if args.no_classify else "") + (
        f"_seed{args.seed0}" if args.seed0 is not None else "") + ".json"
    (OUT / name).write_text(json.dumps(dict(meta=meta, summary=s, per_image=rows), indent=1,
                                       default=float))
    print(f"load average {meta['load'][0]:.1f} (timings provisional on a shared machine)")
    print("| measure | median | max | whole set |\n|---|---|---|---|")
    print(f"| area error | {s['area_err_median']:.1%} | {s['area_err_max']:.1%} | "
          f"{s['area_err_total']:+.1%} |")
    print(f"| length error | {s['length_err_median']:.1%} | {s['length_err_max']:.1%} | "
          f"{s['length_err_total']:+.1%} |")
    if not args.no_classify:
        print(f"| P error (all / status ok) | {s['P_err_median']:.1%} / "
              f"{(s['P_err_median_confident'] or float('nan')):.1%} | | |")
        print(f"\nP within 15 %: {s['n_P_within_15pct']} of {s['n_images']}; low_confidence: "
              f"{s['n_P_low_confidence']}; within or flagged: {s['n_P_within_or_flagged']}; "
              f"confident P off by > 2x: {s['n_confident_P_off_2x']}; P band (10-90 %) holds "
              f"the true P in {s['n_P_band_holds_true']} of {s['n_P_band_defined']}; type "
              f"accuracy by area (median) {s['type_acc_by_area_median']:.2f}")
    print(f"valid: {s['n_valid']} of {s['n_images']}; confidently wrong (valid, area or length "
          f"off by > {WRONG:.0%}): {s['confidently_wrong'] or 'none'}")
    print(f"objects on true cracks: area {s['area_on_cracks_over_true']:.3f} x the true area; "
          f"other objects: {s['area_false_over_true']:.3f} x")
    print(f"{s['megapixels']:.1f} MP, {s['mp_per_s_per_process']:.2f} MP/s per process")
    return 0


if __name__ == "__main__":
    sys.exit(main())
