"""Tacho and encoder pulse trains from the shaft motion, with a wheel's imperfections.

The node carrying the wheel turns by ``ratio (psi(t) + x(t))``: ``psi`` the mean crank angle of
cylinder 1 from firing TDC (exact integral of the operating profile) and ``x`` the node's
(referred) torsional vibration. Tooth ``k`` (pitch position ``j = k mod N`` at its actual
angle, tooth errors and butt joint included) passes the pick-up when that angle reaches
``2 pi floor(k/N) + angle_j - tdc_offset``: TDC of cylinder 1 follows tooth 0 by
``tdc_offset``. The edge times are solved by Newton's method from the mean-motion inverse,
with ``x`` and its velocity interpolated by cubic Hermite polynomials between the integration
samples (interpolation error about ``(omega h)**4 / 384`` of the vibration for a component of
angular frequency ``omega``; Newton converges to round-off in three steps because the
vibration is small).
"""

from __future__ import annotations

import numpy as np

from crankbench.predict.errors import ConfigError

from .imperfections import degrade_edges, tooth_angles

__all__ = ["wheel_edges", "analogue_pickup", "tooth_numbers", "pulse_voltage",
           "pickup_voltage"]

TWO_PI = 2.0 * np.pi


def wheel_edges(profile, *, start_angle, ratio, grid_time, vibration, vibration_velocity,
                pulses_per_rev, missing_teeth, tdc_offset, imperfections, rng,
                duration=None, apply_timing=True):
    """Edge times of a pulse wheel on a vibrating node.

    Parameters
    ----------
    profile : SpeedProfile
        Mean speed of the crankshaft.
    start_angle : float
        Crank angle of cylinder 1 from firing TDC at t = 0, rad.
    ratio : float
        Speed of the node relative to the crankshaft.
    grid_time : numpy.ndarray
        Uniform integration grid, s.
    vibration, vibration_velocity : numpy.ndarray or None
        Referred torsional angle (rad) and velocity (rad/s) of the node on ``grid_time``
        (None: no vibration).
    pulses_per_rev, missing_teeth : int
    tdc_offset : float
        rad.
    imperfections : Imperfections
    rng : numpy.random.Generator
    duration : float, optional
        Record length, s (default the grid's end).
    apply_timing : bool
        Apply jitter, dropouts, spurious pulses and timer quantisation (False for the true
        edges an analogue pick-up is built from).

    Returns
    -------
    edges : numpy.ndarray
        Edge times, s.
    clean : numpy.ndarray
        The true edge times (tooth errors included, timing imperfections not).

    Examples
    --------
    >>> from crankbench.measure.synth.profile import steady
    >>> from crankbench.measure.synth.imperfections import Imperfections
    >>> edges, _ = wheel_edges(steady(600.0, duration=1.0), start_angle=0.0, ratio=1.0,
    ...                        grid_time=np.linspace(0, 1, 11), vibration=None,
    ...                        vibration_velocity=None, pulses_per_rev=4, missing_teeth=0,
    ...                        tdc_offset=0.0, imperfections=Imperfections(),
    ...                        rng=np.random.default_rng(0))
    >>> edges[:3].round(6).tolist()                  # 10 rev/s, 4 teeth: every 25 ms
    [0.0, 0.025, 0.05]
    """
    n = int(pulses_per_rev)
    end = float(grid_time[-1] if duration is None else duration)
    teeth = tooth_angles(n, imperfections, rng)
    present = np.ones(n, bool)
    if missing_teeth:
        present[n - missing_teeth:] = False
    if ratio <= 0:
        raise ConfigError(f"pulse wheel on a node turning at ratio {ratio:g}: expected > 0")
    # wheel angle reached at the ends (vibration is small: pad one revolution)
    w_start = ratio * start_angle + tdc_offset
    w_end = ratio * (start_angle + profile.angle(end)) + tdc_offset
    k0 = int(np.floor(w_start / TWO_PI)) - 1
    k1 = int(np.ceil(w_end / TWO_PI)) + 1
    revs = np.arange(k0, k1 + 1)
    target = (revs[:, None] * TWO_PI + teeth[None, present]).ravel()
    target = target[(target > w_start - 0.5 * TWO_PI) & (target < w_end + 0.5 * TWO_PI)]
    # mean motion first: crank angle psi = wheel/ratio - tdc/ratio
    psi_target = (target - tdc_offset) / ratio
    t = profile.time_at_angle(psi_target - start_angle)
    if vibration is not None:
        from scipy.interpolate import CubicHermiteSpline

        spline = CubicHermiteSpline(grid_time, vibration, vibration_velocity)
        dspline = spline.derivative()
        for _ in range(4):
            tc = np.clip(t, grid_time[0], grid_time[-1])
            f = start_angle + profile.angle(t) + spline(tc) - psi_target
            fp = profile.speed(t) + dspline(tc)
            t = t - f / fp
    keep = (t >= 0.0) & (t <= end)
    clean = np.sort(t[keep])
    edges = degrade_edges(clean, imperfections, rng) if apply_timing else clean
    edges = edges[(edges >= 0.0) & (edges <= end)]
    return edges, clean


