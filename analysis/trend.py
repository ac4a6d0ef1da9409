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

__all__ = ["cycle_average", "remove_trend", "TREND_KINDS"]

log = logging.getLogger("crankbench")

#: what :func:`remove_trend` may find in a channel
TREND_KINDS = ("none", "angle ramp", "speed mean")

_TWO_PI = 2.0 * np.pi


def cycle_average(values: np.ndarray, phi: np.ndarray, fs: float, *,
                  revolutions=(2.0, 3.0)) -> np.ndarray:
    """Time average of ``values`` over windows spanning whole revolutions of shaft angle.

    Each sample is replaced by the mean of ``values`` over the time during which the shaft
    angle ``phi`` stays within ``±R/2`` revolutions of its own angle, for each window length
    ``R`` of ``revolutions`` in turn. A window of two revolutions (one four-stroke cycle)
    averages every order that is a multiple of 1/2 to zero at steady speed, one of three
    revolutions every multiple of 1/3; other orders ``o`` are kept by the factor
    ``Π sin(π o R)/(π o R)``. Near the record ends the windows shrink to stay centred (a ramp
    is kept exactly; the vibration is averaged less there).

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
    out = np.asarray(values, dtype=float)
    room = np.minimum(phi - phi[0], phi[-1] - phi)          # angle to the nearer record end
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
    if kind in ("auto", "angle ramp"):
        # a cheap test on the raw reference first; the cycle average only when it may apply
        if kind == "angle ramp" or _is_ramp(_fit(values, phi)):
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
        omega = speed_rpm * (_TWO_PI / 60.0)
        if kind == "speed mean" or _carries_speed(values, omega, _fit(values, omega)):
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
    """A channel whose mean is the (scaled) shaft speed: the fit explains 90 % of its variance
    or the speed term is ≥ 5× the rest, and the mean is ≥ 20 % of the speed term."""
    share = abs(fit["scale"]) * float(np.mean(omega))
    spread = float(np.std(values - fit["scale"] * omega - fit["offset"]))
    return (share >= 5.0 * spread and abs(float(np.mean(values))) >= 0.2 * share
            and (fit["r2"] >= 0.9 or share >= 50.0 * spread))


def _fit(y, x):
    """Least-squares line ``y ≈ s x + c`` with its R²."""
    xm, ym = float(np.mean(x)), float(np.mean(y))
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
