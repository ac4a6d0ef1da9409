"""Order map, order spectrum, band amplitudes and the rpm–frequency (Campbell) map.

``order_map`` — the order spectrum of each block of revolutions (rfft of the angle-domain
block): the picture of every order against speed. Its amplitude per bin is the *coherent*
(peak) amplitude; with ``scaling="power"`` each bin holds mean-square, so that
:func:`band_amplitude` can sum the energy of an order band (an order between bins loses
nothing). Each block's weighted mean and slope (the channel's trend: a speed channel's mean, a
sensor's drift) are removed before its window and rfft and reported as order 0 (the block
mean), so no trend leaks into low orders. Same resolution trade-off as COT
(:mod:`analysis.orders`).

References
----------
G. Heinzel, A. Rüdiger, R. Schilling, "Spectrum and spectral density estimation by the DFT",
Max-Planck-Institut report (2002), §9–10 (window normalisation, ENBW, band power).
"""

from __future__ import annotations

import functools
import logging

import numpy as np

from crankbench.predict._deprecate import renamed
from crankbench.predict._validate import (check_finite_array, check_int, check_option,
                                          check_positive, check_range)
from crankbench.predict.errors import AnalysisError

from .orders import (_block_coords, _check_order_range, _check_orders, _frame_batches, _frames,
                     _scale_spectrum, _stopped_spans, _track_running_spans,
                     _t0, amplitude_factor, get_window)
from .resample import (_angle_input, _as_rpm, _as_signal, angle_resample, angle_samples,
                       plan_chunks, resample_span)
from .trend import remove_trend

__all__ = ["order_map", "order_spectrum", "band_amplitude", "campbell_map"]

log = logging.getLogger("crankbench")


# ---------------------------------------------------------------------------- order map


class MapSpectra:
    """Order spectra of angle-domain blocks with each block's trend removed first.

    The weighted (window, negative lobes clipped) least-squares constant and slope of each block
    are removed -- their windowed spectrum subtracted from the block's, the same as removing
    them before the window and the rfft (linearity) for one pass less; the constant (the
    block mean) is then put in bin 0 (amplitude: its magnitude; power: its square), so the
    channel's mean and drift cannot leak into low orders. Shared by :func:`order_map` and
    :func:`analysis.stream.order_map_stream`.
    """

    def __init__(self, length: int, window, scaling: str, factor: float, n_orders: int):
        from scipy import fft

        self.w = w = get_window(window, length)
        self.length, self.scaling, self.factor, self.n_orders = length, scaling, factor, n_orders
        s = np.linspace(-1.0, 1.0, length)
        basis = np.stack([np.ones(length), s], axis=1)
        weight = np.clip(w, 0.0, None)            # flat-top windows dip below zero
        gram = basis.T @ (basis * weight[:, None])
        self.proj = np.ascontiguousarray(np.linalg.solve(gram, (basis * weight[:, None]).T).T)
        # the trend's windowed spectrum: subtracted after the transform (linear), which spares
        # a pass over every block
        self.trend_spectra = fft.rfft(basis.T * w, axis=1)[:, :n_orders]
        self.enbw = float(length * np.sum(w ** 2) / np.sum(w) ** 2)
        # a block's time is its window's centroid (samples from its first; a periodic Hann's
        # is length/2, half a sample after the middle): where the envelope is a ramp, the
        # estimate is the envelope there
        self.centroid = float(np.sum(np.arange(length) * w) / np.sum(w))

    def __call__(self, frames: np.ndarray, own: bool = False) -> np.ndarray:
        """Order spectra (blocks, orders) of ``frames`` (blocks, samples); ``own``: the
        caller's own copy, windowed in place."""
        from scipy import fft

        coef = frames @ self.proj
        if own:
            frames *= self.w
        else:
            frames = frames * self.w
        spectra = fft.rfft(frames, axis=1, overwrite_x=True)[:, :self.n_orders]
        spectra -= coef @ self.trend_spectra
        out = _scale_spectrum(spectra, self.w, self.scaling, self.factor)
        out[:, 0] = np.abs(coef[:, 0]) if self.scaling == "amplitude" else coef[:, 0] ** 2
        return out


