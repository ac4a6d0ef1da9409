"""Property-based tests of order analysis on random signals and speeds.

Random signals (noise, constants, tones, tiny and huge scales) with random speeds (steady,
ramps, noisy, with zero, negative or tiny stretches) go through angle resampling, order
tracking (COT and Vold-Kalman), order maps, order spectra and Campbell maps. Each call gives
an :class:`~predict.errors.AnalysisError` (our family) or a result whose numbers are all
finite; none hangs (20 s alarm per call). A known order at a known speed is recovered.
"""

from __future__ import annotations


import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from crankbench.analysis.orders import campbell_map, order_map, order_spectrum, order_track
from crankbench.analysis.resample import angle_resample, shaft_angle
from crankbench.analysis.vkf import vold_kalman
from hang_guard import time_limit
from crankbench.predict.errors import CrankbenchError

FUZZ = settings(max_examples=15, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.filter_too_much])




def _all_finite(result):
    """Every float/complex number in a DataArray/Dataset (data and coords) is finite."""
    objs = [result] if not hasattr(result, "data_vars") else list(result.data_vars.values())
    for obj in objs + [c for c in result.coords.values()]:
        values = np.asarray(obj.values)
        if values.dtype.kind in "fc":
            assert np.all(np.isfinite(values)), (
                f"{obj.name!r}: {int(np.sum(~np.isfinite(values)))} non-finite values")


@st.composite
def signals(draw):
    """(x, fs, rpm) with speeds from 1e-6 rpm to 1e8 rpm.

    Speeds with fewer than 2 samples per revolution, or so slow that the anti-alias filter
    is longer than the record, must be refused before anything large is allocated (found
    unbounded: MemoryError / OOM; fixed in 14ddf9b)."""
    fs = draw(st.sampled_from([200.0, 1000.0, 8000.0]))
    n = draw(st.integers(8, 3000))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    kind = draw(st.sampled_from(["noise", "constant", "zeros", "tone", "spikes"]))
    scale = draw(st.sampled_from([1e-12, 1.0, 1e6, 1e100]))
    t = np.arange(n) / fs
    if kind == "noise":
        x = rng.standard_normal(n)
    elif kind == "constant":
        x = np.full(n, 1.0)
    elif kind == "zeros":
        x = np.zeros(n)
    elif kind == "tone":
        x = np.cos(2 * np.pi * rng.uniform(0, fs / 2) * t)
    else:
        x = np.zeros(n)
        x[rng.integers(0, n, 3)] = 1.0
    rpm_max = draw(st.sampled_from([fs * 60.0 / 2.5, 1e8]))
    rkind = draw(st.sampled_from(["scalar", "steady", "ramp", "noisy", "zero-run", "negative",
                                  "tiny"]))
    r0 = draw(st.floats(2.0, rpm_max))
    if rkind == "scalar":
        rpm = r0
    elif rkind == "steady":
        rpm = np.full(n, r0)
    elif rkind == "ramp":
        rpm = np.linspace(r0, draw(st.floats(2.0, rpm_max)), n)
    elif rkind == "noisy":
        rpm = np.clip(r0 * (1 + 0.1 * rng.standard_normal(n)), 2.0, rpm_max)
    elif rkind == "zero-run":
        rpm = np.full(n, r0)
        a = int(rng.integers(0, n))
        rpm[a:a + int(rng.integers(1, n))] = 0.0
    elif rkind == "negative":
        rpm = -np.full(n, r0)
    else:
        rpm = np.full(n, draw(st.floats(1e-6, 5.0)))
    return x * scale, fs, rpm


CALLS = {
    "angle_resample": lambda x, fs, rpm: angle_resample(x, fs=fs, speed_rpm=rpm,
                                                        samples_per_rev=16),
    "order_track": lambda x, fs, rpm: order_track(x, fs=fs, speed_rpm=rpm, orders=[0.5, 1.0, 2.0],
                                                  samples_per_rev=16, revolutions=2),
    "order_track_vkf": lambda x, fs, rpm: order_track(x, fs=fs, speed_rpm=rpm, orders=[1.0, 2.0],
                                                      method="vkf", bandwidth_orders=0.5),
    "order_map": lambda x, fs, rpm: order_map(x, fs=fs, speed_rpm=rpm, samples_per_rev=16,
                                              revolutions=2),
    "order_spectrum": lambda x, fs, rpm: order_spectrum(x, fs=fs, speed_rpm=rpm,
                                                        samples_per_rev=16),
    "campbell_map": lambda x, fs, rpm: campbell_map(x, fs=fs, speed_rpm=rpm, nperseg=64),
}


