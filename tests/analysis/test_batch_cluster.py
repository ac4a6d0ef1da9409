"""``crankbench batch`` on a real dask.distributed cluster (worker processes, not threads) and
the batch's own safety: paths resolved before submission, one report per record however the
records are named, reports and scheduler checked before any work (issue 19).

The records are 2 s synthetic run-ups of the sample I4 driveline (a torsiograph and a speed
channel), so each analysis takes a few seconds.
"""

from __future__ import annotations

import csv
import os
import shutil
import socket
import time
from pathlib import Path

import pytest

from crankbench.analysis.cli import main

ROOT = Path(__file__).resolve().parents[2]

SCENE = """\
[scene]
name = "short run-up"
engine = "../models/engines/i4.toml"
shaftline = "../models/shaftlines/i4.toml"
seed = {seed}
max_order = 4.0

[profile]
kind = "runup"
start_rpm = 2500.0
end_rpm = 3500.0
duration = 2.0

[[sensor]]
kind = "torsiograph"
name = "tv_pulley"
node = "pulley hub"
quantity = "angle"
sample_rate = 2000.0

[[sensor]]
kind = "speed"
name = "speed"
sample_rate = 100.0
"""


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """A folder with models/ (copies of the sample I4), runs/a/run.h5, runs/b/run.h5 (two
    different run-ups of the same name) and runs/broken.h5 (not a record)."""
    from crankbench.measure.io import write
    from crankbench.measure.synth import Scene, synthesize

    folder = tmp_path_factory.mktemp("bench")
    shutil.copytree(ROOT / "sample_data/engines", folder / "models/engines")
    shutil.copytree(ROOT / "sample_data/shaftlines", folder / "models/shaftlines")
    (folder / "scenes").mkdir()
    for sub, seed in (("a", 1), ("b", 2)):
        scene = folder / "scenes" / f"{sub}.toml"
        scene.write_text(SCENE.format(seed=seed))
        run = synthesize(Scene.from_toml(scene))
        (folder / "runs" / sub).mkdir(parents=True)
        write(run.record, folder / "runs" / sub / "run.h5", truth=run.truth)
    (folder / "runs" / "broken.h5").write_bytes(b"not a record at all")
    return folder


def _rows(path):
    return {r["record"]: r for r in csv.DictReader(open(path, encoding="utf-8"))}


@pytest.mark.slow
def test_batch_on_a_local_cluster_of_processes(bench, monkeypatch, capsys):
    """Worker processes started in another directory; the batch is given relative paths, has a
    failing record and is resumed. Every record is found, each report is its own, the failing
    record is reported and retried, the finished ones come from the cache."""
    distributed = pytest.importorskip("distributed", reason="pip install 'crankbench[distributed]'")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as cluster:
        # the workers' working directory is the test's, not the bench folder
        monkeypatch.chdir(bench)
        argv = ["-q", "batch", "runs/**/*.h5", "--model", "models/shaftlines/i4.toml",
                "-o", "out/summary.csv", "--reports", "out/reports", "--method", "cot",
                "--scheduler", cluster.scheduler_address]
        assert main(argv) == 1          # one record failed, the others were processed
        rows = _rows("out/summary.csv")
        assert set(rows) == {"runs/a/run.h5", "runs/b/run.h5", "runs/broken.h5"}
        assert rows["runs/a/run.h5"]["status"] == "ok" == rows["runs/b/run.h5"]["status"]
        assert rows["runs/broken.h5"]["status"] == "error"
        assert "runs/broken.h5" in rows["runs/broken.h5"]["error"]
        a, b = Path("out/reports/a/run.html"), Path("out/reports/b/run.html")
        assert a.is_file() and b.is_file()          # same stem, two reports
        from crankbench.analysis.report import file_sha256

        assert file_sha256("runs/a/run.h5") in a.read_text(encoding="utf-8")
        assert file_sha256("runs/b/run.h5") in b.read_text(encoding="utf-8")
        # resume: finished records from the cache, the broken one retried
        t0 = time.perf_counter()
        assert main(argv + ["--overwrite"]) == 1
        rows = _rows("out/summary.csv")
        assert rows["runs/a/run.h5"]["status"] == "cached" == rows["runs/b/run.h5"]["status"]
        assert rows["runs/broken.h5"]["status"] == "error"
        assert time.perf_counter() - t0 < 30.0
    capsys.readouterr()


