"""Train and evaluate the built-in post-test crack-typing model (``semkit/classify/model.json``).

``train``: renders the training family (``benchmarks/typing/render.py``, settings ``TRAIN``,
seeds 0..N-1), runs the default crack detection on every image (``semkit.analysis``, typing
off), measures every crack group's morphology and labels it with the majority true type of its
pixels. The inverse L2 strength is chosen by 5-fold cross-validation grouped by image on the
training images only; the temperature on a calibration set (seeds 100000.., same settings).
Writes the model (seed recorded) to ``semkit/classify/model.json``.

``evaluate``: the model on renderings it was not trained on:

* ``heldout-settings`` — the same renderer with other settings (``HELDOUT``: more noise and
  blur, stronger illumination, smaller grains, other widths, steps and layer spacings),
  seeds 200000..;
* ``synth`` — ``semkit.synth`` post-test images, seeds 200-211 (another generator);

accuracy by crack area (pixels both truth and detection call crack), confusion, calibration
(reliability table and ``docs/figures/typing_reliability.png``, expected calibration error),
the share of groups flagged out of range, per-image P error, and typing time per megapixel.
Writes ``benchmarks/semkit_results/typing_model.json``.

``shift``: the spread of the typing's per-image lean (``image_shift_sd`` in the model, which
widens the P band, :mod:`semkit.damage_confidence`): fitted by maximum marginal likelihood
(:func:`semkit.classify.model.fit_image_shift`) on ``HELDOUT`` renderings, seeds 300000..
(apart from the evaluation seeds), and written into the model; then the P band is checked on
``HELDOUT`` renderings of another size (768 x 1024, seeds 200000..): how many images' true P
(tensile / shear pixels of the truth) lies in [P_low, P_high] (nominal 80 %) with and without
the shift, and how many P stay ``ok`` (by the typing alone: the image's validity flags,
which also make P ``low_confidence`` in ``images.csv``, are left out here). Writes
``benchmarks/semkit_results/typing_shift.json``.

Run: ``python benchmarks/typing_model.py train [--n 240]``, ``python
benchmarks/typing_model.py shift [--n 120]``, then ``python benchmarks/typing_model.py evaluate
[--n 60]``.
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "typing"))
MODEL = ROOT.parent / "semkit" / "classify" / "model.json"
OUT = ROOT / "semkit_results"
FIG = ROOT.parent / "docs" / "figures" / "typing_reliability.png"
SHAPE = (384, 512)
SEED = 0
CAL_SEED0 = 100_000
HELD_SEED0 = 200_000
SHIFT_SEED0 = 300_000
BAND_SHAPE = (768, 1024)
C_GRID = (0.03, 0.1, 0.3, 1.0, 3.0)
BINS = np.linspace(1 / 3, 1, 9)


def _family(name):
    import render
    return {"train": render.TRAIN, "heldout": render.HELDOUT}[name]


def _scene(args):
    """The training material of one scene (``semkit.classify.model.image_samples``)."""
    kind, seed = args
    from semkit.analysis import analyse_image
    from semkit.classify.model import image_samples
    if kind == "synth":
        from semkit.synth import make_sem_image
        s = make_sem_image(SHAPE, stage="post", n_cracks=12, seed=seed)
        code = np.zeros(len(s.cracks) + 1, np.int8)
        code[s.cracks.crack_id] = [("tensile", "shear", "mixed").index(t) + 1
                                   for t in s.cracks.type_post]
        image, types = s.image, code[s.crack_labels]
        modes = np.where(types <= 2, types, 0)
    else:
        import render
        image, types, modes, _ = render.render_scene(SHAPE, _family(kind), seed=seed)
    a = analyse_image(image, stage="failure", classify=False)
    th = a.thresholded
    types, modes = _frame(a, types), _frame(a, modes)
    return image_samples(a.crack_labels, types, modes=modes, image=a.smooth,
                         skeleton=a.skeleton, background=th.background,
                         crack_level=th.crack_level)


def _frame(a, arr):
    """``arr`` (raw image frame) cut to the analysis frame (without a detected data bar)."""
    bar = a.data_bar
    if bar is None:
        return arr
    return arr[bar.row1:] if bar.side == "top" else arr[:bar.row0]


def collect(kind, seeds, jobs):
    """Training material of the scenes, one dict per image."""
    with ProcessPoolExecutor(jobs) as ex:
        return list(ex.map(_scene, [(kind, s) for s in seeds], chunksize=4))


def _area_accuracy(P, y, area):
    return float((area * (P.argmax(axis=1) == y)).sum() / area.sum())


def _rows(samples, model):
    from semkit.classify.model import _group_rows
    return _group_rows(samples, model)


def train(n, jobs):
    from semkit.classify.model import calibrate, fit_post, save_model, type_probabilities
    t0 = time.perf_counter()
    S = collect("train", range(SEED, SEED + n), jobs)
    Sc = collect("train", range(CAL_SEED0, CAL_SEED0 + n // 4), jobs)
    cv = {}
    for c in C_GRID:
        acc = []
        for f in range(5):
            m = fit_post([x for i, x in enumerate(S) if i % 5 != f], c_group=c, seed=SEED)
            D, y, area = _rows([x for i, x in enumerate(S) if i % 5 == f], m)
            acc.append(_area_accuracy(type_probabilities(D, m), y, area))
        cv[c] = float(np.mean(acc))
    c_best = max(cv, key=cv.get)
    model = fit_post(S, c_group=c_best, seed=SEED)
    calibrate(model, Sc)
    model["training"] = dict(renderer="benchmarks/typing/render.py", settings="TRAIN",
                             shape=list(SHAPE), seeds=[SEED, SEED + n - 1],
                             calibration_seeds=[CAL_SEED0, CAL_SEED0 + n // 4 - 1],
                             cv_area_accuracy={str(k): v for k, v in cv.items()})
    save_model(model, MODEL)
    print(f"{model['n_groups']} traces from {n} images ({model['n_per_type']} tensile/shear/"
          f"mixed); 5-fold CV accuracy by area {cv}; chose C = {c_best}; temperature "
          f"{model['temperature']:.3f}; {time.perf_counter() - t0:.0f} s")
    return model


def reliability(P, y, w=None):
    """Bins of the top probability: mean confidence, accuracy, count; and the ECE."""
    conf, hit = P.max(axis=1), (P.argmax(axis=1) == y).astype(float)
    w = np.ones(len(y)) if w is None else np.asarray(w, float)
    rows, ece = [], 0.0
    for lo, hi in zip(BINS[:-1], BINS[1:]):
        s = (conf >= lo) & ((conf < hi) | (hi == BINS[-1]))
        if s.any():
            c, a = np.average(conf[s], weights=w[s]), np.average(hit[s], weights=w[s])
            rows.append(dict(lo=float(lo), hi=float(hi), n=int(s.sum()), confidence=float(c),
                             accuracy=float(a)))
            ece += w[s].sum() / w.sum() * abs(c - a)
    return rows, float(ece)


def _plot(tables):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(4.2, 4.0), dpi=120)
    ax.plot([1 / 3, 1], [1 / 3, 1], "k:", lw=1, label="calibrated")
    for name, rows in tables.items():
        ax.plot([r["confidence"] for r in rows], [r["accuracy"] for r in rows], "o-",
                label=name)
    ax.set_xlabel("predicted probability of the chosen type")
    ax.set_ylabel("observed accuracy (crack groups)")
    ax.set_title("Crack typing: reliability on held-out renderings", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    FIG.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(FIG)


def evaluate(n, jobs):
    from semkit.classify.model import DEFAULT_POST_MODEL as model
    from semkit.classify.model import out_of_range, type_probabilities
    res, tables = {}, {}
    for name, kind, seeds in (("heldout-settings", "heldout",
                               range(HELD_SEED0, HELD_SEED0 + n)),
                              ("synth 200-211", "synth", range(200, 212)),
                              ("training family (calibration seeds)", "train",
                               range(CAL_SEED0, CAL_SEED0 + n // 2))):
        D, y, area = _rows(collect(kind, seeds, jobs), model)
        P = type_probabilities(D, model)
        flagged = np.array([bool(s) for s in out_of_range(D, model)])
        conf = np.zeros((3, 3))
        np.add.at(conf, (y, P.argmax(axis=1)), area)
        rows, ece = reliability(P, y)
        tables[name] = rows
        res[name] = dict(n_images=len(seeds), n_groups=int(len(y)),
                         accuracy_by_area=_area_accuracy(P, y, area),
                         accuracy_by_area_in_range=_area_accuracy(P[~flagged], y[~flagged],
                                                                  area[~flagged]),
                         flagged_share=float(flagged.mean()),
                         flagged_area_share=float(area[flagged].sum() / area.sum()),
                         confusion_by_area=(conf / conf.sum(axis=1, keepdims=True)).round(3)
                         .tolist(), reliability=rows, ece=ece)
        print(f"{name}: accuracy by area {res[name]['accuracy_by_area']:.3f} (in range "
              f"{res[name]['accuracy_by_area_in_range']:.3f}), ECE {ece:.3f}, flagged "
              f"{flagged.mean():.1%} of traces; confusion {res[name]['confusion_by_area']}")
    _plot({k: v for k, v in tables.items() if not k.startswith("training")})
    res["speed"] = typing_speed()
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "typing_model.json").write_text(json.dumps(dict(load=os.getloadavg(), results=res),
                                                      indent=1))
    return res


def _band_scene(seed):
    """(true P, typed cracks table) of one large held-out-settings rendering."""
    import render

    from semkit.analysis import analyse_image
    image, _, modes, _ = render.render_scene(BAND_SHAPE, render.HELDOUT, seed=seed)
    a = analyse_image(image, stage="failure", pixel_size_um=1.0)
    modes = _frame(a, modes)
    n_s = int((modes == 2).sum())
    return (int((modes == 1).sum()) / n_s if n_s else float("nan")), a.typed_cracks


def shift(n, jobs, model=None, n_band=40):
    """Fit ``image_shift_sd`` on held-out-settings renderings, write it into the model, and
    check the P band's coverage on larger renderings (see the module docstring). ``model``:
    the one just trained, else the model file as it is now (not the one imported with semkit,
    which a training run in this process has replaced)."""
    from semkit.classify.model import fit_image_shift, load_model, save_model
    from semkit.damage import image_damage
    from semkit.damage_confidence import P_SPREAD_MAX
    model = load_model(MODEL) if model is None else model
    t0 = time.perf_counter()
    fit = fit_image_shift(collect("heldout", range(SHIFT_SEED0, SHIFT_SEED0 + n), jobs), model)
    model["image_shift_sd"] = round(fit["sd"], 3)
    model["image_shift"] = dict(fit, renderer="benchmarks/typing/render.py",
                                settings="HELDOUT", shape=list(SHAPE),
                                seeds=[SHIFT_SEED0, SHIFT_SEED0 + n - 1])
    save_model(model, MODEL)
    with ProcessPoolExecutor(jobs) as ex:
        scenes = list(ex.map(_band_scene, range(HELD_SEED0, HELD_SEED0 + n_band)))
    band = {}
    for name, sd in (("independent draws", 0.0), ("with image shift", model["image_shift_sd"])):
        held, ok, ok_15, ok_2x, n_true = 0, 0, 0, 0, 0
        for p_true, c in scenes:
            if not np.isfinite(p_true) or c.empty:
                continue
            d = image_damage(c.assign(image="x", type_shift_sd=sd)).iloc[0]
            n_true += 1
            held += bool(d.P_low <= p_true <= d.P_high)
            if d.P_status == "ok":
                ok += 1
                ok_15 += bool(abs(d.P / p_true - 1) <= 0.15)
                ok_2x += bool(not 0.5 <= d.P / p_true <= 2)
        band[name] = dict(shift_sd=sd, n_images=n_true, band_holds_true_P=held, n_P_ok=ok,
                          n_P_ok_within_15pct=ok_15, n_P_ok_off_2x=ok_2x)
    res = dict(fit=model["image_shift"], band_check=dict(
        renderer="benchmarks/typing/render.py", settings="HELDOUT", shape=list(BAND_SHAPE),
        seeds=[HELD_SEED0, HELD_SEED0 + n_band - 1], nominal=0.8,
        spread_max=P_SPREAD_MAX, results=band), seconds=time.perf_counter() - t0,
        load=os.getloadavg())
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "typing_shift.json").write_text(json.dumps(res, indent=1))
    print(f"image_shift_sd {fit['sd']:.2f} (95 % {fit['sd_low']:.2f}-{fit['sd_high']:.2f}) "
          f"from {fit['n_groups']} groups on {fit['n_images']} images")
    print("| P band | images | band holds true P | P ok | ok within 15 % | ok off > 2x |")
    print("|---|---|---|---|---|---|")
    for name, b in band.items():
        print(f"| {name} (sd {b['shift_sd']:g}) | {b['n_images']} | {b['band_holds_true_P']} | "
              f"{b['n_P_ok']} | {b['n_P_ok_within_15pct']} | {b['n_P_ok_off_2x']} |")
    return res


def typing_speed(n=4):
    """Median seconds per megapixel of classify_post + the partial-volume areas (the typing
    step of the analysis) on 1024 x 768 semkit.synth post images: wall time and CPU time of
    this process (the CPU time is what a busy shared machine inflates least)."""
    from semkit.analysis import analyse_image
    from semkit.classify import classify_stage
    from semkit.synth import make_sem_image
    wall, cpu = [], []
    for seed in range(n + 1):  # the first run compiles the kernels: not counted
        s = make_sem_image((768, 1024), stage="post", n_cracks=25, seed=300 + seed)
        a = analyse_image(s.image, stage="failure", classify=False)
        c, th, sk = a.cracks, a.thresholded, a.skeleton
        t0, c0 = time.perf_counter(), time.process_time()
        classify_stage(c, a.crack_labels, grey=a.smooth, skeleton=sk,
                       background=th.background, crack_level=th.crack_level)
        mp = s.image.size / 1e6
        if seed:
            wall.append((time.perf_counter() - t0) / mp)
            cpu.append((time.process_time() - c0) / mp)
    return dict(wall_seconds_per_mp_median=float(np.median(wall)),
                cpu_seconds_per_mp_median=float(np.median(cpu)), load=os.getloadavg()[0])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["train", "shift", "evaluate", "speed"])
    ap.add_argument("--n", type=int, default=None,
                    help="images (train 240, shift 120, evaluate 60)")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    if a.what == "train":
        shift(120, a.jobs, model=train(a.n or 240, a.jobs))
    elif a.what == "shift":
        shift(a.n or 120, a.jobs)
    elif a.what == "speed":
        print(json.dumps(typing_speed()))
    else:
        evaluate(a.n or 60, a.jobs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
