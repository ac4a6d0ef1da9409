"""``crankbench info``: the README's main job, on every sample format."""

import hashlib
import json
from pathlib import Path

import pytest

from crankbench.analysis.cli import main

RECORDS = Path(__file__).resolve().parents[2] / "sample_data" / "records"


@pytest.mark.parametrize("ext", [".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav"])
def test_info_json(ext, capsys):
    path = RECORDS / f"i4_runup{ext}"
    assert main(["info", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["attrs"]["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    assert out["attrs"]["start_time"] == "2026-01-15T09:30:00+00:00"
    assert out["duration_s"] == pytest.approx(4.0)
    chans = {c["name"]: c for c in out["channels"]}
    assert chans["acc_block_z"]["sample_rate"] == 10000.0 and chans["acc_block_z"]["n"] == 40000
    assert chans["acc_block_z"]["units"] == "m/s^2"
    assert chans["speed"]["sample_rate"] == 100.0 and chans["speed"]["units"] == "rad/s"
    assert chans["speed"]["dim"] == "time_speed"
    assert chans["tacho"]["quantity"] == "pulse_times" and chans["tacho"]["sample_rate"] is None
    assert chans["tacho"]["pulses_per_rev"] == 60 and chans["tacho"]["missing_teeth"] == 2


def test_info_table(capsys):
    assert main(["info", str(RECORDS / "i4_runup.h5")]) == 0
    text = capsys.readouterr().out
    assert "start_time  2026-01-15T09:30:00+00:00" in text
    assert "duration    4 s" in text
    assert "acc_block_z" in text and "rotational_speed" in text


def test_info_errors_are_one_line(capsys, tmp_path):
    assert main(["info", str(tmp_path / "missing.h5")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("crankbench info: error: record file ") and "missing.h5" in err
    assert main(["info", str(RECORDS / "i4_runup.hdf")]) == 2
    assert "did you mean '.h5'?" in capsys.readouterr().err
