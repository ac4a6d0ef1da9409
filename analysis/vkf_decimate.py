"""The Vold–Kalman filter's decimation: the zero-phase FIR cascade that takes a record to its
solve rate, and the choice of that rate (:func:`_decimation_factor`: between 2.5 and 4 times the
highest order frequency, whichever costs least). Moved out of :mod:`analysis.vkf` (one concept
per module); :mod:`analysis.vkf` re-exports the names it had."""

from __future__ import annotations

import functools
import math

import numpy as np

from . import _vkf_kernels


#: Kaiser design of each decimation stage (dB): ripple ≈ 2.5e-6 in its pass and stop bands by
#: Kaiser's formula, raised where the cascade's computed pass band is not flat to 1e-5 (short
#: stages miss the formula)
_DECIMATION_DB = 112.0

#: lowest solve rate, in units of the highest order frequency ``f_max``: the decimation's last
#: stage then passes ``[0, f_max]`` and stops from ``fs_d/2 = 1.25 f_max`` (the solve itself
#: needs only the band up to ``f_max``; its noise estimate reads no bin above it)
_MIN_SOLVE_RATE = 2.5

#: the solve's work per decimated sample in decimation multiply-adds, per (column)²
#: (2·orders + 1 columns): measured with 3 orders at 20 kHz (a 10 s run-up: 0.25 µs per
#: decimated sample against 0.12 ns per FIR multiply-add), the weight :func:`_decimation_factor`
#: gives the solve against the FIR cascade
_SOLVE_MACS = 40.0

def _kaiser_lowpass(f_pass: float, f_stop: float, fs: float, db: float) -> np.ndarray:
    """Symmetric odd-length Kaiser-windowed ideal low-pass (cut-off midway between ``f_pass``
    and ``f_stop``; β and length from Kaiser's formulas for ``db``), unit DC gain."""
    beta = 0.1102 * (db - 8.7)
    half = int(math.ceil(beta / (np.pi * (f_stop - f_pass)) * fs))
    f_cut = 0.5 * (f_pass + f_stop)
    n = np.arange(-half, half + 1)
    h = np.sinc(2.0 * f_cut / fs * n) * np.kaiser(2 * half + 1, beta)
    return h / h.sum()


