"""The resonance finder: peaks of order tracks identified as SDOF modes."""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass, field

import numpy as np

from crankbench.predict._threads import single_threaded_blas
from crankbench.predict._validate import check_int, check_option, check_positive, check_range
from crankbench.predict.errors import AnalysisError

from .sdof import (RESPONSES, _UNIT_RESPONSE, _crossing, _modal_fit, _parabolic,
                   half_power_damping)
from .sweep import _deinflate, _sweep_effect, _swept_fit

__all__ = ["Resonance", "ResonanceTable", "OrderCurve", "find_resonances"]

log = logging.getLogger("crankbench")

# residual (out-of-band) terms of the modal fit: with at least _RESIDUAL_SIDE half-power
# half-widths of data on both sides of a peak, the fit spans ±_RESIDUAL_REACH half-widths and
# carries a complex constant, linear, residual-mass (1/ω²) and ω² term; a peak near the end of
# the run (one-sided data) keeps ±3 half-widths and constant + linear, which a one-sided
# window can still determine.
_RESIDUAL_TERMS, _RESIDUAL_REACH, _RESIDUAL_SIDE = "clmk", 6.0, 3.0
_EDGE_TERMS, _EDGE_REACH = "cl", 3.0


def _split_sweeps(rpm, hysteresis):
    """Indices splitting ``rpm`` into monotonic sweeps (zig-zag with ``hysteresis`` rpm)."""
    n = len(rpm)
    breaks = [0]
    trend, i_ext = 0, 0
    for i in range(1, n):
        r = rpm[i]
        if trend == 0:
            if r - rpm[0] > hysteresis:
                trend, i_ext = 1, i
            elif rpm[0] - r > hysteresis:
                trend, i_ext = -1, i
        elif trend == 1:
            if r >= rpm[i_ext]:
                i_ext = i
            elif rpm[i_ext] - r > hysteresis:
                breaks.append(i_ext)
                trend, i_ext = -1, i
        else:
            if r <= rpm[i_ext]:
                i_ext = i
            elif r - rpm[i_ext] > hysteresis:
                breaks.append(i_ext)
                trend, i_ext = 1, i
    breaks.append(n)
    return [(breaks[k], breaks[k + 1]) for k in range(len(breaks) - 1)]


def _bin(rpm, values, n_bins):
    """Average ``values`` (real or complex) in ``n_bins`` equal rpm bins; empty bins dropped."""
    edges = np.linspace(rpm.min(), rpm.max(), n_bins + 1)
    idx = np.clip(np.searchsorted(edges, rpm, side="right") - 1, 0, n_bins - 1)
    count = np.bincount(idx, minlength=n_bins)
    keep = count > 0
    centre = np.bincount(idx, weights=rpm, minlength=n_bins)[keep] / count[keep]
    out = []
    for v in values:
        if v is None:
            out.append(None)
        elif np.iscomplexobj(v):
            re = np.bincount(idx, weights=v.real, minlength=n_bins)[keep]
            im = np.bincount(idx, weights=v.imag, minlength=n_bins)[keep]
            out.append((re + 1j * im) / count[keep])
        else:
            out.append(np.bincount(idx, weights=v, minlength=n_bins)[keep] / count[keep])
    return centre, out


def _baseline(x, y, degree, iterations=200):
    """Smooth lower envelope by iterative polynomial peak stripping ('modpoly').

    Lieber, C. A. & Mahadevan-Jansen, A., "Automated method for subtraction of fluorescence
    from biological Raman spectra", Appl. Spectrosc. 57 (2003) 1363–1367.
    """
    from numpy.polynomial import polynomial as P

    t = (x - x.min()) / max(np.ptp(x), 1e-300) * 2.0 - 1.0
    work = y.copy()
    scale = max(np.max(np.abs(y)), 1e-300)
    fit = y
    for _ in range(iterations):
        coef = P.polyfit(t, work, degree)
        fit = P.polyval(t, coef)
        new = np.minimum(work, fit)
        if np.max(np.abs(new - work)) < 1e-9 * scale:
            break
        work = new
    return fit


def _robust_noise(r):
    """Noise standard deviation from the MAD of first differences (robust to smooth peaks)."""
    d = np.diff(r)
    if d.size < 3:
        return 0.0
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))



