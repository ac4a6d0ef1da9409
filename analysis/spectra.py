"""FFT spectra, time-synchronous averaging, and integration/differentiation of records.

``spectrum`` — averaged short-time FFT with any scipy window by name and three scalings:
``'amplitude'`` (coherent amplitude per bin, in the chosen convention: a sine on a bin reads its
amplitude; with scipy's ``flattop`` any sine reads within −0.11 … +0.03 %), ``'power'`` (mean square per
bin: sums over bins are exact by Parseval) and ``'density'`` (units²/Hz). Frames are averaged by
power (``'mean'``, Welch), ``'median'`` (robust against transients; random noise then reads
ln 2 of its mean power, −1.6 dB, tones are unbiased) or ``'max'`` (peak hold).

``synchronous_average`` — the record resampled at constant shaft angle and averaged cycle by
cycle (a cycle is one revolution, or two for a four-stroke engine): what is not locked to the
shaft averages out as ``1/sqrt(cycles)``.

``integrate`` / ``differentiate`` — between acceleration, velocity and displacement (or angular
speed and angle). ``method='fft'`` multiplies by ``(i ω)^∓n`` (exact for components periodic in
the record; a record not holding whole periods leaks at its ends — the default cosine taper of
``taper`` seconds confines that to the first/last ``taper``); drift (the offset and the
low-frequency noise that integration amplifies) is removed by a high-pass at ``highpass_hz``.
``method='time'`` integrates by the trapezoidal rule and removes drift with a zero-phase
Butterworth high-pass after each integration; its gain error is ``(ωΔt)²/12`` (trapezoid) plus
the high-pass attenuation ``(f_c/f)^8`` above ``f_c``.

References
----------
G. Heinzel, A. Rüdiger, R. Schilling, "Spectrum and spectral density estimation by the DFT"
(2002) — scalings, ENBW, flat-top windows.
S. Braun, "The extraction of periodic waveforms by time domain averaging", Acustica 32 (1975).
梁守槃《发动机动力学》(1948) 第九章 “振动之测量”; 交通大学《内燃机动力学》(1958) 第二篇第五章
(the vibrograph records velocity/displacement; converting between them).
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict._validate import check_int, check_option, check_positive, check_range
from crankbench.predict.errors import AnalysisError
from crankbench.predict._deprecate import renamed

from .orders import _frame_batches, _frames, _scale_spectrum, amplitude_factor, get_window
from .resample import _as_signal, angle_resample

__all__ = ["spectrum", "synchronous_average", "integrate", "differentiate"]

log = logging.getLogger("crankbench")

_INTEGRAL_UNITS = {"m/s^2": "m/s", "m/s": "m", "rad/s^2": "rad/s", "rad/s": "rad",
                   "m/s²": "m/s", "rad/s²": "rad/s"}
_DERIVATIVE_UNITS = {v: k for k, v in _INTEGRAL_UNITS.items() if "^" in k}


def _wrap(values, like, fs, units, label, attrs):
    import xarray as xr

    t = np.arange(values.shape[0]) / fs
    return xr.DataArray(values, dims=("time",), coords={"time": ("time", t, {"units": "s"})},
                        name=label, attrs={"units": units, "sample_rate": fs, **attrs})


def spectrum(x, *, fs=None, window="hann", nperseg=None, overlap: float = 0.5,
             scaling: str = "amplitude", amplitude: str = "peak", average: str = "mean",
             detrend: bool = True):
    """Averaged FFT spectrum of a signal.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal; a Record channel supplies ``fs`` and ``units``.
    fs : float, optional
        Sample rate, Hz.
    window : str or tuple
        scipy window by name (``'hann'``, ``'flattop'``, ``'boxcar'``, ``('kaiser', 9)``...).
    nperseg : int, optional
        Samples per frame (resolution ``fs/nperseg`` Hz); default the whole record.
    overlap : float
        Fractional frame overlap.
    scaling : {'amplitude', 'power', 'density'}
        Coherent amplitude per bin, mean square per bin (units²), or density (units²/Hz).
    amplitude : {'peak', 'rms', 'peak-to-peak'}
        Convention for ``scaling='amplitude'``.
    average : {'mean', 'median', 'max'}
        How frames are combined (on power; 'max' is peak hold).
    detrend : bool
        Remove each frame's mean first.

    Returns
    -------
    xarray.DataArray
        Over ``frequency`` (Hz), with units and the parameters used in attrs
        (``resolution_hz``, ``enbw_hz``, ``frames``).

    References
    ----------
    Heinzel et al. (2002), §9–10.

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(4000) / fs
    >>> x = 2.0 * np.sin(2 * np.pi * 123.4 * t)          # not on a bin
    >>> s = spectrum(x, fs=fs, window="flattop", nperseg=1000)
    >>> round(float(s.max()), 3)
    2.0
    """
    values, fs, units, label = _as_signal(x, fs)
    scaling = check_option(scaling, "scaling", ("amplitude", "power", "density"),
                           error=AnalysisError)
    average = check_option(average, "average", ("mean", "median", "max"), error=AnalysisError)
    factor = amplitude_factor(amplitude)
    n = values.shape[0]
    nperseg = n if nperseg is None else check_int(nperseg, "nperseg", minimum=8,
                                                  error=AnalysisError)
    if nperseg > n:
        raise AnalysisError(f"nperseg={nperseg} exceeds the {n} samples of {label}")
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    w = get_window(window, nperseg)
    starts = _frames(n, nperseg, overlap)
    from scipy import fft

    power = np.empty((starts.shape[0], nperseg // 2 + 1))
    for sl in _frame_batches(starts):
        frames = values[starts[sl, None] + np.arange(nperseg)[None, :]]
        if detrend:
            frames = frames - frames.mean(axis=1, keepdims=True)
        power[sl] = _scale_spectrum(fft.rfft(frames * w, axis=1), w, "power", 1.0)
    combined = {"mean": np.mean, "median": np.median, "max": np.max}[average](power, axis=0)
    enbw = nperseg * np.sum(w ** 2) / np.sum(w) ** 2
    if scaling == "power":
        out, out_units = combined, (f"({units})^2" if units else "1")
    elif scaling == "density":
        out, out_units = combined / (fs / nperseg), (f"({units})^2/Hz" if units else "1/Hz")
    else:
        # coherent amplitude: power per bin × ENBW → A_rms² for a tone on a bin
        out = np.sqrt(2.0 * combined * enbw) * factor
        out[0] = np.sqrt(combined[0] * enbw)   # the mean itself, whatever the convention
        out_units = units
    import xarray as xr

    freq = np.arange(nperseg // 2 + 1) * fs / nperseg
    return xr.DataArray(out, dims=("frequency",), name=f"{label} spectrum",
                        coords={"frequency": ("frequency", freq, {"units": "Hz"})},
                        attrs={"units": out_units, "method": "averaged FFT", "window": str(window),
                               "scaling": scaling, "amplitude_convention":
                               amplitude if scaling == "amplitude" else scaling,
                               "average": average, "frames": int(starts.shape[0]),
                               "nperseg": nperseg, "overlap": overlap,
                               "resolution_hz": fs / nperseg, "enbw_hz": enbw * fs / nperseg})


@renamed(rpm="speed_rpm")
def synchronous_average(x, *, fs=None, speed_rpm, revolutions_per_cycle: int = 1,
                        samples_per_rev: int = 256, interpolation: str = "cubic"):
    """Time-synchronous average over shaft cycles (angle domain).

    Parameters
    ----------
    x, fs, rpm
        Signal, sample rate (Hz) and shaft speed (rpm per sample).
    revolutions_per_cycle : int
        1 for a two-stroke or per-revolution average, 2 for a four-stroke cycle (720°).
    samples_per_rev : int
        Angle resolution of the average.
    interpolation : {'linear', 'cubic', 'bandlimited'}
        Resampling interpolation.

    Returns
    -------
    xarray.DataArray
        Over ``angle`` (rad, 0 … 2π·revolutions_per_cycle, from the record's first sample) with
        attrs ``cycles`` and ``noise_rms_estimate`` (the cycle-to-cycle scatter divided by
        ``sqrt(cycles)``: the error of the average).

    References
    ----------
    Braun (1975).

    Examples
    --------
    >>> fs = 5000.0
    >>> t = np.arange(int(10 * fs)) / fs
    >>> from crankbench.analysis.resample import shaft_angle
    >>> rpm = np.full(t.size, 1200.0)
    >>> rng = np.random.default_rng(0)
    >>> x = np.cos(shaft_angle(rpm, fs)) + rng.normal(0, 1.0, t.size)
    >>> avg = synchronous_average(x, fs=fs, speed_rpm=rpm, samples_per_rev=64)
    >>> err = np.abs(avg.values - np.cos(avg.angle.values)).max()
    >>> bool(err < 5 * avg.attrs["noise_rms_estimate"]), avg.attrs["cycles"] > 190
    (True, True)
    """
    rpc = check_int(revolutions_per_cycle, "revolutions_per_cycle", minimum=1,
                    error=AnalysisError)
    y = angle_resample(x, fs=fs, speed_rpm=speed_rpm, samples_per_rev=samples_per_rev,
                       interpolation=interpolation)
    spr = y.attrs["samples_per_rev"]
    per_cycle = spr * rpc
    # start at the first whole cycle boundary so the average is referenced to angle 0
    j0 = int(round(y["angle"].values[0] / (2 * np.pi / spr)))
    first = -(-j0 // per_cycle) * per_cycle - j0                # samples to the next cycle start
    data = y.values[first:]
    cycles = data.shape[0] // per_cycle
    if cycles < 2:
        raise AnalysisError(f"{y.name}: only {cycles} whole cycle(s) of "
                            f"{rpc} revolution(s); need at least 2 to average")
    stack = data[: cycles * per_cycle].reshape(cycles, per_cycle)
    mean = stack.mean(axis=0)
    noise = float(np.sqrt(np.mean(stack.var(axis=0, ddof=1)) / cycles))
    import xarray as xr

    grid = np.arange(per_cycle) * (2 * np.pi / spr)
    return xr.DataArray(mean, dims=("angle",), name=f"{y.name} synchronous average",
                        coords={"angle": ("angle", grid, {"units": "rad"})},
                        attrs={"units": y.attrs.get("units", ""),
                               "method": "time-synchronous average (angle domain)",
                               "cycles": int(cycles), "revolutions_per_cycle": rpc,
                               "samples_per_rev": spr, "interpolation": interpolation,
                               "noise_rms_estimate": noise})


def _fft_operator(values, fs, power, highpass_hz, taper):
    """Multiply the spectrum by (iω)^power with an ideal-ish high-pass (cosine ramp)."""
    from scipy import fft

    n = values.shape[0]
    data = values - values.mean()
    if taper > 0:
        m = min(n // 4, int(round(taper * fs)))
        if m > 1:
            ramp = 0.5 * (1 - np.cos(np.pi * np.arange(m) / m))
            data = data.copy()
            data[:m] *= ramp
            data[-m:] *= ramp[::-1]
    nfft = fft.next_fast_len(n, real=True)
    spec = fft.rfft(data, nfft)
    f = np.arange(spec.shape[0]) * fs / nfft
    gain = np.zeros_like(f, dtype=complex)
    nz = f > 0
    gain[nz] = (2j * np.pi * f[nz]) ** power
    if highpass_hz is not None and highpass_hz > 0:
        ramp = np.clip((f - 0.5 * highpass_hz) / (0.5 * highpass_hz), 0.0, 1.0)
        gain *= 0.5 * (1 - np.cos(np.pi * ramp))
    return fft.irfft(spec * gain, nfft)[:n]


def _time_highpass(values, fs, highpass_hz):
    from scipy import signal

    sos = signal.butter(2, highpass_hz, btype="high", fs=fs, output="sos")
    return signal.sosfiltfilt(sos, values, padlen=min(values.shape[0] - 1,
                                                     int(3 * fs / highpass_hz)))


def integrate(x, *, fs=None, times: int = 1, highpass_hz: float = 2.0, method: str = "fft",
              taper: float = 0.0, trend: str = "auto"):
    """Integrate a signal once or twice (acceleration → velocity → displacement) without drift.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal (a Record channel supplies fs and units; ``m/s^2`` becomes ``m/s`` then ``m``).
    fs : float, optional
        Sample rate, Hz.
    times : {1, 2}
        Number of integrations.
    highpass_hz : float
        Drift control: components below this frequency are removed (fft: cosine ramp from
        ``highpass_hz/2`` to ``highpass_hz``; time: 2nd-order zero-phase Butterworth after each
        integration).
    method : {'fft', 'time'}
        Frequency-domain division by ``(iω)^n`` or trapezoidal integration (module docs).
    taper : float
        fft method: cosine taper length at each end, s (limits end leakage of records not
        holding whole periods).
    trend : {'auto', 'keep', 'remove', 'none'}
        fft method: a ramp (an IAS channel's changing mean speed) is taken out as a quadratic
        before the transform, which would wrap it into end spikes, and integrated exactly;
        'auto' does so when the channel ramps (module docs) and then drops its integral when
        ``highpass_hz`` asks for drift removal (keeps it otherwise); 'keep'/'remove' decide
        explicitly; 'none' transforms the samples as they are.

    Returns
    -------
    xarray.DataArray
        Over ``time`` with units and the parameters in attrs (``trend``: what was done).

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(5000) / fs
    >>> acc = 3.0 * np.cos(2 * np.pi * 20 * t) + 0.05          # an offset that would drift
    >>> vel = integrate(acc, fs=fs, highpass_hz=5.0)
    >>> exact = 3.0 * np.sin(2 * np.pi * 20 * t) / (2 * np.pi * 20)
    >>> bool(np.abs(vel.values - exact).max() < 1e-12), vel.attrs["method"]
    (True, 'fft integral x1')
    """
    return _calculus(x, fs, check_int(times, "times", minimum=1, error=AnalysisError),
                     -1, highpass_hz, method, taper, trend)


def differentiate(x, *, fs=None, times: int = 1, method: str = "fft", highpass_hz=None,
                  taper: float = 0.0, trend: str = "auto"):
    """Differentiate a signal (displacement → velocity → acceleration).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal.
    fs : float, optional
        Sample rate, Hz.
    times : int
        Number of differentiations.
    method : {'fft', 'time'}
        Multiplication by ``iω`` (exact for periodic content) or second-order central
        differences (gain error ``(ωΔt)²/6``).
    highpass_hz : float, optional
        Remove components below this frequency as well.
    taper : float
        fft method: end taper, s.
    trend : {'auto', 'keep', 'remove', 'none'}
        fft method: a ramp (an encoder angle's rotation, a changing mean) is taken out as a
        quadratic before the transform (the rest is transformed as an even extension) and
        differentiated exactly, then added back ('auto' and
        'keep'; 'remove' drops it); a wrapped angle channel (quantity 'angle', jumps of 2π) is
        unwrapped first. 'none': the samples as they are.

    Returns
    -------
    xarray.DataArray
        The derivative; for an encoder angle (rad) the shaft speed (rad/s) including its mean.

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(1000) / fs
    >>> v = differentiate(np.sin(2 * np.pi * 10 * t), fs=fs)
    >>> round(float(v.values.max() / (2 * np.pi * 10)), 9)
    1.0
    """
    return _calculus(x, fs, check_int(times, "times", minimum=1, error=AnalysisError),
                     +1, highpass_hz, method, taper, trend)


def _calculus(x, fs, times, sign, highpass_hz, method, taper, trend="auto"):
    values, fs, units, label = _as_signal(x, fs)
    method = check_option(method, "method", ("fft", "time"), error=AnalysisError)
    trend = check_option(trend, "trend", ("auto", "keep", "remove", "none"), error=AnalysisError)
    if highpass_hz is not None:
        highpass_hz = check_positive(highpass_hz, "highpass_hz", error=AnalysisError)
        if highpass_hz >= 0.5 * fs:
            raise AnalysisError(f"highpass_hz={highpass_hz} must be below fs/2 = {0.5 * fs}")
    taper = check_range(taper, "taper", 0.0, None, error=AnalysisError)
    out_units = units
    for _ in range(times):
        table = _INTEGRAL_UNITS if sign < 0 else _DERIVATIVE_UNITS
        out_units = table.get(out_units, (f"{out_units}*s" if sign < 0 else f"{out_units}/s")
                              if out_units else "")
    done = "none"
    if trend != "none" and _wrapped_angle(values, getattr(x, "attrs", {}) or {}, units):
        values = np.unwrap(values)
        done = "unwrapped"
    if method == "fft":
        poly, ramp = _ramp(values, fs)
        if trend in ("keep", "remove") or (trend == "auto" and ramp):
            keep = trend == "keep" or (trend == "auto" and (sign > 0 or highpass_hz is None))
            t = np.arange(values.shape[0]) / fs
            # the rest, mirrored (an even extension has no jump at the ends to wrap)
            rest = values - poly(t)
            result = _fft_operator(np.concatenate([rest, rest[::-1]]), fs, sign * times,
                                   highpass_hz, taper)[:values.shape[0]]
            op = poly.deriv(times) if sign > 0 else poly.integ(times)
            if keep:
                result = result + op(t)
            done = (done + ", " if done != "none" else "") + (
                f"quadratic trend {'transformed exactly and kept' if keep else 'removed'}")
        else:
            result = _fft_operator(values, fs, sign * times, highpass_hz, taper)
    else:
        result = values.copy()
        for _ in range(times):
            if sign < 0:
                result = np.concatenate([[0.0], np.cumsum(0.5 * (result[1:] + result[:-1]))
                                         / fs])
                if highpass_hz is not None:
                    result = _time_highpass(result, fs, highpass_hz)
                else:
                    result = result - result.mean()
            else:
                result = np.gradient(result, 1.0 / fs, edge_order=2)
                if highpass_hz is not None:
                    result = _time_highpass(result, fs, highpass_hz)
    what = "integral" if sign < 0 else "derivative"
    return _wrap(result, x, fs, out_units, f"{label} {what}",
                 {"method": f"{method} {what} x{times}", "highpass_hz":
                  float("nan") if highpass_hz is None else highpass_hz, "taper_s": taper,
                  "trend": done})


def _ramp(values, fs):
    """Least-squares quadratic of the samples (a numpy Polynomial in time, s) and whether it is
    a ramp the FFT would wrap: the jump between the record's ends exceeds ten times the spread
    of what the quadratic leaves, or the quadratic explains 90 % of the variance."""
    from numpy.polynomial import Polynomial

    n = values.shape[0]
    t = np.arange(n) / fs
    poly = Polynomial.fit(t, values, 2).convert()
    resid = values - poly(t)
    spread = float(np.std(resid))
    total = float(np.var(values))
    jump = abs(float(values[-1] - values[0]))
    ramp = (jump > 10.0 * spread and jump > 1e-12 * max(abs(values).max(), 1e-300)) or \
        (total > 0 and 1.0 - spread ** 2 / total >= 0.9)
    return poly, bool(ramp)


def _wrapped_angle(values, attrs, units) -> bool:
    """An angle channel wrapped into one turn (jumps of about 2π between samples)."""
    if attrs.get("quantity") != "angle" and units != "rad":
        return False
    if values.shape[0] < 4 or np.ptp(values) > 2.0 * np.pi * 1.01:
        return False
    jumps = np.abs(np.diff(values)) > np.pi
    return bool(jumps.sum() >= 2)
