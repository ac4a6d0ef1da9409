"""The committed sample records: current, deterministic, consistent across formats, < 2 MB."""

import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from crankbench.measure import io

FORMATS = (".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav")


@pytest.fixture(scope="module")
def generator():
    script = Path(__file__).resolve().parents[2] / "sample_data" / "make_records.py"
    return runpy.run_path(str(script))


@pytest.mark.parametrize("ext", FORMATS)
def test_committed_file_matches_generator_and_is_small(ext, sample_data, generator):
    path = sample_data / "records" / f"i4_runup{ext}"
    assert path.stat().st_size < 2_000_000
    record, _ = generator["build"]()
    back = io.read(path)
    for name in record.data_vars:
        np.testing.assert_array_equal(back[name].values, record[name].values, err_msg=name)
        assert back[name].attrs["units"] == record[name].attrs["units"]
    assert back.attrs["start_time"] == "2026-01-15T09:30:00+00:00"


def test_truth_matches_the_signal(sample_data, generator):
    """Least-squares fit of cos/sin of every truth order over 0.1 s windows, with the shaft
    angle from the analytic run-up, recovers the stored truth amplitudes within the noise."""
    rec = io.read(sample_data / "records" / "i4_runup.h5")
    truth = io.read_truth(sample_data / "records" / "i4_runup.h5")
    t = rec["time"].values
    x = rec["acc_block_z"].values.astype(np.float64)
    theta = 2 * np.pi * generator["revolutions"](t)
    orders = truth["order"].values
    for t_mid in (0.5, 2.0, 3.5):
        sel = np.abs(t - t_mid) < 0.05
        basis = np.column_stack([f(q * theta[sel]) for q in orders for f in (np.cos, np.sin)]
                                + [np.ones(sel.sum())])
        coef, *_ = np.linalg.lstsq(basis, x[sel], rcond=None)
        rpm = generator["speed_rpm"](t_mid)
        for k, q in enumerate(orders):
            ref = truth["amplitude"].sel(order=q).interp(rpm=rpm).item()
            # amplitude varies ~2 % across the window; noise 0.05 rms over 1000 samples
            assert np.hypot(*coef[2 * k:2 * k + 2]) == pytest.approx(ref, rel=0.03, abs=0.02)


def test_tacho_is_60_minus_2(sample_data):
    rec = io.read(sample_data / "records" / "i4_runup.tdms")
    edges = rec["tacho"].values
    gaps = np.diff(edges)
    ratio = gaps[1:] / gaps[:-1]
    # the gap after tooth 57 spans 3 pitches; 2 missing teeth per revolution
    assert np.sum(ratio > 2.5) == pytest.approx(len(edges) / 58, abs=1)


def test_generator_refuses_overwrite(tmp_path):
    script = Path(__file__).resolve().parents[2] / "sample_data" / "make_records.py"
    (tmp_path / "i4_runup.tdms").write_bytes(b"keep me")
    res = subprocess.run([sys.executable, str(script), "--out", str(tmp_path)],
                         capture_output=True, text=True)
    assert res.returncode == 1 and "pass --overwrite to replace them" in res.stderr
    assert (tmp_path / "i4_runup.tdms").read_bytes() == b"keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["i4_runup.tdms"]


def test_raw_genset_export_matches_its_generator_and_imports(sample_data, tmp_path):
    """sample_data/raw: the committed raw export is what make_raw.py writes, and its map reads
    it to the 60-2 wheel it holds (58 edges per revolution, the runt tooth 57 named)."""
    script = sample_data / "raw" / "make_raw.py"
    made = runpy.run_path(str(script))["make"](tmp_path)
    for p in made:
        assert p.read_bytes() == (sample_data / "raw" / p.name).read_bytes(), p.name
    rec = io.read(sample_data / "raw" / "genset_60-2.txt",
                  map=sample_data / "raw" / "genset_60-2_map.toml")
    assert rec["crank"].attrs["runt_teeth"] == [57]
    assert "58.00 per revolution" in rec["crank"].attrs["decoding"]
    assert rec.attrs["engine_id"] == "G1 genset"
