"""Bad inputs to the order map after its one-pass checks: each still gets the full check's
clear error (the fast path only accepts; it never decides an error)."""

import numpy as np
import pytest

from crankbench.analysis.ordermap import order_map
from crankbench.predict.errors import AnalysisError


def _case(n=40_000, fs=4_000.0):
    t = np.arange(n) / fs
    return np.cos(2 * np.pi * 40.0 * t), fs, np.linspace(1200.0, 1800.0, n)


def test_an_empty_speed_channel_is_named_not_a_traceback():
    x, fs, _ = _case()
    with pytest.raises(AnalysisError, match="speed_rpm holds no samples"):
        order_map(x, fs=fs, speed_rpm=np.array([]))


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_sample_is_located(bad):
    x, fs, rpm = _case()
    x[1234] = bad
    with pytest.raises(AnalysisError, match="1 NaN/inf value.*first at index 1234"):
        order_map(x, fs=fs, speed_rpm=rpm)
    x[1234] = 0.0
    rpm[777] = bad
    with pytest.raises(AnalysisError, match="NaN/inf value.*first at index 777"):
        order_map(x, fs=fs, speed_rpm=rpm)


def test_huge_finite_values_are_refused_by_name():
    """Finite samples whose sum of squares overflows (10 × 1e308) are not NaN nor inf, but
    every sum of squares of the analysis would overflow into NaN tracks: refused with the
    channel's name and magnitude (the full check finds no NaN/inf, so it is the size)."""
    from crankbench.analysis.resample import _as_signal
    from crankbench.predict.errors import AnalysisError

    with pytest.raises(AnalysisError, match=r"x reaches 1e\+308 .*too large to analyse"):
        _as_signal(np.full(10, 1e308), 2.0)
    values, fs, _, _ = _as_signal(np.full(10, 1e150), 2.0)
    assert values.shape == (10,) and fs == 2.0
