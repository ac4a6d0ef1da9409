"""Vold–Kalman order tracking: the envelopes of several orders solved jointly.

Model (second-generation VKF, real form): the signal is a sum of orders with slowly varying
complex envelopes ``A_k(t)``,

    x(t) = Σ_k Re{A_k(t) e^{i o_k φ_k(t)}} + noise,

and the envelopes minimise ``Σ_n (x_n − model_n)² + Σ_k r_k² Σ_n |∇^p A_k(n)|²`` (``p`` =
``filter_order``: first or second differences). The normal equations couple the 2K real
unknowns of one sample with each other and with ``p`` neighbours only, so the matrix is banded
(half-bandwidth ``2Kp``) and is solved by a banded Cholesky factorisation with one step of
iterative refinement — O(N K² p²) work, O(N K p) memory, stable for very narrow bandwidths.
Solving all orders together is what keeps crossing orders from corrupting each other.

Bandwidth: for a stationary order the envelope filter is ``|H(ν)|² = 1/(1 + r² (2 sin(π ν/fs))^{2p})``
(``ν`` the offset from the order), so ``r = (2 sin(π B/(2 fs)))^{−p}`` puts the −3 dB points at
``±B/2``: ``B`` (``bandwidth_hz``) is the full −3 dB bandwidth around the order. With
``bandwidth_orders`` it is ``B(t) = bandwidth_orders · rpm(t)/60`` (constant width in orders);
give one value per order for a bandwidth proportional to the order.

Errors: an envelope varying at rate ν is attenuated by ``|H(ν)|`` (choose ``B`` above the
envelope's own bandwidth — for a resonance crossing, about the resonance's half-power
bandwidth or more); noise enters with the equivalent noise bandwidth
``ENBW = (B/2)(π/p)/sin(π/2p)``, giving an amplitude standard deviation
``σ_A ≈ sqrt(N0 · ENBW)`` (``N0`` the one-sided noise density, estimated from the residual and
reported in ``attrs['amplitude_std_estimate']``).

Implementation: the record is first low-passed and decimated (linear-phase Kaiser FIR, 100 dB)
to about four times the highest order frequency, then solved in overlapping blocks whose
overlap covers the filter's memory (``6/B`` seconds each side), so memory is bounded for long
records. The record ends (half the decimation filter) are trimmed.

References
----------
H. Vold and J. Leuridan, "High resolution order tracking at extreme slew rates, using Kalman
tracking filters", SAE Technical Paper 931288 (1993).
J. Tůma, "Setting the passband width in the Vold–Kalman order tracking filter", Proc. ICSV12
(2005) — the bandwidth/weighting relation used here.
M.-Ch. Pan and Y.-F. Lin, "Further exploration of Vold–Kalman-filtering order tracking with
shaft-speed information", MSSP 20 (2006) — multi-order (joint) formulation.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from crankbench.predict._validate import check_int, check_option, check_positive
from crankbench.predict.errors import AnalysisError
from crankbench.predict._deprecate import renamed
from crankbench.predict._threads import single_threaded_blas

from .resample import _as_rpm, _as_signal, shaft_angle

__all__ = ["vold_kalman", "vkf_weight", "enbw_hz"]

log = logging.getLogger("crankbench")

_DIFF = {1: np.array([-1.0, 1.0]), 2: np.array([1.0, -2.0, 1.0])}


def vkf_weight(bandwidth_hz, fs: float, filter_order: int):
    """Weight ``r`` giving a full −3 dB bandwidth ``bandwidth_hz`` at sample rate ``fs``.

    For the real-signal least-squares form used here the envelope response is
    ``H(ν) = 1/(1 + 2 r² (2 sin(π ν/fs))^{2p})`` (the data term sees half of ``|A|²``), so
    ``|H| = 1/√2`` at ``ν = B/2`` when ``r² = (√2 − 1) / (2 (2 sin(π B/(2 fs)))^{2p})``.

    Parameters
    ----------
    bandwidth_hz : float or ndarray
        Full −3 dB bandwidth around the order, Hz (< fs).
    fs : float
        Sample rate of the solve, Hz.
    filter_order : {1, 2}
        Order of the difference (smoothness) equation.

    Returns
    -------
    float or ndarray
        ``r`` (dimensionless).

    References
    ----------
    Tůma (2005), see the module docstring.

    Examples
    --------
    >>> r = vkf_weight(2.0, 1000.0, 2)
    >>> nu = 1.0                                    # half the bandwidth, Hz
    >>> gain = 1 / (1 + 2 * r**2 * (2 * np.sin(np.pi * nu / 1000.0)) ** 4)
    >>> round(float(gain), 12) == round(2 ** -0.5, 12)
    True
    """
    d = 2.0 * np.sin(np.pi * np.asarray(bandwidth_hz, float) / (2.0 * fs))
    return np.sqrt((np.sqrt(2.0) - 1.0) / 2.0) * d ** (-filter_order)


def enbw_hz(bandwidth_hz, filter_order: int):
    """Equivalent noise bandwidth ``∫|H(ν)|² dν`` (Hz, two-sided around the order) of the VKF.

    With ``H = 1/(1 + c (2ν/B)^{2p})``, ``c = √2 − 1``:
    ``ENBW = (B/2) c^{−1/2p} · 2 (2p − 1)/(2p) · π/(2p sin(π/2p))``.

    Examples
    --------
    >>> round(float(enbw_hz(2.0, 1)), 6)
    2.440662
    """
    p = filter_order
    n = 2 * p
    integral = 2.0 * (n - 1) / n * np.pi / (n * np.sin(np.pi / n))
    return 0.5 * np.asarray(bandwidth_hz, float) * (np.sqrt(2.0) - 1.0) ** (-1.0 / n) * integral


def _decimate(values: np.ndarray, fs: float, f_max: float):
    """Low-pass and decimate so that ``f_max`` stays flat (ripple ≈ 1e-5).

    Returns (decimated values, input index of each output sample, new rate)."""
    q = int(max(1, math.floor(fs / (4.0 * f_max))))
    if q == 1:
        return values, np.arange(values.shape[0]), fs
    from scipy import signal

    fs_new = fs / q
    f_stop = fs_new - f_max  # aliases of f >= f_stop fall at >= f_max ... keep them out
    numtaps, beta = signal.kaiserord(100.0, (f_stop - f_max) / (0.5 * fs))
    numtaps |= 1
    if values.shape[0] <= numtaps + 4 * q:  # before designing: the filter could be huge
        return values, np.arange(values.shape[0]), fs
    h = signal.firwin(numtaps, 0.5 * (f_max + f_stop), window=("kaiser", beta), fs=fs)
    half = numtaps // 2
    filtered = signal.oaconvolve(values, h, mode="valid")[::q]
    index = half + q * np.arange(filtered.shape[0])
    return filtered, index, fs_new


def _spline_weights(n: int, m: int):
    """Envelope representation on knots every ``m`` samples.

    ``m == 1``: one unknown per sample (the classical VKF). ``m > 1``: uniform cubic B-spline
    coefficients; sample ``i`` uses coefficients ``q_i … q_i + 3``. Returns (q, W, n_coef)."""
    if m == 1:
        return np.arange(n), np.ones((n, 1)), n
    pos = np.arange(n) / m
    q = np.floor(pos).astype(np.int64)
    f = pos - q
    f2, f3 = f * f, f * f * f
    w = np.empty((n, 4))
    w[:, 0] = (1.0 - f) ** 3 / 6.0
    w[:, 1] = (3.0 * f3 - 6.0 * f2 + 4.0) / 6.0
    w[:, 2] = (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0) / 6.0
    w[:, 3] = f3 / 6.0
    return q, w, int(q[-1]) + 4


def _assemble(basis, x, q, w, n_coef, weights, p):
    """Banded upper form of A = CᵀC + Σ_k r_k² D_pᵀ D_p and the right side Cᵀx.

    ``basis``: (N, 2K) columns cos θ_k, −sin θ_k; ``q, w``: envelope representation
    (:func:`_spline_weights`); ``weights``: (n_coef − p, K) squared weights per difference row.
    Unknown (coefficient c, j) has flat index 2K c + j (j = 2k real, 2k+1 imaginary part).
    """
    m = basis.shape[1]
    s = w.shape[1]
    u = m * max(p, s - 1) + m - 1
    size = n_coef * m
    ab = np.zeros((u + 1, size))
    for a in range(s):
        for b in range(a, s):
            wab = w[:, a] * w[:, b]
            for j in range(m):
                for jj in range(m):
                    d = (b - a) * m + (jj - j)
                    if d < 0:
                        continue
                    col = (q + b) * m + jj
                    ab[u - d] += np.bincount(col, wab * basis[:, j] * basis[:, jj], minlength=size)
    c = _DIFF[p]
    w2 = np.repeat(weights, 2, axis=1)                      # (n_coef - p, m)
    rows = np.arange(weights.shape[0])
    for a in range(p + 1):
        for b in range(a, p + 1):
            cols = ((rows[:, None] + b) * m + np.arange(m)[None, :]).ravel()
            ab[u - (b - a) * m, cols] += c[a] * c[b] * w2.ravel()
    rhs = np.zeros(size)
    for a in range(s):
        for j in range(m):
            rhs += np.bincount((q + a) * m + j, w[:, a] * basis[:, j] * x, minlength=size)
    return ab, rhs


def _banded_matvec(ab, z, u):
    """y = A z for a symmetric matrix in upper banded storage."""
    y = ab[u] * z
    for d in range(1, u + 1):
        diag = ab[u - d, d:]
        y[:-d] += diag * z[d:]
        y[d:] += diag * z[:-d]
    return y


def _solve_block(x, phase, knot_weights, p, m):
    """Solve one block; ``knot_weights``: (n_coef - p, K) r² per difference row of the knots."""
    from scipy.linalg import cho_solve_banded, cholesky_banded

    n, k = phase.shape
    basis = np.empty((n, 2 * k))
    basis[:, 0::2] = np.cos(phase)
    basis[:, 1::2] = -np.sin(phase)
    q, w, n_coef = _spline_weights(n, m)
    ab, rhs = _assemble(basis, x, q, w, n_coef, knot_weights, p)
    u = ab.shape[0] - 1
    # factor in LAPACK's lower band form (dpbtrf 'L'): same matrix, and OpenBLAS's threaded
    # upper-form path can be ~100x slower on a busy machine
    low = np.zeros_like(ab)
    for d in range(u + 1):
        low[d, : ab.shape[1] - d] = ab[u - d, d:]
    try:
        factor = cholesky_banded(low, lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        raise AnalysisError("Vold-Kalman system is not positive definite; the bandwidth is "
                            "too narrow for float64 at this sample rate (widen bandwidth)") from None
    z = cho_solve_banded((factor, True), rhs, check_finite=False)
    z += cho_solve_banded((factor, True), rhs - _banded_matvec(ab, z, u), check_finite=False)
    coef = z.reshape(n_coef, 2 * k)
    cplx = coef[:, 0::2] + 1j * coef[:, 1::2]               # (n_coef, K)
    env = np.zeros((n, k), dtype=complex)
    for a in range(w.shape[1]):
        env += w[:, a:a + 1] * cplx[q + a]
    model = np.real(env * np.exp(1j * phase)).sum(axis=1)
    return env, model


@renamed(rpm="speed_rpm")
@single_threaded_blas  # banded solves per block: BLAS threads only cost (issue 21)
def vold_kalman(x, *, fs=None, speed_rpm, orders, bandwidth_hz=None, bandwidth_orders=None,
                filter_order: int = 2, decimate: bool = True, block: int = 1 << 15,
                knots_per_bandwidth: float | None = 40.0):
    """Vold–Kalman filter: complex envelopes of several orders, solved jointly.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal (any SI unit); a Record channel supplies ``fs`` and ``units``.
    fs : float, optional
        Sample rate, Hz (required for a plain array).
    speed_rpm : float, array_like (N,) or (K, N)
        Shaft speed per sample, rpm; a 2-D array gives each order its own speed reference
        (orders of different shafts, which may cross).
    orders : sequence of float
        Orders to extract (per revolution of their shaft).
    bandwidth_hz : float or sequence, optional
        Full −3 dB bandwidth around each order, Hz (constant).
    bandwidth_orders : float or sequence, optional
        Bandwidth in orders (Hz = value · rpm/60, following the speed); one value per order for a
        bandwidth proportional to the order. Default ``0.1`` if neither is given.
    filter_order : {1, 2}
        Order of the smoothness (difference) equation; 2 gives a flatter pass band.
    decimate : bool
        Low-pass and decimate to ≈ 4× the highest order frequency before solving (faster; the
        pass band is flat to ≈ 1e-5).
    block : int
        Samples (after decimation) solved at a time, plus the overlap (bounds memory).
    knots_per_bandwidth : float or None
        Fidelity knob: the envelope is represented by a cubic B-spline with knots every
        ``1/(knots_per_bandwidth · B)`` seconds (never closer than one sample); this keeps the
        solve well conditioned for narrow bandwidths. ``None`` solves one envelope value per
        sample (the classical form; ill-conditioned when ``B/fs`` ≲ 1e-4).

    Returns
    -------
    xarray.Dataset
        ``envelope`` (complex, units of ``x``; peak amplitude ``|A|`` and phase ``arg A`` of
        ``Re{A e^{i o φ}}``) and ``reconstruction`` (order ``o`` as a time signal) over
        (``order``, ``time``), ``rpm`` along time, and ``residual``. Attrs: method, bandwidth,
        filter order, solve rate, ``amplitude_std_estimate`` (noise part of the error).

    References
    ----------
    Vold & Leuridan (1993); Tůma (2005); Pan & Lin (2006) — see the module docstring.

    Examples
    --------
    >>> fs = 2000.0
    >>> t = np.arange(int(6 * fs)) / fs
    >>> rpm = 600 + 200 * t
    >>> phi = shaft_angle(rpm, fs)
    >>> x = 1.0 * np.cos(2 * phi) + 0.2 * np.cos(3 * phi)
    >>> res = vold_kalman(x, fs=fs, speed_rpm=rpm, orders=[2, 3], bandwidth_hz=2.0)
    >>> amp = np.abs(res.envelope.isel(time=slice(200, -200)))
    >>> np.round(amp.mean("time").values, 4)
    array([1. , 0.2])
    """
    values, fs, units, label = _as_signal(x, fs)
    n = values.shape[0]
    orders = np.atleast_1d(np.asarray(orders, dtype=float))
    if orders.ndim != 1 or orders.size == 0 or not np.all(np.isfinite(orders)) or (orders <= 0).any():
        raise AnalysisError(f"orders must be positive numbers, got {orders.tolist()}")
    k = orders.shape[0]
    p = check_int(filter_order, "filter_order", minimum=1, error=AnalysisError)
    check_option(p, "filter_order", (1, 2), error=AnalysisError)
    block = check_int(block, "block", minimum=256, error=AnalysisError)
    rpm_arr = np.asarray(speed_rpm.values if hasattr(speed_rpm, "dims") else speed_rpm, dtype=float)
    if rpm_arr.ndim == 2:
        if rpm_arr.shape != (k, n):
            raise AnalysisError(f"a 2-D rpm must have shape (len(orders), len(x)) = ({k}, {n}), "
                                f"got {rpm_arr.shape}")
        speeds = np.stack([_as_rpm(r, n, fs) for r in rpm_arr])
    else:
        speeds = np.tile(_as_rpm(speed_rpm, n, fs), (k, 1))
    if bandwidth_hz is not None and bandwidth_orders is not None:
        raise AnalysisError("give bandwidth_hz or bandwidth_orders, not both")
    if bandwidth_hz is None and bandwidth_orders is None:
        bandwidth_orders = 0.1
    if bandwidth_hz is not None:
        bw = np.broadcast_to(np.asarray(bandwidth_hz, float), (k,)).copy()
        for i, b in enumerate(bw):
            check_positive(b, f"bandwidth_hz[{i}]", error=AnalysisError)
        bw_t = np.repeat(bw[:, None], n, axis=1)
        kind = f"{bw.tolist()} Hz (constant)"
    else:
        bo = np.broadcast_to(np.asarray(bandwidth_orders, float), (k,)).copy()
        for i, b in enumerate(bo):
            check_positive(b, f"bandwidth_orders[{i}]", error=AnalysisError)
        bw_t = bo[:, None] * speeds / 60.0
        kind = f"{bo.tolist()} orders (∝ speed)"
    phis = np.stack([shaft_angle(s, fs) for s in speeds]) * orders[:, None]
    f_max = float((orders[:, None] * speeds / 60.0 + bw_t).max())
    if f_max >= 0.5 * fs:
        raise AnalysisError(f"the highest order frequency {f_max:.6g} Hz is above the Nyquist "
                            f"frequency {0.5 * fs:.6g} Hz of {label}")
    if decimate:
        xd, index, fs_d = _decimate(values, fs, f_max)
    else:
        xd, index, fs_d = values, np.arange(n), fs
    nd = xd.shape[0]
    phase = phis[:, index].T                                   # (Nd, K)
    bw_d = bw_t[:, index].T
    if (bw_d >= fs_d).any():
        raise AnalysisError(f"bandwidth up to {bw_d.max():.6g} Hz is too wide for the solve rate "
                            f"{fs_d:.6g} Hz")
    # envelope knots every m samples (cubic B-spline) when the band is narrow: keeps the normal
    # equations well conditioned (condition ~ r² m^(-2p)) at no visible cost, the knot
    # spacing being below 1/(knots_per_bandwidth · B)
    m = 1 if knots_per_bandwidth is None else max(1, int(fs_d / (knots_per_bandwidth * bw_d.max())))
    overlap = int(math.ceil(6.0 * fs_d / bw_d.min()))
    overlap = m * int(math.ceil(overlap / m))
    block = m * max(1, int(math.ceil(block / m)))
    env = np.empty((nd, k), dtype=complex)
    model = np.empty(nd)
    for start in range(0, nd, block):
        stop = min(nd, start + block)
        a, b = max(0, start - overlap), min(nd, stop + overlap)
        if b - a <= (p + 1) * m:
            raise AnalysisError(f"{label}: too few samples ({b - a}) for the Vold-Kalman filter")
        n_coef = b - a if m == 1 else (b - a - 1) // m + 4
        at_knots = np.clip(a + (np.arange(n_coef - p) + 0.5 * p - (0 if m == 1 else 1)) * m,
                           a, b - 1).astype(np.int64)
        r2 = vkf_weight(bw_d[at_knots], fs_d, p) ** 2 * float(m) ** (1 - 2 * p)
        e, mdl = _solve_block(xd[a:b], phase[a:b], r2, p, m)
        env[start:stop] = e[start - a: stop - a]
        model[start:stop] = mdl[start - a: stop - a]
    residual = xd - model
    # one-sided noise density near the orders (the decimation filter shapes the band above)
    from scipy.signal import welch

    freq, psd = welch(residual, fs_d, nperseg=min(4096, nd))
    band = psd[(freq > 0) & (freq <= f_max)]
    n0 = float(np.median(band)) if band.size else 2.0 * float(np.mean(residual ** 2)) / fs_d
    std = np.sqrt(n0 * enbw_hz(bw_d.mean(axis=0), p))
    t = index / fs
    import xarray as xr

    recon = np.real(env * np.exp(1j * phase)).T
    ds = xr.Dataset(
        {"envelope": (("order", "time"), env.T, {"units": units, "long_name":
                                                  "complex envelope A of Re{A exp(i o phi)}"}),
         "reconstruction": (("order", "time"), recon, {"units": units}),
         "residual": (("time",), residual, {"units": units})},
        coords={"order": ("order", orders, {"units": "1"}),
                "time": ("time", t, {"units": "s"}),
                "rpm": ("time", speeds[0, index], {"units": "rpm"})},
        attrs={"method": "Vold-Kalman filter (joint, banded Cholesky)",
               "channel": label, "bandwidth": kind, "filter_order": p,
               "bandwidth_hz_min": float(bw_t.min()),
               "solve_rate_hz": fs_d, "decimation": int(round(fs / fs_d)),
               "block_samples": block, "overlap_samples": overlap, "knot_spacing_samples": m,
               "amplitude_std_estimate": std.tolist(),
               "error_note": "noise part sqrt(N0*ENBW); envelope changes faster than the "
                             "bandwidth are attenuated by |H|"})
    log.debug("vold_kalman %s: %d orders, %d samples at %.6g Hz", label, k, nd, fs_d)
    return ds
