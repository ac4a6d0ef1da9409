"""Angle-domain resampling: computed order tracking (COT).

A time record ``x(t)`` taken while the shaft turns at ``rpm(t)`` is re-sampled at constant
increments of shaft angle, so that an order ``o`` (a component ``cos(o φ)``) becomes a fixed
frequency of ``o`` cycles per revolution whatever the speed does. Steps:

1. shaft angle ``φ(t) = ∫ 2π rpm/60 dt`` (trapezoidal rule, exact for a speed linear between
   samples; φ = 0 at the first sample);
2. anti-alias low-pass in time, chunk by chunk: a linear-phase Kaiser FIR (100 dB) passing
   orders ≤ ``samples_per_rev/4`` at the chunk's top speed (ripple ≈ 1e-5) and stopping
   orders ≥ ``3/4 samples_per_rev`` at its lowest speed; the record ends, where the filter is
   incomplete, are trimmed (half the filter length each) rather than padded;
3. the times of the constant-angle samples from the inverse of φ(t);
4. interpolation of ``x`` at those times: ``"linear"``, ``"cubic"`` (4-point Lagrange) or
   ``"bandlimited"`` (Kaiser-windowed sinc, 16 taps).

Interpolation error for a tone at ``f`` sampled at ``fs`` (``h = 2π f/fs``): linear ≈ h²/8
(peak, relative), cubic ≈ 3h⁴/128, band-limited < 1e-4 up to 0.4 fs and ≈ 1e-7 below 0.1 fs.
The bench suite ``orders`` measures these against a closed form.

Half orders of a four-stroke engine (one cycle = 720°) need no separate grid: the angle samples
run continuously from the first sample, and an analysis block of an even number of revolutions
(``revolutions`` in :mod:`analysis.orders`, or ``revolutions_per_cycle=2`` in
:func:`analysis.synchronous_average`) puts every half order on a bin.

Long records are processed in chunks of ``chunk`` input samples (overlapped by the filter's
settling length), so the working memory is bounded whatever the record length.

References
----------
K. R. Fyfe and E. D. S. Munck, "Analysis of computed order tracking", Mechanical Systems and
Signal Processing 11(2), 187–205 (1997).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from crankbench.predict._validate import check_finite_array, check_int, check_option, check_positive
from crankbench.predict.errors import AnalysisError
from crankbench.predict._deprecate import renamed

__all__ = ["angle_resample", "shaft_angle", "INTERPOLATIONS"]

log = logging.getLogger("crankbench")

#: interpolation name -> documented relative peak error for h = 2π f / fs (see module docs)
INTERPOLATIONS = ("linear", "cubic", "bandlimited")

_SINC_HALF = 8  # band-limited kernel half-width in samples (16 taps)
_SINC_BETA = 8.0  # Kaiser window shape of the band-limited kernel


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
    values = check_finite_array(x, label, ndim=1, min_length=8, error=AnalysisError)
    return values, fs, units, label


def _as_rpm(rpm, n: int, fs: float | None = None) -> np.ndarray:
    """Speed in rpm as an array of length ``n`` (a scalar means a steady speed).

    ``fs`` (Hz), when known, lets an error say at what time the speed was bad.
    """
    if hasattr(rpm, "values") and hasattr(rpm, "dims"):
        rpm = rpm.values
    arr = np.asarray(rpm, dtype=float) if not np.isscalar(rpm) else None
    if arr is None or arr.ndim == 0:
        value = check_positive(rpm if arr is None else float(arr), "rpm", error=AnalysisError)
        return np.full(n, value)
    arr = check_finite_array(arr, "rpm", ndim=1, error=AnalysisError)
    if arr.shape[0] != n:
        raise AnalysisError(f"rpm has {arr.shape[0]} samples but the signal has {n}; "
                            "give one speed per signal sample (see analysis.speedref)")
    if arr.min() <= 0:
        bad = np.flatnonzero(arr <= 0)
        i, j = int(bad[0]), int(bad[-1])
        when = (lambda k: f" (t = {k / fs:.6g} s)") if fs else (lambda k: "")
        raise AnalysisError(f"rpm must be > 0 throughout (shaft turning one way); found "
                            f"{len(bad)} sample(s) <= 0 (min {float(arr.min()):.6g} rpm), first "
                            f"at sample {i}{when(i)}, last at sample {j}{when(j)}; trim the "
                            "record to the running span")
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
    omega = np.asarray(speed_rpm, dtype=float) * (2.0 * np.pi / 60.0)
    phi = np.empty_like(omega)
    phi[0] = 0.0
    np.cumsum(0.5 * (omega[1:] + omega[:-1]) / fs, out=phi[1:])
    return phi


# ---------------------------------------------------------------------------- interpolation


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
    # band-limited: Kaiser-windowed sinc over 2*_SINC_HALF taps
    i0 = np.floor(u).astype(np.int64)
    offsets = np.arange(-_SINC_HALF + 1, _SINC_HALF + 1)
    idx = i0[:, None] + offsets[None, :]
    d = u[:, None] - idx
    w = np.sinc(d) * np.i0(_SINC_BETA * np.sqrt(np.clip(1.0 - (d / _SINC_HALF) ** 2, 0.0, None)))
    w /= np.i0(_SINC_BETA)
    np.clip(idx, 0, n - 1, out=idx)
    return np.einsum("ij,ij->i", w, x[idx])


def _antialias_taps(samples_per_rev: int, rpm_min: float, rpm_max: float, fs: float,
                    n: int | None = None):
    """Linear-phase FIR low-pass protecting orders <= samples_per_rev/4 from aliasing.

    Pass band up to ``samples_per_rev/4`` orders at the chunk's top speed, stop band from
    ``3 samples_per_rev/4`` orders at its lowest speed (content between 1/2 and 3/4 of the
    angle sample rate aliases only above ``samples_per_rev/4``). Kaiser design, 100 dB, so the
    pass-band ripple is about 1e-5. Returns ``None`` when no alias can reach the pass band.
    """
    from scipy import signal

    f_pass = samples_per_rev / 4 * rpm_max / 60.0
    f_stop = 3 * samples_per_rev / 4 * rpm_min / 60.0
    if f_stop >= 0.5 * fs:
        return None
    if f_stop <= f_pass * 1.05:
        raise AnalysisError(
            f"speed varies too much within one chunk ({rpm_min:.6g}..{rpm_max:.6g} rpm) for "
            f"samples_per_rev={samples_per_rev}; raise samples_per_rev or lower chunk")
    numtaps, beta = signal.kaiserord(100.0, (f_stop - f_pass) / (0.5 * fs))
    if n is not None and numtaps > n:  # check before designing: the filter could be huge
        raise AnalysisError(
            f"the anti-alias filter for {rpm_min:.6g}..{rpm_max:.6g} rpm at fs = {fs:.6g} Hz needs "
            f"{numtaps} taps, more than the {n} samples of the record: the speed is far too low "
            "for this sample rate (is rpm in rpm, not rad/s or Hz?) or the record too short")
    numtaps |= 1  # odd: integer group delay, so the filtered signal stays on the sample grid
    return signal.firwin(numtaps, 0.5 * (f_pass + f_stop), window=("kaiser", beta), fs=fs)


def _chunk_bounds(speed: np.ndarray, chunk: int) -> np.ndarray:
    """Chunk limits of at most ``chunk`` samples, split until speed varies < 2:1 in each."""
    n = speed.shape[0]
    n_chunks = max(1, int(math.ceil(n / chunk)))
    pending = [int(v) for v in np.round(np.linspace(0, n, n_chunks + 1))]
    out = [pending[0]]
    for b in pending[1:]:
        a = out[-1]
        stack = [b]
        while stack:
            b = stack[-1]
            seg = speed[a:b]
            if seg.max() <= 2.0 * seg.min() or b - a <= 256:
                out.append(b)
                stack.pop()
                a = b
            else:
                stack.append((a + b) // 2)
    return np.asarray(out, dtype=np.int64)


# ---------------------------------------------------------------------------- public


@renamed(rpm="speed_rpm")
def angle_resample(x, *, fs=None, speed_rpm, samples_per_rev: int = 64,
                   interpolation: str = "cubic",
                   antialias: bool = True, chunk: int = 1 << 18):
    """Resample a signal at constant increments of shaft angle (computed order tracking).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal (any SI unit). A Record channel supplies ``fs`` (``sample_rate``) and ``units``.
    fs : float, optional
        Sample rate, Hz (required for a plain array).
    speed_rpm : float or array_like
        Shaft speed, rpm, one value per sample of ``x`` (a scalar for a steady speed); > 0.
    samples_per_rev : int
        Angle samples per revolution (the angle-domain "sample rate"); orders up to
        ``samples_per_rev/4`` are passed unattenuated by the anti-alias filter.
    interpolation : {'linear', 'cubic', 'bandlimited'}
        Interpolation of ``x`` at the constant-angle instants (errors in the module docs).
    antialias : bool
        Low-pass the signal below the angle-domain Nyquist order of the chunk's lowest speed.
    chunk : int
        Input samples processed at a time (bounds memory).

    Returns
    -------
    xarray.DataArray
        Dims ``("angle",)``; coordinate ``angle`` (rad, shaft angle from the first sample),
        with ``time`` (s) and ``rpm`` along it. Attrs: ``units``, ``samples_per_rev``,
        ``interpolation``, ``antialias``, ``method``.

    References
    ----------
    Fyfe & Munck (1997), see the module docstring.

    Examples
    --------
    >>> fs = 5000.0
    >>> t = np.arange(20000) / fs
    >>> rpm = 600 + 300 * t                       # run-up 600 -> 1800 rpm
    >>> phi = shaft_angle(rpm, fs)
    >>> y = angle_resample(np.cos(3 * phi), fs=fs, speed_rpm=rpm, samples_per_rev=32)
    >>> err = np.abs(y.values - np.cos(3 * y.angle.values)).max()
    >>> bool(err < 1e-4)
    True
    """
    values, fs, units, label = _as_signal(x, fs)
    n = values.shape[0]
    speed = _as_rpm(speed_rpm, n, fs)
    samples_per_rev = check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    interpolation = check_option(interpolation, "interpolation", INTERPOLATIONS,
                                 error=AnalysisError)
    chunk = check_int(chunk, "chunk", minimum=1024, error=AnalysisError)
    filtered_any = False
    phi = shaft_angle(speed, fs)
    t = np.arange(n) / fs
    dphi = 2.0 * np.pi / samples_per_rev
    bounds = _chunk_bounds(speed, chunk)
    per_rev = 60.0 * fs / float(speed.max())
    if per_rev < 2.0:
        raise AnalysisError(
            f"rpm up to {float(speed.max()):.6g} at fs = {fs:.6g} Hz leaves {per_rev:.3g} time "
            "samples per revolution (at least 2 needed): check the speed units (rpm expected) "
            "and the sample rate")
    taps = [_antialias_taps(samples_per_rev, speed[a:b].min(), speed[a:b].max(), fs, n)
            if antialias else None for a, b in zip(bounds[:-1], bounds[1:])]
    half = [0 if h is None else h.shape[0] // 2 for h in taps]
    margin = _SINC_HALF + 2
    # the filter needs `half` samples on either side: trim the record ends (no edge transients)
    u_first, u_last = half[0] + margin, n - 1 - half[-1] - margin
    if u_last <= u_first:
        raise AnalysisError(f"{label}: record of {n} samples is shorter than the anti-alias "
                            f"filter ({2 * max(half) + 1} taps); pass antialias=False or a longer record")
    j0 = int(np.ceil(phi[u_first] / dphi))
    j1 = int(np.floor(phi[u_last] / dphi))
    if j1 - j0 < 3:
        raise AnalysisError(f"{label}: the record covers only {phi[-1] / (2 * np.pi):.3g} "
                            "revolutions; need at least a few angle samples")
    grid = np.arange(j0, j1 + 1) * dphi
    t_out = np.interp(grid, phi, t)
    u_out = t_out * fs
    out = np.empty(grid.shape[0])
    for (start, stop), h, hl in zip(zip(bounds[:-1], bounds[1:]), taps, half):
        lo = int(np.searchsorted(u_out, start, side="left"))
        hi = int(np.searchsorted(u_out, stop, side="left")) if stop < n else grid.shape[0]
        if hi <= lo:
            continue
        a, b = max(0, start - hl - margin), min(n, stop + hl + margin)
        if h is None:
            segment, offset = values[a:b], a
        else:
            from scipy import signal

            segment, offset = signal.oaconvolve(values[a:b], h, mode="valid"), a + hl
        out[lo:hi] = _interp(segment, u_out[lo:hi] - offset, interpolation)
        filtered_any = filtered_any or h is not None
    import xarray as xr

    coords = {"angle": ("angle", grid, {"units": "rad", "long_name": "shaft angle"}),
              "time": ("angle", t_out, {"units": "s"}),
              "rpm": ("angle", np.interp(t_out, t, speed), {"units": "rpm"})}
    log.debug("angle_resample %s: %d -> %d samples (%d/rev, %s)", label, n, grid.shape[0],
              samples_per_rev, interpolation)
    return xr.DataArray(out, dims=("angle",), coords=coords, name=label,
                        attrs={"units": units, "samples_per_rev": samples_per_rev,
                               "interpolation": interpolation,
                               "antialias": "kaiser FIR 100 dB, linear phase" if filtered_any else "none",
                               "method": "computed order tracking (angle-domain resampling)"})
