"""``crankbench analyse``: a hand-built record through the command line."""

import json

import numpy as np
import pytest

from crankbench.analysis.cli import main
from crankbench.analysis.resample import shaft_angle


@pytest.fixture
def record_path(tmp_path):
    measure_io = pytest.importorskip("crankbench.measure.io")
    from crankbench.measure.record import make_record

    fs = 5000.0
    t = np.arange(int(6 * fs)) / fs
    rpm = 1200 + 100 * t
    acc = 2.0 * np.cos(1.5 * shaft_angle(rpm, fs)) + 0.5 * np.cos(3 * shaft_angle(rpm, fs))
    ts = np.arange(0, 6.0, 0.01)
    rec = make_record({
        "acc": dict(data=acc, sample_rate=fs, units="m/s^2", quantity="acceleration"),
        "speed": dict(data=(1200 + 100 * ts) * 2 * np.pi / 60, sample_rate=100.0, units="rad/s",
                      quantity="rotational_speed"),
    })
    path = tmp_path / "runup.nc"
    measure_io.write(rec, path)
    return path


def test_json_summary_recovers_orders(record_path, capsys):
    code = main(["analyse", str(record_path), "--channel", "acc", "--orders", "1.5,3",
                 "--revolutions", "8", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    amps = {row["order"]: row["mean_amplitude"] for row in out["summary"]}
    assert amps[1.5] == pytest.approx(2.0, rel=1e-3)
    assert amps[3.0] == pytest.approx(0.5, rel=1e-3)
    assert out["units"] == "m/s^2" and out["amplitude_convention"] == "peak"
    assert out["tracks"]["orders"]["1.5"]["amplitude"]


def test_vkf_rms_table(record_path, capsys):
    code = main(["analyse", str(record_path), "--channel", "acc", "--orders", "1.5",
                 "--method", "vkf", "--bandwidth-hz", "2", "--amplitude", "rms"])
    assert code == 0
    text = capsys.readouterr().out
    assert "rms amplitude" in text and "1.41" in text        # 2/√2


def test_plots_written_atomically_and_not_overwritten(record_path, tmp_path, capsys):
    out = tmp_path / "plots"
    args = ["analyse", str(record_path), "--channel", "acc", "--orders", "1.5,3",
            "--revolutions", "8", "--plot", str(out)]
    assert main(args) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["campbell.png", "order_map.png", "order_tracks.png"]
    assert main(args) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert main(args + ["--overwrite"]) == 0


def test_unknown_channel_suggests(record_path, capsys):
    assert main(["analyse", str(record_path), "--channel", "acx", "--orders", "1"]) == 2
    assert "did you mean 'acc'" in capsys.readouterr().err
