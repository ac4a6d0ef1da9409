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
