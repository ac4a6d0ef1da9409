"""Order-tracking settings chosen from the record: what ``order_track()`` does with no option.

A fixed default is wrong for somebody: a bandwidth narrow enough to reject the noise of a slow
run-up flattens a resonance crossed at 1000 rpm/s (−54 % at the peak), one wide enough for the
crossing doubles the noise of every steady order. The default therefore follows the record:

1. **Probe.** A Vold–Kalman solve (:func:`analysis.vkf.vold_kalman`, joint with the order-0
   trend) at a moderate bandwidth, a quarter order (``0.25·rpm/60`` Hz), gives each order's
   amplitude and the noise density beside it.
2. **Noise.** Where an order is steady the bandwidth is as narrow as the record allows:
   ``B_floor = max(8/duration, 0.005·rpm/60)`` Hz (the envelope may still vary over an
   eighth of the record, or over 200 revolutions).
3. **Sharp peaks.** Around each peak of an order's amplitude (less its running mean, so
   shoulders count) that stands out of the noise (ten times the amplitude noise: a resonance
   crossing, half-power crossing time ``T``, smearing ``≈ 159/(πTB)^4`` for the 2nd-order
   filter, estimated from ``|A''|``), the bandwidth is widened over ``±2T``, to the value
   minimising noise² + smearing² (``B* = (8 b₀² B₀⁸/(ENBW' N0))^{1/9}``) and at least
   ``4/T``, and the solve repeated (≤ 4 passes, until the bandwidth changes by < 15 %); each
   pass sees the peak sharper than the last. Elsewhere the order keeps the narrow band: a
   curved but peak-free envelope (an order growing with speed) is smeared little by the
   2nd-order filter (its response is flat to fourth order) and what remains is reported in
   the uncertainty.
4. **Limits.** An order's bandwidth never exceeds 1.5 times the distance to the nearest other
   tracked order (jointly solved, they stay apart), half the order itself (its distance to
   order 0 and to its mirror), a quarter of the solve rate, nor what lets another
   line of the signal (an order not tracked, read in the residual's order spectrum) reach the
   order above 0.1 % of its amplitude; where that limit leaves more than
   about 1 % of expected error, an :class:`analysis.orders.OrderWarning` names the order, the
   speed, the local sweep rate, the expected error and the setting to use.
5. **Lines beside the orders.** The lines that the probe's residual shows within 1.5 orders
   of a tracked order (an engine signal has every half order) are solved jointly with the
   tracked orders from then on, at the floor bandwidth, and not reported
   (``attrs['auto_joint_lines']``): at the floor bandwidth of a short record (4 Hz for 2 s)
   a half order 12.5 Hz away still passed, and a beat read as envelope curvature widened the
   band further -- order 1 of a steady 2 s record with every half order read 27 % off.
   A record of 2-4 half-overlapping 8-revolution blocks (12-24 revolutions) is searched too.
6. **Short records** (:func:`short_record_blocks`, called by ``order_track``): where the
   floor band exceeds half an order, or where the line search finds lines beside the tracked
   orders in a record of fewer than :data:`SHORT_REVOLUTIONS` revolutions, computed order
   tracking takes over (the reason in ``attrs['auto_settings']``).

The result is an ordinary order track (``method='vkf'`` layout) with ``amplitude_uncertainty``
(noise and smearing), ``bandwidth_hz`` (order, time), NaN within half the response time
``1/B`` of the record's ends (:data:`UNSETTLED`: there the smoother's error exceeds its stated
uncertainty), and ``attrs['auto_settings']``: the chosen bandwidths, the reason for each,
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

__all__ = ["sweep_rate", "auto_track", "steady_speed", "short_record_blocks"]

log = logging.getLogger("crankbench")

#: results within ``UNSETTLED / B`` of a record's ends are left NaN (B the bandwidth there).
#: Measured with the filter at its 8/duration floor: on steady and swept orders under white
#: noise (6 seeds, 3-10 s records) the rms error over the rms stated uncertainty is 1.8-1.9
#: within 0.1/B of an end (the smoother sees one side only; the stated uncertainty is the
#: interior's), 1.3-1.5 at 0.1-0.25/B, 1.0-1.1 at 0.25-0.5/B and 0.95-1.1 beyond, as in the
#: interior; with every half order 0.5-10 in the signal (2-8 s records) the error reaches
#: 3.6-9.6 % at 0.25-0.5/B (within 2.8 stated σ) and at most 2.3 % at 0.5-1/B, as in the
#: interior (2.7 %). Blanking the whole response time 1/B, as before, lost a quarter of a
#: record at the floor bandwidth (2.5 s of a 10 s run-up); half of it is now kept.
UNSETTLED = 0.5

_ERROR_TARGET = 0.002        # aim: noise and smearing each ~0.2 % of the local amplitude
_WARN_AT = 0.01              # warn where the expected error exceeds ~1 %
_MAX_PASSES = 4
_PEAK_SIGMAS = 10.0         # a peak stands out by this many amplitude-noise sigmas
_CAP_SPACING = 1.5          # widest band: this many times the distance to the nearest order
#: records of fewer revolutions with lines beside the tracked orders go to computed order
#: tracking (:func:`short_record_blocks`)
SHORT_REVOLUTIONS = 24
_JOINT_REACH = 1.5          # lines of the signal this close (orders) to a tracked order are
                            # solved with it (not reported): a 2 s steady record's untracked
                            # half orders had put order 1 off by 27 % with the defaults


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


def _line_caps(res, orders, fs, p, found=None):
    """Largest bandwidth (Hz) per (decimated sample, order) that keeps every other line of the
    signal out of each tracked order: for a line of amplitude ``A_L`` at ``Δf`` from an order of
    amplitude ``A``, the VKF lets ``|H(Δf)| A_L`` through, so
    ``B ≤ 2Δf (c A_L / (ε A))^{-1/2p}`` with ``ε`` = 0.1 %. The lines are read in the
    residual of the current solve (orders not tracked) on an order spectrum of 16-revolution
    blocks: a line counts where it stays on its order bin over five consecutive blocks and lies
    at least 0.4 orders from the tracked order (closer content is the order's own envelope
    spread by a fast crossing). ``found``, a set, receives the order (bin) of every such line
    within :data:`_JOINT_REACH` orders of a tracked order (:func:`auto_track` solves them
    jointly)."""
    from .ordermap import MapSpectra
    from .resample import resample_arrays

    resid = np.asarray(res["residual"].values, float)
    rpm_d = np.asarray(res["rpm"].values, float)
    fs_d = float(res.attrs["solve_rate_hz"])
    t = res["time"].values
    amp = np.abs(res["envelope"].values).T                     # (Nd, K)
    nd, k = amp.shape
    caps = np.full((nd, k), np.inf)
    if found is not None:
        found.clear()
    top = 0.45 * fs_d / (rpm_d.max() / 60.0)                   # highest order the solve holds
    spr = int(8 * np.ceil(max(4.0 * top, 16.0) / 8.0))
    try:
        y, t_rel, r_y, _, _ = resample_arrays(resid, fs_d, rpm_d, samples_per_rev=spr,
                                              antialias=False, label="residual")
    except Exception:                                          # too short to look for lines
        return caps
    # 16-revolution blocks where five fit (48 revolutions), else 8 (two of them in 12
    # revolutions at least): a line must show in five consecutive blocks (all of two to
    # four); half orders stay 4 bins apart in 8-revolution blocks, the bins between them on
    # the window's nulls (in 4-revolution blocks no bin between two half orders is free of
    # them, and the lower quartile of the bins read as noise sat on the lines)
    revs = 16 if y.shape[0] >= 48 * spr else 8
    length = spr * revs
    if y.shape[0] < 3 * length // 2:  # fewer than 2 half-overlapping blocks: no persistence
        return caps
    starts = np.arange(0, y.shape[0] - length + 1, length // 2)
    spectra = MapSpectra(length, "hann", "amplitude", 1.0, length // 2 + 1)
    lines = spectra(y[starts[:, None] + np.arange(length)[None, :]])   # (blocks, bins)
    axis = np.arange(lines.shape[1]) / revs
    keep = axis <= top
    t_blk = np.interp(starts + length / 2.0, np.arange(t_rel.shape[0]), t_rel) + t[0]
    c = np.sqrt(2.0) - 1.0
    eps = 1e-3
    rows = lines * keep[None, :]
    # each block's noise level: the lower quartile of its bins scaled to the median of a
    # Rayleigh (noise-only) amplitude, 1.177/0.759 -- the median itself sat on the lines' main
    # lobes where the lines are dense (every half order: every bin of an 8-revolution block)
    floors = np.array([1.55 * float(np.percentile(r[keep], 25.0)) if keep.any() else 0.0
                       for r in rows])
    is_peak = np.zeros_like(rows, dtype=bool)
    is_peak[:, 1:-1] = ((rows[:, 1:-1] > rows[:, :-2]) & (rows[:, 1:-1] >= rows[:, 2:])
                        & (rows[:, 1:-1] > 10.0 * floors[:, None]))
    # an order-locked line stays on its order bin (±1) in the neighbouring blocks; a fixed
    # frequency (a resonance's free vibration after a crossing, part of the order's envelope
    # by definition) moves across the order axis and is no line to keep out
    spread = is_peak.copy()
    spread[:, 1:] |= is_peak[:, :-1]
    spread[:, :-1] |= is_peak[:, 1:]
    # on its bin (±1) in the 5 consecutive blocks nearest this one (about 48 revolutions;
    # the record's first and last blocks are judged with the 5 at that end), or in all of a
    # short record's 2-4 blocks
    nb = rows.shape[0]
    width = min(5, nb)
    persistent = np.zeros_like(is_peak)
    for b in range(nb):
        lo = min(max(b - width // 2, 0), nb - width)
        persistent[b] = is_peak[b] & np.all(spread[lo:lo + width], axis=0)
    for b in range(starts.shape[0]):
        row = rows[b]
        peaks = np.flatnonzero(persistent[b])
        if peaks.size == 0:
            continue
        if found is not None:
            for q in peaks:
                gap = np.abs(axis[q] - orders).min()
                # (and 0.4 orders from order 0, the trend's: closer content is its drift)
                if 0.4 <= gap <= _JOINT_REACH and axis[q] >= 0.4:
                    found.add(float(axis[q]))
        half = (length / 2.0) * 60.0 / (spr * max(float(r_y.mean()), 1e-9))
        # the samples within the block's time span (t is sorted: a slice, not a mask over
        # the whole record per block, which made this quadratic in the record length)
        sel = slice(int(np.searchsorted(t, t_blk[b] - half, side="left")),
                    int(np.searchsorted(t, t_blk[b] + half, side="right")))
        if sel.stop <= sel.start:
            continue
        n_here = float(np.median(rpm_d[sel]))
        for j, order in enumerate(orders):
            a_k = max(float(np.median(amp[sel, j])), 1e-300)
            for q in peaks:
                d_ord = abs(axis[q] - order)
                if d_ord < 0.4:
                    continue         # the order's own envelope content (a crossing's spread)
                a_line = float(row[q])
                bound = 2.0 * d_ord * n_here / 60.0 * (c * a_line / (eps * a_k)) ** (-0.5 / p)
                caps[sel, j] = np.minimum(caps[sel, j], bound)
    return caps


def _smooth(b, fs_d, floor):
    """Let a widened bandwidth rise and fall over about one of its own response times
    (a running mean over 1/B), so the filter changes gradually."""
    from scipy.ndimage import uniform_filter1d

    out = b.copy()
    for j in range(b.shape[1]):
        col = b[:, j]
        wide = col > floor[:, j] * 1.0001
        if not wide.any():
            continue
        size = int(np.clip(fs_d / max(float(np.median(col[wide])), 1e-9), 1, col.shape[0]))
        out[:, j] = np.maximum(uniform_filter1d(col, size=size, mode="nearest"), floor[:, j])
    return out


def _peaks(amp, noise, t, fs_d, probe_bw, floor=0.0):
    """Sharp peaks of one order's amplitude: ``[(i_peak, i_start, i_stop, T_half_power)]``.

    Peaks are sought in the amplitude less its running mean over ``10/B`` seconds (so a
    resonance on a rising baseline, a shoulder, counts too); a peak stands out by at least
    ten times the local amplitude noise (and the median noise), and lies at least ``2/B``
    from the record's ends (where the filter has not settled). ``T`` is the width at half the
    peak's prominence divided by √3 (for a resonance's envelope ``1/√(1 + (2t/T)²)`` the
    half-height width is √3 T). A peak less prominent than 0.1 % of its amplitude is none
    (a smoothing filter cannot take more than the prominence off it; on a noise-free record
    round-off ripples would otherwise pass ten times a noise of 1e-13). ``floor``: the
    amplitude the solve cannot resolve (signal units; :func:`_level_floor`), a noise the
    peaks must stand out of too (an order the record lacks reads round-off of the others)."""
    from scipy.ndimage import uniform_filter1d
    from scipy.signal import find_peaks, peak_widths

    size = int(np.clip(10.0 / max(probe_bw, 1e-9) * fs_d, 3, amp.shape[0]))
    high = amp - uniform_filter1d(amp, size=size, mode="nearest")
    sigma = max(float(np.median(noise)), floor)
    idx, props = find_peaks(high, prominence=_PEAK_SIGMAS * sigma)
    # the filter's ends are not settled: no peak within 2/B of the record's ends
    inside = (t[idx] - t[0] >= 2.0 / probe_bw) & (t[-1] - t[idx] >= 2.0 / probe_bw)
    idx = idx[inside]
    props = {key: value[inside] for key, value in props.items()}
    if idx.size == 0:
        return []
    widths, _, left, right = peak_widths(high, idx, rel_height=0.5,
                                         prominence_data=(props["prominences"],
                                                          props["left_bases"],
                                                          props["right_bases"]))
    dt = 1.0 / fs_d
    out = []
    for i, prom, w, lo, hi in zip(idx, props["prominences"], widths, left, right):
        if prom < _PEAK_SIGMAS * max(float(noise[i]), floor):
            continue                                # a bump of the local noise
        if prom < 0.5 * _ERROR_TARGET * float(amp[i]):
            continue    # flattened entirely it would cost < 0.1 %: no reason to widen
        out.append((int(i), int(np.floor(lo)), int(np.ceil(hi)), float(w * dt / np.sqrt(3.0))))
    return out


def _next_bandwidth(res, current, floor, cap, p, level_floor=0.0):
    """Bandwidth per (decimated sample, order) for the next pass: the floor where the order is
    steady, and around each sharp peak (:func:`_peaks`, above ``level_floor``, signal units)
    the value minimising noise² + smearing² (and at least ``4/T`` for a half-power crossing
    time ``T``) over ±2 T."""
    from .vkf import enbw_hz

    amp = np.abs(res["envelope"].values).T                  # (Nd, K)
    noise = res["amplitude_noise"].values.T
    smear = res["smearing_model"].values.T       # the Lorentzian model: scales as B^(-2p)
    t = res["time"].values
    enbw_per_hz = float(enbw_hz(1.0, p))
    n0 = noise ** 2 / np.maximum(enbw_per_hz * current, 1e-300)
    k4 = 4 * p
    new = floor.copy()
    fs_d = float(res.attrs["solve_rate_hz"])
    for j in range(amp.shape[1]):
        probe_bw = float(np.median(current[:, j]))
        for i, lo, hi, width in _peaks(amp[:, j], noise[:, j], t, fs_d, probe_bw,
                                       level_floor):
            s_pk = float(smear[lo:hi + 1, j].max())
            b_pk = float(current[i, j])
            # noise² + s²(B0/B)^(4p) is least at B* = (4p s² B0^(4p) / (e N0))^(1/(4p+1))
            best = (k4 * s_pk ** 2 * b_pk ** k4 / max(enbw_per_hz * float(n0[i, j]), 1e-300)) \
                ** (1.0 / (k4 + 1)) if s_pk > 0 else 0.0
            want = max(best, 4.0 / max(width, 1e-9))
            reach = 2.0 * max(width, 1.0 / max(want, 1e-9))
            sel = (t >= t[lo] - reach) & (t <= t[hi] + reach)
            new[sel, j] = np.maximum(new[sel, j], want)
    return np.clip(new, floor, cap)


def _expected(res, current, new, p, level_floor=0.0):
    """Expected relative error (total, smearing) at bandwidth ``new`` from the solve at
    ``current``, relative to the order's local level (at least ``level_floor``, signal units:
    the error of an order the record lacks is judged against what the solve can resolve)."""
    amp = np.abs(res["envelope"].values).T
    noise = res["amplitude_noise"].values.T
    smear = res["smearing_model"].values.T       # the Lorentzian model: scales as B^(-2p)
    with np.errstate(divide="ignore", invalid="ignore"):
        smear_new = smear * np.minimum(current / new, 1e3) ** (2 * p)
        noise_new = noise * np.sqrt(new / current)
    level = np.maximum(_local_level(amp, res), level_floor)
    return np.hypot(smear_new, noise_new) / level, smear_new / level


def _level_floor(values) -> float:
    """The amplitude below which the solve resolves nothing of a channel (signal units): the
    VKF's numerical floor (:data:`analysis.vkf.NUMERICAL_FLOOR`) times the channel's peak-
    equivalent level ``√2·std``. A clean two-order run-up's absent order 6 (round-off of the
    others, ~1e-9 of the level) had been widened to 75 Hz around its "peaks" and warned of
    with an expected error of 56 %."""
    from .vkf import NUMERICAL_FLOOR

    return NUMERICAL_FLOOR * float(np.sqrt(2.0) * np.std(values))


def _local_level(amp, res):
    """Running maximum of each order's amplitude over ±max(2/B_min, 0.25 s) (the scale an
    error is judged against: a ripple after a resonance is judged against the resonance)."""
    from scipy.ndimage import maximum_filter1d

    fs_d = float(res.attrs["solve_rate_hz"])
    reach = int(max(2.0 / float(res.attrs["bandwidth_hz_min"]), 0.25) * fs_d)
    out = maximum_filter1d(amp, size=2 * reach + 1, axis=0, mode="nearest")
    return np.maximum(out, 1e-300)


def auto_track(context, *, orders, bandwidth_hz=None, bandwidth_orders=None,
               filter_order: int = 2, min_bandwidth_orders=None, _joint=(), **_ignored):
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
    min_bandwidth_orders : float, optional
        A floor in orders (Hz = value · rpm/60) above the noise floor, for a caller that needs
        the track to resolve a known feature width (the pipeline's resonance identification).
    _joint : tuple of float
        Internal: orders among ``orders`` that are lines of the signal found beside the
        requested ones (within :data:`_JOINT_REACH`), solved jointly at the floor bandwidth so
        that they do not leak into them, and not reported.

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
    if min_bandwidth_orders is not None:
        floor_full = np.maximum(floor_full, float(min_bandwidth_orders) * speed[None, :] / 60.0)
    cap_orders = np.asarray([np.abs(orders[j] - np.concatenate([[0.0], np.delete(orders, j)]))
                             .min() for j in range(k)])
    # half the distance to the nearest tracked order (or order 0): wider, the joint solve
    # trades content between neighbours (beats read as curvature)
    # wider than the order's own frequency the envelope would take in order 0 and the mirror
    cap_full = np.minimum(_CAP_SPACING * cap_orders, 0.5 * orders)[:, None] * speed[None, :] / 60.0
    probe = np.minimum(np.maximum(0.25 * speed[None, :] / 60.0, floor_full),
                       0.5 * cap_orders[:, None] * speed[None, :] / 60.0)
    extra = np.isin(orders, np.asarray(_joint, dtype=float))
    if extra.any():            # lines solved with the orders: narrow throughout
        cap_full[extra] = floor_full[extra]
        probe[extra] = floor_full[extra]
    current = probe
    level_floor = _level_floor(values)
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
        found = set() if it == 0 and not _joint else None
        cap_d = np.minimum(np.minimum(cap_full[:, index].T, nyq_cap),
                           np.maximum(_line_caps(res, orders, fs, p, found), floor_d))
        if found:              # lines beside the orders: solve them jointly from the start
            return _with_joint_lines(context, orders, _merge_lines(found), filter_order,
                                     min_bandwidth_orders)
        new_d = _next_bandwidth(res, cur_d, floor_d, cap_d, p, level_floor)
        new_d = np.minimum(_smooth(new_d, fs_d, floor_d), cap_d)
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
    rel, smear_rel = _expected(res, cur_d, cur_d, p, level_floor)   # at the bandwidth used
    ds = _vkf_dataset(res, context, orders)
    bw_used = current[:, index]
    per_order = []
    for j, order in enumerate(orders):
        if extra[j]:
            continue
        b = bw_used[j]
        wide = b > 1.5 * floor_full[j, index]
        text = (f"order {order:g}: {np.median(b):.3g} Hz where steady"
                f" (floor {np.median(floor_full[j, index]):.3g} Hz: 8/duration or 0.005 order)")
        if wide.any():
            r = res["rpm"].values
            text += (f", widened up to {b.max():.3g} Hz at {r[wide].min():.0f}–"
                     f"{r[wide].max():.0f} rpm around sharp envelope features")
        per_order.append(text)
    worst = np.array([np.nanmax(c) if np.isfinite(c).any() else np.nan for c in rel.T])
    worst = worst[~extra]
    settings = {
        "method": ("Vold-Kalman, joint with order 0" + (
            f" and with the lines of the signal at orders {', '.join(f'{o:g}' for o in _joint)}"
            " beside the tracked ones (found in the residual's order spectrum; solved at the "
            "floor bandwidth, not reported)" if extra.any() else "")
            + ", bandwidth per order against time"),
        "reason": ("narrow where the orders are steady (noise rejection), widened where the "
                   "envelope bends faster than the filter passes (resonance crossings)"),
        "sweep_rate_rpm_per_s": rate, "steady_speed": steady, "passes": len(history),
        "bandwidths": per_order, "filter_order": p,
        "expected_error_max_relative": [float(v) for v in worst]}
    ds.attrs["auto_settings"] = "; ".join(f"{key}: {value}" for key, value in settings.items())
    ds.attrs["auto_bandwidth_hz_range"] = [float(bw_used[~extra].min()),
                                           float(bw_used[~extra].max())]
    ds.attrs["auto_expected_error"] = [float(v) for v in worst]
    ds["bandwidth_hz"] = (("order", "time"), bw_used, {"units": "Hz", "long_name":
                                                      "VKF -3 dB bandwidth used"})
    # near the record's ends the smoother sees data on one side only: no result there
    tt = ds["time"].values
    near_end = np.minimum(tt - tt[0], tt[-1] - tt)[None, :] < UNSETTLED / bw_used
    if near_end.any():
        for name in ("amplitude", "phase", "amplitude_uncertainty", "amplitude_noise"):
            ds[name] = ds[name].where(~near_end)
        lost = near_end[~extra].any(axis=0)
        head = float(tt[np.argmin(lost)] - tt[0]) if not lost.all() else float(tt[-1] - tt[0])
        tail = float(tt[-1] - tt[::-1][np.argmin(lost[::-1])]) if not lost.all() else 0.0
        ds.attrs["unsettled_ends"] = (
            f"results within {UNSETTLED:g}/B of the record's ends are NaN: the first "
            f"{head:.3g} s and the last {tail:.3g} s at most ({100 * lost.mean():.3g} % of "
            "the record)")

    if extra.any():
        keep = np.flatnonzero(~extra)
        std = ds.attrs.get("amplitude_std_estimate")
        ds = ds.isel(order=keep)
        if isinstance(std, list) and len(std) == extra.shape[0]:
            ds.attrs["amplitude_std_estimate"] = [std[j] for j in keep]
        ds.attrs["auto_joint_lines"] = [float(o) for o in _joint]
        orders, rel, smear_rel = orders[keep], rel[:, keep], smear_rel[:, keep]
        cap_d, bw_used = cap_d[:, keep], bw_used[keep]
    _warn_limits(ds, orders, rel, smear_rel, cap_d, bw_used.T, speed[index],
                 fs, OrderWarning)
    return ds


def _merge_lines(found) -> tuple:
    """The lines found (orders, on the 1/16-order bins of the line search), one per cluster of
    bins within 1/8 order (a line between two bins shows on both)."""
    merged = []
    for o in sorted(found):
        if merged and o - merged[-1][-1] <= 0.125 + 1e-9:
            merged[-1].append(o)
        else:
            merged.append([o])
    return tuple(float(np.mean(group)) for group in merged)


def _with_joint_lines(context, orders, lines, filter_order, min_bandwidth_orders):
    """:func:`auto_track` of ``orders`` with ``lines`` solved jointly (not reported)."""
    every = np.sort(np.concatenate([orders, np.asarray(lines, dtype=float)]))
    log.info("order_track: lines of the signal at orders %s beside the tracked ones are solved "
             "with them", ", ".join(f"{o:g}" for o in lines))
    return auto_track(context, orders=every, filter_order=filter_order,
                      min_bandwidth_orders=min_bandwidth_orders, _joint=tuple(lines))


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
        own = cap_d[i, j] >= 0.98 * 0.5 * order * rpm[i] / 60.0   # half the order: order 0
        why = ("half the order's own frequency (its distance to order 0 and its mirror)" if own
               else "the distance to the nearest tracked order or other line of the signal")
        advice = ("sweep slower, or accept the leakage of order 0 with method='vkf', "
                  f"bandwidth_hz={min(4 * cap_d[i, j], 0.25 * fs):.3g}" if own else
                  f"track order {order:g} alone or with orders further apart (method='vkf', "
                  f"bandwidth_hz={min(4 * cap_d[i, j], 0.25 * fs):.3g}), or sweep slower")
        # (a steady stretch has no sweep to blame: what bends its envelope is a beat with a
        # line of the signal the bandwidth cannot keep out)
        sweep = (f"sweep {abs(local):.4g} rpm/s" if abs(local) >= 1.0 else
                 "steady speed: a beat with a line of the signal, not a sweep")
        warnings.warn(
            f"order {order:g} near {rpm[i]:.0f} rpm ({sweep}): the envelope "
            f"changes faster than the widest usable bandwidth ({cap_d[i, j]:.3g} Hz, set by "
            f"{why}) passes; expected peak error up to about {100 * smear_rel[i, j]:.2g} % "
            f"(total {100 * rel[i, j]:.2g} %; the smearing estimate is conservative). "
            f"To do better: {advice}",
            category, stacklevel=4)
        log.warning("order %g: expected error %.2g %% near %.0f rpm (bandwidth limited)",
                    order, 100 * rel[i, j], rpm[i])


def short_record_blocks(phi, speed_rpm, fs, orders, lines=None):
    """``(revolutions, window, reason)`` when a record is too short for the adaptive
    Vold–Kalman default, else None. ``phi`` shaft angle (rad) and ``speed_rpm`` speed (rpm)
    per sample, ``fs`` sample rate (Hz); ``lines``: the lines of the signal beside the tracked
    orders that the adaptive filter's line search found (``attrs['auto_joint_lines']``), if it
    ran.

    The adaptive filter's narrowest band is ``8/duration`` Hz (:mod:`analysis.autotrack`) and
    an order's band may not exceed half the order (its distance to order 0 and its mirror);
    where the first exceeds the second for any order at the record's lowest speed, the filter
    cannot separate that order in this record (it would return NaN after trimming its
    unsettled ends). Nor, in a record of fewer than :data:`SHORT_REVOLUTIONS` revolutions,
    the ``lines`` beside an order: its narrowest band (a third of an order or more) passes
    them, and jointly solved at that band they still beat with the orders (with every half
    order 0.5-10 in the signal, orders 1, 2 and 4.5 read up to 30 % off on a steady
    17.5-revolution record and 11 % on a 20-revolution ramp; 0.6-1.2 % with 4-revolution
    blocks). A short record of a single order crossing a resonance keeps the filter (computed
    order tracking read a Q = 20 peak 2 % low at 400 rpm/s in 19 revolutions, the filter
    0.06 %). Computed order tracking takes over with Hann blocks of ``4/spacing``
    revolutions (the orders, and order 0, outside each other's main lobe), fewer where the
    record holds less than two such blocks (the spacing check then warns).
    """
    duration = phi.shape[0] / fs
    floor = 8.0 / duration
    low = float(np.min(speed_rpm)) / 60.0
    orders = np.asarray(orders, float)
    caps = 0.5 * orders * low
    revs_total = abs(float(phi[-1] - phi[0])) / (2 * np.pi)
    too_wide = not np.all(floor <= caps)
    if not too_wide and not (lines and revs_total < SHORT_REVOLUTIONS):
        return None
    worst = float(orders[np.argmax(floor - caps)])
    why = (f"the record ({duration:.3g} s, {revs_total:.3g} revolutions) is too short for the "
           f"adaptive Vold-Kalman default, whose narrowest band 8/duration = {floor:.3g} Hz "
           + (f"exceeds half of order {worst:g} ({0.5 * worst * low:.3g} Hz at "
              f"{60.0 * low:.4g} rpm)" if too_wide else
              f"({floor / max(low, 1e-300):.2g} orders at {60.0 * low:.4g} rpm) cannot keep "
              f"the lines of the signal at orders {', '.join(f'{q:g}' for q in lines)} out "
              f"of the tracked ones in fewer than {SHORT_REVOLUTIONS} revolutions"))
    o = np.sort(np.concatenate([[0.0], orders]))
    need = int(np.ceil(4.0 / float(np.min(np.diff(o)))))
    revs = max(1, min(need, int(np.floor(revs_total / 2.0))))
    return revs, "hann", why
