"""Order tracks: amplitude and phase of shaft orders against time and speed.

Methods and which to use when
-----------------------------
``order_track(method="auto")`` (the default) — the settings are chosen from the record
(:mod:`analysis.autotrack`): Vold–Kalman filtering with a bandwidth per order set by its noise
(narrow where the order is steady, for noise rejection) and widened in time around sharp peaks
found in a first pass (a resonance crossing keeps its peak); the chosen settings and why are in
``attrs['auto_settings']``, and a warning names the sweep rate, the expected bias and the
setting to use where no setting meets about 1 %.

``order_track(method="cot")`` — computed order tracking: the record is resampled at constant
shaft angle (:func:`analysis.resample.angle_resample`) and each block of ``revolutions``
revolutions is fitted by weighted least squares (window weights) with every requested order
*and* a constant and a slope (the channel's trend, reported as ``mean``, order 0) at once, so an
order need not sit on a bin, no trend leaks into low orders, and requested orders inside each
other's window main lobe are separated (a warning gives the noise amplification; orders closer
than one bin are refused). Amplitude resolution is one block. Error: the interpolation error
(``resample`` docs) plus the noise ``σ_A ≈ κ sqrt(N0 · ENBW / T_block)`` (``κ`` the least-squares
noise amplification, 1 for well separated orders) plus the smoothing of the envelope over the
block, ``≈ (μ₂/2)|A''|`` with ``μ₂`` the window's second moment in time; both are in
``amplitude_uncertainty``.

``order_track(method="vkf")`` — Vold–Kalman filter (:mod:`analysis.vkf`): the envelopes of all
requested orders and an order-0 trend solved jointly by least squares with a smoothness
constraint. Its time resolution is set by the bandwidth, not by a block; use it for fast sweeps
through resonances, for crossing orders and for closely spaced orders.

The order map, order spectrum, band amplitudes and Campbell map are in
:mod:`analysis.ordermap` (re-exported here).

Measured (bench suite ``orders``; an order crossing a Q = 20 resonance, truth = the exact
envelope from ``solve_ivp``): see the rows ``resonance …`` and ``defaults …`` of
``crankbench bench orders``; the defaults keep the peak within 0.5 % at 100–1000 rpm/s on that
case (``tests/analysis/test_autotrack.py`` checks 2 % at 400 rpm/s and 5 % at 1000 rpm/s on other
Q, orders and noise).

Conventions: the phase of an order ``o`` is that of ``A cos(o φ + phase)`` with the shaft
angle ``φ`` of the speed reference: from TDC of cylinder 1 when the speed reference carries the
encoder angle (:func:`analysis.speedref.speed_reference` attaches it from a pulse train), else
zero at the first sample of the record; ``attrs['phase_reference']`` says which. Amplitudes are
given as ``'peak'`` (A), ``'rms'`` (A/√2) or ``'peak-to-peak'`` (2A).

References
----------
K. R. Fyfe and E. D. S. Munck, "Analysis of computed order tracking", MSSP 11(2) (1997).
G. Heinzel, A. Rüdiger, R. Schilling, "Spectrum and spectral density estimation by the DFT",
Max-Planck-Institut report (2002), §9–10 (window normalisation, ENBW, band power).
S. M. Kay, *Fundamentals of Statistical Signal Processing: Estimation Theory* (1993), §8.6
(weighted least squares of sinusoids with nuisance terms).
"""

from __future__ import annotations

import logging
import warnings

import numpy as np

from crankbench.predict._deprecate import renamed
from crankbench.predict._validate import (check_finite_array, check_int, check_option,
                                          check_range)
from crankbench.predict.errors import AnalysisError

from .resample import INTERPOLATIONS, _angle_input, _as_rpm, _as_signal, resample_arrays
from .block_smearing import smearing_bias, warn_block_smearing as _warn_block_smearing
from .spans import stopped_spans as _stopped_spans
from .blocks import (_FRAMES_PER_BATCH, BlockFit, _frame_batches, _frames,  # noqa: F401
                     _hop, _scale_spectrum, get_window)  # (re-exported: the block machinery's home)

__all__ = ["order_track", "order_map", "order_spectrum", "band_amplitude", "campbell_map",
           "AMPLITUDES", "amplitude_factor", "get_window", "BlockFit", "OrderWarning"]

