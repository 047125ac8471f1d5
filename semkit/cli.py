"""``semkit`` command line: a thin argparse layer over :mod:`semkit.workflow` (no maths here).

Exit status: 0 all images analysed; 1 the batch finished but some images failed (a one-line
summary on stderr, details in ``images.csv``); 2 bad input (bad flag value, missing folder,
unreadable config); 130 interrupted (finished results are kept).
"""
from __future__ import annotations

import argparse
import sys

from .errors import InputError

__all__ = ["main", "build_parser"]

#: keys a --config YAML file may set (the API keywords of analyse_folder)
_ANALYSE_KEYS = ("threshold", "flatten", "denoise_sigma_px", "despeckle", "min_area_um2",
                 "max_hole_px", "length", "exclude_pores", "pixel_size_um", "jobs", "progress",
                 "overlays", "classify", "crack_model", "grains", "minerals", "classes",
                 "labels", "roi", "ridge", "link", "reject", "save_masks", "segmenter",
                 "segmenter_threshold", "bright_cracks", "scan_lines", "area")


def _version():
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("rockkit")
    except PackageNotFoundError:
        return "unknown"


def _add_analyse(sub):
    p = sub.add_parser("analyse", aliases=["analyze"], help="measure cracks in a folder of images",
                       description="Threshold, clean, label and measure cracks in every image of "
                                   "DIR; write images.csv, cracks.csv and overlays/ to --out.")
    p.add_argument("folder", metavar="DIR", help="folder of images (manifest.csv optional)")
    p.add_argument("--out", required=True, metavar="OUT", help="output folder")
    p.add_argument("--threshold", default=None, metavar="METHOD",
                   help="auto (default) | otsu | local | manual:VALUE")
    p.add_argument("--flatten", default=None, choices=["polynomial", "gaussian", "none"],
                   help="illumination flattening (default polynomial)")
    p.add_argument("--denoise-sigma-px", type=float, default=None, metavar="PX",
                   help="Gaussian denoising before thresholding, px (default 0.7; 0 = off)")
    p.add_argument("--despeckle", default=None, choices=["specks", "median", "none"],
                   help="specks (default: isolated specks only) | median (ImageJ 3x3; erases "
                        "1-px cracks) | none")
    p.add_argument("--min-area-um2", "--min-area", dest="min_area_um2", type=float, default=None,
                   metavar="UM2", help="remove objects smaller than this area, µm²")
    p.add_argument("--max-hole-px", type=int, default=None, metavar="PX",
                   help="fill holes up to this area, px (default 100; 0 = fill all, as ImageJ)")
    p.add_argument("--pixel-size-um", "--pixel-size", dest="pixel_size_um", type=float,
                   default=None, metavar="UM",
                   help="pixel size when manifest, TIFF metadata and magnification give none")
    p.add_argument("--no-length", dest="length", action="store_false", default=None,
                   help="skip skeletons and lengths")
    p.add_argument("--keep-pores", dest="exclude_pores", action="store_false", default=None,
                   help="count round pores as cracks")
    p.add_argument("--no-overlay", dest="overlays", action="store_false", default=None,
                   help="do not write overlay PNGs")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="worker processes (default: all cores)")
    p.add_argument("--no-progress", dest="progress", action="store_false", default=None,
                   help="no progress bar")
    p.add_argument("--config", metavar="FILE.yaml", help="options from YAML (flags win)")
    # crack types, P, grains (docs/semkit_science.md)
    p.add_argument("--roi", default=None, metavar="auto|none|MASK.png",
                   help="sample region: auto (default: crop the SEM data bar, drop a black or "
                        "white surround), none, or a mask image (non-zero = sample)")
    p.add_argument("--bright-cracks", dest="bright_cracks", action="store_true", default=None,
                   help="cracks are brighter than the rock (fluorescent-dye sections): invert "
                        "the grey image first")
    p.add_argument("--no-ridge", dest="ridge", action="store_false", default=None,
                   help="threshold only (no ridge detector for thin, faint cracks)")
    p.add_argument("--no-scan-lines", dest="scan_lines", action="store_false", default=None,
                   help="keep row-to-row grey offsets of the raster scan (removed by default "
                        "when they stand above pixel noise)")
    p.add_argument("--area", choices=("midpoint", "mixed"), default=None,
                   help="crack area: mixed (default): midpoint count on resolved cross-sections, "
                        "partial volume on every thin stretch; or midpoint: the pixel count, "
                        "partial volume only for cracks thinner than 1.6 px")
    p.add_argument("--link", dest="link", action="store_true", default=None,
                   help="join the pieces of faint, beaded cracks along their lines (about "
                        "doubles the CPU time)")
    p.add_argument("--no-link", dest="link", action="store_false",
                   help="do not link (the default)")
    p.add_argument("--no-reject", dest="reject", action="store_false", default=None,
                   help="keep dark objects the shape and surroundings rules would reject")
    p.add_argument("--save-masks", dest="save_masks", action="store_true", default=None,
                   help="write masks/<stem>_cracks.png (0/255) and masks/<stem>_labels.png")
    p.add_argument("--segmenter", default=None, metavar="SEG.skops",
                   help="trained pixel classifier used instead of threshold and ridge")
    p.add_argument("--segmenter-threshold", type=float, default=None, metavar="P",
                   help="decision level on P(crack) in (0, 1) (default: the one the model "
                        "records, 0.5 unless trained with --threshold)")
    p.add_argument("--classify", dest="classify", action="store_true", default=None,
                   help="type tensile/shear/mixed on every image (default: only on loaded "
                        "stages of manifest.csv)")
    p.add_argument("--no-classify", dest="classify", action="store_false", default=None,
                   help="skip tensile/shear/mixed typing (then no P)")
    p.add_argument("--crack-model", default=None, metavar="MODEL.json",
                   help="post-test crack model from `semkit classify --train` (default built in)")
    p.add_argument("--labels", default=None, metavar="LABELS.csv",
                   help="user crack types (image, crack_id, type) overriding the classifier")
    p.add_argument("--grains", action="store_true", default=None,
                   help="segment minerals and grains: type_pre, grains.csv, grain maps")
    p.add_argument("--minerals", default=None, metavar="NAMES",
                   help="mineral names brightest-first (pyroxene,plagioclase,biotite) or a "
                        "number of phases (default 3)")
    p.add_argument("--classes", default=None, metavar="E1,E2",
                   help="grain-size class edges fine/medium,medium/coarse in µm (default: "
                        "10th/90th count percentiles per mineral)")
    p.set_defaults(run=_run_analyse)


