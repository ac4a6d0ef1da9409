"""The bench command runs suites, writes its table and fails on an exceeded error bound."""

import json
import sys
import types

import pytest

import crankbench.analysis.bench as bench
from crankbench.analysis.bench import Row, median_time
from crankbench.analysis.cli import main


def _fake_suite(monkeypatch, name, rows):
    module = types.ModuleType(f"crankbench.analysis.bench.suite_{name}")
    module.run = lambda quick: rows
    monkeypatch.setitem(sys.modules, f"crankbench.analysis.bench.suite_{name}", module)
    monkeypatch.setattr(bench, "suites", lambda: [name])


def test_bench_writes_table_and_exits_zero_within_bounds(monkeypatch, tmp_path, capsys):
    rows = [Row("demo", "series", "n=2", 1e-3, "max rel", "exact", 1e-4, bound=1e-2),
            Row("demo", "series", "n=4", 1e-6, "max rel", "exact", 2e-4, bound=1e-2)]
    _fake_suite(monkeypatch, "demo", rows)
    assert main(["bench", "--quick", "--json", "-o", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["failed"] == 0 and [r["setting"] for r in out["rows"]] == ["n=2", "n=4"]
    assert {p.name for p in tmp_path.iterdir()} == {"bench.csv", "bench.json", "demo.png"}
    # a second run refuses to overwrite without --overwrite
    assert main(["bench", "--quick", "-o", str(tmp_path)]) == 2
    assert "--overwrite" in capsys.readouterr().err


def test_bench_exits_nonzero_when_an_error_exceeds_its_bound(monkeypatch, capsys):
    _fake_suite(monkeypatch, "demo", [Row("demo", "m", "s", 0.5, "rel", "ref", 1e-3, bound=0.1)])
    assert main(["bench", "--quick"]) == 1
    _fake_suite(monkeypatch, "demo", [Row("demo", "m", "s", float("nan"), "rel", "ref", 1e-3)])
    assert main(["bench", "--quick"]) == 1


def test_a_missed_speed_target_is_reported_not_failed(monkeypatch, capsys):
    """A target row (a time ratio against a goal) past its goal is named in a warning and the
    JSON, but only an error row past its bound makes the run exit 1."""
    target = Row("demo", "m speed", "n=100", 2.1, "time / dsterf", "target <= 2x", 1e-3,
                 bound=2.0, target=True)
    _fake_suite(monkeypatch, "demo", [target])
    assert main(["bench", "--quick", "--json"]) == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert out["failed"] == 0 and out["targets_missed"] == 1
    assert out["rows"][0]["passed"] is False
    assert "1 speed target(s) missed" in captured.err and "2.1x > 2x" in captured.err
    error_row = Row("demo", "m", "s", 0.5, "rel", "ref", 1e-3, bound=0.1)
    _fake_suite(monkeypatch, "demo", [target, error_row])
    assert main(["bench", "--quick"]) == 1


def test_bench_rejects_unknown_suite(monkeypatch, capsys):
    _fake_suite(monkeypatch, "demo", [])
    assert main(["bench", "--suite", "dem"]) == 2
    assert "--suite='dem' is not one of 'demo' (did you mean 'demo'?)" in capsys.readouterr().err


def test_median_time_reports_per_call_cpu_time():
    """CPU time per call: a busy loop counts, sleeping (waiting, not computing) does not."""
    import time

    def spin():
        t0 = time.process_time()
        while time.process_time() - t0 < 0.002:
            pass

    assert 0.0019 < median_time(spin, repeats=3, warmup=0) < 0.02
    assert median_time(lambda: time.sleep(0.002), repeats=3, warmup=0) < 0.001


def test_compare_interleaves_and_pairs_ratios():
    """Interleaved rounds, rotating order; paired ratio of a 2x cost with its spread."""
    import time

    from crankbench.analysis.bench import compare

    order = []

    def spin(seconds, name):
        def run():
            order.append(name)
            t0 = time.process_time()
            while time.process_time() - t0 < seconds:
                pass
        return run

    t = compare({"a": spin(0.004, "a"), "b": spin(0.002, "b")}, rounds=4, warmup=1,
                min_time=0.0)
    assert order == ["a", "b", "a", "b", "b", "a", "a", "b", "b", "a"]  # warm-up, rotation
    ratio, lo, hi = t.ratio("a", "b")
    assert 1.6 < ratio < 2.5 and lo <= ratio <= hi
    row = t.row("demo", "slow", "a", "b", "n=1", 0.0, "abs", "exact")
    assert row.paired and row.rounds == 4 and row.versus.startswith(f"{ratio:.3g}x slower than b")
    fast = t.row("demo", "fast", "b", ("a", "method a"), "n=1", 0.0, "abs", "exact")
    assert "x faster than method a" in fast.versus


def test_rows_from_separate_medians_say_unpaired():
    row = Row("demo", "m", "s", 0.0, "abs", "ref", 1.0, baseline="base", ratio=3.0)
    assert row.versus == "3x slower than base, unpaired"


def test_machine_description():
    from crankbench.analysis.bench import machine

    info = machine()
    assert info["cpus_logical"] >= 1 and info["numpy"] and info["python"]
    assert all("internal_api" in lib for lib in info["blas"])


def test_verbosity_flags_work_before_and_after_the_command(capsys):
    from crankbench.analysis.cli import build_parser

    parser = build_parser()
    assert parser.parse_args(["-q", "bench", "--list"]).quiet is True
    assert parser.parse_args(["bench", "--list", "-q"]).quiet is True
    assert parser.parse_args(["bench", "--list"]).quiet is False
    assert parser.parse_args(["bench", "-vv", "--list"]).verbose == 2
    assert parser.parse_args(["predict", "torsion", "m.toml", "-q"]).quiet is True


def test_warnings_reach_the_cli_user_as_one_log_line(tmp_path):
    """A real user's process (pytest records warnings in-process, so run the CLI for real): a
    clipped channel is analysed, and the warning reads as one log line, no Python traceback
    style 'file:line: RecordWarning' echo."""
    import subprocess

    import numpy as np

    from crankbench.measure.io import write
    from crankbench.measure.record import make_record

    fs, n = 2000.0, 8000
    t = np.arange(n) / fs
    acc = np.clip(1.3 * np.cos(2 * np.pi * 50.0 * t), -0.8, 0.8)      # order 2 at 1500 rpm
    rec = make_record({"acc": dict(data=acc, sample_rate=fs, units="m/s^2",
                                   quantity="acceleration"),
                       "speed": dict(data=np.full(40, 1500 * np.pi / 30), sample_rate=10.0,
                                     units="rad/s", quantity="rotational_speed")})
    path = tmp_path / "clip.h5"
    write(rec, path)
    done = subprocess.run([sys.executable, "-m", "crankbench", "analyse", str(path),
                           "--channel", "acc", "--orders", "2", "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "warning: clip.h5: channel 'acc' looks clipped" in done.stderr
    assert "RecordWarning" not in done.stderr and "warnings.warn" not in done.stderr
