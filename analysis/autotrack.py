"""Order-tracking settings chosen from the record: what ``order_track()`` does with no option.

A fixed default is wrong for somebody: a bandwidth narrow enough to reject the noise of a slow
run-up flattens a resonance crossed at 1000 rpm/s (−54 % at the peak), one wide enough for the
crossing doubles the noise of every steady order. The default therefore follows the record:

1. **Probe.** A Vold–Kalman solve (:func:`analysis.vkf.vold_kalman`, joint with the order-0
   trend) at a moderate bandwidth, half an order (``0.5·rpm/60`` Hz), gives each order's
   amplitude and the noise density beside it.
2. **Noise.** Where an order is steady the bandwidth is as narrow as the record allows:
   ``B_floor = max(8/duration, 0.005·rpm/60)`` Hz (the envelope may still vary over an
   eighth of the record, or over 200 revolutions).
3. **Sharp features.** Where the solved envelope bends faster than its bandwidth passes (a
   resonance crossing: half-power crossing time ``T``, smearing ``≈ 159/(πTB)^4`` for the
   2nd-order filter, estimated from ``|A''|``), the bandwidth is widened in time, to the value
   minimising noise² + smearing² (``B* = (8 b₀² B₀⁸/(ENBW' N0))^{1/9}``), kept at least over
   ``±2/B`` around the feature, and the solve repeated (≤ 4 passes, until the bandwidth
   changes by < 15 %); each pass sees the feature sharper than the last.
4. **Limits.** An order's bandwidth never exceeds the distance to the nearest other tracked
   order (and to order 0), nor a quarter of the solve rate; where that limit leaves more than
   about 1 % of expected error, an :class:`analysis.orders.OrderWarning` names the order, the
   speed, the local sweep rate, the expected error and the setting to use.

The result is an ordinary order track (``method='vkf'`` layout) with ``amplitude_uncertainty``
(noise and smearing) and ``attrs['auto_settings']``: the chosen bandwidths, the reason for each,
the sweep rate and the expected error per order.

Measured (bench suite ``orders``, rows ``defaults …``; truth the exact envelope of a Q = 20
resonance from ``solve_ivp`` and the synthesised amplitudes of a noisy run-up): see
``crankbench bench orders``; the acceptance figures of issue 13 (peak within 2 % at 400 rpm/s,
5 % at 1000 rpm/s; noisy run-up ≤ 0.5 % rms) are test assertions in
``tests/analysis/test_autotrack.py`` on other Q, orders and noise levels as well.

References
----------
J. Tůma, "Setting the passband width in the Vold–Kalman order tracking filter", Proc. ICSV12
(2005) (the bandwidth against the sweep rate); H. Vold and J. Leuridan, SAE 931288 (1993).
"""

from __future__ import annotations

import logging
import warnings

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["sweep_rate", "auto_track", "steady_speed"]

log = logging.getLogger("crankbench")

_ERROR_TARGET = 0.002        # aim: noise and smearing each ~0.2 % of the local amplitude
_WARN_AT = 0.01              # warn where the expected error exceeds ~1 %
_MAX_PASSES = 4


