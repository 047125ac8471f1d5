"""The information bar that SEMs write under (or over) a micrograph, and its scale bar.

Zeiss, Thermo/FEI, TESCAN and JEOL instruments save the micrograph with a band of full-width
rows holding text (voltage, working distance, magnification, date) and a scale bar: a solid
horizontal line with its length written beside it ("200 µm"). :func:`find_data_bar` finds the
band: a run of rows from the bottom (or top) edge where most pixels of every third of the width
share the row's modal grey (a flat background with text on it), beginning abruptly. The sample
above it never looks like that (texture and noise), and neither do the black corners of a round
core, whose middle third is sample.

:func:`read_scale_bar` finds the longest solid horizontal line in the band and reads the label
next to it with a small template OCR (glyphs rendered from the DejaVu fonts shipped with
matplotlib, compared by normalised correlation on size-normalised binary glyphs): digits,
``.``, and the units ``nm``, ``µm`` (or ``um``), ``mm``. The pixel size is the written length
over the line's length in pixels. A label read with low glyph confidence is not used.
"""
from __future__ import annotations

import dataclasses
import functools
import re

import numpy as np

from . import config

__all__ = ["DataBar", "ScaleBar", "find_data_bar", "read_scale_bar"]

_GLYPHS = "0123456789.µmnu"
_GLYPH_SIZE = (24, 16)  # rows, cols of the normalised glyph
_UNIT_UM = {"nm": 1e-3, "µm": 1.0, "um": 1.0, "mm": 1e3}


@dataclasses.dataclass
class DataBar:
    """Rows ``[row0, row1)`` of an information bar at the image's ``side`` (bottom or top)."""

    row0: int
    row1: int
    side: str
    background: float  #: modal grey of the bar


@dataclasses.dataclass
class ScaleBar:
    """A scale bar read from a data bar."""

    length_px: float        #: length of the line, px
    text: str               #: the label as read
    length_um: float        #: the label's length in µm (NaN if unreadable)
    confidence: float       #: lowest glyph correlation of the label (0-1)
    box: tuple              #: (row0, col0, row1, col1) of the line in the image

    @property
    def pixel_size_um(self):
        return self.length_um / self.length_px if self.length_px > 0 else float("nan")


def _to_u8(image):
    a = np.asarray(image, np.float32)
    lo, hi = float(a.min()), float(a.max())
    return np.zeros(a.shape, np.uint8) if hi <= lo else \
        np.clip((a - lo) * (255.0 / (hi - lo)), 0, 255).astype(np.uint8)


