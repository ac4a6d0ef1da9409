"""The HTML report opened in headless Chromium: no console errors, every figure rendered.

Skipped (with the reason) where Chromium is not installed; install it with
``apt-get install -y chromium``. The report itself contains no script; the test opens a copy
with a small probe appended that, after load, records how many figures decoded (images with a
natural size, inline SVGs with a layout box) into the document title, which ``--dump-dom``
then shows. Console messages are read from Chromium's log (``--enable-logging=stderr``).
"""

import re
import shutil
import subprocess

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from crankbench.analysis.limits import check_vibration_severity
from crankbench.analysis.report import Report

CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium"),
                             shutil.which("chromium-browser"), shutil.which("google-chrome"))
                 if p), None)

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None or not shutil.os.path.exists(CHROMIUM),
                       reason="headless Chromium not installed (apt-get install -y chromium)"),
]

PROBE = """
<script>
window.addEventListener("load", function () {
  var imgs = Array.from(document.querySelectorAll("figure img"));
  var svgs = Array.from(document.querySelectorAll("figure svg"));
  var okImg = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
  var okSvg = svgs.filter(function (s) { return s.getBoundingClientRect().width > 0; }).length;
  document.title = "PROBE figures=" + (imgs.length + svgs.length) + " rendered=" +
                   (okImg + okSvg);
});
</script>
"""


def _chromium(args, tmp_path):
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           "--no-first-run", f"--user-data-dir={tmp_path / 'profile'}",
           "--enable-logging=stderr", "--v=0", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def _report(tmp_path):
    rep = Report("Browser check", subtitle="6L32 run-up")
    rep.add_metadata({"engine": "6L32", "test": "T-7"})
    for i, fmt in enumerate(("png", "svg", "png")):
        fig, ax = plt.subplots()
        ax.plot(np.linspace(0, 1, 50), np.sin(np.linspace(0, 6 * (i + 1), 50)))
        rep.add_figure(fig, title=f"figure {i}", image_format=fmt)
    rep.add_table(pd.DataFrame({"order": [6.0], "speed_rpm": [400.0]}), title="table")
    rep.add_limit_checks([check_vibration_severity([1e-3, 3e-3], machine_class="III")])
    return rep, rep.save(tmp_path / "report.html")