log = logging.getLogger("crankbench")

#: amplitude conventions and their factor relative to the peak amplitude
AMPLITUDES = {"peak": 1.0, "rms": 1.0 / np.sqrt(2.0), "peak-to-peak": 2.0}

_METHODS = ("auto", "cot", "vkf")


class OrderWarning(UserWarning):
    """An order result is less accurate than asked: the message names the cause and the
    setting to use."""


def amplitude_factor(amplitude: str) -> float:
    """Factor turning a peak amplitude into the ``amplitude`` convention ('peak'|'rms'|'peak-to-peak').

    Examples
    --------
    >>> amplitude_factor("peak-to-peak")
    2.0
    """
    check_option(amplitude, "amplitude", AMPLITUDES, error=AnalysisError)
    return float(AMPLITUDES[amplitude])


def _t0(x) -> float:
    """Time of the first sample of a Record channel (its time coordinate), else 0."""
    dims = getattr(x, "dims", None)
    if dims and dims[0] in getattr(x, "coords", {}) and x.shape[0]:
        return float(x.coords[dims[0]].values[0])
    return 0.0


def _check_orders(orders) -> np.ndarray:
    """Orders as a float array: finite, > 0, each given once."""
    arr = check_finite_array(np.atleast_1d(np.asarray(orders, dtype=float)), "orders", ndim=1,
                             min_length=1, error=AnalysisError)
    if (arr <= 0).any():
        raise AnalysisError(f"orders must be > 0 (cycles per shaft revolution), got {arr.tolist()}"
                            "; the channel's mean (order 0) is reported as the track's 'mean'")
    srt = np.sort(arr)
    same = np.flatnonzero(np.diff(srt) <= 1e-9 * np.maximum(1.0, srt[1:]))
    if same.size:
        dup = sorted({float(srt[i]) for i in same})
        raise AnalysisError(f"orders contain duplicates ({', '.join(f'{o:g}' for o in dup)} "
                            f"given more than once in {[float(v) for v in arr]}); give each order "
                            "once")
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
    _check_nyquist(top_order, float(speed.max()), fs_, label)



def _check_nyquist(top_order, speed_max_rpm, fs, label):
    """Refuse an order above the channel's Nyquist frequency; when it is far above (>= 5x),
    name the likely cause: a time axis in ms read as s, or a sample rate stated wrongly."""
    f_top = float(top_order) * float(speed_max_rpm) / 60.0
    if f_top < 0.5 * fs:
        return
    hint = ""
    if f_top >= 2.5 * fs:
        hint = (f"; the channel's {fs:.6g} Hz is implausibly low for an engine record at "
                f"{speed_max_rpm:.6g} rpm: check its time axis (a time column in ms read as s "
                "makes the rate 1000x too low: name the unit, e.g. 'time [ms]', or give "
                "[source] time_units / sample_rate in a channel map)")
    raise AnalysisError(f"order {top_order:g} reaches {f_top:.6g} Hz at {speed_max_rpm:.6g} "
                        f"rpm, above the Nyquist frequency {0.5 * fs:.6g} Hz of {label}{hint}")

def default_samples_per_rev(top_order: float) -> int:
    """Angle samples per revolution: 64, or more so the top order is in the pass band.

    Examples
    --------
    >>> default_samples_per_rev(4.5), default_samples_per_rev(24)
    (64, 96)
    """
    return int(max(64, 8 * np.ceil(4.0 * top_order / 8.0)))


# ---------------------------------------------------------------------------- order track