@dataclass(frozen=True)
class Resonance:
    """One identified resonance (a peak of one order in one sweep).

    Speeds in rpm, frequencies in Hz, amplitudes in the track's units and amplitude convention.

    Attributes
    ----------
    order : float
    speed_rpm : float
        Critical speed: the natural frequency × 60 / order, sweep-corrected where possible.
    frequency_hz : float
        Natural frequency ``speed_rpm × order / 60``.
    damping_ratio : float
        Best estimate: modal fit (de-inflated for the sweep when corrected), else half-power.
    amplitude : float
        Measured peak order amplitude (raw track, parabolic peak).
    amplitude_corrected : float
        ``amplitude`` with the sweep peak loss restored (steady-state equivalent).
    resonant_amplitude : float
        Height of the peak above the smooth baseline (speed-growth part removed).
    baseline_amplitude : float
        Smooth baseline at the peak.
    peak_speed_rpm : float
        Where the measured amplitude peaks (includes the sweep's delay).
    resonance_speed_rpm : float
        Where the identified SDOF's steady-state response peaks: ``speed_rpm·√(1 − 2ζ²)``
        for displacement, ``speed_rpm`` for velocity, ``speed_rpm/√(1 − 2ζ²)`` for
        acceleration — the convention of a "resonance peak" critical speed.
    speed_rpm_half_power, damping_ratio_half_power : float
        Half-power estimates (exact SDOF relations).
    speed_rpm_fit, damping_ratio_fit, fit_r2 : float
        Modal fit of the complex track (SDOF plus residual terms for the out-of-band modes);
        NaN when the fit failed.
    half_power_complete : bool
        Both half-power points observed.
    snr : float
        Resonant amplitude / noise standard deviation: the track's own ``amplitude_noise``
        at the peak when it has one, else the scatter of neighbouring points.
    confidence : float
        0..1: fit quality (R² of the modal fit; 0.25 when no SDOF shape could be fitted) ×
        SNR factor (1 − exp(−SNR/10)) × (1 if both half-power points were seen else 0.5).
    sweep, direction : int, str
        Which monotonic sweep of the record ('up' or 'down').
    sweep_rate_rpm_per_s : float
        Local speed sweep rate at the peak (NaN without a time axis).
    sweep_eta : float
        α/(ζ f_n)²: the dimensionless sweep parameter.
    sweep_peak_loss : float
        Estimated fraction of the steady-state peak lost to the sweep.
    sweep_shift_rpm : float
        Estimated shift of the peak by the sweep, rpm.
    sweep_corrected : bool
    method : str
    merged : int
        Further detections of the same peak (another sweep, another sample) merged into this.
    """

    order: float
    speed_rpm: float
    frequency_hz: float
    damping_ratio: float
    amplitude: float
    amplitude_corrected: float
    resonant_amplitude: float
    baseline_amplitude: float
    peak_speed_rpm: float
    resonance_speed_rpm: float
    speed_rpm_half_power: float
    damping_ratio_half_power: float
    speed_rpm_fit: float
    damping_ratio_fit: float
    fit_r2: float
    half_power_complete: bool
    snr: float
    confidence: float
    sweep: int
    direction: str
    sweep_rate_rpm_per_s: float
    sweep_eta: float
    sweep_peak_loss: float
    sweep_shift_rpm: float
    sweep_corrected: bool
    method: str
    merged: int = 0


@dataclass(frozen=True)
class OrderCurve:
    """One order in one sweep as analysed: binned amplitude and its smooth baseline vs rpm."""

    order: float
    sweep: int
    direction: str
    speed_rpm: np.ndarray
    amplitude: np.ndarray
    baseline: np.ndarray


