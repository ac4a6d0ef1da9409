"""What a Vold–Kalman envelope loses to its own filter, and to the decimation before it.

Two corrections to the plain solve of :mod:`analysis.vkf`:

* **Decimation gain.** The solve runs on a low-passed, decimated record; the FIR cascade's pass
  band is flat to 1e-5, not exactly 1, so every envelope read ``|H_dec(f)|`` times its value
  (3–9e-6 measured on steady tones). The cascade is known exactly: :func:`cascade_gain` gives
  its zero-phase gain at the order's instantaneous frequency and the envelope is divided by it
  (a steady tone then reads within 1e-9).
* **Smearing by the envelope filter, estimated by filtering again.** For one order the VKF acts
  on the demodulated signal as the smoother ``S = (I + 2 Dᵀ R D)⁻¹`` (``D`` the ``p``-th
  difference, ``R`` the per-sample weight ``r² = vkf_weight(B)²``; the response
  ``1/(1 + 2 r² (2 sin πν/fs)^{2p})`` of :func:`analysis.vkf.vkf_weight`). The estimate is
  ``Â = S A`` (plus noise), its bias ``(S − I) A``. Applied to ``Â`` once more,
  ``S Â − Â = (S − I) S A ≈ (S − I) A``; where the filter takes the fraction ``1 − s`` of a
  feature, the second pass sees ``s`` of it, so the bias is read as
  ``|S Â − Â| · |Â| / |S Â|`` (ratio held within [1, 3]). Unlike a model of the envelope's
  shape (a Lorentzian peak, :func:`analysis.vkf.smearing_constant`) this holds on flanks, at
  a bandwidth that changes along the record and near the record's ends. The difference is
  solved directly, ``(I + 2DᵀRD) δ = −2 DᵀR (D Â)``, so a narrow band (``r²`` up to ~1e12)
  costs no accuracy in ``δ``. The bias passes through zero where it changes sign while the
  error does not (the estimate is local, the error is the filter's response over about
  ``1/B``): the stated value is the largest within ``±1/(2B)`` of each sample.

Checked in ``tests/analysis/test_vkf_smear.py`` against the exact (noise-free) envelope of a
resonance crossing integrated by ``solve_ivp`` and against closed forms.
"""

from __future__ import annotations

import functools
import math

import numpy as np

__all__ = ["NOISE_SHARE", "cascade_gain", "decimation_gain", "refilter_bias"]

#: frequencies per cascade at which the gain is tabulated (then interpolated linearly): the
#: ripple of a stage of L taps at input rate f_in repeats every ~f_in/L Hz, ≫ the table's step
_GAIN_GRID = 513


def _stage_gains(stages, fs: float, freq: np.ndarray) -> np.ndarray:
    gain = np.ones_like(freq)
    rate = float(fs)
    for qs, h in stages:
        taps = np.asarray(h, dtype=float)
        half = taps.shape[0] // 2
        lags = np.arange(1, half + 1)
        # symmetric odd-length taps: the zero-phase response is a cosine series over one half
        gain = gain * (taps[half] + 2.0 * (np.cos(2.0 * np.pi * np.multiply.outer(freq, lags)
                                                  / rate) @ taps[half + 1:]))
        rate /= qs
    return gain


def cascade_gain(stages, fs: float, freq_hz) -> np.ndarray:
    """Zero-phase gain of an FIR decimation cascade at the frequencies ``freq_hz``.

    Parameters
    ----------
    stages : sequence of (int, ndarray)
        ``(q_s, h_s)`` per stage (symmetric odd-length taps, applied at the rate left by the
        stages before it), as :func:`analysis.vkf_decimate._decimator` returns.
    fs : float
        Input sample rate, Hz.
    freq_hz : array_like
        Frequencies, Hz (any shape).

    Returns
    -------
    ndarray
        ``∏_s H_s(f)`` (dimensionless), the shape of ``freq_hz``.

    Examples
    --------
    >>> h = np.array([0.25, 0.5, 0.25])                # (1 + cos 2πf/fs)/2
    >>> np.round(cascade_gain(((2, h),), 1000.0, [0.0, 250.0]), 12).tolist()
    [1.0, 0.5]
    """
    return _stage_gains(stages, fs, np.asarray(freq_hz, dtype=float))


