"""Speed and angle reference for a record channel: shaft speed (rpm) and shaft angle per sample.

Order analysis needs the shaft speed, and for phases the shaft angle, at every sample of the
analysed channel. A Record carries them as

* a ``rotational_speed`` channel (rad/s, possibly on another clock): interpolated linearly;
* a tacho/encoder pulse train (edge times with ``pulses_per_rev``, ``missing_teeth``, optional
  ``speed_ratio``, ``tdc_offset_deg``): the speed from :func:`measure.tacho.speed_from_pulses`
  (exact for constant angular acceleration; averaged over one revolution), and the *angle from
  the edges themselves* (:func:`measure.tacho.angle_from_pulses`: counted, so it cannot drift;
  zero at TDC of cylinder 1 when the wheel has a gap or a reference mark, moved by
  ``tdc_offset_deg``);
* an encoder *angle* channel (quantity ``angle`` that follows the shaft's rotation, possibly
  wrapped; ``speed_ratio`` turns per crankshaft turn): its own angle, and the speed from it;
* an instantaneous-angular-speed (IAS) channel (quantity ``angular_velocity`` in rad/s carrying
  the mean speed): the speed from it, the angle by integration.

The angle attached to the speed (the ``shaft_angle`` coordinate, rad) is the source's angle
averaged over whole engine cycles (:func:`analysis.trend.mean_rotation`): the shaft's mean
rotation, without its torsional vibration or tooth-spacing errors, which would otherwise
modulate the resampling. A pulse train anywhere in the record gives this angle (and the TDC
reference) even when the speed comes from a speed channel. ``attrs['angle_reference']`` says
what the zero is.

Checks before any result: the speed source must overlap the channel's time span (no overlap,
or less than half of it, is refused; a shorter gap is held at the end value with a warning),
a zero-length channel or source is refused, and — where the record sweeps and the signal has
order-locked content — the speed must agree with the signal's own order lines
(:func:`analysis.speedcheck.check_speed_reference`: a speed clock 10× off is refused, not
tracked into wrong amplitudes).

Error: linear interpolation of the speed adds ``(Δt)² |d²n/dt²| / 8`` rpm between speed samples;
the pulse angle is exact at the edges and interpolated by a cubic spline between them
(``|ω''| Δt³/12`` per pitch time ``Δt``).

References
----------
交通大学《内燃机动力学》(1958) 第二篇第五章 §1 (time and angle marks on torsiograph records).
"""

from __future__ import annotations

import logging
import warnings

import numpy as np
import xarray as xr

from crankbench.predict._validate import suggest
from crankbench.predict.errors import AnalysisError, RecordError

__all__ = ["speed_reference", "find_speed_channel", "SpeedReferenceWarning"]

log = logging.getLogger("crankbench")

_TWO_PI = 2.0 * np.pi


class SpeedReferenceWarning(UserWarning):
    """The speed source covers the channel only in part (held at its end values)."""


def _is_pulses(var) -> bool:
    return var.attrs.get("quantity") == "pulse_times" or (
        len(var.dims) == 1 and str(var.dims[0]).split("_")[0] == "pulse")


def _times(record, name: str) -> np.ndarray:
    var = record[name]
    if _is_pulses(var):
        return np.asarray(var.values, dtype=float)
    dim = var.dims[0]
    if dim in record.coords:
        return np.asarray(record[dim].values, dtype=float)
    rate = var.attrs.get("sample_rate")
    if rate is None:
        raise RecordError(f"channel {name!r}: dim {dim!r} has no time coordinate and no "
                          "sample_rate attr")
    return np.arange(var.shape[0]) / float(rate)


def _ratio(var, name) -> float:
    ratio = float(var.attrs.get("speed_ratio", 1.0))
    if not np.isfinite(ratio) or ratio <= 0:
        raise AnalysisError(f"channel {name!r}: speed_ratio={ratio!r}; expected > 0 (turns of "
                            "the source per crankshaft turn)")
    return ratio


def _is_angle_source(var) -> bool:
    """An encoder angle channel: quantity 'angle' in rad that turns with the shaft (its span
    is many revolutions, far more than any torsional vibration)."""
    if var.attrs.get("quantity") != "angle" or var.ndim != 1 or var.shape[0] < 8:
        return False
    values = np.asarray(var.values, float)
    values = values[np.isfinite(values)]
    if values.size < 8:
        return False
    unwrapped = np.unwrap(values) if np.ptp(values) <= _TWO_PI + 1e-6 else values
    return abs(float(unwrapped[-1] - unwrapped[0])) > 4.0 * _TWO_PI


