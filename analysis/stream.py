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
  referred to the shaft angle from the record start;
* a speed or IAS channel is prepared as :func:`analysis.speedref.speed_reference` prepares it
  (counter glitches bridged with a warning, a speed negative throughout taken by its magnitude,
  a reversal refused, a fast or IAS channel cycle-averaged; an encoder angle channel unwrapped,
  its mean rotation the phase angle): on its own clock it is read whole and repaired by the
  same functions, on the analysed channel's clock block by block
  (:mod:`analysis.stream_speed`: equal to memory, ``tests/analysis/test_stream_speed.py``);
  a record where the shaft stops is tracked in each running span, as in memory;
* a pulse train (the speed source, or any wheel with a gap or mark in the record) gives the
  shaft angle per span as :func:`analysis.speedref.speed_reference` gives it in memory: the
  edges' mean rotation (:func:`analysis.trend.mean_rotation`, each span read with its reach as
  margin), phases referred to TDC of cylinder 1; a ``speed_rpm`` from ``speed_reference``
  brings its ``shaft_angle`` coordinate along (``tests/analysis/test_stream.py``: streamed COT
  equals in-memory to 1e-9 on a vibrating 60-2 wheel).

Error: COT streamed equals the in-memory result to rounding (``tests/analysis/test_stream.py``:
800 000 samples, 4 resampling chunks, 30 s segments, read back from .h5 — the resampled angle
samples bit-identical, amplitudes and phases to 1e-9). VKF streamed differs from the whole-record solve by the filter's memory cut at
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

from .stream_speed import SpanSpeed, _running_span, _speed_for, _stopped_spans

__all__ = ["SpanSpeed", "decimate_stream", "order_map_stream", "order_track_stream"]

log = logging.getLogger("crankbench")

_TWO_PI = 2.0 * np.pi


# ---------------------------------------------------------------------------- stops


def _track_running_spans(record, channel, speed, stops, options, *, compute=None,
                         what="orders are tracked"):
    """Streamed tracks (or, with ``compute=order_map_stream``, the order map) of each span
    where the shaft turns, as the in-memory tracker gives them (a warning names the standing
    spans; their results are absent)."""
    import warnings

    from .orders import OrderWarning
    from .spans import join_running_spans, running_spans

    compute = order_track_stream if compute is None else compute
    n, fs, t0 = speed.n, speed.fs, speed.t0
    runs, shown = running_spans(stops, n, t0=t0, fs=fs)
    warnings.warn(f"{channel}: the shaft stands (speed <= 0.5 % of {speed.extremes[1]:.6g} "
                  f"rpm) at {shown}; {what} in each running span separately",
                  OrderWarning, stacklevel=3)
    log.warning("%s: the shaft stands at %s; %s in each running span", channel, shown, what)
    dim = record[channel].dims[0]
    parts, skipped = [], []
    for a, b in runs:
        sub = record[[channel]].isel({dim: slice(a, b)})
        try:
            parts.append(compute(sub, channel, speed_rpm=_running_span(speed, a, b), **options))
        except AnalysisError as exc:
            skipped.append(f"{t0 + a / fs:.6g}..{t0 + (b - 1) / fs:.6g} s ({exc})")
    return join_running_spans(parts, skipped, stops, label=channel, t0=t0, fs=fs)


def _reader(var):
    """``read(a, b)`` -> float64 samples a..b-1 of a (lazy) channel, checked finite."""
    from .stream_speed import read_finite

    data = var.data
    label = f"channel {str(var.name)!r}"

    def read(a, b):
        return read_finite(data, a, b, label, "streamed order tracking needs finite samples "
                           "(use order_track on a span)")
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