@functools.lru_cache(maxsize=64)
def _decimation_table(fs: float, f_max: float, q: int):
    from .vkf_decimate import _decimator

    grid = np.linspace(0.0, f_max, _GAIN_GRID)
    return grid, _stage_gains(_decimator(fs, f_max, q), fs, grid)


def decimation_gain(fs: float, f_max: float, q: int, freq_hz) -> np.ndarray:
    """Gain of the Vold–Kalman decimation cascade (:func:`analysis.vkf_decimate._decimator` of
    ``fs``, ``f_max``, ``q``) at ``freq_hz`` (within ``[0, f_max]``), from a table of 513
    frequencies interpolated linearly (cached per cascade; within 1e-10 of
    :func:`cascade_gain`, ``tests/analysis/test_vkf_smear.py``)."""
    grid, gain = _decimation_table(float(fs), float(f_max), int(q))
    return np.interp(np.abs(freq_hz), grid, gain)


# ------------------------------------------------------------------------------- smearing


def _smoother_difference_numpy(env, r2, p):
    """``δ = S Â − Â`` per order (``r2``: (N − p, K) weight of each difference row)."""
    from scipy.linalg import solveh_banded

    n, k = env.shape
    coef = np.array([-1.0, 1.0]) if p == 1 else np.array([1.0, -2.0, 1.0])
    out = np.zeros_like(env)
    for j in range(k):
        w = 2.0 * r2[:, j]
        a = env[:, j]
        d = np.zeros(n - p, dtype=complex)
        for t in range(p + 1):
            d += coef[t] * a[t:n - p + t]
        rhs = np.zeros(n, dtype=complex)
        band = np.zeros((p + 1, n))                    # upper form: band[p - o, i + o] = M[i, i+o]
        band[p] = 1.0
        for t in range(p + 1):
            rhs[t:n - p + t] -= coef[t] * w * d
            for s in range(t, p + 1):
                band[p - (s - t), t + (s - t):n - p + t + (s - t)] += coef[t] * coef[s] * w
        out[:, j] = solveh_banded(band, rhs)
    return out


