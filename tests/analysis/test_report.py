"""The Report: add_* calls, self-contained HTML, overwrite protection, PDF fallback."""

import base64
import hashlib
import re
import shutil
import subprocess

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from crankbench.analysis.limits import check_residual_unbalance, check_vibration_severity
from crankbench.analysis.report import Report, file_sha256
from crankbench.analysis.report.pdf import write_pdf
from crankbench.predict.errors import ConfigError


def _report(tmp_path):
    rep = Report("Run-up T-001", subtitle="6L32 <marine>")
    rep.add_metadata({"engine": "6L32", "test id": "T-001", "load": 0.75})
    record = tmp_path / "run.h5"
    record.write_bytes(b"record bytes")
    rep.add_provenance(files=[record], model=None, parameters={"orders": [3, 4.5, 6]})
    for i, fmt in enumerate(("png", "svg")):
        fig, ax = plt.subplots()
        ax.plot(np.arange(5), np.arange(5) ** i)
        rep.add_figure(fig, title=f"figure {i}", caption="caption & <b>tag</b>",
                       image_format=fmt)
    rep.add_table(pd.DataFrame({"order": [6.0, 4.5], "speed_rpm": [400.0, np.nan],
                                "ok": [True, False]}), title="Criticals")
    rep.add_limit_checks([check_vibration_severity([1e-3, 2e-3], machine_class="III"),
                          check_residual_unbalance([5e-3], rotor_mass=100.0, speed_rpm=600.0,
                                                   grade=6.3)])
    rep.add_text("<script>alert('x')</script>\n\nsecond paragraph")
    return rep, record


def test_html_is_self_contained_and_escaped(tmp_path):
    rep, record = _report(tmp_path)
    out = rep.save(tmp_path / "report.html")
    text = out.read_text(encoding="utf-8")
    # no network references of any kind
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//)""", text)
    assert "<script" not in text and "&lt;script&gt;" in text
    assert "6L32 &lt;marine&gt;" in text and "caption &amp; &lt;b&gt;tag&lt;/b&gt;" in text
    # figures embedded: the PNG one decodes, the others (default) are inline vector SVG
    pngs = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', text)
    assert len(pngs) == 1
    assert all(base64.b64decode(p)[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)
    assert text.count("<svg") == rep.n_figures - 1 >= 2
    assert f'<meta name="crankbench-figures" content="{rep.n_figures}">' in text
    # provenance: the record's hash
    assert hashlib.sha256(b"record bytes").hexdigest() in text
    assert file_sha256(record) == hashlib.sha256(b"record bytes").hexdigest()
    # verdict: 2 mm/s is zone B of class III; 5e-3 kg·m < U_per = 6.3e-3·100/62.83 = 1.0e-2
    assert 'class="status pass">pass<' in text and "every required check passed" in text
    assert "all checks passed" not in text


def test_verdict_reflects_failed_check(tmp_path):
    rep = Report("r")
    rep.add_limit_checks([check_vibration_severity([9e-3], machine_class="II")], figures=False)
    text = rep.to_html()
    assert 'class="status fail">fail<' in text and rep.verdict.status == "fail"


def test_nothing_assessed_is_inconclusive_not_green():
    rep = Report("r")
    rep.add_limit_checks([check_vibration_severity([1e-3], machine_class=None)], figures=False)
    assert rep.verdict.status == "inconclusive"
    assert 'class="status inconclusive">inconclusive<' in rep.to_html()
    assert Report("empty").verdict.status == "inconclusive"


def test_save_refuses_to_overwrite_and_names_option(tmp_path):
    rep, _ = _report(tmp_path)
    path = tmp_path / "r.html"
    rep.save(path)
    before = path.read_bytes()
    with pytest.raises(FileExistsError, match=r"r.html exists; pass overwrite=True to "
                                              r"replace it"):
        rep.save(path)
    with pytest.raises(FileExistsError, match="pass --overwrite"):
        rep.save(path, option="--overwrite")
    assert path.read_bytes() == before
    rep.save(path, overwrite=True)
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".part")] == []


def test_bad_suffix_and_bad_inputs(tmp_path):
    rep = Report()
    with pytest.raises(ConfigError, match=r"must end in .html or .pdf"):
        rep.save(tmp_path / "r.docx")
    with pytest.raises(ConfigError, match="add_table: frame must be a pandas DataFrame"):
        rep.add_table([[1, 2]], title="x")
    with pytest.raises(ConfigError, match="add_figure: fig must be a matplotlib Figure"):
        rep.add_figure("not a figure", title="x")
    with pytest.raises(ConfigError, match=r"image_format='jpg' is not one of 'png', 'svg'"):
        rep.add_figure(plt.figure(), title="x", image_format="jpg")


def _pdf_pages(path):
    if shutil.which("pdfinfo"):
        out = subprocess.run(["pdfinfo", str(path)], capture_output=True, text=True, check=True)
        return int(re.search(r"Pages:\s+(\d+)", out.stdout).group(1))
    # no poppler: count the page objects, also those inside compressed object streams
    # (WeasyPrint >= 68 writes the page tree into FlateDecode object streams)
    import zlib

    data = path.read_bytes()
    texts = [data]
    for m in re.finditer(rb"stream\r?\n(.*?)endstream", data, re.S):
        try:
            texts.append(zlib.decompress(m.group(1)))
        except zlib.error:
            pass
    return sum(len(re.findall(rb"/Type\s*/Page(?![s\w])", t)) for t in texts)


def test_pdf_is_weasyprint_only(tmp_path):
    rep, _ = _report(tmp_path)
    path = tmp_path / "r.pdf"
    assert write_pdf(rep, path) == "weasyprint"
    assert path.read_bytes()[:5] == b"%PDF-"
    assert _pdf_pages(path) >= 2


def test_table_headers_units_and_roundoff():
    rep = Report("r")
    rep.add_table(pd.DataFrame({"speed_rpm_predicted": [721.04, 540.0],
                                "amplitude_measured": [2.03e-14, 3.1e-3],
                                "phase_deg": [33.0, 12.0]}),
                  title="t", amplitude_units="rad")
    item = rep._sections[0].items[0].payload
    assert item["columns"] == ["predicted speed (rpm)", "measured amplitude (mdeg)",
                               "phase (deg)"]
    # 3.1e-3 rad = 177.6 mdeg; a 2e-14 residual is round-off: 0, and no phase on it
    assert item["rows"] == [["721.0", "0", "—"], ["540.0", "178", "12"]]


@pytest.mark.skipif(shutil.which("pdftoppm") is None, reason="pdftoppm (poppler) not installed")
def test_pdf_converts_to_images(tmp_path):
    rep, _ = _report(tmp_path)
    path = rep.save(tmp_path / "r.pdf")
    subprocess.run(["pdftoppm", "-r", "30", "-png", str(path), str(tmp_path / "page")],
                   check=True, capture_output=True)
    pages = sorted(tmp_path.glob("page*.png"))
    assert len(pages) == _pdf_pages(path) >= 2
    assert all(p.read_bytes()[:4] == b"\x89PNG" for p in pages)
