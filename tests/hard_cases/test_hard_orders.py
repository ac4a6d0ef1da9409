"""Hard cases for order tracking (COT and VKF): very fast run-ups, an order crossing a
fixed-frequency component, 0 dB signal-to-noise with the stated error estimate checked against
the actual error, zero-speed and crawling-speed segments. Truth: the synthesis (closed form).

Already covered elsewhere (not repeated):

* two shafts' orders crossing at 120 rpm/s, VKF joint solve — ``tests/analysis/test_vkf.py
  ::test_crossing_orders_separated_only_when_solved_jointly``;
* negative / NaN speed refused by ``order_track``, ``order_map``, ``order_spectrum``, zero
  speed by the map and spectrum — ``tests/reliability/test_bad_signals.py
  ::test_unusable_channel_is_named_error`` (``order_track`` tracks around a stop, below);
* COT noise estimate at moderate SNR — ``tests/analysis/test_orders.py``.
"""

import numpy as np
import pytest

from crankbench.analysis.orders import order_track
from crankbench.analysis.resample import shaft_angle
from crankbench.measure.tacho import speed_from_pulses
from crankbench.predict.errors import AnalysisError

TWO_PI = 2 * np.pi


def _fast_runup(fs=20_000.0, duration=3.0, rpm0=600.0, rate=2000.0):
    t = np.arange(int(round(duration * fs))) / fs
    rpm = rpm0 + rate * t
    return t, rpm, shaft_angle(rpm, fs)


def _amp2(rpm):
    """Order-2 amplitude growing with speed (as an inertia-driven order does)."""
    return 1.0 + rpm / 6000.0


def test_cot_through_a_2000_rpm_per_s_runup():
    """600 → 6600 rpm in 3 s: order 2 (amplitude ∝ speed) within 0.5 % of the truth at the
    block centre speed, steady order 4 within 1e-3."""
    fs = 20_000.0
    t, rpm, phi = _fast_runup(fs)
    x = _amp2(rpm) * np.cos(2 * phi + 0.4) + 0.3 * np.cos(4 * phi)
    res = order_track(x, fs=fs, speed_rpm=rpm, orders=[2, 4], revolutions=8)
    a2 = res.amplitude.sel(order=2).values
    assert a2.size >= 30
    assert np.abs(a2 / _amp2(res.rpm.values) - 1).max() < 5e-3
    assert np.abs(res.amplitude.sel(order=4).values / 0.3 - 1).max() < 1e-3
    assert np.abs(np.angle(np.exp(1j * (res.phase.sel(order=2).values - 0.4)))).max() < 1e-2


def test_vkf_through_a_2000_rpm_per_s_runup():
    fs = 20_000.0
    t, rpm, phi = _fast_runup(fs)
    x = _amp2(rpm) * np.cos(2 * phi + 0.4) + 0.3 * np.cos(4 * phi)
    res = order_track(x, fs=fs, speed_rpm=rpm, orders=[2, 4], method="vkf", bandwidth_orders=0.2)
    sel = ((res.time > 0.3) & (res.time < 2.7)).values
    a2 = res.amplitude.sel(order=2).values[sel]
    assert np.abs(a2 / _amp2(res.rpm.values[sel]) - 1).max() < 1e-3
    assert np.abs(res.amplitude.sel(order=4).values[sel] / 0.3 - 1).max() < 1e-3


def test_fast_runup_tracked_with_speed_from_a_60_tooth_wheel():
    """The realistic chain at 2000 rpm/s: exact edge times of a 60-tooth wheel → speed →
    COT. The speed and the order amplitude stay within 1e-3 of the truth."""
    fs = 20_000.0
    t, rpm, phi = _fast_runup(fs)
    w0, alpha = 600.0 * TWO_PI / 60, 2000.0 * TWO_PI / 60
    theta = np.arange(1, int(phi[-1] / (TWO_PI / 60))) * TWO_PI / 60
    edges = (-w0 + np.sqrt(w0 ** 2 + 2 * alpha * theta)) / alpha
    trace = speed_from_pulses(edges, pulses_per_rev=60)
    rpm_meas = np.interp(t, trace.time, trace.speed_rpm)
    inside = (t > trace.time[0]) & (t < trace.time[-1])
    assert np.abs(rpm_meas[inside] / rpm[inside] - 1).max() < 1e-6
    x = _amp2(rpm) * np.cos(2 * phi + 0.4)
    res = order_track(x, fs=fs, speed_rpm=rpm_meas, orders=[2], revolutions=8)
    ok = ((res.time > trace.time[0] + 0.05) & (res.time < trace.time[-1] - 0.05)).values
    a2 = res.amplitude.sel(order=2).values[ok]
    assert np.abs(a2 / _amp2(res.rpm.values[ok]) - 1).max() < 5e-3


def test_order_crossing_a_fixed_frequency_component_at_1000_rpm_per_s():
    """Order 2 sweeps through a 50 Hz component (mains / a structural mode) at 1500 rpm during
    a 1000 rpm/s run-up. Solved jointly (the 50 Hz line as order 1 of a 3000 rpm 'shaft', a
    2-D rpm), both amplitudes stay within 1e-3 through the crossing; tracking order 2 alone
    shows the beat (> 10 % error near the crossing)."""
    fs = 4000.0
    t = np.arange(int(2.4 * fs)) / fs
    rpm = 300.0 + 1000.0 * t
    x = np.cos(2 * shaft_angle(rpm, fs)) + 0.5 * np.cos(TWO_PI * 50.0 * t + 1.0)
    both = np.stack([rpm, np.full(t.size, 3000.0)])
    alone = order_track(x, fs=fs, speed_rpm=both[0], orders=[2], method="vkf", bandwidth_hz=2.0)
    near = np.abs(alone.rpm.values - 1500.0) < 60
    assert np.abs(alone.amplitude.values[0][near] - 1.0).max() > 0.1
    from crankbench.analysis.vkf import vold_kalman

    res = vold_kalman(x, fs=fs, speed_rpm=both, orders=[2, 1], bandwidth_hz=2.0)
    sel = ((res.time > 0.3) & (res.time < 2.1)).values
    env = np.abs(res.envelope.values[:, sel])
    assert np.abs(env[0] - 1.0).max() < 1e-3
    assert np.abs(env[1] - 0.5).max() < 1e-3