def _is_ias_source(var) -> bool:
    """An IAS channel: angular velocity (rad/s) whose mean is the shaft speed (mean at least
    5× its spread and above 1 rad/s)."""
    if var.attrs.get("quantity") not in ("angular_velocity",) or var.ndim != 1:
        return False
    if str(var.attrs.get("units", "rad/s")) != "rad/s":
        return False
    values = np.asarray(var.values, float)
    values = values[np.isfinite(values)]
    if values.size < 8:
        return False
    mean = float(np.mean(values))
    return abs(mean) > 1.0 and abs(mean) >= 5.0 * float(np.std(values))


def find_speed_channel(record, channel: str | None = None) -> str:
    """Name of the record's speed source.

    In order of preference: a ``rotational_speed`` channel, a pulse train, an encoder angle
    channel (quantity 'angle' turning with the shaft), an IAS channel (quantity
    'angular_velocity' carrying the mean speed); within each kind, one on the same clock as
    ``channel`` (and not ``channel`` itself, unless it is the only source).

    Examples
    --------
    >>> import xarray as xr
    >>> rec = xr.Dataset({"n": ("time", np.full(4, 100.0), {"quantity": "rotational_speed",
    ...                                                      "units": "rad/s"})})
    >>> find_speed_channel(rec)
    'n'
    """
    names = [str(n) for n in record.data_vars]
    speeds = [n for n in names if record[n].attrs.get("quantity") == "rotational_speed"]
    pulses = [n for n in names if _is_pulses(record[n])]
    angles = [n for n in names if n != channel and _is_angle_source(record[n])]
    ias = [n for n in names if n != channel and _is_ias_source(record[n])]
    if not (speeds or pulses or angles or ias) and channel in names:
        # the channel itself may be the only source (an IAS or encoder angle analysed alone)
        angles = [channel] if _is_angle_source(record[channel]) else []
        ias = [channel] if _is_ias_source(record[channel]) else []
    for group in (speeds, pulses, angles, ias):
        if group:
            if channel is not None and channel in record.data_vars:
                same = [n for n in group if record[n].dims == record[channel].dims]
                if same:
                    return same[0]
            if len(group) > 1:
                log.info("several speed sources (%s); using %r", ", ".join(group), group[0])
            return group[0]
    raw = [n for n in names if n != channel and _raw_pulses(record[n])]
    raise AnalysisError(f"record has no speed reference: no channel with quantity "
                        f"'rotational_speed', no pulse train, no encoder angle or IAS channel; "
                        f"channels: {', '.join(names)}" + (_decode_hint(raw[0]) if raw else ""))


def _raw_pulses(var) -> bool:
    """A voltage channel that switches between two levels (a tacho, wheel pick-up or TDC
    mark recorded raw): at least 90 % of its samples within 15 % of its range of the two
    extreme levels, and at least 8 switchings."""
    if var.ndim != 1 or str(var.attrs.get("units", "")) not in ("V", "mV") or var.shape[0] < 64:
        return False
    values = np.asarray(var.values, float)
    values = values[np.isfinite(values)]
    if values.size < 64:
        return False
    lo, hi = np.percentile(values, [1, 99])
    if not hi > lo:
        return False
    near = (np.abs(values - lo) <= 0.15 * (hi - lo)) | (np.abs(values - hi) <= 0.15 * (hi - lo))
    switches = int(np.count_nonzero(np.diff((values > 0.5 * (lo + hi)).astype(np.int8))))
    return bool(near.mean() >= 0.9 and switches >= 8)


def _decode_hint(name: str) -> str:
    """The channel-map lines that decode raw pulse channel ``name``."""
    return (f". Channel {name!r} looks like a raw pulse signal (two voltage levels): decode it "
            "with a channel map (--map MAP.toml) holding\n  [source]\n  keep_unmapped = true"
            f"     # the other columns as their headers say\n  [channel.{name}]\n"
            f"  column = \"{name}\"    # or its number, 1-based\n  role = \"wheel\"\n"
            "  pulses_per_rev = <teeth, or 1 for a once-per-revolution mark>\n"
            "  (or role = \"tdc\" for a TDC mark; see sample_data/raw/genset_60-2_map.toml)")


