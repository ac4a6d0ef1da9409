"""A speed channel read span by span for the streamed trackers, repaired as in memory.

:func:`analysis.speedref.speed_reference` prepares a ``rotational_speed`` or IAS channel before
order analysis: counter glitches (overflow spikes, a few samples dropping to 0 while the shaft
runs) are bridged, a channel negative throughout is taken by its magnitude, a reversal is
refused, and a fast channel (≥ 10 samples a revolution, or any IAS channel) is averaged over
whole engine cycles so its torsional vibration does not modulate the resampling. The streamed
trackers (:mod:`analysis.stream`) never hold a channel of the record's length, so here the same
rules — the same functions of :mod:`analysis.speedref` — run block by block:

* :class:`RepairedChannel`: a speed channel on the analysed channel's clock (as long as the
  record), read in blocks of ``block`` samples, each with a margin of the running median's
  half width, so each sample's median is the whole-record one. Three passes before any
  tracking: the median speed (samples per revolution → the median width), the robust spread
  of the deviation from the running median, and the candidate glitch runs — a run open at a
  block's end is carried into the next block, so a glitch straddling a block boundary is one
  run, judged by the rate rule on its whole span. The spread and the median speed are those of
  the whole channel up to ``_SAMPLE_CAP`` samples (identical to memory), of every k-th sample
  beyond (a strided estimate of a robust statistic). A glitch's bridge is the straight line
  between the samples on either side of it, as in memory.
* :class:`CycleAveraged`: the cycle average (:func:`analysis.trend.cycle_average`) of any span,
  read with the averaging's reach as margin and with the integrated shaft angle carried from
  checkpoints every ``block`` samples (the same sequential sum as the whole record), so each
  value equals the whole-record one to rounding.

Both are sliced like arrays (``speed[a:b]``, ``speed[::q]``) for :class:`SpanSpeed` (the
speed of any span of a channel, public as :class:`analysis.stream.SpanSpeed`), which
``_speed_for`` builds from the record's speed source as
:func:`analysis.speedref.speed_reference` would: a speed or IAS channel on its own clock read
whole and prepared by the same functions, one on the analysed channel's clock through
:class:`RepairedChannel` (and :class:`CycleAveraged` where memory averages), an encoder angle on
that clock through :class:`EncoderAngle` (its mean rotation the phase angle), a pulse train's
edge angle; a stop is left to the tracker (tracked per running span, as in memory).
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict._deprecate import renamed
from crankbench.predict.errors import AnalysisError, RecordError

__all__: list[str] = []        # SpanSpeed is public as analysis.stream.SpanSpeed

log = logging.getLogger("crankbench")

_TWO_PI = 2.0 * np.pi
#: statistics (median speed, robust spread) from every sample up to this many, else strided
_SAMPLE_CAP = 1 << 22
#: samples of a same-clock speed channel read at a time
BLOCK = 1 << 20


def read_finite(data, a, b, label, need):
    """Samples a..b-1 of a (lazy) array as float64, refused with ``need`` (what the caller
    needs instead) where one is NaN/inf."""
    part = data[a:b]
    part = np.asarray(part.compute() if hasattr(part, "compute") else part, np.float64)
    if not np.isfinite(part).all():
        i = a + int(np.flatnonzero(~np.isfinite(part))[0])
        raise AnalysisError(f"{label}: NaN/inf at sample {i}; {need}")
    return part


class _Spans:
    """Array-like speed (rpm) computed per span: ``self[a:b]`` and strided ``self[::q]``."""

    n: int
    block: int

    def span(self, a: int, b: int) -> np.ndarray:       # pragma: no cover - abstract
        raise NotImplementedError

    ndim = 1

    @property
    def shape(self):
        return (self.n,)

    def __len__(self):
        return self.n

    def __getitem__(self, key):
        if not isinstance(key, slice):
            raise TypeError("speed spans are read by slices")
        start, stop, step = key.indices(self.n)
        if step == 1:
            return self.span(start, max(start, stop))
        if step < 1:
            raise TypeError("speed spans are read forwards")
        size = step * max(1, self.block // step)
        parts = [self.span(a, min(stop, a + size))[::step] for a in range(start, stop, size)]
        return np.concatenate(parts) if parts else np.empty(0)


class RepairedChannel(_Spans):
    """A lazy speed channel (rad/s) on the analysed channel's clock, as rpm per span, with the
    glitch repair and sign rule of :func:`analysis.speedref.speed_reference`.

    Parameters
    ----------
    data : array_like
        The channel's samples (numpy or dask), rad/s of the source.
    fs, t0 : float
        Sample rate (Hz) and time of the first sample (s).
    ratio : float
        Turns of the source per crankshaft turn.
    source : str
        Label for messages (e.g. ``"speed channel 'n'"``).
    block : int, optional
        Samples read at a time (default :data:`BLOCK`).

    Examples
    --------
    >>> w = np.full(4000, 125.0)
    >>> w[1999:2002] = 0.0                       # a 3-sample drop-out straddling a block edge
    >>> s = RepairedChannel(w, fs=1000.0, t0=0.0, ratio=1.0, source="n", block=2000)
    >>> s.glitches, round(float(s[1990:2010].min() * np.pi / 30), 6)
    (3, 125.0)
    """

    def __init__(self, data, *, fs, t0, ratio, source, block=None):
        from .speedref import _glitch_width

        self.data, self.fs, self.t0 = data, float(fs), float(t0)
        self.ratio, self.source = float(ratio), source
        self.n = int(data.shape[0])
        self.block = max(1024, int(BLOCK if block is None else block))
        self.flip = 1.0
        sample = self._sample(lambda w, a, b: w)
        self.median_rpm = float(np.median(np.abs(sample))) * 60.0 / _TWO_PI
        t_sample = np.arange(2) / self.fs                # regular clock: median dt = 1/fs
        self.width = _glitch_width(t_sample, sample) if self.n >= 9 else 0
        self._runs = np.empty((0, 2), np.int64)
        self._ends = np.empty((0, 2))
        if self.width:
            self._find_glitches()
        self._stats()

    # -- reading

    def _raw(self, a, b):
        return read_finite(self.data, a, b, self.source, "the streamed trackers need a finite "
                           "speed channel on the signal's clock (read the record whole, or "
                           "give a speed channel on its own clock)") / self.ratio

    def _blocks(self, margin=0):
        """``(a, b, ra, values[ra:rb])`` for consecutive blocks a..b-1 read with ``margin``."""
        for a in range(0, self.n, self.block):
            b = min(self.n, a + self.block)
            ra, rb = max(0, a - margin), min(self.n, b + margin)
            yield a, b, ra, self._raw(ra, rb)

    def _median_dev(self, a, b, ra, w):
        from .speedref import _running_median

        med = _running_median(w, self.width)
        return med[a - ra:b - ra], (w - med)[a - ra:b - ra]

    def _sample(self, pick):
        """Every k-th value of ``pick(window, a, b)`` over the channel (all up to _SAMPLE_CAP)."""
        step = max(1, -(-self.n // _SAMPLE_CAP))
        margin = self.width // 2 + 1 if getattr(self, "width", 0) else 0
        parts = [pick(w, a, ra)[(-a) % step::step] if step > 1 else pick(w, a, ra)
                 for a, _, ra, w in self._blocks(margin)]
        return np.concatenate(parts)

    # -- the passes

    def _find_glitches(self):
        from .speedref import (_glitch_candidates, _is_glitch_run, _robust_sigma,
                               _warn_glitches)

        half = self.width // 2 + 1

        def dev_of(w, a, ra):
            b = min(self.n, a + self.block)
            return self._median_dev(a, b, ra, w)[1]

        sigma = _robust_sigma(self._sample(dev_of))
        runs, peaks, left, right = [], [], [], []
        open_start, open_peak = None, 0.0
        for a, b, ra, w in self._blocks(half):
            med, dev = self._median_dev(a, b, ra, w)
            bad = _glitch_candidates(med, dev, sigma)
            flags = np.concatenate([[open_start is not None], bad, [False]]).astype(np.int8)
            edges = np.flatnonzero(np.diff(flags))        # starts and ends, local to a - 1
            for e in edges:
                i = a + int(e)                             # global index of the change
                if flags[e + 1]:                           # a run starts at sample i
                    open_start, open_peak = i, 0.0
                    left.append(w[i - 1 - ra] if i > 0 else np.nan)
                elif i < b:                                # the open run ends before sample i
                    seg = dev[max(open_start, a) - a:i - a]
                    peak = max(open_peak, float(np.max(np.abs(seg))) if seg.size else 0.0)
                    runs.append((open_start, i))
                    peaks.append(peak)
                    right.append(w[i - ra] if i < self.n else np.nan)
                    open_start = None
            if open_start is not None:                     # carried into the next block
                seg = dev[max(open_start, a) - a:]
                open_peak = max(open_peak, float(np.max(np.abs(seg))) if seg.size else 0.0)
        if open_start is not None:                         # runs to the record's end
            runs.append((open_start, self.n))
            peaks.append(open_peak)
            right.append(np.nan)
        if not runs:
            return
        runs = np.asarray(runs, np.int64)
        keep = np.array([_is_glitch_run(p, (min(e, self.n - 1) - max(s - 1, 0)) / self.fs)
                         for (s, e), p in zip(runs, peaks)], bool)
        count = int(np.sum(runs[keep, 1] - runs[keep, 0]))
        if count == 0 or count == self.n:
            return
        self._runs = runs[keep]
        self._ends = np.column_stack([left, right])[keep]
        self.glitches = count
        first = (self.t0 + np.concatenate([np.arange(s, e) for s, e in self._runs[:3]])[:3]
                 / self.fs)
        _warn_glitches(self.source, count, max(p for p, k in zip(peaks, keep) if k), first)

    glitches = 0

    def _stats(self):
        """Sign rule and refusal (:func:`analysis.speedref._one_direction`), the extremes."""
        from .speedref import _negative_throughout, _not_one_way, _warn_negative

        lo = hi = top = None
        i_lo = 0
        for a in range(0, self.n, self.block):
            w = self._repaired(a, min(self.n, a + self.block))
            j = int(np.argmin(w))
            if lo is None or w[j] < lo:
                lo, i_lo = float(w[j]), a + j
            hi = float(w.max()) if hi is None else max(hi, float(w.max()))
            top = float(np.abs(w).max()) if top is None else max(top, float(np.abs(w).max()))
        if _negative_throughout(hi, top):
            _warn_negative(self.source, lo, hi)
            self.flip = -1.0
            lo, hi = -hi, -lo
            i_lo = None
        if hi <= 0 or lo < 0:
            raise _not_one_way(self.source, lo * 60.0 / _TWO_PI,
                               self.t0 + (i_lo or 0) / self.fs)
        self.low_rpm, self.high_rpm = lo * 60.0 / _TWO_PI, hi * 60.0 / _TWO_PI

    def _repaired(self, a, b):
        w = self._raw(a, b)
        if self._runs.shape[0]:
            lo = int(np.searchsorted(self._runs[:, 1], a, side="right"))
            hi = int(np.searchsorted(self._runs[:, 0], b, side="left"))
            for (s, e), (vl, vr) in zip(self._runs[lo:hi], self._ends[lo:hi]):
                i = np.arange(max(s, a), min(e, b))
                if np.isnan(vl):
                    w[i - a] = vr
                elif np.isnan(vr):
                    w[i - a] = vl
                else:
                    w[i - a] = vl + (vr - vl) * (i - (s - 1)) / (e - (s - 1))
        return w

    def span(self, a, b):
        """Speed (rpm) of samples a..b-1."""
        return self._repaired(a, b) * (self.flip * 60.0 / _TWO_PI)


class CycleAveraged(_Spans):
    """The cycle average of a speed (rpm) given per span, per span.

    Parameters
    ----------
    inner : callable
        ``inner(a, b)`` → speed (rpm) of samples a..b-1.
    n : int
        Samples.
    fs : float
        Sample rate, Hz.
    low_rpm : float
        Lowest speed (> 0; sets the averaging's reach).
    block : int
        Samples between angle checkpoints.

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(20000) / fs
    >>> rpm = 600.0 + 6.0 * t + 30.0 * np.cos(2 * np.pi * 15.0 * t)     # order 1.5 vibration
    >>> avg = CycleAveraged(lambda a, b: rpm[a:b], n=rpm.size, fs=fs, low_rpm=570.0, block=4096)
    >>> bool(np.abs(avg[5000:15000] - (600.0 + 6.0 * t[5000:15000])).max() < 0.5)
    True
    """

    def __init__(self, inner, *, n, fs, low_rpm, block=1 << 13):
        from .resample import integrate_angle
        from .trend import CYCLE_REACH_REVOLUTIONS

        self.inner, self.n, self.fs = inner, int(n), float(fs)
        self.block = max(1024, int(block))
        # the average is applied twice (twicing): twice the reach of one pass, and a fifth more
        self.margin = int(np.ceil(2.4 * CYCLE_REACH_REVOLUTIONS * 60.0 / low_rpm * self.fs)) + 2
        cps, phi = [], 0.0
        for a in range(0, self.n, self.block):
            b = min(self.n, a + self.block + 1)
            cps.append(phi)
            phi = float(integrate_angle(inner(a, b), self.fs, phi)[-1])
        self._checkpoints, self._end = np.asarray(cps), phi

    def span(self, a, b):
        """Cycle-averaged speed (rpm) of samples a..b-1."""
        from .resample import integrate_angle
        from .trend import cycle_average

        ra, rb = max(0, a - self.margin), min(self.n, b + self.margin)
        k = ra // self.block
        base = k * self.block
        r = self.inner(base, rb)
        phi = integrate_angle(r, self.fs, float(self._checkpoints[k]))
        return cycle_average(r[ra - base:], phi[ra - base:], self.fs,
                             ends=(0.0, self._end))[a - ra:b - ra]


class EncoderAngle(_Spans):
    """An encoder angle channel (rad) on the analysed channel's clock as the crankshaft angle
    and speed per span, as :func:`analysis.speedref.speed_reference` takes it whole: unwrapped
    (a wrapped channel; the 2π count carried across blocks), turned round if it counts
    backwards, divided by its ``speed_ratio``, moved by ``tdc_offset_deg``; the speed its
    central-difference derivative (``np.gradient``, each span read with one sample of margin).

    Parameters
    ----------
    data : array_like
        The channel's samples (numpy or dask), rad.
    fs, t0 : float
        Sample rate (Hz), time of the first sample (s).
    ratio : float
        Turns of the encoder per crankshaft turn.
    tdc_deg : float
        The channel's ``tdc_offset_deg``.
    source : str
        Label for messages.
    block : int, optional
        Samples read at a time (default :data:`BLOCK`).

    Examples
    --------
    >>> t = np.arange(3000) / 1000.0
    >>> enc = np.mod(2 * np.pi * 20.0 * t, 2 * np.pi)          # 1200 rpm, wrapped
    >>> e = EncoderAngle(enc, fs=1000.0, t0=0.0, ratio=1.0, tdc_deg=0.0, source="enc",
    ...                  block=1024)
    >>> round(float(e.angle(2990, 3000)[-1] / (2 * np.pi)), 6), round(float(e[1500:1501][0]), 6)
    (59.98, 1200.0)
    """

    def __init__(self, data, *, fs, t0, ratio, tdc_deg, source, block=None):
        from .speedref import _not_one_way

        self.data, self.fs, self.t0 = data, float(fs), float(t0)
        self.ratio, self.tdc, self.source = float(ratio), float(tdc_deg), source
        self.n = int(data.shape[0])
        self.block = max(1024, int(BLOCK if block is None else block))
        lo = hi = None
        for a in range(0, self.n, self.block):
            w = self._read(a, min(self.n, a + self.block))
            lo = float(w.min()) if lo is None else min(lo, float(w.min()))
            hi = float(w.max()) if hi is None else max(hi, float(w.max()))
        self.wrapped = hi - lo <= _TWO_PI + 1e-6
        # per block: the raw value before it and the 2π count to add (np.unwrap carried)
        self._before, self._offset = [], []
        before, offset = None, 0.0
        for a in range(0, self.n, self.block):
            w = self._read(a, min(self.n, a + self.block))
            self._before.append(before)
            self._offset.append(offset)
            if self.wrapped:
                u = self._unwrap(w, before, offset)
                before, offset = float(w[-1]), float(u[-1] - w[-1])
            else:
                before = float(w[-1])
        first = self._unwrapped(0, 1)[0]
        last = self._unwrapped(self.n - 1, self.n)[0]
        self.sign = -1.0 if last < first else 1.0
        self.ends = (self.angle(0, 1)[0], self.angle(self.n - 1, self.n)[0])
        low = high = None
        for a in range(0, self.n, self.block):
            r = self.span(a, min(self.n, a + self.block))
            j = int(np.argmin(r))
            if low is None or r[j] < low[0]:
                low = (float(r[j]), a + j)
            high = float(r.max()) if high is None else max(high, float(r.max()))
        if high <= 0 or low[0] < 0:
            raise _not_one_way(source, low[0], self.t0 + low[1] / self.fs)
        self.low_rpm, self.high_rpm = low[0], high

    def _read(self, a, b):
        return read_finite(self.data, a, b, self.source,
                           "the streamed trackers need a finite encoder angle")

    @staticmethod
    def _unwrap(w, before, offset):
        if before is None:
            return np.unwrap(w)
        return np.unwrap(np.concatenate([[before], w]))[1:] + offset

    def _unwrapped(self, a, b):
        """The channel unwrapped as a whole, samples a..b-1."""
        if not self.wrapped:
            return self._read(a, b)
        k = a // self.block
        base = k * self.block
        u = self._unwrap(self._read(base, b), self._before[k], self._offset[k])
        return u[a - base:]

    def angle(self, a, b):
        """Crankshaft angle (rad) of samples a..b-1, as speedref._channel_angle gives it."""
        return self.sign * self._unwrapped(a, b) / self.ratio - np.radians(self.tdc)

    def span(self, a, b):
        """Speed (rpm) of samples a..b-1: the angle's derivative."""
        ra, rb = max(0, a - 1), min(self.n, b + 1)
        if rb - ra < 2:
            return np.zeros(b - a)
        t = self.t0 + np.arange(ra, rb) / self.fs
        return np.gradient(self.angle(ra, rb), t)[a - ra:b - ra] * (60.0 / _TWO_PI)


# ---------------------------------------------------------------------------- speed per span


class SpanSpeed:
    """Shaft speed (rpm) on any span of a channel's samples, without the whole-record array.

    Parameters
    ----------
    n : int
        Samples of the analysed channel.
    fs : float
        Its sample rate, Hz.
    t0 : float
        Time of its first sample, s.
    rpm : float or array_like, optional
        Speed per sample (rpm) or a constant; else taken from ``t_in``/``omega``.
    t_in, omega : ndarray, optional
        A speed trace (s, rad/s) interpolated linearly (ends held), as
        :func:`analysis.speedref.speed_reference` does.

    Examples
    --------
    >>> s = SpanSpeed(10, 10.0, 0.0, t_in=np.array([0.0, 1.0]), omega=np.array([0.0, 2 * np.pi]))
    >>> s(2, 4).tolist()
    [12.0, 18.0]
    """

    @renamed(rpm="speed_rpm")
    def __init__(self, n, fs, t0, *, speed_rpm=None, t_in=None, omega=None):
        self.n, self.fs, self.t0 = int(n), float(fs), float(t0)
        if speed_rpm is None or hasattr(speed_rpm, "compute") or hasattr(speed_rpm, "span"):
            # dask, or computed per span (analysis.stream_speed): sliced per span, never whole
            self._rpm = speed_rpm
        else:
            self._rpm = np.asarray(speed_rpm,
                                   float) if not np.isscalar(speed_rpm) else float(speed_rpm)
        self._t_in, self._omega = t_in, omega
        self.angle = None            # optional angle(a, b) -> shaft angle (rad) of the span
        self.angle_reference = ("shaft angle 0 at the first sample of the record "
                                "(speed-reference integration)")

    def __call__(self, a: int, b: int) -> np.ndarray:
        if self._rpm is not None:
            if np.ndim(self._rpm) == 0:
                return np.full(b - a, self._rpm)
            part = self._rpm[a:b]
            part = np.asarray(part.compute() if hasattr(part, "compute") else part, float)
            if not np.isfinite(part).all() or part.min() <= 0:
                raise AnalysisError(f"speed between samples {a} and {b} is not finite and > 0 "
                                    "rpm; order analysis needs the shaft turning")
            return part
        t = self.t0 + np.arange(a, b) / self.fs
        return np.interp(t, self._t_in, self._omega) * (60.0 / _TWO_PI)


def _speed_for(record, channel, var, *, speed_rpm, speed_channel) -> SpanSpeed:
    from .speedref import _is_pulses, _pulse_reference_channel, _pulse_speed
    from .speedref import find_speed_channel

    n, fs = var.shape[0], float(var.attrs["sample_rate"])
    t0 = _first_time(record, var)
    if speed_rpm is not None:
        if not np.isscalar(speed_rpm) and np.shape(speed_rpm)[0] != n:
            raise AnalysisError(f"speed_rpm has {np.shape(speed_rpm)[0]} samples but channel {channel!r} has "
                                f"{n}; give one speed per sample, a constant, or speed_channel")
        speed = SpanSpeed(n, fs, t0, speed_rpm=speed_rpm.data if hasattr(speed_rpm, "coords")
                          else speed_rpm)
        coords = getattr(speed_rpm, "coords", {})
        if "shaft_angle" in coords:              # speed_reference's angle, as in memory
            angle = speed_rpm["shaft_angle"].data
            speed.angle = lambda a, b: np.asarray(angle[a:b], float)
            speed.angle_reference = str(speed_rpm["shaft_angle"].attrs.get(
                "reference", speed_rpm.attrs.get("angle_reference", "")))
        return speed
    name = speed_channel or find_speed_channel(record, channel)
    if name not in record.data_vars:
        raise RecordError(f"record has no speed channel {name!r}")
    sv = record[name]
    if _is_pulses(sv):
        t_in, omega = _pulse_speed(sv, name)
        source = f"pulse train {name!r}"
    elif sv.attrs.get("quantity") == "angle" and sv.dims == var.dims:
        return _same_clock_encoder(sv, name, n, fs, t0)
    else:
        source = _check_speed_channel(sv, name)
        if sv.dims == var.dims:       # same clock: read the speed channel span by span
            return _same_clock_speed(record, var, sv, name, source, n, fs, t0)
        t_in, omega = _speed_trace(record, sv, name, source)
    good = np.isfinite(omega)
    t_in, omega = np.asarray(t_in)[good], np.asarray(omega)[good]
    if t_in.shape[0] == 0:
        raise AnalysisError(f"speed source {name!r} holds no usable speed values")
    from .speedref import _check_overlap

    cover = None
    if _is_pulses(sv) and sv.shape[0] > 1:
        edges = np.asarray(sv.values, float)
        cover = (float(np.nanmin(edges)), float(np.nanmax(edges)))
    _check_overlap(t_in, np.array([t0, t0 + (n - 1) / fs]), source, channel, omega, cover)
    speed = SpanSpeed(n, fs, t0, t_in=t_in, omega=omega)
    low, high = _span_extremes(t_in, omega, t0, t0 + (n - 1) / fs)
    speed.extremes = (low, high)
    pulse = name if _is_pulses(sv) else _pulse_reference_channel(record, exclude=name)
    if pulse is not None and omega.min() > 0:
        _attach_pulse_angle(speed, record[pulse], pulse, low)
    if speed.angle is None and not _is_pulses(sv) and low > 0:
        from .speedref import _averaged, _samples_per_rev

        if _averaged(source, _samples_per_rev(t_in, omega)):
            speed = _averaged_speed(speed, low)
    return speed


def _same_clock_encoder(sv, name, n, fs, t0) -> SpanSpeed:
    """An encoder angle channel on the analysed channel's clock: its own angle (the mean
    rotation) and speed, span by span, as speed_reference takes it whole."""
    from .speedref import _is_angle_source, _ratio
    from .stream_speed import EncoderAngle

    if sv.shape[0] >= 8 and not _is_angle_source(sv[:: max(1, sv.shape[0] // 4096)]):
        raise AnalysisError(f"channel {name!r} (quantity 'angle') does not turn with the "
                            "shaft (it spans less than 4 revolutions): it is a vibratory "
                            "angle, not an encoder angle; name a speed channel or pulse train")
    tdc = float(sv.attrs.get("tdc_offset_deg", 0.0))
    enc = EncoderAngle(sv.data, fs=fs, t0=t0, ratio=_ratio(sv, name), tdc_deg=tdc,
                       source=f"encoder angle channel {name!r}")
    speed = SpanSpeed(n, fs, t0, speed_rpm=enc)
    speed.extremes = (enc.low_rpm, enc.high_rpm)
    if enc.low_rpm > 0:
        reference = (f"zero of encoder angle channel {name!r}" +
                     (f" moved by tdc_offset_deg {tdc:g}" if tdc else ""))
        _attach_mean_rotation(speed, enc.angle, enc.ends, enc.low_rpm, reference)
    return speed


def _check_speed_channel(sv, name) -> str:
    """The label of a speed or IAS channel (rad/s), as speed_reference names it."""
    if sv.attrs.get("quantity") == "angle":
        raise AnalysisError(f"channel {name!r} is an encoder angle on another clock than the "
                            "analysed channel: the streamed trackers take it on the same clock "
                            "only; give a speed channel or pulse train with --speed-channel, "
                            "or analyse the record in memory")
    if sv.attrs.get("units", "rad/s") != "rad/s":
        raise RecordError(f"speed channel {name!r} has units {sv.attrs.get('units')!r}; "
                          "expected 'rad/s'")
    return ("IAS channel" if sv.attrs.get("quantity") == "angular_velocity"
            else "speed channel") + f" {name!r}"


def _speed_trace(record, sv, name, source):
    """A speed channel on its own clock (small: read whole) as (s, rad/s of the crankshaft),
    its glitches bridged and its sign rule applied as in memory."""
    from .speedref import (_finite_speed, _not_one_way, _one_direction, _ratio,
                           _repair_glitches, _times)

    rate = sv.attrs.get("sample_rate")
    if rate is not None and sv.dims[0] in record.coords:   # regular clock: t0 + i/rate
        t_in = _first_time(record, sv) + np.arange(sv.shape[0]) / float(rate)
    else:
        t_in = np.asarray(_times(record, name), float)
    t_in, omega = _finite_speed(t_in, np.asarray(sv.values, float) / _ratio(sv, name), source)
    omega = _one_direction(_repair_glitches(t_in, omega, source), source)
    if omega.max() <= 0 or omega.min() < 0:
        i = int(np.argmin(omega))
        raise _not_one_way(source, omega[i] * 60.0 / _TWO_PI, t_in[i])
    return t_in, omega


def _same_clock_speed(record, var, sv, name, source, n, fs, t0) -> SpanSpeed:
    """A speed or IAS channel on the analysed channel's clock, repaired, sign-corrected and
    (where the in-memory path does) cycle-averaged span by span."""
    from .speedref import _averaged, _pulse_reference_channel, _ratio
    from .stream_speed import RepairedChannel

    raw = RepairedChannel(sv.data, fs=fs, t0=t0, ratio=_ratio(sv, name), source=source)
    speed = SpanSpeed(n, fs, t0, speed_rpm=raw)
    speed.extremes = (raw.low_rpm, raw.high_rpm)
    if raw.low_rpm <= 0:              # a stop: tracked per running span, never averaged
        return speed
    pulse = _pulse_reference_channel(record, exclude=name)
    if pulse is not None:
        _attach_pulse_angle(speed, record[pulse], pulse, raw.low_rpm)
    median_rev = 60.0 / max(raw.median_rpm, 1e-300) * fs
    if speed.angle is None and _averaged(source, median_rev):
        speed = _averaged_speed(speed, raw.low_rpm)
        speed.extremes = (raw.low_rpm, raw.high_rpm)
    return speed


def _averaged_speed(speed: SpanSpeed, low_rpm: float) -> SpanSpeed:
    """``speed`` averaged over whole engine cycles (:func:`analysis.trend.cycle_average`), as
    :func:`analysis.speedref.speed_reference` does for a fast speed or IAS channel."""
    from .stream_speed import CycleAveraged

    avg = CycleAveraged(speed, n=speed.n, fs=speed.fs, low_rpm=low_rpm)
    return SpanSpeed(speed.n, speed.fs, speed.t0, speed_rpm=avg)


def _span_extremes(t_in, omega, a, b):
    """Lowest and highest speed (rpm) of a trace interpolated over the times a..b."""
    inside = omega[(t_in > a) & (t_in < b)]
    ends = np.interp([a, b], t_in, omega)
    values = np.concatenate([inside, ends]) * (60.0 / _TWO_PI)
    return float(values.min()), float(values.max())


def _stopped_spans(speed: SpanSpeed):
    """Sample spans ``[(a, b), ...]`` where the shaft stands (speed ≤ 0.5 % of the highest, the
    rule of the in-memory tracker), or None when it turns throughout."""
    low, high = getattr(speed, "extremes", (1.0, 1.0))
    if high <= 0 or low > 5e-3 * high:
        return None
    edges, prev, step = [], False, 1 << 18
    for a in range(0, speed.n, step):
        b = min(speed.n, a + step)
        if speed._rpm is None:
            part = np.interp(speed.t0 + np.arange(a, b) / speed.fs, speed._t_in,
                             speed._omega) * (60.0 / _TWO_PI)
        else:
            part = np.asarray(speed._rpm[a:b], float)
        flags = np.concatenate([[prev], part <= 5e-3 * high]).astype(np.int8)
        edges.extend(a + np.flatnonzero(np.diff(flags)))
        prev = bool(flags[-1])
    if prev:
        edges.append(speed.n)
    return list(zip(edges[0::2], edges[1::2])) or None


class _Shifted:
    """Samples a..b-1 of a SpanSpeed as a speed of their own (a running span)."""

    ndim = 1

    def __init__(self, speed, a, b):
        self.speed, self.a, self.n = speed, int(a), int(b - a)

    def span(self, i, j):
        return self.speed(self.a + i, self.a + j)

    def __getitem__(self, key):
        start, stop, step = key.indices(self.n)
        return self.speed(self.a + start, self.a + stop)[::step]


def _running_span(speed: SpanSpeed, a: int, b: int) -> SpanSpeed:
    """The speed of samples a..b-1 (a running span), its angle from the span's start as in
    memory (:func:`analysis.orders.order_track` on a record that stops)."""
    sub = SpanSpeed(b - a, speed.fs, speed.t0 + a / speed.fs, speed_rpm=_Shifted(speed, a, b))
    sub.extremes = (1.0, 1.0)
    return sub


def _attach_pulse_angle(speed: SpanSpeed, pv, name: str, low: float) -> None:
    """The shaft angle per span from a pulse train's edges, as
    :func:`analysis.speedref.speed_reference` gives it for the whole channel (the edges' mean
    rotation, :func:`analysis.trend.mean_rotation`, each span read with its reach as margin),
    and the phase reference (TDC where the wheel has a gap or mark)."""
    from crankbench.predict.errors import AnalysisError as _AE

    from .speedref import _pulse_angle_function
    edges = np.asarray(pv.values, float)
    n, fs, t0 = speed.n, speed.fs, speed.t0
    if edges.size <= 8 or edges[0] > t0 + (n - 1) / fs or edges[-1] < t0:
        return
    try:
        at, reference = _pulse_angle_function(pv, name)
    except _AE as exc:                         # an undecodable wheel: integrate instead
        log.warning("pulse train %r gives no angle (%s); phases from the integrated speed",
                    name, exc)
        return
    ends = (float(at(np.array([t0]))[0]), float(at(np.array([t0 + (n - 1) / fs]))[0]))
    _attach_mean_rotation(speed, lambda a, b: at(t0 + np.arange(a, b) / fs), ends, low,
                          reference)


def _attach_mean_rotation(speed: SpanSpeed, raw, ends, low, reference) -> None:
    """``speed.angle``: the mean rotation (:func:`analysis.trend.mean_rotation`) of a measured
    angle ``raw(a, b)`` (rad of samples a..b-1), each span read with its reach as margin."""
    from .trend import MEAN_ROTATION_REACH_REVOLUTIONS, mean_rotation

    n, fs = speed.n, speed.fs
    margin = int(np.ceil(1.2 * MEAN_ROTATION_REACH_REVOLUTIONS * 60.0 / low * fs)) + 2

    def angle(a, b):
        ra, rb = max(0, a - margin), min(n, b + margin)
        return mean_rotation(raw(ra, rb), speed(ra, rb), fs, ends=ends)[a - ra:b - ra]

    speed.angle = angle
    speed.angle_reference = reference


def _first_time(record, var) -> float:
    dim = var.dims[0]
    if dim in record.coords and var.shape[0]:
        return float(record[dim][0].values)
    return 0.0