def sweep_rate(speed_rpm, fs: float, *, window_s: float | None = None) -> float:
    """Median sweep rate ``|d rpm/dt|`` (rpm/s) of a speed trace, robust to speed noise.

    The speed is fitted by straight lines over windows of ``window_s`` (default: a tenth of
    the record, at least 0.5 s) and the median of the absolute slopes returned; a constant
    speed gives 0 (not the slope of its noise).

    Examples
    --------
    >>> fs = 100.0
    >>> t = np.arange(2000) / fs
    >>> rng = np.random.default_rng(0)
    >>> round(sweep_rate(1000 + 50 * t + rng.normal(0, 2, t.size), fs))
    50
    >>> sweep_rate(np.full(2000, 1500.0) + rng.normal(0, 2, 2000), fs) < 1.0
    True
    """
    speed = np.asarray(getattr(speed_rpm, "values", speed_rpm), dtype=float)
    if speed.ndim == 0 or speed.shape[0] < 4:
        return 0.0
    n = speed.shape[0]
    duration = n / fs
    window = max(0.5, duration / 10.0) if window_s is None else float(window_s)
    length = max(4, min(n, int(round(window * fs))))
    slopes = []
    t = (np.arange(length) - 0.5 * (length - 1)) / fs
    denom = float(np.dot(t, t))
    for start in range(0, n - length + 1, max(1, length // 2)):
        seg = speed[start:start + length]
        slopes.append(float(np.dot(t, seg - seg.mean())) / denom)
    slopes = np.abs(np.asarray(slopes))
    rate = float(np.median(slopes))
    # a slope within the noise of its window is no sweep
    resid = np.std(np.diff(speed)) / np.sqrt(2.0)
    noise_slope = resid / np.sqrt(denom)
    return rate if rate > 3.0 * noise_slope else 0.0


def steady_speed(speed_rpm, fs: float, *, tolerance: float = 0.01) -> bool:
    """True when the speed stays within ``±tolerance`` (relative) of its median.

    Examples
    --------
    >>> steady_speed(np.full(1000, 1500.0), 100.0), steady_speed(np.linspace(1000, 1200, 1000), 100.0)
    (True, False)
    """
    speed = np.asarray(getattr(speed_rpm, "values", speed_rpm), dtype=float)
    med = float(np.median(speed))
    lo, hi = np.percentile(speed, [1.0, 99.0])
    return bool(med > 0 and (hi - lo) <= 2.0 * tolerance * med)


def _caps(orders, speed_d):
    """Largest bandwidth (Hz) per order against time: the distance to the nearest other
    tracked order or to order 0, in Hz at the local speed."""
    o = np.asarray(orders, float)
    others = [np.abs(o[j] - np.concatenate([[0.0], np.delete(o, j)])).min()
              for j in range(o.shape[0])]
    return np.asarray(others)[None, :] * speed_d[:, None] / 60.0


def _spread(b, fs_d, floor):
    """Hold a widened bandwidth over ±2/B around where it was asked (running max), then smooth
    it, so the filter is wide across the whole feature and changes gradually."""
    from scipy.ndimage import maximum_filter1d, uniform_filter1d

    out = b.copy()
    for j in range(b.shape[1]):
        col = b[:, j]
        if np.all(col <= floor[:, j] * 1.0001):
            continue
        reach = int(np.clip(2.0 * fs_d / max(np.median(col[col > floor[:, j] * 1.0001]), 1e-9),
                            1, col.shape[0]))
        wide = maximum_filter1d(col, size=2 * reach + 1, mode="nearest")
        out[:, j] = np.maximum(uniform_filter1d(wide, size=reach + 1, mode="nearest"),
                               floor[:, j])
    return out


def _next_bandwidth(res, current, floor, cap, p):
    """Bandwidth per (decimated sample, order) minimising noise² + smearing² near the current
    solve; returns (bandwidth, expected relative error at it)."""
    from .vkf import enbw_hz

    amp = np.abs(res["envelope"].values).T                  # (Nd, K)
    noise = res["amplitude_noise"].values.T
    total = res["amplitude_uncertainty"].values.T
    smear = np.sqrt(np.maximum(total ** 2 - noise ** 2, 0.0))
    # N0 from the noise at the current bandwidth: σ² = N0 · ENBW(B)
    enbw_per_hz = float(enbw_hz(1.0, p))
    n0 = noise ** 2 / np.maximum(enbw_per_hz * current, 1e-300)
    # smearing well below the aim is no reason to widen (and is mostly the estimate's noise)
    smear = np.where(smear > 0.25 * _ERROR_TARGET * _local_level(amp, res), smear, 0.0)
    # smearing b(B) = b0 (B0/B)^(2p): minimise N0·e·B + b0² B0^(4p) B^(-4p)
    k4 = 4 * p
    with np.errstate(divide="ignore", invalid="ignore"):
        best = (k4 * smear ** 2 * current ** k4 / np.maximum(enbw_per_hz * n0, 1e-300)) \
            ** (1.0 / (k4 + 1))
    best = np.nan_to_num(best, nan=0.0, posinf=np.inf)
    new = np.clip(np.maximum(best, floor), floor, cap)
    with np.errstate(divide="ignore", invalid="ignore"):
        smear_new = smear * (current / new) ** (2 * p)
        noise_new = np.sqrt(n0 * enbw_per_hz * new)
    # errors relative to the order's local level: its largest amplitude within ±1 s or ±2/B
    level = _local_level(amp, res)
    return new, np.hypot(smear_new, noise_new) / level, smear_new / level


def _local_level(amp, res):
    """Running maximum of each order's amplitude over ±max(2/B_min, 0.25 s) (the scale an
    error is judged against: a ripple after a resonance is judged against the resonance)."""
    from scipy.ndimage import maximum_filter1d

    fs_d = float(res.attrs["solve_rate_hz"])
    reach = int(max(2.0 / float(res.attrs["bandwidth_hz_min"]), 0.25) * fs_d)
    out = maximum_filter1d(amp, size=2 * reach + 1, axis=0, mode="nearest")
    return np.maximum(out, 1e-300)


def auto_track(context, *, orders, bandwidth_hz=None, bandwidth_orders=None,
               filter_order: int = 2, **_ignored):
    """The default order track: adaptive Vold–Kalman settings chosen from the record.

    Parameters
    ----------
    context : dict
        The prepared channel from :func:`analysis.orders.order_track` (``values``, ``fs``,
        ``speed``, ``phi``, ``units``, ``label``, ``t0``, ``factor``, ``reference``).
    orders : ndarray
        Checked orders.
    bandwidth_hz, bandwidth_orders : optional
        A bandwidth given by the caller is used as is (one solve, no adaptation).
    filter_order : {1, 2}

    Returns
    -------
    xarray.Dataset
        As :func:`analysis.orders.order_track` with method 'vkf', plus
        ``attrs['auto_settings']``.
    """
    from .orders import OrderWarning, _vkf_dataset
    from .vkf import vold_kalman

    values, fs, speed, phi = context["values"], context["fs"], context["speed"], context["phi"]
    n = values.shape[0]
    duration = n / fs
    rate = sweep_rate(speed, fs)
    steady = steady_speed(speed, fs)
    if bandwidth_hz is not None or bandwidth_orders is not None:
        res = vold_kalman(values, fs=fs, speed_rpm=speed, orders=orders,
                          bandwidth_hz=bandwidth_hz, bandwidth_orders=bandwidth_orders,
                          filter_order=filter_order, shaft_angle=phi)
        ds = _vkf_dataset(res, context, orders)
        ds.attrs["auto_settings"] = ("Vold-Kalman with the caller's bandwidth "
                                     f"({res.attrs['bandwidth']}); sweep rate {rate:.4g} rpm/s")
        return ds
    k = orders.shape[0]
    p = filter_order
    # bandwidths against time at full rate (K, N); decimated views for the update rule
    floor_full = np.maximum(8.0 / duration, 0.005 * speed / 60.0)[None, :] * np.ones((k, 1))
    o = np.sort(np.concatenate([[0.0], orders]))
    cap_orders = np.asarray([np.abs(orders[j] - np.concatenate([[0.0], np.delete(orders, j)]))
                             .min() for j in range(k)])
    cap_full = cap_orders[:, None] * speed[None, :] / 60.0
    probe = np.minimum(np.maximum(0.5 * speed[None, :] / 60.0, floor_full), cap_full)
    current = probe
    history = []
    res = None
    rel = smear_rel = None
    for it in range(_MAX_PASSES):
        res = vold_kalman(values, fs=fs, speed_rpm=speed, orders=orders, bandwidth_hz=current,
                          filter_order=p, shaft_angle=phi)
        index = np.rint(res["time"].values * fs).astype(np.int64)
        fs_d = float(res.attrs["solve_rate_hz"])
        cur_d = current[:, index].T
        floor_d = floor_full[:, index].T
        nyq_cap = 0.25 * fs_d
        cap_d = np.minimum(cap_full[:, index].T, nyq_cap)
        new_d, rel, smear_rel = _next_bandwidth(res, cur_d, floor_d, cap_d, p)
        new_d = np.minimum(_spread(new_d, fs_d, floor_d), cap_d)
        if it > 0:
            # after the probe, widen only: a narrower solve sees a feature flatter than it is
            new_d = np.maximum(new_d, cur_d)
        change = float(np.max(np.abs(np.log(new_d / cur_d))))
        history.append(change)
        if it > 0 and change < np.log(1.15):
            break
        if it == _MAX_PASSES - 1:
            break
        t_d = index / fs
        t_full = np.arange(n) / fs
        current = np.stack([np.interp(t_full, t_d, new_d[:, j]) for j in range(k)])
        current = np.minimum(np.maximum(current, floor_full), cap_full)
    ds = _vkf_dataset(res, context, orders)
    bw_used = current[:, index]
    per_order = []
    for j, order in enumerate(orders):
        b = bw_used[j]
        wide = b > 1.5 * floor_full[j, index]
        text = (f"order {order:g}: {np.median(b):.3g} Hz where steady"
                f" (floor {np.median(floor_full[j, index]):.3g} Hz: 8/duration or 0.005 order)")
        if wide.any():
            r = res["rpm"].values
            text += (f", widened up to {b.max():.3g} Hz at {r[wide].min():.0f}–"
                     f"{r[wide].max():.0f} rpm around sharp envelope features")
        per_order.append(text)
    worst = np.nanmax(rel, axis=0)
    settings = {
        "method": "Vold-Kalman, joint with order 0, bandwidth per order against time",
        "reason": ("narrow where the orders are steady (noise rejection), widened where the "
                   "envelope bends faster than the filter passes (resonance crossings)"),
        "sweep_rate_rpm_per_s": rate, "steady_speed": steady, "passes": len(history),
        "bandwidths": per_order, "filter_order": p,
        "expected_error_max_relative": [float(v) for v in worst]}
    ds.attrs["auto_settings"] = "; ".join(f"{key}: {value}" for key, value in settings.items())
    ds.attrs["auto_bandwidth_hz_range"] = [float(bw_used.min()), float(bw_used.max())]
    ds.attrs["auto_expected_error"] = [float(v) for v in worst]
    ds["bandwidth_hz"] = (("order", "time"), bw_used, {"units": "Hz", "long_name":
                                                      "VKF -3 dB bandwidth used"})
    _warn_limits(ds, orders, rel, smear_rel, cap_full[:, index].T, bw_used.T, speed[index],
                 fs, OrderWarning)
    return ds


def _warn_limits(ds, orders, rel, smear_rel, cap_d, bw_d, speed_d, fs, category):
    """One warning per order whose expected error exceeds ~1 % where the bandwidth hit its
    limit (too fast a sweep for the noise or for the order spacing)."""
    rpm = ds["rpm"].values
    t = ds["time"].values
    # the filter's ends are not settled (they are not results to judge): skip 2/B at each end
    edge = 2.0 / max(float(np.min(bw_d)), 1e-9)
    inner = (t >= t[0] + edge) & (t <= t[-1] - edge)
    for j, order in enumerate(orders):
        bad = inner & (smear_rel[:, j] > _WARN_AT) & (bw_d[:, j] >= 0.98 * cap_d[:, j])
        if not bad.any():
            continue
        i = int(np.argmax(np.where(bad, smear_rel[:, j], -np.inf)))
        lo, hi = max(0, i - 50), min(rpm.shape[0], i + 50)
        local = float(np.polyfit(t[lo:hi], rpm[lo:hi], 1)[0]) if hi - lo > 2 else float("nan")
        warnings.warn(
            f"order {order:g} near {rpm[i]:.0f} rpm (sweep {abs(local):.4g} rpm/s): the envelope "
            f"changes faster than the widest usable bandwidth ({cap_d[i, j]:.3g} Hz, the "
            f"distance to the nearest tracked order) passes; expected peak error about "
            f"{100 * smear_rel[i, j]:.2g} % (total {100 * rel[i, j]:.2g} %). Track order "
            f"{order:g} alone or with orders further apart (method='vkf', "
            f"bandwidth_hz={min(4 * cap_d[i, j], 0.25 * fs):.3g}), or sweep slower",
            category, stacklevel=4)
        log.warning("order %g: expected error %.2g %% near %.0f rpm (bandwidth limited)",
                    order, 100 * rel[i, j], rpm[i])