#: decoded pulse trains (speed, angle) by content: one record's channels all take the same
#: reference, decoded (and its repairs logged) once
_DECODED: dict = {}


def _decoded(kind, var, name, make):
    edges = np.ascontiguousarray(np.asarray(var.values, dtype=float))
    layout = tuple(str(var.attrs.get(k)) for k in ("pulses_per_rev", "missing_teeth",
                                                   "tdc_offset_deg", "speed_ratio"))
    key = (kind, name, edges.shape[0], layout, hash(edges.tobytes()))
    if key not in _DECODED:
        if len(_DECODED) >= 16:
            _DECODED.pop(next(iter(_DECODED)))
        _DECODED[key] = make()
    return _DECODED[key]


class _SameRepairs(logging.Filter):
    """Drops the tacho's repair report of a second decoding of the same edges (the speed's
    decoding reported it)."""

    def filter(self, record):
        return not str(record.msg).startswith("tacho:")


def _pulse_speed(var, name):
    """Speed trace (s, rad/s) of the crankshaft from a pulse channel (layout from its attrs)."""
    if var.attrs.get("pulses_per_rev") is None:
        raise RecordError(f"pulse channel {name!r} has no 'pulses_per_rev' attr")
    if var.shape[0] == 0:
        raise AnalysisError(f"pulse channel {name!r} holds no edges (zero-length channel)")
    from crankbench.measure.tacho import pulse_channel_speed  # reads the layout attrs

    def make():
        t, omega = pulse_channel_speed(var)
        return np.asarray(t, float), np.asarray(omega, float)

    t, omega = _decoded("speed", var, name, make)
    return t.copy(), omega.copy()


def _pulse_angle(var, name, t_out):
    """Crankshaft angle (rad) at ``t_out`` from the edges, and what its zero is."""
    at, reference = _pulse_angle_function(var, name)
    return at(t_out), reference


def _pulse_angle_function(var, name):
    """``(at, reference)``: ``at(t)`` the crankshaft angle (rad) from the edges at times ``t``
    (the same numbers for the whole channel or any span of it), ``reference`` its zero."""
    from crankbench.measure.tacho import angle_from_pulses

    missing = var.attrs.get("missing_teeth", 0)
    tdc = float(var.attrs.get("tdc_offset_deg", 0.0))

    def make():
        quiet = _SameRepairs()
        log.addFilter(quiet)
        try:
            return angle_from_pulses(np.asarray(var.values, dtype=float),
                                     pulses_per_rev=int(var.attrs["pulses_per_rev"]),
                                     missing_teeth=0 if missing is None else int(missing),
                                     tdc_offset_deg=tdc)
        finally:
            log.removeFilter(quiet)

    trace = _decoded("angle", var, name, make)
    ratio = _ratio(var, name)

    def at(t):
        return trace.at(t) / ratio

    if trace.reference in ("gap", "reference mark"):
        what = "wheel gap" if trace.reference == "gap" else "reference mark"
        reference = (f"TDC of cylinder 1: the {what} of pulse train {name!r} moved by "
                     f"tdc_offset_deg {tdc:g}")
    else:
        reference = (f"first edge of pulse train {name!r} (no gap or reference mark: not TDC)"
                     + (f", moved by tdc_offset_deg {tdc:g}" if tdc else ""))
    return at, reference


def _channel_angle(var, name, t_in):
    """An encoder angle channel as the crankshaft angle: unwrapped, divided by its ratio."""
    values = np.asarray(var.values, float)
    if np.ptp(values) <= _TWO_PI + 1e-6:
        values = np.unwrap(values)
    if values[-1] < values[0]:
        values = -values            # the encoder counts the other way: the shaft still turns
    tdc = float(var.attrs.get("tdc_offset_deg", 0.0))
    angle = values / _ratio(var, name) - np.radians(tdc)
    reference = (f"zero of encoder angle channel {name!r}" +
                 (f" moved by tdc_offset_deg {tdc:g}" if tdc else ""))
    return t_in, angle, reference