def analogue_pickup(edges, *, time, pulses_per_rev, missing_teeth, profile, amplitude=1.0):
    """Magnetic pick-up voltage with a rising zero crossing at each edge.

    Between consecutive edges the signal is ``A sin(2 pi u)``, ``u`` the fractional edge count
    (linear in time between edges), so the rising zero crossings fall exactly on the edges;
    across a missing-tooth gap the signal stays at zero (no tooth, no flux change). The
    amplitude grows with speed like an inductive pick-up's (``A = amplitude * omega /
    omega_max``).

    Returns
    -------
    numpy.ndarray
        Voltage, V, on ``time``.

    Examples
    --------
    >>> from crankbench.measure.synth.profile import steady
    >>> from crankbench.measure.tacho import detect_edges
    >>> edges = np.arange(1, 40) * 0.025
    >>> t = np.arange(20_000) / 20_000.0
    >>> v = analogue_pickup(edges, time=t, pulses_per_rev=4, missing_teeth=0,
    ...                     profile=steady(600.0, duration=1.0))
    >>> bool(np.allclose(detect_edges(v, fs=20_000.0)[:3], edges[1:4], atol=1e-6))
    True
    """
    time = np.asarray(time, float)
    u = np.interp(time, edges, np.arange(edges.size), left=np.nan, right=np.nan)
    omega = profile.speed(time)
    amp = amplitude * omega / omega.max()
    out = amp * np.sin(TWO_PI * np.nan_to_num(u))
    out[np.isnan(u)] = 0.0
    if missing_teeth and edges.size > 2:
        dt = np.diff(edges)
        ref = np.median(dt)
        for g in np.flatnonzero(dt > 1.5 * ref):
            a, b = edges[g], edges[g + 1]
            inside = (time > a) & (time < b)
            ti = time[inside]
            # a positive half-wave after the last tooth, flat, a negative half-wave before the
            # first tooth after the gap (its rising zero crossing is the edge)
            wave = np.where(ti < a + 0.5 * ref, np.sin(TWO_PI * (ti - a) / ref), 0.0)
            wave = np.where(ti > b - 0.5 * ref, np.sin(TWO_PI * (ti - b) / ref), wave)
            out[inside] = amp[inside] * wave
    return out


def tooth_numbers(edges, *, pulses_per_rev, missing_teeth):
    """Tooth number of each edge of a wheel: 0 for the first tooth after the gap.

    Without a gap the first edge is tooth 0. The gap is an interval longer than 1.5 times the
    median interval.

    Examples
    --------
    >>> e = np.delete(np.arange(20.0), [4, 5, 10, 11, 16, 17])     # a 6-2 wheel
    >>> tooth_numbers(e, pulses_per_rev=6, missing_teeth=2).tolist()
    [0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1]
    """
    edges = np.asarray(edges, float)
    n = int(pulses_per_rev)
    if edges.size < 2:
        return np.zeros(edges.size, int)
    if not missing_teeth:
        return np.mod(np.arange(edges.size), n)
    dt = np.diff(edges)
    gap_end = np.flatnonzero(dt > 1.5 * np.median(dt)) + 1
    present = n - int(missing_teeth)
    out = np.empty(edges.size, int)
    first = int(gap_end[0]) if gap_end.size else 0
    out[first:] = np.mod(np.arange(edges.size - first), present)
    out[:first] = np.mod(np.arange(-first, 0), present)
    return out


