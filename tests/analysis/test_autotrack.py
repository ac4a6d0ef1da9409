"""Order tracks with no option given (issue 13): analytic signals with known truth.

* a Q-resonance crossed by an order: truth the exact envelope of the swept SDOF response
  (``analysis.bench.suite_orders.sdof_sweep``, ``solve_ivp`` in the rotating frame);
* a noisy run-up of three orders of known amplitude;
* channels that carry their trend (an IAS channel its mean speed, an encoder angle its ramp);
* a constant-speed record (steady-state order table).
"""

import warnings

import numpy as np
import pytest

from crankbench.analysis.bench.suite_orders import _peak, sdof_sweep
from crankbench.analysis.orders import OrderWarning, order_map, order_track
from crankbench.analysis.resample import shaft_angle


@pytest.mark.parametrize("natural_hz, q, order, rate, tol", [
    (100.0, 20.0, 3.0, 400.0, 0.02),          # the acceptance figures
    (100.0, 20.0, 3.0, 1000.0, 0.05),
    (60.0, 20.0, 4.5, 400.0, 0.02),           # other order, frequency, Q
    (80.0, 10.0, 2.0, 1000.0, 0.05),
    (100.0, 40.0, 3.0, 400.0, 0.02),
])
def test_default_keeps_a_resonance_peak(natural_hz, q, order, rate, tol):
    """Measured: peak error ≤ 0.6 % in every case (−26.8 % / −54.5 % with the former defaults
    at 400 / 1000 rpm/s); the stated uncertainty at the true peak covers the error there."""
    case = sdof_sweep(rate, natural_frequency=natural_hz, q_factor=q, order=order)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OrderWarning)
        tr = order_track(case["x"], fs=case["fs"], speed_rpm=case["rpm"], orders=[order])
    true_peak, _ = _peak(case["rpm"], case["envelope"])
    amp = tr["amplitude"].values[0]
    peak, _ = _peak(tr["rpm"].values, amp)
    assert abs(peak / true_peak - 1) <= tol
    k = int(np.argmax(np.interp(tr["time"].values, case["t"], case["envelope"])))
    truth_k = np.interp(tr["time"].values[k], case["t"], case["envelope"])
    assert abs(amp[k] - truth_k) <= tr["amplitude_uncertainty"].values[0][k]
    assert "sweep_rate_rpm_per_s" in tr.attrs["auto_settings"]


def test_too_fast_a_sweep_warns_with_rate_error_and_setting():
    """3000 rpm/s through a Q = 20 resonance at order 3 (no bandwidth keeps ~1 %): the warning
    names the sweep rate, the expected error and the setting; the stated uncertainty at the
    peak includes the smearing bias, not only the noise."""
    case = sdof_sweep(3000.0, natural_frequency=100.0, q_factor=20.0, order=3.0)
    x = case["x"] + np.random.default_rng(1).normal(0.0, 0.5, case["x"].size)
    with pytest.warns(OrderWarning) as record:
        tr = order_track(x, fs=case["fs"], speed_rpm=case["rpm"], orders=[3.0])
    text = " ".join(str(w.message) for w in record)
    assert "3000 rpm/s" in text and "expected peak error" in text and "bandwidth_hz=" in text
    unc = tr["amplitude_uncertainty"].values[0]
    noise_only = float(tr.attrs["amplitude_std_estimate"][0]) if np.ndim(
        tr.attrs.get("amplitude_std_estimate", np.nan)) else np.nan
    k = int(np.nanargmax(tr["amplitude"].values[0]))
    err = abs(tr["amplitude"].values[0][k]
              - np.interp(tr["time"].values[k], case["t"], case["envelope"]))
    assert unc[k] >= err
    if np.isfinite(noise_only):
        assert unc[k] > noise_only


def _runup(fs, noise, seed, duration=20.0):
    t = np.arange(int(duration * fs)) / fs
    rpm = 1000.0 + 2000.0 * t / duration
    phi = shaft_angle(rpm, fs)
    truth = {1.0: 1.0, 2.0: 0.5, 4.5: 0.25}
    x = sum(a * np.cos(o * phi + 0.1 * o) for o, a in truth.items())
    return t, rpm, x + np.random.default_rng(seed).normal(0.0, noise, t.size), truth