def _pulse_reference_channel(record, exclude=None):
    """A pulse train with a TDC reference to phase against, or None: a wheel with a gap first,
    then a once-per-revolution mark with a ``tdc_offset_deg``."""
    candidates = [str(n) for n in record.data_vars
                  if str(n) != exclude and _is_pulses(record[n])
                  and record[n].attrs.get("pulses_per_rev") and record[n].shape[0] > 8]
    for name in candidates:
        if int(record[name].attrs.get("missing_teeth", 0) or 0) > 0:
            return name
    for name in candidates:
        var = record[name]
        if int(var.attrs.get("pulses_per_rev")) == 1 and "tdc_offset_deg" in var.attrs:
            return name
    return None


def speed_reference(record, channel: str, *, speed_channel: str | None = None,
                    check: bool = True) -> xr.DataArray:
    """Shaft speed in rpm (and the shaft angle) at each time sample of ``channel``.

    Parameters
    ----------
    record : xarray.Dataset
        A Record (docs/DESIGN.md data model).
    channel : str
        The channel to be analysed (its time samples are where the speed is wanted).
    speed_channel : str, optional
        The speed source: a ``rotational_speed`` channel (rad/s), a pulse train (edge times,
        attrs ``pulses_per_rev``, ``missing_teeth``), an encoder angle channel or an IAS
        channel. Default: found by :func:`find_speed_channel`.
    check : bool
        Refuse a speed that contradicts the channel's own order content
        (:func:`analysis.speedcheck.check_speed_reference`).

    Returns
    -------
    xarray.DataArray
        Speed, rpm (``attrs["units"]``), one value per sample of ``channel``, on that channel's
        time coordinate (s), with a ``shaft_angle`` coordinate (rad) when the record holds an
        angle (pulses, encoder angle) and ``attrs["angle_reference"]`` naming its zero;
        ``attrs["source"]`` names where the speed came from. Pass it as ``speed_rpm=`` to the
        order trackers (they use the angle for resampling and phase).

    Raises
    ------
    RecordError
        Unknown channel or source, a zero-length channel.
    AnalysisError
        A source that does not overlap the channel (or covers less than half of it), a
        negative or never-positive speed, a speed inconsistent with the signal.

    Examples
    --------
    >>> import xarray as xr
    >>> t = np.arange(5) / 10.0
    >>> rec = xr.Dataset(
    ...     {"acc": ("time", np.zeros(5), {"units": "m/s^2", "sample_rate": 10.0}),
    ...      "n": ("time_tacho", np.full(3, 2 * np.pi * 25.0), {"quantity": "rotational_speed",
    ...                                                         "units": "rad/s"})},
    ...     coords={"time": t, "time_tacho": [0.0, 0.2, 0.4]})
    >>> n = speed_reference(rec, "acc")
    >>> n.values, n.attrs["units"], n.attrs["source"]
    (array([1500., 1500., 1500., 1500., 1500.]), 'rpm', "speed channel 'n'")
    """
    if channel not in record.data_vars:
        raise RecordError(f"record has no channel {channel!r}"
                          f"{suggest(channel, map(str, record.data_vars))}; channels: "
                          f"{', '.join(map(str, record.data_vars))}")
    if record[channel].ndim != 1 or record[channel].shape[0] == 0:
        raise RecordError(f"channel {channel!r} holds no samples (zero-length or not 1-D, shape "
                          f"{record[channel].shape}); nothing to analyse")
    name = speed_channel or find_speed_channel(record, channel)
    if name not in record.data_vars:
        raise RecordError(f"record has no speed channel {name!r}"
                          f"{suggest(name, map(str, record.data_vars))}")
    var = record[name]
    if var.ndim != 1 or var.shape[0] == 0:
        raise RecordError(f"speed source {name!r} holds no samples (zero-length channel)")
    t_out = _times(record, channel)
    fs = _rate(record, channel, t_out)
    angle_trace = None                     # (t, angle) of an angle source, or None
    reference = "shaft angle 0 at the first sample (integrated speed)"
    if _is_pulses(var):
        t_in, omega = _pulse_speed(var, name)
        source = f"pulse train {name!r}"
    elif var.attrs.get("quantity") == "angle":
        if not _is_angle_source(var):
            raise AnalysisError(f"channel {name!r} (quantity 'angle') does not turn with the "
                                "shaft (it spans less than 4 revolutions): it is a vibratory "
                                "angle, not an encoder angle; name a speed channel or pulse "
                                "train")
        t_in, ang, reference = _channel_angle(var, name, _times(record, name))
        good = np.isfinite(ang)
        t_in, ang = t_in[good], ang[good]
        angle_trace = (t_in, ang)
        omega = np.gradient(ang, t_in)
        source = f"encoder angle channel {name!r}"
    else:
        units = var.attrs.get("units", "rad/s")
        if units not in ("rad/s",):
            raise RecordError(f"speed channel {name!r} has units {units!r}; expected 'rad/s' "
                              "(convert at ingest)"
                              + (_decode_hint(name) if _raw_pulses(var) else ""))
        t_in = _times(record, name)
        omega = np.asarray(var.values, dtype=float) / _ratio(var, name)
        source = ("IAS channel" if var.attrs.get("quantity") == "angular_velocity"
                  else "speed channel") + f" {name!r}"
    t_in, omega = _finite_speed(t_in, omega, source)
    if source.startswith(("IAS", "speed channel")):
        omega = _repair_glitches(t_in, omega, source)
        omega = _one_direction(omega, source)
    cover = None
    if _is_pulses(var) and var.shape[0] > 1:
        edges = np.asarray(var.values, float)
        cover = (float(np.nanmin(edges)), float(np.nanmax(edges)))
    _check_overlap(t_in, t_out, source, channel, omega, cover)
    rpm = np.interp(t_out, t_in, omega) * (60.0 / _TWO_PI)
    if rpm.max() <= 0 or rpm.min() < 0:
        i = int(np.argmin(rpm))
        raise _not_one_way(source, rpm[i], t_out[i])
    # the shaft angle: from an angle source, else from a TDC-referenced pulse train, averaged
    # over whole cycles (the mean rotation)
    angle = None
    from .resample import shaft_angle
    from .trend import cycle_average, mean_rotation

    if angle_trace is not None:
        angle = np.interp(t_out, *angle_trace)
    else:
        pulse = name if _is_pulses(var) else _pulse_reference_channel(record, exclude=name)
        if pulse is not None:
            pv = record[pulse]
            edges = np.asarray(pv.values, float)
            if edges.size > 8 and edges[0] <= t_out[-1] and edges[-1] >= t_out[0]:
                try:
                    angle, reference = _pulse_angle(pv, pulse, t_out)
                except AnalysisError as exc:        # an undecodable wheel: integrate instead
                    log.warning("pulse train %r gives no angle (%s); phases from the "
                                "integrated speed", pulse, exc)
                    angle = None
    coords = {}
    dim = record[channel].dims[0]
    if angle is not None and np.all(np.diff(angle) > 0) and rpm.min() > 0:
        # windows from the integrated speed: the edge angle carries its node's vibration
        smooth = mean_rotation(angle, rpm, fs)
        if np.all(np.diff(smooth) > 0):
            coords["shaft_angle"] = (dim, smooth, {"units": "rad", "reference": reference,
                                                   "long_name": "shaft angle (mean rotation)"})
    elif angle is None and rpm.min() > 0 and _averaged(source, _samples_per_rev(t_in, omega)):
        # a speed or IAS channel sampled fast carries the shaft's torsional vibration: as the
        # resampling speed it would phase-modulate every order (an IAS exported as "ias
        # [rpm]" read orders 3 and 6 of its own vibration 0.26 % and 0.9 % off); averaged
        # over whole cycles it is the mean rotation (a slow bench channel, < 10 samples a
        # revolution, carries no vibration and is interpolated as it is)
        phi = shaft_angle(rpm, fs)
        rpm = cycle_average(rpm, phi, fs)
    out = xr.DataArray(rpm, dims=(dim,), coords={dim: (dim, t_out, {"units": "s"}), **coords},
                       name="speed_rpm",
                       attrs={"units": "rpm", "long_name": "shaft speed", "source": source,
                              "channel": channel,
                              "angle_reference": reference if coords else
                              "shaft angle 0 at the first sample (integrated speed)"})
    if check:
        from .speedcheck import check_speed_reference

        values = np.asarray(record[channel].values, float)
        if np.isfinite(values).all() and values.shape[0] >= 64:
            check_speed_reference(values, fs, rpm, label=channel, source=source)
    return out