@renamed(rpm="speed_rpm")
def order_track(x, *, fs=None, speed_rpm, orders, amplitude: str = "peak", method: str = "auto",
                samples_per_rev=None, revolutions=None, overlap: float = 0.5,
                window="hann", interpolation: str = "auto", bandwidth_hz=None,
                bandwidth_orders=None, filter_order: int = 2, shaft_angle=None,
                trend: str = "auto", min_bandwidth_orders=None):
    """Amplitude and phase of shaft orders against time (and speed).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal (any SI unit); a Record channel supplies ``fs``, ``units`` and ``quantity``.
    fs : float, optional
        Sample rate, Hz (required for a plain array).
    speed_rpm : float or array_like
        Shaft speed, rpm, one value per sample (see :func:`analysis.speedref.speed_reference`,
        whose result may carry the encoder angle as a ``shaft_angle`` coordinate).
    orders : sequence of float
        Orders to track, each once (cycles per shaft revolution; 0.5 = half order of a
        4-stroke). The channel's mean (order 0) is always reported as ``mean``.
    amplitude : {'peak', 'rms', 'peak-to-peak'}
        Amplitude convention of the result.
    method : {'auto', 'cot', 'vkf'}
        'auto': chosen from the record (:mod:`analysis.autotrack`; COT when ``revolutions``
        or ``samples_per_rev`` is given, VKF with that bandwidth when one is); 'cot': computed order
        tracking (angle resampling + block least squares); 'vkf': Vold–Kalman filtering (see
        the module docstring for which to use when).
    samples_per_rev, revolutions, overlap, window, interpolation
        COT parameters: angle samples per revolution (default 64, more for orders above 16),
        block length (revolutions; the order resolution is ``1/revolutions``; default chosen
        from the sweep rate and the order spacing), fractional block overlap, scipy window
        name, and the resampling interpolation ('auto', 'bandlimited', 'cubic', 'linear').
    bandwidth_hz, bandwidth_orders, filter_order
        VKF parameters (see :func:`analysis.vkf.vold_kalman`).
    shaft_angle : array_like, optional
        Shaft angle (rad, increasing) per sample for resampling and phase (default: the
        ``shaft_angle`` coordinate of ``speed_rpm`` if present, else the integrated speed).
    trend : {'auto', 'none', 'angle ramp', 'speed mean'}
        The channel's trend removed before tracking (:func:`analysis.trend.remove_trend`);
        'auto' detects an encoder angle's ramp and an IAS channel's mean speed.
    min_bandwidth_orders : float, optional
        'auto' only: a bandwidth floor in orders (a caller that must resolve features of a
        known width, e.g. resonance identification at a known damping).

    Returns
    -------
    xarray.Dataset
        ``amplitude`` (units of ``x``) and ``phase`` (rad) over (``order``, ``time``), with
        ``rpm`` along ``time``; ``mean`` (time): order 0, the channel's mean (after any trend
        removed, see ``attrs['trend']``); ``amplitude_uncertainty`` (order, time): 1-σ noise
        and the estimated envelope smearing combined; COT adds ``amplitude_noise`` (time,
        noise part at unit noise gain). Attrs name the method and its parameters and the
        ``phase_reference``.

    References
    ----------
    Fyfe & Munck (1997); Heinzel et al. (2002); Kay (1993) — see the module docstring.

    Examples
    --------
    >>> fs = 4000.0
    >>> t = np.arange(int(8 * fs)) / fs
    >>> rpm = 900 + 60 * t                                  # slow run-up
    >>> from crankbench.analysis.resample import shaft_angle
    >>> phi = shaft_angle(rpm, fs)
    >>> x = 2.0 * np.cos(2 * phi + 0.3) + 0.5 * np.cos(0.5 * phi) + 7.0   # with an offset
    >>> res = order_track(x, fs=fs, speed_rpm=rpm, orders=[0.5, 2], method="cot",
    ...                   revolutions=8)
    >>> np.round(res.amplitude.mean("time").values, 4), round(float(res["mean"].mean()), 4)
    (array([0.5, 2. ]), 7.0)
    >>> round(float(res.phase.sel(order=2).mean()), 4)
    0.3
    """
    method = check_option(method, "method", _METHODS, error=AnalysisError)
    if method == "auto" and (revolutions is not None or samples_per_rev is not None):
        method = "cot"                     # a block length asked for: computed order tracking
    factor = amplitude_factor(amplitude)
    orders = _check_orders(orders)
    options = dict(orders=orders, amplitude=amplitude, method=method,
                   samples_per_rev=samples_per_rev, revolutions=revolutions, overlap=overlap,
                   window=window, interpolation=interpolation, bandwidth_hz=bandwidth_hz,
                   bandwidth_orders=bandwidth_orders, filter_order=filter_order, trend=trend,
                   min_bandwidth_orders=min_bandwidth_orders)
    masked = _dropout_spans(x, fs)
    if masked is not None:
        return _track_around_dropouts(x, fs, masked, speed_rpm=speed_rpm,
                                      shaft_angle=shaft_angle, **options)
    stops = _stopped_spans(x, fs, speed_rpm)
    if stops is not None:
        return _track_running_spans(x, fs, speed_rpm, stops, shaft_angle=shaft_angle, **options)
    values, fs_, units, label = _as_signal(x, fs)
    n = values.shape[0]
    angle, reference = _angle_input(shaft_angle, speed_rpm, n)
    speed = _as_rpm(speed_rpm, n, fs_)
    _check_nyquist(float(orders.max()), float(speed.max()), fs_, label)
    from .resample import shaft_angle as integrate

    phi = integrate(speed, fs_) if angle is None else angle
    from .trend import remove_trend

    attrs = getattr(x, "attrs", {}) or {}
    values, trend_info = remove_trend(values, fs_, phi=phi, speed_rpm=speed, kind=trend,
                                      quantity=attrs.get("quantity"), units=units)
    context = dict(values=values, fs=fs_, speed=speed, phi=phi, angle=angle, units=units,
                   label=label, t0=_t0(x), factor=factor, reference=reference)
    short = None
    adaptive = method == "auto" and bandwidth_hz is None and bandwidth_orders is None
    if adaptive:
        from .autotrack import short_record_blocks

        short = short_record_blocks(phi, speed, fs_, orders)
    if short is None and method == "auto":
        from .autotrack import auto_track

        ds = auto_track(context, **options)
        lines = ds.attrs.get("auto_joint_lines") if adaptive else None
        if lines:  # lines beside the orders in a short record: COT after all
            short = short_record_blocks(phi, speed, fs_, orders, lines=lines)
    if short is not None:             # too short for the adaptive filter: COT, stated
        revs, win, why = short
        ds = _cot_track(context, orders, samples_per_rev=samples_per_rev, revolutions=revs,
                        overlap=overlap, window=win, interpolation=interpolation)
        ds.attrs["auto_settings"] = (f"computed order tracking, {revs}-revolution {win} "
                                     f"blocks: {why}")
        log.info("order_track: %s", ds.attrs["auto_settings"])
    elif method == "vkf":
        ds = _vkf_track(context, orders, bandwidth_hz=bandwidth_hz,
                        bandwidth_orders=bandwidth_orders, filter_order=filter_order)
    elif method == "cot":             # ('auto' has its track from the adaptive filter above)
        ds = _cot_track(context, orders, samples_per_rev=samples_per_rev,
                        revolutions=revolutions, overlap=overlap, window=window,
                        interpolation=interpolation)
    ds.attrs.update({"amplitude_convention": amplitude, "trend": trend_info["removed"],
                     "trend_kind": trend_info["kind"]})
    return ds