@dataclass(frozen=True)
class ResonanceTable:
    """Resonances found in an order track, with the curves they were found on.

    Attributes
    ----------
    resonances : tuple of Resonance
        Sorted by order, then speed.
    curves : tuple of OrderCurve
    units : str
        Amplitude units of the track.
    amplitude_convention : str
        'peak' | 'rms' | 'peak-to-peak', from the track.
    settings : dict
        Parameters used (response, thresholds, baseline degree...).
    """

    resonances: tuple
    curves: tuple = ()
    units: str = ""
    amplitude_convention: str = "peak"
    settings: dict = field(default_factory=dict)

    def __len__(self):
        return len(self.resonances)

    def __iter__(self):
        return iter(self.resonances)

    def to_frame(self):
        """One row per resonance (pandas DataFrame); speeds rpm, frequencies Hz."""
        import pandas as pd

        cols = list(Resonance.__dataclass_fields__)
        frame = pd.DataFrame([asdict(r) for r in self.resonances], columns=cols)
        if frame.empty:  # keep the dtypes of a filled table
            types = {k: v.type for k, v in Resonance.__dataclass_fields__.items()}
            frame = frame.astype({k: ("float64" if t in ("float", float) else
                                      "int64" if t in ("int", int) else
                                      "bool" if t in ("bool", bool) else "object")
                                  for k, t in types.items()})
        frame.attrs.update(units=self.units, amplitude_convention=self.amplitude_convention)
        return frame

    def plot(self, ax=None):
        """Order amplitude against rpm with baselines and the resonances marked; returns figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(8, 4.5))
        else:
            fig = ax.figure
        colours = {}
        for c in self.curves:
            line, = ax.plot(c.speed_rpm, c.amplitude, lw=1.0,
                            label=f"order {c.order:g}" if c.order not in colours else None,
                            color=colours.get(c.order))
            colours.setdefault(c.order, line.get_color())
            ax.plot(c.speed_rpm, c.baseline, lw=0.8, ls=":", color=colours[c.order])
        for r in self.resonances:
            ax.plot(r.peak_speed_rpm, r.amplitude, "v", color=colours.get(r.order, "k"), ms=7)
            ax.annotate(f"{r.frequency_hz:.2f} Hz", (r.peak_speed_rpm, r.amplitude),
                        textcoords="offset points", xytext=(0, 6), ha="center", fontsize=7)
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel(f"order amplitude ({self.amplitude_convention}, {self.units})".replace(", )", ")"))
        if self.curves:
            ax.legend(fontsize=7, ncol=2)
        ax.grid(alpha=0.3)
        return fig




def _track_noise(track, order, n):
    """The track's own 1-σ amplitude noise for one order (its ``amplitude_noise``, per order
    or, for a COT track, per block times the order's least-squares noise gain), else None."""
    if "amplitude_noise" not in track:
        return None
    noise = track["amplitude_noise"]
    if "order" in noise.dims:
        out = np.asarray(noise.sel(order=order).values, dtype=float)
    else:
        out = np.asarray(noise.values, dtype=float)
        gains = track.attrs.get("noise_gain")
        if gains is not None and len(gains) == track.sizes.get("order", 0):
            k = int(np.argmin(np.abs(np.asarray(track["order"].values, float) - order)))
            out = out * float(gains[k])
    return out if out.shape[0] == n else None


def _track_arrays(track, order):
    """(rpm, time or None, amplitude, complex or None, noise or None) for one order."""
    sub = track.sel(order=order)
    amp = np.asarray(sub["amplitude"].values, dtype=float)
    dim = sub["amplitude"].dims[0] if sub["amplitude"].ndim == 1 else None
    if dim is None:
        raise AnalysisError(f"track amplitude for order {order:g} must be 1-D along time or "
                            f"rpm, got dims {sub['amplitude'].dims}")
    if "rpm" in sub.coords:
        rpm = np.asarray(sub["rpm"].values, dtype=float)
    elif "speed_rpm" in sub.coords:
        rpm = np.asarray(sub["speed_rpm"].values, dtype=float)
    else:
        raise AnalysisError("track has no 'rpm' coordinate; expected an order track from "
                            "analysis.order_track (coordinate 'rpm' along 'time')")
    time = np.asarray(sub["time"].values, dtype=float) if "time" in sub.coords else None
    comp = None
    if "phase" in sub:
        ph = np.asarray(sub["phase"].values, dtype=float)
        units = str(track["phase"].attrs.get("units", "rad")).lower()
        if units.startswith("deg"):
            ph = np.deg2rad(ph)
        comp = amp * np.exp(1j * ph)
    noise = _track_noise(track, order, amp.shape[0])
    ok = np.isfinite(rpm) & np.isfinite(amp)
    if comp is not None:
        ok &= np.isfinite(comp)
    if time is not None:
        ok &= np.isfinite(time)
    if noise is not None:
        noise = np.where(np.isfinite(noise), noise, 0.0)
    return (rpm[ok], None if time is None else time[ok], amp[ok],
            None if comp is None else comp[ok], None if noise is None else noise[ok])


