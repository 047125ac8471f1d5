"""A report as one self-contained ``report.html`` and the same content as ``report.md``.

The HTML holds everything it shows: figures inline as base64 PNG (large images scaled down to
:data:`MAX_WIDTH_PX`), a small inline style sheet, no script, no link to anything outside it,
so it opens from a USB stick. The Markdown has the same headings, text and tables, and shows
the figures from their files (relative paths beside it), for version control.
"""
from __future__ import annotations

import base64
import html
import math
import os
import pathlib

__all__ = ["Report", "MAX_WIDTH_PX", "format_value"]

#: Images wider than this are scaled down before they are inlined in the HTML.
MAX_WIDTH_PX = 900

_STYLE = """
body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:0.6em 0 1.2em;font-size:0.9em}
th,td{border:1px solid #bbb;padding:3px 8px;text-align:right}
th{background:#eee}td.t,th.t{text-align:left}
figure{display:inline-block;margin:0.5em 1em 1em 0;vertical-align:top}
figcaption{font-size:0.85em;color:#444;max-width:600px}
img{max-width:100%;height:auto;border:1px solid #ddd}
.bad{color:#b00}.ok{color:#070}p.note{font-size:0.9em;color:#444}
"""


def format_value(v, digits=4) -> str:
    """A table cell: numbers with ``digits`` significant digits, NaN/None as '–'.

    Examples
    --------
    >>> format_value(3.14159), format_value(None), format_value(True), format_value(12345.6)
    ('3.142', '–', 'True', '1.235e+04')
    """
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    if isinstance(v, bool) or type(v).__name__ == "bool_":
        return str(bool(v))
    if isinstance(v, float) or type(v).__name__.startswith("float"):
        return format(float(v), f".{digits}g")
    return str(v)


def _md_cell(cell) -> str:
    return format_value(cell).replace("|", "\\|")


def _is_text(cell) -> bool:
    """A cell shown left-aligned: text that is not a number."""
    if not isinstance(cell, str):
        return False
    try:
        float(cell.split(" ± ")[0])
    except ValueError:
        return cell != "–"
    return False


def _png_data(path) -> str:
    """Base64 PNG of an image file, scaled down to MAX_WIDTH_PX wide."""
    import cv2
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise ValueError(f"{path}: not a readable image")
    if img.shape[1] > MAX_WIDTH_PX:
        h = int(round(img.shape[0] * MAX_WIDTH_PX / img.shape[1]))
        img = cv2.resize(img, (MAX_WIDTH_PX, max(h, 1)), interpolation=cv2.INTER_AREA)
    ok, buf = cv2.imencode(".png", img, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:
        raise ValueError(f"{path}: cannot encode as PNG")
    return base64.b64encode(buf.tobytes()).decode("ascii")


class Report:
    """Blocks of a report (headings, text, tables, figures) written as HTML and Markdown.

    Examples
    --------
    >>> r = Report("A run")
    >>> r.heading("Numbers"); r.table(["a", "b"], [[1, 2.5]])
    >>> print(r.markdown("."))
    # A run
    <BLANKLINE>
    ## Numbers
    <BLANKLINE>
    | a | b |
    |---|---|
    | 1 | 2.5 |
    <BLANKLINE>
    """

    def __init__(self, title: str):
        self.title = title
        self.blocks = []

    def heading(self, text: str, level: int = 2):
        self.blocks.append(("h", level, text))

    def text(self, text: str, note: bool = False):
        self.blocks.append(("p", note, text))

    def table(self, columns, rows, caption: str = ""):
        """A table; ``rows`` are sequences of cells (formatted by :func:`format_value`)."""
        self.blocks.append(("t", list(columns), [list(r) for r in rows], caption))

    def frame(self, frame, caption: str = "", digits: int = 4):
        """A pandas DataFrame as a table."""
        rows = [[format_value(v, digits) for v in r] for r in frame.itertuples(index=False)]
        self.table([str(c) for c in frame.columns], rows, caption)

    def figure(self, path, caption: str = ""):
        """A figure from a PNG file (left out, with a note, when the file is missing)."""
        if path is None or not os.path.exists(path):
            self.text(f"(figure not available: {caption or path})", note=True)
            return
        self.blocks.append(("f", str(path), caption))

    # ------------------------------------------------------------------ writers
    def html(self) -> str:
        """The self-contained HTML page."""
        e = html.escape
        parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
                 '<meta name="viewport" content="width=device-width, initial-scale=1">',
                 '<link rel="icon" href="data:,">', f"<title>{e(self.title)}</title>",
                 f"<style>{_STYLE}</style></head><body>", f"<h1>{e(self.title)}</h1>"]
        for b in self.blocks:
            if b[0] == "h":
                parts.append(f"<h{b[1]}>{e(b[2])}</h{b[1]}>")
            elif b[0] == "p":
                parts.append(f'<p{" class=note" if b[1] else ""}>{e(b[2])}</p>')
            elif b[0] == "t":
                _, cols, rows, cap = b
                head = "".join(f'<th class="t">{e(str(c))}</th>' if k == 0 else
                               f"<th>{e(str(c))}</th>" for k, c in enumerate(cols))
                body = "".join("<tr>" + "".join(
                    f'<td class="t">{e(format_value(c))}</td>' if k == 0 or _is_text(c) else
                    f"<td>{e(format_value(c))}</td>" for k, c in enumerate(r)) + "</tr>"
                    for r in rows)
                cap_html = f"<caption>{e(cap)}</caption>" if cap else ""
                parts.append(f"<table>{cap_html}<thead><tr>{head}</tr></thead>"
                             f"<tbody>{body}</tbody></table>")
            else:
                _, path, cap = b
                parts.append(f'<figure><img alt="{e(cap or os.path.basename(path))}" '
                             f'src="data:image/png;base64,{_png_data(path)}">'
                             f"<figcaption>{e(cap)}</figcaption></figure>")
        parts.append("</body></html>")
        return "\n".join(parts) + "\n"

    def markdown(self, folder) -> str:
        """The Markdown page; figure paths relative to ``folder`` (where it is written)."""
        lines = [f"# {self.title}", ""]
        for b in self.blocks:
            if b[0] == "h":
                lines += ["#" * b[1] + " " + b[2], ""]
            elif b[0] == "p":
                lines += [f"*{b[2]}*" if b[1] else b[2], ""]
            elif b[0] == "t":
                _, cols, rows, cap = b
                if cap:
                    lines += [f"*{cap}*", ""]
                lines += ["| " + " | ".join(_md_cell(c) for c in cols) + " |",
                          "|" + "---|" * len(cols)]
                lines += ["| " + " | ".join(_md_cell(c) for c in r) + " |" for r in rows]
                lines.append("")
            else:
                _, path, cap = b
                rel = pathlib.Path(os.path.relpath(path, folder)).as_posix()
                lines += [f"![{cap}]({rel})", "", f"*{cap}*" if cap else "", ""]
        return "\n".join(lines).rstrip("\n") + "\n"

    def write(self, folder, name: str = "report") -> tuple:
        """Write ``<name>.html`` and ``<name>.md`` into ``folder`` atomically; returns both
        paths."""
        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = []
        for suffix, text in ((".html", self.html()), (".md", self.markdown(folder))):
            path = folder / f"{name}{suffix}"
            tmp = folder / f".{name}{suffix}.tmp"
            tmp.write_text(text, encoding="utf-8")
            os.replace(tmp, path)
            paths.append(str(path))
        return tuple(paths)
