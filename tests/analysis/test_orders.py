"""Order analysis against signals whose orders are known exactly (closed-form truth)."""

import numpy as np
import pytest
import xarray as xr

from crankbench.analysis.orders import band_amplitude, campbell_map, order_map, order_spectrum, order_track
from crankbench.analysis.resample import angle_resample, shaft_angle
from crankbench.predict.errors import AnalysisError


def _runup(fs, duration, rpm0, rpm1):
    t = np.arange(int(round(duration * fs))) / fs
    rpm = rpm0 + (rpm1 - rpm0) * t / duration
    return t, rpm, shaft_angle(rpm, fs)


def test_steady_order_amplitude_within_0p1_percent():
    """A steady order's peak amplitude and phase are recovered (truth: the synthesis)."""
    fs = 10_000.0
    t, rpm, phi = _runup(fs, 4.0, 1800.0, 1800.0)
    x = 0.8 * np.cos(3 * phi + 0.7) + 0.3 * np.cos(1.5 * phi - 1.0)
    res = order_track(x, fs=fs, speed_rpm=rpm, orders=[1.5, 3], revolutions=8)
    amp = res.amplitude.values
    assert np.abs(amp[0] / 0.3 - 1).max() < 1e-3
    assert np.abs(amp[1] / 0.8 - 1).max() < 1e-3
    assert np.abs(res.phase.sel(order=3) - 0.7).max() < 1e-3
    assert res.amplitude.attrs["units"] == ""
    assert set(res.amplitude.dims) == {"order", "time"} and "rpm" in res.coords


@pytest.mark.parametrize("amplitude, factor", [("peak", 1.0), ("rms", 2 ** -0.5),
                                               ("peak-to-peak", 2.0)])
def test_amplitude_conventions(amplitude, factor):
    fs = 5000.0
    t, rpm, phi = _runup(fs, 3.0, 1200.0, 1200.0)
    res = order_track(np.cos(2 * phi), fs=fs, speed_rpm=rpm, orders=[2], amplitude=amplitude,
                      revolutions=8)
    assert np.allclose(res.amplitude, factor, rtol=1e-4)
    assert res.attrs["amplitude_convention"] == amplitude


def test_parseval_power_scaling():
    """Σ of the power spectrum over orders > 0 equals the windowed mean square of the block with
    its window-weighted trend (constant and slope) removed (Parseval), and order 0 holds the squared
    block mean; any window. The block is rebuilt here from angle_resample independently (with
    the map's max_order: the samples clean up to order 32, as the map resamples them)."""
    fs = 4096.0
    rng = np.random.default_rng(4)
    x = rng.normal(size=16384) + 0.7
    from scipy.signal import get_window
    for window in ("boxcar", "hann", "flattop"):
        p = order_map(x, fs=fs, speed_rpm=1200.0, revolutions=8, window=window, scaling="power",
                      max_order=32, samples_per_rev=64)
        y = angle_resample(x, fs=fs, speed_rpm=1200.0, samples_per_rev=64, max_order=32)
        w = get_window(window, 512)
        s = np.linspace(-1, 1, 512)
        basis = np.stack([np.ones(512), s], axis=1)
        wp = np.clip(w, 0, None)                     # weights: the window, negative lobes cut
        coef = np.linalg.solve(basis.T @ (basis * wp[:, None]), basis.T @ (wp * y.values[:512]))
        seg = (y.values[:512] - basis @ coef) * w
        first = p.isel(time=0)
        # Parseval over all bins of the detrended block; its own bin 0 (zero for a window
        # without negative lobes) is replaced by the mean
        own_dc = np.sum(seg) ** 2 / (512 * np.sum(w ** 2))
        assert float(first.isel(order=slice(1, None)).sum()) == pytest.approx(
            np.sum(seg ** 2) / np.sum(w ** 2) - own_dc, rel=1e-10)
        assert float(first.isel(order=0)) == pytest.approx(coef[0] ** 2, rel=1e-10)


