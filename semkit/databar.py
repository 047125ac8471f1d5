"""The information bar that SEMs write under (or over) a micrograph, and its scale bar.

Zeiss, Thermo/FEI, TESCAN and JEOL instruments save the micrograph with a band of full-width
rows holding text (voltage, working distance, magnification, date) and a scale bar: a solid
horizontal line with its length written beside it ("200 µm"). :func:`find_data_bar` finds the
band: a run of rows from the bottom (or top) edge where most pixels of every third of the width
share the row's modal grey (a flat background with text on it), beginning abruptly. The sample
above it never looks like that (texture and noise), and neither do the black corners of a round
core, whose middle third is sample.

:func:`read_scale_bar` finds the longest solid horizontal line in the band and reads the label
next to it with a small template OCR (glyphs rendered from the DejaVu Sans faces shipped with
matplotlib, Pillow's default face Aileron and OpenCV's Hershey faces, compared by normalised
correlation on size-normalised binary glyphs; touching glyphs of bold labels cut apart where the
parts read better): digits, ``.``, and the units ``nm``, ``µm`` (or ``um``), ``mm``. The pixel
size is the written length over the line's length in pixels. A label read with low glyph
confidence is not used, nor one with a glyph that reads almost as well as another character (a
"5" drawn in a font unlike the templates can read as "6": a confident misreading would scale
every figure).
"""
from __future__ import annotations

import dataclasses
import functools
import re

import numpy as np

from . import config

__all__ = ["DataBar", "ScaleBar", "DataBarCrop", "find_data_bar", "read_scale_bar",
           "crop_data_bar"]

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
    margin: float = 1.0     #: least lead of a glyph's reading over its next-best character
    ambiguous: str = ""     #: the glyph read with the least lead and its runner-up ("6/5")

    @property
    def pixel_size_um(self):
        return self.length_um / self.length_px if self.length_px > 0 else float("nan")


@dataclasses.dataclass
class DataBarCrop:
    """An image without its data bar, and the pixel size after reading the scale bar."""

    image: np.ndarray
    bar: DataBar | None
    scale_bar: ScaleBar | None
    pixel_size_um: float
    pixel_size_source: str
    note: str = ""          #: why the scale bar was not used, or how it disagrees


def _to_u8(image, rows=slice(None), cols=slice(None)):
    """``image`` stretched to 0..255 (uint8) over its full range; only ``image[rows, cols]``
    is converted (the same values as converting all, then slicing)."""
    a = np.asarray(image)
    if a.dtype.kind in "ui":    # the float32 range of an integer image: exact, no copy
        lo, hi = float(np.float32(a.min())), float(np.float32(a.max()))
    else:
        f = np.asarray(a, np.float32)
        lo, hi = float(f.min()), float(f.max())
    part = np.asarray(a[rows, cols], np.float32)
    return np.zeros(part.shape, np.uint8) if hi <= lo else \
        np.clip((part - lo) * (255.0 / (hi - lo)), 0, 255).astype(np.uint8)


