"""Order tracking of long (lazy) records segment by segment, with bounded memory.

:func:`analysis.order_track` and :func:`analysis.order_map` take the whole channel and the
speed per sample in memory (a 2 GB float32 record is 4 GB as float64, plus as much again for the
speed and the time axis). The functions here take a Record opened lazily by
:func:`measure.open` and read it one segment at a time:

* the speed is never materialised for the whole record: for a ``rotational_speed`` channel (its
  own, slow clock; small) or a pulse train the speed trace is loaded once and interpolated
  linearly onto just the samples of the current span; the sample times are ``t0 + i/fs``
  computed from the channel's ``sample_rate`` and its first time value (no time array);
* COT: the anti-alias filter and the angle resampling run on exactly the chunks
  :func:`analysis.resample.angle_resample` uses (``chunk`` input samples, split where the
  speed varies more than 2:1), each read with the filter's half length plus the interpolation
  margin on either side — so every angle sample equals the in-memory one. The shaft angle is
  integrated from the record start and carried across segments (same sequential sum), so the
  phase reference is that of the whole record. Angle samples are buffered only until the blocks
  of ``revolutions`` that need them are complete (the overlap in the angle domain is one block);
* VKF: overlapping segments with ``vkf_overlap`` / B_min seconds (default 8 decay lengths of
  the filter) on either side; only each segment's interior is kept, and the envelope phase is
  referred to the shaft angle from the record start.

Error: COT streamed equals the in-memory result to rounding (bit-identical in
``tests/analysis/test_stream.py``: 800 000 samples, 4 resampling chunks, 30 s segments, read
back from .h5). VKF streamed differs from the whole-record solve by the filter's memory cut at
the segment edges, ~exp(−vkf_overlap) of the envelope (2.4e-5 relative measured with the
default overlap, B = 2 Hz), and its solve grid (decimation) may differ per segment — compare on
common times.

:func:`decimate_stream` low-passes and decimates a long channel block by block (state carried)
for analyses that need the whole (low-band) channel in memory, e.g. the Campbell map.

Memory: O(segment) — a few times ``segment_seconds · fs`` float64 samples plus the result.
``benchmarks/analysis_memory.py`` measured on a 2 GB float32 .h5 record (500 M samples at
51.2 kHz, 2.7 h run-up 600 → 3000 rpm, 100 Hz speed channel): peak RSS 395 MB (181 MB of it
the interpreter and imports), 64 s (7.9 M samples/s, 31 MB/s) on 2 cores; order amplitudes
within the noise (mean error −3e-5 relative, max 4.4 σ over 36 620 blocks) and the phase from
the record start held over 1.8e5 revolutions.

References
----------
K. R. Fyfe and E. D. S. Munck, "Analysis of computed order tracking", MSSP 11(2) (1997).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from crankbench.predict._validate import check_int, check_option, check_positive, check_range
from crankbench.predict.errors import AnalysisError, RecordError
from crankbench.predict._deprecate import renamed

__all__ = ["SpanSpeed", "decimate_stream", "order_map_stream", "order_track_stream"]

log = logging.getLogger("crankbench")

_TWO_PI = 2.0 * np.pi


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
        if speed_rpm is None or hasattr(speed_rpm,
                                        "compute"):      # dask: sliced per span, never whole
            self._rpm = speed_rpm
        else:
            self._rpm = np.asarray(speed_rpm,
                                   float) if not np.isscalar(speed_rpm) else float(speed_rpm)
        self._t_in, self._omega = t_in, omega

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
    from .speedref import _is_pulses, _pulse_speed, _times, find_speed_channel

    n, fs = var.shape[0], float(var.attrs["sample_rate"])
    t0 = _first_time(record, var)
    if speed_rpm is not None:
        if not np.isscalar(speed_rpm) and np.shape(speed_rpm)[0] != n:
            raise AnalysisError(f"speed_rpm has {np.shape(speed_rpm)[0]} samples but channel {channel!r} has "
                                f"{n}; give one speed per sample, a constant, or speed_channel")
        return SpanSpeed(n, fs, t0, speed_rpm=speed_rpm)
    name = speed_channel or find_speed_channel(record, channel)
    if name not in record.data_vars:
        raise RecordError(f"record has no speed channel {name!r}")
    sv = record[name]
    if _is_pulses(sv):
        t_in, omega = _pulse_speed(sv, name)
    else:
        if sv.attrs.get("units", "rad/s") != "rad/s":
            raise RecordError(f"speed channel {name!r} has units {sv.attrs.get('units')!r}; "
                              "expected 'rad/s'")
        if sv.dims == var.dims:       # same clock: read the span of the speed channel itself
            return SpanSpeed(n, fs, t0, speed_rpm=sv.data * (60.0 / _TWO_PI))
        rate = sv.attrs.get("sample_rate")
        if rate is not None and sv.dims[0] in record.coords:   # regular clock: t0 + i/rate
            t_in = _first_time(record, sv) + np.arange(sv.shape[0]) / float(rate)
        else:
            t_in = np.asarray(_times(record, name), float)
        omega = np.asarray(sv.values, float)
    good = np.isfinite(omega)
    t_in, omega = np.asarray(t_in)[good], np.asarray(omega)[good]
    if t_in.shape[0] == 0:
        raise AnalysisError(f"speed source {name!r} holds no usable speed values")
    return SpanSpeed(n, fs, t0, t_in=t_in, omega=omega)


def _first_time(record, var) -> float:
    dim = var.dims[0]
    if dim in record.coords and var.shape[0]:
        return float(record[dim][0].values)
    return 0.0


def _reader(var):
    """``read(a, b)`` -> float64 samples a..b-1 of a (lazy) channel, checked finite."""
    data = var.data
    name = str(var.name)

    def read(a, b):
        block = data[a:b]
        block = np.asarray(block.compute() if hasattr(block, "compute") else block, np.float64)
        if not np.isfinite(block).all():
            i = a + int(np.flatnonzero(~np.isfinite(block))[0])
            raise AnalysisError(f"channel {name!r}: NaN/inf at sample {i}; streamed order "
                                "tracking needs finite samples (use order_track on a span)")
        return block
    return read


def _channel(record, channel):
    if channel not in record.data_vars:
        from crankbench.predict._validate import suggest

        raise RecordError(f"record has no channel {channel!r}"
                          f"{suggest(channel, map(str, record.data_vars))}; channels: "
                          f"{', '.join(map(str, record.data_vars))}")
    var = record[channel]
    if var.ndim != 1 or var.attrs.get("sample_rate") is None:
        raise RecordError(f"channel {channel!r} is not a sampled 1-D channel (no sample_rate)")
    return var


# ---------------------------------------------------------------------------- COT stream


def _chunk_plan(speed: SpanSpeed, chunk: int):
    """Chunk bounds of ``resample._chunk_bounds`` computed span by span, and the rpm range
    (cached on ``speed``: one pass over the speed per chunk size)."""
    cache = speed.__dict__.setdefault("_plans", {})
    if chunk not in cache:
        cache[chunk] = _plan(speed, chunk)
    return cache[chunk]


def _plan(speed: SpanSpeed, chunk: int):
    n = speed.n
    n_chunks = max(1, int(math.ceil(n / chunk)))
    pending = [int(v) for v in np.round(np.linspace(0, n, n_chunks + 1))]
    out = [pending[0]]
    lo, hi = np.inf, -np.inf
    ranges = []
    for b0 in pending[1:]:
        a0 = out[-1]
        sp = speed(a0, b0)
        lo, hi = min(lo, float(sp.min())), max(hi, float(sp.max()))
        if sp.min() <= 0:
            raise AnalysisError(f"rpm must be > 0 throughout; found {float(sp.min()):.6g} rpm "
                                f"between samples {a0} and {b0}")
        a = a0
        stack = [b0]
        while stack:
            b = stack[-1]
            seg = sp[a - a0:b - a0]
            if seg.max() <= 2.0 * seg.min() or b - a <= 256:
                out.append(b)
                ranges.append((float(seg.min()), float(seg.max())))
                stack.pop()
                a = b
            else:
                stack.append((a + b) // 2)
    return np.asarray(out, np.int64), ranges, lo, hi


def _angle_samples(read, speed: SpanSpeed, *, samples_per_rev, interpolation, chunk,
                   segment, label):
    """Yield ``(values, t_rel, rpm, angle)`` arrays of consecutive angle samples, exactly as
    :func:`analysis.resample.angle_resample` computes them, one group of chunks at a time."""
    from scipy import signal

    from .resample import _SINC_HALF, _antialias_taps, _interp

    n, fs = speed.n, speed.fs
    bounds, ranges, _, rmax = _chunk_plan(speed, chunk)
    per_rev = 60.0 * fs / rmax
    if per_rev < 2.0:
        raise AnalysisError(f"rpm up to {rmax:.6g} at fs = {fs:.6g} Hz leaves {per_rev:.3g} time "
                            "samples per revolution (at least 2 needed)")
    taps = [_antialias_taps(samples_per_rev, r0, r1, fs, n) for r0, r1 in ranges]
    half = [0 if h is None else h.shape[0] // 2 for h in taps]
    margin = _SINC_HALF + 2
    u_first, u_last = half[0] + margin, n - 1 - half[-1] - margin
    if u_last <= u_first:
        raise AnalysisError(f"{label}: record of {n} samples is shorter than the anti-alias "
                            f"filter ({2 * max(half) + 1} taps)")
    dphi = _TWO_PI / samples_per_rev
    # first pass: shaft angle at u_first and u_last (sequential sum, as shaft_angle does)
    phi_carry = 0.0          # phi at sample `pos`
    pos = 0
    phi_at = {}
    targets = sorted({u_first, u_last})
    step = max(chunk, 1 << 16)
    while pos < n - 1 and len(phi_at) < len(targets):
        b = min(n, pos + step + 1)
        omega = speed(pos, b) * (_TWO_PI / 60.0)
        inc = 0.5 * (omega[1:] + omega[:-1]) / fs
        phi = np.cumsum(np.concatenate(([phi_carry], inc)))
        for u in targets:
            if pos <= u < b:
                phi_at[u] = float(phi[u - pos])
        phi_carry, pos = float(phi[-1]), b - 1
    j0 = int(np.ceil(phi_at[u_first] / dphi))
    j1 = int(np.floor(phi_at[u_last] / dphi))
    if j1 - j0 < 3:
        raise AnalysisError(f"{label}: the record covers too few revolutions")
    # second pass: chunk groups
    groups, cur, size = [], [], 0
    for k in range(len(taps)):
        cur.append(k)
        size += int(bounds[k + 1] - bounds[k])
        if size >= segment:
            groups.append(cur)
            cur, size = [], 0
    if cur:
        groups.append(cur)
    windows = []
    for g in groups:
        s0, s1 = int(bounds[g[0]]), int(bounds[g[-1] + 1])
        hmax = max(half[k] for k in g)
        windows.append((max(0, s0 - hmax - margin), min(n, s1 + hmax + margin)))
    phi_carry, pos = 0.0, 0     # phi at sample pos (pos advances with the groups)
    next_j = j0
    for gi, g in enumerate(groups):
        s1 = int(bounds[g[-1] + 1])
        ra, rb = windows[gi]
        values = read(ra, rb)
        # shaft angle over [pos .. rb) (pos <= ra): continue the sequential sum
        omega = speed(pos, rb) * (_TWO_PI / 60.0)
        inc = 0.5 * (omega[1:] + omega[:-1]) / fs
        phi = np.cumsum(np.concatenate(([phi_carry], inc)))[ra - pos:]
        sp = omega[ra - pos:] * (60.0 / _TWO_PI)
        t = np.arange(ra, rb) / fs
        # angle samples whose time falls in [s0, s1) (the last group takes all up to j1)
        last = g[-1] == len(taps) - 1
        top = j1 if last else min(j1, int(np.floor(phi[-1] / dphi)))
        js = np.arange(next_j, top + 1)
        grid = js * dphi
        t_out = np.interp(grid, phi, t)
        u_out = t_out * fs
        if not last:
            keep = int(np.searchsorted(u_out, s1, side="left"))
            js, grid, t_out, u_out = js[:keep], grid[:keep], t_out[:keep], u_out[:keep]
        out = np.empty(grid.shape[0])
        for k in g:
            start, stop = int(bounds[k]), int(bounds[k + 1])
            lo = int(np.searchsorted(u_out, start, side="left"))
            hi = (int(np.searchsorted(u_out, stop, side="left")) if stop < n
                  else grid.shape[0])
            if hi <= lo:
                continue
            a, b = max(0, start - half[k] - margin), min(n, stop + half[k] + margin)
            if taps[k] is None:
                seg, offset = values[a - ra:b - ra], a
            else:
                seg = signal.oaconvolve(values[a - ra:b - ra], taps[k], mode="valid")
                offset = a + half[k]
            out[lo:hi] = _interp(seg, u_out[lo:hi] - offset, interpolation)
        rpm_out = np.interp(t_out, t, sp)
        if js.shape[0]:
            next_j = int(js[-1]) + 1
        # carry the shaft angle to the start of the next group's read window
        if not last:
            nxt_ra = windows[gi + 1][0]
            if not ra <= nxt_ra < rb:
                raise AnalysisError(f"{label}: internal: segment windows do not overlap "
                                    f"({ra}..{rb} then {nxt_ra}); raise segment_seconds")
            phi_carry, pos = float(phi[nxt_ra - ra]), nxt_ra
        yield out, t_out, rpm_out, grid


class _Framer:
    """Cut a stream of angle samples into blocks of ``length`` with hop ``hop``."""

    def __init__(self, length, hop):
        self.length, self.hop = length, hop
        self.buf = [np.empty(0)] * 4   # values, time, rpm, angle
        self.offset = 0                # global index of buf[...][0]
        self.next_start = 0

    def push(self, arrays, final=False):
        self.buf = [np.concatenate([b, a]) for b, a in zip(self.buf, arrays)]
        end = self.offset + self.buf[0].shape[0]
        last = end - self.length
        if last < self.next_start:
            return None
        starts = np.arange(self.next_start, last + 1, self.hop, dtype=np.int64)
        local = starts - self.offset
        out = (starts, local, [b for b in self.buf])
        self.next_start = int(starts[-1]) + self.hop
        drop = self.next_start - self.offset
        if drop > 0:
            self.buf = [b[drop:] for b in self.buf]
            self.offset += drop
        return out


def _cot_blocks(record, channel, *, orders, speed_rpm, speed_channel, samples_per_rev, revolutions,
                overlap, window, interpolation, segment_seconds, chunk, per_frames):
    """Run the streamed angle resampling and call ``per_frames(frames, phi0, t, r)``."""
    from .orders import get_window

    var = _channel(record, channel)
    label = str(channel)
    samples_per_rev = check_int(samples_per_rev, "samples_per_rev", minimum=4,
                                error=AnalysisError)
    revolutions = check_int(revolutions, "revolutions", minimum=1, error=AnalysisError)
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    from .resample import INTERPOLATIONS

    check_option(interpolation, "interpolation", INTERPOLATIONS, error=AnalysisError)
    segment_seconds = check_positive(segment_seconds, "segment_seconds", error=AnalysisError)
    chunk = check_int(chunk, "chunk", minimum=1024, error=AnalysisError)
    speed = _speed_for(record, channel, var, speed_rpm=speed_rpm, speed_channel=speed_channel)
    if orders is not None:          # before any work: the top order below the Nyquist frequency
        top = float(np.max(orders)) * _chunk_plan(speed, chunk)[3] / 60.0
        if top >= 0.5 * speed.fs:
            raise AnalysisError(f"order {np.max(orders):g} reaches {top:.6g} Hz, above the "
                                f"Nyquist frequency {0.5 * speed.fs:.6g} Hz of {label}")
    segment = max(chunk, int(round(segment_seconds * speed.fs)))
    length = samples_per_rev * revolutions
    hop = max(1, int(round(length * (1.0 - overlap))))
    w = get_window(window, length)
    framer = _Framer(length, hop)
    n_blocks = 0
    for arrays in _angle_samples(_reader(var), speed, samples_per_rev=samples_per_rev,
                                 interpolation=interpolation, chunk=chunk, segment=segment,
                                 label=label):
        got = framer.push(arrays)
        if got is None:
            continue
        _, local, (y, t, r, ang) = got
        centre = local + length / 2.0 - 0.5
        idx = np.arange(y.shape[0])
        tc = np.interp(centre, idx, t) + speed.t0
        rc = np.interp(centre, idx, r)
        for i in range(0, local.shape[0], 256):
            sl = local[i:i + 256]
            frames = y[sl[:, None] + np.arange(length)[None, :]]
            per_frames(frames, ang[sl], tc[i:i + 256], rc[i:i + 256])
        n_blocks += local.shape[0]
    if n_blocks == 0:
        raise AnalysisError(f"{label}: the record covers fewer revolutions than one block of "
                            f"revolutions={revolutions}; lower revolutions")
    return var, speed, w, length


@renamed(rpm="speed_rpm")
def order_track_stream(record, channel: str, *, orders, speed_rpm=None, speed_channel=None,
                       segment_seconds: float = 20.0, amplitude: str = "peak",
                       method: str = "cot", samples_per_rev: int = 64, revolutions: int = 16,
                       overlap: float = 0.5, window="hann", interpolation: str = "cubic",
                       chunk: int = 1 << 18, bandwidth_hz=None, bandwidth_orders=None,
                       filter_order: int = 2, vkf_overlap: float = 8.0):
    """:func:`analysis.order_track` of a (lazy) Record channel, segment by segment.

    Parameters
    ----------
    record : xarray.Dataset
        A Record, typically opened by :func:`measure.open` (dask-backed channels).
    channel : str
        Channel to analyse (needs ``sample_rate``).
    orders : sequence of float
        Orders to track.
    speed_rpm : float or array_like, optional
        Speed per sample (rpm) or a constant; default: from ``speed_channel`` (a
        ``rotational_speed`` channel on its own clock, or a pulse train), found in the record
        when not given — interpolated only over the span being processed.
    speed_channel : str, optional
        Name of the speed source.
    segment_seconds : float
        Length of record read at a time, s (memory ≈ a few × ``segment_seconds · fs`` × 8 B).
    amplitude, method, samples_per_rev, revolutions, overlap, window, interpolation, chunk
        As in :func:`analysis.order_track` / :func:`analysis.resample.angle_resample`
        (``chunk`` must equal the in-memory one for identical results; default the same).
    bandwidth_hz, bandwidth_orders, filter_order
        VKF parameters (:func:`analysis.vkf.vold_kalman`).
    vkf_overlap : float
        VKF segment overlap on either side, in units of ``1/B_min`` (s); error ~exp(−vkf_overlap).

    Returns
    -------
    xarray.Dataset
        As :func:`analysis.order_track`; attrs add ``streamed_segment_seconds``.

    References
    ----------
    Fyfe & Munck (1997), see the module docstring.

    Examples
    --------
    >>> from crankbench.measure.record import make_record
    >>> from crankbench.analysis.resample import shaft_angle
    >>> fs = 2000.0
    >>> t = np.arange(int(6 * fs)) / fs
    >>> rpm = 1200.0 + 60.0 * t
    >>> rec = make_record({"acc": dict(data=0.5 * np.cos(2 * shaft_angle(rpm, fs)),
    ...                                sample_rate=fs, units="m/s^2")})
    >>> res = order_track_stream(rec.chunk({"time": 3000}), "acc", orders=[2], speed_rpm=rpm,
    ...                          revolutions=8, segment_seconds=1.0, chunk=2048)
    >>> round(float(res.amplitude.mean()), 4)
    0.5
    """
    from .orders import _METHODS, _check_orders, _track_dataset, amplitude_factor

    method = check_option(method, "method", _METHODS, error=AnalysisError)
    factor = amplitude_factor(amplitude)
    orders = _check_orders(orders)
    if method == "vkf":
        return _vkf_stream(record, channel, orders=orders, speed_rpm=speed_rpm,
                           speed_channel=speed_channel,
                           segment_seconds=segment_seconds, amplitude=amplitude,
                           bandwidth_hz=bandwidth_hz, bandwidth_orders=bandwidth_orders,
                           filter_order=filter_order, vkf_overlap=vkf_overlap)
    spr = check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    if orders.max() > spr / 4 + 1e-12:
        raise AnalysisError(f"order {orders.max():g} exceeds samples_per_rev/4 = {spr / 4:g} "
                            f"(the anti-alias pass band); use samples_per_rev >= "
                            f"{int(np.ceil(4 * orders.max()))}")
    from scipy import fft

    from .orders import _scale_spectrum, get_window

    length = spr * int(revolutions)
    w = get_window(window, length)
    local = _TWO_PI * np.arange(length) / spr
    kernel = (w[:, None] * np.exp(-1j * np.outer(local, orders))) * (2.0 / w.sum())
    band = slice(1, min(length // 2, int(spr / 4.0 * int(revolutions))) + 1)
    parts = {"coef": [], "floor": [], "t": [], "r": []}

    def per_frames(frames, phi0, t, r):
        c = (frames @ kernel) * np.exp(-1j * np.outer(phi0, orders))
        power = _scale_spectrum(fft.rfft(frames * w, axis=1), w, "power", 1.0)[:, band]
        parts["coef"].append(c)
        parts["floor"].append(np.median(power, axis=1) / np.log(2.0))
        parts["t"].append(t)
        parts["r"].append(r)

    var, speed, w, length = _cot_blocks(
        record, channel, orders=orders, speed_rpm=speed_rpm, speed_channel=speed_channel,
        samples_per_rev=spr, revolutions=revolutions, overlap=overlap, window=window,
        interpolation=interpolation, segment_seconds=segment_seconds, chunk=chunk,
        per_frames=per_frames)
    coef = np.concatenate(parts["coef"])
    floor = np.concatenate(parts["floor"])
    enbw = float(length * np.sum(w ** 2) / np.sum(w) ** 2)
    units = str(var.attrs.get("units", ""))
    ds = _track_dataset(np.abs(coef).T * factor, np.angle(coef).T, orders,
                        np.concatenate(parts["t"]), np.concatenate(parts["r"]), units, channel)
    ds["amplitude_noise"] = ("time", np.sqrt(floor * enbw) * factor,
                             {"units": units, "long_name":
                              "1-sigma amplitude error from the broadband noise floor"})
    ds.attrs.update({"method": "computed order tracking (angle resampling + block DFT at order)",
                     "amplitude_convention": amplitude, "window": str(window),
                     "samples_per_rev": spr, "revolutions": int(revolutions),
                     "resolution_orders": 1.0 / int(revolutions), "overlap": overlap,
                     "interpolation": interpolation, "enbw_bins": enbw,
                     "streamed_segment_seconds": float(segment_seconds)})
    log.info("order_track_stream %s: %d blocks from %d samples", channel, coef.shape[0],
             speed.n)
    return ds


@renamed(rpm="speed_rpm")
def order_map_stream(record, channel: str, *, speed_rpm=None, speed_channel=None,
                     segment_seconds: float = 20.0, samples_per_rev: int = 64,
                     revolutions: int = 16, overlap: float = 0.5, window="hann",
                     amplitude: str = "peak", scaling: str = "amplitude", max_order=None,
                     interpolation: str = "cubic", chunk: int = 1 << 18):
    """:func:`analysis.order_map` (time × order) of a (lazy) Record channel, segment by segment.

    Parameters are those of :func:`analysis.order_map` plus ``record``, ``channel``, ``rpm``,
    ``speed_channel``, ``segment_seconds`` and ``chunk`` as in :func:`order_track_stream`
    (no ``rpm_bins``: bin the result with ``groupby_bins`` on its ``rpm`` coordinate).

    Returns
    -------
    xarray.DataArray
        Dims (``time``, ``order``), equal to the in-memory order map to rounding.

    Examples
    --------
    >>> from crankbench.measure.record import make_record
    >>> from crankbench.analysis.resample import shaft_angle
    >>> fs = 2000.0
    >>> rpm = np.full(12000, 1500.0)
    >>> rec = make_record({"acc": dict(data=0.7 * np.cos(3 * shaft_angle(rpm, fs)),
    ...                                sample_rate=fs, units="m/s^2")})
    >>> m = order_map_stream(rec, "acc", speed_rpm=1500.0, revolutions=8, chunk=2048)
    >>> round(float(m.sel(order=3).mean()), 4)
    0.7
    """
    import xarray as xr
    from scipy import fft

    from .orders import _scale_spectrum, amplitude_factor, get_window

    scaling = check_option(scaling, "scaling", ("amplitude", "power"), error=AnalysisError)
    factor = amplitude_factor(amplitude)
    spr = check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    top = spr / 4.0 if max_order is None else check_positive(max_order, "max_order",
                                                             error=AnalysisError)
    if top > spr / 2 + 1e-12:
        raise AnalysisError(f"max_order {top:g} exceeds samples_per_rev/2 = {spr / 2:g}")
    length = spr * int(revolutions)
    n_orders = min(length // 2 + 1, int(np.floor(top * int(revolutions))) + 1)
    w = get_window(window, length)
    parts = {"v": [], "t": [], "r": []}

    def per_frames(frames, phi0, t, r):
        X = fft.rfft(frames * w, axis=1)[:, :n_orders]
        parts["v"].append(_scale_spectrum(X, w, scaling, factor))
        parts["t"].append(t)
        parts["r"].append(r)

    var, _, w, length = _cot_blocks(
        record, channel, orders=None, speed_rpm=speed_rpm, speed_channel=speed_channel,
        samples_per_rev=spr, revolutions=revolutions, overlap=overlap, window=window,
        interpolation=interpolation, segment_seconds=segment_seconds, chunk=chunk,
        per_frames=per_frames)
    units = str(var.attrs.get("units", ""))
    out_units = units if scaling == "amplitude" else (f"({units})^2" if units else "1")
    attrs = {"units": out_units, "method": "order map (angle resampling + block rfft)",
             "scaling": scaling, "amplitude_convention": amplitude if scaling == "amplitude"
             else "mean-square per bin", "window": str(window), "samples_per_rev": spr,
             "revolutions": int(revolutions), "resolution_orders": 1.0 / int(revolutions),
             "overlap": overlap, "interpolation": interpolation,
             "enbw_bins": float(length * np.sum(w ** 2) / np.sum(w) ** 2),
             "streamed_segment_seconds": float(segment_seconds)}
    return xr.DataArray(np.concatenate(parts["v"]), dims=("time", "order"),
                        name=f"{channel} order map",
                        coords={"time": ("time", np.concatenate(parts["t"]), {"units": "s"}),
                                "rpm": ("time", np.concatenate(parts["r"]), {"units": "rpm"}),
                                "order": ("order", np.arange(n_orders) / int(revolutions),
                                          {"units": "1", "long_name": "shaft order"})},
                        attrs=attrs)


# ---------------------------------------------------------------------------- VKF stream


def _vkf_stream(record, channel, *, orders, speed_rpm, speed_channel, segment_seconds, amplitude,
                bandwidth_hz, bandwidth_orders, filter_order, vkf_overlap):
    from .orders import _track_dataset, amplitude_factor
    from .vkf import vold_kalman

    var = _channel(record, channel)
    speed = _speed_for(record, channel, var, speed_rpm=speed_rpm, speed_channel=speed_channel)
    vkf_overlap = check_positive(vkf_overlap, "vkf_overlap", error=AnalysisError)
    n, fs = speed.n, speed.fs
    read = _reader(var)
    seg = max(1024, int(round(segment_seconds * fs)))
    # smallest bandwidth over the record (Hz): constant, or proportional to the lowest speed
    if bandwidth_hz is not None:
        b_min = float(np.min(bandwidth_hz))
    else:
        bo = 0.1 if bandwidth_orders is None else float(np.min(bandwidth_orders))
        lo = min(float(speed(a, min(n, a + seg)).min()) for a in range(0, n, seg))
        b_min = bo * lo / 60.0
    pad = int(math.ceil(vkf_overlap / b_min * fs))
    factor = amplitude_factor(amplitude)
    env, times, rpms = [], [], []
    phi_carry, pos = 0.0, 0
    attrs = {}
    for a in range(0, n, seg):
        b = min(n, a + seg)
        ra, rb = max(0, a - pad), min(n, b + pad)
        sp = speed(ra, rb)
        # shaft angle at ra from the record start (carried sequential sum)
        if ra > pos:
            om = speed(pos, ra + 1) * (_TWO_PI / 60.0)
            phi_carry = float(np.cumsum(np.concatenate(([phi_carry],
                                                        0.5 * (om[1:] + om[:-1]) / fs)))[-1])
            pos = ra
        res = vold_kalman(read(ra, rb), fs=fs, speed_rpm=sp, orders=orders,
                          bandwidth_hz=bandwidth_hz,
                          bandwidth_orders=bandwidth_orders, filter_order=filter_order)
        tr = res["time"].values + ra / fs          # s from the channel's first sample
        sel = (tr >= a / fs) & (tr < b / fs) if b < n else tr >= a / fs
        e = res["envelope"].values[:, sel]
        env.append(e * np.exp(-1j * orders * phi_carry)[:, None])
        times.append(speed.t0 + tr[sel])
        rpms.append(res["rpm"].values[sel])
        attrs = dict(res.attrs)
    e = np.concatenate(env, axis=1)
    ds = _track_dataset(np.abs(e) * factor, np.angle(e), orders, np.concatenate(times),
                        np.concatenate(rpms), str(var.attrs.get("units", "")), channel)
    ds.attrs.update(attrs)
    ds.attrs.update({"amplitude_convention": amplitude,
                     "streamed_segment_seconds": float(segment_seconds),
                     "streamed_overlap_s": pad / fs})
    return ds


# ---------------------------------------------------------------------------- decimation


@renamed(rpm="speed_rpm")
def decimate_stream(record, channel: str, *, max_frequency: float, speed_rpm=None,
                    speed_channel=None):
    """Low-pass and decimate a (lazy) channel block by block, with the speed at the kept samples.

    For analyses that need the whole channel in memory but only a low band (e.g. the Campbell
    map of a long record). An 8th-order Butterworth low-pass (second-order sections, state
    carried across blocks, so the result does not depend on the block size) at
    ``1.25 · max_frequency`` precedes keeping every ``q``-th sample, ``q`` the largest integer
    with ``fs/q ≥ 3 · max_frequency``. Error: pass-band ripple 0 (Butterworth), attenuation
    ≤ 0.03 % below ``max_frequency/2`` and ≤ 3 % at ``max_frequency``; aliases are ≥ 48 dB down.

    Parameters
    ----------
    record : xarray.Dataset
        Record (lazy or not).
    channel : str
        Sampled channel.
    max_frequency : float
        Highest frequency to keep, Hz.
    rpm, speed_channel
        Speed source as in :func:`order_track_stream`.

    Returns
    -------
    (xarray.DataArray, ndarray)
        The decimated channel (attrs with the new ``sample_rate``; time coordinate in s) and
        the speed at its samples, rpm.

    Examples
    --------
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"x": dict(data=np.cos(2 * np.pi * 5 * np.arange(8000) / 1000.0),
    ...                              sample_rate=1000.0, units="V")})
    >>> y, r = decimate_stream(rec, "x", max_frequency=20.0, speed_rpm=600.0)
    >>> y.attrs["sample_rate"], round(float(np.abs(y[200:]).max()), 3), r[:2].tolist()
    (62.5, 1.0, [600.0, 600.0])
    """
    import xarray as xr
    from scipy import signal

    from crankbench.measure.io import iter_blocks

    var = _channel(record, channel)
    max_frequency = check_positive(max_frequency, "max_frequency", error=AnalysisError)
    speed = _speed_for(record, channel, var, speed_rpm=speed_rpm, speed_channel=speed_channel)
    fs = speed.fs
    q = max(1, int(fs // (3.0 * max_frequency)))
    kept, start = [], 0
    if q == 1:
        for _, block in iter_blocks(record, channel):
            kept.append(np.asarray(block, np.float64))
    else:
        sos = signal.butter(8, 1.25 * max_frequency, fs=fs, output="sos")
        zi = np.zeros((sos.shape[0], 2))
        for _, block in iter_blocks(record, channel):
            y, zi = signal.sosfilt(sos, np.asarray(block, np.float64), zi=zi)
            first = (-start) % q
            kept.append(y[first::q])
            start += block.shape[0]
    data = np.concatenate(kept)
    idx = np.arange(data.shape[0]) * q
    t = speed.t0 + idx / fs
    if speed._rpm is None:
        r = np.interp(t, speed._t_in, speed._omega) * (60.0 / _TWO_PI)
    elif np.ndim(speed._rpm) == 0:
        r = np.full(data.shape[0], speed._rpm)
    else:
        r = np.asarray(speed._rpm[::q], float)
    attrs = dict(var.attrs)
    attrs.update(sample_rate=fs / q, decimation=q,
                 antialias="butterworth order 8 at 1.25 max_frequency" if q > 1 else "none")
    out = xr.DataArray(data, dims=(var.dims[0],), name=channel, attrs=attrs,
                       coords={var.dims[0]: (var.dims[0], t, {"units": "s"})})
    return out, r