@functools.lru_cache(maxsize=1)
def _numba():
    """The compiled kernels, or None (numba missing, or ``CRANKBENCH_NO_NUMBA`` set)."""
    from ._vkf_kernels import njit_or_none

    njit = njit_or_none()
    if njit is None:
        return None

    @njit(cache=True)
    def difference(env, r2, p):   # pragma: no cover - compiled
        # banded LDLᵀ of M = I + 2 DᵀRD (half-bandwidth p ≤ 2), one order at a time
        n, k = env.shape
        out = np.zeros_like(env)
        coef = np.zeros(3)
        if p == 1:
            coef[0], coef[1] = -1.0, 1.0
        else:
            coef[0], coef[1], coef[2] = 1.0, -2.0, 1.0
        m = np.zeros((n, 3))                      # m[i, o] = M[i, i + o]
        rhs = np.zeros(n, dtype=np.complex128)
        for j in range(k):
            m[:, :] = 0.0
            m[:, 0] = 1.0
            rhs[:] = 0.0
            for i in range(n - p):
                w = 2.0 * r2[i, j]
                d = 0.0 + 0.0j
                for t in range(p + 1):
                    d += coef[t] * env[i + t, j]
                for t in range(p + 1):
                    rhs[i + t] -= coef[t] * w * d
                    for s in range(t, p + 1):
                        m[i + t, s - t] += coef[t] * coef[s] * w
            # LDLᵀ in place: m[i, 0] = D_i, m[i, o] = L[i + o, i]
            for i in range(n):
                for o in range(1, p + 1):
                    if i - o >= 0:
                        lo = m[i - o, o]
                        m[i, 0] -= lo * lo * m[i - o, 0]
                # off-diagonals of column i: M[i + o, i] minus the earlier columns' share
                for o in range(1, p + 1):
                    if i + o < n:
                        v = m[i, o]
                        for t in range(1, p + 1 - o):
                            if i - t >= 0:
                                v -= m[i - t, t] * m[i - t, t + o] * m[i - t, 0]
                        m[i, o] = v / m[i, 0]
            # forward: L y = rhs; diagonal; back: Lᵀ x = y
            for i in range(n):
                v = rhs[i]
                for o in range(1, p + 1):
                    if i - o >= 0:
                        v -= m[i - o, o] * rhs[i - o]
                rhs[i] = v
            for i in range(n):
                rhs[i] = rhs[i] / m[i, 0]
            for i in range(n - 1, -1, -1):
                v = rhs[i]
                for o in range(1, p + 1):
                    if i + o < n:
                        v -= m[i, o] * rhs[i + o]
                rhs[i] = v
            for i in range(n):
                out[i, j] = rhs[i]
        return out

    @njit(cache=True)
    def local_max(values, half):   # pragma: no cover - compiled
        # max of values[i - half[i] : i + half[i] + 1] per sample, by a sparse table built level
        # by level (memory O(N)): a window of 2h + 1 is covered by two blocks of 2^L ≤ 2h + 1
        n = values.shape[0]
        out = np.empty(n)
        level = np.empty(n)
        level[:] = values
        need = np.empty(n, np.int64)
        lo_at = np.empty(n, np.int64)
        hi_at = np.empty(n, np.int64)
        top = 0
        for i in range(n):
            lo = i - half[i]
            hi = i + half[i]
            if lo < 0:
                lo = 0
            if hi > n - 1:
                hi = n - 1
            lo_at[i] = lo
            hi_at[i] = hi
            w = hi - lo + 1
            lv = 0
            while (2 << lv) <= w:
                lv += 1
            need[i] = lv
            if lv > top:
                top = lv
        size = 1
        for lv in range(top + 1):
            if lv > 0:
                for i in range(n - size + 1):
                    b = level[i + size // 2]
                    if b > level[i]:
                        level[i] = b
            for i in range(n):
                if need[i] == lv:
                    a = level[lo_at[i]]
                    b = level[hi_at[i] - size + 1]
                    out[i] = a if a > b else b
            size *= 2
        return out

    return {"difference": difference, "local_max": local_max}


def _local_max_numpy(values, half):
    n = values.shape[0]
    out = np.empty(n)
    for i in range(n):
        out[i] = values[max(0, i - half[i]):i + half[i] + 1].max()
    return out


#: ``∫|H(1 − H)|² / ∫|H|²`` of the envelope response ``H = 1/(1 + (√2 − 1)(2ν/B)^{2p})``:
#: the share of the envelope's noise power that a second pass moves (1/8 for p = 1, 5/96 for
#: p = 2; ``tests/analysis/test_vkf_smear.py`` integrates it)
NOISE_SHARE = {1: 1.0 / 8.0, 2: 5.0 / 96.0}

#: samples per response time 1/B of the widest band at which the second pass is computed
_POINTS_PER_RESPONSE = 20


def refilter_bias(env, bw_d, fs_d: float, p: int, noise=None) -> np.ndarray:
    """Smearing bias of Vold–Kalman envelopes, from filtering the estimate once more.

    Parameters
    ----------
    env : ndarray, complex, shape (N, K)
        Solved envelopes (signal units) at the solve rate.
    bw_d : ndarray, shape (N, K)
        Full −3 dB bandwidth of each order per sample, Hz.
    fs_d : float
        Solve rate, Hz.
    p : {1, 2}
        Filter order.
    noise : ndarray, shape (N, K), optional
        1-σ amplitude noise of each envelope (signal units): the noise's own share of
        ``|S Â − Â|²``, ``2 σ² NOISE_SHARE[p]`` (complex, two quadratures), is removed 4×
        over (``|δ_noise|²`` exceeds that in 1.8 % of samples) before the local maximum, so a
        steady noisy order is not stated as smeared.

    Returns
    -------
    ndarray, shape (N, K)
        Estimated amplitude bias (signal units, ≥ 0): ``|S Â − Â| · |Â|/|S Â|`` (ratio within
        [1, 3]), the largest within ``±1/(2B)`` of each sample (module docstring).

    Examples
    --------
    A 1st-order filter leaves a constant and a ramp alone and lifts a parabola ``c t²`` by
    ``2 c (√2 − 1)/(π B)²`` (its response ``1 − (√2 − 1)(2ν/B)²`` near 0):

    >>> n, fs, c, bw = 6000, 1000.0, 0.5, 2.0
    >>> t = np.arange(n) / fs
    >>> env = np.stack([np.full(n, 2.0), 1.0 + 0.5 * t, 1.0 + c * t ** 2], 1) + 0j
    >>> b = refilter_bias(env, np.full((n, 3), bw), fs, 1)
    >>> bool(b[n // 2, :2].max() < 1e-9)
    True
    >>> round(float(b[n // 2, 2] / (2 * c * (2 ** 0.5 - 1) / (np.pi * bw) ** 2)), 2)
    1.0
    """
    from .vkf import vkf_weight

    env = np.ascontiguousarray(env, dtype=complex)
    bw_d = np.ascontiguousarray(np.broadcast_to(bw_d, env.shape), dtype=float)
    n, k = env.shape
    noise = None if noise is None else np.broadcast_to(np.asarray(noise, float), env.shape)
    # the envelopes are band-limited to about B: computed on every `step`-th sample (at least
    # _POINTS_PER_RESPONSE per 1/B of the widest band), then interpolated back
    step = max(1, int(fs_d / (_POINTS_PER_RESPONSE * float(bw_d.max()))))
    if step > 1 and n > 4 * step:
        at = np.arange(0, n, step)
        coarse = refilter_bias(env[at], bw_d[at], fs_d / step, p,
                               None if noise is None else noise[at])
        grid = np.arange(n)
        out = np.empty((n, k))              # column by column (np.stack on axis 1: a slow copy)
        for j in range(k):
            out[:, j] = np.interp(grid, at, coarse[:, j])
        return out
    if n <= p + 1:
        return np.zeros((n, k))
    # weight of the difference row starting at sample i sits at its centre i + p/2
    centre = np.minimum(np.arange(n - p) + (p + 1) // 2, n - 1)
    r2 = np.ascontiguousarray(vkf_weight(bw_d[centre], fs_d, p) ** 2)
    kernels = _numba()
    delta = (kernels["difference"](env, r2, int(p)) if kernels is not None
             else _smoother_difference_numpy(env, r2, p))
    amp = np.abs(env)
    again = np.abs(env + delta)
    ratio = np.clip(amp / np.maximum(again, np.finfo(float).tiny), 1.0, 3.0)
    bias = np.abs(delta) * ratio
    if noise is not None:
        floor2 = 8.0 * NOISE_SHARE[int(p)] * noise ** 2
        bias = np.sqrt(np.maximum(bias * bias - floor2, 0.0))
    half = np.ceil(fs_d / (2.0 * np.maximum(bw_d, 1e-300))).astype(np.int64)
    out = np.empty((n, k))
    for j in range(k):
        col, hw = np.ascontiguousarray(bias[:, j]), np.ascontiguousarray(half[:, j])
        out[:, j] = (kernels["local_max"](col, hw) if kernels is not None
                     else _local_max_numpy(col, hw))
    return out
