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
