"""1st-order vibration phasors of balancing runs from records (input to influence balancing).

Influence-coefficient balancing (:mod:`predict.rotor_balance`) needs, for every run and every
measurement plane, the once-per-revolution vibration as amplitude and phase against a mark on
the rotor. :func:`first_order_phasors` takes them from a Record: the shaft speed comes from
:func:`analysis.speedref.speed_reference`, the 1st order from computed order tracking
(:func:`analysis.orders.order_track`, blocks of ``revolutions`` shaft revolutions), and the
block phasors ``A e^{ip}`` of the steady part of the run are averaged (vector mean).

Phase reference. ``order_track`` gives the phase of ``A cos(φ + p)`` with the shaft angle ``φ``
zero at the record's first sample, which differs from run to run. When the record holds a
once-per-revolution pulse train (a tacho: ``pulses_per_rev = 1``), the phase is moved to the
tacho mark: each block's phase is referred to the tacho edge nearest its centre,
``p' = p + φ(t_edge)``, so ``x = A cos(θ + p')`` with ``θ`` the shaft angle since the mark
passed the pick-up. Without a tacho the reference stays the record start, which is consistent
between runs only when the acquisition was triggered at the same shaft angle; the reference
used is reported in the
``phase_reference`` column and the balance command refuses runs with different references.

Error: the averaged phasor's scatter is reported as ``std`` (the RMS distance of the block
phasors from their mean, units of the channel) and ``phase_std_deg`` (``std/amplitude`` in
degrees); blocks overlap by half, so the standard error of the mean is about
``std·sqrt(2/n_blocks)``. Integrating the angle between tacho edges adds ``Δn/n · 360°``
per revolution for a speed error ``Δn``, at most half a revolution away from an edge.

References
----------
交通大学《内燃机动力学》(1958) 第二篇第五章 §1 (angle marks on vibration records).
ISO 21940-11:2016 (balancing of rotors; initial, trial and check runs).
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict._validate import check_int, check_range, suggest
from crankbench.predict.errors import AnalysisError, RecordError

__all__ = ["first_order_phasors", "tacho_channel", "check_run_speeds", "RUN_SPEED_TOLERANCE"]

log = logging.getLogger("crankbench")


#: largest relative speed difference between balancing runs (the same 2 % as the steady-block
#: criterion of :func:`first_order_phasors`): influence coefficients belong to one speed
RUN_SPEED_TOLERANCE = 0.02


def check_run_speeds(runs, *, speed_tolerance: float = RUN_SPEED_TOLERANCE) -> float | None:
    """Refuse balancing runs taken at different speeds.

    Influence coefficients are the rotor's response per unit unbalance at one speed; near a
    critical speed the response changes fast with speed (for an amplification Q the slope of
    the response is of order Q per unit speed ratio), so a trial run at another speed mixes
    the trial mass's effect with the speed change and the corrections come out wrong without
    any sign of it. Every run with a known speed must lie within ``speed_tolerance`` of the
    first run with a known speed (the initial run in the usual order).

    Parameters
    ----------
    runs : sequence of (name, speed_rpm or None)
        Runs in the order given; a run without a speed is not checked.
    speed_tolerance : float
        Largest relative deviation, default :data:`RUN_SPEED_TOLERANCE` (0.02).

    Returns
    -------
    float or None
        The reference speed, rpm (None if no run has a speed).

    Raises
    ------
    AnalysisError
        Naming every run beyond the tolerance, its speed and deviation.

    Examples
    --------
    >>> check_run_speeds([("initial", 2400.0), ("trial 1", 2410.0), ("trial 2", None)])
    2400.0
    >>> try:
    ...     check_run_speeds([("initial", 2400.0), ("trial 1", 2880.0)])
    ... except AnalysisError as exc:
    ...     print(exc)
    balance runs at different speeds: 'trial 1' at 2880 rpm (+20.0 %) against 'initial' at 2400 rpm, beyond speed_tolerance=0.02 (2 %); influence coefficients hold at one speed: repeat the run at 2400 rpm
    """
    speed_tolerance = check_range(speed_tolerance, "speed_tolerance", 0.0, 1.0,
                                  error=AnalysisError)
    known = [(str(n), float(v)) for n, v in runs if v is not None]
    if not known:
        return None
    for name, v in known:
        if not np.isfinite(v) or v <= 0:
            raise AnalysisError(f"balance run {name!r}: speed {v:g} rpm must be finite and > 0")
    ref_name, ref = known[0]
    off = [(n, v, v / ref - 1.0) for n, v in known[1:] if abs(v / ref - 1.0) > speed_tolerance]
    if off:
        listing = "; ".join(f"{n!r} at {v:.6g} rpm ({100 * d:+.1f} %)" for n, v, d in off)
        raise AnalysisError(f"balance runs at different speeds: {listing} against {ref_name!r} "
                            f"at {ref:.6g} rpm, beyond speed_tolerance={speed_tolerance:g} "
                            f"({100 * speed_tolerance:g} %); influence coefficients hold at "
                            f"one speed: repeat the run at {ref:.6g} rpm")
    return ref


def tacho_channel(record) -> str | None:
    """Name of the record's once-per-revolution pulse train (the phase mark), or None.

    Examples
    --------
    >>> import xarray as xr
    >>> rec = xr.Dataset({"key": ("pulse", [0.0, 0.1], {"quantity": "pulse_times",
    ...                                                 "pulses_per_rev": 1})})
    >>> tacho_channel(rec)
    'key'
    """
    for name in map(str, record.data_vars):
        var = record[name]
        pulses = (var.attrs.get("quantity") == "pulse_times"
                  or str(var.dims[0]).startswith("pulse"))
        if pulses and int(var.attrs.get("pulses_per_rev", 0)) == 1 and not int(
                var.attrs.get("missing_teeth", 0)):
            return name
    return None


def _steady_mask(rpm: np.ndarray, steady_fraction: float, speed_tolerance: float) -> np.ndarray:
    n = rpm.size
    drop = int(np.floor(n * (1.0 - steady_fraction) / 2.0))
    keep = np.zeros(n, bool)
    keep[drop:n - drop] = True
    mid = np.median(rpm[keep])
    return keep & (np.abs(rpm - mid) <= speed_tolerance * mid)


def first_order_phasors(record, channels, *, speed_channel: str | None = None,
                        steady_fraction: float = 0.8, speed_tolerance: float = 0.02,
                        revolutions: int = 16):
    """Averaged 1st-order amplitude and phase of measurement channels over a steady run.

    Parameters
    ----------
    record : xarray.Dataset
        A Record (see docs/DESIGN.md) with the vibration channels and a speed reference (a
        ``rotational_speed`` channel or a pulse train; a 1/rev tacho also sets the phase mark).
    channels : sequence of str
        Measurement-plane channels, in plane order.
    speed_channel : str, optional
        Speed source (default: found by :func:`analysis.speedref.find_speed_channel`).
    steady_fraction : float
        Central fraction of the run's order-track blocks used (0–1]; the run-in and run-out
        ends are dropped.
    speed_tolerance : float
        Of those, blocks whose speed is within this fraction of the median speed are averaged.
    revolutions : int
        Order-tracking block length, revolutions (fidelity knob: longer blocks reject more
        broadband noise, error ∝ 1/sqrt(revolutions)).

    Returns
    -------
    pandas.DataFrame
        One row per channel: ``channel``, ``amplitude`` (peak, SI units of the channel),
        ``phase_deg`` (of ``A cos(θ + phase)``), ``std`` (scatter of the block phasors, units
        of the channel), ``phase_std_deg``, ``rpm`` (mean speed of the averaged blocks),
        ``n_blocks``, ``units`` and ``phase_reference`` ("1/rev tacho '<name>'" or 'record start').

    References
    ----------
    Fyfe & Munck, "Analysis of computed order tracking", MSSP 11(2) (1997) (order tracking);
    ISO 21940-11:2016 (trial-weight runs).

    Examples
    --------
    >>> from crankbench.measure.record import make_record
    >>> fs, f = 1000.0, 20.0                     # 1200 rpm
    >>> t = np.arange(int(8 * fs)) / fs
    >>> rec = make_record({
    ...     "brg": dict(data=2e-5 * np.cos(2 * np.pi * f * t + 0.5), sample_rate=fs, units="m"),
    ...     "key": dict(data=(np.arange(160) + 0.25) / f, quantity="pulse_times", units="s",
    ...                 pulses_per_rev=1)})
    >>> df = first_order_phasors(rec, ["brg"])
    >>> print(f"{df.amplitude[0] * 1e6:.3f} µm, {df.phase_deg[0]:.2f}°, {df.rpm[0]:.1f} rpm")
    20.000 µm, 118.65°, 1200.0 rpm
    """
    import pandas as pd

    from .orders import order_track
    from .resample import shaft_angle
    from .speedref import _times, speed_reference

    steady_fraction = check_range(steady_fraction, "steady_fraction", 0.0, 1.0,
                                  error=AnalysisError)
    if steady_fraction <= 0:
        raise AnalysisError("steady_fraction must be > 0 (fraction of the run averaged)")
    speed_tolerance = check_range(speed_tolerance, "speed_tolerance", 0.0, 1.0,
                                  error=AnalysisError)
    revolutions = check_int(revolutions, "revolutions", minimum=1, error=AnalysisError)
    if isinstance(channels, str):
        channels = [channels]
    channels = list(channels)
    if not channels:
        raise AnalysisError("channels must name at least one measurement-plane channel")
    names = list(map(str, record.data_vars))
    source = record.attrs.get("source", "record")
    for ch in channels:
        if ch not in names:
            raise RecordError(f"{source}: no channel {ch!r}{suggest(ch, names)}; channels: "
                              f"{', '.join(names)}")
    mark = tacho_channel(record)
    rows = []
    speeds = {}  # one speed reference per clock
    for ch in channels:
        clock = record[ch].dims
        if clock not in speeds:
            speeds[clock] = speed_reference(record, ch, speed_channel=speed_channel)
        rpm = speeds[clock]
        # phases from the integrated speed, re-referred to the tacho mark below
        rpm = rpm.drop_vars("shaft_angle", errors="ignore")
        track = order_track(record[ch], speed_rpm=rpm, orders=[1], revolutions=revolutions)
        amp = track.amplitude.values[0]
        phase = track.phase.values[0]
        t_blk = track.time.values
        r_blk = track.rpm.values
        if mark is not None:
            t_ch = _times(record, ch)
            fs = (t_ch.size - 1) / (t_ch[-1] - t_ch[0])
            phi = shaft_angle(rpm, fs)
            edges = np.asarray(record[mark].values, float)
            edges = edges[(edges >= t_ch[0]) & (edges <= t_ch[-1])]
            if edges.size == 0:
                raise RecordError(f"{source}: tacho {mark!r} has no edge within channel "
                                  f"{ch!r}'s time span")
            near = edges[np.clip(np.searchsorted(edges, t_blk), 0, edges.size - 1)]
            prev = edges[np.clip(np.searchsorted(edges, t_blk) - 1, 0, edges.size - 1)]
            near = np.where(np.abs(prev - t_blk) < np.abs(near - t_blk), prev, near)
            phase = phase + np.interp(near, t_ch, phi)
            reference = f"1/rev tacho {mark!r}"
        else:
            reference = "record start"
        good = _steady_mask(r_blk, steady_fraction, speed_tolerance) & np.isfinite(amp)
        if not good.any():
            raise AnalysisError(f"{source}: channel {ch!r}: no steady order-track block (speed "
                                f"within {100 * speed_tolerance:g} % of the median); record "
                                f"holds {t_blk.size} blocks of {revolutions} revolutions")
        z = amp[good] * np.exp(1j * phase[good])
        mean = z.mean()
        if good.sum() > 1:
            std = float(np.sqrt(np.mean(np.abs(z - mean) ** 2)))
        else:  # one block: the broadband-noise error estimate of order_track
            std = float(track.amplitude_noise.values[good][0])
        rows.append(dict(channel=ch, amplitude=float(abs(mean)),
                         phase_deg=float(np.degrees(np.angle(mean))), std=std,
                         phase_std_deg=float(np.degrees(std / abs(mean))) if abs(mean) > 0
                         else 180.0,
                         rpm=float(r_blk[good].mean()), n_blocks=int(good.sum()),
                         units=str(record[ch].attrs.get("units", "")),
                         phase_reference=reference))
    return pd.DataFrame(rows)
