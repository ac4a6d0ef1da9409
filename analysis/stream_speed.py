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

Both are sliced like arrays (``speed[a:b]``, ``speed[::q]``) for
:class:`analysis.stream.SpanSpeed`.
"""

from __future__ import annotations

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__: list[str] = []        # helpers of analysis.stream

_TWO_PI = 2.0 * np.pi
#: statistics (median speed, robust spread) from every sample up to this many, else strided
_SAMPLE_CAP = 1 << 22
#: samples of a same-clock speed channel read at a time
BLOCK = 1 << 20


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
        part = self.data[a:b]
        part = np.asarray(part.compute() if hasattr(part, "compute") else part, np.float64)
        if not np.isfinite(part).all():
            i = a + int(np.flatnonzero(~np.isfinite(part))[0])
            raise AnalysisError(f"{self.source}: NaN/inf at sample {i}; the streamed trackers "
                                "need a finite speed channel on the signal's clock (read the "
                                "record whole, or give a speed channel on its own clock)")
        return part / self.ratio

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
        part = self.data[a:b]
        part = np.asarray(part.compute() if hasattr(part, "compute") else part, np.float64)
        if not np.isfinite(part).all():
            i = a + int(np.flatnonzero(~np.isfinite(part))[0])
            raise AnalysisError(f"{self.source}: NaN/inf at sample {i}; the streamed trackers "
                                "need a finite encoder angle")
        return part

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