@functools.lru_cache(maxsize=64)
def _decimator(fs: float, f_max: float, q: int):
    """Stages ``((q_s, h_s), …)`` of an FIR cascade decimating by ``q`` that keeps
    ``[0, f_max]`` flat (|H − 1| ≤ 1e-5, checked on the designed taps) and attenuates by
    ≥ 100 dB all that would alias into the output band ``[0, fs/(2q)]``: stage ``s`` (output
    rate ``f_s``) stops from ``f_s − fs/(2q)`` (what lies between its pass and stop edges
    folds above ``fs/(2q)`` and is removed by the next stage). Of ``q`` itself and its
    two-factor splits, the one with the fewest multiply-adds per input sample."""
    fs_out = fs / q
    probe = np.linspace(0.0, f_max, 1025)
    best = None
    for factors in [(q,)] + [(a, q // a) for a in range(2, q) if q % a == 0]:
        db = _DECIMATION_DB
        while True:
            rate, cost, stages, gain = fs, 0.0, [], np.ones_like(probe)
            for qs in factors:
                rate /= qs
                h = _kaiser_lowpass(f_max, rate - 0.5 * fs_out, rate * qs, db)
                n = np.arange(h.shape[0]) - h.shape[0] // 2
                gain *= np.cos(2.0 * np.pi * np.outer(probe, n) / (rate * qs)) @ h
                cost += h.shape[0] * rate / fs           # multiply-adds per input sample
                stages.append((qs, h))
            if np.abs(gain - 1.0).max() <= 1e-5 or db > _DECIMATION_DB + 20:
                break
            db += 6.0
        if best is None or cost < best[0]:
            best = (cost, tuple(stages))
    return best[1]


def _fir_macs(fs: float, f_max: float, q: int) -> tuple[float, float]:
    """Multiply-adds per input sample of the cheapest cascade :func:`_decimator` would consider
    for ``q`` (``q`` or a two-factor split), from Kaiser's length formula at
    ``_DECIMATION_DB`` (no design: an estimate to choose ``q`` by), and its half-length in
    seconds (what it leaves incomplete at each end of the record)."""
    beta = 0.1102 * (_DECIMATION_DB - 8.7)
    fs_out = fs / q
    splits = [(q,)]
    a = 2
    while a * a <= q:
        if q % a == 0:
            splits += [(a, q // a), (q // a, a)]
        a += 1
    best = (math.inf, 0.0)
    for factors in splits:
        rate, cost, reach = fs, 0.0, 0.0
        for qs in factors:
            rate /= qs
            half = beta / (math.pi * (rate - 0.5 * fs_out - f_max))     # s
            cost += (2 * math.ceil(half * rate * qs) + 1) * rate / fs
            reach += half
        best = min(best, (cost, reach))
    return best


@functools.lru_cache(maxsize=256)
def _decimation_factor(fs: float, f_max: float, columns: int, duration: float) -> int:
    """The decimation ``q`` for a solve of ``columns`` unknowns per sample of a record of
    ``duration`` seconds: from ``floor(fs/(4 f_max))`` (a solve rate of 4 f_max) to
    ``floor(fs/(2.5 f_max))``, the one with the least work per input sample -- the FIR
    cascade's (:func:`_fir_macs`) plus the solve's, ``_SOLVE_MACS·columns²/q`` -- among those
    whose cascade leaves no more than 0.5 % of the record (or what 4 f_max leaves, if more)
    incomplete at each end: a lower solve rate asks for a sharper, longer last stage. A prime
    ``q`` asks for one long single-stage filter and loses to its neighbours; beyond 40
    candidates an evenly spread 40 are weighed.

    On the bench's 10 s run-up (3 orders, 20 kHz, f_max 225.5 Hz) ``q`` = 33 instead of 22: the
    solve at 606 instead of 909 Hz, 50 ms instead of 19 ms left incomplete at either end
    (``tests/analysis/test_vkf_decimation.py``; the time saved: bench suite ``orders``, row
    ``order_track vkf speed``). A 0.5 s sweep keeps
    the 4 f_max rate."""
    q_lo = int(max(1, math.floor(fs / (4.0 * f_max))))
    q_hi = int(max(q_lo, math.floor(fs / (_MIN_SOLVE_RATE * f_max))))
    if q_hi == 1:
        return 1
    span = q_hi - q_lo + 1
    cands = (range(q_lo, q_hi + 1) if span <= 40 else
             sorted({int(round(v)) for v in np.linspace(q_lo, q_hi, 40)}))
    limit = max(0.005 * duration, _fir_macs(fs, f_max, q_lo)[1] if q_lo > 1 else 0.0)
    solve = _SOLVE_MACS * columns * columns
    best, q_best = math.inf, q_lo
    for q in cands:
        macs, reach = _fir_macs(fs, f_max, q) if q > 1 else (0.0, 0.0)
        if q != q_lo and reach > limit:
            continue
        if macs + solve / q < best:
            best, q_best = macs + solve / q, q
    return q_best


def _decimate(values: np.ndarray, fs: float, f_max: float, columns: int = 3):
    """Low-pass and decimate by ``q`` (:func:`_decimation_factor`: a solve rate between 2.5 and
    4 times ``f_max``, whichever costs least with ``columns`` unknowns per solved sample and
    leaves at most 0.5 % of the record incomplete at either end) with
    the FIR cascade of :func:`_decimator` (zero phase: each output is centred on an input
    sample; pass band flat to 1e-5, aliases ≥ 100 dB down; polyphase, so the work is the taps
    per *output* sample).

    Returns (decimated values, input index of each output sample, new rate); the record ends
    that the filters do not cover fully are dropped."""
    q = _decimation_factor(float(fs), float(f_max), int(columns), values.shape[0] / float(fs))
    if q == 1:
        return values, np.arange(values.shape[0]), fs
    # records shorter than a one-stage filter are solved at their own rate (checked before any
    # design: an extremely low speed asks for a huge q)
    from .resample import _aa_half_length

    half = int(math.ceil(_aa_half_length(f_max, 0.5 * fs / q) * fs)) + 1
    if values.shape[0] <= 2 * half + 4 * q:
        return values, np.arange(values.shape[0]), fs
    stages = _decimator(float(fs), float(f_max), q)
    y, offset, step = values, 0, 1           # y[l] is centred on input offset + step·l
    for qs, h in stages:
        half = h.shape[0] // 2
        first = -(-half // qs)                          # first complete output
        last = (y.shape[0] - 1 - half) // qs            # last complete output
        y = _vkf_kernels.fir_decimate(y, h, qs, first, last - first + 1)
        offset += step * qs * first
        step *= qs
    return y, offset + step * np.arange(y.shape[0]), fs / q