def test_order_exactly_between_bins_band_energy():
    """An order half-way between two bins: a single bin loses ~15 %, the band sum nothing."""
    fs = 8000.0
    t, rpm, phi = _runup(fs, 6.0, 1500.0, 1500.0)
    revolutions = 16
    order = 2.0 + 0.5 / revolutions          # exactly between bins 32 and 33
    x = 1.0 * np.cos(order * phi)
    p = order_spectrum(x, fs=fs, speed_rpm=rpm, revolutions=revolutions, scaling="power")
    a = order_spectrum(x, fs=fs, speed_rpm=rpm, revolutions=revolutions)
    single = float(a.sel(order=order, method="nearest"))
    assert 0.80 < single < 0.90               # Hann scalloping loss (-1.42 dB = 0.849)
    band = band_amplitude(p, [order], half_width=4 / revolutions)
    assert float(band[0]) == pytest.approx(1.0, rel=1e-3)
    # the direct DFT at the order (COT track) is also exact between bins
    res = order_track(x, fs=fs, speed_rpm=rpm, orders=[order], revolutions=revolutions)
    assert np.abs(res.amplitude.values / 1.0 - 1).max() < 1e-3


def test_runup_orders_within_half_percent_rms():
    """Run-up 1000→3000 rpm in 20 s at 20 kHz, orders 1, 2, 4.5 (peak 1, 0.5, 0.25) + 0.1 rms
    white noise: every order within 0.5 % rms over 10–90 % of the run-up (COT)."""
    fs = 20_000.0
    t, rpm, phi = _runup(fs, 20.0, 1000.0, 3000.0)
    truth = {1.0: 1.0, 2.0: 0.5, 4.5: 0.25}
    rng = np.random.default_rng(20)
    x = sum(a * np.cos(o * phi + 0.3 * o) for o, a in truth.items()) + rng.normal(0, 0.1, t.size)
    res = order_track(x, fs=fs, speed_rpm=rpm, orders=list(truth), revolutions=64, window="boxcar",
                      overlap=0.5)
    sel = (res.time > 2.0) & (res.time < 18.0)
    for o, a in truth.items():
        err = res.amplitude.sel(order=o).values[sel.values] / a - 1
        assert np.sqrt(np.mean(err ** 2)) < 5e-3, o
    # the reported noise error matches the observed scatter (order 4.5) within a factor 1.5
    scatter = np.sqrt(np.mean((res.amplitude.sel(order=4.5).values[sel.values] - 0.25) ** 2))
    assert 1 / 1.5 < float(res.amplitude_noise[sel].mean()) / scatter < 1.5


def test_order_map_rpm_bins_and_campbell():
    fs = 4000.0
    t, rpm, phi = _runup(fs, 8.0, 900.0, 2100.0)
    x = 0.4 * np.cos(2 * phi)
    m = order_map(x, fs=fs, speed_rpm=rpm, revolutions=8, speed_bins_rpm=6)
    assert m.dims == ("rpm", "order")
    assert np.allclose(m.sel(order=2), 0.4, rtol=1e-3)
    c = campbell_map(x, fs=fs, speed_rpm=rpm, nperseg=512, max_frequency=200)
    assert c.dims == ("time", "frequency") and c.attrs["order_lines"]
    # the order-2 ridge follows 2·rpm/60 Hz within one bin
    ridge = c["frequency"].values[c.argmax("frequency").values]
    assert np.abs(ridge - 2 * c["rpm"].values / 60).max() <= c.attrs["resolution_hz"]


