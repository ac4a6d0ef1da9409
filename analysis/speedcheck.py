"""Does the speed reference belong to the signal? The tacho checked against the signal's orders.

A speed reference on the wrong clock (its sample rate 10× off, another run's speed channel, a
time offset) or in the wrong unit gives order amplitudes that look plausible and are wrong
(0.08 instead of 1.86 on one such record). The signal itself says which speed it ran at: the
spectral lines of an engine channel move with the shaft speed, each at a fixed order. So,
frame by frame of a short-time spectrum, the strongest lines are compared with the reference:

* **locked** frames: one of the frame's three strongest lines lies at one of the record's
  orders — the dominant apparent order ``o*`` (the mode of ``f/(rpm/60)`` of each frame's
  strongest line) or any apparent order held in consecutive frames while the reference speed
  changes by 20 % (the strongest line of an I4 run-up moves from order 2 to 4, 3.5, 6) —,
  within 2 % or one frequency bin;
* on a record that sweeps (speed range ≥ 10 % of the median), where the lines move (the
  strongest line's frequency spans ≥ 10 %), fewer than half the frames locked means the reference
  does not follow the signal: :class:`AnalysisError`;
* a locked dominant line at an apparent order below 0.2 or above 200, or at ``o*`` times a
  units slip (2π/60, 60/2π, 60, 1/60) landing on a half order, is a reference off by a constant
  factor: :class:`AnalysisError` naming the factor.

Records without moving lines (steady speed, or a signal of fixed-frequency content only) carry
no evidence either way and pass; the summary says so.

References
----------
K. R. Fyfe and E. D. S. Munck, "Analysis of computed order tracking", MSSP 11(2) (1997) §2
(orders as rays of the rpm–frequency map).
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["check_speed_reference"]

log = logging.getLogger("crankbench")

#: units slips of the speed reference -> the factor that corrects the apparent order (values in
#: rad/s read as rpm make the speed 60/2π too low, every apparent order 60/2π too high)
_SLIPS = {"rad/s read as rpm": 2 * np.pi / 60.0, "rpm read as rad/s": 60.0 / (2 * np.pi),
          "rps read as rpm": 1.0 / 60.0, "rpm read as rps": 60.0}


def check_speed_reference(values, fs: float, speed_rpm, *, label: str = "signal",
                          source: str = "the speed reference") -> dict:
    """Refuse a speed reference that contradicts the signal's own order lines.

    Parameters
    ----------
    values : ndarray
        The analysed channel (any unit).
    fs : float
        Its sample rate, Hz.
    speed_rpm : ndarray
        The reference speed at each sample, rpm.
    label, source : str
        Names for the messages.

    Returns
    -------
    dict
        ``locked_fraction``, ``dominant_order``, ``frames``, ``informative`` (False when the
        record gave no evidence), ``verdict`` (text).

    Raises
    ------
    AnalysisError
        The reference does not follow the signal's moving lines, or is off by a units slip.

    Examples
    --------
    >>> fs = 2000.0
    >>> t = np.arange(int(20 * fs)) / fs
    >>> rpm = 900 + 60 * t                                    # run-up 900 -> 2100 rpm
    >>> phi = 2 * np.pi * np.cumsum(rpm / 60) / fs
    >>> x = np.cos(3 * phi) + 0.3 * np.cos(4.5 * phi)
    >>> check_speed_reference(x, fs, rpm)["locked_fraction"]
    1.0
    >>> wrong = np.interp(t * 10, t, rpm)                      # the speed on a clock 10x off
    >>> check_speed_reference(x, fs, wrong)
    Traceback (most recent call last):
    ...
    crankbench.predict.errors.AnalysisError: the speed reference does not follow signal: ...
    """
    x = np.asarray(values, float)
    speed = np.asarray(getattr(speed_rpm, "values", speed_rpm), float)
    if speed.ndim == 0:
        speed = np.full(x.shape[0], float(speed))
    out = {"locked_fraction": float("nan"), "dominant_order": float("nan"), "frames": 0,
           "informative": False, "verdict": "no evidence (too short)"}
    n = x.shape[0]
    running = speed > 0.05 * max(float(speed.max()), 1e-300)
    if n < 64 or running.sum() < 64 or speed.max() <= 0:
        return out
    med = float(np.median(speed[running]))
    # frames: at least 4 revolutions at the lowest running speed, at most n/8 samples
    low = float(np.percentile(speed[running], 5))
    # (and at least 0.1 s: a reference too fast by a units slip would otherwise give frames
    # a few bins wide, too coarse to tell which slip it is)
    length = int(2 ** np.ceil(np.log2(max(64.0, 4.0 * 60.0 / low * fs, 0.1 * fs))))
    length = min(length, int(2 ** np.floor(np.log2(max(64, n // 8)))))
    if length < 64:
        return out
    from scipy import signal

    hop = length // 2
    starts = np.arange(0, n - length + 1, hop)
    if starts.shape[0] < 4:
        return out
    win = signal.get_window("hann", length)
    frames = x[starts[:, None] + np.arange(length)[None, :]]
    frames = frames - frames.mean(axis=1, keepdims=True)
    power = np.abs(np.fft.rfft(frames * win, axis=1)) ** 2
    freq = np.fft.rfftfreq(length, 1.0 / fs)
    df = fs / length
    frame_rpm = np.array([np.mean(speed[s:s + length]) for s in starts])
    lines, keep = [], []
    for i in range(starts.shape[0]):
        if frame_rpm[i] <= 0.05 * med:
            continue
        f_lo = 0.2 * frame_rpm[i] / 60.0
        band = (freq >= max(f_lo, 2 * df)) & (freq <= 0.45 * fs)
        p = power[i]
        floor = float(np.median(p[band])) if band.any() else 0.0
        peaks, _ = signal.find_peaks(np.where(band, p, 0.0), height=max(30.0 * floor, 1e-300))
        if peaks.size == 0:
            continue
        top = peaks[np.argsort(p[peaks])[::-1][:3]]
        lines.append(_refined(p, top) * df)
        keep.append(i)
    out["frames"] = len(keep)
    if len(keep) < 4:
        out["verdict"] = "no evidence (no clear spectral lines)"
        return out
    frame_rpm = frame_rpm[keep]
    # dominant apparent order: the mode of log(f/n) of each frame's strongest line
    logs = np.log(np.array([ln[0] / (r / 60.0) for ln, r in zip(lines, frame_rpm)]))
    hist, edges = np.histogram(logs, bins=np.arange(logs.min() - 0.03, logs.max() + 0.06, 0.03))
    k = int(np.argmax(hist))
    centre = float(np.median(logs[(logs >= edges[k]) & (logs < edges[k + 1])]))
    o_star = float(np.exp(centre))
    # the record's order set: besides o*, every apparent order (of a frame's three strongest
    # lines) held in consecutive frames while the reference speed changes by 20 % or more —
    # the strongest line may move from order to order over a run-up (an I4: 2, then 4, 3.5,
    # 6), each still at a fixed order of the true speed; on a wrong speed law the apparent
    # orders drift through any one order (and a fixed-frequency line against a reference that
    # stands still proves nothing)
    logs_all = [np.log(ln / (r / 60.0)) for ln, r in zip(lines, frame_rpm)]
    every = np.concatenate(logs_all)
    grid = np.arange(every.min(), every.max() + 0.03, 0.03)
    log_rpm = np.log(frame_rpm)
    centres = []
    for c in grid:
        hit = np.array([np.any(np.abs(lg - c) <= 0.02) for lg in logs_all])
        hit[1:-1] |= hit[:-2] & hit[2:]            # one frame's line off by more: bridged
        run_start, best = None, 0.0
        for i, h in enumerate(np.append(hit, False)):
            if h and run_start is None:
                run_start = i
            elif not h and run_start is not None:
                best = max(best, float(np.ptp(log_rpm[run_start:i])))
                run_start = None
        if best >= np.log(1.2):
            centres.append(float(c))
    centres = np.array(sorted(set(centres) | {centre}))
    locked = np.array([np.any(np.abs(np.log(ln / (r / 60.0))[:, None] - centres[None, :])
                              <= np.maximum(0.02, df / np.maximum(ln, df))[:, None])
                       for ln, r in zip(lines, frame_rpm)])
    frac = float(locked.mean())
    out.update(locked_fraction=frac, dominant_order=o_star)
    sweeps = (np.percentile(speed[running], 95) - np.percentile(speed[running], 5)) >= 0.1 * med
    strongest = np.array([ln[0] for ln in lines])
    moving = np.ptp(np.log(np.maximum(strongest, df))) >= np.log(1.1)
    name = f"{source} does not follow {label}"
    if sweeps and moving:
        out["informative"] = True
        if frac < 0.5:
            raise AnalysisError(
                f"the speed reference does not follow {label}: its spectral lines move with "
                f"another speed law (only {100 * frac:.0f} % of {len(keep)} frames have a line "
                f"at a fixed order of {source}); the speed source is on another clock or from "
                "another run: check its sample rate and time offset, or name the right speed "
                "channel")
    if np.isfinite(o_star) and frac >= 0.5:
        out["informative"] = True
        # relative uncertainty of o*: a twentieth of a bin of the dominant line after the peak
        # interpolation, at least 0.2 % (measured: within 1.4e-4 on clean and noisy run-ups)
        rel = max(0.002, 0.05 * df / float(np.median(strongest)))
        slip = _units_slip(o_star, rel)
        if o_star < 0.2 or o_star > 200.0 or slip is not None:
            what = f" ({slip[0]}: order {slip[1]:g} at the corrected speed)" if slip else ""
            raise AnalysisError(
                f"{name}: the signal's dominant order-locked line sits at order {o_star:.4g} of "
                f"that speed, which no engine order explains{what}; check the speed units "
                "and scale")
    out["verdict"] = (f"consistent: {100 * frac:.0f} % of frames locked to order {o_star:.3g}"
                      if out["informative"] else "no evidence (no moving order lines)")
    log.debug("speed check %s against %s: %s", label, source, out["verdict"])
    return out


def _refined(power: np.ndarray, bins: np.ndarray) -> np.ndarray:
    """Peak positions (in bins) refined by a parabola through the log power of each peak bin
    and its neighbours (Hann window: within a few hundredths of a bin on a clean line)."""
    k = np.clip(bins, 1, power.shape[0] - 2)
    with np.errstate(divide="ignore"):
        a, b, c = (np.log(np.maximum(power[k + d], 1e-300)) for d in (-1, 0, 1))
    den = a - 2 * b + c
    shift = np.where(den < 0, 0.5 * (a - c) / np.where(den < 0, den, -1.0), 0.0)
    return k + np.clip(shift, -0.5, 0.5)


def _units_slip(order: float, rel: float = 0.015):
    """A units slip that maps an implausible apparent order onto a half order, else None.

    ``rel``: relative uncertainty of ``order``; an order within it (or 0.03) of a half order
    is explained as it stands.
    """
    def miss(o, strict=False):
        """How far ``o`` is from a plausible half order, in its tolerance (inf outside
        0.5..40): its own uncertainty, at least 0.03 — and, to claim a slip, at most 0.05 (a
        coarse estimate at a high order would fit some half order by chance)."""
        tol = max(0.03, rel * o)
        if strict:
            tol = min(tol, 0.05)
        if not 0.5 - tol <= o <= 40.0 + tol:
            return np.inf
        return abs(o - round(2 * o) / 2) / tol

    if miss(order) <= 1.0:
        return None
    fits = sorted((miss(order * factor, strict=True), what, order * factor)
                  for what, factor in _SLIPS.items())
    if fits[0][0] <= 1.0:
        return fits[0][1], round(2 * fits[0][2]) / 2
    return None
