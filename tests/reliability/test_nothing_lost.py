"""Nothing lost: inputs are never modified, outputs are atomic and never silently overwritten.

* Every reader (all formats, eager ``read`` and lazy ``open``), ``crankbench info`` and the model
  loaders leave their input byte-for-byte unchanged (SHA-256, size and mtime compared before and
  after) and create no file beside it. Under ``strace`` the same runs are shown to open the
  inputs read-only (no ``O_WRONLY``/``O_RDWR``/``O_CREAT``/``O_TRUNC``, no rename/unlink).
* ``measure.write`` refuses to replace a file without ``overwrite=True``; a write that fails
  half-way (disk full, Ctrl-C) leaves the previous file intact and no temporary file behind.
* CLI commands that write (``bench -o``) refuse to overwrite without ``--overwrite``; commands
  that only print (``info``, ``predict torsion``) write nothing.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from crankbench.analysis.cli import main as cli_main
from crankbench.measure import io as mio
from crankbench.measure.record import make_record

ROOT = Path(__file__).resolve().parents[2]
FORMATS = [".h5", ".nc", ".csv", ".tdms", ".mf4", ".wav", ".uff"]
MODELS = ROOT / "sample_data"


def fingerprint(folder: Path) -> dict:
    """{relative name: (sha256, size, mtime_ns)} of every file under ``folder``."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            st = p.stat()
            out[str(p.relative_to(folder))] = (hashlib.sha256(p.read_bytes()).hexdigest(),
                                               st.st_size, st.st_mtime_ns)
    return out


def _record(n=400, fs=1000.0):
    t = np.arange(n) / fs
    return make_record({
        "acc": dict(data=np.sin(2 * np.pi * 30 * t), sample_rate=fs, units="m/s^2",
                    quantity="acceleration"),
        "disp": dict(data=1e-4 * np.cos(2 * np.pi * 30 * t), sample_rate=fs, units="m",
                     quantity="displacement"),
    })


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A folder with one small record per format (plus the WAV sidecar)."""
    folder = tmp_path_factory.mktemp("inputs")
    rec = _record()
    for ext in FORMATS:
        mio.write(rec, folder / f"rec{ext}")
    return folder


# ------------------------------------------------------------------------------ inputs
@pytest.mark.parametrize("ext", FORMATS)
def test_read_and_open_leave_input_unchanged(ext, inputs, capsys):
    before = fingerprint(inputs)
    path = inputs / f"rec{ext}"
    rec = mio.read(path)
    assert mio.source_sha256(rec) == before[path.name][0]
    lazy = mio.open(path)
    lazy.load()
    for name in ("acc", "disp"):
        for _block in mio.iter_blocks(lazy, name):
            pass
    assert cli_main(["info", str(path)]) == 0
    assert cli_main(["info", str(path), "--json"]) == 0
    capsys.readouterr()
    assert fingerprint(inputs) == before


def test_sample_records_read_unchanged(tmp_path):
    """The shipped sample records (copies) read without a change or a new file."""
    src = ROOT / "sample_data" / "records"
    if not src.is_dir():
        pytest.skip("sample_data/records not present")
    folder = tmp_path / "records"
    shutil.copytree(src, folder)
    for p in folder.iterdir():           # keep the mtimes of the originals
        shutil.copystat(src / p.name, p)
    before = fingerprint(folder)
    for p in sorted(folder.iterdir()):
        if p.suffix in mio.EXTENSIONS:
            mio.read(p)
    assert fingerprint(folder) == before


@pytest.mark.parametrize("kind, rel", [
    ("shaftline", "shaftlines/two_rotor.toml"),
    ("shaftline", "shaftlines/i4.toml"),
    ("rotor", "rotors/two_disk.toml"),
])
def test_model_loaders_leave_model_unchanged(kind, rel, tmp_path, capsys):
    src = MODELS / rel
    if not src.exists():
        pytest.skip(f"{rel} not present")
    folder = tmp_path / "models"
    shutil.copytree(MODELS, folder, ignore=shutil.ignore_patterns("records", "*.py"))
    path = folder / rel
    before = fingerprint(folder)
    if kind == "shaftline":
        from crankbench.predict.torsion import from_toml

        try:
            from_toml(path)
        except FileNotFoundError:
            pytest.skip("its engine model is not in sample_data yet")
        except Exception as exc:   # a referenced engine file still missing is a ModelError
            if "does not exist" not in str(exc):
                raise
            pytest.skip(str(exc))
        assert cli_main(["predict", "torsion", str(path), "--no-forced", "--speed-range",
                         "100", "3000"]) == 0
    else:
        from crankbench.predict.lateral import load_rotor

        load_rotor(path)
    capsys.readouterr()
    assert fingerprint(folder) == before


_STRACE_SCRIPT = textwrap.dedent("""
    import sys
    from pathlib import Path
    from crankbench.measure import io as mio
    from crankbench.analysis.cli import main
    folder = Path(sys.argv[1])
    for p in sorted(folder.iterdir()):
        if p.suffix in mio.EXTENSIONS:
            mio.read(p)
            mio.open(p).load()