@pytest.mark.parametrize("seed", [5, 9])
def test_noisy_runup_defaults_worst_order_within_half_percent(seed):
    """1000 → 3000 rpm in 20 s, the issue's noise density (0.1 rms at 20 kHz = 0.05 rms at
    5 kHz): worst order 0.15 % (seed 5) and 0.27 % (seed 9) rms measured with the defaults
    (target ≤ 0.5 %; the former defaults 0.65–0.8 %). Ends where the filter has not settled are NaN, not wrong."""
    fs = 5000.0
    t, rpm, x, truth = _runup(fs, 0.05, seed)
    tr = order_track(x, fs=fs, speed_rpm=rpm, orders=list(truth))
    sel = ((tr["time"] > 3.0) & (tr["time"] < 17.0)).values
    worst = max(float(np.sqrt(np.mean((tr["amplitude"].sel(order=o).values[sel] / a - 1) ** 2)))
                for o, a in truth.items())
    assert worst <= 0.005
    inside = tr["amplitude"].values[:, sel]
    assert np.isfinite(inside).all()


def test_ias_channel_with_its_mean_leaks_nothing_into_low_orders():
    """An IAS channel (rad/s) of a 1500 → 1800 rpm run: mean speed 157…188 rad/s under 2 rad/s
    at order 0.5 and 1 rad/s at order 1 (truth by construction). VKF was 2 % / 1.4 % off; COT
    with 2-revolution blocks read half the mean speed as order 0.5."""
    fs = 2000.0
    t = np.arange(int(10 * fs)) / fs
    rpm = 1500.0 + 30.0 * t
    phi = shaft_angle(rpm, fs)
    truth = {0.5: 2.0, 1.0: 1.0}
    omega = rpm * np.pi / 30.0 + sum(a * np.cos(o * phi + 0.3) for o, a in truth.items())
    sel = slice(None)
    for kwargs in ({}, {"method": "vkf", "bandwidth_orders": 0.1},
                   {"method": "cot", "revolutions": 2}):
        tr = order_track(omega, fs=fs, speed_rpm=rpm, orders=list(truth), **kwargs)
        tt = tr["time"].values
        sel = (tt > 1.5) & (tt < 8.5)
        for o, a in truth.items():
            got = tr["amplitude"].sel(order=o).values[sel]
            assert np.nanmax(np.abs(got / a - 1)) < 0.01, (kwargs, o)
    m = order_map(omega, fs=fs, speed_rpm=rpm, revolutions=8)
    inner = ((m["time"] > 1.5) & (m["time"] < 8.5)).values
    assert np.abs(m.sel(order=0.5).values[inner] / 2.0 - 1).max() < 0.02


def test_encoder_angle_with_its_ramp_keeps_the_angular_vibration():
    """An encoder angle channel (the shaft's rotation, 2π per revolution, plus 2e-3 rad at
    order 1.5 and 1e-3 rad at order 1/3): the ramp is the shaft angle, not an order (it read
    1070° at order 1/3)."""
    fs = 2000.0
    t = np.arange(int(12 * fs)) / fs
    rpm = 1200.0 + 20.0 * t
    phi = shaft_angle(rpm, fs)
    truth = {1 / 3: 1e-3, 1.5: 2e-3}
    angle = phi + 0.7 + sum(a * np.cos(o * phi) for o, a in truth.items())
    for kwargs in ({}, {"method": "cot", "revolutions": 6}):
        tr = order_track(angle, fs=fs, speed_rpm=rpm, orders=list(truth), **kwargs)
        tt = tr["time"].values
        sel = (tt > 2.0) & (tt < 10.0)
        for o, a in truth.items():
            got = tr["amplitude"].sel(order=o).values[sel]
            assert np.nanmax(np.abs(got / a - 1)) < 0.02, (kwargs, o)