def test_report_renders_without_console_errors_and_all_figures(tmp_path):
    rep, path = _report(tmp_path)
    probe = tmp_path / "probe.html"
    probe.write_text(path.read_text(encoding="utf-8").replace("</body>", PROBE + "</body>"),
                     encoding="utf-8")
    run = _chromium(["--virtual-time-budget=5000", "--dump-dom", probe.as_uri()], tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    m = re.search(r"PROBE figures=(\d+) rendered=(\d+)", run.stdout)
    assert m, run.stdout[:500]
    assert int(m.group(1)) == rep.n_figures == 4
    assert int(m.group(2)) == rep.n_figures
    console = [line for line in run.stderr.splitlines() if "CONSOLE" in line]
    assert console == [], console
    # the report itself (no probe) loads with no console output and no failed requests
    plain = _chromium(["--virtual-time-budget=3000", "--dump-dom", path.as_uri()], tmp_path)
    assert "Browser check" in plain.stdout
    assert [line for line in plain.stderr.splitlines() if "CONSOLE" in line] == []
    assert "net::ERR" not in plain.stderr


def test_report_screenshot(tmp_path):
    _, path = _report(tmp_path)
    shot = tmp_path / "shot.png"
    run = _chromium([f"--screenshot={shot}", "--window-size=1200,3000", path.as_uri()],
                    tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width = int.from_bytes(data[16:20], "big")
    assert width == 1200


# ---------------------------------------------------------------------------------------------
# the full test report, as printed: every column and every figure reaches the page
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def pipeline_report(tmp_path_factory):
    """The report of a short synthetic run-up of the 6L32 (a few seconds)."""
    from pathlib import Path

    from crankbench.analysis.pipeline import LoadCase, analyse
    from crankbench.analysis.report.build import build_report
    from crankbench.measure.synth import Scene, synthesize

    root = Path(__file__).resolve().parents[2]
    text = (root / "sample_data/scenes/marine_6l_runup.toml").read_text(encoding="utf-8")
    out = tmp_path_factory.mktemp("printed")
    scene_path = root / "sample_data/scenes/marine_6l_runup.toml"
    scene = Scene.from_toml(scene_path)
    run = synthesize(scene)
    result = analyse(run.record, root / "sample_data/shaftlines/marine_6l.toml",
                     load=LoadCase.from_any(scene.load, scene.engine))
    rep = build_report(result)
    html = rep.save(out / "report.html")
    pdf = rep.save(out / "report.pdf")
    del text
    return rep, html, pdf, out


def _headers(rep):
    out = []
    for sec in rep._sections:
        for item in sec.items:
            if item.kind == "table":
                out.extend(item.payload["columns"])
    return out


def _words(text):
    return re.sub(r"\s+", " ", text)


@pytest.mark.slow
def test_printed_report_has_every_column_figure_and_page_number(pipeline_report, tmp_path):
    """WeasyPrint PDF (the supported path): the text layer holds every table header, every
    figure caption, the verdict, and 'page n of N' on every page."""
    rep, _, pdf, _ = pipeline_report
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext (poppler) not installed")
    text = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True,
                          text=True, check=True).stdout
    flat = _words(text)
    n_pages = int(re.search(r"page 1 of (\d+)", flat).group(1))
    for k in range(1, n_pages + 1):
        assert f"page {k} of {n_pages}" in flat
    # every header word reaches the page (headers may wrap inside their cell)
    for h in set(_headers(rep)):
        for word in re.findall(r"[A-Za-z]{3,}", h):
            assert word in flat, (h, word)
    assert flat.count("Figure ") >= rep.n_figures
    for k in range(1, rep.n_figures + 1):
        assert f"Figure {k}:" in flat
    assert "Verdict:" in flat and "FAIL" in flat.upper()
    assert "M68.5" in flat
    # pages are A4 portrait and nothing is wider than the page: every table column header's
    # first word is found on a page, and figures are vector (axis labels are text)
    assert "engine speed (rpm)" in flat and "frequency (Hz)" in flat


@pytest.mark.slow
def test_report_in_chromium_fits_the_page(pipeline_report, tmp_path):
    """In the browser at A4 width no table is cut or scrolls, every figure renders; Chromium's
    own print to PDF keeps every header."""
    rep, html, _, _ = pipeline_report
    probe = tmp_path / "probe.html"
    check = """
<script>
window.addEventListener("load", function () {
  var width = document.documentElement.clientWidth;
  var wide = Array.from(document.querySelectorAll("table")).filter(function (t) {
    return t.getBoundingClientRect().right > width + 1; }).length;
  var svgs = Array.from(document.querySelectorAll("figure svg"));
  var ok = svgs.filter(function (s) { return s.getBoundingClientRect().width > 0; }).length;
  document.title = "PROBE wide=" + wide + " figures=" + svgs.length + " rendered=" + ok;
});
</script>
"""
    probe.write_text(html.read_text(encoding="utf-8").replace("</body>", check + "</body>"),
                     encoding="utf-8")
    run = _chromium(["--virtual-time-budget=8000", "--window-size=794,1123", "--dump-dom",
                     probe.as_uri()], tmp_path)
    m = re.search(r"PROBE wide=(\d+) figures=(\d+) rendered=(\d+)", run.stdout)
    assert m, run.stdout[:300]
    assert int(m.group(1)) == 0
    assert int(m.group(2)) == int(m.group(3)) == rep.n_figures
    printed = tmp_path / "chromium.pdf"
    _chromium(["--no-pdf-header-footer", f"--print-to-pdf={printed}", html.as_uri()], tmp_path)
    if printed.is_file() and shutil.which("pdftotext"):
        text = _words(subprocess.run(["pdftotext", str(printed), "-"], capture_output=True,
                                     text=True, check=True).stdout)
        for h in set(_headers(rep)):
            for word in re.findall(r"[A-Za-z]{3,}", h):
                assert word in text, (h, word)