def _vkf_track(context, orders, *, bandwidth_hz, bandwidth_orders, filter_order):
    """VKF of the prepared channel, as an order-track Dataset with the smearing estimate."""
    from .vkf import _vold_kalman_arrays

    res = _vold_kalman_arrays(context["values"], fs=context["fs"], speed_rpm=context["speed"],
                              orders=orders, bandwidth_hz=bandwidth_hz,
                              bandwidth_orders=bandwidth_orders, filter_order=filter_order,
                              shaft_angle=context["phi"], checked=True)
    return _vkf_dataset(res, context, orders)


def _vkf_dataset(res, context, orders):
    """Order-track Dataset of a VKF result: the ``vold_kalman`` Dataset or its arrays (dict)."""
    amp = None
    if isinstance(res, dict):
        env, mean, time = res["envelope"].T, res["mean"], res["time"]
        amp = res["amplitude"].T if "amplitude" in res else None
        rpm, unc, noise = res["rpm"], res["uncertainty"].T, res["noise"].T
        attrs = res["attrs"]
    else:
        env, mean, time = res["envelope"].values, res["mean"].values, res["time"].values
        rpm, unc = res["rpm"].values, res["amplitude_uncertainty"].values
        noise, attrs = res["amplitude_noise"].values, res.attrs
    factor, units = context["factor"], context["units"]
    if factor != 1.0:                   # (peak amplitudes, the default, need no pass)
        unc, noise = unc * factor, noise * factor
    amp = np.abs(env) if amp is None else amp
    ds = _track_dataset(amp * factor if factor != 1.0 else amp, np.angle(env),
                        orders, time + context["t0"] if context["t0"] else time, rpm,
                        units, context["label"], context["reference"], variables={
                            "mean": ("time", mean, {"units": units, "long_name": "order 0: "
                                                    "the channel's mean (trend envelope)"}),
                            "amplitude_uncertainty": (("order", "time"), unc, {
                                "units": units, "long_name": "1-sigma amplitude uncertainty "
                                "(noise and envelope smearing)"}),
                            "amplitude_noise": (("order", "time"), noise, {
                                "units": units, "long_name": "1-sigma amplitude noise (its "
                                "part of the uncertainty)"})})
    ds.attrs.update(attrs)
    ds.attrs["phase_reference"] = context["reference"]
    return ds