def _chunk_plan(speed: SpanSpeed, chunk: int, samples_per_rev: int = 64,
                interpolation: str = "auto", clean_order: float | None = None):
    """The resampling plan of :func:`analysis.resample.plan_chunks`, computed span by span
    (cached on ``speed``: one pass over the speed per setting)."""
    from .resample import plan_chunks

    cache = speed.__dict__.setdefault("_plans", {})
    key = (chunk, samples_per_rev, interpolation, clean_order)
    if key not in cache:
        cache[key] = plan_chunks(speed, n=speed.n, fs=speed.fs, samples_per_rev=samples_per_rev,
                                 interpolation=interpolation, chunk=chunk,
                                 clean_order=clean_order)
    return cache[key]


def _speed_top(speed: SpanSpeed, chunk: int) -> float:
    """Highest speed of the record (rpm), one pass over the speed (cached)."""
    cache = speed.__dict__.setdefault("_top", {})
    if chunk not in cache:
        cache[chunk] = max(float(speed(a, min(speed.n, a + chunk)).max())
                           for a in range(0, speed.n, chunk))
    return cache[chunk]


class _AngleCarry:
    """The shaft angle of consecutive spans: integrated speed carried across spans (the same
    sequential sum as :func:`analysis.resample.shaft_angle` of the whole record), or the
    encoder angle evaluated per span."""

    def __init__(self, speed: SpanSpeed):
        self.speed = speed
        self.pos, self.phi = 0, 0.0          # the angle at sample `pos`

    def __call__(self, a: int, b: int) -> np.ndarray:
        """Angle (rad) of samples a..b-1, a >= the previous call's a."""
        from .resample import integrate_angle

        if self.speed.angle is not None:
            return self.speed.angle(a, b)
        if a < self.pos:
            raise AnalysisError(f"internal: angle asked from sample {a}, already past {self.pos}")
        phi = integrate_angle(self.speed(self.pos, b), self.speed.fs, self.phi)[a - self.pos:]
        return phi

    def advance(self, to: int, phi_span: np.ndarray, span_start: int) -> None:
        """Carry the angle to sample ``to`` (inside the span just computed)."""
        if self.speed.angle is None:
            self.phi, self.pos = float(phi_span[to - span_start]), to


def _angle_samples(read, speed: SpanSpeed, *, samples_per_rev, interpolation, chunk,
                   segment, label, clean_order=None):
    """Yield ``(values, t_rel, rpm, angle)`` arrays of consecutive angle samples, computed by
    :func:`analysis.resample.resample_span` (the in-memory engine) one group of chunks at a
    time."""
    from .resample import angle_range, resample_span

    n = speed.n
    plan = _chunk_plan(speed, chunk, samples_per_rev, interpolation, clean_order)
    first, last_u = plan.usable()
    if last_u <= first:
        raise AnalysisError(f"{label}: record of {n} samples is shorter than the anti-alias "
                            f"filter ({2 * max(plan.filter_half) + 1} samples)")
    # first pass: the shaft angle at the first and last usable samples
    carry = _AngleCarry(speed)
    step = max(chunk, 1 << 16)
    phi_at = {}
    pos = 0
    while len(phi_at) < 2 and pos < n:
        b = min(n, pos + step + 1)
        phi = carry(pos, b)
        for u in (first, last_u):
            if pos <= u < b:
                phi_at[u] = float(phi[u - pos])
        carry.advance(b - 1, phi, pos)
        pos = b - 1
        if b == n:
            break
    j0, j1 = angle_range(plan, phi_at[first], phi_at[last_u])
    if j1 - j0 < 3:
        raise AnalysisError(f"{label}: the record covers too few revolutions")
    # second pass: groups of chunks of about `segment` samples
    groups, cur, size = [], [], 0
    for k in range(plan.chunks):
        cur.append(k)
        size += int(plan.bounds[k + 1] - plan.bounds[k])
        if size >= segment:
            groups.append(cur)
            cur, size = [], 0
    if cur:
        groups.append(cur)
    from .chunk_blend import zone_input

    # each group reads its chunks' windows and, from its first chunk's lower boundary on,
    # the input of the crossfade there (which this group produces)
    windows = [(min(plan.window(g[0])[0], zone_input(plan, g[0] - 1)[0] if g[0] else n),
                plan.window(g[-1])[1]) for g in groups]
    carry = _AngleCarry(speed)
    next_j = j0
    for gi, g in enumerate(groups):
        ra, rb = windows[gi]
        last = g[-1] == plan.chunks - 1
        phi = carry(ra, rb)
        out, t_out, rpm_out, grid = resample_span(plan, g, read(ra, rb), ra, phi,
                                                  speed(ra, rb), next_j, j1, last=last)
        if grid.shape[0]:
            next_j = int(round(grid[-1] / (_TWO_PI / samples_per_rev))) + 1
        if not last:
            nxt = windows[gi + 1][0]
            if not ra <= nxt < rb:
                raise AnalysisError(f"{label}: internal: segment windows do not overlap "
                                    f"({ra}..{rb} then {nxt}); raise segment_seconds")
            carry.advance(nxt, phi, ra)
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