@single_threaded_blas  # many tiny least-squares fits: BLAS threads only cost (issue 21)
def find_resonances(track, *, orders=None, response=None, min_snr=5.0, min_prominence=0.05,
                    min_amplitude_fraction=1e-3,
                    max_damping=0.2, min_damping=0.004, min_confidence=0.5, baseline_degree=3,
                    max_points=3000, sweep_correction=True, sweep_hysteresis=0.02):
    """Find and identify resonances in an order track.

    Parameters
    ----------
    track : xarray.Dataset
        Order track as returned by :func:`analysis.order_track`: ``amplitude`` (and optionally
        ``phase``, rad) over (``order``, ``time``) with an ``rpm`` coordinate along ``time``.
        A track over (``order``, ``rpm``) is also accepted (no sweep-rate correction then).
    orders : sequence of float, optional
        Orders to search (default: all in the track).
    response : {'displacement', 'velocity', 'acceleration'}, optional
        Measured quantity; default inferred from ``amplitude.attrs['units']`` (rad, m →
        displacement; rad/s, m/s → velocity; m/s² → acceleration).
    min_snr : float
        Minimum resonant amplitude / noise standard deviation (robust MAD of first
        differences).
    min_prominence : float
        Minimum height of the peak above its surroundings as a fraction of the peak value
        (dimensionless): rejects ripples on a large smooth track.
    min_amplitude_fraction : float
        Minimum resonant amplitude as a fraction of the largest amplitude of any analysed
        order: bumps at the floor of weak orders (leakage of strong ones) are not sought.
    max_damping : float
        Peaks wider than this damping ratio are treated as growth with speed, not resonance.
    min_damping : float
        Peaks narrower than this damping ratio are treated as spikes (noise, pulse dropouts):
        engine shaft-line modes have ζ of order 0.01–0.1.
    min_confidence : float
        Resonances below this confidence (0..1) are dropped.
    baseline_degree : int
        Degree of the polynomial baseline (in rpm) that models order amplitude growing with
        speed; it is fitted to the log amplitude as a lower envelope (peak stripping) and
        removed before peaks are sought.
    max_points : int
        Each sweep is averaged into at most this many rpm bins (resolution knob).
    sweep_correction : bool
        Correct critical speed, amplitude and damping for the finite sweep rate (needs a
        ``time`` axis).
    sweep_hysteresis : float
        Fraction of the total speed span that a reversal must exceed to start a new sweep.

    Returns
    -------
    ResonanceTable
        ``.to_frame()`` lists order, critical ``speed_rpm``, natural ``frequency_hz``,
        ``damping_ratio`` (fit and half-power), ``amplitude`` (and sweep-corrected), the
        sweep rate, its estimated peak loss and a confidence per resonance.

    Raises
    ------
    AnalysisError
        Track without an ``order`` dimension, ``amplitude`` variable or rpm coordinate.

    Notes
    -----
    Per order and monotonic sweep: bin in rpm, fit the baseline, find peaks of the residual
    (scipy.signal.find_peaks with SNR and prominence thresholds; a smaller peak within four
    half-power widths of a larger one in the same sweep is a sweep ripple and dropped),
    then estimate half-power and modal-fit parameters. The modal fit accounts for the modes
    outside the peak with residual terms (a complex constant, a term linear in frequency, a
    residual-mass 1/ω² and an ω² term, solved by linear least squares for each trial pole)
    over ±6 half-power widths; a peak with less than 3 half-widths of data on one side (near
    the end of the run) is fitted over ±3 half-widths with constant + linear only. Measured
    on the 6L32 marine scene (damper mode, weak at the free end on the tails of modes 1 and
    3): critical speed −0.32…+0.02 % and amplitude ≤ 4.4 % at 14 and 100 rpm/s, against
    +0.74…+0.79 % with a constant + linear background alone.
    Cost: O(N) per order plus a few ms per resonance for the fit and sweep correction.

    References
    ----------
    Ewins, *Modal Testing*, 2nd ed., §4.3 (SDOF modal analysis: peak amplitude and circle
    fit; residual terms for the out-of-range modes); Lewis (1932), Trans. ASME 54, 253–261
    (passage through resonance at a finite rate);
    internal-combustion engine dynamics (1958), chapter on torsional vibration: critical speed
    n_c = 60 f_n / k and the resonance curve (seeds/001).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> from crankbench.analysis.resonance import sdof_response
    >>> rpm = np.linspace(300, 900, 3001)
    >>> f = 6 * rpm / 60                        # order 6 excitation, Hz
    >>> h = sdof_response(f, natural_frequency=60.0, damping_ratio=0.03)
    >>> track = xr.Dataset({"amplitude": (("order", "time"), np.abs(h)[None] * 1e-3),
    ...                     "phase": (("order", "time"), np.angle(h)[None])},
    ...                    coords={"order": [6.0], "rpm": ("time", rpm)})
    >>> res = find_resonances(track).to_frame()
    >>> print(res[["order", "speed_rpm", "frequency_hz", "damping_ratio"]].round(4).to_string(index=False))
     order  speed_rpm  frequency_hz  damping_ratio
       6.0      600.0          60.0           0.03
    """
    import xarray as xr
    from scipy.signal import find_peaks

    if not isinstance(track, xr.Dataset):
        if isinstance(track, xr.DataArray):
            track = track.to_dataset(name="amplitude")
        else:
            raise AnalysisError(f"track must be an xarray.Dataset order track, got "
                                f"{type(track).__name__}")
    if "amplitude" not in track:
        raise AnalysisError(f"track has no 'amplitude' variable; variables: {list(track.data_vars)}")
    if "order" not in track["amplitude"].dims:
        raise AnalysisError(f"track amplitude has no 'order' dimension; dims: "
                            f"{track['amplitude'].dims}")
    units = str(track["amplitude"].attrs.get("units", track.attrs.get("units", "")))
    convention = str(track["amplitude"].attrs.get("amplitude",
                     track.attrs.get("amplitude", "peak")))
    if response is None:
        response = _UNIT_RESPONSE.get(units.strip(), "displacement")
    check_option(response, "response", RESPONSES)
    p = RESPONSES[response]
    min_snr = check_positive(min_snr, "min_snr", error=AnalysisError)
    min_prominence = check_range(min_prominence, "min_prominence", 0.0, 1.0, error=AnalysisError)
    max_damping = check_range(max_damping, "max_damping", 0.0, 0.5, inclusive=(False, True),
                              error=AnalysisError)
    min_damping = check_range(min_damping, "min_damping", 0.0, max_damping,
                              inclusive=(True, False), error=AnalysisError)
    min_confidence = check_range(min_confidence, "min_confidence", 0.0, 1.0, error=AnalysisError)
    baseline_degree = check_int(baseline_degree, "baseline_degree", minimum=0, error=AnalysisError)
    max_points = check_int(max_points, "max_points", minimum=16, error=AnalysisError)
    sweep_hysteresis = check_range(sweep_hysteresis, "sweep_hysteresis", 0.0, 1.0,
                                   inclusive=(False, False), error=AnalysisError)
    all_orders = [float(o) for o in np.atleast_1d(track["order"].values)]
    if orders is None:
        orders = all_orders
    else:
        orders = [float(o) for o in np.atleast_1d(orders)]
        for o in orders:
            if not np.any(np.isclose(all_orders, o, rtol=0, atol=1e-9)):
                raise AnalysisError(f"order {o:g} is not in the track; available: "
                                    f"{', '.join(f'{v:g}' for v in all_orders)}")

    min_amplitude_fraction = check_range(min_amplitude_fraction, "min_amplitude_fraction", 0.0,
                                         1.0, error=AnalysisError)
    sel = track["amplitude"].sel(order=orders) if len(orders) else track["amplitude"]
    global_max = float(np.nanmax(np.abs(sel.values))) if sel.size else 0.0
    floor_abs = min_amplitude_fraction * global_max
    found, curves = [], []
    for order in orders:
        rpm, time, amp, comp, track_noise = _track_arrays(track, order)
        if rpm.size < 16:
            log.info("order %g: only %d finite points, skipped", order, rpm.size)
            continue
        span = float(np.ptp(rpm))
        if span <= 0:
            continue
        segments = _split_sweeps(rpm, sweep_hysteresis * span)
        for k, (i0, i1) in enumerate(segments):
            seg = slice(i0, i1 + 1 if i1 < rpm.size else i1)
            r_seg = rpm[seg]
            if r_seg.size < 16 or np.ptp(r_seg) < 3 * sweep_hysteresis * span:
                continue
            direction = "up" if r_seg[-1] >= r_seg[0] else "down"
            rate_fn = None
            if time is not None:
                t_seg = time[seg]
                rate_fn = _local_rate(t_seg, r_seg)
            n_bins = int(min(r_seg.size, max_points))
            x, (a, c, sig_track) = _bin(r_seg, [amp[seg], None if comp is None else comp[seg],
                                                None if track_noise is None
                                                else track_noise[seg]], n_bins)
            if x.size < 16:
                continue
            # lower envelope of log amplitude: always positive, and a large peak elsewhere
            # in the sweep cannot drag it below zero
            floor = max(np.max(a), 1e-300) * 1e-12
            base = np.exp(_baseline(x, np.log(np.maximum(a, floor)), baseline_degree))
            curves.append(OrderCurve(order, k, direction, x, a, base))
            resid = a - base
            floor = 1e-9 * max(np.max(np.abs(a)), 1e-300)
            # the noise a peak is judged against: the track's own uncertainty where it has one
            # (a filtered track's noise is correlated over the filter's response, which the
            # differences between neighbouring points do not see), else the differences
            sigma = max(_robust_noise(resid), floor)
            sigma_at = np.full(x.shape[0], sigma)
            if sig_track is not None:
                sigma_at = np.maximum(sigma_at, sig_track)
                sigma = max(sigma, float(np.median(sig_track)))
            peaks, props = find_peaks(resid, prominence=max(min_snr * sigma, floor_abs))
            if peaks.size == 0:
                continue
            order_idx = np.argsort(props["prominences"])[::-1]
            accepted = []  # (x_peak, half-width, prominence)
            for j in order_idx:
                i = int(peaks[j])
                prom = float(props["prominences"][j])
                if prom < min_prominence * a[i]:
                    continue
                if prom < min_snr * sigma_at[i]:
                    continue
                res = _identify(x, a, c, base, resid, i, p, response, order,
                                max(sigma, float(sigma_at[i])), prom,
                                max_damping, accepted, rate_fn, direction, k,
                                sweep_correction, min_damping)
                if res is None or res.confidence < min_confidence:
                    continue
                found.append(res)
    found = _merge_duplicates(found)
    found.sort(key=lambda r: (r.order, r.sweep, r.speed_rpm))
    settings = {"response": response, "min_snr": min_snr, "min_prominence": min_prominence,
                "max_damping": max_damping, "min_damping": min_damping,
                "min_confidence": min_confidence,
                "min_amplitude_fraction": min_amplitude_fraction,
                "baseline_degree": baseline_degree, "max_points": max_points,
                "sweep_correction": bool(sweep_correction),
                "sweep_hysteresis": sweep_hysteresis}
    return ResonanceTable(tuple(found), tuple(curves), units, convention, settings)


