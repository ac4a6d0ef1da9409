"""A channel's mean and ramp, kept out of its orders.

Real channels carry more than vibration: an instantaneous-angular-speed (IAS) channel carries
the mean shaft speed (a 1200 rpm engine: 125.7 rad/s under a few rad/s of vibration), an
encoder angle channel the shaft's rotation itself (a ramp of 2π per revolution), any sensor an
offset. A windowed DFT or a Vold–Kalman filter at a low order sees that trend through its
side lobes or its skirt: half the mean speed read as order 0.5, an angle ramp as order 1/3 of
1070°. The trackers therefore

1. remove the *known* trend first (:func:`remove_trend`): an angle channel that follows the
   shaft angle loses ``s·θ̄(t) + c``, an IAS channel ``s·ω̄(t) + c`` (``s`` and ``c`` by least
   squares; ``s`` is the gear ratio to the reference shaft, 1 on the same shaft), where
   ``θ̄``/``ω̄`` is the reference angle/speed averaged over one engine cycle (:func:`cycle_average`,
   which nulls every half order of the reference: an encoder angle or a speed derived from pulses
   carries part of the vibration, and subtracting that would cancel the vibration sought);
2. fit what is left of the trend jointly with the orders (a constant and a slope per COT block,
   an order-0 envelope in the VKF), and report it as the track's ``mean`` (order 0).

Error: the cycle average of a speed varying as ``α t`` is exact; a change of acceleration
within one cycle leaves ``|α'| T_cycle²/24`` rad/s, a slow drift that step 2 removes.

References
----------
K. R. Fyfe and E. D. S. Munck, "Analysis of computed order tracking", MSSP 11(2) (1997) §4
(leakage of low-frequency content into low orders).
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["cycle_average", "mean_rotation", "remove_trend", "SpanTrend", "TREND_KINDS"]

log = logging.getLogger("crankbench")

#: what :func:`remove_trend` may find in a channel
TREND_KINDS = ("none", "angle ramp", "speed mean")

_TWO_PI = 2.0 * np.pi


#: revolutions of the successive cycle-average windows, and their total half-reach
CYCLE_WINDOWS = (2.0, 3.0)
CYCLE_REACH_REVOLUTIONS = 0.5 * sum(CYCLE_WINDOWS)
#: reach of :func:`mean_rotation`: two twiced cycle averages in a row
MEAN_ROTATION_REACH_REVOLUTIONS = 4.0 * CYCLE_REACH_REVOLUTIONS


def cycle_average(values: np.ndarray, phi: np.ndarray, fs: float, *,
                  revolutions=CYCLE_WINDOWS, ends=None) -> np.ndarray:
    """Time average of ``values`` over windows spanning whole revolutions of shaft angle.

    Each sample is replaced by the mean of ``values`` over the time during which the shaft
    angle ``phi`` stays within ``±R/2`` revolutions of its own angle, for each window length
    ``R`` of ``revolutions`` in turn. A window of two revolutions (one four-stroke cycle)
    averages every order that is a multiple of 1/2 to zero at steady speed, one of three
    revolutions every multiple of 1/3; other orders ``o`` are kept by the factor
    ``Π sin(π o R)/(π o R)``. Near the record ends the windows shrink to stay centred (a ramp
    is kept exactly; the vibration is averaged less there). The average is applied twice
    ("twicing": the average of the values plus the average of what it left), which removes the
    lag of a plain time average on an accelerating shaft. The windows are bounded by ``phi``:
    averaging an angle against itself returns its vibration unchanged (the windows move with
    it); use :func:`mean_rotation` for a measured angle.

    Parameters
    ----------
    values : ndarray
        Samples to average (any unit).
    phi : ndarray
        Shaft angle at each sample, rad, increasing.
    fs : float
        Sample rate, Hz (the average is over time).
    revolutions : sequence of float
        Window lengths, revolutions, applied one after the other.
    ends : (float, float), optional
        Shaft angle at the record's first and last samples when ``values`` is a span of a
        longer record (streaming): the windows shrink near the record's ends, not the span's.
        Samples within ``CYCLE_REACH_REVOLUTIONS`` of a span end that is not a record end are
        incomplete (read the span with that margin).

    Returns
    -------
    ndarray

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(8000) / fs
    >>> phi = 2 * np.pi * 10.0 * t                       # 600 rpm
    >>> omega = 62.83 + 3.0 * np.cos(0.5 * phi) + 1.0 * np.cos(phi / 3)
    >>> smooth = cycle_average(omega, phi, fs)
    >>> round(float(np.abs(smooth[2000:-2000] - 62.83).max()), 6)
    0.0
    """
    values = np.asarray(values, dtype=float)
    first, last = (phi[0], phi[-1]) if ends is None else ends
    room = np.minimum(phi - first, last - phi)              # angle to the nearer record end
    return _twiced(values, phi, room, revolutions)


def _twiced(values, phi, room, revolutions):
    once = _smooth(values, phi, room, revolutions)
    # twicing (Tukey): smooth the residual too, which cancels the smoother's own bias on a
    # curved trend (a time average over angle windows lags an accelerating shaft by
    # ~α h²/(6ω²)) while every half/third order still averages to zero
    return once + _smooth(values - once, phi, room, revolutions)


def mean_rotation(angle: np.ndarray, speed_rpm: np.ndarray, fs: float, *, ends=None,
                  revolutions=CYCLE_WINDOWS) -> np.ndarray:
    """Mean rotation of a measured shaft angle: its torsional vibration averaged out.

    A pulse-edge or encoder angle carries the vibration of the node it is measured at. Averaged
    over windows bounded by *that same* angle it would come back unchanged (the windows move
    with the vibration), so the windows here are set by the integrated speed ``φ_s`` (the
    pulse train's revolution-averaged speed: little vibration left, and only its differences
    over a window matter), and the average is taken of the difference from a smooth reference
    ``θ_r = ∫ n̄`` (``n̄`` the cycle-averaged speed): ``θ̄ = θ_r + cycle_average(θ − θ_r)``.
    Every multiple of 1/2 (and 1/3) of the shaft order is nulled at steady speed; the result
    stays anchored to the measured angle (counted edges do not drift). Each value depends only
    on the samples within :data:`MEAN_ROTATION_REACH_REVOLUTIONS` of it (and on the record
    ends), so a span read with that margin gives the whole record's values (streaming).

    Parameters
    ----------
    angle : ndarray
        Measured shaft angle at each sample, rad, increasing.
    speed_rpm : ndarray
        Shaft speed at each sample, rpm (> 0), e.g. the pulse train's revolution-averaged speed.
    fs : float
        Sample rate, Hz.
    ends : (float, float), optional
        The measured angle at the record's first and last samples when ``angle`` is a span of
        a longer record (the windows shrink near the record's ends only).
    revolutions : sequence of float
        Window lengths, revolutions (:func:`cycle_average`).

    Returns
    -------
    ndarray
        Mean shaft angle, rad.

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(10000) / fs
    >>> phi0 = 2 * np.pi * (10.0 * t + 0.1 * t ** 2)            # 600 → 720 rpm
    >>> theta = phi0 + 2e-3 * np.cos(4.5 * phi0) + 1e-3 * np.cos(3 * phi0)
    >>> rpm = 60.0 * (10.0 + 0.2 * t) * (1 + 0.01 * np.cos(4.5 * phi0))   # part of it in n
    >>> err = mean_rotation(theta, rpm, fs) - phi0
    >>> bool(np.abs(err[2000:-2000]).max() < 1e-6)
    True
    """
    from .resample import integrate_angle

    angle = np.asarray(angle, dtype=float)
    rpm = np.asarray(speed_rpm, dtype=float)
    first, last = (angle[0], angle[-1]) if ends is None else ends
    room = np.minimum(angle - first, last - angle)     # the measured angle: span-independent
    start = float(angle[0])
    phi = integrate_angle(rpm, fs, start)
    ref = integrate_angle(_twiced(rpm, phi, room, revolutions), fs, start)
    return ref + _twiced(angle - ref, phi, room, revolutions)


def _smooth(values, phi, room, revolutions):
    out = values
    for revs in np.atleast_1d(revolutions):
        half = np.minimum(0.5 * float(revs) * _TWO_PI, room)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (out[1:] + out[:-1]))])
        a = _position(phi, phi - half)
        b = _position(phi, phi + half)
        width = b - a
        wide = width > 1e-9
        integral = _cum_at(cum, out, b) - _cum_at(cum, out, a)
        out = np.where(wide, integral / np.where(wide, width, 1.0), out)
    return out


def _position(phi, target):
    """Fractional sample position where the increasing ``phi`` reaches ``target``."""
    n = phi.shape[0]
    j = np.clip(np.searchsorted(phi, target, side="right") - 1, 0, n - 2)
    span = phi[j + 1] - phi[j]
    frac = np.clip((target - phi[j]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
    return j + frac


def _cum_at(cum, values, pos):
    """Trapezoidal integral of ``values`` (linear between samples) from 0 to position ``pos``."""
    j = np.clip(np.floor(pos).astype(np.int64), 0, values.shape[0] - 2)
    f = pos - j
    v0, v1 = values[j], values[j + 1]
    return cum[j] + f * v0 + 0.5 * f * f * (v1 - v0)


def remove_trend(values: np.ndarray, fs: float, *, phi: np.ndarray, speed_rpm: np.ndarray,
                 kind: str = "auto", quantity: str | None = None, units: str = ""):
    """Remove a channel's known trend (shaft-angle ramp or mean speed) before order tracking.

    Parameters
    ----------
    values : ndarray
        Channel samples.
    fs : float
        Sample rate, Hz.
    phi : ndarray
        Reference shaft angle at each sample, rad (integrated speed or encoder angle).
    speed_rpm : ndarray
        Reference speed at each sample, rpm.
    kind : {'auto', 'none', 'angle ramp', 'speed mean'}
        'auto' decides from the channel: an angle channel (quantity 'angle', units 'rad', or any
        channel) that follows ``s·φ`` (R² ≥ 0.99 of a least-squares line, ``|s|`` ≥ 0.05) is an
        angle ramp; a speed channel (quantity 'angular_velocity'/'rotational_speed', units
        'rad/s', or any channel) whose mean is at least 20 % of ``s·ω̄`` with a fit explaining
        90 % of its variance carries the mean speed; otherwise nothing is removed here.
    quantity, units : str, optional
        The channel's attrs, to name what was found.

    Returns
    -------
    (ndarray, dict)
        The detrended samples and a description: ``kind``, ``scale`` (s), ``offset`` (c),
        ``removed`` (text for the result's attrs).

    Examples
    --------
    >>> fs = 2000.0
    >>> t = np.arange(8000) / fs
    >>> rpm = np.full(t.size, 1200.0)
    >>> phi = 2 * np.pi * 20.0 * t
    >>> angle = 1.0 * phi + 0.3 + 2e-3 * np.cos(1.5 * phi)   # encoder angle with its ramp
    >>> resid, info = remove_trend(angle, fs, phi=phi, speed_rpm=rpm)
    >>> info["kind"], round(float(np.abs(resid - 2e-3 * np.cos(1.5 * phi)).max()), 5)
    ('angle ramp', 0.0)
    """
    if kind not in ("auto",) + TREND_KINDS:
        raise AnalysisError(f"trend={kind!r} is not one of 'auto', "
                            f"{', '.join(map(repr, TREND_KINDS))}")
    info = {"kind": "none", "scale": 0.0, "offset": 0.0, "removed": "nothing before tracking"}
    if kind == "none":
        return values, info
    # the tests on about 4000 samples (a fit of a line needs no more; cheap on a long record)
    step = max(1, values.shape[0] // 4000)
    sub = slice(None, None, step)
    # the quick tests' fits of the channel on the angle and on the speed, from the centred
    # subsample's dot products (the same sums as two _fit calls, half the time)
    quick = (_subsample_fits(values[sub], phi[sub], speed_rpm[sub] * (_TWO_PI / 60.0))
             if kind == "auto" else None)
    if kind in ("auto", "angle ramp"):
        # a cheap test on the raw reference first; the cycle average only when it may apply
        if kind == "angle ramp" or _is_ramp(quick[0]):
            smooth = cycle_average(phi, phi, fs)
            ramp = _fit(values, smooth)
            if kind == "angle ramp" or _is_ramp(ramp):
                s, c = ramp["scale"], ramp["offset"]
                info.update(kind="angle ramp", scale=s, offset=c,
                            removed=f"shaft-angle ramp {s:.6g}·θ̄ + {c:.6g} (θ̄: reference angle "
                                    "averaged over whole engine cycles)")
                log.info("channel follows the shaft angle (%s%s): ramp %.6g·θ̄ removed before "
                         "order tracking", quantity or "", f", {units}" if units else "", s)
                return values - (s * smooth + c), info
    if kind in ("auto", "speed mean"):
        if kind == "speed mean" or _speed_rule(quick[1], quick[1]["x_mean"],
                                               quick[1]["y_mean"], quick[1]["spread"]):
            omega = speed_rpm * (_TWO_PI / 60.0)
            smooth = cycle_average(omega, phi, fs)
            fit = _fit(values, smooth)
            if kind == "speed mean" or _carries_speed(values, smooth, fit):
                s, c = fit["scale"], fit["offset"]
                info.update(kind="speed mean", scale=s, offset=c,
                            removed=f"mean speed {s:.6g}·ω̄ + {c:.6g} (ω̄: reference speed "
                                    "averaged over whole engine cycles, rad/s)")
                log.info("channel carries the shaft speed (%s%s): %.6g·ω̄ removed before order "
                         "tracking", quantity or "", f", {units}" if units else "", s)
                return values - (s * smooth + c), info
    return values, info


def _is_ramp(fit) -> bool:
    """A channel that follows the shaft angle: R² ≥ 0.99 with a ratio of at least 0.05."""
    return fit["r2"] >= 0.99 and abs(fit["scale"]) >= 0.05


def _carries_speed(values, omega, fit) -> bool:
    """A channel whose mean is the (scaled) shaft speed (:func:`_speed_rule` on the fit of
    ``values`` on ``omega``)."""
    spread = float(np.std(values - fit["scale"] * omega - fit["offset"]))
    return _speed_rule(fit, float(np.mean(omega)), float(np.mean(values)), spread)


def _speed_rule(fit, x_mean: float, y_mean: float, spread: float) -> bool:
    """The fit ``y ≈ s ω + c`` (means ``x_mean``, ``y_mean``; residual standard deviation
    ``spread``) says the channel carries the speed: it explains 90 % of the variance or the
    speed term is ≥ 5× the rest, and the mean is ≥ 20 % of the speed term."""
    share = abs(fit["scale"]) * x_mean
    return (share >= 5.0 * spread and abs(y_mean) >= 0.2 * share
            and (fit["r2"] >= 0.9 or share >= 50.0 * spread))


def _subsample_fits(y, x1, x2):
    """The least-squares lines ``y ≈ s x1 + c`` and ``y ≈ s x2 + c`` as :func:`_fit` gives
    them, from one Gram matrix of the centred samples; the second also with the means and
    the residual's standard deviation (``x_mean``, ``y_mean``, ``spread``) that
    :func:`_speed_rule` judges."""
    m = max(int(y.shape[0]), 1)
    a = np.empty((3, y.shape[0]))
    a[0], a[1], a[2] = y, x1, x2
    mean = np.add.reduce(a, axis=1) / m
    a -= mean[:, None]
    dot = np.dot                      # (five dot products: a @ a.T costs 2x, BLAS set-up)
    total = float(dot(a[0], a[0]))
    fits = []
    for j in (1, 2):
        var, cov = float(dot(a[j], a[j])), float(dot(a[0], a[j]))
        if var <= 0:
            fits.append({"scale": 0.0, "offset": float(mean[0]), "r2": 0.0, "resid": total})
            continue
        s = cov / var
        resid = max(total - s * cov, 0.0)
        fits.append({"scale": s, "offset": float(mean[0]) - s * float(mean[j]),
                     "r2": 1.0 - resid / total if total > 0 else 0.0, "resid": resid})
    fits[1].update(x_mean=float(mean[2]), y_mean=float(mean[0]),
                   spread=float(np.sqrt(fits[1]["resid"] / m)))
    return fits


def _fit(y, x):
    """Least-squares line ``y ≈ s x + c`` with its R²."""
    n = max(int(x.shape[0]), 1)
    xm, ym = float(np.add.reduce(x)) / n, float(np.add.reduce(y)) / n
    dx = x - xm
    var = float(np.dot(dx, dx))
    if var <= 0:
        return {"scale": 0.0, "offset": ym, "r2": 0.0}
    dy = y - ym
    s = float(np.dot(dx, dy)) / var
    total = float(np.dot(dy, dy))
    resid = dy - s * dx
    r2 = 1.0 - float(np.dot(resid, resid)) / total if total > 0 else 0.0
    return {"scale": s, "offset": ym - s * xm, "r2": r2}


class _Moments:
    """Running centred sums of (x, r) over spans (Chan et al.'s pairwise update), so a fit
    over a record read in pieces is as accurate as one over the whole array."""

    def __init__(self):
        self.n, self.mx, self.mr = 0, 0.0, 0.0
        self.sxx = self.srr = self.sxr = 0.0

    def add(self, x, r):
        m = x.shape[0]
        if m == 0:
            return
        mx, mr = float(np.mean(x)), float(np.mean(r))
        dx, dr = x - mx, r - mr
        sxx, srr, sxr = float(dx @ dx), float(dr @ dr), float(dx @ dr)
        n = self.n + m
        ddx, ddr = mx - self.mx, mr - self.mr
        self.sxx += sxx + ddx * ddx * self.n * m / n
        self.srr += srr + ddr * ddr * self.n * m / n
        self.sxr += sxr + ddx * ddr * self.n * m / n
        self.mx += ddx * m / n
        self.mr += ddr * m / n
        self.n = n

    def fit(self):
        """``{'scale', 'offset', 'r2', 'mean_x', 'mean_r', 'spread'}`` of ``x ≈ s r + c``."""
        if self.n == 0 or self.srr <= 0:
            return {"scale": 0.0, "offset": self.mx, "r2": 0.0, "mean_x": self.mx,
                    "mean_r": self.mr, "spread": 0.0}
        s = self.sxr / self.srr
        res = max(self.sxx - s * self.sxr, 0.0)
        r2 = 1.0 - res / self.sxx if self.sxx > 0 else 0.0
        return {"scale": s, "offset": self.mx - s * self.mr, "r2": r2, "mean_x": self.mx,
                "mean_r": self.mr, "spread": float(np.sqrt(res / self.n))}


class SpanTrend:
    """:func:`remove_trend` for a record read span by span (the streamed trackers).

    Pass 1 (:meth:`fit`) reads the record in segments, each with a margin of
    ``CYCLE_REACH_REVOLUTIONS`` at the lowest speed, and fits the angle-ramp and mean-speed
    models from running centred sums; the decision rules are those of :func:`remove_trend`.
    Afterwards the object reads detrended spans (``self(a, b)``) for the trackers.

    Parameters
    ----------
    read : callable
        ``read(a, b)`` → channel samples a..b-1.
    speed_rpm : callable
        ``speed_rpm(a, b)`` → speed (rpm) of samples a..b-1.
    angle : callable
        ``angle()`` → a fresh callable ``phi(a, b)`` giving the shaft angle of samples a..b-1
        (called with non-decreasing ``a``).
    n, fs : int, float
        Samples and sample rate of the channel.
    ends : (float, float)
        Shaft angle at the first and last samples.
    low_rpm : float
        Lowest speed of the record (sets the margin).
    kind : str
        As in :func:`remove_trend`.
    """

    def __init__(self, read, speed_rpm, angle, *, n, fs, ends, low_rpm, kind="auto"):
        if kind not in ("auto",) + TREND_KINDS:
            raise AnalysisError(f"trend={kind!r} is not one of 'auto', "
                                f"{', '.join(map(repr, TREND_KINDS))}")
        self.read, self.speed, self.angle = read, speed_rpm, angle
        self.n, self.fs, self.ends, self.kind = int(n), float(fs), ends, kind
        self.margin = int(np.ceil(1.2 * CYCLE_REACH_REVOLUTIONS * 60.0 / low_rpm * fs)) + 2
        self.info = {"kind": "none", "scale": 0.0, "offset": 0.0,
                     "removed": "nothing before tracking"}
        self._phi = None

    def _refs(self, phi_fn, a, b):
        """Cycle-averaged angle and speed (rad, rad/s) of samples a..b-1 (read with margin)."""
        ra, rb = max(0, a - self.margin), min(self.n, b + self.margin)
        phi = phi_fn(ra, rb)
        omega = self.speed(ra, rb) * (_TWO_PI / 60.0)
        theta = cycle_average(phi, phi, self.fs, ends=self.ends)[a - ra:b - ra]
        wbar = cycle_average(omega, phi, self.fs, ends=self.ends)[a - ra:b - ra]
        return theta, wbar

    def fit(self, segment: int):
        """Pass 1: decide the trend from the whole record, ``segment`` samples at a time."""
        if self.kind == "none":
            return self.info
        phi_fn = self.angle()
        ramp, speed = _Moments(), _Moments()
        for a in range(0, self.n, segment):
            b = min(self.n, a + segment)
            x = self.read(a, b)
            theta, wbar = self._refs(phi_fn, a, b)
            ramp.add(x, theta)
            speed.add(x, wbar)
        fr, fw = ramp.fit(), speed.fit()
        if self.kind == "angle ramp" or (self.kind == "auto" and _is_ramp(fr)):
            self.info.update(kind="angle ramp", scale=fr["scale"], offset=fr["offset"],
                             removed=f"shaft-angle ramp {fr['scale']:.6g}·θ̄ + "
                                     f"{fr['offset']:.6g} (θ̄: reference angle averaged over "
                                     "whole engine cycles)")
        elif self.kind == "speed mean" or (self.kind == "auto" and _speed_like(fw)):
            self.info.update(kind="speed mean", scale=fw["scale"], offset=fw["offset"],
                             removed=f"mean speed {fw['scale']:.6g}·ω̄ + {fw['offset']:.6g} "
                                     "(ω̄: reference speed averaged over whole engine cycles, "
                                     "rad/s)")
        return self.info

    def __call__(self, a: int, b: int) -> np.ndarray:
        """Detrended samples a..b-1 (calls with non-decreasing ``a``)."""
        x = self.read(a, b)
        if self.info["kind"] == "none":
            return x
        if self._phi is None or a < self._last:
            self._phi = self.angle()
        self._last = max(0, a - self.margin)
        theta, wbar = self._refs(self._phi, a, b)
        ref = theta if self.info["kind"] == "angle ramp" else wbar
        return x - (self.info["scale"] * ref + self.info["offset"])


def _speed_like(fit) -> bool:
    """:func:`_carries_speed` from a moments fit."""
    share = abs(fit["scale"]) * fit["mean_r"]
    spread = fit["spread"]
    return (share >= 5.0 * spread and abs(fit["mean_x"]) >= 0.2 * share
            and (fit["r2"] >= 0.9 or share >= 50.0 * spread))