def _finite_speed(t_in, omega, source):
    """A speed trace without its non-finite values (skipped with a warning); refused when
    none is left."""
    good = np.isfinite(omega)
    if not good.all():
        log.warning("%s: %d non-finite speed values skipped", source, int((~good).sum()))
        t_in, omega = t_in[good], omega[good]
    if t_in.shape[0] == 0:
        raise AnalysisError(f"{source} holds no usable speed values")
    return t_in, omega


#: a speed glitch: this many robust standard deviations from the running median, and at least
#: this fraction of it (a shaft cannot step by that much between two samples and back)
_GLITCH_SIGMAS = 10.0
_GLITCH_FRACTION = 0.05
#: ... and reached and left faster than any engine changes speed (free revving ~1e4 rpm/s)
_GLITCH_RATE_RPM_S = 2.0e4


def _repair_glitches(t_in, omega, source):
    """Counter glitches of a speed channel (overflow spikes such as 65535, single samples
    dropping to 0 while the shaft runs) bridged by interpolation, with a warning.

    A sample is a glitch when it stands more than ``_GLITCH_SIGMAS`` robust standard
    deviations (of the channel's deviation from its running median over about one
    revolution, so a real IAS oscillation sets its own scale) and ``_GLITCH_FRACTION`` of the
    local speed away from that median, in a run left and re-entered faster than
    ``_GLITCH_RATE_RPM_S`` (2e4 rpm/s, twice a free-revving engine); a slower departure (a real
    stop or step) is kept. The streamed trackers apply the same rules block by block
    (:mod:`analysis.stream_speed`).

    Examples
    --------
    >>> t = np.arange(200) / 100.0
    >>> w = np.full(200, 125.0)
    >>> w[50], w[120:122] = 6863.0, 0.0
    >>> fixed = _repair_glitches(t, w, "speed channel 'n'")
    >>> float(fixed.min()), float(fixed.max())
    (125.0, 125.0)
    """
    n = omega.shape[0]
    if n < 9:
        return omega
    width = _glitch_width(t_in, omega)
    med = _running_median(omega, width)
    dev = omega - med
    bad = _glitch_candidates(med, dev, _robust_sigma(dev))
    if not bad.any():
        return omega
    # keep departures a shaft can make (a real stop or step): out and back over the run's
    # span at less than _GLITCH_RATE_RPM_S
    edges = np.flatnonzero(np.diff(np.concatenate([[0], bad.astype(np.int8), [0]])))
    for a, b in edges.reshape(-1, 2):
        if not _is_glitch_run(float(np.max(np.abs(dev[a:b]))),
                              float(t_in[min(b, n - 1)] - t_in[max(a - 1, 0)])):
            bad[a:b] = False
    if not bad.any() or bad.all():
        return omega
    fixed = omega.copy()
    fixed[bad] = np.interp(t_in[bad], t_in[~bad], omega[~bad])
    _warn_glitches(source, int(bad.sum()), float(np.max(np.abs(dev[bad]))),
                   t_in[np.flatnonzero(bad)[:3]])
    return fixed


