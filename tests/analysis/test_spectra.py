"""FFT spectra, synchronous averaging and integration against closed forms."""

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from crankbench.analysis.resample import shaft_angle
from crankbench.analysis.spectra import differentiate, integrate, spectrum, synchronous_average
from crankbench.predict.errors import AnalysisError


@settings(max_examples=25, deadline=None)
@given(freq=st.floats(50.0, 400.0), amp=st.floats(0.01, 100.0), phase=st.floats(0, 6.28))
def test_flattop_reads_any_sine_amplitude(freq, amp, phase):
    """Flat-top window: a sine anywhere between bins reads its amplitude within the window's
    scalloping band (scipy flattop: −0.113 … +0.027 %, computed from its DTFT)."""
    fs = 1000.0
    t = np.arange(8192) / fs
    s = spectrum(amp * np.cos(2 * np.pi * freq * t + phase), fs=fs, window="flattop",
                 nperseg=2048)
    assert -1.15e-3 < float(s.max()) / amp - 1 < 3e-4


def test_sine_on_bin_exact_any_window_and_conventions():
    fs, n = 1024.0, 4096
    t = np.arange(n) / fs
    x = 1.5 * np.sin(2 * np.pi * 64.0 * t)
    for window in ("boxcar", "hann", "blackmanharris"):
        for conv, f in (("peak", 1.5), ("rms", 1.5 / np.sqrt(2)), ("peak-to-peak", 3.0)):
            s = spectrum(x, fs=fs, window=window, nperseg=1024, amplitude=conv)
            assert float(s.sel(frequency=64.0)) == pytest.approx(f, rel=1e-12)


def test_parseval_power_and_density():
    """Σ power bins = mean square of the windowed frames (per frame, averaged); the density
    integrates to the same."""
    rng = np.random.default_rng(0)
    fs = 2000.0
    x = rng.normal(0, 0.7, 2 ** 14)
    for window in ("boxcar", "hann"):
        p = spectrum(x, fs=fs, window=window, nperseg=2 ** 14, scaling="power", detrend=False)
        from scipy.signal import get_window
        w = get_window(window, 2 ** 14)
        assert float(p.sum()) == pytest.approx(np.sum((x * w) ** 2) / np.sum(w ** 2), rel=1e-10)
        d = spectrum(x, fs=fs, window=window, nperseg=2 ** 14, scaling="density", detrend=False)
        assert float(d.sum()) * fs / 2 ** 14 == pytest.approx(float(p.sum()), rel=1e-10)


def test_white_noise_density_level():
    """Welch average of white noise of variance σ² reads the one-sided density 2σ²/fs."""
    rng = np.random.default_rng(1)
    fs = 1000.0
    x = rng.normal(0, 0.5, 200_000)
    d = spectrum(x, fs=fs, nperseg=1024, scaling="density")
    assert float(d[5:-5].mean()) == pytest.approx(2 * 0.25 / fs, rel=0.02)


def test_integrate_sine_to_velocity_and_displacement_without_drift():
    """a = A cos ωt + offset → v = A sin ωt / ω, d = −A cos ωt / ω² (offset removed)."""
    fs, f0, amp = 2000.0, 25.0, 4.0
    t = np.arange(int(8 * fs)) / fs
    w = 2 * np.pi * f0
    acc = xr.DataArray(amp * np.cos(w * t) + 0.3, dims="time",
                       attrs={"units": "m/s^2", "sample_rate": fs})
    for method, tol in (("fft", 1e-9), ("time", 5e-3)):
        vel = integrate(acc, highpass_hz=3.0, method=method)
        disp = integrate(acc, times=2, highpass_hz=3.0, method=method)
        mid = slice(int(1.5 * fs), int(6.5 * fs))     # time method: filter ends settle
        assert vel.attrs["units"] == "m/s" and disp.attrs["units"] == "m"
        assert np.abs(vel.values[mid] - amp * np.sin(w * t[mid]) / w).max() < tol * amp / w
        assert np.abs(disp.values[mid] + amp * np.cos(w * t[mid]) / w ** 2).max() < \
            2 * tol * amp / w ** 2
        # drift removed: no trend left in the displacement
        slope = np.polyfit(t[mid], disp.values[mid], 1)[0]
        assert abs(slope) < 1e-3 * amp / w ** 2