def cot_settings(speed, fs, orders, *, revolutions=None, samples_per_rev=None):
    """Block length and angle sampling of COT for this speed and these orders.

    ``revolutions``: at least 4 bins between neighbouring orders (and order 0), so every
    order is outside the others' Hann main lobe; at most what keeps the envelope smearing of a
    Q = 20 resonance crossed at the record's sweep rate below ~0.5 % (a block spans ≤ 1/5 of
    the half-power crossing time); 16 when nothing constrains; even (half orders on bins).

    Examples
    --------
    >>> cot_settings(np.full(10000, 1500.0), 2000.0, [0.5, 1.0, 1.5])
    (16, 64)
    """
    orders = np.asarray(orders, float)
    spr = default_samples_per_rev(float(orders.max())) if samples_per_rev is None else \
        check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    if revolutions is not None:
        return check_int(revolutions, "revolutions", minimum=1, error=AnalysisError), spr
    o = np.sort(np.concatenate([[0.0], orders]))
    need = int(np.ceil(4.0 / float(np.min(np.diff(o)))))
    from .autotrack import sweep_rate

    rate = sweep_rate(speed, fs)
    revs = 16
    if rate > 0:
        n = float(np.median(speed))
        # crossing time of the half-power band of a Q = 20 resonance at order o_max
        f_order = float(orders.max()) * n / 60.0
        t_cross = (f_order / 20.0) / (float(orders.max()) * rate / 60.0)
        revs = int(np.clip(np.floor(0.2 * t_cross * n / 60.0), 2, 16))
    revs = max(revs, need)
    revs += revs % 2
    return int(revs), spr


def _cot_track(context, orders, *, samples_per_rev, revolutions, overlap, window,
               interpolation):
    values, fs, speed = context["values"], context["fs"], context["speed"]
    revolutions, spr = cot_settings(speed, fs, orders, revolutions=revolutions,
                                    samples_per_rev=samples_per_rev)
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    check_option(interpolation, "interpolation", INTERPOLATIONS, error=AnalysisError)
    if orders.max() > spr / 4 + 1e-12:
        raise AnalysisError(
            f"order {orders.max():g} exceeds samples_per_rev/4 = {spr / 4:g} (the anti-alias "
            f"pass band); use samples_per_rev >= {int(np.ceil(4 * orders.max()))}")
    _check_nyquist(float(orders.max()), float(speed.max()), fs, context["label"])
    fitter = BlockFit(orders, spr, revolutions, window)
    fitter.check_spacing()
    y, t_rel, rpm, angle, plan = resample_arrays(
        values, fs, speed, samples_per_rev=spr, interpolation=interpolation,
        angle=context["angle"] if context["angle"] is not None else context["phi"],
        label=context["label"])
    length = fitter.length
    starts = _frames(y.shape[0], length, overlap)
    if starts.shape[0] == 0:
        raise AnalysisError(
            f"{context['label']}: the record covers {y.shape[0] / spr:.4g} revolutions, fewer "
            f"than one block of revolutions={revolutions}; lower revolutions")
    coef = np.empty((starts.shape[0], orders.shape[0]), dtype=complex)
    mean, floor, level = (np.empty(starts.shape[0]) for _ in range(3))
    spec = np.empty((starts.shape[0], fitter.bins.stop - 1), dtype=complex)
    for sl in _frame_batches(starts):
        frames = y[starts[sl, None] + np.arange(length)[None, :]]
        coef[sl], mean[sl], floor[sl], level[sl], spec[sl] = fitter.fit(
            frames, angle[starts[sl]], spectra=True)
    floor = fitter.line_free_floor(spec, floor, angle[starts], _hop(length, overlap))
    from .leakage import check_grid_leakage

    leaked = check_grid_leakage(fitter, y, starts, angle, coef, context["label"])
    t, r, span = _block_coords(t_rel, rpm, starts, length, fitter.centroid)
    return _cot_dataset(coef, mean, floor, fitter, t + context["t0"], r, span, context,
                        overlap=overlap, interpolation=plan.interpolation, plan=plan,
                        level=level, leaked=leaked)


