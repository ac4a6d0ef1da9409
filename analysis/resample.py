"""Angle-domain resampling: computed order tracking (COT).

A time record ``x(t)`` taken while the shaft turns at ``rpm(t)`` is re-sampled at constant
increments of shaft angle, so that an order ``o`` (a component ``cos(o φ)``) becomes a fixed
frequency of ``o`` cycles per revolution whatever the speed does. Steps:

1. shaft angle ``φ(t)``: either given per sample (the encoder angle from the pulse edges,
   :func:`analysis.speedref.speed_reference` attaches it), or ``∫ 2π rpm/60 dt`` by the
   trapezoidal rule (exact for a speed linear between samples; φ = 0 at the first sample);
2. anti-alias low-pass, chunk by chunk, applied in the frequency domain: one real FFT of the
   chunk, multiplied by the response of a Kaiser-windowed ideal low-pass (100 dB; impulse
   response of finite length ``±T``, ``T = β/(π Δf)``), passing orders ≤ ``samples_per_rev/4``
   at the chunk's top speed (ripple ≈ 1e-5) and stopping orders ≥ ``3/4 samples_per_rev`` at
   its lowest speed; the inverse FFT keeps only the bins below the output rate's Nyquist
   frequency, so the filtered chunk comes out decimated (by a fractional factor, ≥ 4 samples
   per period of the stop edge) for the cost of about one FFT of the chunk. Half-band
   decimations by 2 come first (31-tap equiripple, pass band to 1/8 and stop band from 3/8
   of their input rate, both within 1.7e-7: 135 dB; one compiled pass each), as many as keep
   the orders in use (``samples_per_rev/4``, or an order map's ``max_order``) at the chunk's
   top speed within a quarter of the rate they leave: there every stage is flat and what it
   folds comes from its stop band; what it folds from its transition band lands above those
   orders and below ``3/4 samples_per_rev``, where the angle sampling does not fold it back
   (on records at least 1000× the 15·(2^stages − 1) samples they leave incomplete at either
   end). The FFT then runs on 1/2^stages of the samples (lengths ``2^a 5^b 3^c``, the chunk
   read with real samples up to that length rather than zero padded — after the chunk, or
   before it at the record's end) and zero pads its spectrum where the output rate is higher
   than the stages' rate; the anti-alias stop band measured on a 1000→3000 rpm run-up: a
   unit tone at orders 48–63 leaves ≤ 7.7e-6 at its alias, i.e. ≥ 102 dB. The ``T·fs``
   samples at either end of a chunk window, where the filter is incomplete, are never used:
   chunks are read with that margin, and the record ends are trimmed rather than padded.
   Neighbouring chunks' filters differ in their transition band, so at a boundary the signal
   crossfades from one to the other over 2 revolutions either side
   (:mod:`analysis.chunk_blend`): a component there is faded, not switched (switched, a unit
   tone at order 20–30 leaked 1.8e-3 into every order of the straddling block);
3. the times of the constant-angle samples from the inverse of φ(t);
4. interpolation of the filtered signal at those times: ``"bandlimited"`` (default through
   ``"auto"``: Kaiser-windowed sinc, 16 taps, β = 12.5, weights normalised to a unit sum),
   ``"cubic"`` (4-point Lagrange) or ``"linear"`` (the last two at the full input rate, no
   decimation).

Interpolation error for a tone at ``f`` sampled at ``fs`` (``h = 2π f/fs``), peak relative,
measured by the bench suite ``orders`` against the closed form: linear ≈ h²/8, cubic ≈ 3h⁴/128,
band-limited ≤ 5e-6 for ``f ≤ fs/4`` (1.7e-3 at 0.3 fs, 0.15 at 0.4 fs — the decimation keeps
every component the filter passes below ``fs_out/4``); checked at these figures by
``tests/analysis/test_resample_interp.py``.

Half orders of a four-stroke engine (one cycle = 720°) need no separate grid: the angle samples
run continuously from the angle reference, and an analysis block of an even number of
revolutions (``revolutions`` in :mod:`analysis.orders`, or ``revolutions_per_cycle=2`` in
:func:`analysis.synchronous_average`) puts every half order on a bin.

One engine serves the in-memory and the streamed paths: :func:`plan_chunks` decides chunks,
filters and decimation from the speed alone, and :func:`resample_span` turns one span of
input samples (with its shaft angle) into angle samples. :func:`angle_resample` calls it once
for the whole record; :mod:`analysis.stream` calls it group by group with the shaft angle
carried across segments, so both produce the same numbers.

References
----------
K. R. Fyfe and E. D. S. Munck, "Analysis of computed order tracking", Mechanical Systems and
Signal Processing 11(2), 187–205 (1997).
J. F. Kaiser, "Nonrecursive digital filter design using the I0-sinh window function", Proc.
IEEE ISCAS (1974) — the window and its Fourier transform.
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import dataclass

import numpy as np

from crankbench.predict._deprecate import renamed
from crankbench.predict._validate import (check_finite_array, check_int, check_option,
                                          check_positive)
from crankbench.predict.errors import AnalysisError

from .speed_spans import _split_chunks
from .antialias import (_kaiser_step, _lowpass_gain, _aa_half_length, _good_size, _HB_TAPS, _HB_REACH, _HB_MAX_STAGES, _halfband_taps, _fft_lowpass, _lowpass_response)  # noqa: F401 (re-exported)

__all__ = ["angle_resample", "shaft_angle", "plan_chunks", "resample_span", "ChunkPlan",
           "INTERPOLATIONS"]

log = logging.getLogger("crankbench")

#: interpolation names ('auto' = band-limited)
INTERPOLATIONS = ("auto", "linear", "cubic", "bandlimited")

_SINC_HALF = 8        # band-limited kernel half-width in samples (16 taps)
_SINC_BETA = 12.5     # Kaiser shape of the band-limited kernel (error <= 5e-6 up to fs/4)
_SINC_PHASES = 512    # fractional positions tabulated (linear between them: < 1e-8)
_AA_BETA = 0.1102 * (100.0 - 8.7)   # Kaiser beta of the 100 dB anti-alias low-pass
_TWO_PI = 2.0 * np.pi


# ---------------------------------------------------------------------------- input handling


def _as_signal(x, fs, name: str = "x"):
    """Return ``(values, fs, units, label)`` from a plain array or a Record channel.

    A Record channel is an ``xarray.DataArray`` with ``sample_rate`` (Hz) and ``units`` attrs;
    its sample rate is used unless ``fs`` is given (then they must agree).
    """
    units = ""
    label = name
    attrs = getattr(x, "attrs", None)
    if attrs is not None and hasattr(x, "dims"):
        units = str(attrs.get("units", ""))
        label = str(getattr(x, "name", None) or name)
        rate = attrs.get("sample_rate")
        if rate is not None:
            rate = check_positive(rate, f"{label}.attrs['sample_rate']", error=AnalysisError)
            if fs is not None and not math.isclose(float(fs), rate, rel_tol=1e-9):
                raise AnalysisError(
                    f"fs={fs!r} disagrees with channel {label!r} sample_rate={rate!r} Hz; "
                    "omit fs to use the channel's rate")
            fs = rate
        x = x.values
    if fs is None:
        raise AnalysisError(f"fs is required for a plain array {name}; give the sample rate in Hz")
    fs = check_positive(fs, "fs", error=AnalysisError)
    if np.ndim(x) == 1 and np.shape(x)[0] == 0:
        raise AnalysisError(f"{label} holds no samples (zero-length channel); order analysis "
                            "needs a record of at least a few revolutions")
    values = _finite_fast(x, 8, label)
    if values is None:          # something is wrong: the full check names it
        values = check_finite_array(x, label, ndim=1, min_length=8, error=AnalysisError)
    return values, fs, units, label


#: about the largest magnitude the order analysis takes (in the channel's unit): the sum of
#: squares of the samples must be finite (a record of 10⁸ samples at this level sums to 1e308)
MAX_MAGNITUDE = 1e150


def _finite_fast(x, min_length: int, label: str | None = None):
    """``x`` as a float64 1-D array when it is one of at least ``min_length`` finite values
    whose sum of squares is finite, decided in one pass (``x·x``, finite only if every term
    is and nothing overflows), else None (then the full check, :func:`check_finite_array`,
    names what is wrong). With ``label``: finite values too large to square and sum raise
    :class:`AnalysisError` naming the channel and its largest magnitude (every later sum of
    squares of the analysis would overflow into NaN)."""
    if isinstance(x, np.ndarray) and x.dtype == np.float64:
        arr = x
    else:
        try:
            arr = np.asarray(x, dtype=np.float64)
        except (TypeError, ValueError):
            return None
    if arr.ndim != 1 or arr.shape[0] < min_length:
        return None
    with np.errstate(over="ignore", invalid="ignore"):     # an overflow means: check fully
        total = float(np.dot(arr, arr)) if arr.flags.c_contiguous else float(
            np.add.reduce(arr * arr))
    if np.isfinite(total):
        return arr
    if label is not None and np.isfinite(arr).all():
        raise AnalysisError(
            f"{label} reaches {float(np.max(np.abs(arr))):.3g} (in its unit): too large to "
            f"analyse (its sum of squares overflows; magnitudes up to about {MAX_MAGNITUDE:.0e} "
            "are taken); check the channel's unit and calibration, or scale it")
    return None


def _as_rpm(rpm, n: int, fs: float | None = None, *, allow_stop: bool = False) -> np.ndarray:
    """Speed in rpm as an array of length ``n`` (a scalar means a steady speed).

    ``fs`` (Hz), when known, lets an error say at what time the speed was bad.
    ``allow_stop``: zero speed is accepted (a time-domain map labels frames by speed; only
    a negative speed is refused).
    """
    if hasattr(rpm, "values") and hasattr(rpm, "dims"):
        rpm = rpm.values
    arr = np.asarray(rpm, dtype=float) if not np.isscalar(rpm) else None
    if arr is None or arr.ndim == 0:
        value = check_positive(rpm if arr is None else float(arr), "rpm", error=AnalysisError)
        return np.full(n, value)
    if arr.ndim == 1 and arr.shape[0] == 0:
        raise AnalysisError("speed_rpm holds no samples (zero-length speed channel)")
    fast = _finite_fast(arr, 1)
    if fast is not None and fast.shape[0] == n and fast.min() > 0:
        return fast                     # finite, one per sample, turning: the common case
    arr = check_finite_array(arr, "rpm", ndim=1, error=AnalysisError)
    if arr.shape[0] != n:
        raise AnalysisError(f"rpm has {arr.shape[0]} samples but the signal has {n}; "
                            "give one speed per signal sample (see analysis.speedref)")
    if arr.min() < 0 or (arr.min() == 0 and not allow_stop):
        bad = np.flatnonzero(arr < 0 if allow_stop else arr <= 0)
        i, j = int(bad[0]), int(bad[-1])
        when = (lambda k: f" (t = {k / fs:.6g} s)") if fs else (lambda k: "")
        raise AnalysisError(f"rpm must be > 0 throughout (shaft turning one way); found "
                            f"{len(bad)} sample(s) <= 0 (min {float(arr.min()):.6g} rpm), first "
                            f"at sample {i}{when(i)}, last at sample {j}{when(j)}; trim the "
                            "record to the running span")
    return arr


def _as_angle(angle, n: int) -> np.ndarray | None:
    """A shaft angle per sample (rad, increasing), or None."""
    if angle is None:
        return None
    if hasattr(angle, "values") and hasattr(angle, "dims"):
        angle = angle.values
    arr = check_finite_array(angle, "shaft_angle", ndim=1, error=AnalysisError)
    if arr.shape[0] != n:
        raise AnalysisError(f"shaft_angle has {arr.shape[0]} samples but the signal has {n}; "
                            "give the angle (rad) at every signal sample")
    if np.any(np.diff(arr) <= 0):
        raise AnalysisError("shaft_angle must increase at every sample (shaft turning one way)")
    return arr


@renamed(rpm="speed_rpm")
def shaft_angle(speed_rpm: np.ndarray, fs: float) -> np.ndarray:
    """Shaft angle (rad) at each sample from the speed (rpm), zero at the first sample.

    Parameters
    ----------
    speed_rpm : ndarray
        Shaft speed at each sample, rpm (> 0).
    fs : float
        Sample rate, Hz.

    Returns
    -------
    ndarray
        ``φ(t) = ∫ 2π rpm/60 dt`` by the trapezoidal rule, rad (exact for piecewise-linear speed).

    Examples
    --------
    >>> phi = shaft_angle(np.full(1001, 60.0), 1000.0)   # 1 rev/s for 1 s
    >>> round(float(phi[-1] / (2 * np.pi)), 12)
    1.0
    """
    return integrate_angle(np.asarray(speed_rpm, dtype=float), fs, 0.0)


def integrate_angle(speed_rpm: np.ndarray, fs: float, start: float) -> np.ndarray:
    """Trapezoidal shaft angle (rad) over a span of samples, ``start`` at its first sample.

    The running sum is sequential, so integrating a record in consecutive spans (each starting
    from the previous span's value at the shared sample) gives the whole-record angle exactly.

    Examples
    --------
    >>> whole = integrate_angle(np.array([60.0, 120.0, 180.0]), 10.0, 0.0)
    >>> part = integrate_angle(np.array([120.0, 180.0]), 10.0, float(whole[1]))
    >>> bool(part[-1] == whole[-1])
    True
    """
    from ._kernels import integrate_speed

    return integrate_speed(speed_rpm, fs, start)    # one pass compiled, else cumsum


# ---------------------------------------------------------------------------- interpolation


@functools.lru_cache(maxsize=1)
def _sinc_table() -> np.ndarray:
    """Kaiser-windowed sinc weights for fractional positions ``p/_SINC_PHASES`` (rows), taps at
    offsets ``-_SINC_HALF+1 … _SINC_HALF`` (columns), each row normalised to a unit sum."""
    from scipy import special

    mu = np.arange(_SINC_PHASES + 1) / _SINC_PHASES
    offsets = np.arange(-_SINC_HALF + 1, _SINC_HALF + 1)
    d = mu[:, None] - offsets[None, :]
    w = np.sinc(d) * special.i0(_SINC_BETA * np.sqrt(np.clip(1.0 - (d / _SINC_HALF) ** 2,
                                                              0.0, None)))
    table = w / w.sum(axis=1, keepdims=True)
    table.flags.writeable = False
    return table


@functools.lru_cache(maxsize=1)
def _sinc_steps() -> np.ndarray:
    """``_sinc_table()[1:] - _sinc_table()[:-1]``: the change of each weight from one
    tabulated phase to the next (the compiled kernel's second dot product)."""
    steps = np.ascontiguousarray(np.diff(_sinc_table(), axis=0))
    steps.flags.writeable = False
    return steps


def _interp(x: np.ndarray, u: np.ndarray, method: str) -> np.ndarray:
    """Interpolate samples ``x`` (unit spacing) at fractional positions ``u``."""
    n = x.shape[0]
    if method == "linear":
        i = np.clip(np.floor(u).astype(np.int64), 0, n - 2)
        f = u - i
        return x[i] * (1.0 - f) + x[i + 1] * f
    if method == "cubic":
        # 4-point Lagrange through x[i-1..i+2]; exact for cubics, error O(h^4)
        i = np.clip(np.floor(u).astype(np.int64), 1, n - 3)
        f = u - i
        xm, x0, x1, x2 = x[i - 1], x[i], x[i + 1], x[i + 2]
        fm1, f1, f2 = f + 1.0, f - 1.0, f - 2.0
        return (-xm * f * f1 * f2 / 6.0 + x0 * fm1 * f1 * f2 / 2.0
                - x1 * fm1 * f * f2 / 2.0 + x2 * fm1 * f * f1 / 6.0)
    # band-limited: tabulated normalised Kaiser-windowed sinc, linear between table rows
    table = _sinc_table()
    from ._kernels import sinc_interp

    fast = sinc_interp(x, u, table, _sinc_steps(), _SINC_HALF, _SINC_PHASES)
    if fast is not None:
        return fast
    i0 = np.clip(np.floor(u).astype(np.int64), _SINC_HALF - 1, n - 1 - _SINC_HALF)
    pos = (u - i0) * _SINC_PHASES
    row = np.clip(pos.astype(np.int64), 0, _SINC_PHASES - 1)
    frac = (pos - row)[:, None]
    w = table[row]
    w += (table[row + 1] - w) * frac
    from numpy.lib.stride_tricks import sliding_window_view

    windows = sliding_window_view(x, 2 * _SINC_HALF)
    return np.einsum("ij,ij->i", w, windows[i0 - (_SINC_HALF - 1)])


@dataclass(frozen=True)
class ChunkPlan:
    """How a record is resampled, decided from its speed alone (no signal samples read).

    Attributes
    ----------
    n : int
        Input samples.
    fs : float
        Input sample rate, Hz.
    samples_per_rev : int
    interpolation : str
        Resolved interpolation ('linear', 'cubic' or 'bandlimited').
    bounds : ndarray
        Chunk limits (input sample indices), ``len = chunks + 1``.
    bands : tuple
        Per chunk ``(f_pass, f_stop)`` of the anti-alias filter, Hz, or None (not needed).
    windows : tuple of (int, int)
        Per chunk: input samples ``[a, b)`` read — the chunk with the filter's and the
        interpolation's margins, extended where the record allows to the transform length.
    lengths : tuple of (int, int)
        Per chunk: the transform length and the length of the filtered output (its rate is
        ``fs · out/transform``: a fractional decimation), or (0, 0) without a filter.
    filter_half : tuple of int
        Per chunk: samples at either end of a read window left incomplete by the filter.
    reach : tuple of int
        Per chunk: input samples the interpolation reaches beyond an output position.
    halfband_stages : tuple of int
        Per chunk: half-band decimations by 2 before the FFT low-pass (:func:`_halfband_taps`).
    blends : tuple of int
        Per chunk: half-width (input samples) of the crossfade to the next chunk's filter
        around their boundary (:mod:`analysis.chunk_blend`), 0 for none.
    """

    n: int
    fs: float
    samples_per_rev: int
    interpolation: str
    bounds: np.ndarray
    bands: tuple
    windows: tuple
    lengths: tuple
    filter_half: tuple
    reach: tuple
    halfband_stages: tuple = ()
    blends: tuple = ()

    @property
    def chunks(self) -> int:
        return len(self.bands)

    @property
    def decimation(self) -> tuple:
        """Per chunk: input samples per filtered sample (1 without a filter)."""
        return tuple(1.0 if m == 0 else t / m for t, m in self.lengths)

    def window(self, k: int) -> tuple[int, int]:
        """Input samples ``[a, b)`` read to produce the output of chunk ``k``."""
        return self.windows[k]

    def usable(self) -> tuple[int, int]:
        """First and last input positions whose filtered, interpolated value is complete."""
        first = self.filter_half[0] + self.reach[0]
        last = self.n - 1 - self.filter_half[-1] - self.reach[-1]
        return first, last


def plan_chunks(speed_rpm, *, n: int, fs: float, samples_per_rev: int = 64,
                interpolation: str = "auto", antialias: bool = True,
                chunk: int = 1 << 18, speed_limits_rpm=None,
                clean_order: float | None = None, span_extremes=None) -> ChunkPlan:
    """Decide chunks, anti-alias filters and decimation of a resampling from the speed.

    Parameters
    ----------
    speed_rpm : callable or ndarray
        ``speed_rpm(a, b)`` → speed (rpm) of input samples ``a..b-1``; or the whole speed
        array.
    n : int
        Input samples.
    fs : float
        Input sample rate, Hz.
    samples_per_rev, interpolation, antialias, chunk
        As in :func:`angle_resample`.
    speed_limits_rpm : (float, float), optional
        The record's lowest and highest speed (rpm), when the caller knows them already.
    span_extremes : SpanExtremes, optional
        The speed's extremes by span (saves a pass over the speed per span).
    clean_order : float, optional
        Highest order the result is used at (default ``samples_per_rev/4``, the filter's pass
        band; an order map showing more passes its ``max_order``). The half-band stages keep
        every order up to it flat and free of their own folding; above it (the filter's
        transition band) they may fold their transition band in.

    Returns
    -------
    ChunkPlan

    Examples
    --------
    >>> plan = plan_chunks(np.linspace(1000.0, 3000.0, 200_000), n=200_000, fs=20_000.0)
    >>> plan.chunks, [round(q, 2) for q in plan.decimation], plan.interpolation
    (2, [6.25, 2.67], 'bandlimited')
    """
    if callable(speed_rpm):
        speed = speed_rpm
    else:
        arr = np.asarray(speed_rpm, dtype=float)
        speed = lambda a, b: arr[a:b]          # noqa: E731 - a span reader
    samples_per_rev = check_int(samples_per_rev, "samples_per_rev", minimum=4,
                                error=AnalysisError)
    interpolation = check_option(interpolation, "interpolation", INTERPOLATIONS,
                                 error=AnalysisError)
    method = "bandlimited" if interpolation == "auto" else interpolation
    chunk = check_int(chunk, "chunk", minimum=1024, error=AnalysisError)
    clean = samples_per_rev / 4.0 if clean_order is None else max(float(clean_order),
                                                                   samples_per_rev / 4.0)
    bounds, ranges = _split_chunks(speed, n, chunk, speed_limits_rpm, span_extremes)
    top = max(r[1] for r in ranges)
    per_rev = 60.0 * fs / top
    if per_rev < 2.0:
        raise AnalysisError(
            f"rpm up to {top:.6g} at fs = {fs:.6g} Hz leaves {per_rev:.3g} time samples per "
            "revolution (at least 2 needed): check the speed units (rpm expected) and the "
            "sample rate")
    bands, windows, lengths, halves, reach, n_stages = [], [], [], [], [], []
    for k, (lo, hi) in enumerate(ranges):
        f_pass = samples_per_rev / 4 * hi / 60.0
        f_stop = 3 * samples_per_rev / 4 * lo / 60.0
        c0, c1 = int(bounds[k]), int(bounds[k + 1])
        if not antialias or f_stop >= 0.5 * fs:
            bands.append(None)
            lengths.append((0, 0))
            halves.append(0)
            step = (_SINC_HALF + 2) if method == "bandlimited" else 4
            reach.append(step)
            n_stages.append(0)
            windows.append((max(0, c0 - step), min(n, c1 + step)))
            continue
        if f_stop <= f_pass * 1.05:   # pragma: no cover - the 2:1 split prevents it
            raise AnalysisError(
                f"speed varies too much within one chunk ({lo:.6g}..{hi:.6g} rpm) for "
                f"samples_per_rev={samples_per_rev}; raise samples_per_rev or lower chunk")
        # the filtered output at (at least) 4 samples per period of the stop edge for the
        # band-limited kernel (its documented error holds up to a quarter of its rate); at the
        # input rate for cubic/linear, whose error is documented there
        ratio = max(1.0, fs / (4.0 * f_stop)) if method == "bandlimited" else 1.0
        # half-band stages first, as many as keep the clean orders (up to ``clean`` at the
        # chunk's top speed) within a quarter of the rate they leave: there each stage is flat
        # (its pass band, 1/8 of its input rate) and nothing folds in (what folds there comes
        # from its stop band, 135 dB); what folds from its transition band lands above the
        # clean orders, below the stop edge or in the FFT low-pass's stop band, and never at
        # an order that the angle sampling folds back (module docstring). The FFT then runs
        # on 1/2^stages of the samples and returns the output rate above, zero padded where
        # that is higher than the stages' rate. Their ends are incomplete over
        # HB_REACH·(2^s − 1) more samples: no more stages than leave 0.25 % of the record so
        # (both ends together; 0.1 % before: a 10 s record at 20 kHz missed its third stage by
        # 10 samples, and the order map ran 3.6 % slower for them). And no more than keep the
        # FFT low-pass's stop edge within the stages' Nyquist frequency: above it the filter
        # cannot act, the spectrum's top bin keeps what the stages folded there (the window
        # ends' transients), and the zero padded transform spreads it over the whole window as
        # one cosine -- a steady 1500 rpm record at 8 kHz (stop edge 1200 Hz, 2 stages to
        # 2 kHz) read 3.4e-4 off in its angle samples over 60 s, a crossfade's short window
        # 2e-3 (tests/analysis/test_resample_halfband.py)
        stages = 0
        if method == "bandlimited":
            f_clean = clean * hi / 60.0
            stages = max(0, min(_HB_MAX_STAGES,
                                int(math.floor(math.log2(fs / (4.0 * f_clean)) + 1e-12))))
            while stages and (2 * _HB_REACH * ((1 << stages) - 1) > n // 400
                              or f_stop > fs / (1 << (stages + 1))):
                stages -= 1
        half = int(math.ceil(_aa_half_length(f_pass, f_stop) * fs)) + 1
        half += _HB_REACH * ((1 << stages) - 1)
        if 2 * half + 1 > n:
            raise AnalysisError(
                f"the anti-alias filter for {lo:.6g}..{hi:.6g} rpm at fs = {fs:.6g} Hz "
                f"spans {2 * half + 1} samples, more than the {n} samples of the record: "
                "the speed is far too low for this sample rate (is rpm in rpm, not rad/s "
                "or Hz?) or the record too short")
        step = int(math.ceil((_SINC_HALF + 2) * ratio)) + 1
        a = max(0, c0 - half - step)
        b = min(n, c1 + half + step)
        size = _good_size(b - a)
        if a + size > n:   # the record's end: read real samples before the chunk instead
            a = max(0, n - size, windows[-1][0] if windows else 0)
        b = min(n, a + size)                  # read real samples rather than pad, if any
        out = size if ratio == 1.0 else min(size, _good_size(int(math.ceil(size / ratio))))
        while stages and size % (1 << stages):
            stages -= 1              # (a margin a little wider than needed is harmless)
        bands.append((f_pass, f_stop))
        n_stages.append(stages)
        windows.append((a, b))
        lengths.append((size, out))
        halves.append(half)
        reach.append(step)
    from .chunk_blend import blend_widths

    return ChunkPlan(n=n, fs=float(fs), samples_per_rev=samples_per_rev, interpolation=method,
                     bounds=bounds, bands=tuple(bands), windows=tuple(windows),
                     lengths=tuple(lengths), filter_half=tuple(halves), reach=tuple(reach),
                     halfband_stages=tuple(n_stages),
                     blends=blend_widths(bounds, ranges, bands, halves, reach, fs, n))


def angle_range(plan: ChunkPlan, phi_first: float, phi_last: float) -> tuple[int, int]:
    """Indices ``j0, j1`` of the first and last angle samples ``j · 2π/samples_per_rev`` whose
    interpolation is complete, given the shaft angle at the first and last usable positions."""
    dphi = _TWO_PI / plan.samples_per_rev
    return int(np.ceil(phi_first / dphi)), int(np.floor(phi_last / dphi))


def resample_span(plan: ChunkPlan, ks, values: np.ndarray, start: int, phi: np.ndarray,
                  speed_rpm: np.ndarray, j_first: int, j_last: int, *, last: bool,
                  positions=None):
    """Angle samples produced by chunks ``ks`` from one span of input samples.

    Parameters
    ----------
    plan : ChunkPlan
    ks : sequence of int
        Consecutive chunk indices.
    values, phi, speed_rpm : ndarray
        Input samples, shaft angle (rad) and speed (rpm) of input samples ``start …``; they
        must cover the read windows of ``ks`` (:meth:`ChunkPlan.window`).
    start : int
        Input index of ``values[0]``.
    j_first, j_last : int
        Angle-sample index range still to produce (the caller carries ``j_first``).
    last : bool
        The span holds the final chunk (all remaining angle samples up to ``j_last``).
    positions : (ndarray, ndarray), optional
        With ``last``: the input positions of the angle samples ``j_first … j_last`` and the
        speed there, when already known (:func:`angle_grid`).

    Returns
    -------
    (values, time, rpm, angle) : tuple of ndarray
        Resampled values, time of each angle sample (s from the first input sample), speed
        there (rpm) and the angle (rad).
    """
    fs = plan.fs
    dphi = _TWO_PI / plan.samples_per_rev
    blends = plan.blends or (0,) * plan.chunks
    # a span that is not the record's last stops before the crossfade at its upper boundary
    # (the next span, which holds the next chunk, produces it: analysis.chunk_blend)
    stop = int(plan.bounds[ks[-1] + 1]) - blends[ks[-1]]
    top = j_last if last else min(j_last, int(np.floor(phi[-1] / dphi)))
    grid = np.arange(j_first, top + 1) * dphi
    if positions is not None and last:
        u_out, rpm_out = positions
    else:
        from ._kernels import positions_and_values

        u_out, rpm_out = positions_and_values(phi, grid, start, speed_rpm)
    if not last:
        keep = int(np.searchsorted(u_out, stop, side="left"))
        grid, u_out, rpm_out = grid[:keep], u_out[:keep], rpm_out[:keep]
    out = np.empty(grid.shape[0])
    for k in ks:
        c0, c1 = int(plan.bounds[k]), int(plan.bounds[k + 1])
        w_lo = blends[k - 1] if k else 0
        if w_lo:              # the crossfade from the previous chunk's filter to this one's
            from .chunk_blend import zone_values

            lo = int(np.searchsorted(u_out, c0 - w_lo, side="left"))
            hi = int(np.searchsorted(u_out, c0 + w_lo, side="left"))
            if hi > lo:
                out[lo:hi] = zone_values(plan, k - 1, values, start, u_out[lo:hi])
        lo = int(np.searchsorted(u_out, c0 + w_lo, side="left"))
        hi = (int(np.searchsorted(u_out, c1 - blends[k], side="left")) if c1 < plan.n
              else grid.shape[0])
        if hi <= lo:
            continue
        a, b = plan.window(k)
        data = values[a - start:b - start]
        band = plan.bands[k]
        scale = 1.0
        if band is not None:
            nfft, n_out = plan.lengths[k]
            stages = plan.halfband_stages[k] if plan.halfband_stages else 0
            data = _fft_lowpass(data, fs, band[0], band[1], nfft, n_out, stages=stages)
            scale = n_out / nfft
        out[lo:hi] = _interp(data, (u_out[lo:hi] - a) * scale, plan.interpolation)
    return out, u_out / fs, rpm_out, grid


def resample_arrays(values: np.ndarray, fs: float, speed_rpm: np.ndarray, *,
                    samples_per_rev: int = 64, interpolation: str = "auto",
                    antialias: bool = True, chunk: int = 1 << 18, angle=None, label="x",
                    max_order=None):
    """:func:`angle_resample` on plain arrays: ``(values, time, rpm, angle, plan)``."""
    plan = plan_chunks(speed_rpm, n=values.shape[0], fs=fs, samples_per_rev=samples_per_rev,
                       interpolation=interpolation, antialias=antialias, chunk=chunk,
                       clean_order=max_order)
    phi, j0, j1, positions = angle_samples(plan, speed_rpm, angle=angle, label=label)
    out, t_out, rpm_out, grid = resample_span(plan, range(plan.chunks), values, 0, phi,
                                              speed_rpm, j0, j1, last=True, positions=positions)
    return out, t_out, rpm_out, grid, plan


def angle_samples(plan: ChunkPlan, speed_rpm: np.ndarray, *, angle=None, label="x",
                  speed_max=None):
    """The shaft angle of a whole record and the angle samples its plan can produce:
    ``(phi, j0, j1, positions)`` — ``phi`` the given ``angle`` or the integrated speed (rad),
    samples ``j0 … j1`` (``j · 2π/samples_per_rev``) complete after the filter and the
    interpolation, ``positions`` their input positions and speed for :func:`resample_span`
    (found in the integration's own pass; None for a given angle)."""
    n = plan.n
    first, last = plan.usable()
    if last <= first:
        raise AnalysisError(f"{label}: record of {n} samples is shorter than the anti-alias "
                            f"filter ({2 * max(plan.filter_half) + 1} samples); pass "
                            "antialias=False or a longer record")
    positions = None
    if angle is None:
        from ._kernels import angle_grid

        phi, j0, u_out, rpm_out = angle_grid(speed_rpm, plan.fs, _TWO_PI / plan.samples_per_rev,
                                             first, last, speed_max=speed_max)
        j1 = j0 + u_out.shape[0] - 1
        positions = (u_out, rpm_out)
    else:
        phi = angle
        j0, j1 = angle_range(plan, phi[first], phi[last])
    if j1 - j0 < 3:
        raise AnalysisError(f"{label}: the record covers only "
                            f"{(phi[-1] - phi[0]) / _TWO_PI:.3g} revolutions; need at least a "
                            "few angle samples")
    return phi, j0, j1, positions


# ---------------------------------------------------------------------------- public


@renamed(rpm="speed_rpm")
def angle_resample(x, *, fs=None, speed_rpm, samples_per_rev: int = 64,
                   interpolation: str = "auto", antialias: bool = True, chunk: int = 1 << 18,
                   shaft_angle=None, max_order=None):
    """Resample a signal at constant increments of shaft angle (computed order tracking).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal (any SI unit). A Record channel supplies ``fs`` (``sample_rate``) and ``units``.
    fs : float, optional
        Sample rate, Hz (required for a plain array).
    speed_rpm : float or array_like
        Shaft speed, rpm, one value per sample of ``x`` (a scalar for a steady speed); > 0.
        A DataArray from :func:`analysis.speedref.speed_reference` may carry the encoder
        angle as a ``shaft_angle`` coordinate, which is then used (see ``shaft_angle``).
    samples_per_rev : int
        Angle samples per revolution (the angle-domain "sample rate"); orders up to
        ``samples_per_rev/4`` are passed unattenuated by the anti-alias filter.
    interpolation : {'auto', 'bandlimited', 'cubic', 'linear'}
        Interpolation at the constant-angle instants (errors in the module docs); 'auto' is
        the band-limited kernel on the decimated, filtered signal.
    antialias : bool
        Low-pass the signal below the angle-domain Nyquist order of the chunk's lowest speed.
    chunk : int
        Input samples processed at a time (bounds memory).
    shaft_angle : array_like, optional
        Shaft angle (rad, increasing) at every sample, e.g. from the encoder edges; default
        the integral of the speed from the first sample.
    max_order : float, optional
        Highest order the samples are used at (default ``samples_per_rev/4``, the filter's
        pass band; up to ``samples_per_rev/2``): the half-band stages before the filter keep
        every order up to it free of their own folding, as :func:`analysis.ordermap.order_map`
        with the same ``max_order`` resamples.

    Returns
    -------
    xarray.DataArray
        Dims ``("angle",)``; coordinate ``angle`` (rad, shaft angle), with ``time`` (s) and
        ``rpm`` along it. Attrs: ``units``, ``samples_per_rev``, ``interpolation``,
        ``antialias``, ``decimation``, ``angle_reference``, ``method``.

    References
    ----------
    Fyfe & Munck (1997), see the module docstring.

    Examples
    --------
    >>> fs = 5000.0
    >>> t = np.arange(20000) / fs
    >>> rpm = 600 + 300 * t                       # run-up 600 -> 1800 rpm
    >>> phi = integrate_angle(rpm, fs, 0.0)
    >>> y = angle_resample(np.cos(3 * phi), fs=fs, speed_rpm=rpm, samples_per_rev=32)
    >>> err = np.abs(y.values - np.cos(3 * y.angle.values)).max()
    >>> bool(err < 1e-5)
    True
    """
    values, fs, units, label = _as_signal(x, fs)
    n = values.shape[0]
    angle, reference = _angle_input(shaft_angle, speed_rpm, n)
    speed = _as_rpm(speed_rpm, n, fs)
    out, t_out, rpm_out, grid, plan = resample_arrays(
        values, fs, speed, samples_per_rev=samples_per_rev, interpolation=interpolation,
        antialias=antialias, chunk=chunk, angle=angle, label=label,
        max_order=None if max_order is None else check_positive(max_order, "max_order",
                                                                 error=AnalysisError))
    import xarray as xr

    coords = {"angle": ("angle", grid, {"units": "rad", "long_name": "shaft angle"}),
              "time": ("angle", t_out, {"units": "s"}),
              "rpm": ("angle", rpm_out, {"units": "rpm"})}
    log.debug("angle_resample %s: %d -> %d samples (%d/rev, %s)", label, n, grid.shape[0],
              plan.samples_per_rev, plan.interpolation)
    filtered = any(b is not None for b in plan.bands)
    return xr.DataArray(out, dims=("angle",), coords=coords, name=label,
                        attrs={"units": units, "samples_per_rev": plan.samples_per_rev,
                               "interpolation": plan.interpolation,
                               "antialias": ("kaiser low-pass 100 dB, zero phase (FFT)"
                                             if filtered else "none"),
                               "decimation": list(plan.decimation),
                               "angle_reference": reference,
                               "method": "computed order tracking (angle-domain resampling)"})


def _angle_input(shaft_angle, speed_rpm, n):
    """The shaft angle to resample on and what its zero is: an explicit array, the
    ``shaft_angle`` coordinate of a speed DataArray, or None (integrated speed)."""
    if shaft_angle is None and hasattr(speed_rpm, "coords") and "shaft_angle" in speed_rpm.coords:
        coord = speed_rpm.coords["shaft_angle"]
        return (_as_angle(coord.values, n),
                str(coord.attrs.get("reference", "encoder angle from the pulse edges")))
    if shaft_angle is not None:
        attrs = getattr(shaft_angle, "attrs", {}) or {}
        return _as_angle(shaft_angle, n), str(attrs.get("reference", "given shaft angle"))
    return None, "shaft angle 0 at the first sample (speed-reference integration)"