def _add_synth(sub):
    p = sub.add_parser("synth", help="write the synthetic sample image set with ground truth")
    p.add_argument("out", metavar="OUT", help="output folder")
    p.add_argument("--seed", type=int, default=2026)
    p.set_defaults(run=_run_synth)


def build_parser():
    """The argparse parser of ``semkit`` (subcommands: analyse/analyze, synth)."""
    ap = argparse.ArgumentParser(prog="semkit", description="SEM micro-crack statistics.")
    ap.add_argument("--version", action="version", version=f"semkit {_version()}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    _add_analyse(sub)
    _add_synth(sub)
    _add_science(sub)  # grains, indices, classify
    _add_train_segmenter(sub)
    return ap


def _load_config(path):
    import yaml
    try:
        with open(path) as f:
            cfg = yaml.safe_load(f) or {}
    except (OSError, yaml.YAMLError) as e:
        raise InputError(f"{path}: cannot read YAML config ({e})") from None
    if not isinstance(cfg, dict):
        raise InputError(f"{path}: expected a mapping of options")
    cfg = {str(k).replace("-", "_"): v for k, v in cfg.items()}
    bad = sorted(set(cfg) - set(_ANALYSE_KEYS))
    if bad:
        raise InputError(f"{path}: unknown option(s) {', '.join(bad)}; expected some of "
                         f"{', '.join(_ANALYSE_KEYS)}")
    return cfg


def _run_analyse(args):
    from .workflow import analyse_folder
    kw = _load_config(args.config) if args.config else {}
    for k in _ANALYSE_KEYS:
        v = getattr(args, k, None)
        if v is not None:
            kw[k] = v
    if kw.get("max_hole_px") == 0:
        kw["max_hole_px"] = None
    if kw.get("jobs") is not None and kw["jobs"] < 1:
        raise InputError(f"--jobs: expected >= 1, got {kw['jobs']}")
    if kw.get("labels") is not None:
        from .classify import read_labels
        kw["labels"] = read_labels(kw["labels"])
    if kw.get("segmenter") is not None:
        from .segmenter_file import load_segmenter
        kw["segmenter"] = load_segmenter(kw["segmenter"])
    if kw.get("classes") is not None:
        from .grains import parse_classes
        parse_classes(kw["classes"])
    images, _ = analyse_folder(args.folder, args.out, **kw)
    skipped = images.attrs.get("skipped", [])
    if skipped:
        print(f"semkit: skipped {len(skipped)} non-image file(s): {', '.join(skipped)}",
              file=sys.stderr)
    for line in _p_lines(args.out):
        print(line, file=sys.stderr)
    failed = images["error"].fillna("").astype(str).str.len() > 0
    n_fail = int(failed.sum())
    if n_fail:
        first = images.loc[failed].iloc[0]
        print(f"semkit: {n_fail} of {len(images)} images failed (first: {first['image']}: "
              f"{first['error']}); see {args.out}/images.csv", file=sys.stderr)
        return 1
    return 0


def _p_lines(out):
    """One line per specimen and test of ``damage.csv``: each stage's P_mean with its band,
    and whether any is low_confidence (nothing when no stage has a P)."""
    import pathlib

    import pandas as pd
    path = pathlib.Path(out) / "damage.csv"
    if not path.is_file():
        return []
    from .damage import band_text
    d = pd.read_csv(path)
    d = d[d["P_mean"].notna()]
    lines = []
    for (spec, test), g in d.groupby(["specimen", "test"], sort=False):
        parts = []
        for r in g.itertuples():
            band = band_text(getattr(r, "P_mean_low", None), getattr(r, "P_mean_high", None))
            parts.append(f"{r.stage} {r.P_mean:.3g}" + (f" ({band})" if band else ""))
        low = (g["P_status"].astype(str) == "low_confidence").any() if "P_status" in g else False
        lines.append(f"semkit: P = A_T/A_S, {spec} {test}, mean by stage (10-90 % typing band): "
                     + ", ".join(parts) + ("; low_confidence: quote the band (damage.csv "
                                           "P_note)" if low else ""))
    return lines


# ----------------------------------------------------------- semkit grains | indices | classify
def _add_science(sub):
    p = sub.add_parser("grains", help="grain map and grain-size table (grains.csv) of a folder")
    p.add_argument("folder", metavar="DIR", help="folder of images (manifest.csv optional)")
    p.add_argument("--out", required=True, metavar="OUT", help="output folder")
    p.add_argument("--minerals", default=None, metavar="NAMES",
                   help="mineral names brightest-first, or a number of phases (default 3)")
    p.add_argument("--classes", default=None, metavar="E1,E2",
                   help="class edges in µm (default: 10th/90th percentiles per mineral)")
    p.add_argument("--pixel-size-um", dest="pixel_size_um", type=float, default=None,
                   metavar="UM", help="fallback pixel size")
    p.add_argument("--no-progress", dest="progress", action="store_false", default=True)
    p.add_argument("--seed", type=int, default=None)
    p.set_defaults(run=_run_grains)
    p = sub.add_parser("indices", help="H, MHI and R_a of a grain-size table (grains.csv)")
    p.add_argument("table", metavar="GRAINS.csv")
    p.add_argument("--convention", default="N1", choices=["N1", "geometric", "measured"],
                   help="class-mean convention (default N1; see docs/semkit_science.md)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(run=_run_indices)
    p = sub.add_parser("classify", help="fit the post-test crack model from user labels")
    p.add_argument("folder", metavar="DIR", help="the images the labels refer to")
    p.add_argument("--train", required=True, metavar="LABELS.csv",
                   help="image, crack_id, type (tensile|shear|mixed)")
    p.add_argument("--out", default="crack_model.json", metavar="MODEL.json")
    p.add_argument("--pixel-size-um", dest="pixel_size_um", type=float, default=None)
    p.add_argument("--seed", type=int, default=None)
    p.set_defaults(run=_run_classify)


def _run_grains(args):
    from .workflow import analyse_grains_folder
    t = analyse_grains_folder(args.folder, args.out, minerals=args.minerals,
                              classes=args.classes, pixel_size_um=args.pixel_size_um,
                              progress=args.progress, seed=args.seed)
    print(f"wrote grains.csv ({t['mineral'].nunique()} minerals) to {args.out}")
    return 0


def _run_indices(args):
    import json

    import pandas as pd

    from .indices import indices_from_table
    try:
        table = pd.read_csv(args.table)
    except (OSError, ValueError) as e:
        raise InputError(f"{args.table}: cannot read grain-size table ({e})") from None
    try:
        r = indices_from_table(table, convention=args.convention)
    except ValueError as e:
        raise InputError(f"{args.table}: {e}") from None
    if args.json:
        print(json.dumps({"H": r["H"], "MHI": r["MHI"], "R_a_mm": r["R_a_mm"],
                          "R_a_um": r["R_a_um"], "convention": r["convention"],
                          "mineral_mean_um": r["mineral_mean_um"]}))
    else:
        print(f"H = {r['H']:.4f}  MHI = {r['MHI']:.4f}  R_a = {r['R_a_mm']:.4g} mm "
              f"(convention {r['convention']})")
    return 0


def _run_classify(args):
    from .classify import read_labels, save_model
    from .workflow import train_from_folder
    model = train_from_folder(args.folder, read_labels(args.train),
                              pixel_size_um=args.pixel_size_um, seed=args.seed)
    save_model(model, args.out)
    print(f"wrote crack model to {args.out} ({model['n_groups']} crack groups, "
          f"{'/'.join(map(str, model['n_per_type']))} tensile/shear/mixed)")
    return 0


def _add_train_segmenter(sub):
    p = sub.add_parser("train-segmenter", help="train a crack pixel classifier from labels",
                       description="Train a random-forest crack / not-crack pixel classifier "
                                   "(for semkit analyse --segmenter) from label images: 0 "
                                   "unlabelled, 1 crack, 2 not crack (scribbles or full "
                                   "masks).")
    p.add_argument("images", nargs="+", metavar="IMAGES",
                   help="image files and/or folders (images without a label file are skipped)")
    p.add_argument("--labels", required=True, metavar="LABELS",
                   help="folder of label PNGs named <image stem>.png or <stem>_labels.png")
    p.add_argument("--out", required=True, metavar="SEG.skops", help="model file to write")
    p.add_argument("--binary-masks", action="store_true",
                   help="labels are painted crack masks (0 background, nonzero crack)")
    p.add_argument("--trees", type=int, default=None, metavar="N", help="trees (default 50)")
    p.add_argument("--sigma-max-px", type=float, default=None, metavar="PX",
                   help="largest feature scale, px (default 8)")
    p.add_argument("--threshold", type=float, default=None, metavar="P",
                   help="decision level on P(crack) recorded in the model (default 0.5)")
    p.add_argument("--jobs", type=int, default=None, metavar="N", help="threads (default all)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-progress", dest="progress", action="store_false", default=True)
    p.set_defaults(run=_run_train_segmenter)


def _run_train_segmenter(args):
    from .segmenter import train_segmenter
    from .segmenter_file import read_training_set, save_segmenter
    if not str(args.out).endswith(".skops"):
        raise InputError(f"--out: expected a .skops file name, got {args.out}")
    images, labels, names, skipped = read_training_set(args.images, args.labels,
                                                       binary_masks=args.binary_masks)
    if skipped:
        print(f"skipped {len(skipped)} image(s) without a label file: {', '.join(skipped)}",
              file=sys.stderr)
    kw = {k: v for k, v in (("n_trees", args.trees), ("sigma_max", args.sigma_max_px),
                            ("threshold", args.threshold)) if v is not None}
    seg = train_segmenter(images, labels, names=names, n_jobs=args.jobs, seed=args.seed,
                          progress=args.progress, **kw)
    save_segmenter(seg, args.out)
    s = seg.scores
    print(f"wrote {args.out}: {len(names)} images, {seg.label_counts['crack_sampled']} crack / "
          f"{seg.label_counts['not_crack_sampled']} not-crack pixels; out-of-bag crack F1 "
          f"{s.get('crack_f1', float('nan')):.3f} (optimistic: pixels of the training images)")
    return 0


def _run_synth(args):
    from .synth import write_sample_set
    t = write_sample_set(args.out, seed=args.seed)
    print(f"wrote {len(t)} images with manifest.csv and truth.csv to {args.out}")
    return 0


def main(argv=None) -> int:
    """Entry point of the ``semkit`` console script; returns the exit status."""
    ap = build_parser()
    args = ap.parse_args(argv)
    if not getattr(args, "run", None):
        ap.print_help(sys.stderr)
        return 2
    try:
        return args.run(args)
    except InputError as e:
        print(f"semkit: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("semkit: interrupted; finished results were kept", file=sys.stderr)
        return 130
