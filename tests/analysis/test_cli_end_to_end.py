"""The workbench as a user drives it: demo, compare, report, batch (through analysis.cli.main)."""

import csv
import json
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest

from crankbench.analysis.cli import main

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "sample_data/shaftlines/marine_6l.toml"


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    t0 = time.perf_counter()
    status = main(["-q", "demo", "-o", str(out)])
    elapsed = time.perf_counter() - t0
    assert status == 0
    return out, elapsed


@pytest.mark.slow
def test_demo_runs_the_chain_in_under_a_minute(demo_dir):
    out, elapsed = demo_dir
    assert elapsed < 60.0, f"demo took {elapsed:.1f} s"
    report = out / "report.html"
    record = out / "marine_6l_runup.h5"
    assert report.is_file() and record.is_file()
    text = report.read_text(encoding="utf-8")
    n_figures = int(re.search(r'name="crankbench-figures" content="(\d+)"', text).group(1))
    assert n_figures >= 6
    for heading in ("Order map", "Campbell diagram", "Order tracks against prediction",
                    "Mode shapes (model)", "Critical speeds: predicted and measured",
                    "Limit checks", "Verdict:",
                    "Analysis settings", "Provenance"):
        assert heading in text, heading
    from crankbench.analysis.report import file_sha256

    assert file_sha256(record) in text  # provenance hashes the record written