def _zero_db(seed, fs=5000.0, duration=20.0):
    """Order 3 of peak amplitude 1 in white noise of equal power (SNR 0 dB over the band)."""
    t = np.arange(int(duration * fs)) / fs
    rpm = np.full(t.size, 1500.0)
    rng = np.random.default_rng(seed)
    x = np.cos(3 * shaft_angle(rpm, fs) + 0.2) + rng.normal(0.0, np.sqrt(0.5), t.size)
    return x, rpm, fs


def test_cot_at_0db_snr_error_estimate_covers_the_actual_error():
    """62 independent blocks: the rms amplitude error lies within [0.7, 1.4] × the stated
    1-σ ``amplitude_noise`` and ≥ 85 % of the blocks are within 2σ (Gaussian: 95 %); the mean
    amplitude is within 3σ/√n of the truth (no bias at 0 dB)."""
    x, rpm, fs = _zero_db(0)
    res = order_track(x, fs=fs, speed_rpm=rpm, orders=[3], revolutions=8, overlap=0.0)
    err = res.amplitude.values[0] - 1.0
    sigma = res.amplitude_noise.values
    assert err.size >= 60 and np.all(np.isfinite(sigma)) and np.all(sigma > 0)
    ratio = np.sqrt(np.mean(err ** 2)) / np.mean(sigma)
    assert 0.7 <= ratio <= 1.4
    assert np.mean(np.abs(err) <= 2 * sigma) >= 0.85
    assert abs(err.mean()) <= 3 * np.mean(sigma) / np.sqrt(err.size)


def test_vkf_at_0db_snr_error_estimate_covers_the_actual_error():
    """Over five noise realisations, the VKF rms amplitude error (1 Hz bandwidth, 18 s) lies
    within [0.7, 1.4] × the stated ``amplitude_std_estimate``."""
    ratios = []
    for seed in range(5):
        x, rpm, fs = _zero_db(seed)
        res = order_track(x, fs=fs, speed_rpm=rpm, orders=[3], method="vkf", bandwidth_hz=1.0)
        sel = ((res.time > 1) & (res.time < 19)).values
        err = res.amplitude.values[0][sel] - 1.0
        ratios.append(np.sqrt(np.mean(err ** 2)) / res.attrs["amplitude_std_estimate"][0])
    assert 0.7 <= np.sqrt(np.mean(np.square(ratios))) <= 1.4


@pytest.mark.parametrize("method", ["cot", "vkf", "auto"])
def test_a_stop_is_tracked_around_and_named(method):
    """The shaft stands for 0.5 s (0 rpm at samples 12000-13999): every tracker warns naming
    the span in seconds (plain numbers) and tracks the running spans on either side, each
    within 1e-3 of the truth; no result falls inside the stop."""
    from crankbench.analysis.orders import OrderWarning

    fs = 4000.0
    t = np.arange(int(8 * fs)) / fs
    rpm = np.full(t.size, 1500.0)
    rpm[12000:14000] = 0.0
    x = np.cos(2 * np.cumsum(rpm) / 60 * TWO_PI / fs)
    kw = {"revolutions": 8} if method == "cot" else {}
    with pytest.warns(OrderWarning, match=r"the shaft stands .* at 3\.\.3\.49975 s") as rec:
        res = order_track(x, fs=fs, speed_rpm=rpm, orders=[2], method=method, **kw)
    assert "np.float64" not in str(rec[0].message)
    tt = res.time.values
    assert not np.any((tt > 3.0) & (tt < 3.5))
    assert np.any(tt < 3.0) and np.any(tt > 3.5)
    amp = res.amplitude.values[0]
    inner = ((tt > 0.3) & (tt < 2.7)) | ((tt > 3.8) & (tt < 7.7))
    # (the automatic tracker leaves its unsettled ends, within 1/B of each span, NaN)
    assert np.isfinite(amp[inner]).mean() > 0.6
    assert np.nanmax(np.abs(amp[inner] - 1.0)) < 1e-3


@pytest.mark.parametrize("method", ["cot", "vkf"])
def test_crawling_speed_dip_gives_finite_accurate_orders_or_clear_error(method):
    """Speed dips from 1500 to 5 rpm and back: either a clear AnalysisError or amplitudes
    that are finite everywhere and within 1e-3 of the truth (no NaN, no silent garbage)."""
    fs = 4000.0
    t = np.arange(int(8 * fs)) / fs
    rpm = 1500.0 - 1495.0 * np.exp(-((t - 4.0) / 0.5) ** 2)
    x = np.cos(2 * shaft_angle(rpm, fs))
    try:
        kw = {"revolutions": 4} if method == "cot" else {}
        res = order_track(x, fs=fs, speed_rpm=rpm, orders=[2], method=method, **kw)
    except AnalysisError as exc:
        assert "rpm" in str(exc) and method == "cot"
        return
    amp = res.amplitude.values[0]
    assert np.all(np.isfinite(amp))
    assert np.abs(amp - 1.0).max() < 1e-3
