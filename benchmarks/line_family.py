"""Benchmark: default ``semkit analyse`` on clean line images with exact truth.

Two families of 1024 x 768 images, grey 30 cracks in a 170 mineral, exact partial-volume
coverage, a Gaussian blur, white noise, 8 bit:

* ``hairlines`` — six slanted cracks, all of one width (1, 1.5, 2 or 3 px): no crack wide
  enough to show the void grey once blurred (blur 0.6, 1.0, 1.4 px; noise 3 and 8);
* ``mix`` — eight parallel cracks 1.5, 2, 2.5, 3, 3.5, 4, 6 and 8 px wide (blur 0.6, 1.0,
  1.4 px; noise 8): the wide ones show the void grey, the narrow ones partial volumes.

Each image is scored by its total area and length against the truth (area: the coverage sum;
length: the drawn length of each line), with the crack grey semkit read, and whether the row
is ``valid``. A *confidently wrong* image is valid with area or length off by more than 25 %
(``benchmarks/heldout_semkit.confidently_wrong``, one rule for every family). The images are
simple on purpose: they isolate the crack-grey read-out and the partial-volume area from
everything else. The rules of the crack-grey read-out were set on them (with the development
family and micro-CT slices 1-10), so their figures check the mechanism; they are not an
accuracy for unseen images.

Writes ``benchmarks/semkit_results/line_family.json`` and prints a markdown table.

Run: ``python benchmarks/line_family.py [--jobs 2]``
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from heldout_semkit import WRONG, confidently_wrong  # noqa: E402  (one rule for all families)

OUT = pathlib.Path(__file__).resolve().parent / "semkit_results"
SHAPE = (768, 1024)
CRACK_GREY, MINERAL_GREY = 30.0, 170.0
MARGIN = 50            # the lines stop this many px from the left and right edges
HAIRLINE_ANGLES = (0.07, -0.11, 0.23, -0.3, 0.02, 0.15)
MIX_WIDTHS = (1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 6.0, 8.0)


def _render(lines, blur, noise, seed, shape=SHAPE):
    """``lines``: (row of the centre, angle, width); returns (image, area, length)."""
    from scipy import ndimage as ndi
    h, w = shape
    yy, xx = np.mgrid[0:h, 0:w]
    cov = np.zeros(shape)
    inside = (xx > MARGIN) & (xx < w - MARGIN)
    length = 0.0
    for y0, ang, width in lines:
        d = np.abs((yy - y0) * np.cos(ang) - (xx - w / 2) * np.sin(ang))
        cov = np.maximum(cov, np.clip(width / 2 + 0.5 - d, 0, 1) * inside)
        length += (w - 2 * MARGIN - 1) / np.cos(ang)
    img = ndi.gaussian_filter(MINERAL_GREY * (1 - cov) + CRACK_GREY * cov, blur)
    img += noise * np.random.default_rng(seed).standard_normal(shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), float(cov.sum()), float(length)


def hairlines(width, blur, noise, seed=0, shape=SHAPE):
    """Six slanted cracks of one width (they cross): ``(image, true area px, length px)``."""
    h = shape[0]
    return _render([((k + 0.5) * h / 6, a, width) for k, a in enumerate(HAIRLINE_ANGLES)],
                   blur, noise, seed, shape)


def line_mix(blur, noise=8.0, seed=1, shape=SHAPE):
    """Eight parallel cracks 1.5-8 px wide: ``(image, true area px, length px)``."""
    h = shape[0]
    return _render([((k + 0.5) * h / len(MIX_WIDTHS), 0.05, wd)
                    for k, wd in enumerate(MIX_WIDTHS)], blur, noise, seed, shape)


CASES = ([("hairlines", dict(width=wd, blur=b, noise=n)) for wd in (1.0, 1.5, 2.0, 3.0)
          for b in (0.6, 1.0, 1.4) for n in (3.0, 8.0)]
         + [("mix", dict(blur=b, noise=8.0)) for b in (0.6, 1.0, 1.4)])


def score(k):
    """Analyse case ``k`` of :data:`CASES`; its truth, semkit's numbers and the errors."""
    from semkit.analysis import analyse_image
    family, kw = CASES[k]
    img, area, length = (hairlines if family == "hairlines" else line_mix)(**kw)
    a = analyse_image(img, pixel_size_um=1.0, stage="failure", classify=False)
    row = a.summary()
    return dict(case=k, family=family, **kw, area_err=row["crack_area_um2"] / area - 1,
                length_err=row["crack_length_um"] / length - 1,
                crack_grey=float(a.thresholded.crack_level), valid=bool(row["valid"]),
                valid_note=row["valid_note"])


def summarise(rows):
    wrong = set(confidently_wrong(rows, key="case"))
    out = {}
    for fam in ("hairlines", "mix"):
        f = [r for r in rows if r["family"] == fam]
        ae = np.abs([r["area_err"] for r in f])
        le = np.abs([r["length_err"] for r in f])
        out[fam] = dict(n=len(f), area_err_median=float(np.median(ae)),
                        area_err_max=float(ae.max()), length_err_median=float(np.median(le)),
                        length_err_max=float(le.max()), n_valid=int(sum(r["valid"] for r in f)),
                        n_confidently_wrong=int(sum(r["case"] in wrong for r in f)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=str(OUT))
    args = ap.parse_args(argv)
    with ProcessPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(score, range(len(CASES))))
    summary = summarise(rows)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "line_family.json").write_text(json.dumps(dict(summary=summary, per_image=rows),
                                                     indent=1))
    print("| family | width | blur | noise | crack grey | area error | length error | valid |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['family']} | {r.get('width', '1.5-8')} | {r['blur']} | {r['noise']:g} | "
              f"{r['crack_grey']:.0f} | {r['area_err']:+.1%} | {r['length_err']:+.1%} | "
              f"{'yes' if r['valid'] else 'no: ' + r['valid_note'][:60]} |")
    for fam, s in summary.items():
        print(f"\n{fam}: {s['n']} images, area error median {s['area_err_median']:.1%} "
              f"(max {s['area_err_max']:.1%}), length {s['length_err_median']:.1%} "
              f"(max {s['length_err_max']:.1%}); valid {s['n_valid']}; confidently wrong "
              f"{s['n_confidently_wrong']} (off by > {WRONG:.0%})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