@pytest.mark.parametrize("scaling, want", [("amplitude", 0.7), ("power", 0.7 ** 2 / 2 / 1.5)])
def test_the_top_bin_of_a_map_reads_its_order_in_full(scaling, want):
    """The map keeps bins up to max_order (default samples_per_rev/4 = 16), far below the block
    transform's Nyquist bin: its last column is an ordinary bin. A tone at order 16 reads its
    amplitude 0.7 (power: its mean square 0.245 over the Hann window's 1.5-bin noise
    bandwidth on its bin), as one at order 15 does -- not half of it (a bin halved as if it
    were the Nyquist bin). Likewise a Campbell map cut at max_frequency."""
    fs = 20_000.0
    t, rpm, phi = _runup(fs, 5.0, 1500.0, 1500.0)
    for o in (15.0, 16.0):
        m = order_map(0.7 * np.cos(o * phi), fs=fs, speed_rpm=rpm, scaling=scaling)
        assert float(m["order"][-1]) == 16.0
        assert float(m.sel(order=o).mean()) == pytest.approx(want, rel=1e-4)
    f = 1500.0 / 60.0 * 8                                  # 200 Hz, on a bin of nperseg=1000
    c = campbell_map(0.7 * np.cos(8 * phi), fs=fs, speed_rpm=rpm, nperseg=1000,
                     max_frequency=f)
    assert float(c["frequency"][-1]) == f
    assert float(c.sel(frequency=f).mean()) == pytest.approx(0.7, rel=1e-4)


def test_map_block_time_is_its_window_centroid():
    """An order whose amplitude is a ramp (1 + 0.5 t) at a steady 900 rpm: each block of the
    map reads the envelope at the block's stated time (closed form), within 1e-5. The time
    is the Hann window's centroid, half an angle sample after the block's middle; stamped at
    the middle, the map read 1.7e-4 high (0.52 ms late at 15 rev/s)."""
    fs = 10_000.0
    t, rpm, phi = _runup(fs, 20.0, 900.0, 900.0)
    m = order_map((1 + 0.5 * t) * np.cos(3 * phi), fs=fs, speed_rpm=rpm, revolutions=8)
    tt = m["time"].values
    inner = (tt > 1) & (tt < 19)
    assert np.abs(m.sel(order=3).values[inner] / (1 + 0.5 * tt[inner]) - 1).max() <= 1e-5


@pytest.mark.parametrize("method", ["auto", "cot", "map"])
def test_a_channel_too_large_to_square_is_refused_by_name(method):
    """Finite samples whose sum of squares overflows (1e200: a unit or calibration slip)
    gave NaN tracks; now a clear error naming the channel and its magnitude. 1e150 (the
    documented limit for records up to 10⁸ samples) is still analysed, exactly."""
    fs = 5000.0
    t, rpm, phi = _runup(fs, 10.0, 1200.0, 1200.0)
    for scale, ok in ((1e150, True), (1e200, False)):
        x = xr.DataArray(scale * np.cos(2 * phi), dims="time", name="acc_z",
                         attrs={"sample_rate": fs, "units": "m/s^2"})
        call = ((lambda: order_map(x, speed_rpm=rpm).sel(order=2).values) if method == "map"
                else (lambda: order_track(x, speed_rpm=rpm, orders=[2],
                                          method=method).amplitude.values))
        if ok:
            assert np.nanmax(np.abs(call() / scale - 1)) < 1e-4
        else:
            with pytest.raises(AnalysisError, match=r"acc_z reaches 1e\+200 .*too large to analyse"):
                call()


def test_record_channel_input_takes_fs_and_units():
    fs = 5000.0
    t, rpm, phi = _runup(fs, 3.0, 1500.0, 1500.0)
    ch = xr.DataArray(0.02 * np.cos(phi), dims="time", name="torsio",
                      attrs={"units": "rad", "sample_rate": fs, "quantity": "angle"})
    res = order_track(ch, speed_rpm=rpm, orders=[1], revolutions=8)
    assert res.amplitude.attrs["units"] == "rad"
    assert np.allclose(res.amplitude, 0.02, rtol=1e-4)