""")


def test_readers_open_inputs_read_only_under_strace(inputs, tmp_path):
    """System-call proof: no input is opened for writing, created, truncated, renamed or
    unlinked by any reader (eager and lazy)."""
    strace = shutil.which("strace")
    if strace is None:
        pytest.skip("strace not installed")
    log = tmp_path / "strace.log"
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    proc = subprocess.run(
        [strace, "-f", "-qq", "-o", str(log), "-e",
         "trace=open,openat,creat,rename,renameat,renameat2,unlink,unlinkat,truncate",
         sys.executable, "-c", _STRACE_SCRIPT, str(inputs)],
        capture_output=True, text=True, timeout=120, env=env)
    if proc.returncode != 0 and "ptrace" in proc.stderr:
        pytest.skip(f"ptrace not permitted: {proc.stderr.strip()[:200]}")
    assert proc.returncode == 0, proc.stderr[-2000:]
    folder = str(inputs)
    touched = [line for line in log.read_text().splitlines() if folder in line]
    assert any("O_RDONLY" in line for line in touched), "the inputs were never opened?"
    bad = [line for line in touched
           if re.search(r"O_WRONLY|O_RDWR|O_CREAT|O_TRUNC", line)
           or re.search(r"\b(creat|rename\w*|unlink\w*|truncate)\(", line)]
    assert bad == [], "\n".join(bad[:10])


# ------------------------------------------------------------------------------ outputs
@pytest.mark.parametrize("ext", FORMATS)
def test_write_refuses_to_overwrite(ext, tmp_path):
    path = tmp_path / f"out{ext}"
    mio.write(_record(), path)
    before = fingerprint(tmp_path)
    with pytest.raises(FileExistsError, match=rf"out{re.escape(ext)} exists; pass "
                                              r"overwrite=True to replace it"):
        mio.write(_record(n=500), path)
    assert fingerprint(tmp_path) == before
    mio.write(_record(n=500), path, overwrite=True)
    assert mio.read(path).sizes["time"] == 500
    assert not list(tmp_path.glob("*.part")) and not list(tmp_path.glob(".*"))


def test_wav_sidecar_is_not_overwritten_either(tmp_path):
    """An existing ``.wav.json`` alone blocks the write (its pair would be inconsistent)."""
    side = tmp_path / "out.wav.json"
    side.write_text('{"mine": true}')
    with pytest.raises(FileExistsError, match=r"out\.wav\.json exists; pass overwrite=True"):
        mio.write(_record(), tmp_path / "out.wav")
    assert side.read_text() == '{"mine": true}'
    assert not (tmp_path / "out.wav").exists()


@pytest.mark.parametrize("failure", [OSError(28, "No space left on device"),
                                     KeyboardInterrupt()], ids=["disk-full", "ctrl-c"])
@pytest.mark.parametrize("existing", [False, True], ids=["new", "replace"])
def test_failed_write_leaves_previous_file_and_no_temporary(failure, existing, tmp_path,
                                                            monkeypatch):
    from crankbench.measure.readers import module_for

    path = tmp_path / "out.h5"
    if existing:
        mio.write(_record(), path)
    before = fingerprint(tmp_path)
    module = module_for(path)

    def half_write(record, target, truth=None):
        Path(target).write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100)   # partial output
        raise failure

    monkeypatch.setattr(module, "write", half_write)
    with pytest.raises(type(failure)):
        mio.write(_record(n=300), path, overwrite=True)
    assert fingerprint(tmp_path) == before        # old file intact (or still absent)
    assert sorted(p.name for p in tmp_path.iterdir()) == (["out.h5"] if existing else [])


def _fake_rows(names, quick, progress=None):
    from crankbench.analysis.bench import Row

    return [Row(suite="fake", method="m", setting="s", error=0.0, error_kind="abs",
                reference="closed form", time_s=1e-3, bound=1.0)]


def test_bench_refuses_to_overwrite_its_outputs(tmp_path, monkeypatch, capsys):
    import crankbench.analysis.bench as bench_pkg

    monkeypatch.setattr(bench_pkg, "run_suites", _fake_rows)
    monkeypatch.setattr(bench_pkg, "suites", lambda: ["fake"])
    out = tmp_path / "bench-out"
    assert cli_main(["bench", "--suite", "fake", "-o", str(out)]) == 0
    before = fingerprint(out)
    assert {"bench.csv", "bench.json", "fake.png"} <= set(before)
    status = cli_main(["bench", "--suite", "fake", "-o", str(out)])
    err = capsys.readouterr().err
    assert status == 2
    assert re.search(r"bench\.csv exists; pass --overwrite to replace it", err), err
    assert fingerprint(out) == before
    assert cli_main(["bench", "--suite", "fake", "-o", str(out), "--overwrite"]) == 0
    assert not [p for p in out.iterdir() if p.name.startswith(".") or p.suffix == ".part"]


def test_bench_refusal_writes_nothing_when_only_a_later_output_exists(tmp_path, monkeypatch,
                                                                      capsys):
    import crankbench.analysis.bench as bench_pkg

    monkeypatch.setattr(bench_pkg, "run_suites", _fake_rows)
    monkeypatch.setattr(bench_pkg, "suites", lambda: ["fake"])
    out = tmp_path / "bench-out"
    out.mkdir()
    (out / "bench.json").write_text(json.dumps({"old": True}))
    before = fingerprint(out)
    assert cli_main(["bench", "--suite", "fake", "-o", str(out)]) == 2
    capsys.readouterr()
    assert fingerprint(out) == before


def test_printing_commands_write_nothing(inputs, tmp_path, capsys, monkeypatch):
    """``info`` and ``predict torsion`` (with --json) create no file in the working folder."""
    monkeypatch.chdir(tmp_path)
    model = MODELS / "shaftlines" / "two_rotor.toml"
    assert cli_main(["info", str(inputs / "rec.h5"), "--json"]) == 0
    if model.exists():
        assert cli_main(["predict", "torsion", str(model), "--json", "--no-forced",
                         "--speed-range", "100", "3000"]) == 0
    capsys.readouterr()
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------ CLI outputs
def _scene_file(folder: Path) -> Path:
    """The corpus' small valid scene (1 s steady, tacho + speed) with absolute model paths."""
    from importlib.util import module_from_spec, spec_from_file_location

    name = "crankbench_corpus_make_bad_models"
    if name not in sys.modules:
        spec = spec_from_file_location(name, ROOT / "tests" / "corpus" / "make_bad_models.py")
        sys.modules[name] = module_from_spec(spec)
        spec.loader.exec_module(sys.modules[name])
    gen = sys.modules[name]
    path = folder / "scene.toml"
    path.write_text(gen.SCENE.replace("../../../../sample_data", str(ROOT / "sample_data")))
    return path


