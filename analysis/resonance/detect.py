"""What resonance the measurement could have shown: the finder's detection limit per critical.

A predicted critical the finder did not report is a disagreement only if the record could
have shown it. :func:`analysis.find_resonances` accepts a peak whose rise above the order's
baseline is at least ``min_snr`` times the track's amplitude noise there, at least
``min_prominence`` of the amplitude, at least ``min_amplitude_fraction`` of the largest
amplitude tracked, and whose confidence ``quality · (1 − exp(−snr/10))`` reaches
``min_confidence`` (so, at best quality, ``snr ≥ −10 ln(1 − min_confidence)``: 6.9 for 0.5).
The detection limit of a critical is the largest of these at its speed, read from the track
(noise: ``amplitude_uncertainty`` within ±2 % of the speed; level: the amplitude there).
"""

from __future__ import annotations

import numpy as np

__all__ = ["detection_limits"]


def detection_limits(track, orders, speeds_rpm, *, min_snr=5.0, min_prominence=0.05,
                     min_confidence=0.5, min_amplitude_fraction=1e-3, window=0.02):
    """Smallest resonance rise the finder can report, and the track's level, per critical.

    Parameters
    ----------
    track : xarray.Dataset
        Order track (``amplitude``, ``amplitude_uncertainty`` over ``order``, ``time`` with
        ``rpm`` along time), as from :func:`analysis.order_track`.
    orders, speeds_rpm : array_like
        Order and critical speed (rpm) of each predicted critical.
    min_snr, min_prominence, min_confidence, min_amplitude_fraction : float
        The finder's settings (:func:`analysis.find_resonances`).
    window : float
        Relative speed window around each critical over which noise and level are read.

    Returns
    -------
    (limit, level) : tuple of ndarray
        Detection limit (rise above the baseline, units of the track) and the track's median
        amplitude within the window; NaN where the order is not tracked, the track has no
        noise estimate, or the run did not reach the speed.

    Examples
    --------
    >>> import xarray as xr
    >>> rpm = np.linspace(300.0, 700.0, 401)
    >>> ds = xr.Dataset({"amplitude": (("order", "time"), np.full((1, 401), 2e-3)),
    ...                  "amplitude_uncertainty": (("order", "time"), np.full((1, 401), 5e-5))},
    ...                 coords={"order": [6.0], "time": np.arange(401.0), "rpm": ("time", rpm)})
    >>> limit, level = detection_limits(ds, [6.0, 6.0, 4.5], [500.0, 900.0, 500.0])
    >>> print([f"{v:.4g}" for v in limit], level[0])   # 5e-5 x 10 ln 2 (confidence 0.5)
    ['0.0003466', 'nan', 'nan'] 0.002
    """
    orders = np.atleast_1d(np.asarray(orders, dtype=float))
    speeds = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    limit = np.full(orders.shape, np.nan)
    level = np.full(orders.shape, np.nan)
    if "amplitude_uncertainty" not in track or "rpm" not in track.coords:
        return limit, level
    snr = max(float(min_snr), -10.0 * np.log(max(1.0 - float(min_confidence), 1e-12)))
    amp_all = np.asarray(track["amplitude"].values, dtype=float)
    top = float(np.nanmax(np.abs(amp_all))) if np.isfinite(amp_all).any() else np.nan
    rpm = np.asarray(track["rpm"].values, dtype=float)
    tracked = np.asarray(track["order"].values, dtype=float)
    for i, (order, speed) in enumerate(zip(orders, speeds)):
        hit = np.flatnonzero(np.isclose(tracked, order, rtol=0.0, atol=1e-9))
        if hit.size == 0 or not np.isfinite(speed):
            continue
        sub = track.isel(order=int(hit[0]))
        amp = np.asarray(sub["amplitude"].values, dtype=float)
        noise = np.asarray(sub["amplitude_uncertainty"].values, dtype=float)
        near = (np.abs(rpm - speed) <= window * speed) & np.isfinite(amp) & np.isfinite(noise)
        if not near.any():
            continue
        level[i] = float(np.median(amp[near]))
        limit[i] = max(snr * float(np.median(noise[near])), min_prominence * level[i],
                       min_amplitude_fraction * top)
    return limit, level
