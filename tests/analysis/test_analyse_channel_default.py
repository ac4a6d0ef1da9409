"""`crankbench analyse` without --channel: the record's only signal channel, or a clear error
listing the candidates."""

import json

import numpy as np

from crankbench.analysis.cli import main


def _csv(path, extra=False):
    fs = 2000.0
    t = np.arange(int(4 * fs)) / fs
    rpm = 1200 + 100 * t
    phi = np.cumsum(rpm / 60 * 2 * np.pi / fs)
    acc = 0.5 * np.sin(2 * phi)
    head = "time [s],speed [rpm],acc [m/s^2]" + (",acc2 [m/s^2]" if extra else "")
    path.write_text(head + "\n" + "".join(
        f"{a:.6f},{b:.3f},{c:.6f}" + (f",{c:.6f}" if extra else "") + "\n"
        for a, b, c in zip(t, rpm, acc)))
    return path


def test_only_signal_channel_is_taken(tmp_path, capsys):
    path = _csv(tmp_path / "one.csv")
    assert main(["analyse", str(path), "--orders", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["channel"] == "acc"


def test_two_signal_channels_need_a_choice(tmp_path, capsys):
    path = _csv(tmp_path / "two.csv", extra=True)
    assert main(["analyse", str(path), "--orders", "2"]) == 2
    err = capsys.readouterr().err
    assert "give --channel: the record has 2 signal channels (acc, acc2)" in err


def test_time_in_ms_labelled_seconds_is_named(tmp_path, capsys):
    """A time column in ms under a 'Time [s]' header makes the rate 1000x too low: the
    refusal names the time axis as the likely cause and the settings to fix it."""
    fs = 2000.0
    t = np.arange(int(2 * fs)) / fs
    phi = np.cumsum((1500 + 0 * t) / 60 * 2 * np.pi / fs)
    path = tmp_path / "ms.csv"
    path.write_text("Time [s],speed [rpm],acc [m/s^2]\n" + "".join(
        f"{1e3 * a:.4f},1500,{np.sin(2 * p):.6f}\n" for a, p in zip(t, phi)))
    assert main(["analyse", str(path), "--orders", "2"]) == 2
    err = capsys.readouterr().err
    assert "above the Nyquist frequency 1 Hz" in err and "time column in ms read as s" in err