def _merge_duplicates(found):
    """One resonance per (order, direction, peak): resonances of the same order and sweep
    direction whose critical speeds lie within the larger half-power half-width (ζ·n) of each
    other — the same peak seen in two sweeps of a partial or interrupted run-up, or from two
    samples — are one; the most confident is kept and ``merged`` counts the others (a run-up
    and a run-down stay separate measurements)."""
    import dataclasses

    out = []
    by_order = {}
    for r in found:
        by_order.setdefault((r.order, r.direction), []).append(r)
    for order, group in by_order.items():
        group = sorted(group, key=lambda r: r.confidence, reverse=True)
        kept = []
        for r in group:
            same = [k for k in kept if abs(k.speed_rpm - r.speed_rpm)
                    <= max(k.damping_ratio * k.speed_rpm, r.damping_ratio * r.speed_rpm)]
            if same:
                i = kept.index(same[0])
                kept[i] = dataclasses.replace(kept[i], merged=kept[i].merged + 1)
            else:
                kept.append(r)
        out.extend(kept)
    return out


def _stepped(t, rpm) -> bool:
    """A dwell/stepped test: the speed holds on plateaus and jumps between them (most
    consecutive points change by less than 2 % of the mean change), so there is no sweep."""
    d = np.abs(np.diff(rpm[np.argsort(t)]))
    if d.size < 8 or d.mean() <= 0:
        return False
    return bool(np.median(d) < 0.02 * d.mean())


