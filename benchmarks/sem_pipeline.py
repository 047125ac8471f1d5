"""Benchmark: speed of the SEM crack pipeline beside the error it reaches (issue #2).

20 seeded synthetic images (10 at 1024 x 768, 10 at 2048 x 1536; cracks 2-8 px wide; every
other image with a 2.5x illumination gradient) are written as PNG with their ground truth. Then
for ``auto`` and for ``otsu`` (both with illumination flattening, cleaning, labelling,
skeleton and length):

* ``compute``: images decoded in memory, the pipeline timed per image in ``--jobs`` worker
  processes; megapixels/s = total MP / wall time of the parallel run; also per core from the
  workers' CPU time (``time.process_time``), which a busy shared machine does not inflate;
* ``end_to_end``: ``semkit.analyse_folder`` on the PNG folder (decode, CSVs, no overlays),
  megapixels/s = total MP / wall time;

with the total crack area and length errors against the truth (median and max |error|).
Writes ``benchmarks/results/sem_pipeline.json`` and prints a markdown table.

Run: ``python benchmarks/sem_pipeline.py [--jobs 2] [--quick]``
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd

SIZES = [(768, 1024)] * 10 + [(1536, 2048)] * 10
SEED0 = 1000


def _make(k, shape, folder):
    from semkit.io import write_image
    from semkit.synth import make_sem_image
    s = make_sem_image(shape, stage="pre", widths=(2.0, 8.0), gradient=2.5 if k % 2 else 1.0,
                       n_cracks=int(30 * shape[0] * shape[1] / 786432), seed=SEED0 + k)
    name = f"img_{k:02d}.png"
    write_image(pathlib.Path(folder) / name, s.image)
    return dict(image=name, height=shape[0], width=shape[1], gradient=2.5 if k % 2 else 1.0,
                area_px=s.crack_area_px, length_px=s.crack_length_px)


def _warm(_):
    import cv2
    cv2.setNumThreads(1)

    from semkit.analysis import analyse_image
    img = np.full((96, 128), 180, np.uint8)
    img[40:44, 10:110] = 30
    analyse_image(img).summary()
    return os.getpid()


def _run_one(args):
    path, method = args
    from semkit.analysis import analyse_image
    from semkit.io import read_image
    img = read_image(path)
    t0, c0 = time.perf_counter(), time.process_time()
    a = analyse_image(img, threshold=method)
    c = a.cracks
    a.summary()
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    return (pathlib.Path(path).name, dt, dc, float(c["area_px"].sum()),
            float(c["length_px"].sum()))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="4 small + 2 large images")
    ap.add_argument("--out", default=str(pathlib.Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    sizes = SIZES[:4] + SIZES[10:12] if args.quick else SIZES
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="semkit_bench_"))
    t0 = time.perf_counter()
    import multiprocessing as mp
    ctx = mp.get_context("forkserver")
    with ProcessPoolExecutor(max_workers=args.jobs, mp_context=ctx) as ex:
        truth = pd.DataFrame(list(ex.map(_make, range(len(sizes)), sizes, [tmp] * len(sizes))))
    print(f"generated {len(truth)} images in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    mp = truth.height * truth.width / 1e6
    total_mp = float(mp.sum())
    results = {}
    with ProcessPoolExecutor(max_workers=args.jobs, mp_context=ctx) as ex:
        list(ex.map(_warm, range(4 * args.jobs)))  # compile / load numba caches in every worker
        for method in ("auto", "otsu"):
            paths = [(str(tmp / n), method) for n in truth.image]
            t1 = time.perf_counter()
            out = list(ex.map(_run_one, paths))
            wall = time.perf_counter() - t1
            r = pd.DataFrame(out, columns=["image", "seconds", "cpu_s", "area_px", "length_px"])
            r = r.merge(truth, on="image")
            ea = r["area_px_x"] / r["area_px_y"] - 1
            el = r["length_px_x"] / r["length_px_y"] - 1
            per_mp = r.seconds / (r.height * r.width / 1e6)
            results[method] = dict(
                compute_mp_per_s=total_mp / wall, wall_s=wall,
                single_core_mp_per_s=float(1.0 / per_mp.median()),
                cpu_mp_per_s_per_core=total_mp / float(r.cpu_s.sum()),
                area_err_median=float(ea.abs().median()), area_err_max=float(ea.abs().max()),
                length_err_median=float(el.abs().median()), length_err_max=float(el.abs().max()),
                area_err_signed_median=float(ea.median()),
                length_err_signed_median=float(el.median()))
    # end to end through analyse_folder (PNG decode, CSV writing, process pool)
    from semkit.workflow import analyse_folder
    for method in ("auto", "otsu"):
        t1 = time.perf_counter()
        analyse_folder(tmp, tmp / f"out_{method}", jobs=args.jobs, progress=False,
                       overlays=False, threshold=method, classify=False)
        results[method]["end_to_end_mp_per_s"] = total_mp / (time.perf_counter() - t1)
    info = dict(n_images=len(truth), total_mp=total_mp, jobs=args.jobs,
                cpu_count=os.cpu_count(), load_avg_1min=os.getloadavg()[0],
                python=platform.python_version(), machine=platform.machine())
    outdir = pathlib.Path(args.out)
    outdir.mkdir(parents=True, exist_ok=True)
    (outdir / "sem_pipeline.json").write_text(json.dumps(dict(info=info, results=results),
                                                         indent=2))
    print(f"\n{len(truth)} images, {total_mp:.1f} MP, {args.jobs} processes, "
          f"load avg {info['load_avg_1min']:.1f}\n")
    print("| method | MP/s compute (wall) | MP/s end-to-end (wall) | MP/s per core (CPU time) "
          "| area err median / max | length err median / max |")
    print("|---|---|---|---|---|---|")
    for m, v in results.items():
        print(f"| {m} | {v['compute_mp_per_s']:.1f} | {v['end_to_end_mp_per_s']:.1f} | "
              f"{v['cpu_mp_per_s_per_core']:.1f} | {v['area_err_median']:.1%} / "
              f"{v['area_err_max']:.1%} | {v['length_err_median']:.1%} / "
              f"{v['length_err_max']:.1%} |")
    import shutil
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