def test_differentiate_inverts_integrate():
    fs = 1000.0
    t = np.arange(4000) / fs
    x = np.sin(2 * np.pi * 7 * t) + 0.2 * np.cos(2 * np.pi * 31 * t)
    v = differentiate(x, fs=fs)
    exact = 2 * np.pi * 7 * np.cos(2 * np.pi * 7 * t) - 0.2 * 2 * np.pi * 31 * np.sin(2 * np.pi * 31 * t)
    assert np.abs(v.values - exact).max() < 1e-9
    vt = differentiate(x, fs=fs, method="time")
    assert np.abs(vt.values[2:-2] - exact[2:-2]).max() < 0.01 * np.abs(exact).max()


def test_synchronous_average_removes_asynchronous_content():
    """Average of a four-stroke cycle (720°) keeps the half order and removes a tone at a
    non-integer multiple of the cycle frequency (error ~ 1/cycles)."""
    fs = 4000.0
    t = np.arange(int(30 * fs)) / fs
    rpm = 1500 + 20 * np.sin(0.5 * t)
    phi = shaft_angle(rpm, fs)
    x = 0.5 * np.cos(0.5 * phi) + 1.0 * np.cos(2 * np.pi * 37.3 * t)
    avg = synchronous_average(x, fs=fs, speed_rpm=rpm, revolutions_per_cycle=2, samples_per_rev=64)
    assert avg.sizes["angle"] == 128
    err = np.abs(avg.values - 0.5 * np.cos(0.5 * avg.angle.values)).max()
    assert err < 0.05 and avg.attrs["cycles"] > 300


def test_errors():
    with pytest.raises(AnalysisError, match="scaling='psd' is not one of"):
        spectrum(np.zeros(100), fs=10.0, scaling="psd")
    with pytest.raises(AnalysisError, match="nperseg=200 exceeds the 100 samples"):
        spectrum(np.zeros(100), fs=10.0, nperseg=200)
    with pytest.raises(AnalysisError, match=r"highpass_hz=6.0 must be below fs/2 = 5.0"):
        integrate(np.zeros(100), fs=10.0, highpass_hz=6.0)
    with pytest.raises(AnalysisError, match="need at least 2 to average"):
        synchronous_average(np.zeros(3000), fs=1000.0, speed_rpm=60.0, samples_per_rev=16)


@pytest.mark.parametrize("wrapped", [False, True])
def test_differentiate_an_encoder_angle_gives_the_speed(wrapped):
    """An encoder angle channel of a 3000 → 4000 rpm run-up (500 rpm/s) with 1e-3 rad at
    order 1.5: the default FFT derivative is the closed-form speed, its ends included (it gave
    1616/1598/0 rpm where the truth was 3227); a wrapped channel labelled as an angle (rad) is
    unwrapped first."""
    import xarray as xr

    fs = 5000.0
    t = np.arange(int(2 * fs)) / fs
    phi = 2 * np.pi * (50.0 * t + 500.0 / 120.0 * t * t)
    angle = phi + 1e-3 * np.cos(1.5 * phi)
    omega = 2 * np.pi * (50.0 + 500.0 / 60.0 * t) * (1 - 1.5e-3 * np.sin(1.5 * phi))
    values = np.angle(np.exp(1j * angle)) if wrapped else angle
    da = xr.DataArray(values, dims="time", coords={"time": t},
                      attrs={"units": "rad", "quantity": "angle", "sample_rate": fs})
    d = differentiate(da)
    assert d.attrs["units"] == "rad/s"
    inner = slice(200, -200)
    assert np.abs(d.values[inner] - omega[inner]).max() < 1e-6 * omega.mean()
    rpm_ends = d.values[[0, -1]] * 30 / np.pi
    assert rpm_ends == pytest.approx(omega[[0, -1]] * 30 / np.pi, rel=2e-3)