def _map_spectra(length, window, scaling, factor, n_orders):
    """A cached :class:`MapSpectra` (its window and trend projection are set up once)."""
    try:
        return _cached_map_spectra(length, window, scaling, factor, n_orders)
    except TypeError:                       # an unhashable window spec
        return MapSpectra(length, window, scaling, factor, n_orders)


@functools.lru_cache(maxsize=32)
def _cached_map_spectra(length, window, scaling, factor, n_orders):
    return MapSpectra(length, window, scaling, factor, n_orders)


@renamed(rpm="speed_rpm", rpm_bins="speed_bins_rpm")
def order_map(x, *, fs=None, speed_rpm, samples_per_rev: int = 64, revolutions: int = 16,
              overlap: float = 0.5, window="hann", amplitude: str = "peak",
              scaling: str = "amplitude", max_order=None, speed_bins_rpm=None,
              interpolation: str = "auto", trend: str = "auto"):
    """Order spectrum of each block of revolutions: the order map (time or rpm × order).

    Parameters
    ----------
    x, fs, speed_rpm
        Signal, sample rate (Hz) and shaft speed (rpm per sample) as in :func:`order_track`
        (a ``shaft_angle`` coordinate of the speed is used for the resampling).
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
    trend : {'auto', 'none', 'angle ramp', 'speed mean'}
        As in :func:`order_track`; each block's mean and slope are removed in any case and the
        mean shown at order 0.

    Returns
    -------
    xarray.DataArray
        Order map with units in attrs and the parameters used; order 0 holds the block mean.

    Examples
    --------
    >>> fs = 4000.0
    >>> t = np.arange(int(6 * fs)) / fs
    >>> rpm = 1200 + 100 * t
    >>> from crankbench.analysis.resample import shaft_angle
    >>> x = 0.7 * np.cos(3 * shaft_angle(rpm, fs)) + 2.0
    >>> m = order_map(x, fs=fs, speed_rpm=rpm, revolutions=8)
    >>> round(float(m.sel(order=3).mean()), 4), round(float(m.sel(order=0).mean()), 4), m.dims
    (0.7, 2.0, ('time', 'order'))
    """
    scaling = check_option(scaling, "scaling", ("amplitude", "power"), error=AnalysisError)
    factor = amplitude_factor(amplitude)
    spr = check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    revolutions = check_int(revolutions, "revolutions", minimum=1, error=AnalysisError)
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    top = spr / 4.0 if max_order is None else check_positive(max_order, "max_order",
                                                             error=AnalysisError)
    limits, running, extremes = _running_throughout(x, speed_rpm)
    stops = None if running or np.isscalar(speed_rpm) else _stopped_spans(x, fs, speed_rpm)
    if stops is not None:   # a record that stops: the map of each running span, as tracks
        m = _track_running_spans(
            x, fs, speed_rpm, stops, shaft_angle=None, compute=order_map,
            what="the order map is computed", samples_per_rev=spr, revolutions=revolutions,
            overlap=overlap, window=window, amplitude=amplitude, scaling=scaling,
            max_order=max_order, interpolation=interpolation, trend=trend)
        if speed_bins_rpm is None:
            return m
        return _speed_binned(m.values, m["rpm"].values, speed_bins_rpm, scaling, dict(m.attrs),
                             ("order", m["order"].values, dict(m["order"].attrs)),
                             str(m.name).removesuffix(" order map"))
    values, fs_, units, label = _as_signal(x, fs)
    n = values.shape[0]
    angle, reference = _angle_input(None, speed_rpm, n)
    speed = (getattr(speed_rpm, "values", speed_rpm) if running
             else _as_rpm(speed_rpm, n, fs_))
    if max_order is not None:
        _check_order_range(top, spr, values, fs_, speed, divisor=2)
    # the plan from the speed alone; the shaft angle and the angle samples' positions in one
    # pass; the channel's trend (by that angle) removed before the anti-alias filter
    plan = plan_chunks(speed, n=n, fs=fs_, samples_per_rev=spr, interpolation=interpolation,
                       speed_limits_rpm=limits, clean_order=top, span_extremes=extremes)
    phi, j0, j1, positions = angle_samples(plan, speed, angle=angle, label=label,
                                           speed_max=None if limits is None else limits[1])
    attrs_in = getattr(x, "attrs", {}) or {}
    values, trend_info = remove_trend(values, fs_, phi=phi, speed_rpm=speed, kind=trend,
                                      quantity=attrs_in.get("quantity"), units=units)
    y, t_rel, r_s, _ = resample_span(plan, range(plan.chunks), values, 0, phi, speed, j0, j1,
                                     last=True, positions=positions)
    length = spr * revolutions
    starts = _frames(y.shape[0], length, overlap)
    if starts.shape[0] == 0:
        raise AnalysisError(
            f"{label}: the record covers {y.shape[0] / spr:.4g} revolutions, fewer than one "
            f"block of revolutions={revolutions}; lower revolutions")
    n_orders = min(length // 2 + 1, int(np.floor(top * revolutions)) + 1)
    spectra = _map_spectra(length, window, scaling, factor, n_orders)
    out = np.empty((starts.shape[0], n_orders))
    # every block start as a row (a strided view, no copy; rows gathered per batch)
    blocks = np.lib.stride_tricks.as_strided(y, (y.shape[0] - length + 1, length),
                                             (y.strides[0], y.strides[0]), writeable=False)
    for sl in _frame_batches(starts):
        out[sl] = spectra(blocks[starts[sl]], own=True)     # (gathered: a copy)
    values = out
    order_axis = np.arange(n_orders) / revolutions
    t, r, _ = _block_coords(t_rel, r_s, starts, length, spectra.centroid)
    t = t + _t0(x)
    out_units = units if scaling == "amplitude" else (f"({units})^2" if units else "1")
    attrs = {"units": out_units, "method": "order map (angle resampling + block rfft, block "
                                           "trend removed; order 0 = block mean)",
             "scaling": scaling, "amplitude_convention": amplitude if scaling == "amplitude"
             else "mean-square per bin", "window": str(window), "samples_per_rev": spr,
             "revolutions": revolutions, "resolution_orders": 1.0 / revolutions,
             "overlap": overlap, "interpolation": plan.interpolation,
             "enbw_bins": spectra.enbw, "trend": trend_info["removed"],
             "phase_reference": reference}
    order_coord = ("order", order_axis, {"units": "1", "long_name": "shaft order"})
    if speed_bins_rpm is None:
        return _labelled_map(values, t, r, order_coord, attrs, f"{label} order map")
    return _speed_binned(values, r, speed_bins_rpm, scaling, attrs, order_coord, label)


def _running_throughout(x, speed_rpm):
    """``((min, max) speed, True, extremes)`` when ``speed_rpm`` is a finite float64 array,
    one value per sample of ``x``, above 0.5 % of its maximum everywhere (no stop, nothing for
    :func:`_as_rpm` to refuse), found from the extremes of its blocks (two vectorised passes;
    NaN and inf show in them), which then serve every span the plan asks about
    (:class:`analysis.speed_spans.SpanExtremes`); else ``(None, False, None)`` (the full checks
    then run)."""
    from .speed_spans import SpanExtremes

    speed = getattr(speed_rpm, "values", speed_rpm) if hasattr(speed_rpm, "dims") else speed_rpm
    if not (isinstance(speed, np.ndarray) and speed.dtype == np.float64 and speed.ndim == 1
            and speed.shape[0] == np.shape(getattr(x, "values", x))[0] and speed.shape[0]):
        return None, False, None
    extremes = SpanExtremes(speed)
    lo, hi = extremes.limits()
    if np.isfinite(lo) and np.isfinite(hi) and hi > 0 and lo > 5e-3 * hi:
        return (lo, hi), True, extremes
    return None, False, None


def _labelled_map(values, t, r, order_coord, attrs, name):
    """The (time × order) DataArray with its two indexes built directly: the variables and
    :class:`xarray.indexes.PandasIndex` objects handed to the constructor's ``fastpath``
    (0.06 against 0.16 ms for the public :class:`xarray.Coordinates` route and 0.30 ms for
    xarray's own inference, measured); ``tests/analysis/test_ordermap_paths.py`` checks that
    the result is identical to the inferred one, and any error there falls back to the public
    route."""
    import pandas as pd
    import xarray as xr
    from xarray.indexes import PandasIndex

    time_index = PandasIndex(pd.Index(t, name="time"), "time")
    time_var = xr.Variable("time", t, {"units": "s"})
    try:
        order_index, order_ivar = _order_index(
            np.asarray(order_coord[1], dtype=np.float64).tobytes(),
            tuple(sorted(order_coord[2].items())))
        coords = {"time": time_index.create_variables({"time": time_var})["time"],
                  "rpm": xr.Variable("time", r, {"units": "rpm"}),
                  "order": order_ivar.copy(deep=False)}          # its own attrs dict
        return xr.DataArray(xr.Variable(("time", "order"), values, attrs), coords=coords,
                            name=name, indexes={"time": time_index, "order": order_index},
                            fastpath=True)
    except Exception:  # pragma: no cover - an xarray whose private route changed
        order_index = PandasIndex(pd.Index(order_coord[1], name="order"), "order")
        coords = xr.Coordinates(
            {"time": time_var, "rpm": xr.Variable("time", r, {"units": "rpm"}),
             "order": xr.Variable(*order_coord)},
            indexes={"time": time_index, "order": order_index})
        return xr.DataArray(values, coords=coords, dims=("time", "order"), attrs=attrs,
                            name=name)


@functools.lru_cache(maxsize=16)
def _order_index(axis_bytes: bytes, attrs: tuple):
    """An order axis (float64 values as bytes, attrs as sorted items) as an index and its
    index variable, made once per axis: the pandas index is immutable, and each map gets a
    shallow copy of the variable (its own attrs dict)."""
    import pandas as pd
    import xarray as xr
    from xarray.indexes import PandasIndex

    axis = np.frombuffer(axis_bytes, dtype=np.float64).copy()
    index = PandasIndex(pd.Index(axis, name="order"), "order")
    var = xr.Variable("order", axis, dict(attrs))
    return index, index.create_variables({"order": var})["order"]


def _speed_binned(values, r, speed_bins_rpm, scaling, attrs, order_coord, label):
    """Blocks of an order map (time × order) power-averaged into speed bins (rpm × order)."""
    import xarray as xr

    n_orders = values.shape[1]
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
    return xr.DataArray(binned[filled], dims=("rpm", "order"), name=f"{label} order map",
                        coords={"rpm": ("rpm", centres[filled], {"units": "rpm"}),
                                "blocks": ("rpm", counts[filled]), "order": order_coord},
                        attrs=attrs)


@renamed(rpm="speed_rpm")
def order_spectrum(x, *, fs=None, speed_rpm, samples_per_rev: int = 64, revolutions=None,
                   overlap: float = 0.5, window="hann", amplitude: str = "peak",
                   scaling: str = "amplitude", max_order=None, interpolation: str = "auto"):
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
    speed = _as_rpm(speed_rpm, values.shape[0], fs, allow_stop=True)  # frames of a stop: 0 rpm
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