def test_steady_record_gives_the_order_table():
    """Constant 900 rpm for 20 s, orders 1.5 / 3 / 4.5 of known amplitude and phase under
    noise: the steady-state table holds each within its stated uncertainty (3 σ) and the
    uncertainty is about the noise figure (σ of a least-squares sine: noise·√(2/N))."""
    from crankbench.analysis.steady import steady_orders

    fs = 2000.0
    n = int(20 * fs)
    t = np.arange(n) / fs
    phi = 2 * np.pi * 15.0 * t
    truth = {1.5: (0.4, 30.0), 3.0: (1.0, -60.0), 4.5: (0.2, 120.0)}
    x = sum(a * np.cos(o * phi + np.radians(p)) for o, (a, p) in truth.items())
    x = x + 0.3 + np.random.default_rng(2).normal(0.0, 0.2, n)
    table = steady_orders(x, fs=fs, speed_rpm=np.full(n, 900.0), orders=list(truth))
    assert len(table) == 3
    sigma = 0.2 * np.sqrt(2.0 / n)
    for _, row in table.iterrows():
        a, p = truth[float(row["order"])]
        assert abs(row["amplitude"] - a) <= 3 * row["amplitude_uncertainty"]
        assert row["amplitude_uncertainty"] == pytest.approx(sigma, rel=0.5)
        dp = (row["phase_deg"] - p + 180.0) % 360.0 - 180.0
        assert abs(dp) <= 3 * row["phase_uncertainty_deg"] + 1e-9


@pytest.mark.parametrize("seed", [7, 8])
def test_slow_noisy_runup_without_resonance_keeps_the_narrow_band(seed):
    """10 rpm/s over 60 s, two steady orders under 0.5 rms noise, no resonance: nothing is
    sharp, so the defaults keep the narrow band everywhere (a noise bump once widened order
    1.5 to 15 Hz at 1300 rpm, 6 % off, with a stated uncertainty of 100 %), and the
    amplitudes are within their stated σ: none beyond 4 σ, at least 90 % within 3 σ. (The
    errors are correlated over 1/B = 7.5 s, so the 45 s judged hold about six independent
    ones: over 20 seeds, 3 of 40 tracks had 94-98 % within 3 σ with the solve at 286 Hz and
    as many at 182 Hz, rms error / rms σ 0.94 both; the largest |error|/σ was 3.5.)"""
    fs = 4000.0
    t = np.arange(int(60 * fs)) / fs
    rpm = 800 + 10 * t
    phi = shaft_angle(rpm, fs)
    x = (2 * np.cos(1.5 * phi) + np.cos(3 * phi)
         + 0.5 * np.random.default_rng(seed).standard_normal(t.size))
    ds = order_track(x, fs=fs, speed_rpm=rpm, orders=[1.5, 3.0])
    floor = max(8 / 60.0, 0.005 * 800 / 60)
    assert float(ds["bandwidth_hz"].max()) < 1.5 * floor, ds.attrs["auto_settings"]
    for order, true in ((1.5, 2.0), (3.0, 1.0)):
        a = ds["amplitude"].sel(order=order).values
        u = ds["amplitude_uncertainty"].sel(order=order).values
        ok = np.isfinite(a)
        assert ok.mean() > 0.7                 # 1/B = 7.5 s unsettled at each end
        # a Gaussian error passes 3 σ 0.3 % of the time and 4 σ 0.006 % (the stated σ, not the
        # truth): a σ stated 1.5x low would show errors near 5 σ
        assert np.mean(np.abs(a[ok] - true) <= 3 * u[ok]) > 0.9
        assert np.max(np.abs(a[ok] - true) / u[ok]) < 4.0
        assert np.abs(a[ok] / true - 1).max() < 0.015