def _glitch_width(t_in, omega) -> int:
    """Running-median width of the glitch test: about one revolution, odd, 5..101 samples."""
    return int(np.clip(_samples_per_rev(t_in, omega), 5, 101)) | 1


def _running_median(omega, width):
    from scipy.ndimage import median_filter

    return median_filter(omega, size=width, mode="nearest")


def _robust_sigma(dev) -> float:
    """Robust standard deviation (1.4826 × median absolute deviation) of ``dev``."""
    return 1.4826 * float(np.median(np.abs(dev - np.median(dev))))


def _glitch_candidates(med, dev, sigma):
    """Samples ``_GLITCH_SIGMAS`` σ and ``_GLITCH_FRACTION`` of the local speed off the
    running median ``med`` (``dev`` = speed − ``med``)."""
    return (np.abs(dev) > _GLITCH_SIGMAS * sigma) & (np.abs(dev) > _GLITCH_FRACTION * np.abs(med))


def _is_glitch_run(peak, span) -> bool:
    """A run of candidates ``peak`` rad/s off, left and re-entered over ``span`` s: faster
    than ``_GLITCH_RATE_RPM_S`` (a shaft cannot follow)."""
    return peak * 60.0 / _TWO_PI / max(span, 1e-300) >= _GLITCH_RATE_RPM_S


def _warn_glitches(source, count, worst, first_times):
    log.warning("%s: %d glitch sample(s) (spikes or drop-outs a shaft cannot follow: up to "
                "%.4g rpm off the running speed) bridged by interpolation, first at t = %s s",
                source, count, worst * 60 / _TWO_PI, ", ".join(f"{v:.6g}" for v in first_times))


