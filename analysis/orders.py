"""Order analysis: order spectrum, order map, order tracks and the rpm–frequency (Campbell) map.

Methods and which to use when
-----------------------------
``order_track(method="cot")`` — computed order tracking: the record is resampled at constant
shaft angle (:func:`analysis.resample.angle_resample`) and each block of ``revolutions``
revolutions is analysed by a windowed DFT evaluated *at the exact order* (so an order need not
sit on a bin). Amplitude resolution is one block; use it for steady-amplitude orders in
run-ups and for slow sweeps across resonances (≲ 100 rpm/s for Q ≈ 20). Error: the
interpolation error (``resample`` docs) plus the noise ``σ_A ≈ sqrt(N0 · ENBW / T_block)``
(``N0`` the one-sided noise density, ``T_block`` the block duration) plus, when the amplitude
changes within the block, the smoothing of the envelope over one block.

``order_map`` — the order spectrum of each block (rfft of the angle-domain block): the picture
of every order against speed. Its amplitude per bin is the *coherent* (peak) amplitude;
with ``scaling="power"`` each bin holds mean-square, so that :func:`band_amplitude` can sum the
energy of an order band (an order between bins loses nothing). Same resolution trade-off as COT.

``order_track(method="vkf")`` — Vold–Kalman filter (:mod:`analysis.vkf`): the envelopes of all
requested orders solved jointly by least squares with a smoothness constraint. Its time
resolution is set by the bandwidth, not by a block; use it for fast sweeps through resonances,
for crossing orders and for closely spaced orders. See ``analysis.vkf`` for its error.

Measured (bench suite ``orders``; order 3 crossing a Q = 20 resonance at 100 Hz, i.e. 2000 rpm,
half-power bandwidth ``f_n/Q`` = 5 Hz; truth = exact envelope from ``solve_ivp``):

=============================  ==============  ==============  ===============
peak-amplitude error           100 rpm/s       400 rpm/s       1000 rpm/s
=============================  ==============  ==============  ===============
COT tracks, Hann, 2 rev        −0.04 %         −0.48 %         −1.9 %
COT tracks, Hann, 4 rev        −0.17 %         −1.9 %          −7.0 %
order map, 2 rev, band ±2 bin  −0.01 %         −0.12 %         −0.42 %
VKF p=2, B = 4 f_n/Q           < 0.01 %        −0.05 %         −0.70 %
VKF p=2, B = 8 f_n/Q           < 0.01 %        < 0.01 %        −0.04 %
=============================  ==============  ==============  ===============

Which method when:

* **fast sweeps through resonances** (the resonance crossed in a few of its decay times,
  ``(df/dt)/(f_n/Q)² ≳ 0.5``): VKF, second order, bandwidth 4–8 × the resonance's
  half-power bandwidth ``f_n/Q`` (wider passes more noise: ``σ_A ∝ sqrt(B)``);
* **slow sweeps and steady or slowly varying orders** (run-ups with ≲ 100 rpm/s across a
  Q ≈ 20 resonance, steady-state points): COT tracks or the order map with blocks of
  ``revolutions`` long enough for the noise (error ``sqrt(N0·ENBW/T_block)``) and short
  enough for the envelope (a block spans ≲ 1/5 of the resonance's half-power crossing time);
* **crossing orders** (orders of different shafts, or an order through a fixed-frequency
  component): VKF with all of them in one solve;
* **an overview of all orders**: the order map (``scaling="power"`` + :func:`band_amplitude`
  when an order falls between bins); the Campbell map for fixed-frequency resonances.

Conventions: the phase of an order ``o`` is that of ``A cos(o φ + phase)`` with the shaft
angle ``φ`` from the speed reference, zero at the first sample of the record. Amplitudes are
given as ``'peak'`` (A), ``'rms'`` (A/√2) or ``'peak-to-peak'`` (2A).

References
----------
K. R. Fyfe and E. D. S. Munck, "Analysis of computed order tracking", MSSP 11(2) (1997).
G. Heinzel, A. Rüdiger, R. Schilling, "Spectrum and spectral density estimation by the DFT",
Max-Planck-Institut report (2002), §9–10 (window normalisation, ENBW, band power).
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict._validate import (check_finite_array, check_int, check_option,
                                          check_positive,
                               check_range)
from crankbench.predict.errors import AnalysisError
from crankbench.predict._deprecate import renamed

from .resample import INTERPOLATIONS, _as_rpm, _as_signal, angle_resample

__all__ = ["order_track", "order_map", "order_spectrum", "band_amplitude", "campbell_map",
           "AMPLITUDES", "amplitude_factor", "get_window"]

log = logging.getLogger("crankbench")

#: amplitude conventions and their factor relative to the peak amplitude
AMPLITUDES = {"peak": 1.0, "rms": 1.0 / np.sqrt(2.0), "peak-to-peak": 2.0}

_METHODS = ("cot", "vkf")
_FRAMES_PER_BATCH = 256  # frames transformed at a time (bounds memory)


def amplitude_factor(amplitude: str) -> float:
    """Factor turning a peak amplitude into the ``amplitude`` convention ('peak'|'rms'|'peak-to-peak').

    Examples
    --------
    >>> amplitude_factor("peak-to-peak")
    2.0
    """
    check_option(amplitude, "amplitude", AMPLITUDES, error=AnalysisError)
    return float(AMPLITUDES[amplitude])


def get_window(window, length: int) -> np.ndarray:
    """A periodic (DFT-even) window from :func:`scipy.signal.get_window` by name.

    ``window`` is a name (``"hann"``, ``"flattop"``, ``"boxcar"``...) or a tuple such as
    ``("kaiser", 8.0)``; an unknown name raises :class:`AnalysisError` listing valid names.

    Examples
    --------
    >>> float(get_window("hann", 4)[2])
    1.0
    """
    from scipy.signal import get_window as scipy_window
    from scipy.signal.windows import _windows

    try:
        return scipy_window(window, length, fftbins=True)
    except (ValueError, TypeError) as exc:
        names = sorted(k for k in getattr(_windows, "_win_equiv", {}) if isinstance(k, str))
        from crankbench.predict._validate import suggest

        raise AnalysisError(f"window={window!r} is not a scipy window ({exc}); valid names "
                            f"include {', '.join(names[:30])}"
                            f"{suggest(str(window), names)}") from None


def _t0(x) -> float:
    """Time of the first sample of a Record channel (its time coordinate), else 0."""
    dims = getattr(x, "dims", None)
    if dims and dims[0] in getattr(x, "coords", {}):
        return float(x.coords[dims[0]].values[0])
    return 0.0


def _check_orders(orders) -> np.ndarray:
    arr = check_finite_array(np.atleast_1d(np.asarray(orders, dtype=float)), "orders", ndim=1,
                             min_length=1, error=AnalysisError)
    if (arr <= 0).any():
        raise AnalysisError(f"orders must be > 0 (cycles per shaft revolution), got {arr.tolist()}")
    return arr


def _check_order_range(top_order: float, samples_per_rev: int, x, fs, rpm, *,
                       divisor: int = 4) -> None:
    """Orders must lie in the anti-alias pass band (``samples_per_rev/4``; a map may show up to
    the angle-domain Nyquist order ``samples_per_rev/2``) and below the record's Nyquist
    frequency."""
    if top_order > samples_per_rev / divisor + 1e-12:
        what = "the anti-alias pass band" if divisor == 4 else "the angle-domain Nyquist order"
        raise AnalysisError(
            f"order {top_order:g} exceeds samples_per_rev/{divisor} = "
            f"{samples_per_rev / divisor:g} ({what}); use samples_per_rev >= "
            f"{int(np.ceil(divisor * top_order))}")
    values, fs_, _, label = _as_signal(x, fs)
    speed = _as_rpm(rpm, values.shape[0], fs_)
    f_top = top_order * float(speed.max()) / 60.0
    if f_top >= 0.5 * fs_:
        raise AnalysisError(f"order {top_order:g} reaches {f_top:.6g} Hz at {speed.max():.6g} "
                            f"rpm, above the Nyquist frequency {0.5 * fs_:.6g} Hz of {label}")


def _frames(n: int, length: int, overlap: float) -> np.ndarray:
    """Start indices of frames of ``length`` samples with fractional ``overlap``."""
    hop = max(1, int(round(length * (1.0 - overlap))))
    if n < length:
        return np.zeros(0, dtype=np.int64)
    return np.arange(0, n - length + 1, hop, dtype=np.int64)


def _frame_batches(starts: np.ndarray, batch: int = _FRAMES_PER_BATCH):
    for i in range(0, starts.shape[0], batch):
        yield slice(i, min(starts.shape[0], i + batch))


def _angle_blocks(x, fs, rpm, samples_per_rev, revolutions, overlap, interpolation):
    """Resample and cut into blocks; returns (resampled DataArray, starts, block length)."""
    samples_per_rev = check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    revolutions = check_int(revolutions, "revolutions", minimum=1, error=AnalysisError)
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    check_option(interpolation, "interpolation", INTERPOLATIONS, error=AnalysisError)
    y = angle_resample(x, fs=fs, speed_rpm=rpm, samples_per_rev=samples_per_rev,
                       interpolation=interpolation)
    length = samples_per_rev * revolutions
    starts = _frames(y.shape[0], length, overlap)
    if starts.shape[0] == 0:
        raise AnalysisError(
            f"{y.name}: the record covers {y.shape[0] / samples_per_rev:.4g} revolutions, fewer "
            f"than one block of revolutions={revolutions}; lower revolutions")
    return y, starts, length


def _block_coords(y, starts, length):
    centre = starts + length / 2.0 - 0.5
    idx = np.arange(y.shape[0])
    t = np.interp(centre, idx, y["time"].values)
    r = np.interp(centre, idx, y["rpm"].values)
    return t, r


# ---------------------------------------------------------------------------- order track


@renamed(rpm="speed_rpm")
def order_track(x, *, fs=None, speed_rpm, orders, amplitude: str = "peak", method: str = "cot",
                samples_per_rev: int = 64, revolutions: int = 16, overlap: float = 0.5,
                window="hann", interpolation: str = "cubic", bandwidth_hz=None,
                bandwidth_orders=None, filter_order: int = 2):
    """Amplitude and phase of shaft orders against time (and speed).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal (any SI unit); a Record channel supplies ``fs`` and ``units``.
    fs : float, optional
        Sample rate, Hz (required for a plain array).
    speed_rpm : float or array_like
        Shaft speed, rpm, one value per sample (see :func:`analysis.speedref.speed_reference`).
    orders : sequence of float
        Orders to track (cycles per shaft revolution; 0.5 = half order of a 4-stroke).
    amplitude : {'peak', 'rms', 'peak-to-peak'}
        Amplitude convention of the result.
    method : {'cot', 'vkf'}
        Computed order tracking (angle resampling + block DFT at each order) or Vold–Kalman
        filtering (see the module docstring for which to use when).
    samples_per_rev, revolutions, overlap, window, interpolation
        COT parameters: angle samples per revolution, block length (revolutions; the order
        resolution is ``1/revolutions``), fractional block overlap, scipy window name, and the
        resampling interpolation ('linear', 'cubic', 'bandlimited').
    bandwidth_hz, bandwidth_orders, filter_order
        VKF parameters (see :func:`analysis.vkf.vold_kalman`).

    Returns
    -------
    xarray.Dataset
        ``amplitude`` (units of ``x``) and ``phase`` (rad) over (``order``, ``time``), with
        ``rpm`` along ``time``; attrs name the method and its parameters. COT adds
        ``amplitude_noise`` (time): the 1-σ amplitude error due to the block's broadband noise
        floor; VKF reports ``attrs['amplitude_std_estimate']`` per order.

    References
    ----------
    Fyfe & Munck (1997); Heinzel et al. (2002) — see the module docstring.

    Examples
    --------
    >>> fs = 4000.0
    >>> t = np.arange(int(8 * fs)) / fs
    >>> rpm = 900 + 60 * t                                  # slow run-up
    >>> from crankbench.analysis.resample import shaft_angle
    >>> phi = shaft_angle(rpm, fs)
    >>> x = 2.0 * np.cos(2 * phi + 0.3) + 0.5 * np.cos(0.5 * phi)
    >>> res = order_track(x, fs=fs, speed_rpm=rpm, orders=[0.5, 2], revolutions=8)
    >>> np.round(res.amplitude.mean("time").values, 4)
    array([0.5, 2. ])
    >>> round(float(res.phase.sel(order=2).mean()), 4)
    0.3
    """
    method = check_option(method, "method", _METHODS, error=AnalysisError)
    factor = amplitude_factor(amplitude)
    orders = _check_orders(orders)
    masked = _dropout_spans(x, fs)
    if masked is not None:
        return _track_around_dropouts(x, fs, masked, speed_rpm=speed_rpm, orders=orders,
                                      amplitude=amplitude, method=method,
                                      samples_per_rev=samples_per_rev, revolutions=revolutions,
                                      overlap=overlap, window=window,
                                      interpolation=interpolation, bandwidth_hz=bandwidth_hz,
                                      bandwidth_orders=bandwidth_orders,
                                      filter_order=filter_order)
    if method == "vkf":
        from .vkf import vold_kalman

        values, fs_, units, label = _as_signal(x, fs)
        res = vold_kalman(values, fs=fs_, speed_rpm=speed_rpm, orders=orders,
                          bandwidth_hz=bandwidth_hz,
                          bandwidth_orders=bandwidth_orders, filter_order=filter_order)
        amp = np.abs(res["envelope"].values) * factor
        ds = _track_dataset(amp, np.angle(res["envelope"].values), orders,
                            res["time"].values + _t0(x), res["rpm"].values, units, label)
        ds.attrs.update(res.attrs)
        ds.attrs.update({"amplitude_convention": amplitude})
        return ds
    _check_order_range(float(orders.max()), check_int(samples_per_rev, "samples_per_rev",
                                                       minimum=4, error=AnalysisError), x, fs, speed_rpm)
    y, starts, length = _angle_blocks(x, fs, speed_rpm, samples_per_rev, revolutions, overlap,
                                      interpolation)
    w = get_window(window, length)
    # complex amplitude A = 2 Σ y w e^{-i o φ} / Σ w  (coherent gain, exact at any order)
    local = 2.0 * np.pi * np.arange(length) / samples_per_rev
    kernel = (w[:, None] * np.exp(-1j * np.outer(local, orders))) * (2.0 / w.sum())
    data = y.values
    phi0 = y["angle"].values[starts]
    coef = np.empty((starts.shape[0], orders.shape[0]), dtype=complex)
    floor = np.empty(starts.shape[0])
    enbw = float(length * np.sum(w ** 2) / np.sum(w) ** 2)
    # broadband noise floor of each block: median mean-square per bin over the pass band
    # (robust to the order lines) / ln 2 (median of an exponential variable); the 1-sigma
    # error of an amplitude is then sqrt(P_noise * ENBW)
    from scipy import fft

    band = slice(1, min(length // 2, int(samples_per_rev / 4.0 * revolutions)) + 1)
    for sl in _frame_batches(starts):
        idx = starts[sl, None] + np.arange(length)[None, :]
        frames = data[idx]
        coef[sl] = frames @ kernel
        power = _scale_spectrum(fft.rfft(frames * w, axis=1), w, "power", 1.0)[:, band]
        floor[sl] = np.median(power, axis=1) / np.log(2.0)
    coef *= np.exp(-1j * np.outer(phi0, orders))
    t, r = _block_coords(y, starts, length)
    t = t + _t0(x)
    ds = _track_dataset(np.abs(coef).T * factor, np.angle(coef).T, orders, t, r,
                        y.attrs.get("units", ""), y.name)
    ds["amplitude_noise"] = ("time", np.sqrt(floor * enbw) * factor,
                             {"units": y.attrs.get("units", ""), "long_name":
                              "1-sigma amplitude error from the broadband noise floor"})
    ds.attrs.update({"method": "computed order tracking (angle resampling + block DFT at order)",
                     "amplitude_convention": amplitude, "window": str(window),
                     "samples_per_rev": samples_per_rev, "revolutions": revolutions,
                     "resolution_orders": 1.0 / revolutions, "overlap": overlap,
                     "interpolation": interpolation, "enbw_bins": enbw})
    return ds


def _dropout_spans(x, fs):
    """NaN/inf spans ``[(start, stop), ...]`` of a 1-D signal with some finite samples, else
    None (a clean signal, or one that is not usable at all: left to the normal checks)."""
    from crankbench.measure.record import nonfinite_spans

    values = getattr(x, "values", x)
    try:
        values = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        return None
    if values.ndim != 1 or np.isfinite(values).all() or not np.isfinite(values).any():
        return None
    if fs is None and getattr(x, "attrs", {}).get("sample_rate") is None:
        return None
    return nonfinite_spans(values)


def _track_around_dropouts(x, fs, spans, **options):
    """Order-track a signal with dropouts (NaN/inf runs, e.g. a record read with
    ``allow_nonfinite=True``): the runs are bridged by linear interpolation for the computation
    only, and every result whose analysis window reaches a run is set to NaN, with a warning
    naming the spans. The window is the block (``revolutions``) for COT and ±2/bandwidth
    (the filter's memory: outside it the bridged gap moves a 2nd-order VKF track by ~1e-4
    relative) for VKF, plus one revolution of guard."""
    import warnings

    from crankbench.measure.record import RecordWarning

    values = np.asarray(getattr(x, "values", x), dtype=float)
    fs_ = float(fs if fs is not None else x.attrs["sample_rate"])
    label = str(getattr(x, "name", None) or "x")
    good = np.isfinite(values)
    idx = np.arange(values.shape[0])
    filled = values.copy()
    filled[~good] = np.interp(idx[~good], idx[good], values[good])
    t0 = _t0(x)
    times = [(t0 + a / fs_, t0 + (b - 1) / fs_) for a, b in spans]
    shown = ", ".join(f"{a:.6g}..{b:.6g} s" for a, b in times[:5])
    more = f" and {len(times) - 5} more" if len(times) > 5 else ""
    warnings.warn(f"{label}: {int((~good).sum())} NaN/inf sample(s) masked at {shown}{more}; "
                  "order-track results whose analysis window reaches them are NaN",
                  RecordWarning, stacklevel=3)
    signal = x.copy(data=filled) if hasattr(x, "dims") else filled
    ds = order_track(signal, fs=fs, **options)
    rpm = ds["rpm"].values
    rev = 60.0 / rpm                                            # s per revolution at each result
    if options["method"] == "vkf":
        half = 2.0 / float(ds.attrs["bandwidth_hz_min"]) + rev
    else:
        half = (0.5 * options["revolutions"] + 1.0) * rev
    t = ds["time"].values
    hit = np.zeros(t.shape[0], bool)
    for a, b in times:
        hit |= (t + half >= a) & (t - half <= b)
    for name in ("amplitude", "phase"):
        ds[name] = ds[name].where(~hit)
    if "amplitude_noise" in ds:
        ds["amplitude_noise"] = ds["amplitude_noise"].where(~hit)
    ds.attrs["masked_spans_s"] = [v for span in times for v in span]
    return ds


def _track_dataset(amp, phase, orders, t, r, units, label):
    import xarray as xr

    coords = {"order": ("order", orders, {"units": "1", "long_name": "shaft order"}),
              "time": ("time", np.asarray(t, float), {"units": "s"}),
              "rpm": ("time", np.asarray(r, float), {"units": "rpm", "long_name": "shaft speed"})}
    return xr.Dataset(
        {"amplitude": (("order", "time"), amp, {"units": units,
                                                "long_name": f"{label} order amplitude"}),
         "phase": (("order", "time"), phase, {"units": "rad",
                                               "long_name": "phase of A cos(o φ + phase)"})},
        coords=coords, attrs={"channel": str(label),
                              "phase_reference": "shaft angle 0 at the first sample of the "
                                                 "record (speed-reference integration)"})


# ---------------------------------------------------------------------------- order map


def _scale_spectrum(X: np.ndarray, w: np.ndarray, scaling: str, factor: float) -> np.ndarray:
    """Coherent amplitude or mean-square per bin of one-sided DFTs ``X`` (rows)."""
    length = w.shape[0]
    if scaling == "amplitude":
        out = np.abs(X) * (2.0 / w.sum())
        out[:, 0] *= 0.5
        if length % 2 == 0:
            out[:, -1] *= 0.5
        return out * factor
    # mean square per bin: P_k = 2|X_k|^2 / (M Σ w^2); band sums give A_rms^2 (Parseval)
    out = np.abs(X) ** 2 * (2.0 / (length * np.sum(w ** 2)))
    out[:, 0] *= 0.5
    if length % 2 == 0:
        out[:, -1] *= 0.5
    return out


def _map_values(y, starts, length, w, scaling, factor, n_orders):
    from scipy import fft

    data = y.values
    out = np.empty((starts.shape[0], n_orders))
    for sl in _frame_batches(starts):
        idx = starts[sl, None] + np.arange(length)[None, :]
        X = fft.rfft(data[idx] * w, axis=1)[:, :n_orders]
        # reference each block's phase to φ = 0 is not needed for magnitudes
        out[sl] = _scale_spectrum(X, w, scaling, factor)
    return out


@renamed(rpm="speed_rpm", rpm_bins="speed_bins_rpm")
def order_map(x, *, fs=None, speed_rpm, samples_per_rev: int = 64, revolutions: int = 16,
              overlap: float = 0.5, window="hann", amplitude: str = "peak",
              scaling: str = "amplitude", max_order=None, speed_bins_rpm=None,
              interpolation: str = "cubic"):
    """Order spectrum of each block of revolutions: the order map (time or rpm × order).

    Parameters
    ----------
    x, fs, rpm
        Signal, sample rate (Hz) and shaft speed (rpm per sample) as in :func:`order_track`.
    samples_per_rev, revolutions, overlap, window, interpolation
        As in :func:`order_track`; bins are ``1/revolutions`` orders apart.
    amplitude : {'peak', 'rms', 'peak-to-peak'}
        Convention when ``scaling='amplitude'``.
    scaling : {'amplitude', 'power'}
        ``'amplitude'``: coherent amplitude per bin (exact for an order on a bin);
        ``'power'``: mean square per bin (units²) so that band sums are exact
        (:func:`band_amplitude`).
    max_order : float, optional
        Highest order kept (default ``samples_per_rev/4``, the anti-alias pass band; at most
        ``samples_per_rev/2``, the bins above ``samples_per_rev/4`` being in the filter's
        transition band).
    speed_bins_rpm : int or array_like, optional
        Average the blocks in speed bins (count or edges in rpm; power average). The result then
        has dims (``rpm``, ``order``); otherwise (``time``, ``order``) with ``rpm`` along time.

    Returns
    -------
    xarray.DataArray
        Order map with units in attrs and the parameters used.

    Examples
    --------
    >>> fs = 4000.0
    >>> t = np.arange(int(6 * fs)) / fs
    >>> rpm = 1200 + 100 * t
    >>> from crankbench.analysis.resample import shaft_angle
    >>> x = 0.7 * np.cos(3 * shaft_angle(rpm, fs))
    >>> m = order_map(x, fs=fs, speed_rpm=rpm, revolutions=8)
    >>> round(float(m.sel(order=3).mean()), 4), m.dims
    (0.7, ('time', 'order'))
    """
    scaling = check_option(scaling, "scaling", ("amplitude", "power"), error=AnalysisError)
    factor = amplitude_factor(amplitude)
    spr = check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    top = spr / 4.0 if max_order is None else check_positive(max_order, "max_order",
                                                             error=AnalysisError)
    if max_order is not None:
        _check_order_range(top, spr, x, fs, speed_rpm, divisor=2)
    y, starts, length = _angle_blocks(x, fs, speed_rpm, samples_per_rev, revolutions, overlap,
                                      interpolation)
    n_orders = min(length // 2 + 1, int(np.floor(top * revolutions)) + 1)
    w = get_window(window, length)
    values = _map_values(y, starts, length, w, scaling, factor, n_orders)
    order_axis = np.arange(n_orders) / revolutions
    t, r = _block_coords(y, starts, length)
    t = t + _t0(x)
    units = y.attrs.get("units", "")
    out_units = units if scaling == "amplitude" else (f"({units})^2" if units else "1")
    import xarray as xr

    attrs = {"units": out_units, "method": "order map (angle resampling + block rfft)",
             "scaling": scaling, "amplitude_convention": amplitude if scaling == "amplitude"
             else "mean-square per bin", "window": str(window), "samples_per_rev": spr,
             "revolutions": revolutions, "resolution_orders": 1.0 / revolutions,
             "overlap": overlap, "interpolation": interpolation,
             "enbw_bins": float(length * np.sum(w ** 2) / np.sum(w) ** 2)}
    order_coord = ("order", order_axis, {"units": "1", "long_name": "shaft order"})
    if speed_bins_rpm is None:
        return xr.DataArray(values, dims=("time", "order"), name=f"{y.name} order map",
                            coords={"time": ("time", t, {"units": "s"}),
                                    "rpm": ("time", r, {"units": "rpm"}), "order": order_coord},
                            attrs=attrs)
    edges = (np.linspace(r.min(), r.max() * (1 + 1e-12), int(speed_bins_rpm) + 1)
             if np.isscalar(speed_bins_rpm) else check_finite_array(speed_bins_rpm,
                                                                    "speed_bins_rpm", ndim=1,
                                                              min_length=2, error=AnalysisError))
    which = np.digitize(r, edges) - 1
    keep = (which >= 0) & (which < edges.shape[0] - 1)
    power = values ** 2 if scaling == "amplitude" else values
    binned = np.full((edges.shape[0] - 1, n_orders), np.nan)
    counts = np.bincount(which[keep], minlength=edges.shape[0] - 1)
    for b in np.flatnonzero(counts):
        binned[b] = power[keep][which[keep] == b].mean(axis=0)
    if scaling == "amplitude":
        binned = np.sqrt(binned)
    filled = counts > 0
    centres = 0.5 * (edges[1:] + edges[:-1])
    attrs["rpm_averaging"] = "power mean of the blocks in each speed bin"
    return xr.DataArray(binned[filled], dims=("rpm", "order"), name=f"{y.name} order map",
                        coords={"rpm": ("rpm", centres[filled], {"units": "rpm"}),
                                "blocks": ("rpm", counts[filled]), "order": order_coord},
                        attrs=attrs)


@renamed(rpm="speed_rpm")
def order_spectrum(x, *, fs=None, speed_rpm, samples_per_rev: int = 64, revolutions=None,
                   overlap: float = 0.5, window="hann", amplitude: str = "peak",
                   scaling: str = "amplitude", max_order=None, interpolation: str = "cubic"):
    """Order spectrum at (nearly) steady speed, averaged over blocks (Welch, power average).

    Parameters
    ----------
    x, fs, rpm, samples_per_rev, overlap, window, amplitude, scaling, max_order, interpolation
        As in :func:`order_map`.
    revolutions : int, optional
        Block length in revolutions; default: the whole record in one block.

    Returns
    -------
    xarray.DataArray
        Over ``order``; ``scaling='power'`` gives mean square per bin (band sums via
        :func:`band_amplitude`), ``'amplitude'`` the coherent amplitude per bin.

    Examples
    --------
    >>> fs = 2000.0
    >>> t = np.arange(int(4 * fs)) / fs
    >>> from crankbench.analysis.resample import shaft_angle
    >>> x = 1.5 * np.cos(2 * shaft_angle(np.full(t.size, 1500.0), fs))
    >>> s = order_spectrum(x, fs=fs, speed_rpm=1500.0, revolutions=20)
    >>> round(float(s.sel(order=2)), 4)
    1.5
    """
    if revolutions is None:
        # whole revolutions available after resampling (the anti-alias filter trims the ends)
        y = angle_resample(x, fs=fs, speed_rpm=speed_rpm, samples_per_rev=samples_per_rev,
                           interpolation=interpolation)
        revolutions = max(1, y.shape[0] // int(samples_per_rev))
    m = order_map(x, fs=fs, speed_rpm=speed_rpm, samples_per_rev=samples_per_rev,
                  revolutions=revolutions,
                  overlap=overlap, window=window, amplitude=amplitude, scaling=scaling,
                  max_order=max_order, interpolation=interpolation)
    if scaling == "amplitude":
        out = np.sqrt((m ** 2).mean("time"))
    else:
        out = m.mean("time")
    out.attrs.update(m.attrs)
    out.attrs["blocks_averaged"] = int(m.sizes["time"])
    out.attrs["rpm_mean"] = float(m["rpm"].mean())
    out.name = m.name.replace("order map", "order spectrum")
    return out


def band_amplitude(power, orders, *, half_width, amplitude: str = "peak"):
    """Amplitude of each order from the energy summed over a band of bins around it.

    Parameters
    ----------
    power : xarray.DataArray
        An order spectrum or map computed with ``scaling='power'`` (dim ``order``).
    orders : sequence of float
        Band centres (orders).
    half_width : float
        Half-width of each band, orders; it must hold the window's main lobe (for Hann at least
        2 bins, i.e. ``2/revolutions``; 3 bins leaves < 1e-4 of the energy outside).
    amplitude : {'peak', 'rms', 'peak-to-peak'}

    Returns
    -------
    xarray.DataArray
        Over ``order`` (plus any other dims of ``power``): ``sqrt(2 Σ P_k)`` × convention.

    References
    ----------
    Heinzel et al. (2002) §10: the power in a band of bins of a power spectrum is exact by
    Parseval's theorem whatever the tone's position between bins.

    Examples
    --------
    >>> fs = 2000.0
    >>> t = np.arange(int(4 * fs)) / fs
    >>> from crankbench.analysis.resample import shaft_angle
    >>> x = np.cos(2.025 * shaft_angle(np.full(t.size, 1500.0), fs))   # between bins
    >>> p = order_spectrum(x, fs=fs, speed_rpm=1500.0, revolutions=20, scaling="power")
    >>> round(float(band_amplitude(p, [2.025], half_width=0.2)[0]), 4)
    1.0
    """
    if power.attrs.get("scaling") != "power":
        raise AnalysisError("band_amplitude needs a spectrum or map computed with "
                            "scaling='power'")
    factor = amplitude_factor(amplitude)
    orders = _check_orders(orders)
    half_width = check_positive(half_width, "half_width", error=AnalysisError)
    import xarray as xr

    axis = power["order"].values
    bands = []
    for o in orders:
        sel = np.abs(axis - o) <= half_width + 1e-12
        if not sel.any():
            raise AnalysisError(f"no bin within half_width={half_width} of order {o}")
        bands.append(np.sqrt(2.0 * power.isel(order=np.flatnonzero(sel)).sum("order")) * factor)
    out = xr.concat(bands, dim="order").assign_coords(order=orders)
    base = str(power.attrs.get("units", "")).removeprefix("(").removesuffix(")^2")
    out.attrs = {**power.attrs, "units": base, "scaling": "band amplitude",
                 "band_half_width_orders": half_width, "amplitude_convention": amplitude}
    return out


# ---------------------------------------------------------------------------- Campbell map


@renamed(rpm="speed_rpm", rpm_bins="speed_bins_rpm")
def campbell_map(x, *, fs=None, speed_rpm, nperseg: int = 4096, overlap: float = 0.5, window="hann",
                 amplitude: str = "peak", max_frequency=None, orders=(0.5, 1, 1.5, 2, 3, 4, 6),
                 speed_bins_rpm=None):
    """Rpm–frequency (Campbell / waterfall) map: short-time spectra in the time domain.

    Resonances (fixed frequencies) show as vertical lines and orders as rays through the origin;
    the order rays to draw are stored in ``attrs['order_lines']`` (see
    :func:`analysis.plots.plot_campbell`).

    Parameters
    ----------
    x, fs, rpm
        As in :func:`order_track`.
    nperseg : int
        Samples per short-time frame (frequency resolution ``fs/nperseg``).
    overlap : float
        Fractional frame overlap.
    window : str
        scipy window name.
    amplitude : {'peak', 'rms', 'peak-to-peak'}
        Coherent amplitude convention per bin.
    max_frequency : float, optional
        Highest frequency kept, Hz.
    orders : sequence of float
        Order lines recorded in attrs.
    speed_bins_rpm : int or array_like, optional
        Power-average the frames in speed bins (dims become (``rpm``, ``frequency``)).

    Returns
    -------
    xarray.DataArray
        Dims (``time``, ``frequency``) with ``rpm`` along time (mean speed of each frame).

    Examples
    --------
    >>> fs = 2048.0
    >>> t = np.arange(int(4 * fs)) / fs
    >>> x = 0.25 * np.cos(2 * np.pi * 100.0 * t)
    >>> c = campbell_map(x, fs=fs, speed_rpm=1500.0, nperseg=1024)
    >>> round(float(c.sel(frequency=100.0).mean()), 4)
    0.25
    """
    values, fs, units, label = _as_signal(x, fs)
    speed = _as_rpm(speed_rpm, values.shape[0], fs)
    factor = amplitude_factor(amplitude)
    nperseg = check_int(nperseg, "nperseg", minimum=8, error=AnalysisError)
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    starts = _frames(values.shape[0], nperseg, overlap)
    if starts.shape[0] == 0:
        raise AnalysisError(f"{label}: {values.shape[0]} samples is shorter than "
                            f"nperseg={nperseg}")
    freq = np.arange(nperseg // 2 + 1) * fs / nperseg
    n_freq = freq.shape[0] if max_frequency is None else int(np.searchsorted(
        freq, check_positive(max_frequency, "max_frequency", error=AnalysisError), "right"))
    w = get_window(window, nperseg)
    from scipy import fft

    out = np.empty((starts.shape[0], n_freq))
    for sl in _frame_batches(starts):
        idx = starts[sl, None] + np.arange(nperseg)[None, :]
        out[sl] = _scale_spectrum(fft.rfft(values[idx] * w, axis=1)[:, :n_freq], w,
                                  "amplitude", factor)
    cs = np.concatenate([[0.0], np.cumsum(speed)])
    frame_rpm = (cs[starts + nperseg] - cs[starts]) / nperseg
    t = (starts + nperseg / 2.0 - 0.5) / fs + _t0(x)
    import xarray as xr

    orders = _check_orders(orders)
    attrs = {"units": units, "method": "short-time FFT (rpm-frequency map)",
             "window": str(window), "nperseg": nperseg, "overlap": overlap,
             "resolution_hz": fs / nperseg, "amplitude_convention": amplitude,
             "order_lines": orders.tolist()}
    da = xr.DataArray(out, dims=("time", "frequency"), name=f"{label} campbell",
                      coords={"time": ("time", t, {"units": "s"}),
                              "rpm": ("time", frame_rpm, {"units": "rpm"}),
                              "frequency": ("frequency", freq[:n_freq], {"units": "Hz"})},
                      attrs=attrs)
    if speed_bins_rpm is None:
        return da
    edges = (np.linspace(frame_rpm.min(), frame_rpm.max() * (1 + 1e-12), int(speed_bins_rpm) + 1)
             if np.isscalar(speed_bins_rpm) else np.asarray(speed_bins_rpm, float))
    which = np.digitize(frame_rpm, edges) - 1
    rows, centres = [], []
    for b in range(edges.shape[0] - 1):
        sel = which == b
        if sel.any():
            rows.append(np.sqrt((out[sel] ** 2).mean(axis=0)))
            centres.append(0.5 * (edges[b] + edges[b + 1]))
    return xr.DataArray(np.array(rows), dims=("rpm", "frequency"), name=da.name,
                        coords={"rpm": ("rpm", np.array(centres), {"units": "rpm"}),
                                "frequency": da["frequency"]},
                        attrs={**attrs, "rpm_averaging": "power mean of frames per speed bin"})
