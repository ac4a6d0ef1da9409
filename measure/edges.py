"""Edge times from an analogue pulse signal: adaptive levels, hysteresis from the noise.

A test-bench pulse channel is whatever the pick-up gave: a magnetic pick-up's sine-like wave
whose amplitude grows with speed, a TTL square wave with ringing on its flanks, a once-per-
revolution TDC mark one or two samples wide on a drifting baseline, a tooth whose pulse is a
runt. :func:`find_edges` handles them without a threshold from the user:

1. **Noise.** The noise rms is estimated from differences of order 1 to 6 of the samples
   (``MAD(Δᵏx) / 0.6745 / √C(2k, k)``, the smallest over ``k``): white noise gives the same
   value at every order, a pulse shape only inflates the orders that see it, so the smallest
   is a close upper estimate whatever the pulse shape; for square pulses only a few samples
   long, where every difference sees edges, the spread of the samples about each of the two
   levels is the estimate.
2. **Envelope.** The local high and low levels are the running maximum and minimum over a
   window of 2.5 of the longest pulse intervals (a first pass finds them), so the switching
   level follows the amplitude of an inductive pick-up over a run-up and a drifting baseline,
   and a 1-sample mark once per revolution sets its own level ("envelope per revolution").
3. **Hysteresis.** The switching level is the mid level of the envelope; the trigger arms
   below ``mid − h`` and fires above ``mid + h`` with ``h = max(4 σ, 0.05 swing)``: noise
   and ringing cannot chatter, a swing smaller than ``min_snr`` noise rms is no pulse at all
   (no edge is reported there rather than edges in noise).
4. **Edge time.** The crossing of the mid level, between samples by linear interpolation or,
   where the four samples around it rise monotonically (a smooth flank), by the cubic through
   them. A 1–2-sample mark gets the linear crossing (a cubic through a spike is meaningless).
5. **Runts.** Pulses that leave the baseline (by more than ``max(6 σ, 0.04 swing)``) without
   reaching the switching level are reported apart (:attr:`EdgeDetection.runt_times`), for
   the wheel decoder (:mod:`measure.wheel`) to use where a tooth is known to be.

References
----------
Liang Shoupan, *Engine dynamics* (發動機動力學), 1948, ch. 9 (timing marks on records).
D. L. Donoho, I. M. Johnstone, "Ideal spatial adaptation by wavelet shrinkage", *Biometrika*
81 (1994) 425–455: the noise scale as MAD / 0.6745 of the finest-scale coefficients.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from math import comb

import numpy as np

from crankbench.predict._validate import check_finite_array, check_option, check_positive, \
    check_range
from crankbench.predict.errors import AnalysisError

__all__ = ["find_edges", "detect_edges", "EdgeDetection", "noise_rms"]

log = logging.getLogger("crankbench")

#: peak-to-peak swing below this many noise rms is not a pulse
MIN_SNR = 12.0
#: envelope window, in multiples of the longest pulse interval
ENVELOPE_INTERVALS = 2.5


@dataclass(frozen=True)
class EdgeDetection:
    """Edges found in an analogue pulse signal, with the levels used.

    Attributes
    ----------
    edges : numpy.ndarray
        Edge times, s from the first sample, ascending.
    runt_times : numpy.ndarray
        Times of runt pulses (they leave the baseline but never reach the switching level),
        s: the rising crossing of their own half height (half way from the baseline to the
        median of their top).
    runt_heights : numpy.ndarray
        Their peak above the local low level, as a fraction of the local swing.
    noise_rms : float
        Estimated noise, signal units rms.
    swing : float
        Median peak-to-peak swing of the envelope where pulses are, signal units.
    hysteresis : float
        Median half-width of the hysteresis band, signal units.
    window_s : float
        Envelope window, s.
    level : str
        "adaptive" (envelope mid level) or "fixed".
    """

    edges: np.ndarray
    runt_times: np.ndarray
    runt_heights: np.ndarray
    noise_rms: float
    swing: float
    hysteresis: float
    window_s: float
    level: str = "adaptive"

    @property
    def snr(self) -> float:
        """Swing over noise rms (inf for a noise-free signal)."""
        return self.swing / self.noise_rms if self.noise_rms > 0 else float("inf")


def noise_rms(signal) -> float:
    """Noise rms of a sampled signal, robust to the signal itself (see the module notes).

    The smallest over ``k = 1..6`` of ``1.4826 MAD(Δᵏx) / √C(2k, k)``; records longer than
    10⁶ samples are estimated on four slices of 2.5·10⁵ samples.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> t = np.arange(200_000) / 100_000.0
    >>> x = np.sign(np.sin(2 * np.pi * 50.0 * t)) + 0.01 * rng.standard_normal(t.size)
    >>> round(noise_rms(x), 3)        # square wave + 0.01 rms: the square wave is ignored
    0.01
    """
    x = np.asarray(signal, dtype=np.float64)
    if x.size > 1_000_000:
        starts = np.linspace(0, x.size - 250_000, 4).astype(int)
        return float(min(noise_rms(x[s:s + 250_000]) for s in starts))
    best = _two_level_noise(x)
    d = x
    for k in range(1, 7):
        d = np.diff(d)
        if d.size < 8:
            break
        mad = float(np.median(np.abs(d - np.median(d))))
        best = min(best, 1.482602218505602 * mad / np.sqrt(comb(2 * k, k)))
    return float(best) if np.isfinite(best) else 0.0


def _two_level_noise(x) -> float:
    """Noise of a two-level signal (square pulses, few samples per pulse, where differences
    see edges everywhere): the spread of the samples around each level, when the two levels
    (split at Otsu's threshold) hold at least 5 % of the samples each and stand more than 8
    spreads apart; else inf (one level, or a continuum: no such estimate)."""
    if x.size < 64:
        return np.inf
    hist, edges = np.histogram(x, bins=256)
    centres = 0.5 * (edges[1:] + edges[:-1])
    w0 = np.cumsum(hist)
    w1 = w0[-1] - w0
    m0 = np.cumsum(hist * centres)
    mean0 = m0 / np.maximum(w0, 1)
    mean1 = (m0[-1] - m0) / np.maximum(w1, 1)
    k = int(np.argmax(w0 * w1 * (mean0 - mean1) ** 2))      # Otsu's between-class variance
    thr = edges[k + 1]
    lo, hi = x[x < thr], x[x >= thr]
    if min(lo.size, hi.size) < 0.05 * x.size:
        return np.inf
    spread = [1.482602218505602 * float(np.median(np.abs(v - np.median(v)))) for v in (lo, hi)]
    sigma = float(np.median(spread))
    if not sigma > 0 or np.median(hi) - np.median(lo) < 8.0 * max(spread):
        return np.inf
    return sigma


def _envelope(x, width):
    """Running maximum and minimum over ``width`` samples, strict local extremes refined to the
    vertex of the parabola through them and their neighbours (a sampled sine's peak is up to
    ``1 - cos(pi / samples_per_period)`` below the true one; the vertex is within ~1e-3)."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    width = int(max(3, min(width, x.size)))
    hi_src, lo_src = x, x
    if x.size >= 5:
        hi_src = _vertices(x, +1.0)
        lo_src = -_vertices(-x, +1.0)
    hi = maximum_filter1d(hi_src, width, mode="nearest")
    lo = minimum_filter1d(lo_src, width, mode="nearest")
    half = width // 2
    if x.size > width:  # the first and last half windows see only part of a window: hold
        hi[:half], lo[:half] = hi[half], lo[half]
        hi[-half:], lo[-half:] = hi[-half - 1], lo[-half - 1]
    return hi, lo


def _vertices(x, sign):
    """``x`` with each smooth strict local maximum raised to its parabolic vertex.

    Smooth: the parabola through the maximum and its neighbours also predicts the samples two
    away within its curvature ``d = 2 x_p - x_{p-1} - x_{p+1}`` (a sampled sine: within 0.58 d
    at 8 samples per period, 0.99 d at 6; the corner of a square wave, which a 3-point parabola
    would overshoot, misses by about 2 d), and the signal falls on both sides of it.
    """
    a, b, c = x[1:-3], x[2:-2], x[3:-1]
    peak = np.flatnonzero((b > a) & (b > c)) + 2
    if peak.size == 0:
        return x
    a, b, c = x[peak - 1], x[peak], x[peak + 1]
    d = 2.0 * b - a - c
    pred_lo = b - (c - a) - 2.0 * d
    pred_hi = b + (c - a) - 2.0 * d
    smooth = (np.abs(pred_lo - x[peak - 2]) < d) & (np.abs(pred_hi - x[peak + 2]) < d)
    # both flanks fall comparably (a sine: within 2.4 : 1 at 8 samples per period; the corner
    # of a pulse, ramped by a sample of partial coverage, falls on one side only)
    left, right = b - x[peak - 2], b - x[peak + 2]
    smooth &= (left > 0) & (right > 0) & (np.maximum(left, right) < 4.0 * np.minimum(left, right))
    if not smooth.any():
        return x
    out = x.copy()
    p = peak[smooth]
    out[p] = b[smooth] + (c[smooth] - a[smooth]) ** 2 / (8.0 * d[smooth])
    return out


def _schmitt(x, upper, lower, valid):
    """Indices of the first sample above ``upper`` after the signal was below ``lower``."""
    state = np.zeros(x.size, dtype=np.int8)
    state[(x > upper) & valid] = 1
    state[(x < lower) & valid] = -1
    idx = np.where(state != 0, np.arange(x.size), 0)
    np.maximum.accumulate(idx, out=idx)
    held = state[idx]
    on = np.flatnonzero((held[1:] == 1) & (held[:-1] == -1)) + 1
    off = np.flatnonzero((held[1:] == -1) & (held[:-1] == 1)) + 1
    return on, off


def _crossings(x, mid, lower, switch_on, interpolation):
    """Sub-sample time (in samples) of the mid-level crossing that caused each switch.

    Where the signal took more than 4 samples to pass the hysteresis band (a slow or noisy
    flank) the crossing is where the least-squares line through those samples meets the mid
    level (noise moves it by ``sigma / (slope sqrt(m))`` rather than by the width of the
    chatter); on a fast flank it is interpolated between the two samples around the level.
    """
    up = np.flatnonzero((x[:-1] < mid[:-1]) & (x[1:] >= mid[1:]) & (x[1:] > x[:-1]))
    pos = np.searchsorted(up, switch_on, side="left") - 1
    ok = pos >= 0
    s_on = switch_on[ok]
    j = up[pos[ok]]
    level = mid[j]
    frac = (level - x[j]) / (x[j + 1] - x[j])
    if interpolation == "cubic" and j.size:
        inner = (j >= 1) & (j + 2 < x.size)
        jj = np.clip(j, 1, max(x.size - 3, 1))
        smooth = inner & (x[jj - 1] <= x[jj]) & (x[jj + 1] <= x[jj + 2])
        if smooth.any():
            frac = frac.copy()
            frac[smooth] = _cubic_crossing(x, j[smooth], frac[smooth], level[smooth])
    out = j + frac
    # slow/noisy flanks: regression over the band crossing [last sample below lower, switch]
    below = np.flatnonzero(x < lower)
    k = np.searchsorted(below, s_on) - 1
    arm = np.where(k >= 0, below[np.maximum(k, 0)], s_on)
    length = s_on - arm + 1
    slow = length > 5
    if slow.any():
        a, m = arm[slow], length[slow]
        starts = np.concatenate([[0], np.cumsum(m)[:-1]])
        u = np.arange(int(m.sum())) - np.repeat(starts, m)          # 0..m-1 per flank
        y = x[np.repeat(a, m) + u]
        su, suu = np.add.reduceat(u, starts), np.add.reduceat(u * u, starts)
        sy, suy = np.add.reduceat(y, starts), np.add.reduceat(u * y, starts)
        den = m * suu - su * su
        b = (m * suy - su * sy) / den
        c = (sy - b * su) / m
        lvl = mid[np.minimum(a + m // 2, x.size - 1)]
        t_fit = a + (lvl - c) / np.where(b > 0, b, 1.0)
        good = (b > 0) & (t_fit >= a) & (t_fit <= a + m - 1)
        fitted = out[slow]
        fitted[good] = t_fit[good]
        out[slow] = fitted
    return out


def _cubic_crossing(x, j, frac, level):
    """Refine linear crossing fractions with Newton steps on the cubic through j-1..j+2."""
    y0, y1, y2, y3 = (x[j - 1] - level, x[j] - level, x[j + 1] - level, x[j + 2] - level)

    # Lagrange cubic through nodes -1, 0, 1, 2 evaluated at u in [0, 1]
    def poly(u):
        return (-y0 * u * (u - 1) * (u - 2) / 6 + y1 * (u + 1) * (u - 1) * (u - 2) / 2
                - y2 * (u + 1) * u * (u - 2) / 2 + y3 * (u + 1) * u * (u - 1) / 6)

    def dpoly(u):
        return (-y0 * (3 * u * u - 6 * u + 2) / 6 + y1 * (3 * u * u - 4 * u - 1) / 2
                - y2 * (3 * u * u - 2 * u - 2) / 2 + y3 * (3 * u * u - 1) / 6)

    u = frac.copy()
    for _ in range(4):
        d = dpoly(u)
        safe = np.abs(d) > 1e-12 * (np.abs(y2 - y1) + 1e-300)
        step = np.where(safe, poly(u) / np.where(safe, d, 1.0), 0.0)
        u = np.clip(u - step, 0.0, 1.0)
    return u


def _typical_levels(x, mid, width):
    """Median of the samples below and above the mid level, per block of ``width`` samples
    (the baseline a pulse rises from, unmoved by ringing and over/undershoots)."""
    n = x.size
    width = int(max(8, min(width, n)))
    starts = np.arange(0, n, width)
    lo = np.empty(starts.size)
    hi = np.empty(starts.size)
    for k, a in enumerate(starts):
        seg, m = x[a:a + width], mid[a:a + width]
        below, above = seg[seg < m], seg[seg >= m]
        lo[k] = np.median(below) if below.size else seg.min()
        hi[k] = np.median(above) if above.size else seg.max()
    centres = starts + 0.5 * np.minimum(width, n - starts)
    idx = np.arange(n)
    return np.interp(idx, centres, lo), np.interp(idx, centres, hi)


def _runts(x, mid, width, sigma, switch_on, upper):
    """Pulses that rise off the baseline but never reach the switching level."""
    lo, hi = _typical_levels(x, mid, width)
    swing = np.maximum(hi - lo, 0.0)
    rise = np.maximum(6.0 * sigma, 0.04 * swing)
    on, off = _schmitt(x, lo + rise, lo + 0.5 * rise, swing > 0)
    if on.size == 0:
        return np.empty(0), np.empty(0)
    k = np.searchsorted(off, on, side="right")
    end = np.where(k < off.size, off[np.minimum(k, max(off.size - 1, 0))] if off.size else 0,
                   x.size)
    # a segment holding a full switch is a full pulse
    if switch_on.size:
        k = np.searchsorted(switch_on, on, side="left")
        full = (k < switch_on.size) & (switch_on[np.minimum(k, switch_on.size - 1)] < end)
    else:
        full = np.zeros(on.size, bool)
    times, heights = [], []
    for a, b in zip(on[~full], end[~full]):
        seg = x[a:b]
        if seg.size == 0:
            continue
        p = a + int(np.argmax(seg))
        if x[p] >= upper[p]:
            continue
        # its own level: the median of its top half (overshoot and noise average out)
        top = seg[seg >= 0.5 * (lo[p] + x[p])]
        half = 0.5 * (lo[p] + float(np.median(top)))
        j = p
        while j > 0 and x[j - 1] >= half:
            j -= 1
        if j == 0:
            continue
        frac = (half - x[j - 1]) / (x[j] - x[j - 1])
        times.append(j - 1 + frac)
        heights.append((x[p] - lo[p]) / swing[p] if swing[p] > 0 else 0.0)
    return np.asarray(times, float), np.asarray(heights, float)


def find_edges(signal, *, fs, slope="rising", level=None, hysteresis=None,
               interpolation="cubic", min_snr=MIN_SNR) -> EdgeDetection:
    """Edges of an analogue tacho/encoder/TDC signal with levels adapted to the signal.

    Parameters
    ----------
    signal : array_like, shape (n,)
        Pick-up voltage (any units), uniformly sampled.
    fs : float
        Sample rate, Hz.
    slope : {"rising", "falling"}
        Which edges to return (a negative-going mark: ``"falling"``).
    level : float, optional
        Fixed switching level in signal units (default: the mid level of the local envelope).
    hysteresis : float, optional
        Hysteresis band as a fraction of the local swing, in [0, 1) (the band is ±half of it
        around the level). Default: ``±max(4 σ, 0.05 swing)`` from the estimated noise rms σ.
    interpolation : {"cubic", "linear"}
        Sub-sample interpolation of the crossing; cubic only where the four samples around
        it rise monotonically (smooth flanks), linear elsewhere.
    min_snr : float
        Smallest local peak-to-peak swing, in noise rms, that counts as pulses (default 12).

    Returns
    -------
    EdgeDetection

    Raises
    ------
    AnalysisError
        Constant signal; a signal whose swing never exceeds ``min_snr`` times its noise (no
        pulses, only noise); more edges than a quarter of the samples (noise, not pulses).

    Examples
    --------
    A once-per-revolution TDC mark two samples wide on a noisy, drifting baseline:

    >>> fs = 100_000.0
    >>> t = np.arange(200_000) / fs
    >>> x = 0.2 + 0.5 * t + 0.02 * np.random.default_rng(1).standard_normal(t.size)
    >>> marks = np.arange(0.013, 2.0, 0.04)              # 1500 rpm
    >>> x[np.rint(marks * fs).astype(int)] += 3.0
    >>> x[np.rint(marks * fs).astype(int) + 1] += 3.0
    >>> found = find_edges(x, fs=fs)
    >>> found.edges.size, float(np.max(np.abs(found.edges - marks))) < 1.5 / fs
    (50, True)
    """
    x = check_finite_array(signal, "signal", ndim=1, min_length=4, error=AnalysisError)
    fs = check_positive(fs, "fs", error=AnalysisError)
    check_option(slope, "slope", ("rising", "falling"), error=AnalysisError)
    check_option(interpolation, "interpolation", ("cubic", "linear"), error=AnalysisError)
    min_snr = check_positive(min_snr, "min_snr", error=AnalysisError)
    if hysteresis is not None:
        hysteresis = check_range(hysteresis, "hysteresis", 0.0, 1.0, inclusive=(True, False),
                                 error=AnalysisError)
    if slope == "falling":
        x = -x
    lo_all, hi_all = float(x.min()), float(x.max())
    if hi_all == lo_all:
        raise AnalysisError(f"signal is constant (no pulses): every sample is {lo_all:g}; "
                            "expected a pulse train")
    sigma = noise_rms(x)
    floor = max(min_snr * sigma, 1e-9 * (hi_all - lo_all))
    # first pass: a window from the spacing of excursions off the median
    med = float(np.median(x))
    thr = max(8.0 * sigma, 0.01 * (hi_all - lo_all))
    active = np.abs(x - med) > thr
    starts = np.flatnonzero(active[1:] & ~active[:-1]) + 1
    width = x.size if starts.size < 2 else \
        int(ENVELOPE_INTERVALS * np.percentile(np.diff(starts), 99.5)) + 3
    edges, info = _detect(x, fs, width, sigma, floor, level, hysteresis, slope, interpolation)
    if edges.size >= 2:  # second pass: a window from the pulse intervals themselves
        spacing = np.diff(edges) * fs
        width = int(ENVELOPE_INTERVALS * np.percentile(spacing, 99.5)) + 3
        edges, info = _detect(x, fs, width, sigma, floor, level, hysteresis, slope,
                              interpolation)
    if edges.size > x.size // 4:
        raise AnalysisError(f"signal: {edges.size} edges in {x.size} samples (more than one "
                            "per 4 samples): that is noise, not pulses; expected a pulse train "
                            "sampled at several samples per pulse")
    return EdgeDetection(edges=edges, window_s=width / fs, noise_rms=sigma,
                         level="fixed" if level is not None else "adaptive", **info)


def _detect(x, fs, width, sigma, floor, level, hysteresis, slope, interpolation):
    hi, lo = _envelope(x, width)
    swing = hi - lo
    del hi
    valid = swing > floor
    if not valid.any():
        raise AnalysisError(
            f"signal: no pulses above the noise — its peak-to-peak swing over windows of "
            f"{width / fs:.4g} s never exceeds {floor / max(sigma, 1e-300):.0f} × the noise "
            f"rms ({sigma:.3g}; largest swing {float(swing.max()):.3g}); expected a pulse "
            "train (pick-up disconnected or unpowered?)")
    if level is None:
        from scipy.ndimage import uniform_filter1d

        # averaged over the window: the extremes of noise and of the sampling phase average out
        mid = uniform_filter1d(lo + 0.5 * swing, int(max(3, min(width, x.size))),
                               mode="nearest")
    else:
        mid = np.full(x.size, float(level) * (-1.0 if slope == "falling" else 1.0))
    if hysteresis is None:
        h = np.maximum(4.0 * sigma, 0.05 * swing)
    else:
        h = 0.5 * hysteresis * swing
    upper = mid + h
    on, _ = _schmitt(x, upper, mid - h, valid)
    if on.size == 0:
        edges = np.empty(0)
        runt_t = runt_h = np.empty(0)
    else:
        edges = _crossings(x, mid, mid - h, on, interpolation) / fs
        runt_t, runt_h = _runts(x, mid, width, sigma, on, upper)
        runt_t = runt_t / fs
    info = dict(runt_times=runt_t, runt_heights=runt_h,
                swing=float(np.median(swing[valid])), hysteresis=float(np.median(h[valid])))
    return edges, info


def detect_edges(signal, *, fs, hysteresis=None, level=None, slope="rising",
                 interpolation="cubic"):
    """Edge times of an analogue tacho signal (levels adapted to the signal).

    The edges of :func:`find_edges` (which see for the method, its parameters and the
    details it also returns: runt pulses, noise, swing).

    Parameters
    ----------
    signal : array_like, shape (n,)
        Pick-up voltage (any units), uniformly sampled.
    fs : float
        Sample rate, Hz.
    hysteresis : float, optional
        Hysteresis band as a fraction of the local swing, in [0, 1); default from the noise.
    level : float, optional
        Fixed switching level in signal units; default the mid level of the local envelope.
    slope : {"rising", "falling"}
    interpolation : {"cubic", "linear"}
        Cubic (Lagrange through the four samples around a smooth crossing) has an error of
        order ``(f_pulse / fs)**4`` of a sample for a sine-like magnetic pick-up, linear of
        order ``(f_pulse / fs)**2``; square pulses with a rise shorter than a sample are
        limited to about a tenth of a sample either way.

    Returns
    -------
    numpy.ndarray
        Edge times, s from the first sample, ascending.

    References
    ----------
    Liang Shoupan, *Engine dynamics*, 1948, ch. 9 (timing of records).

    Examples
    --------
    >>> fs = 20_000.0
    >>> t = np.arange(2000) / fs
    >>> edges = detect_edges(np.sin(2 * np.pi * 250.0 * t - 0.3), fs=fs)
    >>> print(np.round(edges[:3] * 1e3, 5))  # ms; up-crossings at (0.3 + 2 pi k)/(2 pi 250)
    [0.19099 4.19099 8.19099]
    """
    found = find_edges(signal, fs=fs, hysteresis=hysteresis, level=level, slope=slope,
                       interpolation=interpolation)
    return found.edges
