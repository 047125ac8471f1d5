"""Benchmark: reading SEM scale-bar labels drawn in fonts the OCR has templates of, and in fonts
it has none of.

:mod:`semkit.databar` reads a scale bar's label by template correlation against glyphs of the
DejaVu Sans faces, Aileron (Pillow's default face) and OpenCV's Hershey simplex, duplex, complex
and plain faces. Labels of the usual lengths (1-2-2.5-3-5 series, µm and mm) are drawn here under
a 10-px line on a dark and a light bar, at two text heights, in those fonts and in fonts that are
*not* templates: Computer Modern Sans and Roman, DejaVu Serif, STIX (matplotlib's), Liberation
Sans, Sans Narrow and Serif (Debian's fonts-liberation, metric twins of Arial and Times; left out
where absent) and OpenCV's Hershey triplex and complex-small at two stroke widths. Each label is
scored as

* ``correct`` -- read, and the value is right;
* ``wrong`` -- read, and the value is wrong (the pixel size, and every figure in µm, would be
  wrong while looking fine: this must be zero);
* ``unread`` -- the label is not used (low glyph correlation, a glyph that reads almost as well
  as another character, or no ``<number> <unit>`` word): the image is flagged, not wrong.

Run with the margin rule (``SCALEBAR_MIN_MARGIN``) as configured and with it off (0), so the
rule's cost (correct readings given up) is read beside what it prevents.

Writes ``benchmarks/semkit_results/scale_bar_fonts.json`` and prints a markdown table.

Run: ``python benchmarks/scale_bar_fonts.py``
"""
from __future__ import annotations

import json
import pathlib
import sys

import cv2
import numpy as np
from matplotlib import font_manager
from PIL import Image, ImageDraw, ImageFont

from semkit import config, databar

OUT = pathlib.Path(__file__).resolve().parent / "semkit_results"
LABELS = [(1, "um"), (2, "um"), (2.5, "um"), (3, "um"), (5, "um"), (10, "um"), (20, "um"),
          (25, "um"), (30, "um"), (50, "um"), (100, "um"), (200, "um"), (250, "um"),
          (300, "um"), (500, "um"), (1, "mm"), (2, "mm"), (500, "nm"), (200, "nm"), (40, "um"),
          (400, "um"), (60, "um"), (80, "um"), (800, "um"), (150, "um"), (75, "um")]
TTF = {"cmss10": "unseen", "cmr10": "unseen", "DejaVu Serif": "unseen", "STIXGeneral": "unseen",
       "Liberation Sans": "unseen", "Liberation Serif": "unseen",
       "Liberation Sans Narrow": "unseen", "DejaVu Sans": "template",
       "DejaVu Sans Mono": "template", "Aileron": "template"}
HERSHEY = {"hershey_simplex": cv2.FONT_HERSHEY_SIMPLEX, "hershey_duplex": cv2.FONT_HERSHEY_DUPLEX,
           "hershey_plain": cv2.FONT_HERSHEY_PLAIN, "hershey_complex": cv2.FONT_HERSHEY_COMPLEX,
           "hershey_triplex": cv2.FONT_HERSHEY_TRIPLEX,
           "hershey_complex_small": cv2.FONT_HERSHEY_COMPLEX_SMALL}
HERSHEY_KIND = {"hershey_triplex": "unseen", "hershey_complex_small": "unseen"}


def bar_image(value, unit, font, size, dark, thick=1, rng=None):
    """A 400 x 640 micrograph-like noise field with a data bar holding one labelled line."""
    rng = rng or np.random.default_rng(0)
    w, bh = 640, max(int(2.6 * size), 40)
    sample = np.clip(rng.normal(140, 25, (400, w)), 0, 255).astype(np.uint8)
    bg, ink = (0, 255) if dark else (240, 0)
    bar = Image.new("L", (w, bh), bg)
    d = ImageDraw.Draw(bar)
    label = f"{value:g} {unit}"
    length = 100 + int(rng.integers(0, 200))
    x0, y = 380, int(0.72 * bh)
    d.rectangle([x0, y, x0 + length - 1, y + 3], fill=ink)
    if font in HERSHEY:
        a = np.array(bar)
        scale = cv2.getFontScaleFromHeight(HERSHEY[font], size, thick)
        cv2.putText(a, label, (x0, int(0.55 * bh)), HERSHEY[font], scale, ink, thick, cv2.LINE_AA)
        bar = Image.fromarray(a)
    else:
        d.text((x0, 2), label, fill=ink, font=_font(font, size))
    return np.vstack([sample, np.asarray(bar)]), value * {"nm": 1e-3, "mm": 1e3}.get(unit, 1.0)