def test_errors_name_the_argument():
    with pytest.raises(AnalysisError, match="fs is required"):
        order_track(np.zeros(1000), speed_rpm=1000.0, orders=[1])
    with pytest.raises(AnalysisError, match=r"rpm has 10 samples but the signal has 1000"):
        order_track(np.zeros(1000), fs=1000.0, speed_rpm=np.ones(10), orders=[1])
    with pytest.raises(AnalysisError, match="method='kvf' is not one of .*did you mean 'vkf'"):
        order_track(np.zeros(1000), fs=1000.0, speed_rpm=600.0, orders=[1], method="kvf")
    with pytest.raises(AnalysisError, match="rpm must be > 0"):
        order_track(np.zeros(1000), fs=1000.0, speed_rpm=np.r_[np.ones(999), -1.0], orders=[1])
    with pytest.raises(AnalysisError, match="fewer than one block"):
        order_track(np.zeros(2000), fs=1000.0, speed_rpm=600.0, orders=[1], revolutions=64)
    with pytest.raises(AnalysisError, match=r"order 20 exceeds samples_per_rev/4 = 16 .*"
                                            r"use samples_per_rev >= 80"):
        order_track(np.zeros(20000), fs=1000.0, speed_rpm=600.0, orders=[1, 20],
                    samples_per_rev=64)
    with pytest.raises(AnalysisError, match=r"order 12 reaches 600 Hz at 3000 rpm, above the "
                                            r"Nyquist frequency 500 Hz"):
        order_track(np.zeros(20000), fs=1000.0, speed_rpm=3000.0, orders=[12])
    with pytest.raises(AnalysisError, match="window='hanning2' is not a scipy window"):
        order_map(np.zeros(20000), fs=1000.0, speed_rpm=600.0, window="hanning2", revolutions=2)


def test_chunked_resampling_equals_one_pass():
    """Bounded-memory chunks (with the filter's overlap) give the same samples as one pass for
    content in the pass band (orders <= samples_per_rev/4; the per-chunk anti-alias filters
    differ only in their transition bands)."""
    fs = 8000.0
    t, rpm, phi = _runup(fs, 10.0, 900.0, 2400.0)
    x = np.cos(2 * phi) + 0.3 * np.sin(12 * phi)
    one = angle_resample(x, fs=fs, speed_rpm=rpm, chunk=1 << 22)
    many = angle_resample(x, fs=fs, speed_rpm=rpm, chunk=4096)
    common = np.intersect1d(one.angle.values, many.angle.values)
    a = one.sel(angle=common).values
    b = many.sel(angle=common).values
    assert common.size > 0.99 * one.size
    assert np.abs(a - b).max() < 5e-5                 # two pass-band ripples of ~1e-5


def test_channel_time_offset_is_kept():
    fs = 4000.0
    t, rpm, phi = _runup(fs, 4.0, 1500.0, 1500.0)
    ch = xr.DataArray(np.cos(phi), dims="time", coords={"time": t + 100.0},
                      attrs={"units": "m", "sample_rate": fs})
    res = order_track(ch, speed_rpm=rpm, orders=[1], revolutions=8)
    assert 100.0 < float(res.time[0]) < 101.0


@pytest.mark.parametrize("kwargs", [dict(method="cot", revolutions=8),
                                    dict(method="vkf", bandwidth_hz=4.0)])
def test_sample_record_against_its_synthesis_truth(sample_data, kwargs):
    """The synthetic i4 run-up (written by the measure package with its ground truth): order 2
    and 4 amplitudes (noise 0.05 rms) within 1 % and 3 % rms, phases within 0.01 rad."""
    path = sample_data / "records" / "i4_runup.h5"
    if not path.exists():
        pytest.skip("sample record not generated")
    from crankbench import measure
    from crankbench.measure.io import read_truth

    from crankbench.analysis.speedref import speed_reference

    rec = measure.read(path)
    truth = read_truth(path)
    rpm = speed_reference(rec, "acc_block_z")
    res = order_track(rec["acc_block_z"], speed_rpm=rpm, orders=[2, 4], **kwargs)
    sel = (res.rpm.values > 1600) & (res.rpm.values < 2900)
    for o, tol in ((2, 0.01), (4, 0.03)):
        ref = np.interp(res.rpm.values, truth.rpm.values, truth.amplitude.sel(order=o).values)
        err = res.amplitude.sel(order=o).values[sel] / ref[sel] - 1
        assert np.sqrt(np.mean(err ** 2)) < tol
        ph = np.interp(res.rpm.values, truth.rpm.values, truth.phase.sel(order=o).values)
        dph = np.angle(np.exp(1j * (res.phase.sel(order=o).values[sel] - ph[sel])))
        assert abs(np.median(dph)) < 0.01
