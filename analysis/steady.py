"""Steady-state order tables: amplitude and phase of each order over a constant-speed run.

A record taken at constant speed (a load point, a dwell of a stepped test, the flat top of a
run) has no sweep and no resonance crossing to find; what it holds is the steady-state amplitude
and phase of every order, measured with the whole segment's noise rejection. For each steady
segment (:func:`steady_segments`: speed within ±1 % of its median for at least 20 revolutions)
the channel is resampled at constant shaft angle and one least-squares fit of all orders and
the channel's trend over an even number of whole revolutions gives each order's complex
amplitude (every half order on a bin, so the fit is the exact rectangular-window DFT,
:class:`analysis.orders.BlockFit`).

Uncertainty: ``σ_A = sqrt(P_noise)`` with ``P_noise`` the residual's mean square per bin beside
the orders (the rectangular window's ENBW is one bin), ``σ_φ = σ_A/A`` rad; a speed drifting
within the segment (up to the ±1 % tolerance) smears an order by at most the same relative
amount over its bin, far below a bin width for orders ≤ 50.

Phases follow the order trackers' convention (``A cos(o φ + phase)``), referred to TDC of
cylinder 1 when the speed reference carries the encoder angle
(:func:`analysis.speedref.speed_reference`), else to the record's first sample.
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict._validate import check_int, check_range
from crankbench.predict.errors import AnalysisError

__all__ = ["steady_segments", "steady_orders"]

log = logging.getLogger("crankbench")


def steady_segments(speed_rpm, fs: float, *, tolerance: float = 0.01,
                    min_revolutions: int = 20):
    """Sample spans ``[(start, stop), ...]`` where the speed stays within ``±tolerance`` of the
    span's median for at least ``min_revolutions`` revolutions.

    The speed is examined in one-revolution steps; a span grows while the next revolution's
    mean speed stays within the tolerance of the span's running median.

    Parameters
    ----------
    speed_rpm : array_like
        Speed per sample, rpm.
    fs : float
        Sample rate, Hz.
    tolerance : float
        Relative half-width of the speed band.
    min_revolutions : int
        Shortest segment kept, revolutions.

    Returns
    -------
    list of (int, int)

    Examples
    --------
    >>> fs = 100.0
    >>> rpm = np.concatenate([np.full(2000, 600.0), np.linspace(600, 900, 1000),
    ...                       np.full(3000, 900.0)])
    >>> steady_segments(rpm, fs)          # the ramp's first/last percent still counts as steady
    [(0, 2020), (2967, 6000)]
    """
    speed = np.asarray(getattr(speed_rpm, "values", speed_rpm), dtype=float)
    tolerance = check_range(tolerance, "tolerance", 0.0, 0.5, inclusive=(False, True),
                            error=AnalysisError)
    min_revolutions = check_int(min_revolutions, "min_revolutions", minimum=1,
                                error=AnalysisError)
    n = speed.shape[0]
    out = []
    if n == 0 or speed.max() <= 0:
        return out
    # one-revolution steps at the local speed
    edges = [0]
    while edges[-1] < n:
        here = max(float(speed[edges[-1]]), 1e-9)
        edges.append(min(n, edges[-1] + max(1, int(round(60.0 / here * fs)))))
    edges = np.asarray(edges)
    revs = np.array([speed[a:b].mean() for a, b in zip(edges[:-1], edges[1:])])
    start = 0
    while start < revs.shape[0]:
        stop = start + 1
        while stop < revs.shape[0]:
            med = float(np.median(revs[start:stop + 1]))
            window = revs[start:stop + 1]
            if med <= 0 or np.max(np.abs(window - med)) > tolerance * med:
                break
            stop += 1
        if stop - start >= min_revolutions and revs[start] > 0:
            a, b = int(edges[start]), int(edges[stop])
            # trim samples of the last partial revolution that leave the band
            out.append((a, b))
            start = stop
        else:
            start += 1
    return out


def steady_orders(x, *, fs=None, speed_rpm, orders, amplitude: str = "peak", segments=None,
                  tolerance: float = 0.01, min_revolutions: int = 20, samples_per_rev=None):
    """Steady-state amplitude and phase of each order, per steady segment, with uncertainty.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal; a Record channel supplies ``fs`` and ``units``.
    fs : float, optional
        Sample rate, Hz.
    speed_rpm : float or array_like
        Speed per sample (rpm), e.g. :func:`analysis.speedref.speed_reference` (its
        ``shaft_angle`` coordinate, when present, refers the phases to TDC).
    orders : sequence of float
        Orders, each once.
    amplitude : {'peak', 'rms', 'peak-to-peak'}
    segments : list of (int, int), optional
        Sample spans to evaluate (default :func:`steady_segments`).
    tolerance, min_revolutions
        Passed to :func:`steady_segments`.
    samples_per_rev : int, optional
        Angle samples per revolution (default 64, more for orders above 16).

    Returns
    -------
    pandas.DataFrame
        One row per (segment, order): ``segment``, ``time_start_s``, ``time_stop_s``,
        ``speed_rpm`` (mean), ``speed_spread_rpm`` (max − min), ``revolutions``, ``order``,
        ``amplitude``, ``amplitude_uncertainty`` (1 σ), ``phase_deg``,
        ``phase_uncertainty_deg`` (1 σ). ``attrs``: ``units``, ``amplitude_convention``,
        ``phase_reference``, ``method``.

    Raises
    ------
    AnalysisError
        No steady segment (the message gives the speed range found).

    Examples
    --------
    >>> fs = 2000.0
    >>> t = np.arange(int(10 * fs)) / fs
    >>> phi = 2 * np.pi * 25.0 * t                                     # 1500 rpm
    >>> rng = np.random.default_rng(1)
    >>> x = 0.8 * np.cos(3 * phi + 0.5) + 0.2 * np.cos(1.5 * phi) + rng.normal(0, 0.1, t.size)
    >>> table = steady_orders(x, fs=fs, speed_rpm=1500.0, orders=[1.5, 3])
    >>> print(table[["order", "amplitude", "phase_deg"]].round(1).to_string(index=False))
     order  amplitude  phase_deg
       1.5        0.2       -0.2
       3.0        0.8       28.8
    >>> bool((table.amplitude_uncertainty < 2e-3).all()), round(float(table.phase_uncertainty_deg[0]), 1)
    (True, 0.3)
    """
    import pandas as pd

    from .orders import (BlockFit, _check_nyquist, _check_orders, _t0, amplitude_factor,
                         default_samples_per_rev)
    from .resample import _angle_input, _as_rpm, _as_signal, resample_arrays, shaft_angle

    factor = amplitude_factor(amplitude)
    orders = _check_orders(orders)
    values, fs_, units, label = _as_signal(x, fs)
    n = values.shape[0]
    angle, reference = _angle_input(None, speed_rpm, n)
    speed = _as_rpm(speed_rpm, n, fs_)
    phi = shaft_angle(speed, fs_) if angle is None else angle
    spr = default_samples_per_rev(float(orders.max())) if samples_per_rev is None else \
        check_int(samples_per_rev, "samples_per_rev", minimum=4, error=AnalysisError)
    _check_nyquist(float(orders.max()), float(speed.max()), fs_, label)
    if segments is None:
        segments = steady_segments(speed, fs_, tolerance=tolerance,
                                   min_revolutions=min_revolutions)
    if not segments:
        raise AnalysisError(f"{label}: no steady segment (speed within ±{100 * tolerance:g} % "
                            f"for {min_revolutions} revolutions); the speed spans "
                            f"{speed.min():.6g}–{speed.max():.6g} rpm")
    from .trend import remove_trend

    attrs = getattr(x, "attrs", {}) or {}
    values, trend = remove_trend(values, fs_, phi=phi, speed_rpm=speed,
                                 quantity=attrs.get("quantity"), units=units)
    t0 = _t0(x)
    rows = []
    for k, (a, b) in enumerate(segments):
        try:
            y, t_rel, rpm, ang, _ = resample_arrays(values[a:b], fs_, speed[a:b],
                                                    samples_per_rev=spr, angle=phi[a:b],
                                                    label=label)
        except AnalysisError as exc:
            log.info("%s: steady segment %d skipped (%s)", label, k, exc)
            continue
        revs = 2 * (y.shape[0] // (2 * spr))            # even: every half order on a bin
        if revs < 2:
            continue
        fitter = BlockFit(orders, spr, revs, "boxcar")
        try:
            fitter.check_spacing()
        except AnalysisError as exc:
            log.info("%s: steady segment %d skipped (%s)", label, k, exc)
            continue
        coef, mean, floor, _ = fitter.fit(y[None, :revs * spr], ang[:1])
        sigma = fitter.noise(floor)[0]
        span = speed[a:b]
        for j, order in enumerate(orders):
            amp = float(np.abs(coef[0, j]))
            rows.append({"segment": k, "time_start_s": t0 + a / fs_,
                         "time_stop_s": t0 + (b - 1) / fs_, "speed_rpm": float(span.mean()),
                         "speed_spread_rpm": float(np.ptp(span)), "revolutions": revs,
                         "order": float(order), "amplitude": amp * factor,
                         "amplitude_uncertainty": float(sigma[j]) * factor,
                         "phase_deg": float(np.degrees(np.angle(coef[0, j]))),
                         "phase_uncertainty_deg": float(np.degrees(min(np.pi, sigma[j]
                                                                      / max(amp, 1e-300))))})
    if not rows:
        raise AnalysisError(f"{label}: the steady segments are too short for a steady-state "
                            "table (at least two whole revolutions after resampling)")
    table = pd.DataFrame(rows)
    table.attrs.update(units=units, amplitude_convention=amplitude,
                       phase_reference=reference, trend=trend["removed"],
                       method="least squares of all orders and the trend over an even number "
                              "of whole revolutions (rectangular window) per steady segment")
    return table