def _prepare(record, channel, *, speed_rpm, speed_channel, chunk, trend, segment_seconds,
             orders=None, speed=None):
    """Channel, speed, detrending reader and segment length of a streamed analysis."""
    var = _channel(record, channel)
    label = str(channel)
    segment_seconds = check_positive(segment_seconds, "segment_seconds", error=AnalysisError)
    chunk = check_int(chunk, "chunk", minimum=1024, error=AnalysisError)
    if speed is None:
        speed = _speed_for(record, channel, var, speed_rpm=speed_rpm,
                           speed_channel=speed_channel)
    if orders is not None:          # before any work: the top order below the Nyquist frequency
        top = float(np.max(orders)) * _speed_top(speed, chunk) / 60.0
        if top >= 0.5 * speed.fs:
            raise AnalysisError(f"order {np.max(orders):g} reaches {top:.6g} Hz, above the "
                                f"Nyquist frequency {0.5 * speed.fs:.6g} Hz of {label}")
    segment = max(chunk, int(round(segment_seconds * speed.fs)))
    reader = _detrending_reader(var, speed, chunk, trend, segment)
    return var, label, speed, segment, reader


def _detrending_reader(var, speed, chunk, trend, segment):
    """The channel reader with its trend removed (:class:`analysis.trend.SpanTrend`)."""
    from .trend import SpanTrend

    raw = _reader(var)
    n = speed.n
    # shaft angle at the record's ends and the lowest speed: one pass over the speed
    carry = _AngleCarry(speed)
    low = np.inf
    first = last = None
    step = max(chunk, 1 << 16)
    pos = 0
    while True:
        b = min(n, pos + step + 1)
        phi = carry(pos, b)
        low = min(low, float(speed(pos, b).min()))
        if first is None:
            first = float(phi[0])
        if b == n:
            last = float(phi[-1])
            break
        carry.advance(b - 1, phi, pos)
        pos = b - 1
    span = SpanTrend(raw, speed, lambda: _AngleCarry(speed), n=n, fs=speed.fs,
                     ends=(first, last), low_rpm=low, kind=trend)
    span.fit(segment)
    return span