@pytest.mark.parametrize("rate", [100.0, 400.0])
def test_an_order_the_record_lacks_is_neither_widened_nor_warned_of(rate):
    """Clean run-up with orders 2 and 4.5 only, the defaults asked for orders 2, 4.5 and 6.
    Order 6 reads round-off of the others (~1e-9 of the level); its ripples had been taken
    for sharp peaks: the band widened to 75 Hz and a warning of an expected error of 56-69 %.
    Now judged against the solve's floor (1e-6 of the channel's level): the narrow band is
    kept, no warning, and all three orders are exact (truth: the synthesised amplitudes)."""
    from crankbench.analysis.orders import OrderWarning

    fs = 5000.0
    t = np.arange(int(10 * fs)) / fs
    rpm = 1000.0 + rate * t
    phi = shaft_angle(rpm, fs)
    x = np.cos(2 * phi) + 0.3 * np.cos(4.5 * phi + 0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", OrderWarning)
        tr = order_track(x, fs=fs, speed_rpm=rpm, orders=[2, 4.5, 6])
    amp = tr["amplitude"].values
    assert np.nanmax(np.abs(amp[0] - 1.0)) < 1e-6 and np.nanmax(np.abs(amp[1] - 0.3)) < 1e-6
    assert np.nanmax(amp[2]) < 1e-6
    assert tr.attrs["auto_bandwidth_hz_range"][1] < 2.0        # no widening anywhere
    assert max(tr.attrs["auto_expected_error"]) < 0.01


def _every_half_order(duration, rpm0, rpm1):
    """An engine-like signal: every half order 0.5-10 (amplitudes 0.2-1, random phases) and
    0.05 rms noise, 5 kHz, speed ramping linearly: ``(x, fs, rpm, grid, amplitudes)``."""
    rng = np.random.default_rng(3)
    fs = 5000.0
    t = np.arange(int(duration * fs)) / fs
    rpm = rpm0 + (rpm1 - rpm0) * t / duration
    phi = shaft_angle(rpm, fs)
    grid = np.arange(0.5, 10.01, 0.5)
    amps = rng.uniform(0.2, 1.0, grid.size)
    x = sum(a * np.cos(o * phi + p) for o, a, p in zip(grid, amps,
                                                       rng.uniform(0, 2 * np.pi, grid.size)))
    return x + rng.normal(0.0, 0.05, t.size), fs, rpm, grid, amps


@pytest.mark.parametrize("duration, rpm0, rpm1", [(2.0, 1500.0, 1500.0), (2.0, 1400.0, 1600.0),
                                                  (4.0, 1200.0, 1800.0)])
def test_the_half_orders_not_asked_for_are_solved_with_the_tracked_ones(duration, rpm0, rpm1):
    """An engine signal with every half order 0.5-10 (amplitudes 0.2-1, noise 0.05 rms), the
    defaults asked for orders 1, 2 and 4.5 only. The half orders beside them passed the filter:
    order 1 read 27 % off on the steady 2 s record (order 2 12 % on the 2 s ramp), with a
    warning that blamed the envelope's changes on a steady record. The lines found in the
    residual's order spectrum within 1.5 orders are now solved jointly (not reported): each
    tracked order within 3 % of its synthesised amplitude, 97 % within 3 stated σ, no warning."""
    x, fs, rpm, grid, amps = _every_half_order(duration, rpm0, rpm1)
    with warnings.catch_warnings():
        warnings.simplefilter("error", OrderWarning)
        ds = order_track(x, fs=fs, speed_rpm=rpm, orders=[1.0, 2.0, 4.5])
    assert list(ds["order"].values) == [1.0, 2.0, 4.5]
    assert {0.5, 1.5, 2.5, 4.0, 5.0} <= set(ds.attrs["auto_joint_lines"])
    for j, order in enumerate((1.0, 2.0, 4.5)):
        true = amps[np.argmin(np.abs(grid - order))]
        a = ds["amplitude"].values[j]
        u = ds["amplitude_uncertainty"].values[j]
        ok = np.isfinite(a)
        assert ok.mean() > 0.3
        assert np.abs(a[ok] / true - 1.0).max() < 0.03
        assert np.mean(np.abs(a[ok] - true) <= 3 * u[ok]) > 0.97


@pytest.mark.parametrize("steady", [False, True])
def test_results_reach_near_the_record_ends_within_their_stated_uncertainty(steady):
    """Only half a response time at each end is left NaN (``UNSETTLED``): a 10 s record at
    the 8/duration floor bandwidth (1/B = 1.25 s) keeps more than 85 % of its samples (75 %
    when the whole 1/B was blanked), and where it keeps them within 1/B of an end, the error
    against the synthesised amplitudes (6 noise seeds, two orders) is covered by the stated
    uncertainty as in the interior: rms error / rms σ <= 1.25 (measured 0.95-1.1; 1.8-1.9
    within 0.1/B of an end, which is why the ends stay NaN), none beyond 4.5 σ."""
    fs, dur = 4096.0, 10.0
    t = np.arange(int(dur * fs)) / fs
    rpm = np.full_like(t, 1500.0) if steady else 1000.0 + 200.0 * t
    phi = shaft_angle(rpm, fs)
    truth = {2.0: 1.0, 4.5: 0.5}
    err, sig, kept = [], [], []
    for seed in range(6):
        x = 0.3 * np.random.default_rng(seed).standard_normal(t.size)
        for k, (order, a) in enumerate(truth.items()):
            x += a * np.cos(order * phi + 0.3 * k + seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OrderWarning)
            ds = order_track(x, fs=fs, speed_rpm=rpm, orders=list(truth))
        tt = ds["time"].values
        dist = np.minimum(tt - tt[0], tt[-1] - tt)
        assert "0.5/B" in ds.attrs["unsettled_ends"]
        for order, a in truth.items():
            amp = ds["amplitude"].sel(order=order).values
            u = ds["amplitude_uncertainty"].sel(order=order).values
            b = ds["bandwidth_hz"].sel(order=order).values
            kept.append(np.isfinite(amp).mean())
            assert not np.isfinite(amp[dist < 0.45 / b]).any()
            zone = np.isfinite(amp) & (dist < 1.0 / b)
            assert zone.sum() > 0.05 * tt.size
            err += list(amp[zone] - a)
            sig += list(u[zone])
    err, sig = np.asarray(err), np.asarray(sig)
    assert min(kept) > 0.85
    assert np.sqrt(np.mean(err ** 2)) / np.sqrt(np.mean(sig ** 2)) <= 1.25
    assert np.max(np.abs(err) / sig) < 4.5


@pytest.mark.parametrize("duration, rpm0, rpm1, method", [
    (0.7, 1500.0, 1500.0, "computed order tracking"),   # 17.5 revolutions
    (0.8, 1400.0, 1600.0, "computed order tracking"),   # 20
    (1.0, 1500.0, 1500.0, "Vold-Kalman"),               # 25: line search on 4 blocks
])
def test_short_records_with_every_half_order_read_right_by_default(duration, rpm0, rpm1,
                                                                   method):
    """Every half order 0.5-10 in the signal, orders 1, 2 and 4.5 asked for, records of 17.5
    to 25 revolutions. The adaptive filter's narrowest band (8/duration: 0.3-0.46 order) passed
    the half orders beside them, and the line search that solves them jointly needed five
    blocks of 8 revolutions: order 1 read 30 % off at 17.5 revolutions, 11 % at 20, 9 % at 25.
    The line search now also runs on records of 2-4 blocks; where it finds lines in fewer than
    24 revolutions, computed order tracking takes over (4-revolution blocks: the half orders
    on the main lobe's edge). Each order within 3 % of its synthesised amplitude (measured
    0.6-2.8 %). (A short single-order resonance crossing keeps the filter:
    ``test_default_keeps_a_resonance_peak``, 19 revolutions at 400 rpm/s.)"""
    x, fs, rpm, grid, amps = _every_half_order(duration, rpm0, rpm1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OrderWarning)
        ds = order_track(x, fs=fs, speed_rpm=rpm, orders=[1.0, 2.0, 4.5])
    assert method in (ds.attrs.get("auto_settings", "") + ds.attrs.get("method", ""))
    for j, order in enumerate((1.0, 2.0, 4.5)):
        true = amps[np.argmin(np.abs(grid - order))]
        a = ds["amplitude"].values[j]
        ok = np.isfinite(a)
        assert ok.mean() > 0.8
        assert np.abs(a[ok] / true - 1.0).max() < 0.03, order