@pytest.mark.parametrize("name", list(CALLS))
@FUZZ
@given(data=signals())
def test_random_signal_and_speed_give_our_error_or_finite_result(name, data):
    x, fs, rpm = data
    try:
        with time_limit(20, "order analysis"):
            result = CALLS[name](x, fs, rpm)
    except CrankbenchError as exc:
        assert str(exc)
        return
    _all_finite(result)


@FUZZ
@given(order=st.sampled_from([0.5, 1.0, 1.5, 2.0, 3.0, 4.0]), amp=st.floats(1e-6, 1e6),
       phase=st.floats(-3.0, 3.0), rpm0=st.floats(600.0, 3000.0), rise=st.floats(0.0, 0.5))
def test_known_order_amplitude_and_phase_recovered(order, amp, phase, rpm0, rise):
    """x = A cos(q φ(t) + p) on a slow ramp: COT gives A (0.5 %) and p (0.01 rad) at order q,
    an independent check from the signal's construction."""
    fs = 4000.0
    n = int(3 * fs)
    rpm = rpm0 * (1 + rise * np.arange(n) / n)
    x = amp * np.cos(order * shaft_angle(rpm, fs) + phase)
    res = order_track(x, fs=fs, speed_rpm=rpm, orders=[order], revolutions=8)
    a = res.amplitude.sel(order=order).values
    p = res.phase.sel(order=order).values
    np.testing.assert_allclose(a, amp, rtol=5e-3)
    np.testing.assert_allclose(np.angle(np.exp(1j * (p - phase))), 0.0, atol=1e-2)


@FUZZ
@given(n=st.integers(64, 2000), fs=st.sampled_from([500.0, 4000.0]),
       rpm=st.floats(30.0, 3000.0))
def test_vkf_on_zero_signal_is_zero_not_nan(n, fs, rpm):
    try:
        res = vold_kalman(np.zeros(n), fs=fs, speed_rpm=np.full(n, rpm), orders=[1.0],
                          bandwidth_orders=0.5)
    except CrankbenchError as exc:      # too short for the filter: our error, named
        assert "x:" in str(exc)
        return
    env = np.asarray(res["envelope"].values)
    assert np.all(np.isfinite(env)) and np.all(np.abs(env) < 1e-300)


def test_speed_far_above_sample_rate_is_our_error():
    x = np.random.default_rng(0).standard_normal(200)
    with time_limit(10, "order analysis"), \
            pytest.raises(CrankbenchError, match=r"rpm.*(sample|fs)"):
        order_map(x, fs=1000.0, speed_rpm=1e6)


def test_speed_far_below_sample_rate_is_our_error(monkeypatch):
    """The filter must not be designed when it is longer than the record. scipy's firwin is
    replaced by a guard so the test itself never allocates the 7 GiB."""
    from scipy import signal as sps

    firwin = sps.firwin

    def guarded(numtaps, *args, **kwargs):
        if numtaps > 1_000_000:
            raise AssertionError(f"firwin asked for {numtaps} taps for a 64-sample record")
        return firwin(numtaps, *args, **kwargs)

    monkeypatch.setattr(sps, "firwin", guarded)
    x = np.random.default_rng(0).standard_normal(64)
    with pytest.raises(CrankbenchError, match=r"taps|rpm"):
        angle_resample(x, fs=200.0, speed_rpm=np.full(64, 1e-5), samples_per_rev=16)


def test_vkf_at_extremely_low_speed_does_not_design_a_huge_filter(monkeypatch):
    from scipy import signal as sps

    firwin = sps.firwin

    def guarded(numtaps, *args, **kwargs):
        if numtaps > 1_000_000:
            raise AssertionError(f"firwin asked for {numtaps} taps for an 8-sample record")
        return firwin(numtaps, *args, **kwargs)

    monkeypatch.setattr(sps, "firwin", guarded)
    try:
        vold_kalman(np.full(8, 1e-13), fs=200.0, speed_rpm=np.full(8, 1e-6), orders=[1.0, 2.0],
                    bandwidth_orders=0.5)
    except CrankbenchError:
        pass