def _blocks(speed, reader, *, label, samples_per_rev, revolutions, overlap, interpolation,
            chunk, segment, per_frames, centroid=None, clean_order=None):
    """Run the streamed angle resampling and call ``per_frames(frames, phi0, t, r, span)``
    (``t``, ``r`` at ``centroid`` samples from each block's first, default its middle;
    ``clean_order`` as in :func:`analysis.resample.plan_chunks`)."""
    samples_per_rev = check_int(samples_per_rev, "samples_per_rev", minimum=4,
                                error=AnalysisError)
    revolutions = check_int(revolutions, "revolutions", minimum=1, error=AnalysisError)
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    from .resample import INTERPOLATIONS

    check_option(interpolation, "interpolation", INTERPOLATIONS, error=AnalysisError)
    length = samples_per_rev * revolutions
    from .blocks import _hop

    hop = _hop(length, overlap)
    framer = _Framer(length, hop)
    n_blocks = 0
    for arrays in _angle_samples(reader, speed, samples_per_rev=samples_per_rev,
                                 interpolation=interpolation, chunk=chunk, segment=segment,
                                 label=label, clean_order=clean_order):
        got = framer.push(arrays)
        if got is None:
            continue
        _, local, (y, t, r, ang) = got
        idx = np.arange(y.shape[0])
        at = local + (length / 2.0 - 0.5 if centroid is None else centroid)
        tc = np.interp(at, idx, t) + speed.t0
        rc = np.interp(at, idx, r)
        dur = np.interp(local + length - 1.0, idx, t) - t[local]
        for i in range(0, local.shape[0], 256):
            sl = local[i:i + 256]
            frames = y[sl[:, None] + np.arange(length)[None, :]]
            per_frames(frames, ang[sl], tc[i:i + 256], rc[i:i + 256], dur[i:i + 256])
        n_blocks += local.shape[0]
    if n_blocks == 0:
        raise AnalysisError(f"{label}: the record covers fewer revolutions than one block of "
                            f"revolutions={revolutions}; lower revolutions")


