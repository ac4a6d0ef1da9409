"""Every bad command line of the corpus (``tests/corpus/bad_commands.py``) ends with its exit
status and named message, in one line, without a traceback; a refused command changes no
input and writes no file."""

from __future__ import annotations

import hashlib
import importlib.util
import re
import sys
import time
import warnings
from pathlib import Path

import pytest

from crankbench.analysis.cli import main as cli_main

CORPUS = Path(__file__).resolve().parents[1] / "corpus"


def _load():
    name = "crankbench_corpus_bad_commands"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, CORPUS / "bad_commands.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


gen = _load()


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad_commands")
    return folder, gen.build_workspace(folder)


def _fingerprint(folder: Path) -> dict:
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and not p.is_symlink():
            st = p.stat()
            out[str(p.relative_to(folder))] = (hashlib.sha256(p.read_bytes()).hexdigest(),
                                               st.st_mtime_ns)
        elif p.is_symlink():
            out[str(p.relative_to(folder))] = ("link", str(p.readlink()))
    return out


def test_corpus_covers_the_issue_cases():
    names = {c.name for c in gen.CASES}
    assert {"batch_output_is_the_record", "batch_output_is_the_wav_sidecar",
            "analyse_orders_repeated_item", "analyse_orders_space_inside_one_argument",
            "analyse_orders_empty_item", "compare_reference_rpm_zero",
            "batch_scheduler_unreachable", "balance_trial_run_at_another_speed",
            "predict_lateral_mesh_of_15_million_elements", "synth_scene_at_1e12_hz",
            "predict_torsion_chain_beyond_the_memory_limit",
            "predict_torsion_shear_modulus_in_gpa_without_unit"} <= names
    assert len(names) == len(gen.CASES)


@pytest.mark.parametrize("case", gen.CASES, ids=[c.name for c in gen.CASES])
def test_bad_command(case, workspace, capsys, monkeypatch):
    folder, values = workspace
    for key, value in case.env.items():
        monkeypatch.setenv(key, value)
    argv = [a.format(**values) for a in case.argv]
    before = _fingerprint(folder)
    capsys.readouterr()
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:   # pytest records warnings itself:
        warnings.simplefilter("always")                  # the CLI logs them otherwise
        try:
            status = cli_main(argv)
        except SystemExit as exc:          # argparse's usage errors
            status = exc.code
    elapsed = time.perf_counter() - t0
    err = capsys.readouterr().err + "".join(f"warning: {w.message}\n" for w in caught)
    assert status == case.status, err
    for pattern in case.match:
        assert re.search(pattern, err), f"{pattern!r} not in {err!r}"
    assert "Traceback" not in err
    if case.status != 0:
        # refused: one line naming the problem (argparse adds its usage lines above it)
        errors = [line for line in err.splitlines() if ": error: " in line]
        assert len(errors) == 1, err
        assert _fingerprint(folder) == before, "a refused command changed or wrote a file"
        assert elapsed < 30.0, f"refused only after {elapsed:.0f} s"
