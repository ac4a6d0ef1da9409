"""Order tracking of a channel with a dropout (NaN run): the span is masked, not fatal.

Truth: the signal is a known sum of orders, so every unmasked result is checked against the
amplitudes it was built with; the masked results must cover the dropout.
"""

import numpy as np
import pytest

from crankbench.analysis import order_track
from crankbench.analysis.resample import shaft_angle
from crankbench.measure.record import RecordWarning


@pytest.mark.parametrize("method", ["cot", "vkf"])
def test_dropout_is_masked_with_warning_and_the_rest_is_exact(method):
    fs = 4000.0
    t = np.arange(int(8 * fs)) / fs
    rpm = 1200.0 + 100.0 * t
    phi = shaft_angle(rpm, fs)
    x = np.cos(2 * phi) + 0.3 * np.cos(4.5 * phi)
    x[12000:12200] = np.nan                                     # 3.0 .. 3.04975 s
    with pytest.warns(RecordWarning, match=r"x: 200 NaN/inf sample\(s\) masked at 3\.\.3\.04975 s"):
        res = order_track(x, fs=fs, speed_rpm=rpm, orders=[2, 4.5], method=method, revolutions=8)
    amp = res.amplitude.sel(order=2).values
    times = res.time.values
    masked = ~np.isfinite(amp)
    assert masked[np.abs(times - 3.025) < 0.03].all()            # results at the gap are NaN
    assert masked.mean() < 0.5                                  # ... and not the whole record
    np.testing.assert_allclose(amp[~masked], 1.0, rtol=1e-3)
    np.testing.assert_allclose(res.amplitude.sel(order=4.5).values[~masked], 0.3, rtol=1e-3)
    assert res.attrs["masked_spans_s"] == [3.0, 12199 / fs]


def test_all_nan_channel_is_still_an_error():
    from crankbench.predict.errors import AnalysisError

    with pytest.raises(AnalysisError,
                       match=r"x contains 4000 NaN/inf value\(s\), first at index 0"):
        order_track(np.full(4000, np.nan), fs=4000.0, speed_rpm=1500.0, orders=[2])
