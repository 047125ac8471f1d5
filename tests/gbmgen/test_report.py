"""Reports: ``gbmgen run`` and a study write a self-contained report.html (opened here in Debian's
headless chromium through Playwright: no console error, every image decoded, the tables there)
and the same content as report.md."""
import base64
import doctest
import pathlib
import re
import shutil
import warnings

import cv2
import numpy as np
import pandas as pd
import pytest

from gbmgen import report as report_module
from gbmgen.report import MAX_WIDTH_PX
from gbmgen.study_report import write_study_report

SAMPLES = pathlib.Path(__file__).resolve().parents[2] / "sample_images"
CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def test_docstring_examples():
    res = doctest.testmod(report_module)
    assert res.failed == 0 and res.attempted > 0


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """A tiny ``gbmgen run``: one SEM image, a 2.5 x 5 mm specimen, a short UCS."""
    if not (SAMPLES / "S1_fail_01.png").exists():
        pytest.skip("sample_images not present")
    from gbmgen.run import run
    img = tmp_path_factory.mktemp("images")
    shutil.copy(SAMPLES / "S1_fail_01.png", img)
    shutil.copy(SAMPLES / "manifest.csv", img)
    out = tmp_path_factory.mktemp("run") / "out"
    with warnings.catch_warnings():            # a 2.5 mm specimen is not representative
        warnings.simplefilter("ignore")
        run(img, out, progress=False, width_mm=2.5, height_mm=5.0,
            test_options={"platen_velocity": 0.05, "max_strain": 0.002})
    return out


@pytest.fixture(scope="module")
def study_folder(tmp_path_factory):
    """A study report from a made-up results table (two bridge lengths x two angles x 2
    seeds), as the double-hole study writes it."""
    rows = []
    for b in (0.75, 1.5):
        for a in (0, 60):
            for seed in (1, 2):
                rows.append({"status": "ok", "bridge_mm": b, "bridge_angle_deg": a,
                             "hole_diameter_mm": 1.5, "seed": seed, "ucs_mpa": 100.0 + a,
                             "E_gpa": 60.0, "hole_damage_damaged_area_mm2": 1.0 + a / 60 + seed,
                             "hole_damage_crack_joins_holes": a == 60,
                             "hole_damage_max_displacement_mm": 0.1})
    out = tmp_path_factory.mktemp("study")
    write_study_report(out, "thesis-ch6-double-holes", pd.DataFrame(rows), seeds=2,
                       size_mm=(12.5, 25.0))
    return out


def test_run_report_content(run_folder):
    md = (run_folder / "report.md").read_text()
    html = (run_folder / "report.html").read_text()
    for text in ("damage ratio P", "MHI (Equ. 4-3)", "E (GPa)", "Poisson",
                 "specimen representative"):
        assert text in md and text in html
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md)
    assert len(links) >= 5                    # overlay, sizes, specimen, curve, crack map
    for link in links:                         # report.md shows the figures from files
        assert (run_folder / link).is_file(), link
    # self-contained: every image inline, nothing fetched from anywhere
    inline = re.findall(r'src="data:image/png;base64,([^"]+)"', html)
    assert len(inline) == len(links)
    for data, link in zip(inline, links):     # each figure whole (scaled to the page width)
        img = cv2.imdecode(np.frombuffer(base64.b64decode(data), np.uint8), cv2.IMREAD_COLOR)
        src = cv2.imread(str(run_folder / link), cv2.IMREAD_COLOR)
        assert img is not None and img.shape[1] == min(src.shape[1], MAX_WIDTH_PX), link
        assert abs(img.shape[0] / img.shape[1] - src.shape[0] / src.shape[1]) < 0.01, link
    assert not re.search(r'(src|href)="(?!data:)', html)


def _open(page, path):
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("requestfailed", lambda r: errors.append(f"request failed: {r.url}"))
    page.goto(pathlib.Path(path).resolve().as_uri())
    page.wait_for_load_state("load")
    images = page.evaluate("""async () => Promise.all(Array.from(document.images).map(
        i => i.decode().then(() => [true, i.naturalWidth, i.naturalHeight],
                             () => [false, 0, 0])))""")
    tables = page.evaluate("() => document.querySelectorAll('table tbody tr').length")
    return errors, images, tables


@pytest.fixture(scope="module")
def browser():
    """Debian's headless chromium driven by Playwright (skipped, with the reason, without
    either)."""
    try:
        from playwright.sync_api import Error, sync_playwright
    except ImportError:
        pytest.skip("playwright is not installed (pip install playwright)")
    if not pathlib.Path(CHROMIUM).exists():
        pytest.skip(f"Debian's chromium is not installed at {CHROMIUM} (apt-get install "
                    "chromium)")
    with sync_playwright() as p:
        try:
            b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        except Error as exc:
            pytest.skip(f"chromium at {CHROMIUM} does not start: {str(exc).splitlines()[0]}")
        try:
            yield b
        finally:
            b.close()


def _check(browser, path, n_images):
    """The report's defects as the browser sees them (empty when it is sound)."""
    errors, images, rows = _open(browser.new_page(), path)
    bad = [f"image {k} not decoded" for k, (c, w, h) in enumerate(images)
           if not (c and w > 0 and h > 0)]
    if len(images) < n_images:
        bad.append(f"{len(images)} images, expected >= {n_images}")
    if rows < 3:
        bad.append(f"{rows} table rows, expected >= 3")
    return errors + bad


def test_reports_open_in_headless_chromium(browser, run_folder, study_folder):
    for folder, n_images in ((run_folder, 5), (study_folder, 2)):
        assert _check(browser, folder / "report.html", n_images) == []


def test_the_browser_check_sees_a_broken_report(browser, run_folder, tmp_path):
    """The check above can fail: a report with an image that is not a PNG, a script error and
    a fetched (missing) file is caught on all three counts."""
    html = (run_folder / "report.html").read_text()
    first = html.index('src="data:image/png;base64,') + len('src="data:image/png;base64,')
    broken = html[:first] + "bm90IGEgUE5H" + html[html.index('"', first):]   # "not a PNG"
    broken = broken.replace("</body>", '<img src="missing.png"><script>undefined_name();'
                            "</script></body>")
    (tmp_path / "report.html").write_text(broken)
    problems = _check(browser, tmp_path / "report.html", 5)
    assert any("undefined_name" in p for p in problems), problems
    assert any(p.startswith("request failed") and "missing.png" in p for p in problems)
    assert sum(p.endswith("not decoded") for p in problems) == 2, problems


def test_study_report_findings(study_folder):
    md = (study_folder / "report.md").read_text()
    # made-up table: damaged area larger at 60 than at 0 deg, equal over the bridges
    assert "| largest damaged area at bridge angle (deg) | 60 | 60 | True |" in md
    assert "| smallest damaged area at bridge angle (deg) | 150 | 0 | False |" in md
    assert np.isclose(float(re.search(r"\| 0\.75 \| 60 \| 2 \| 2 \| ([\d.]+) ±", md)[1]), 3.5)