def test_unreachable_scheduler_is_one_line_before_any_work(bench, capsys):
    """Nothing listens on the port: refused in well under the client's 30 s, in one line."""
    pytest.importorskip("distributed")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t0 = time.perf_counter()
    status = main(["batch", str(bench / "runs/a/run.h5"), "--model",
                   str(bench / "models/shaftlines/i4.toml"), "-o", str(bench / "x.csv"),
                   "--scheduler", f"tcp://127.0.0.1:{port}"])
    elapsed = time.perf_counter() - t0
    err = capsys.readouterr().err
    assert status == 2 and elapsed < 15.0
    assert err.strip().count("\n") == 0 and "Traceback" not in err
    assert f"--scheduler 'tcp://127.0.0.1:{port}': no dask scheduler answers there" in err
    assert not (bench / "x.csv").exists()


def test_report_names_are_unique_per_record():
    from crankbench.analysis.commands.batch import report_names

    names = report_names(["/r/a/run.h5", "/r/b/run.h5", "/r/b/run.csv", "/r/c/x.h5"])
    assert [str(n) for n in names] == ["a/run.html", "b/run.h5.html", "b/run.csv.html",
                                       "c/x.html"]
    assert len(set(names)) == len(names)


def test_existing_reports_refused_before_work(bench, capsys):
    """An existing report of a record to be analysed is refused before anything runs (it
    used to mark a good record failed, or with --overwrite race between workers)."""
    out = bench / "refused"
    (out / "reports" / "a").mkdir(parents=True)
    (out / "reports" / "a" / "run.html").write_text("earlier")
    t0 = time.perf_counter()
    status = main(["batch", str(bench / "runs/*/run.h5"), "--model",
                   str(bench / "models/shaftlines/i4.toml"), "-o", str(out / "s.csv"),
                   "--reports", str(out / "reports"), "--no-cache"])
    err = capsys.readouterr().err
    assert status == 2 and time.perf_counter() - t0 < 15.0
    assert "1 report(s) exist" in err and "pass --overwrite" in err
    assert not (out / "s.csv").exists()
    assert (out / "reports" / "a" / "run.html").read_text() == "earlier"


def test_paths_are_absolute_before_submission(bench, monkeypatch):
    """The tasks handed to dask carry absolute paths (a worker may run anywhere)."""
    from crankbench.analysis.commands import batch

    seen = []

    def fake_process_one(record, model, options, cache_file, report, overwrite, store_run,
                         display):
        seen.append((record, model, report, display))
        return {"record": display, "status": "ok", "error": ""}

    monkeypatch.setattr(batch, "process_one", fake_process_one)
    monkeypatch.chdir(bench)
    assert main(["-q", "batch", "runs/a/run.h5", "--model", "models/shaftlines/i4.toml",
                 "-o", "out2/s.csv", "--reports", "out2/r", "--no-cache"]) == 0
    record, model, report, display = seen[0]
    assert os.path.isabs(record) and os.path.isabs(model) and os.path.isabs(report)
    assert Path(record) == bench / "runs/a/run.h5" and display == "runs/a/run.h5"


@pytest.mark.slow
def test_report_then_report_pdf_do_not_collide(bench, capsys):
    """``report -o r.html`` then ``report -o r.html --pdf --overwrite`` then
    ``report -o r.pdf --pdf --overwrite``: each output is what its name says (HTML, PDF),
    written once, and the record and model are untouched."""
    from crankbench.analysis.report import file_sha256

    rec, model = bench / "runs/a/run.h5", bench / "models/shaftlines/i4.toml"
    before = (file_sha256(rec), file_sha256(model))
    out = bench / "rep"
    base = ["-q", "report", str(rec), str(model), "--method", "cot"]
    assert main(base + ["-o", str(out / "r.html")]) == 0
    first = (out / "r.html").read_bytes()
    assert main(base + ["-o", str(out / "r.html"), "--pdf", "--overwrite"]) == 0
    assert (out / "r.html").read_bytes()[:15].lower().startswith(b"<!doctype html")
    assert (out / "r.pdf").read_bytes()[:5] == b"%PDF-"
    assert len(first) > 1000
    assert main(base + ["-o", str(out / "r.pdf"), "--pdf", "--overwrite"]) == 0
    assert (out / "r.pdf").read_bytes()[:5] == b"%PDF-"
    assert sorted(p.name for p in out.iterdir()) == ["r.html", "r.pdf"]   # no stray files
    assert (file_sha256(rec), file_sha256(model)) == before
    capsys.readouterr()