def _cot_dataset(coef, mean, floor, fitter, t, r, span, context, *, overlap, interpolation,
                 plan=None, level=None, leaked=False):
    """The COT order-track Dataset (shared by the in-memory and streamed trackers);
    ``level``: each block's rms (:meth:`BlockFit.fit`), for the smearing warning's floor;
    ``leaked``: a grid line was found leaking into the blocks (the smearing warning says it may
    be its cause)."""
    factor = context["factor"]
    orders = fitter.orders
    units, label = context["units"], context["label"]
    noise = fitter.noise(floor)
    bias = smearing_bias(coef, t, span, fitter.mu2, r)
    _warn_block_smearing(coef, bias, r, fitter, label, noise, level, leaked=leaked)
    ds = _track_dataset(np.abs(coef).T * factor, np.angle(coef).T, orders, t, r, units, label,
                        context["reference"])
    ds["mean"] = ("time", mean, {"units": units, "long_name":
                                 "order 0: block mean of the channel"})
    ds["amplitude_noise"] = ("time", np.sqrt(floor * fitter.enbw) * factor,
                             {"units": units, "long_name":
                              "1-sigma amplitude error from the broadband noise floor"})
    ds["amplitude_uncertainty"] = (("order", "time"), np.hypot(noise, bias).T * factor,
                                   {"units": units, "long_name":
                                    "1-sigma amplitude uncertainty (noise, least-squares gain "
                                    "and block smearing of the envelope)"})
    ds.attrs.update({"method": "computed order tracking (angle resampling + block least "
                               "squares at the orders)",
                     "window": str(fitter.window), "samples_per_rev": fitter.spr,
                     "revolutions": fitter.revolutions,
                     "resolution_orders": 1.0 / fitter.revolutions, "overlap": overlap,
                     "interpolation": interpolation, "enbw_bins": fitter.enbw,
                     "noise_gain": fitter.noise_gain.tolist(),
                     "decimation": list(plan.decimation) if plan is not None else []})
    return ds


def _block_coords(t_rel, rpm, starts, length, centroid=None):
    """Time (s, from the first sample), speed and duration of each block; ``centroid``: the
    window's centroid in samples from the block's first (default its middle)."""
    centre = starts + (length / 2.0 - 0.5 if centroid is None else centroid)
    from ._kernels import lerp

    t, r = lerp(t_rel, centre, 0), lerp(rpm, centre, 0)
    span = t_rel[starts + length - 1] - t_rel[starts]
    return t, r, span


# ---------------------------------------------------------------------------- unusable spans


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


def _result_window(ds, options):
    """Half-width (s) of each result's analysis window plus one revolution of guard."""
    rev = 60.0 / ds["rpm"].values
    if "bandwidth_hz_min" in ds.attrs:
        return 2.0 / float(ds.attrs["bandwidth_hz_min"]) + rev
    return (0.5 * float(ds.attrs.get("revolutions", 16)) + 1.0) * rev


def _track_around_dropouts(x, fs, spans, *, speed_rpm, shaft_angle, **options):
    """Order-track a signal with dropouts (NaN/inf runs, e.g. a record read with
    ``allow_nonfinite=True``): the runs are bridged by linear interpolation for the computation
    only, and every result whose analysis window reaches a run is set to NaN, with a warning
    naming the spans. The window is the block (``revolutions``) for COT and ±2/bandwidth
    (the filter's memory: outside it the bridged gap moves a 2nd-order VKF track by ~1e-4
    relative) for VKF, plus one revolution of guard."""
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
    ds = order_track(signal, fs=fs, speed_rpm=speed_rpm, shaft_angle=shaft_angle, **options)
    half = _result_window(ds, options)
    t = ds["time"].values
    hit = np.zeros(t.shape[0], bool)
    for a, b in times:
        hit |= (t + half >= a) & (t - half <= b)
    for name in ("amplitude", "phase", "amplitude_uncertainty", "amplitude_noise", "mean"):
        if name in ds:
            ds[name] = ds[name].where(~hit)
    ds.attrs["masked_spans_s"] = [v for span in times for v in span]
    return ds