def _row_flatness(u8, tol):
    """Per row and per third of the width: share of pixels within ``tol`` of the row's mode."""
    h, w = u8.shape
    q = (u8 >> 2).astype(np.int64)  # 64 bins
    counts = np.zeros((h, 64), np.int64)
    np.add.at(counts, (np.repeat(np.arange(h), w), q.ravel()), 1)
    mode = counts.argmax(axis=1) * 4 + 2
    near = np.abs(u8.astype(np.int16) - mode[:, None]) <= tol
    thirds = [near[:, k * w // 3:(k + 1) * w // 3].mean(axis=1) for k in range(3)]
    return np.min(thirds, axis=0), mode


def find_data_bar(image, *, min_flat=config.DATABAR_MIN_FLAT):
    """Find an SEM information bar along the bottom or top edge.

    Parameters
    ----------
    image : (M, N) ndarray
        The micrograph as saved by the microscope.
    min_flat : float
        Least share of each third of a bar row that holds the row's modal grey.

    Returns
    -------
    bar : DataBar or None

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> img = rng.integers(60, 200, (120, 160)).astype(np.uint8)
    >>> img[100:] = 0; img[106:112, 20:70] = 255   # a black bar with a white scale bar
    >>> b = find_data_bar(img); (b.row0, b.row1, b.side)
    (100, 120, 'bottom')
    """
    u8 = _to_u8(image)
    h = u8.shape[0]
    if h < 40 or u8.shape[1] < 40:
        return None
    step = max(u8.shape[1] // 1024, 1)
    flat, mode = _row_flatness(np.ascontiguousarray(u8[:, ::step]), config.DATABAR_TOL_GREY)
    is_bar = flat >= min_flat
    for side in ("bottom", "top"):
        rows = is_bar[::-1] if side == "bottom" else is_bar
        # a run from the edge, allowing short gaps (text lines that fill a row)
        n, gap = 0, 0
        for k, b in enumerate(rows):
            if b:
                n, gap = k + 1, 0
            else:
                gap += 1
                if gap > config.DATABAR_MAX_GAP_ROWS:
                    break
        if n < max(config.DATABAR_MIN_ROWS, int(config.DATABAR_MIN_FRACTION * h)) or \
                n > config.DATABAR_MAX_FRACTION * h:
            continue
        # an abrupt start: the rows just past the bar are sample, not flat
        sample_flat = (flat[::-1] if side == "bottom" else flat)[n:n + 3]
        if sample_flat.max() > config.DATABAR_SAMPLE_FLAT:
            continue
        r0, r1 = (h - n, h) if side == "bottom" else (0, n)
        bg = float(np.median(mode[r0:r1]))
        # a bar carries text or a scale bar; empty rows are a surround (semkit.roi)
        ink = np.abs(u8[r0:r1].astype(np.int16) - int(bg)) > config.DATABAR_INK_GREY
        if ink.mean() < config.DATABAR_MIN_INK:
            continue
        return DataBar(r0, r1, side, bg)
    return None


@functools.lru_cache(maxsize=1)
def _templates():
    """Normalised binary glyphs of :data:`_GLYPHS` in the DejaVu fonts of matplotlib."""
    import os

    import matplotlib
    from PIL import Image, ImageDraw, ImageFont
    base = os.path.join(os.path.dirname(matplotlib.__file__), "mpl-data", "fonts", "ttf")
    names, vecs, aspects = [], [], []
    for fname in ("DejaVuSans.ttf", "DejaVuSans-Bold.ttf", "DejaVuSansMono.ttf"):
        font = ImageFont.truetype(os.path.join(base, fname), 48)
        for ch in _GLYPHS:
            im = Image.new("L", (80, 90), 0)
            ImageDraw.Draw(im).text((10, 5), ch, fill=255, font=font)
            g = np.asarray(im) > 127
            v, asp = _normalise(g)
            names.append(ch)
            vecs.append(v)
            aspects.append(asp)
    return names, np.array(vecs), np.array(aspects)


def _normalise(glyph):
    import cv2
    rr, cc = np.nonzero(glyph)
    g = glyph[rr.min():rr.max() + 1, cc.min():cc.max() + 1].astype(np.float32)
    asp = g.shape[1] / g.shape[0]
    r = cv2.resize(g, _GLYPH_SIZE[::-1], interpolation=cv2.INTER_AREA).ravel()
    r = r - r.mean()
    return r / (np.linalg.norm(r) + 1e-9), asp


def _read_glyphs(fg, boxes, height):
    """OCR of glyph boxes (sorted by x): text and the lowest correlation."""
    names, vecs, aspects = _templates()
    text, conf, prev_x1 = "", 1.0, None
    for (r0, c0, r1, c1), g in boxes:
        h = r1 - r0
        if h < 0.35 * height and (c1 - c0) < 0.5 * height:
            ch, c = ".", 1.0
        else:
            v, asp = _normalise(g)
            score = vecs @ v - 0.5 * np.abs(np.log(aspects / asp))
            k = int(np.argmax(score))
            ch, c = names[k], float(vecs[k] @ v)
        if prev_x1 is not None and c0 - prev_x1 > 0.45 * height:
            text += " "
        text += ch
        conf = min(conf, c)
        prev_x1 = c1
    return text, conf


def read_scale_bar(image, bar):
    """Find the scale bar in a data bar and read its label.

    Parameters
    ----------
    image : (M, N) ndarray
        The full micrograph.
    bar : DataBar

    Returns
    -------
    scale : ScaleBar or None
        None when no solid horizontal line is found; ``length_um`` NaN when its label cannot
        be read as ``<number> <nm|µm|um|mm>``.
    """
    import cv2
    u8 = _to_u8(image)[bar.row0:bar.row1]
    fg = (np.abs(u8.astype(np.int16) - int(bar.background)) > config.DATABAR_INK_GREY
          ).astype(np.uint8)
    n, lab, st, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
    w_img = u8.shape[1]
    lines = [k for k in range(1, n) if st[k, 2] >= config.SCALEBAR_MIN_FRACTION * w_img
             and st[k, 2] >= 6 * st[k, 3] and st[k, 4] >= 0.6 * st[k, 2] * st[k, 3]]
    if not lines:
        return None
    k = max(lines, key=lambda i: st[i, 2])
    x0, y0, w, h = (int(v) for v in st[k, :4])
    # the length is the longest row of the line (end ticks make the box taller, not longer)
    length = float((lab[y0:y0 + h, x0:x0 + w] == k).sum(axis=1).max())
    # glyphs: components beside the line, of text size
    glyphs = []
    for j in range(1, n):
        if j == k or j in lines:
            continue
        gx, gy, gw, gh, ga = (int(v) for v in st[j])
        if gh < 5 or gh > 0.9 * u8.shape[0] or gw > 4 * gh:
            continue
        near_x = gx + gw > x0 - 0.6 * w and gx < x0 + 1.6 * w
        near_y = min(abs(gy + gh - y0), abs(gy - (y0 + h)), abs(gy - y0)) < 3 * max(gh, h)
        if near_x and near_y:
            glyphs.append((gy, gx, gy + gh, gx + gw, j))
    text, conf = "", 0.0
    if glyphs:
        # the text line: glyphs whose vertical centre is near the median one
        mid = np.median([(g[0] + g[2]) / 2 for g in glyphs])
        height = np.median([g[2] - g[0] for g in glyphs])
        line = sorted((g for g in glyphs if abs((g[0] + g[2]) / 2 - mid) < 0.6 * height
                       or (g[2] - g[0]) < 0.35 * height and abs(g[2] - mid) < height),
                      key=lambda g: g[1])
        boxes = [((g[0], g[1], g[2], g[3]), lab[g[0]:g[2], g[1]:g[3]] == g[4]) for g in line]
        text, conf = _read_glyphs(fg, boxes, float(max(g[2] - g[0] for g in line)))
    m = re.search(r"(\d+(?:\.\d+)?)\s*(nm|µm|um|mm)", text.replace(" ", "").replace("uum", "um"))
    length_um = float(m.group(1)) * _UNIT_UM[m.group(2)] \
        if m and conf >= config.SCALEBAR_MIN_CONFIDENCE else float("nan")
    return ScaleBar(length, text, length_um, conf,
                    (bar.row0 + y0, x0, bar.row0 + y0 + h, x0 + w))