def pulse_voltage(edges, time, *, widths, levels=1.0, high=5.0, low=0.0):
    """Square pulses (a Hall or optical pick-up, a TDC mark) sampled with exact sub-sample
    coverage: each sample is the mean of the ideal signal over its sampling interval, so edges
    between samples keep their timing in the sampled values (a 1-sample mark included).

    Parameters
    ----------
    edges : array_like
        Rising edge times, s.
    time : array_like
        Sample times (uniform), s.
    widths : float or array_like
        Pulse widths, s.
    levels : float or array_like
        Pulse height as a fraction of ``high - low`` (a runt tooth: e.g. 0.11).
    high, low : float
        Levels, V.

    Returns
    -------
    numpy.ndarray
        Voltage on ``time``.

    Examples
    --------
    >>> t = np.arange(8) * 1e-3          # each sample: the mean over t +- 0.5 ms
    >>> pulse_voltage([2.25e-3], t, widths=2e-3, high=1.0).round(3).tolist()
    [0.0, 0.0, 0.25, 1.0, 0.75, 0.0, 0.0, 0.0]
    """
    edges = np.asarray(edges, float)
    time = np.asarray(time, float)
    widths = np.broadcast_to(np.asarray(widths, float), edges.shape)
    levels = np.broadcast_to(np.asarray(levels, float), edges.shape)
    h = float(time[1] - time[0]) if time.size > 1 else 1.0
    # cumulative "high" integral H(t): piecewise linear through the pulse starts and ends
    ends = edges + widths
    knots = np.column_stack([edges, ends]).ravel()
    steps = np.column_stack([np.zeros_like(widths), widths * levels]).ravel()
    order = np.argsort(knots, kind="stable")
    knots, steps = knots[order], steps[order]
    cum = np.concatenate([[0.0], np.cumsum(steps)])[1:]
    # between a start and its end H rises linearly: interpolate on (start, end) pairs
    integral = np.interp(time + 0.5 * h, knots, cum, left=0.0) - \
        np.interp(time - 0.5 * h, knots, cum, left=0.0)
    return low + (high - low) * integral / h


def pickup_voltage(edges, *, time, params, profile):
    """The analogue voltage of a scene's tacho sensor (see :mod:`measure.synth.scene`).

    ``params`` holds ``pulses_per_rev``, ``missing_teeth`` and the pick-up keys ``shape``
    ("sine": :func:`analogue_pickup`; "square": 0–5 V pulses of half a pitch, or of
    ``mark_width_deg`` for a once-per-revolution mark), ``runt_teeth`` with ``runt_level`` and
    ``ringing`` with ``ringing_hz``.

    Examples
    --------
    >>> from crankbench.measure.synth.profile import steady
    >>> t = np.arange(5000) / 100_000.0                       # 1500 rpm, a mark per rev
    >>> v = pickup_voltage(np.array([0.01, 0.05]), time=t, profile=steady(1500.0, duration=1),
    ...                    params=dict(pulses_per_rev=1, missing_teeth=0, shape="square",
    ...                                mark_width_deg=0.5))  # 0.5 deg = 1.4 samples
    >>> int((v > 2.5).sum()), round(float(v.max()), 6)       # 2 or 3 samples a mark
    (5, 5.0)
    """
    from .imperfections import ring

    n, missing = int(params["pulses_per_rev"]), int(params.get("missing_teeth", 0))
    time = np.asarray(time, float)
    edges = np.asarray(edges, float)
    teeth = tooth_numbers(edges, pulses_per_rev=n, missing_teeth=missing)
    levels = np.where(np.isin(teeth, params.get("runt_teeth") or []),
                      float(params.get("runt_level", 0.11)), 1.0)
    if params.get("shape", "sine") == "square":
        if params.get("mark_width_deg"):
            rev_time = 2.0 * np.pi / profile.speed(edges)
            widths = rev_time * float(params["mark_width_deg"]) / 360.0
        else:
            pitch = np.diff(edges)
            local = np.minimum(np.r_[pitch, pitch[-1:]], np.r_[pitch[:1], pitch]) \
                if edges.size > 1 else np.full(edges.size, 1.0)
            widths = 0.5 * local
        volts = pulse_voltage(edges, time, widths=widths, levels=levels, high=5.0, low=0.0)
    else:
        volts = analogue_pickup(edges, time=time, pulses_per_rev=n, missing_teeth=missing,
                                profile=profile)
        if np.any(levels != 1.0):
            k = np.clip(np.searchsorted(edges, time, side="right") - 1, 0, edges.size - 1)
            volts = volts * levels[k]
    if params.get("ringing"):
        fs = 1.0 / (time[1] - time[0])
        volts = ring(volts, fs, damping=float(params["ringing"]),
                     frequency_hz=float(params.get("ringing_hz", fs / 8.0)))
    return volts