def _row_flatness(u8, tol):
    """Per row: the least share, over the thirds of the width, of pixels within ``tol`` of the
    row's mode; the share over the whole row; the mode.

    From one 256-bin histogram per row and third (``bincount``), not a pass per comparison.
    """
    h, w = u8.shape
    cuts = [k * w // 3 for k in range(4)]
    rows = 256 * np.arange(h, dtype=np.int64)[:, None]
    hist = [np.bincount((u8[:, a:b] + rows).ravel(), minlength=256 * h).reshape(h, 256)
            for a, b in zip(cuts[:-1], cuts[1:])]
    counts = sum(hist).reshape(h, 64, 4).sum(axis=2)  # 64 bins of 4 grey levels
    mode = counts.argmax(axis=1) * 4 + 2
    # pixels within tol of the mode: a window of the cumulative histogram
    lo = np.clip(mode - tol, 0, 256)
    hi = np.clip(mode + tol + 1, 0, 256)
    r = np.arange(h)
    near = []
    for hk in hist:
        c = np.zeros((h, 257), np.int64)
        np.cumsum(hk, axis=1, out=c[:, 1:])
        near.append(c[r, hi] - c[r, lo])
    with np.errstate(invalid="ignore"):  # a third of an image < 3 px wide is empty: NaN
        thirds = [nk / (b - a) for nk, a, b in zip(near, cuts[:-1], cuts[1:])]
    return np.min(thirds, axis=0), sum(near) / w, mode


def find_data_bar(image, *, min_flat=config.DATABAR_MIN_FLAT):
    """Find an SEM information bar along the bottom or top edge.

    Bar rows, counted from the edge: at least ``min_flat`` of the row's pixels are at its
    modal grey, that mode is the bar's background (the mode of the edge row), and in most of
    them this holds in every third of the width. Rows of text or a thick scale bar may
    interrupt the run for at most ``DATABAR_MAX_GAP_ROWS``. Half the rows of the run hold at
    least ``DATABAR_MEDIAN_FLAT`` background. The run must end abruptly (the
    next rows are textured sample: at most ``DATABAR_SAMPLE_FLAT`` of them at the bar's grey,
    or ``DATABAR_SAMPLE_STEP`` less than the bar's median row where the sample is clipped at
    that grey) and carry ink: pixels at the other end of the grey scale (white text on a dark
    bar, dark text on a light one).

    Parameters
    ----------
    image : (M, N) ndarray
        The micrograph as saved by the microscope.
    min_flat : float
        Least share of each third of a bar row that holds the bar's background grey.

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
    h, w = np.shape(image)[:2]
    if h < 40 or w < 40:
        return None
    step = max(w // 1024, 1)
    sub = _to_u8(image, cols=slice(None, None, step))
    thirds, flat, mode = _row_flatness(np.ascontiguousarray(sub), config.DATABAR_TOL_GREY)
    tol = config.DATABAR_TOL_GREY + 2
    for side in ("bottom", "top"):
        fl = flat[::-1] if side == "bottom" else flat
        th = thirds[::-1] if side == "bottom" else thirds
        md = mode[::-1] if side == "bottom" else mode
        ref = int(md[0])
        n_min = max(config.DATABAR_MIN_ROWS, int(config.DATABAR_MIN_FRACTION * h))
        n = _bar_run((fl >= min_flat) & (np.abs(md - ref) <= tol))
        if not _is_bar(image, sub, fl, th, n, side, ref, min_flat, n_min):
            # a sample clipped at the bar's grey continues that run: then the bar's rows are
            # those far flatter than the sample (within DATABAR_SAMPLE_STEP of the edge rows),
            # ending in one step of that much (a round core's corner fades row by row)
            edge = float(np.median(fl[:n_min]))
            n = _bar_run((fl >= max(min_flat, edge - config.DATABAR_SAMPLE_STEP))
                         & (np.abs(md - ref) <= tol))
            step = fl[n - 3:n].max() - fl[n:n + 3].max() if 3 <= n < len(fl) else 0.0
            if step < config.DATABAR_SAMPLE_STEP or \
                    not _is_bar(image, sub, fl, th, n, side, ref, min_flat, n_min, clipped=True):
                continue
        r0, r1 = (h - n, h) if side == "bottom" else (0, n)
        return DataBar(r0, r1, side, float(ref))
    return None


def _is_bar(image, sub, fl, th, n, side, ref, min_flat, n_min, clipped=False):
    """Whether the ``n`` rows from the ``side`` edge (flatness ``fl``, ``th`` counted from
    that edge) are a data bar of background grey ``ref``; ``clipped``: the sample past it may be
    clipped at that grey (then its rows may hold up to ``DATABAR_SAMPLE_STEP`` less than the
    bar's median row at it, the step :func:`find_data_bar` has checked)."""
    h = len(sub)
    if n < n_min or n > config.DATABAR_MAX_FRACTION * h:
        return False
    # an abrupt start: the rows just past the bar are sample, not the bar's grey (a round
    # core's corners fade; a sample clipped at the other end of the grey scale is flat
    # too, but not at the bar's grey), and the background spans the width in most bar
    # rows (a core's corner does not)
    r0, r1 = (h - n, h) if side == "bottom" else (0, n)
    past = sub[max(r0 - 3, 0):r0] if side == "bottom" else sub[r1:r1 + 3]
    at_bar = (np.abs(past.astype(np.int16) - ref) <= config.DATABAR_TOL_GREY).mean(
        axis=1) if past.size else np.zeros(1)
    # a bar is flat: most of its rows are mostly background, far flatter than the sample
    # (a noisy image of large uniform grains has rows 40-50 % "flat" everywhere)
    bar_flat = float(np.median(fl[:n]))
    if bar_flat < config.DATABAR_MEDIAN_FLAT:
        return False
    past_max = max(config.DATABAR_SAMPLE_FLAT, bar_flat - config.DATABAR_SAMPLE_STEP) \
        if clipped else config.DATABAR_SAMPLE_FLAT
    if at_bar.max() > past_max or np.mean(th[:n] >= min_flat) < 0.5:
        return False
    # a bar carries text or a scale bar at the other end of the grey scale
    rows = _to_u8(image, rows=slice(r0, r1))
    ink = rows >= 255 - config.DATABAR_INK_GREY if ref < 128 else \
        rows <= config.DATABAR_INK_GREY
    return ink.mean() >= config.DATABAR_MIN_INK


def _bar_run(is_bar):
    """Rows from the edge up to the last bar row before a gap of more than
    ``DATABAR_MAX_GAP_ROWS``."""
    n, gap = 0, 0
    for k, b in enumerate(is_bar):
        if b:
            n, gap = k + 1, 0
        else:
            gap += 1
            if gap > config.DATABAR_MAX_GAP_ROWS:
                break
    return n


#: OpenCV's Hershey faces (what scripts and many acquisition programs write with
#: ``cv2.putText``), rendered at a 48-px cap height with these stroke widths (px): from a
#: 1-px stroke on a 30-px label to a 2-px stroke on a 12-px one
_HERSHEY_STROKES = (2, 4, 7)


@functools.lru_cache(maxsize=1)
def _templates():
    """Normalised binary glyphs of :data:`_GLYPHS`: the DejaVu Sans faces of matplotlib,
    Aileron (Pillow's default face, a Helvetica-like sans) and OpenCV's Hershey faces.

    Returns the character, normalised glyph, aspect and face name of every template."""
    import os

    import cv2
    import matplotlib
    from PIL import Image, ImageDraw, ImageFont
    base = os.path.join(os.path.dirname(matplotlib.__file__), "mpl-data", "fonts", "ttf")
    fonts = [(ImageFont.truetype(os.path.join(base, f), 48), _GLYPHS)
             for f in ("DejaVuSans.ttf", "DejaVuSans-Bold.ttf", "DejaVuSansMono.ttf")]
    fonts.append((ImageFont.load_default(48), _GLYPHS.replace("µ", "")))  # Aileron: no "µ"
    names, vecs, aspects, faces = [], [], [], []

    def add(ch, g, face):
        v, asp = _normalise(g)
        names.append(ch)
        vecs.append(v)
        aspects.append(asp)
        faces.append(face)

    for font, chars in fonts:
        for ch in chars:
            im = Image.new("L", (80, 90), 0)
            ImageDraw.Draw(im).text((10, 5), ch, fill=255, font=font)
            add(ch, np.asarray(im) > 127, " ".join(font.getname()))
    for face, name in ((cv2.FONT_HERSHEY_SIMPLEX, "simplex"), (cv2.FONT_HERSHEY_DUPLEX, "duplex"),
                       (cv2.FONT_HERSHEY_COMPLEX, "complex"), (cv2.FONT_HERSHEY_PLAIN, "plain")):
        for thick in _HERSHEY_STROKES:
            scale = cv2.getFontScaleFromHeight(face, 48, thick)
            for ch in _GLYPHS.replace("µ", ""):  # Hershey has no "µ"
                im = np.zeros((110, 90), np.uint8)
                cv2.putText(im, ch, (15, 75), face, scale, 255, thick, cv2.LINE_AA)
                add(ch, im > 127, f"Hershey {name} {thick}")
    return names, np.array(vecs), np.array(aspects), faces


def _normalise(glyph):
    import cv2
    rr, cc = np.nonzero(glyph)
    g = glyph[rr.min():rr.max() + 1, cc.min():cc.max() + 1].astype(np.float32)
    asp = g.shape[1] / g.shape[0]
    r = cv2.resize(g, _GLYPH_SIZE[::-1], interpolation=cv2.INTER_AREA).ravel()
    r = r - r.mean()
    return r / (np.linalg.norm(r) + 1e-9), asp


def _words(glyphs):
    """Group glyph boxes ``(r0, c0, r1, c1, id)`` into words: same text line (vertical
    overlap), horizontal gaps under one glyph height; each word sorted by x."""
    glyphs = sorted(glyphs, key=lambda g: g[1])
    lines = []
    for g in glyphs:
        for ln in lines:
            r0, r1 = min(x[0] for x in ln), max(x[2] for x in ln)
            if min(r1, g[2]) - max(r0, g[0]) > 0.3 * min(r1 - r0, g[2] - g[0]) or \
                    (g[2] - g[0] < 0.35 * (r1 - r0) and r0 <= g[2] <= r1 + 2):
                ln.append(g)
                break
        else:
            lines.append([g])
    words = []
    for ln in lines:
        ln.sort(key=lambda g: g[1])
        height = max(g[2] - g[0] for g in ln)
        cur = [ln[0]]
        for g in ln[1:]:
            if g[1] - max(x[3] for x in cur) > config.SCALEBAR_WORD_GAP * height:
                words.append(cur)
                cur = [g]
            else:
                cur.append(g)
        words.append(cur)
    return words


def _score(g):
    """Template scores of a binary glyph: the best character, its correlation, and its lead
    over the best other character with that character's name."""
    names, vecs, aspects, _ = _templates()
    v, asp = _normalise(g)
    score = vecs @ v - 0.5 * np.abs(np.log(aspects / asp))
    k = int(np.argmax(score))
    other = np.where(np.asarray(names) == names[k], -np.inf, score)
    j = int(np.argmax(other))
    return names[k], float(vecs[k] @ v), float(score[k] - other[j]), names[j]


def _split(box, g, height, depth=0):
    """Touching glyphs of one ink component (bold text on a small label): a box wider than
    ``SCALEBAR_SPLIT_ASPECT`` of the text height is cut at its faintest column in the middle
    two fifths (of its three faintest there, the one whose parts read best) when both parts
    correlate with a template better than the whole; repeated on the parts. Returns a list of
    ``(box, glyph)``."""
    r0, c0, r1, c1 = box
    w = c1 - c0
    if depth > 3 or w <= config.SCALEBAR_SPLIT_ASPECT * height:
        return [(box, g)]
    cols = g.sum(axis=0)
    lo, hi = int(0.3 * w), int(np.ceil(0.7 * w))
    best, parts = _score(g)[1], None
    for cut in lo + np.argsort(cols[lo:hi], kind="stable")[:3]:  # the faintest columns
        cand = []
        for a, b in ((0, cut), (cut + (cols[cut] == 0), w)):
            rows = np.flatnonzero(g[:, a:b].any(axis=1))
            if not rows.size:
                break
            cand.append(((r0 + rows[0], c0 + a, r0 + rows[-1] + 1, c0 + b),
                         g[rows[0]:rows[-1] + 1, a:b]))
        else:
            worst = min(_score(p[1])[1] for p in cand)
            if worst > best:
                best, parts = worst, cand
    if parts is None:
        return [(box, g)]
    return [q for p in parts for q in _split(*p, height, depth + 1)]


def _read_glyphs(boxes, height):
    """OCR of glyph boxes (sorted by x).

    Returns the text, the lowest template correlation of its glyphs, and the least lead of
    a glyph's best score over the best score of any other character, with that glyph and its
    runner-up (``"6/5"``; ``""`` when no glyph was scored).
    """
    text, conf, margin, which, prev_x1 = "", 1.0, 1.0, "", None
    for (r0, c0, r1, c1), g in (q for b in boxes for q in _split(*b, height)):
        h = r1 - r0
        if h < 0.35 * height and (c1 - c0) < 0.5 * height:
            ch, c = ".", 1.0
        else:
            ch, c, lead, alt = _score(g)
            if lead < margin:
                margin, which = lead, f"{ch}/{alt}"
        if prev_x1 is not None and c0 - prev_x1 > 0.45 * height:
            text += " "
        text += ch
        conf = min(conf, c)
        prev_x1 = c1
    return text, conf, margin, which


def _is_dot(g, other):
    """Whether glyph box ``g`` is a decimal point beside ``other``: at most 0.4 of its height
    tall and half as wide, on its baseline (a dot 1 px from a digit is not a broken stroke)."""
    h = other[2] - other[0]
    return (g[2] - g[0] <= 0.4 * h and g[3] - g[1] <= 0.5 * h
            and abs(g[2] - other[2]) <= max(1.0, 0.15 * h))


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
    u8 = _to_u8(image, rows=slice(bar.row0, bar.row1))
    fg = (u8 >= 255 - config.DATABAR_INK_GREY if bar.background < 128
          else u8 <= config.DATABAR_INK_GREY).astype(np.uint8)
    n, lab, st, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
    bh, w_img = u8.shape
    lines = []
    for k in range(1, n):
        x, y, w, h, _ = (int(v) for v in st[k])
        if w < config.SCALEBAR_MIN_FRACTION * w_img or w < 6 * h or h > 0.35 * bh:
            continue
        rows = (lab[y:y + h, x:x + w] == k).sum(axis=1)
        if rows.max() >= 0.95 * w:  # a solid line (end ticks only make the box taller)
            lines.append((k, float(rows.max())))
    if not lines:
        return None
    k, length = max(lines, key=lambda t: t[1])
    x0, y0, w, h = (int(v) for v in st[k, :4])
    # glyphs: ink components of text size (at a third of the contrast, so thin anti-aliased
    # strokes and small dots hold together; touching pieces merged), grouped into words
    half = (np.abs(u8.astype(np.int16) - int(bar.background)) > 85).astype(np.uint8)
    half[lab == k] = 0
    n2, lab2, st2, _ = cv2.connectedComponentsWithStats(half, connectivity=8)
    glyphs = []
    for j in sorted(range(1, n2), key=lambda i: st2[i, 0]):
        gx, gy, gw, gh, _ = (int(v) for v in st2[j])
        if gh > 0.6 * bh or gw > 3 * max(gh, 1) or gh * gw < 2:
            continue
        g = (gy, gx, gy + gh, gx + gw, (j,))
        p = glyphs[-1] if glyphs else None
        if p is not None and gx - p[3] <= 1 and min(p[2], g[2]) - max(p[0], g[0]) > \
                0.5 * min(p[2] - p[0], gh) and \
                gx + gw - p[1] <= 1.5 * (max(p[2], gy + gh) - min(p[0], gy)) and \
                not (gx >= p[3] and (_is_dot(g, p) or _is_dot(p, g))):
            glyphs[-1] = (min(p[0], gy), p[1], max(p[2], gy + gh), max(p[3], gx + gw),
                          p[4] + (j,))
        else:
            glyphs.append(g)
    words = _words(glyphs)
    best = None
    for word in words:
        boxes = [((g[0], g[1], g[2], g[3]), np.isin(lab2[g[0]:g[2], g[1]:g[3]], g[4]))
                 for g in word]
        height = float(max(g[2] - g[0] for g in word))
        text, conf, margin, which = _read_glyphs(boxes, height)
        m = re.fullmatch(r"(\d+(?:\.\d+)?) ?(nm|µm|um|mm)", text)
        if not m:
            continue
        cy = (min(g[0] for g in word) + max(g[2] for g in word)) / 2
        cx = (min(g[1] for g in word) + max(g[3] for g in word)) / 2
        dist = abs(cy - (y0 + h / 2)) + max(0.0, abs(cx - (x0 + w / 2)) - w / 2)
        if best is None or dist < best[0]:
            best = (dist, text, conf, float(m.group(1)) * _UNIT_UM[m.group(2)], margin, which)
    if best is None:
        text, conf, length_um, margin, which = "", 0.0, float("nan"), 0.0, ""
    else:
        _, text, conf, length_um, margin, which = best
        if conf < config.SCALEBAR_MIN_CONFIDENCE or margin < config.SCALEBAR_MIN_MARGIN:
            length_um = float("nan")
    return ScaleBar(length, text, length_um, conf,
                    (bar.row0 + y0, x0, bar.row0 + y0 + h, x0 + w), margin, which)


def crop_data_bar(image, *, pixel_size_um, pixel_size_source):
    """Crop the data bar and take the pixel size from its scale bar when none was known.

    Parameters
    ----------
    image : (M, N) ndarray
    pixel_size_um : float
    pixel_size_source : str
        Where ``pixel_size_um`` came from; only ``default`` is replaced by the scale bar
        (source ``scale_bar``). A given pixel size is kept, and a scale bar disagreeing by more
        than ``SCALEBAR_AGREE_FRACTION`` is said in ``note``.

    Returns
    -------
    crop : DataBarCrop
    """
    bar = find_data_bar(image)
    if bar is None:
        return DataBarCrop(image, None, None, pixel_size_um, pixel_size_source)
    img = np.ascontiguousarray(image[bar.row1:] if bar.side == "top" else image[:bar.row0])
    sb = read_scale_bar(image, bar)
    out = DataBarCrop(img, bar, sb, pixel_size_um, pixel_size_source)
    if sb is None:
        return out
    if not np.isfinite(sb.length_um):
        why = ""
        if sb.text and sb.confidence >= config.SCALEBAR_MIN_CONFIDENCE:
            read, alt = sb.ambiguous.split("/")
            why = f": its {read!r} reads almost as well as {alt!r}"
        out.note = f"scale bar label unreadable ({sb.text!r}{why})"
        return out
    px = sb.pixel_size_um
    if pixel_size_source == "default":
        out.pixel_size_um, out.pixel_size_source = px, "scale_bar"
    elif abs(px / pixel_size_um - 1) > config.SCALEBAR_AGREE_FRACTION:
        out.note = (f"scale bar ({sb.text.strip()} over {sb.length_px:.0f} px) gives "
                    f"{px:.4g} um/px, not {pixel_size_um:.4g}")
    return out