def test_synth_writes_atomically_and_refuses_to_overwrite(tmp_path, capsys):
    if not (ROOT / "analysis" / "commands" / "synth.py").exists():
        pytest.skip("crankbench synth not present")
    scene = _scene_file(tmp_path)
    out = tmp_path / "out" / "rec.h5"
    out.parent.mkdir()
    scene_before = fingerprint(tmp_path)
    assert cli_main(["synth", str(scene), "-o", str(out)]) == 0
    capsys.readouterr()
    assert {k: v for k, v in fingerprint(tmp_path).items() if k == "scene.toml"} == {
        k: v for k, v in scene_before.items() if k == "scene.toml"}
    assert [p.name for p in out.parent.iterdir()] == ["rec.h5"]      # no temporary left
    rec = mio.read(out)
    assert "tacho" in rec.data_vars
    before = fingerprint(tmp_path)
    assert cli_main(["synth", str(scene), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert re.search(r"rec\.h5 exists; pass --overwrite to replace it", err), err
    assert fingerprint(tmp_path) == before


@pytest.mark.parametrize("command, existing", [
    (["report", "{rec}", "{model}", "-o", "{out}/rep.html"], ["rep.html"]),
    (["report", "{rec}", "{model}", "-o", "{out}/rep.html", "--pdf"], ["rep.pdf"]),
    (["analyse", "{rec}", "--channel", "acc", "--orders", "2", "--plot", "{out}"],
     ["campbell.png"]),
    (["batch", "{rec}", "--model", "{model}", "-o", "{out}/summary.csv"], ["summary.csv"]),
    (["demo", "-o", "{out}"], ["report.html"]),
    (["bench", "--suite", "kinematics", "-o", "{out}"], ["bench.csv"]),
], ids=["report", "report-pdf", "analyse-plot", "batch", "demo", "bench"])
def test_cli_refuses_existing_output_before_any_work(command, existing, inputs, tmp_path,
                                                     capsys, monkeypatch):
    """An existing output blocks the command (exit 2, message names --overwrite); outputs
    and inputs stay byte-for-byte as they were."""
    name = command[0]
    if not (ROOT / "analysis" / "commands" / f"{name}.py").exists():
        pytest.skip(f"crankbench {name} not present")
    if name == "bench":            # keep the test fast should bench ever run before checking
        import crankbench.analysis.bench as bench_pkg

        monkeypatch.setattr(bench_pkg, "run_suites", _fake_rows)
    out = tmp_path / "out"
    out.mkdir()
    for f in existing:
        (out / f).write_bytes(b"previous results, must survive\n")
    model = MODELS / "shaftlines" / "two_rotor.toml"
    args = [a.format(rec=inputs / "rec.h5", model=model, out=out) for a in command]
    before_out, before_in = fingerprint(out), fingerprint(inputs)
    assert cli_main(args) == 2
    err = capsys.readouterr().err
    assert re.search(rf"{re.escape(existing[0])} exists; pass --overwrite to replace it", err), err
    assert fingerprint(out) == before_out
    assert fingerprint(inputs) == before_in
