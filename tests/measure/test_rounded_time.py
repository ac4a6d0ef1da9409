"""A time column printed with too few decimals (5 kHz written as %.3f) is a uniform clock
rounded: rebuilt, with a warning; a column with a real gap or reversal is still refused."""

import logging

import numpy as np
import pytest

from crankbench.measure import read
from crankbench.predict.errors import RecordError


def _write(path, t, x):
    path.write_text("Time [s];Acc [m/s^2];\r\n"
                    + "".join(f"{a:.3f};{b:.6f};\r\n" for a, b in zip(t, x)))


def test_rounded_time_is_rebuilt_as_the_uniform_clock(tmp_path, caplog):
    fs = 5000.0
    t = 0.0123 + np.arange(20_000) / fs
    x = np.sin(2 * np.pi * 37.0 * t)
    path = tmp_path / "rounded.csv"
    _write(path, t, x)
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        rec = read(path)
    # the stamps carry ±0.5 ms: the clock fitted through 20 000 of them is within 1e-4 in rate
    # and half the rounding step in time (measured 4.3e-5 and 0.17 ms: the exact half-step
    # stamps, 1 in 5 here, round up or down by their binary representation)
    assert rec["Acc"].attrs["sample_rate"] == pytest.approx(fs, rel=1e-4)
    np.testing.assert_allclose(rec["time"].values, t, atol=5e-4)
    assert any("rounded to 0.001 s" in r.getMessage() for r in caplog.records)


def test_a_real_gap_is_not_smoothed_over(tmp_path):
    fs = 5000.0
    t = np.arange(20_000) / fs
    t[10_000:] += 0.01                             # 10 ms missing: not rounding
    path = tmp_path / "gap.csv"
    _write(path, t, np.zeros_like(t))
    with pytest.raises(RecordError):
        read(path)


def _write_g(path, t, columns, header):
    """Time and channels printed as ``%.6g`` (pandas/MATLAB style): time loses a decimal at
    every power of ten, 8 kHz stamps step 0.1/0.2 ms once past 10 s."""
    rows = (",".join(f"{v:.6g}" for v in row) for row in zip(t, *columns))
    path.write_text(header + "\n" + "\n".join(rows) + "\n")


def test_significant_digit_time_is_rebuilt(tmp_path, caplog):
    fs = 8000.0
    t = np.arange(int(12.5 * fs)) / fs           # crosses 1 s and 10 s: 6, 5, 4 decimals
    x = np.sin(2 * np.pi * 50.0 * t)
    path = tmp_path / "g.csv"
    _write_g(path, t, [x], "t,acc [m/s^2]")
    steps = np.diff(np.loadtxt(path, delimiter=",", skiprows=1)[:, 0])
    assert steps.max() > 1.5 / fs                # the file really is irregular as printed
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        rec = read(path)
    assert rec["acc"].attrs["sample_rate"] == pytest.approx(fs, rel=1e-6)
    np.testing.assert_allclose(rec["time"].values, t, atol=0.6e-4)
    assert any("rounded to 0.0001 s" in r.getMessage() for r in caplog.records)


def test_significant_digit_time_with_a_gap_is_refused(tmp_path):
    fs = 8000.0
    t = np.arange(int(12.5 * fs)) / fs
    t[90_000:] += 0.002                          # 16 samples missing after 11.25 s
    path = tmp_path / "g_gap.csv"
    _write_g(path, t, [np.zeros_like(t)], "t,acc [m/s^2]")
    with pytest.raises(RecordError, match="time step"):
        read(path)


def test_a_row_cut_mid_write_is_dropped_with_a_warning(tmp_path, caplog):
    fs = 1000.0
    t = np.arange(2000) / fs
    path = tmp_path / "cut.csv"
    _write_g(path, t, [np.cos(t), 1000 + t], "time [s],acc [g],RPM")
    text = path.read_text()
    path.write_text(text[:text.rstrip("\n").rfind(",")] + ",")   # last cell and newline lost
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        rec = read(path)
    assert rec.sizes["time"] == 1999 and np.all(np.isfinite(rec["acc"].values))
    assert any("cut while writing" in r.getMessage() for r in caplog.records)
    # a column headed just "RPM" is a speed in rpm (stored in rad/s)
    assert rec["RPM"].attrs["units"] == "rad/s"
    np.testing.assert_allclose(rec["RPM"].values, (1000 + t[:1999]) * np.pi / 30, rtol=1e-5)


def test_what_reading_changed_stays_with_the_record(tmp_path):
    """A rebuilt clock and a dropped row are kept in the record's ``read_notes`` attr, so an
    imported record (and the report's metadata) still says so."""
    from crankbench.measure import write

    fs = 8000.0
    t = np.arange(int(10.5 * fs)) / fs
    path = tmp_path / "g.csv"
    _write_g(path, t, [np.sin(t)], "t,acc [m/s^2]")
    path.write_text(path.read_text()[:-4])               # cut inside the last row's cell
    rec = read(path)
    notes = rec.attrs["read_notes"]
    assert "rebuilt as a uniform 8000 Hz clock" in notes and "cut while writing" in notes
    assert rec.sizes["time"] == t.size - 1         # the row with its number cut short
    out = tmp_path / "g.h5"
    write(rec, out)
    assert read(out).attrs["read_notes"] == notes