@pytest.mark.slow
def test_demo_refuses_to_overwrite(demo_dir, capsys):
    out, _ = demo_dir
    assert main(["demo", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "exists; pass --overwrite to replace it" in err


@pytest.mark.slow
def test_compare_json(demo_dir, capsys):
    out, _ = demo_dir
    capsys.readouterr()
    assert main(["-q", "compare", str(out / "marine_6l_runup.h5"), str(MODEL), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["summary"]["model_agrees"] is True
    assert data["verdict"]["verdict"] == "fail"
    assert {c["verdict"] for c in data["checks"]} <= {"pass", "fail", "inconclusive"}
    assert len(data["matched"]) >= 8
    assert {"mode", "order", "deviation_pct", "amplitude_ratio"} <= set(data["matched"][0])
    assert data["natural_frequencies"][0]["mode"] >= 1


@pytest.mark.slow
def test_report_html_and_pdf(demo_dir, tmp_path, capsys):
    out, _ = demo_dir
    target = tmp_path / "r.html"
    assert main(["-q", "report", str(out / "marine_6l_runup.h5"), str(MODEL), "-o",
                 str(target), "--pdf", "--method", "cot"]) == 0
    assert target.is_file() and target.with_suffix(".pdf").is_file()
    pdf = target.with_suffix(".pdf").read_bytes()
    assert pdf[:5] == b"%PDF-"
    if shutil.which("pdfinfo"):
        info = subprocess.run(["pdfinfo", str(target.with_suffix(".pdf"))], text=True,
                              capture_output=True, check=True).stdout
        assert int(re.search(r"Pages:\s+(\d+)", info).group(1)) >= 3
    # no silent overwrite
    assert main(["report", str(out / "marine_6l_runup.h5"), str(MODEL), "-o",
                 str(target)]) == 2
    assert "pass --overwrite" in capsys.readouterr().err


def test_compare_bad_channel_is_one_line_error(tmp_path, capsys):
    from crankbench.measure.record import make_record
    from crankbench.measure.io import write
    import numpy as np

    rec = make_record({"tv_free_end": dict(data=np.zeros(100), sample_rate=100.0, units="rad",
                                           quantity="angle")})
    path = tmp_path / "r.h5"
    write(rec, path)
    assert main(["compare", str(path), str(MODEL), "--channel", "tv_fre_end"]) == 2
    err = capsys.readouterr().err
    assert "record has no channel 'tv_fre_end' (did you mean 'tv_free_end'?)" in err


@pytest.mark.slow
def test_batch_reports_failures_and_resumes(demo_dir, tmp_path, capsys):
    out, _ = demo_dir
    runs = tmp_path / "runs"
    runs.mkdir()
    shutil.copy(out / "marine_6l_runup.h5", runs / "a.h5")
    (runs / "broken.h5").write_bytes(b"not a record")
    summary = tmp_path / "summary.csv"
    status = main(["-q", "batch", str(runs / "*.h5"), "--model", str(MODEL), "-o", str(summary),
                   "--method", "cot", "--workers", "2"])
    assert status == 1  # one record failed, the other was processed
    rows = {Path(r["record"]).name: r for r in csv.DictReader(summary.open())}
    assert rows["a.h5"]["status"] == "ok" and rows["a.h5"]["model_agrees"] == "True"
    assert rows["a.h5"]["verdict"] == "fail" and rows["a.h5"]["comparison_verdict"] == "pass"
    assert rows["broken.h5"]["status"] == "error"
    assert "broken.h5" in rows["broken.h5"]["error"]
    cache = list((tmp_path / "summary.csv.cache").glob("a-*.json"))
    assert len(cache) == 1
    # re-run: the finished record comes from the cache, the broken one is retried
    t0 = time.perf_counter()
    main(["-q", "batch", str(runs / "*.h5"), "--model", str(MODEL), "-o", str(summary),
          "--method", "cot", "--overwrite"])
    assert time.perf_counter() - t0 < 20
    rows = {Path(r["record"]).name: r for r in csv.DictReader(summary.open())}
    assert rows["a.h5"]["status"] == "cached" and rows["broken.h5"]["status"] == "error"


@pytest.mark.slow
def test_batch_on_a_distributed_scheduler(demo_dir, tmp_path):
    distributed = pytest.importorskip(
        "distributed", reason="dask.distributed not installed (pip install 'crankbench[distributed]')")
    out, _ = demo_dir
    summary = tmp_path / "dist.csv"
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        status = main(["-q", "batch", str(out / "marine_6l_runup.h5"), "--model", str(MODEL),
                       "-o", str(summary), "--no-cache", "--method", "cot",
                       "--scheduler", cluster.scheduler_address])
    assert status == 0
    rows = list(csv.DictReader(summary.open()))
    assert len(rows) == 1 and rows[0]["status"] == "ok"


def test_batch_without_distributed_names_the_extra(tmp_path, capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "distributed", None)  # import now raises ImportError
    record = tmp_path / "r.h5"
    record.write_bytes(b"x")
    status = main(["batch", str(record), "--model", str(MODEL), "-o", str(tmp_path / "s.csv"),
                   "--scheduler", "tcp://127.0.0.1:1", "--no-cache"])
    assert status == 2
    assert "pip install 'crankbench[distributed]'" in capsys.readouterr().err


@pytest.mark.slow
def test_demo_happy_path_is_quiet_and_verbose_shows_more(tmp_path):
    """Issue 15 point 5, as a user sees the terminal: the default demo prints no warning, each
    message once, a progress bar that ends at its own total (never 10/9), and ``-v`` prints
    more than the default."""
    import os
    import sys

    env = {**os.environ, "COLUMNS": "120"}

    def run(*flags, out):
        proc = subprocess.run([sys.executable, "-m", "crankbench", *flags, "demo", "-o",
                               str(tmp_path / out)], capture_output=True, text=True, env=env,
                              timeout=600)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return proc.stderr

    quiet = run(out="a")
    lines = [ln.strip() for ln in re.split(r"[\r\n]", quiet) if ln.strip()]
    messages = [ln for ln in lines if not ln.startswith("demo:")]
    assert not [m for m in messages if "warning" in m.lower()], messages
    assert len(messages) == len(set(messages)), messages           # each message once
    counts = [(int(a), int(b)) for a, b in re.findall(r"(\d+)/(\d+) \[", quiet)]
    assert counts and all(a <= b for a, b in counts), counts        # never past its total
    assert max(a for a, _ in counts) == counts[0][1]                # and it reaches it
    assert not re.search(r"\d+step \[", quiet)                       # (tqdm's overflow form)
    verbose = run("-v", out="b")
    more = [ln for ln in re.split(r"[\r\n]", verbose) if ln.strip() and
            not ln.strip().startswith("demo:")]
    assert len(more) > len(messages), (messages, more)