def _one_direction(omega, source):
    """A speed channel negative wherever the shaft runs is a sensor whose sign convention is
    the other way round: its magnitude, with a warning. A channel with both signs (a real
    reversal) is left to the caller's refusal."""
    if _negative_throughout(float(np.max(omega)), float(np.max(np.abs(omega)))):
        _warn_negative(source, float(omega.min()), float(omega.max()))
        return -omega
    return omega


def _negative_throughout(highest, top) -> bool:
    """Whether a speed whose highest value is ``highest`` and largest magnitude ``top`` is
    negative wherever the shaft runs (|speed| > 0.5 % of ``top``)."""
    return top > 0 and highest <= 0.005 * top


def _warn_negative(source, lowest, highest):
    log.warning("%s is negative throughout (%.6g .. %.6g rpm): taken as the shaft turning "
                "the other way round to the sensor's sign convention; its magnitude is "
                "used (order amplitudes unchanged, phases referred to the shaft's own "
                "direction of rotation)", source, lowest * 60 / _TWO_PI, highest * 60 / _TWO_PI)


def _not_one_way(source, value_rpm, t) -> AnalysisError:
    """The refusal of a speed that reverses (or never turns): ``value_rpm`` at ``t`` s."""
    return AnalysisError(f"{source}: speed {value_rpm:.6g} rpm at t = {t:.6g} s; order "
                         "analysis needs the shaft turning one way (>= 0 rpm throughout, "
                         "> 0 somewhere); select a time range where it turns")


def _averaged(source, samples_per_rev) -> bool:
    """Whether a speed source is averaged over whole cycles before use: an IAS channel, or a
    speed channel sampled at least 10 times a revolution (it carries the torsional vibration)."""
    return source.startswith("IAS") or (source.startswith("speed channel")
                                        and samples_per_rev >= 10)


def _samples_per_rev(t_in, omega) -> float:
    """Median samples per shaft revolution of a speed trace (rad/s at times t_in)."""
    if t_in.shape[0] < 2:
        return 0.0
    dt = float(np.median(np.diff(t_in)))
    rev = _TWO_PI / max(float(np.median(np.abs(omega))), 1e-300)
    return rev / dt if dt > 0 else 0.0


def _rate(record, channel, t_out) -> float:
    rate = record[channel].attrs.get("sample_rate")
    if rate is not None:
        return float(rate)
    if t_out.shape[0] > 1:
        return float(1.0 / np.median(np.diff(t_out)))
    return 1.0


def _check_overlap(t_in, t_out, source, channel, omega, cover=None):
    """Refuse a source that misses the channel; warn when it covers it only in part.
    ``cover``: the source's own time span when wider than its speed trace (a pulse train's
    first and last edges: its averaged speed starts a window later)."""
    a, b = float(t_out[0]), float(t_out[-1])
    lo, hi = (float(t_in[0]), float(t_in[-1])) if cover is None else cover
    span = max(b - a, 1e-300)
    covered = max(0.0, min(b, hi) - max(a, lo))
    where = (f"{source} covers {lo:.6g}–{hi:.6g} s but channel {channel!r} spans "
             f"{a:.6g}–{b:.6g} s")
    if covered <= 0 and not (t_in.shape[0] == 1 or lo <= a <= hi):
        raise AnalysisError(f"{where}: they never overlap (the speed source is on another clock "
                            "or from another run); give the matching speed channel or correct "
                            "the time offset")
    if t_in.shape[0] > 1 and covered < 0.5 * span:
        raise AnalysisError(f"{where}: the speed is known for only {100 * covered / span:.3g} % "
                            "of the channel; select the channel's span where the speed is known "
                            "or give a speed source that covers it")
    median = float(np.median(np.abs(omega))) if omega.size else 0.0
    rev_time = _TWO_PI / median if median > 0 else np.inf
    outside = max(lo - a, b - hi)
    # speed from pulses starts a window (1-2 revolutions) after the first edge: holding it over
    # that stretch is expected; beyond 3 revolutions the user should know
    if outside > 3.0 * rev_time:
        warnings.warn(f"{where}; the speed is held constant beyond its ends", SpeedReferenceWarning,
                      stacklevel=3)
        log.warning("%s; the speed is held constant beyond its ends", where)