def _local_rate(t, rpm):
    """Callable: local d(rpm)/dt (rpm/s) at a given speed, from a straight-line fit nearby
    (0 on a dwell/stepped test: the response at each step is steady, nothing to correct)."""
    order = np.argsort(t)
    t, rpm = t[order], rpm[order]
    stepped = _stepped(t, rpm)

    def rate(speed_rpm, half_window_rpm):
        if stepped:
            return 0.0
        near = np.abs(rpm - speed_rpm) <= max(half_window_rpm, 1e-9)
        if near.sum() < 3:
            i = int(np.argmin(np.abs(rpm - speed_rpm)))
            near = np.zeros_like(rpm, dtype=bool)
            near[max(i - 2, 0):i + 3] = True
        if near.sum() < 2 or np.ptp(t[near]) <= 0:
            return float("nan")
        return float(np.polyfit(t[near], rpm[near], 1)[0])

    return rate


def _identify(x, a, c, base, resid, i, p, response, order, sigma, prom, max_damping, accepted,
              rate_fn, direction, sweep, sweep_correction, min_damping=0.0):
    """Identify the peak at bin ``i``; None if it is not a resonance. Appends to ``accepted``."""
    step = float(np.median(np.diff(x)))
    x_pk, a_pk = _parabolic(x, a, i)
    _, r_pk = _parabolic(x, resid, i)
    level = r_pk / np.sqrt(2.0)
    x1 = _crossing(x, resid, i, level, -1)
    x2 = _crossing(x, resid, i, level, +1)
    complete = bool(np.isfinite(x1) and np.isfinite(x2))
    if not complete:  # mirror the observed side
        if np.isfinite(x1):
            x2 = 2 * x_pk - x1
        elif np.isfinite(x2):
            x1 = 2 * x_pk - x2
        else:
            return None
    if x1 <= 0 or x2 <= x1:
        return None
    half_width = 0.5 * (x2 - x1)
    if 2 * half_width < 2.0 * step:
        return None  # narrower than two bins: a spike, not a resonance
    rate = rate_fn(x_pk, 2 * half_width) if rate_fn is not None else float("nan")
    for xa, hw, pr in accepted:
        reach = 4.0 * max(hw, half_width)
        if np.isfinite(rate) and rate != 0 and (x_pk - xa) * rate > 0:
            # after a fast passage the free vibration beats against the excitation: ripples
            # trail the peak at Δν ≈ √(4πks), k = 1, 2, ... (s = dν/d(ω_n t)); cover k ≤ 10
            s_norm = abs(order * rate / 60.0) / (2 * np.pi * (xa * order / 60.0) ** 2)
            reach += xa * np.sqrt(40.0 * np.pi * s_norm)
        if abs(x_pk - xa) < reach and prom < 0.5 * pr:
            return None  # ripple beside a larger peak
        if abs(x_pk - xa) < max(hw, half_width):
            return None  # the same peak seen from another sample
    try:
        zeta_hp, n_hp = half_power_damping(x1, x2, response=response)
    except AnalysisError:
        return None
    if not np.isfinite(zeta_hp) or zeta_hp > max_damping or zeta_hp < min_damping:
        return None

    # modal fit with residual terms for the out-of-band modes (see _RESIDUAL_TERMS); the
    # identified pole must stay within ±3 half-power widths of the peak
    if min(x_pk - x[0], x[-1] - x_pk) >= _RESIDUAL_SIDE * half_width:
        terms, reach = _RESIDUAL_TERMS, _RESIDUAL_REACH
    else:
        terms, reach = _EDGE_TERMS, _EDGE_REACH
    lo, hi = x_pk - reach * half_width, x_pk + reach * half_width
    lo3, hi3 = x_pk - 3 * half_width, x_pk + 3 * half_width
    win = (x >= lo) & (x <= hi)
    fit = None
    if win.sum() >= 7:
        data = c[win] if c is not None else a[win]
        fit = _modal_fit(x[win], data, n_hp, zeta_hp, p, c is not None, terms)
    n_fit = z_fit = r2 = np.nan
    if fit is not None:
        n_fit, z_fit, _, r2 = fit[:4]
        # a fit that left the window or disagrees with the bandwidth by more than 4x is no
        # SDOF peak (edge transient, two modes, trend)
        if not (lo3 <= n_fit <= hi3) or not (0.25 * zeta_hp <= z_fit <= min(4.0 * zeta_hp,
                                                                          max_damping)):
            n_fit = z_fit = np.nan
            r2 = np.nan
    if np.isfinite(n_fit):
        speed, zeta, method = n_fit, z_fit, "modal fit"
        quality = float(np.clip(r2, 0.0, 1.0))
        # half-power again on the resonant part alone: data minus the fitted complex
        # background (a magnitude baseline cannot remove a background that adds in phase)
        xw, clean = x[win], fit[4]
        j = int(np.argmax(clean))
        _, c_pk = _parabolic(xw, clean, j)
        y1 = _crossing(xw, clean, j, c_pk / np.sqrt(2.0), -1)
        y2 = _crossing(xw, clean, j, c_pk / np.sqrt(2.0), +1)
        if np.isfinite(y1) and np.isfinite(y2) and 0 < y1 < y2:
            zeta_hp, n_hp = half_power_damping(y1, y2, response=response)
    else:
        # no SDOF shape could be fitted: keep only as a low-confidence candidate (baseline
        # bumps beside a large peak and edge transients end here)
        speed, zeta, method = n_hp, zeta_hp, "half-power"
        quality = 0.25
    snr = r_pk / sigma

    # sweep-rate effect: a finite sweep lowers, widens and delays the peak. With a modal fit
    # the sweep is modelled in the fit itself (swept SDOF envelope); otherwise the half-power
    # damping is de-inflated by inverting a swept simulation read the same way.
    eta = loss = shift = np.nan
    corrected = False
    amp_corr = a_pk
    if np.isfinite(rate) and rate != 0:
        alpha = order * rate / 60.0
        eta = abs(alpha) / (zeta * speed * order / 60.0) ** 2
        effect = None
        if eta >= 0.02:
            fn_hz = speed * order / 60.0
            effect = _sweep_effect(zeta, alpha / (2 * np.pi * fn_hz**2), p, fn_hz,
                                   complex_data=c is not None)
        # correct only where the sweep matters (peak loss > 0.2 % or shift > 0.05 %)
        if effect is not None and (effect["loss"] > 2e-3 or
                                   abs(effect["shift"]) > 5e-4 * fn_hz):
            if sweep_correction and method == "modal fit":
                data = c[win] if c is not None else a[win]
                swept = _swept_fit(x[win], data, order, rate, speed, zeta, p, c is not None,
                                   terms, (lo3, hi3))
                if swept is not None and lo3 <= swept[0] <= hi3 and \
                        0.2 * zeta <= swept[1] <= min(2.0 * zeta, max_damping) and \
                        swept[2] >= r2 - 0.05:
                    speed, zeta, steady_peak = swept[0], swept[1], swept[3]
                    quality = float(np.clip(swept[2], 0.0, 1.0))
                    corrected = True
                    method = "swept modal fit"
            elif sweep_correction:
                inverted = _deinflate(zeta, speed * order / 60.0, alpha, p,
                                      "apparent_damping", c is not None)
                if inverted is not None:
                    zeta_true, effect = inverted
                    speed = speed - effect["shift"] * 60.0 / order
                    zeta = zeta_true
                    corrected = True
                    method = "half-power + sweep correction"
            fn_hz = speed * order / 60.0
            effect = _sweep_effect(zeta, alpha / (2 * np.pi * fn_hz**2), p, fn_hz,
                                   complex_data=c is not None)
            eta = abs(alpha) / (zeta * fn_hz) ** 2
            loss = effect["loss"]
            shift = effect["shift"] * 60.0 / order
            if method == "swept modal fit":
                amp_corr = steady_peak
            elif corrected:
                amp_corr = a_pk - r_pk + r_pk / max(1.0 - loss, 1e-6)
        elif effect is not None:
            loss, shift = effect["loss"], effect["shift"] * 60.0 / order
        else:
            loss, shift = 0.0, 0.0
    confidence = quality * (1.0 - np.exp(-snr / 10.0)) * (1.0 if complete else 0.5)
    if not min_damping <= zeta <= max_damping:
        return None  # the identified damping says spike or trend after all
    accepted.append((x_pk, half_width, prom))
    return Resonance(
        order=float(order), speed_rpm=float(speed), frequency_hz=float(speed * order / 60.0),
        damping_ratio=float(zeta), amplitude=float(a_pk), amplitude_corrected=float(amp_corr),
        resonant_amplitude=float(r_pk), baseline_amplitude=float(a_pk - r_pk),
        peak_speed_rpm=float(x_pk),
        resonance_speed_rpm=float(speed * np.sqrt(max(1.0 - 2.0 * zeta**2, 1e-12)) ** (1 - p)),
        speed_rpm_half_power=float(n_hp),
        damping_ratio_half_power=float(zeta_hp), speed_rpm_fit=float(n_fit),
        damping_ratio_fit=float(z_fit), fit_r2=float(r2), half_power_complete=complete,
        snr=float(snr), confidence=float(confidence), sweep=int(sweep), direction=direction,
        sweep_rate_rpm_per_s=float(rate), sweep_eta=float(eta),
        sweep_peak_loss=float(loss), sweep_shift_rpm=float(shift), sweep_corrected=corrected,
        method=method)