def _track_running_spans(x, fs, speed_rpm, stops, *, shaft_angle, compute=None,
                         what="orders are tracked", **options):
    """Track each span where the shaft turns (the record stops and restarts); results of the
    standing spans are absent and a warning names them. ``compute`` (default
    :func:`order_track`) may be :func:`analysis.order_map` (no shaft angle: integrated per
    span)."""
    import xarray as xr

    values, fs_, units, label = _as_signal(x, fs)
    speed = np.asarray(getattr(speed_rpm, "values", speed_rpm), dtype=float)
    angle = None if shaft_angle is None else np.asarray(getattr(shaft_angle, "values",
                                                                shaft_angle), float)
    if angle is None and hasattr(speed_rpm, "coords") and "shaft_angle" in speed_rpm.coords:
        angle = np.asarray(speed_rpm.coords["shaft_angle"].values, float)
    t0 = _t0(x)
    n = values.shape[0]
    from .spans import running_spans

    runs, shown = running_spans(stops, n, t0=t0, fs=fs_)
    warnings.warn(f"{label}: the shaft stands (speed <= 0.5 % of {speed.max():.6g} rpm) at "
                  f"{shown}; {what} in each running span separately",
                  OrderWarning, stacklevel=3)
    parts, skipped = [], []
    attrs = getattr(x, "attrs", {}) or {}
    for a, b in runs:
        sub = xr.DataArray(values[a:b], dims=("time",),
                           coords={"time": t0 + np.arange(a, b) / fs_},
                           attrs={**attrs, "sample_rate": fs_}, name=label)
        try:
            if compute is None:
                ds = order_track(sub, speed_rpm=speed[a:b],
                                 shaft_angle=None if angle is None else angle[a:b], **options)
            else:
                ds = compute(sub, speed_rpm=speed[a:b], **options)
        except AnalysisError as exc:
            skipped.append(f"{t0 + a / fs_:.6g}..{t0 + (b - 1) / fs_:.6g} s ({exc})")
            continue
        parts.append(ds)
    from .spans import join_running_spans

    return join_running_spans(parts, skipped, stops, label=label, t0=t0, fs=fs_)


def _track_dataset(amp, phase, orders, t, r, units, label, reference=None, variables=None):
    """Order-track Dataset (amplitude, phase; ``variables``: more data variables, built in the
    same constructor — each later assignment costs a merge)."""
    import pandas as pd
    import xarray as xr

    # Variables and the two indexes built once and handed over: the tuple form had xarray
    # convert each entry and infer both indexes again; they agree by construction, so no merge
    from ._dataset import dataset

    var = xr.Variable
    t = np.asarray(t, float)
    return dataset(
        {"amplitude": var(("order", "time"), amp, {"units": units,
                                                   "long_name": f"{label} order amplitude"}),
         "phase": var(("order", "time"), phase, {"units": "rad",
                                                  "long_name": "phase of A cos(o φ + phase)"}),
         **{name: var(*spec) for name, spec in (variables or {}).items()}},
        {"order": var("order", orders, {"units": "1", "long_name": "shaft order"}),
         "time": var("time", t, {"units": "s"}),
         "rpm": var("time", np.asarray(r, float), {"units": "rpm", "long_name": "shaft speed"})},
        {"order": xr.indexes.PandasIndex(pd.Index(orders, name="order"), "order"),
         "time": xr.indexes.PandasIndex(pd.Index(t, name="time"), "time")},
        {"channel": str(label), "phase_reference": reference or
         "shaft angle 0 at the first sample of the record (speed-reference integration)"})


_MAP_NAMES = ("order_map", "order_spectrum", "band_amplitude", "campbell_map")


def __getattr__(name):
    """The order map and its relatives live in :mod:`analysis.ordermap` (re-exported)."""
    if name in _MAP_NAMES:
        from . import ordermap

        return getattr(ordermap, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
