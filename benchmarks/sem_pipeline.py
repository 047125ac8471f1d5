"""Benchmark: speed of ``semkit analyse`` end to end beside the errors it reaches.

40 seeded synthetic images from :mod:`semkit.synth` (20 at 1024 x 768 and 20 at 2048 x 1536,
78.6 MP; cracks 2-8 px wide; every other image with a 2.5x illumination gradient; half of each
size pre-test, half post-test with tensile / shear / mixed cracks) are written as PNG with a
``manifest.csv`` (stages ``pre-test`` and ``failure``) and their ground truth. Then
``semkit.analyse_folder`` runs on the folder (PNG decoding, CSV writing, ``--jobs``
processes, no overlays), timed on the wall clock:

* ``default`` — the default options: tensile / shear typing on the loaded (post-test) images
  only, as the manifest says;
* ``typing off`` — ``--no-classify``;
* ``threshold only`` — ``--no-classify --no-ridge --no-reject`` (the pipeline before the
  ridge detector and the rejection rules).

Each run is repeated (``--repeat``, default 3, the runs interleaved) and the median wall
time is quoted. Throughput is total MP over wall time, and total MP over the analysis CPU time
summed over the images (``cpu_seconds`` of ``images.csv``: per core, not inflated by other
jobs on a busy machine; file reading is inside it, CSV writing and process start-up are not).

Errors against the truth, per image: total crack area and length (median and max |error|;
length against the crack paths, a layered or stepped shear crack once as ``semkit.synth``
counts it, and against every drawn trace, each layer and step, as semkit measures it), and
for the typed post-test images P = A_T / A_S (median |error|, largest, and how many P values
are flagged ``low_confidence`` or not ``ok``). ImageJ's thesis macro (rolling ball + Otsu +
skeleton) is quoted at 3.2 MP/s, measured on the same kind of folder; it is not run here.

Writes ``benchmarks/semkit_results/sem_pipeline.json`` and prints a markdown table.

Run: ``python benchmarks/sem_pipeline.py [--jobs 2] [--repeat 3] [--quick] [--images DIR]``
(``--images DIR`` keeps the generated folder there and reuses it on the next run).
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

SIZES = [(768, 1024)] * 20 + [(1536, 2048)] * 20
SEED0 = 1000
IMAGEJ_MP_PER_S = 3.2   # thesis macro, quoted (issue 15), not measured here
RUNS = {"default": {}, "typing off": dict(classify=False),
        "threshold only": dict(classify=False, ridge=False, reject=False)}


def _make(k, shape, folder):
    from semkit.io import write_image
    from semkit.synth import make_sem_image
    post = k % 4 >= 2
    s = make_sem_image(shape, stage="post" if post else "pre", widths=(2.0, 8.0),
                       gradient=2.5 if k % 2 else 1.0,
                       n_cracks=int(30 * shape[0] * shape[1] / 786432), seed=SEED0 + k)
    name = f"img_{k:02d}.png"
    write_image(pathlib.Path(folder) / name, s.image)
    lab = s.crack_labels
    types = dict(zip(s.cracks.crack_id, s.cracks.type_post))
    code = np.zeros(lab.max() + 1, np.int8)
    for cid, t in types.items():
        code[cid] = {"tensile": 1, "shear": 2}.get(t, 0)
    tp = code[lab]
    a_t, a_s = int((tp == 1).sum()), int((tp == 2).sum())
    return dict(image=name, height=shape[0], width=shape[1], stage="failure" if post
                else "pre-test", area_px=s.crack_area_px, length_px=s.crack_length_px,
                trace_length_px=float(s.cracks.trace_length_px.sum()),
                P_true=a_t / a_s if post and a_s else np.nan)


def _errors(images, truth):
    r = images.merge(truth, on="image")
    px2 = r.pixel_size_um ** 2
    ea = (r.crack_area_um2 / px2) / r.area_px - 1
    el = (r.crack_length_um / r.pixel_size_um) / r.length_px - 1
    et = (r.crack_length_um / r.pixel_size_um) / r.trace_length_px - 1
    post = r[r.stage == "failure"]
    out = dict(area_err_median=float(ea.abs().median()), area_err_max=float(ea.abs().max()),
               length_err_median=float(el.abs().median()),
               length_err_max=float(el.abs().max()),
               trace_length_err_median=float(et.abs().median()),
               trace_length_err_max=float(et.abs().max()), n_failed=int((r.error.fillna("") != "")
                                                                   .sum()))
    if "P_status" in post and post.P.notna().any():
        ep = (post.P / post.P_true - 1).abs()
        out.update(P_err_median=float(ep.median()), P_err_max=float(ep.max()),
                   n_P=int(post.P.notna().sum()),
                   n_P_not_ok=int((post.P_status.astype(str) != "ok").sum()),
                   n_P_band_holds_true=int(((post.P_low <= post.P_true)
                                            & (post.P_true <= post.P_high)).sum()))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="8 small + 4 large images")
    ap.add_argument("--out", default=str(pathlib.Path(__file__).parent / "semkit_results"))
    ap.add_argument("--repeat", type=int, default=3, help="runs of each setting (median)")
    ap.add_argument("--images", help="keep the generated folder here; reuse it when present")
    args = ap.parse_args(argv)
    sizes = SIZES[:8] + SIZES[20:24] if args.quick else SIZES
    keep = args.images is not None
    tmp = pathlib.Path(args.images) if keep else pathlib.Path(
        tempfile.mkdtemp(prefix="semkit_bench_"))
    old = pd.read_csv(tmp / "truth.csv") if keep and (tmp / "truth.csv").is_file() else None
    if old is not None and len(old) == len(sizes) and "trace_length_px" in old:
        truth = old
    else:
        tmp.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        import multiprocessing as mp
        ctx = mp.get_context("forkserver")
        with ProcessPoolExecutor(max_workers=args.jobs, mp_context=ctx) as ex:
            truth = pd.DataFrame(list(ex.map(_make, range(len(sizes)), sizes,
                                             [tmp] * len(sizes))))
        truth.assign(specimen="S1", test="ucs", pixel_size_um=1.0)[
            ["image", "specimen", "test", "stage", "pixel_size_um"]].to_csv(
                tmp / "manifest.csv", index=False)
        truth.to_csv(tmp / "truth.csv", index=False)
        print(f"generated {len(truth)} images in {time.perf_counter() - t0:.1f} s",
              file=sys.stderr)
    out_root = pathlib.Path(tempfile.mkdtemp(prefix="semkit_bench_out_"))
    total_mp = float((truth.height * truth.width).sum() / 1e6)
    from semkit.workflow import analyse_folder
    # warm the numba caches of the worker processes' code once
    analyse_folder(tmp, out_root / "warm", jobs=1, progress=False, overlays=False)
    walls = {name: [] for name in RUNS}
    cpus = {name: [] for name in RUNS}
    loads = {name: [] for name in RUNS}
    last = {}
    for k in range(args.repeat):   # interleaved, so a load change hits every setting alike
        for name, opts in RUNS.items():
            loads[name].append(os.getloadavg()[0])
            t1 = time.perf_counter()
            images, _ = analyse_folder(tmp, out_root / f"{k}_{len(last)}", jobs=args.jobs,
                                       progress=False, overlays=False, **opts)
            walls[name].append(time.perf_counter() - t1)
            cpus[name].append(float(images.cpu_seconds.sum()))
            last[name] = images
    results = {}
    for name, opts in RUNS.items():
        wall = float(np.median(walls[name]))
        results[name] = dict(options=opts, wall_s=wall, wall_s_runs=walls[name],
                             mp_per_s=total_mp / wall,
                             mp_per_cpu_s=total_mp / float(np.median(cpus[name])),
                             load_avg_1min_before=loads[name],
                             **_errors(last[name], truth))
    info = dict(n_images=len(truth), total_mp=total_mp, jobs=args.jobs,
                cpu_count=os.cpu_count(), load_avg_1min=os.getloadavg()[0],
                imagej_mp_per_s_quoted=IMAGEJ_MP_PER_S,
                python=platform.python_version(), machine=platform.machine())
    outdir = pathlib.Path(args.out)
    outdir.mkdir(parents=True, exist_ok=True)
    (outdir / "sem_pipeline.json").write_text(json.dumps(dict(info=info, results=results),
                                                         indent=2))
    print(f"\n{len(truth)} images, {total_mp:.1f} MP, {args.jobs} processes, median of "
          f"{args.repeat} runs, load avg {info['load_avg_1min']:.1f}\n")
    print("| run | MP/s end to end | MP per CPU-s | area err median / max | "
          "length err median / max (paths; traces) | P err median / max (n, not ok) |")
    print("|---|---|---|---|---|---|")
    for m, v in results.items():
        p = (f"{v['P_err_median']:.1%} / {v['P_err_max']:.0%} ({v['n_P']}, {v['n_P_not_ok']})"
             if "P_err_median" in v else "—")
        print(f"| {m} | {v['mp_per_s']:.1f} | {v['mp_per_cpu_s']:.1f} | "
              f"{v['area_err_median']:.1%} / {v['area_err_max']:.1%} | "
              f"{v['length_err_median']:.1%} / {v['length_err_max']:.1%}; "
              f"{v['trace_length_err_median']:.1%} / {v['trace_length_err_max']:.1%} | {p} |")
    print(f"| ImageJ thesis macro (quoted) | {IMAGEJ_MP_PER_S} | — | — | — | — |")
    import shutil
    shutil.rmtree(out_root, ignore_errors=True)
    if not keep:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