SYSTEM = {"Liberation Sans": "LiberationSans-Regular.ttf",
          "Liberation Serif": "LiberationSerif-Regular.ttf",
          "Liberation Sans Narrow": "LiberationSansNarrow-Regular.ttf"}


def _font(name, size):
    if name == "Aileron":  # Pillow's default face
        return ImageFont.load_default(size)
    if name in SYSTEM:  # Debian's fonts-liberation (the Arial / Times metric faces)
        found = sorted(pathlib.Path("/usr/share/fonts").rglob(SYSTEM[name]))
        if not found:
            raise ValueError(name)
        return ImageFont.truetype(str(found[0]), size)
    return ImageFont.truetype(font_manager.findfont(name, fallback_to_default=False), size)


def _available(name):
    """False for a system font this machine lacks (the Liberation faces)."""
    try:
        _font(name, 12)
    except ValueError:
        return False
    return True


def score(font, thick, margin):
    old = config.SCALEBAR_MIN_MARGIN
    config.SCALEBAR_MIN_MARGIN = margin
    out = {"correct": 0, "wrong": 0, "unread": 0, "wrong_labels": []}
    try:
        rng = np.random.default_rng(1)
        for size in (16, 26):
            for dark in (True, False):
                for value, unit in LABELS:
                    img, um = bar_image(value, unit, font, size, dark, thick, rng)
                    bar = databar.find_data_bar(img)
                    sb = databar.read_scale_bar(img, bar) if bar is not None else None
                    if sb is None or not np.isfinite(sb.length_um):
                        out["unread"] += 1
                    elif abs(sb.length_um / um - 1) < 1e-6:
                        out["correct"] += 1
                    else:
                        out["wrong"] += 1
                        out["wrong_labels"].append(f"{value:g} {unit} -> {sb.text}")
    finally:
        config.SCALEBAR_MIN_MARGIN = old
    return out


def main():
    fonts = [(f, 1, kind) for f, kind in TTF.items() if _available(f)] + \
        [(f, t, HERSHEY_KIND.get(f, "template")) for f in HERSHEY for t in (1, 2)]
    rows = []
    for font, thick, kind in fonts:
        for margin in (config.SCALEBAR_MIN_MARGIN, 0.0):
            r = score(font, thick, margin)
            rows.append(dict(font=font, thickness=thick, kind=kind, margin=margin, **r))
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "scale_bar_fonts.json").write_text(json.dumps(dict(
        n_labels_per_font=4 * len(LABELS), rows=rows), indent=1))
    print(f"{4 * len(LABELS)} labels per font (26 values, 2 sizes, dark and light bars)\n")
    print("| font | templates? | margin rule | correct | wrong | unread |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        name = r["font"] + (f" (stroke {r['thickness']})" if r["font"] in HERSHEY else "")
        print(f"| {name} | {r['kind']} | {'on' if r['margin'] > 0 else 'off'} | {r['correct']} | "
              f"{r['wrong']} | {r['unread']} |")
    for margin in (config.SCALEBAR_MIN_MARGIN, 0.0):
        sel = [r for r in rows if r["margin"] == margin and r["kind"] == "unseen"]
        print(f"unseen fonts, margin {margin:g}: correct {sum(r['correct'] for r in sel)}, "
              f"wrong {sum(r['wrong'] for r in sel)}, unread {sum(r['unread'] for r in sel)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