def _coarse_speed(speed: SpanSpeed, points: int = 20000) -> np.ndarray:
    """The speed at about ``points`` samples spread over the record (sweep-rate estimate)."""
    step = max(1, speed.n // points)
    span = step * max(1, (1 << 18) // step)          # whole spans, every step-th sample kept
    return np.concatenate([speed(a, min(speed.n, a + span))[::step]
                           for a in range(0, speed.n, span)]), speed.fs / step


@renamed(rpm="speed_rpm")
def order_track_stream(record, channel: str, *, orders, speed_rpm=None, speed_channel=None,
                       segment_seconds: float = 20.0, amplitude: str = "peak",
                       method: str = "auto", samples_per_rev=None, revolutions=None,
                       overlap: float = 0.5, window="hann", interpolation: str = "auto",
                       chunk: int = 1 << 18, bandwidth_hz=None, bandwidth_orders=None,
                       filter_order: int = 2, vkf_overlap: float = 8.0, trend: str = "auto"):
    """:func:`analysis.order_track` of a (lazy) Record channel, segment by segment.

    Parameters
    ----------
    record : xarray.Dataset
        A Record, typically opened by :func:`measure.open` (dask-backed channels).
    channel : str
        Channel to analyse (needs ``sample_rate``).
    orders : sequence of float
        Orders to track, each once.
    speed_rpm : float or array_like, optional
        Speed per sample (rpm) or a constant; default: from ``speed_channel`` (a
        ``rotational_speed`` channel on its own clock, or a pulse train), found in the record
        when not given — interpolated only over the span being processed.
    speed_channel : str, optional
        Name of the speed source.
    segment_seconds : float
        Length of record read at a time, s (memory ≈ a few × ``segment_seconds · fs`` × 8 B).
    amplitude, samples_per_rev, revolutions, overlap, window, interpolation, chunk, trend
        As in :func:`analysis.order_track` / :func:`analysis.resample.angle_resample`
        (``chunk`` must equal the in-memory one for identical results; default the same).
    method : {'auto', 'cot', 'vkf'}
        'auto' is COT with the block length chosen from the sweep rate and the order spacing
        (:func:`analysis.orders.cot_settings`): the adaptive Vold–Kalman default of the
        in-memory tracker needs the whole record.
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
    >>> rec = make_record({"acc": dict(data=0.5 * np.cos(2 * shaft_angle(rpm, fs)) + 3.0,
    ...                                sample_rate=fs, units="m/s^2")})
    >>> res = order_track_stream(rec.chunk({"time": 3000}), "acc", orders=[2], speed_rpm=rpm,
    ...                          revolutions=8, segment_seconds=1.0, chunk=2048)
    >>> round(float(res.amplitude.mean()), 4), round(float(res["mean"].mean()), 4)
    (0.5, 3.0)
    """
    from .orders import (_METHODS, BlockFit, _check_orders, _cot_dataset, amplitude_factor,
                         cot_settings)

    method = check_option(method, "method", _METHODS, error=AnalysisError)
    factor = amplitude_factor(amplitude)
    orders = _check_orders(orders)
    speed = None
    if not isinstance(speed_rpm, SpanSpeed):
        speed = _speed_for(record, channel, _channel(record, channel), speed_rpm=speed_rpm,
                           speed_channel=speed_channel)
        stops = _stopped_spans(speed)
        if stops is not None:
            return _track_running_spans(record, channel, speed, stops, dict(
                orders=orders, segment_seconds=segment_seconds, amplitude=amplitude,
                method=method, samples_per_rev=samples_per_rev, revolutions=revolutions,
                overlap=overlap, window=window, interpolation=interpolation, chunk=chunk,
                bandwidth_hz=bandwidth_hz, bandwidth_orders=bandwidth_orders,
                filter_order=filter_order, vkf_overlap=vkf_overlap, trend=trend))
    else:
        speed = speed_rpm
    var, label, speed, segment, reader = _prepare(
        record, channel, speed_rpm=None, speed_channel=speed_channel, chunk=chunk,
        trend=trend, segment_seconds=segment_seconds, orders=orders, speed=speed)
    if method == "vkf" or (method == "auto" and (bandwidth_hz is not None
                                                 or bandwidth_orders is not None)):
        return _vkf_stream(var, label, speed, reader, orders=orders, segment=segment,
                           amplitude=amplitude, bandwidth_hz=bandwidth_hz,
                           bandwidth_orders=bandwidth_orders, filter_order=filter_order,
                           vkf_overlap=vkf_overlap, trend_info=reader.info)
    coarse, coarse_fs = _coarse_speed(speed)
    revolutions, spr = cot_settings(coarse, coarse_fs, orders, revolutions=revolutions,
                                    samples_per_rev=samples_per_rev)
    if orders.max() > spr / 4 + 1e-12:
        raise AnalysisError(f"order {orders.max():g} exceeds samples_per_rev/4 = {spr / 4:g} "
                            f"(the anti-alias pass band); use samples_per_rev >= "
                            f"{int(np.ceil(4 * orders.max()))}")
    fitter = BlockFit(orders, spr, revolutions, window)
    fitter.check_spacing()
    keys = ("coef", "mean", "floor", "level", "spec", "phi0", "t", "r", "span")
    parts = {key: [] for key in keys}

    def per_frames(frames, phi0, t, r, span):
        coef, mean, floor, level, spec = fitter.fit(frames, phi0, spectra=True)
        for key, value in zip(keys, (coef, mean, floor, level, spec,
                                     phi0, t, r, span)):
            parts[key].append(value)

    _blocks(speed, reader, label=label, samples_per_rev=spr, revolutions=revolutions,
            overlap=overlap, interpolation=interpolation, chunk=chunk, segment=segment,
            per_frames=per_frames, centroid=fitter.centroid)
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    # the signal's other lines out of the noise floor, as in memory (analysis.cot_noise)
    from .blocks import _hop

    cat["floor"] = fitter.line_free_floor(cat["spec"], cat["floor"], cat["phi0"],
                                          _hop(fitter.length, overlap))
    context = {"factor": factor, "units": str(var.attrs.get("units", "")), "label": label,
               "reference": speed.angle_reference}
    plan = _chunk_plan(speed, chunk, spr, interpolation)
    ds = _cot_dataset(cat["coef"], cat["mean"], cat["floor"], fitter, cat["t"], cat["r"],
                      cat["span"], context, overlap=overlap, interpolation=plan.interpolation,
                      plan=plan, level=cat["level"])
    ds.attrs.update({"amplitude_convention": amplitude, "trend": reader.info["removed"],
                     "trend_kind": reader.info["kind"],
                     "streamed_segment_seconds": float(segment_seconds)})
    log.info("order_track_stream %s: %d blocks from %d samples", channel, cat["coef"].shape[0],
             speed.n)
    return ds


@renamed(rpm="speed_rpm")
def order_map_stream(record, channel: str, *, speed_rpm=None, speed_channel=None,
                     segment_seconds: float = 20.0, samples_per_rev: int = 64,
                     revolutions: int = 16, overlap: float = 0.5, window="hann",
                     amplitude: str = "peak", scaling: str = "amplitude", max_order=None,
                     interpolation: str = "auto", chunk: int = 1 << 18, trend: str = "auto"):
    """:func:`analysis.order_map` (time × order) of a (lazy) Record channel, segment by segment.

    Parameters are those of :func:`analysis.order_map` plus ``record``, ``channel``,
    ``speed_channel``, ``segment_seconds`` and ``chunk`` as in :func:`order_track_stream`
    (no ``speed_bins_rpm``: bin the result with ``groupby_bins`` on its ``rpm`` coordinate).

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

    from .orders import amplitude_factor
    from .ordermap import MapSpectra

    scaling = check_option(scaling, "scaling", ("amplitude", "power"), error=AnalysisError)
    factor = amplitude_factor(amplitude)
    spr = check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    top = spr / 4.0 if max_order is None else check_positive(max_order, "max_order",
                                                             error=AnalysisError)
    if top > spr / 2 + 1e-12:
        raise AnalysisError(f"max_order {top:g} exceeds samples_per_rev/2 = {spr / 2:g}")
    if not isinstance(speed_rpm, SpanSpeed):
        speed = _speed_for(record, channel, _channel(record, channel), speed_rpm=speed_rpm,
                           speed_channel=speed_channel)
        stops = _stopped_spans(speed)
        if stops is not None:      # a record that stops: the map of each running span
            return _track_running_spans(record, channel, speed, stops, dict(
                segment_seconds=segment_seconds, samples_per_rev=samples_per_rev,
                revolutions=revolutions, overlap=overlap, window=window, amplitude=amplitude,
                scaling=scaling, max_order=max_order, interpolation=interpolation,
                chunk=chunk, trend=trend), compute=order_map_stream,
                what="the order map is computed")
        speed_rpm = speed
    var, label, speed, segment, reader = _prepare(
        record, channel, speed_rpm=None if isinstance(speed_rpm, SpanSpeed) else speed_rpm,
        speed_channel=speed_channel, chunk=chunk, trend=trend,
        segment_seconds=segment_seconds,
        speed=speed_rpm if isinstance(speed_rpm, SpanSpeed) else None)
    length = spr * int(revolutions)
    n_orders = min(length // 2 + 1, int(np.floor(top * int(revolutions))) + 1)
    spectra = MapSpectra(length, window, scaling, factor, n_orders)
    parts = {"v": [], "t": [], "r": []}

    def per_frames(frames, phi0, t, r, span):
        parts["v"].append(spectra(frames))
        parts["t"].append(t)
        parts["r"].append(r)

    _blocks(speed, reader, label=label, samples_per_rev=spr, revolutions=revolutions,
            overlap=overlap, interpolation=interpolation, chunk=chunk, segment=segment,
            per_frames=per_frames, centroid=spectra.centroid, clean_order=top)
    units = str(var.attrs.get("units", ""))
    out_units = units if scaling == "amplitude" else (f"({units})^2" if units else "1")
    plan = _chunk_plan(speed, chunk, spr, interpolation, top)
    attrs = {"units": out_units, "method": "order map (angle resampling + block rfft, block "
                                           "trend removed; order 0 = block mean)",
             "scaling": scaling, "amplitude_convention": amplitude if scaling == "amplitude"
             else "mean-square per bin", "window": str(window), "samples_per_rev": spr,
             "revolutions": int(revolutions), "resolution_orders": 1.0 / int(revolutions),
             "overlap": overlap, "interpolation": plan.interpolation,
             "enbw_bins": spectra.enbw, "trend": reader.info["removed"],
             "phase_reference": speed.angle_reference,
             "streamed_segment_seconds": float(segment_seconds)}
    return xr.DataArray(np.concatenate(parts["v"]), dims=("time", "order"),
                        name=f"{channel} order map",
                        coords={"time": ("time", np.concatenate(parts["t"]), {"units": "s"}),
                                "rpm": ("time", np.concatenate(parts["r"]), {"units": "rpm"}),
                                "order": ("order", np.arange(n_orders) / int(revolutions),
                                          {"units": "1", "long_name": "shaft order"})},
                        attrs=attrs)


# ---------------------------------------------------------------------------- VKF stream


def _vkf_stream(var, label, speed, reader, *, orders, segment, amplitude, bandwidth_hz,
                bandwidth_orders, filter_order, vkf_overlap, trend_info):
    from .orders import _track_dataset, amplitude_factor
    from .vkf import vold_kalman

    vkf_overlap = check_positive(vkf_overlap, "vkf_overlap", error=AnalysisError)
    n, fs = speed.n, speed.fs
    seg = segment
    # smallest bandwidth over the record (Hz): constant, or proportional to the lowest speed
    if bandwidth_hz is not None:
        b_min = float(np.min(bandwidth_hz))
    else:
        bo = 0.1 if bandwidth_orders is None else float(np.min(bandwidth_orders))
        lo = min(float(speed(a, min(n, a + seg)).min()) for a in range(0, n, seg))
        b_min = bo * lo / 60.0
    pad = int(math.ceil(vkf_overlap / b_min * fs))
    factor = amplitude_factor(amplitude)
    env, times, rpms, means, unc = [], [], [], [], []
    carry = _AngleCarry(speed)
    attrs = {}
    for a in range(0, n, seg):
        b = min(n, a + seg)
        ra, rb = max(0, a - pad), min(n, b + pad)
        phi = carry(ra, rb)
        res = vold_kalman(reader(ra, rb), fs=fs, speed_rpm=speed(ra, rb), orders=orders,
                          bandwidth_hz=bandwidth_hz, bandwidth_orders=bandwidth_orders,
                          filter_order=filter_order, shaft_angle=phi)
        tr = res["time"].values + ra / fs          # s from the channel's first sample
        sel = (tr >= a / fs) & (tr < b / fs) if b < n else tr >= a / fs
        env.append(res["envelope"].values[:, sel])
        times.append(speed.t0 + tr[sel])
        rpms.append(res["rpm"].values[sel])
        means.append(res["mean"].values[sel])
        unc.append(res["amplitude_uncertainty"].values[:, sel])
        attrs = dict(res.attrs)
        if b < n:
            nxt = max(0, b - pad)
            if nxt < ra:            # pragma: no cover - windows advance by a whole segment
                raise AnalysisError(f"{label}: internal: VKF windows do not advance")
            carry.advance(nxt, phi, ra)
    e = np.concatenate(env, axis=1)
    units = str(var.attrs.get("units", ""))
    ds = _track_dataset(np.abs(e) * factor, np.angle(e), orders, np.concatenate(times),
                        np.concatenate(rpms), units, label)
    ds["mean"] = ("time", np.concatenate(means), {"units": units, "long_name":
                                                  "order 0: trend envelope (the channel's mean)"})
    ds["amplitude_uncertainty"] = (("order", "time"), np.concatenate(unc, axis=1) * factor,
                                   {"units": units, "long_name": "1-sigma amplitude noise and "
                                    "estimated envelope smearing"})
    ds.attrs.update(attrs)
    ds.attrs["phase_reference"] = speed.angle_reference
    ds.attrs.update({"amplitude_convention": amplitude, "trend": trend_info["removed"],
                     "trend_kind": trend_info["kind"],
                     "streamed_segment_seconds": seg / fs, "streamed_overlap_s": pad / fs})
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
