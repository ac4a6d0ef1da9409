"""Vold–Kalman order tracking: the envelopes of several orders solved jointly.

Model (second-generation VKF, real form): the signal is a sum of orders with slowly varying
complex envelopes ``A_k(t)`` and a slowly varying real trend ``c(t)`` (order 0: the channel's
mean, a speed channel's mean speed, a sensor's drift),

    x(t) = c(t) + Σ_k Re{A_k(t) e^{i o_k φ_k(t)}} + noise,

and the envelopes minimise ``Σ_n (x_n − model_n)² + Σ_k r_k² Σ_n |∇^p A_k(n)|²`` (plus the same
smoothness term for ``c``; ``p`` = ``filter_order``: first or second differences). The trend is
solved with the orders, so it cannot leak into a low order. Each envelope is a cubic B-spline
with knots every ``m`` samples (``m = 1``: one value per sample, the classical form). The normal
equations couple the ``2K + 1`` unknowns of one knot with each other and with ``max(p, 3)``
neighbouring knots only, so the matrix is banded (half-bandwidth ``u = (2K+1)·max(p, 3) + 2K``)
and is solved by a banded Cholesky factorisation with one step of iterative refinement — or,
from ``vkf_iterative.MIN_ORDERS`` = 12 orders (``solver``), by conjugate gradients
preconditioned with the exact normal equations of groups of neighbouring orders
(:mod:`analysis.vkf_iterative`), which never forms the joint matrix.

Cost, for ``N`` samples at the solve rate, ``K`` orders and knots every ``m`` samples (what
runs; :mod:`analysis._vkf_kernels`, compiled by numba, numpy/SciPy twins otherwise):

* decimation: a polyphase FIR cascade, ``Σ_s taps_s/(q_1⋯q_s)`` multiply-adds per input
  sample, linear in the record and independent of ``K``;
* assembly, one pass over the samples: the ``(2K+1)(2K+2)/2`` basis products of each sample
  times the 10 spline-weight pairs of its knot interval, O(N K²);
* factorisation O((N/m)(2K+1) u²) = O((N/m) K³) with ``m`` ≈ ``fs/(40 B)`` (the compiled
  column-band Cholesky up to ``u`` = 39, LAPACK's blocked ``dpbtrf`` above); substitutions,
  refinement and envelopes O((N/m) K²) and O(N K); noise and smearing estimates O(N K);
* iterative solve (12 orders and more): the groups' own normal equations O(N K) to build
  and factorise, then O(N K) per iteration; the iterations depend on how close the orders
  are for their bandwidths (23–40 from 12 to 24 orders 0.5 apart on the bench's scaling
  record, 14 for 16 orders with the automatic bandwidths).

All of it is linear in the samples (bench suite ``scaling``: fitted exponent against record
length, bound 1.25). In the orders the direct solve is cubic with a small constant and takes
over beyond about 8 orders; with the iterative solve from 12 orders the fitted exponent over
3–24 orders (same solve rate) is 1.6 in the same suite (bound 2).

Bandwidth: for a stationary order the envelope filter is
``H(ν) = 1/(1 + 2r²(2 sin(π ν/fs))^{2p})`` (``ν`` the offset from the order; the data term of the
real form sees half of ``|A|²``); :func:`vkf_weight` sets ``r`` so that ``|H| = 1/√2`` at
``ν = ±B/2``: ``B`` (``bandwidth_hz``) is the full −3 dB bandwidth around the order. With
``bandwidth_orders`` it is ``B(t) = bandwidth_orders · rpm(t)/60``; a 2-D ``bandwidth_hz``
(orders × samples) gives each order its own bandwidth against time (:mod:`analysis.autotrack`
widens it around sharp peaks).

Errors: noise enters with the equivalent noise bandwidth ``ENBW = ∫|H|²dν`` (:func:`enbw_hz`:
``(B/2) c^{−1/2p} · 2(2p − 1)/(2p) · π/(2p sin(π/2p))`` with ``c = √2 − 1``, i.e. 1.22 B for
``p = 1`` and 1.04 B for ``p = 2``), giving an amplitude standard deviation
``σ_A = sqrt(N0 · ENBW)`` (``N0`` the one-sided noise density near the order, estimated from the
residual). An envelope varying faster than the bandwidth is smeared: for ``p = 2`` the bias of
a resonance-shaped (Lorentzian) envelope of half-power crossing time ``T`` is about
``159/(π T B)^4`` of its peak; estimated from the solved envelope's second derivative
(``T² = 8|A|/|A''|`` at a Lorentzian peak) and reported with the noise in
``amplitude_uncertainty``.

Implementation: the record is first low-passed and decimated by ``q`` to a solve rate between
2.5 and 4 times ``f_max`` (the highest order frequency plus its bandwidth), the one that costs
least: the cascade's multiply-adds plus the solve's work per decimated sample, which grows as
the square of the unknowns per sample (:mod:`analysis.vkf_decimate`; the bench's 3-order run-up is
solved at 606 instead of 909 Hz: bench suite ``orders``, row ``order_track vkf speed``), as
long as the sharper cascade leaves no more than 0.5 % of the record incomplete at either end,
with a cascade of zero-phase
Kaiser-window FIR stages (``vkf_decimate._decimator``: pass band ``[0, f_max]`` flat to 1e-5, all that
would alias into the output band 100 dB down — both checked on the designed taps by
``tests/analysis/test_vkf_kernels.py``), then solved in overlapping blocks whose overlap covers
the filter's memory (``6/B`` seconds each side), so memory is bounded for long records. The
record ends (the decimation filters' half-lengths) are trimmed.

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

import functools
import logging
import math

import numpy as np

from crankbench.predict._deprecate import renamed
from crankbench.predict._validate import check_int, check_option, check_positive
from crankbench.predict.errors import AnalysisError
from crankbench.predict._threads import single_threaded_blas

from . import _vkf_kernels, _vkf_noise, vkf_iterative, vkf_smear
from .vkf_decimate import (_DECIMATION_DB, _decimate, _decimation_factor, _decimator,  # noqa: F401
                           _fir_macs, _kaiser_lowpass)                    # (re-exported)
from .resample import _as_angle, _as_rpm, _as_signal
from .resample import shaft_angle as _integrate_speed

__all__ = ["vold_kalman", "vkf_weight", "enbw_hz", "smearing_constant"]

log = logging.getLogger("crankbench")



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
    ``ENBW = (B/2) c^{−1/2p} · 2 (2p − 1)/(2p) · π/(2p sin(π/2p))`` — 1.2203 B for ``p = 1``,
    1.0384 B for ``p = 2`` (``tests/analysis/test_vkf.py`` integrates the discrete response).

    Examples
    --------
    >>> round(float(enbw_hz(2.0, 1)), 6), round(float(enbw_hz(1.0, 2)), 4)
    (2.440662, 1.0384)
    """
    p = filter_order
    n = 2 * p
    integral = 2.0 * (n - 1) / n * np.pi / (n * np.sin(np.pi / n))
    return 0.5 * np.asarray(bandwidth_hz, float) * (np.sqrt(2.0) - 1.0) ** (-1.0 / n) * integral


def smearing_constant(filter_order: int) -> float:
    """``K_p`` of the smearing bias of a Lorentzian envelope, ``bias ≈ K_p/(π T B)^{2p}``.

    ``1 − H(ν) ≈ c (2ν/B)^{2p}`` near the order and the complex envelope of a resonance crossed
    in the half-power time ``T`` has the one-sided spectrum ``πT e^{−πTν}``, whose moment
    ``E[ν^{2p}] = (2p)!/(πT)^{2p}``; so ``K_p = c 2^{2p} (2p)!`` (3.31 for ``p = 1``, 159 for
    ``p = 2``).

    Examples
    --------
    >>> round(smearing_constant(2), 1)
    159.1
    """
    c = np.sqrt(2.0) - 1.0
    return float(c * 2.0 ** (2 * filter_order) * math.factorial(2 * filter_order))


#: relative numerical floor of a solved envelope (stated in ``amplitude_uncertainty``): what a
#: noise-free steady or slowly swept tone reads off once the decimation gain is divided out
#: (``tests/analysis/test_vkf_smear.py``)
NUMERICAL_FLOOR = 1e-6


def _solve_block(x, cosp, sinp, knot_weights, p, m, trend, iterative, orders):
    """Solve one block; ``knot_weights``: (n_coef - p, K [+1]) r² per difference row;
    ``iterative``: by PCG (:mod:`analysis.vkf_iterative`), else by banded Cholesky.
    Returns ((envelopes (n, K), trend (n,), model (n,)), PCG iterations: -1 when it did not
    converge and the direct solve was used, 0 for the direct solve)."""
    n, k = cosp.shape
    n_coef = n if m == 1 else (n - 1) // m + 4
    col_w = np.repeat(knot_weights[:, :k], 2, axis=1)
    if trend:
        col_w = np.concatenate([col_w, knot_weights[:, k:]], axis=1)
    iterations = 0
    try:
        if iterative:
            z, iterations = vkf_iterative.solve(x, cosp, sinp, trend, m, n_coef, p, col_w,
                                                orders=orders)
            if iterations >= 0:
                return _vkf_kernels.envelopes(z, cosp, sinp, m, trend), iterations
            log.warning("Vold-Kalman: conjugate gradients did not reach %.0e in %d iterations "
                        "(orders close for their bandwidths); solved directly",
                        vkf_iterative.TOLERANCE, vkf_iterative.MAX_ITERATIONS)
        band, rhs = _vkf_kernels.assemble(x, cosp, sinp, trend, m, n_coef, p, col_w)
        z = _vkf_kernels.solve(band, rhs)
    except _vkf_kernels.NotPositiveDefinite:
        raise AnalysisError("Vold-Kalman system is not positive definite; the bandwidth is "
                            "too narrow for float64 at this sample rate (widen bandwidth)") from None
    return _vkf_kernels.envelopes(z.reshape(n_coef, -1), cosp, sinp, m, trend), iterations


def _columns(rows, n=None, *, scale=None):
    """C-ordered (N, K) array whose column ``j`` is ``rows[j]`` (a (K, N) array, a (K,) vector
    of constants with ``n``, or one (N,) row for every column) times ``scale[j]``: filled
    column by column (numpy's broadcasting over a last axis of a few elements, and a
    transposed copy, both run ~10x slower than these strided passes)."""
    rows = np.asarray(rows, float)
    k = rows.shape[0] if scale is None or rows.ndim == 2 else np.size(scale)
    n = rows.shape[-1] if n is None else n
    out = np.empty((n, k))
    for j in range(k):
        row = rows if rows.ndim == 1 and scale is not None else rows[j]
        if scale is None:
            out[:, j] = row
        else:
            np.multiply(row, scale[j], out=out[:, j])
    return out


def _bandwidths(bandwidth_hz, bandwidth_orders, orders, speeds, n):
    """Bandwidth in Hz against time: ``(at, top, low, kind)`` with ``at(index)`` the (len,
    K) bandwidths at those samples, ``top``/``low`` the largest/smallest per order, and a
    description (the full (K, N) array is never built for a constant or speed-proportional
    bandwidth)."""
    k = orders.shape[0]
    if bandwidth_hz is not None and bandwidth_orders is not None:
        raise AnalysisError("give bandwidth_hz or bandwidth_orders, not both")
    if bandwidth_hz is None and bandwidth_orders is None:
        bandwidth_orders = 0.1
    if bandwidth_hz is not None:
        arr = np.asarray(bandwidth_hz, float)
        if arr.ndim == 2:
            if arr.shape != (k, n):
                raise AnalysisError(f"a 2-D bandwidth_hz must have shape (len(orders), len(x)) "
                                    f"= ({k}, {n}), got {arr.shape}")
            if not np.isfinite(arr).all() or arr.min() <= 0:
                raise AnalysisError("bandwidth_hz must be finite and > 0")
            return (lambda idx: _columns(arr[:, idx]), arr.max(axis=1), arr.min(axis=1),
                    f"per order against time, {arr.min():.4g}..{arr.max():.4g} Hz")
        bw = np.broadcast_to(arr, (k,)).copy()
        for i, b in enumerate(bw):
            check_positive(b, f"bandwidth_hz[{i}]", error=AnalysisError)
        return (lambda idx: _columns(bw, np.size(idx)), bw, bw,
                f"{bw.tolist()} Hz (constant)")
    bo = np.broadcast_to(np.asarray(bandwidth_orders, float), (k,)).copy()
    for i, b in enumerate(bo):
        check_positive(b, f"bandwidth_orders[{i}]", error=AnalysisError)
    return (lambda idx: _columns(speeds[:, idx] if speeds.shape[0] == k else speeds[0, idx],
                                 scale=bo / 60.0),
            bo * speeds.max(axis=1) / 60.0, bo * speeds.min(axis=1) / 60.0,
            f"{bo.tolist()} orders (∝ speed)")


@renamed(rpm="speed_rpm")
def vold_kalman(x, *, fs=None, speed_rpm, orders, bandwidth_hz=None, bandwidth_orders=None,
                filter_order: int = 2, decimate: bool = True, block: int = 1 << 15,
                knots_per_bandwidth: float | None = 40.0, shaft_angle=None,
                trend: bool = True, solver: str = "auto"):
    """Vold–Kalman filter: complex envelopes of several orders (and the trend), solved jointly.

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
    bandwidth_hz : float, sequence or array (K, N), optional
        Full −3 dB bandwidth around each order, Hz: constant, one per order, or one per order
        and sample.
    bandwidth_orders : float or sequence, optional
        Bandwidth in orders (Hz = value · rpm/60, following the speed); one value per order for a
        bandwidth proportional to the order. Default ``0.1`` if neither is given.
    filter_order : {1, 2}
        Order of the smoothness (difference) equation; 2 gives a flatter pass band.
    decimate : bool
        Low-pass and decimate to ≈ 4× the highest order frequency before solving (faster; the
        pass band is flat to 1e-5, aliases 100 dB down).
    block : int
        Samples (after decimation) solved at a time, plus the overlap (bounds memory).
    knots_per_bandwidth : float or None
        Fidelity knob: the envelope is represented by a cubic B-spline with knots every
        ``1/(knots_per_bandwidth · B)`` seconds (never closer than one sample); this keeps the
        solve well conditioned for narrow bandwidths. ``None`` solves one envelope value per
        sample (the classical form; ill-conditioned when ``B/fs`` ≲ 1e-4).
    shaft_angle : array_like, optional
        Shaft angle per sample (rad; 1-D speed only), e.g. the encoder angle; default the
        integrated speed.
    trend : bool
        Solve an order-0 envelope (the channel's mean and drift) with the orders; its −3 dB
        bandwidth is a quarter of the lowest order's frequency at the lowest speed.
    solver : {'auto', 'direct', 'iterative'}
        The joint normal equations by banded Cholesky ('direct', cubic in the number of
        orders) or by block-preconditioned conjugate gradients ('iterative',
        :mod:`analysis.vkf_iterative`: linear in the orders, envelopes within 1e-7 of the
        largest of the direct solve's; falls back to 'direct' with a warning if it does not
        converge); 'auto': iterative from ``vkf_iterative.MIN_ORDERS`` orders.

    Returns
    -------
    xarray.Dataset
        ``envelope`` (complex, units of ``x``; peak amplitude ``|A|`` and phase ``arg A`` of
        ``Re{A e^{i o φ}}``) and ``reconstruction`` (order ``o`` as a time signal) over
        (``order``, ``time``); ``mean`` (the order-0 envelope), ``residual``;
        ``amplitude_uncertainty`` and ``amplitude_noise`` (order, time): 1-σ noise plus the
        estimated smearing, and the noise part alone; ``rpm`` along time. Attrs: method,
        bandwidth, filter order, solve rate, ``amplitude_std_estimate`` (noise part, mean per
        order).

    References
    ----------
    Vold & Leuridan (1993); Tůma (2005); Pan & Lin (2006) — see the module docstring.

    Examples
    --------
    >>> fs = 2000.0
    >>> t = np.arange(int(6 * fs)) / fs
    >>> rpm = 600 + 200 * t
    >>> phi = _integrate_speed(rpm, fs)
    >>> x = 1.0 * np.cos(2 * phi) + 0.2 * np.cos(3 * phi) + 5.0
    >>> res = vold_kalman(x, fs=fs, speed_rpm=rpm, orders=[2, 3], bandwidth_hz=2.0)
    >>> amp = np.abs(res.envelope.isel(time=slice(200, -200)))
    >>> np.round(amp.mean("time").values, 4), round(float(res["mean"].mean()), 4)
    (array([1. , 0.2]), 5.0)
    """
    res = _vold_kalman_arrays(x, fs=fs, speed_rpm=speed_rpm, orders=orders,
                              bandwidth_hz=bandwidth_hz, bandwidth_orders=bandwidth_orders,
                              filter_order=filter_order, decimate=decimate, block=block,
                              knots_per_bandwidth=knots_per_bandwidth, shaft_angle=shaft_angle,
                              trend=trend, solver=solver)
    import xarray as xr

    units = res["units"]
    env = res["envelope"]
    recon = env.real * res["cos"] - env.imag * res["sin"]
    ds = xr.Dataset(
        {"envelope": (("order", "time"), env.T, {"units": units, "long_name":
                                                  "complex envelope A of Re{A exp(i o phi)}"}),
         "reconstruction": (("order", "time"), recon.T, {"units": units}),
         "mean": (("time",), res["mean"], {"units": units, "long_name":
                                           "order 0: trend envelope (the channel's mean)"}),
         "residual": (("time",), res["residual"], {"units": units}),
         "amplitude_noise": (("order", "time"), res["noise"].T, {"units": units, "long_name":
                                                                 "1-sigma amplitude noise"}),
         "amplitude_uncertainty": (("order", "time"), res["uncertainty"].T,
                                   {"units": units, "long_name": "1-sigma amplitude noise, "
                                    "estimated envelope smearing and numerical floor"}),
         "smearing_model": (("order", "time"), res["smearing_model"].T,
                            {"units": units, "long_name": "smearing of a Lorentzian envelope "
                             "of the solved curvature, K_p/(pi T B)^(2p) (to choose bandwidths)"})},
        coords={"order": ("order", res["orders"], {"units": "1"}),
                "time": ("time", res["time"], {"units": "s"}),
                "rpm": ("time", res["rpm"], {"units": "rpm"})},
        attrs=res["attrs"])
    return ds


@single_threaded_blas  # the numpy forms' banded solves per block: BLAS threads only cost
def _vold_kalman_arrays(x, *, fs, speed_rpm, orders, bandwidth_hz, bandwidth_orders,
                        filter_order, decimate=True, block=1 << 15, knots_per_bandwidth=40.0,
                        shaft_angle=None, trend=True, checked=False, solver="auto"):
    """:func:`vold_kalman` as plain arrays (dict): ``envelope`` (N, K) complex, its
    ``amplitude`` ``|A|``, ``mean``,
    ``residual``, ``noise`` and ``uncertainty`` (N, K), ``time``, ``rpm``, ``orders``, the
    basis ``cos``/``sin`` (N, K) of ``o_k φ``, ``units``, ``label`` and the Dataset's
    ``attrs``. ``checked``: the caller has validated ``x`` (float array), ``fs``, a 1-D
    ``speed_rpm`` and ``shaft_angle`` (``order_track`` has)."""
    if checked:
        values, units, label = np.asarray(x, dtype=float), "", "x"
    else:
        values, fs, units, label = _as_signal(x, fs)
    n = values.shape[0]
    orders = np.atleast_1d(np.asarray(orders, dtype=float))
    if orders.ndim != 1 or orders.size == 0 or not np.all(np.isfinite(orders)) or (orders <= 0).any():
        raise AnalysisError(f"orders must be positive numbers, got {orders.tolist()}")
    k = orders.shape[0]
    p = check_int(filter_order, "filter_order", minimum=1, error=AnalysisError)
    check_option(p, "filter_order", (1, 2), error=AnalysisError)
    block = check_int(block, "block", minimum=256, error=AnalysisError)
    solver = check_option(solver, "solver", ("auto", "direct", "iterative"), error=AnalysisError)
    iterative = solver == "iterative" or (solver == "auto" and k >= vkf_iterative.MIN_ORDERS)
    rpm_arr = np.asarray(speed_rpm.values if hasattr(speed_rpm, "dims") else speed_rpm, dtype=float)
    angle = None
    if rpm_arr.ndim == 2:
        if rpm_arr.shape != (k, n):
            raise AnalysisError(f"a 2-D rpm must have shape (len(orders), len(x)) = ({k}, {n}), "
                                f"got {rpm_arr.shape}")
        speeds = np.stack([_as_rpm(r, n, fs) for r in rpm_arr])
        single = None
    else:
        speeds = None
        if checked:
            single = rpm_arr
            angle = None if shaft_angle is None else np.asarray(shaft_angle, dtype=float)
        else:
            single = _as_rpm(speed_rpm, n, fs)
            angle = _as_angle(shaft_angle, n)
        if angle is None and hasattr(speed_rpm, "coords") and "shaft_angle" in speed_rpm.coords:
            angle = _as_angle(speed_rpm.coords["shaft_angle"].values, n)
    speed_at = (lambda i: single if i is None else single[i]) if speeds is None else None
    top_speed = single.max() if speeds is None else speeds.max(axis=1)
    bw_at, bw_top, bw_low, kind = _bandwidths(bandwidth_hz, bandwidth_orders, orders,
                                              single[None, :] if speeds is None else speeds, n)
    f_max = float(np.max(orders * top_speed / 60.0 + bw_top))
    if f_max >= 0.5 * fs:
        raise AnalysisError(f"the highest order frequency {f_max:.6g} Hz is above the Nyquist "
                            f"frequency {0.5 * fs:.6g} Hz of {label}")
    if decimate:
        xd, index, fs_d = _decimate(values, fs, f_max, 2 * k + (1 if trend else 0))
    else:
        xd, index, fs_d = values, np.arange(n), fs
    nd = xd.shape[0]
    if speeds is None:
        phi = _integrate_speed(single, fs) if angle is None else angle
        cosp, sinp = _vkf_kernels.order_basis(phi[index], orders)      # (Nd, K)
        rpm_d = speed_at(index)
        low_speed = float(rpm_d.min())
    else:
        phase = np.stack([_integrate_speed(s, fs)[index] for s in speeds], axis=1) * orders
        rpm_d = speeds[0, index]
        low_speed = float(speeds[:, index].min())
        cosp, sinp = np.cos(phase), np.sin(phase)
    bw_d = bw_at(index)                                        # (Nd, K)
    if bw_d.max() >= fs_d:
        raise AnalysisError(f"bandwidth up to {bw_d.max():.6g} Hz is too wide for the solve rate "
                            f"{fs_d:.6g} Hz")
    # trend bandwidth: its response at the lowest order frequency is 1e-3 (joint solve: the
    # order's own response changes by < 1e-3 there)
    # (and no wider than the widest order band: the trend need not follow faster than they do)
    b_trend = min(2.0 * float(orders.min()) * low_speed / 60.0 / (
        1e3 / (np.sqrt(2.0) - 1.0)) ** (1.0 / (2 * p)), float(bw_d.max()))
    bw_top_d, bw_low_d = float(bw_d.max()), float(bw_d.min())
    if trend:
        bw_top_d, bw_low_d = max(bw_top_d, b_trend), min(bw_low_d, b_trend)
    # envelope knots every m samples (cubic B-spline) when the band is narrow: keeps the normal
    # equations well conditioned (condition ~ r² m^(-2p)) at no visible cost, the knot
    # spacing being below 1/(knots_per_bandwidth · B)
    m = 1 if knots_per_bandwidth is None else max(1, int(fs_d / (knots_per_bandwidth
                                                                  * bw_top_d)))
    overlap = int(math.ceil(6.0 * fs_d / bw_low_d))
    overlap = m * int(math.ceil(overlap / m))
    block = m * max(1, int(math.ceil(block / m)))
    if nd > block:
        env = np.empty((nd, k), dtype=complex)
        mean = np.zeros(nd)
        model = np.empty(nd)
    iterations = []
    for start in range(0, nd, block):
        stop = min(nd, start + block)
        a, b = max(0, start - overlap), min(nd, stop + overlap)
        if b - a <= (p + 1) * m:
            raise AnalysisError(f"{label}: too few samples ({b - a}) for the Vold-Kalman filter")
        n_coef = b - a if m == 1 else (b - a - 1) // m + 4
        at_knots = np.clip(a + (np.arange(n_coef - p) + 0.5 * p - (0 if m == 1 else 1)) * m,
                           a, b - 1).astype(np.int64)
        bw_knots = bw_d[at_knots]
        if trend:
            bw_knots = np.concatenate([bw_knots, np.full((at_knots.shape[0], 1), b_trend)], axis=1)
        r2 = vkf_weight(bw_knots, fs_d, p) ** 2 * float(m) ** (1 - 2 * p)
        (e, mn, mdl), its = _solve_block(xd[a:b], cosp[a:b], sinp[a:b], r2, p, m, trend,
                                         iterative, orders)
        iterations.append(its)
        if a == 0 and b == nd:               # one block: its arrays are the result
            env, mean, model = e, mn, mdl
            break
        env[start:stop] = e[start - a: stop - a]
        mean[start:stop] = mn[start - a: stop - a]
        model[start:stop] = mdl[start - a: stop - a]
    residual = xd - model
    rpm_orders = rpm_d if speeds is None else speeds[:, index].T
    f_ord = _columns(rpm_orders.T if rpm_orders.ndim == 2 else rpm_orders, scale=orders / 60.0)
    if fs_d != fs:          # the cascade's pass band (flat to 1e-5) divided out: it is known
        for j in range(k):  # by order (in place: env is this call's own array): np.interp of
            # a monotone column, not of the orders interleaved (4x faster)
            env[:, j] /= vkf_smear.decimation_gain(fs, f_max, int(round(fs / fs_d)),
                                                   f_ord[:, j])
    noise, smear = _uncertainty(env, residual, fs_d, orders, rpm_orders, bw_d, p, f_max,
                                trend_hz=b_trend if trend else 0.0, f_ord=f_ord)
    # smearing: the larger of the second-pass estimate (any envelope shape, bandwidth changes,
    # record ends) and the Lorentzian peak model (the second pass sees an already broadened
    # peak: at 5 % loss it reads ~0.8 of it)
    stated = np.maximum(vkf_smear.refilter_bias(env, bw_d, fs_d, p, noise), smear)
    stated *= stated                # noise, smearing and the numerical floor in quadrature
    amplitude = np.abs(env)
    floor = amplitude * NUMERICAL_FLOOR
    floor *= floor
    stated += floor
    stated += noise * noise
    np.sqrt(stated, out=stated)
    # rms over time, per order (einsum: no BLAS call, whose strided dot ran slow in place)
    std = np.sqrt(np.einsum("ij,ij->j", noise, noise) / nd)
    fallback = iterative and min(iterations) < 0
    how = ("conjugate gradients" if iterative and not fallback else "banded Cholesky")
    attrs = {"method": f"Vold-Kalman filter (joint with an order-0 trend, {how})"
                       if trend else f"Vold-Kalman filter (joint, {how})",
             "solver": ("direct (banded Cholesky)" if not iterative else
                        f"iterative (block-preconditioned conjugate gradients to a relative "
                        f"residual of {vkf_iterative.TOLERANCE:.0e}, at most "
                        f"{max(iterations)} iterations per block)" if not fallback else
                        f"direct (banded Cholesky) after conjugate gradients did not converge "
                        f"in {vkf_iterative.MAX_ITERATIONS} iterations"),
             "channel": label, "bandwidth": kind, "filter_order": p,
             "bandwidth_hz_min": float(np.min(bw_low)), "bandwidth_hz_max": float(np.max(bw_top)),
             "trend_bandwidth_hz": b_trend if trend else float("nan"),
             "solve_rate_hz": fs_d, "decimation": int(round(fs / fs_d)),
             "block_samples": block, "overlap_samples": overlap, "knot_spacing_samples": m,
             "amplitude_std_estimate": std.tolist(),
             "error_note": "amplitude_uncertainty = noise sqrt(N0*ENBW), the smearing of "
                           "the envelope by the filter (the larger of: filtering the solved "
                           "envelope again, largest within 1/(2B); the Lorentzian-peak model "
                           f"K_p/(pi T B)^(2p), K_p = {smearing_constant(p):.4g}) and a numerical floor "
                           f"{NUMERICAL_FLOOR:.0e}|A|, in quadrature; envelopes corrected "
                           "for the decimation filter's gain"}
    log.debug("vold_kalman %s: %d orders, %d samples at %.6g Hz", label, k, nd, fs_d)
    return {"envelope": env, "mean": mean, "residual": residual, "noise": noise,
            "uncertainty": stated, "smearing_model": smear, "amplitude": amplitude,
            "time": index / fs, "rpm": rpm_d,
            "orders": orders, "cos": cosp, "sin": sinp, "units": units, "label": label,
            "attrs": attrs}


def _uncertainty(env, residual, fs_d, orders, rpm_d, bw_d, p, f_pass, *, trend_hz=0.0,
                 f_ord=None):
    """(noise, smearing) per sample and order, both 1-σ-like amplitudes in signal units
    (``f_ord``: each order's frequency per sample, Hz, when the caller has it).

    Noise: ``sqrt(N0 · ENBW)`` with ``N0`` the residual's one-sided density beside each order,
    local in time and frequency: short-time spectra of the residual (frames of at least 2 s),
    over the bins within ±max(8 B, 20 bins) of the order's frequency: the lower quartile
    divided by ln(4/3) (quartile of an exponential variable), robust to the lines of orders
    not tracked that pass by (up to three quarters of the bins). The joint solve empties the
    residual around every tracked order and order 0 by the filter's own response,
    ``∏ (1 − H_m)²`` averaged over the frame (the orders move in a sweep): each bin is divided
    by it, and bins emptied below a quarter left out (read raw, bins beside the other orders
    had put the noise up to 2× low at wide bands). Smearing: for a Lorentzian envelope of
    half-power crossing time ``T`` the relative peak loss is ``K_p/(πTB)^{2p}``; ``T`` follows
    from the solved envelope as ``T² = 8|A|/|A''|``, i.e. loss
    ``K_p (|A''|/(8|A|))^p/(πB)^{2p}``, with the noise part of ``|A''|²`` removed first."""
    nd, k = env.shape
    if f_ord is None:
        f_ord = _columns(rpm_d.T if rpm_d.ndim == 2 else rpm_d, scale=orders / 60.0)
    by_order = np.ascontiguousarray(bw_d.T)  # (numpy reduces an (N, 3) array over N ~20x slower)
    b_low, b_high = by_order.min(axis=1), by_order.max(axis=1)
    b_med = b_low.copy()                    # (a constant bandwidth needs no sort)
    varies = b_low != b_high
    if varies.any():
        b_med[varies] = np.median(by_order[varies], axis=1)
    n0 = _local_noise(residual, fs_d, f_ord, b_med, f_pass, p, trend_hz, bw_d)
    enbw_per_hz = float(enbw_hz(1.0, p))
    if nd < 8:
        noise = np.sqrt(n0 * (bw_d * enbw_per_hz))
        return noise, np.zeros_like(noise)
    # noise part of |A''|²: N0 ∫ (2 sin(πν/fs)·fs)^4 |H(ν)|² dν over the solve band; the
    # integral scales as B^5 for p = 2 (B^3 for p = 1 within the band): evaluated at each
    # order's median bandwidth (all orders at once) and scaled
    nu, gain4, d2p = _smearing_grid(float(fs_d), p)
    h = 1.0 / (1.0 + 2.0 * (vkf_weight(b_med, fs_d, p) ** 2)[:, None] * d2p[None, :])
    per_n0 = np.trapezoid(gain4 * h * h, nu, axis=1)
    # |A''|² is averaged over the filter's response time, less ten times its expected noise
    # part (E|A''_noise|² = 2 N0 ∫ D⁴|H|²): only curvature well above the noise counts (noise
    # alone would otherwise read as smearing that grows with B)
    span = np.maximum(1, np.round(fs_d / (2.0 * b_low))).astype(np.int64)
    return _vkf_noise.noise_smearing(env, n0, bw_d, per_n0, b_med, span, p,
                                       smearing_constant(p), fs_d, enbw_per_hz)


@functools.lru_cache(maxsize=16)
def _smearing_grid(fs_d: float, p: int):
    """``ν`` over the solve band (4097 points), ``(2 sin(πν/fs) fs)^4`` and
    ``(2 sin(πν/fs))^{2p}`` for the noise part of ``|A''|²`` (read-only arrays)."""
    nu = np.linspace(-0.5 * fs_d, 0.5 * fs_d, 4097)
    d2nu = (2.0 * np.sin(np.pi * nu / fs_d)) ** 2          # (2 sin(πν/fs))², once for all orders
    gain4 = d2nu * d2nu * fs_d ** 4
    d2p = d2nu if p == 1 else d2nu * d2nu                  # (2 sin(πν/fs))^{2p}
    for a in (nu, gain4, d2p):
        a.flags.writeable = False
    return nu, gain4, d2p


def _local_noise(residual, fs_d, f_ord, b_med, f_pass, p=2, trend_hz=0.0, bw_d=None):
    """One-sided noise density (units²/Hz) of the residual beside each order, per sample
    (``b_med``: each order's median bandwidth, Hz; ``trend_hz``: the order-0 trend's bandwidth,
    0 without one; ``bw_d``: the bandwidth per sample and order, default ``b_med``), each bin
    corrected for the solve's own notches (see :func:`_uncertainty`)."""
    nd, k = f_ord.shape
    length = int(2 ** np.ceil(np.log2(max(64.0, 2.0 * fs_d))))
    length = min(length, int(2 ** np.floor(np.log2(max(64, nd)))))
    hop = length // 2
    starts = np.arange(0, max(1, nd - length + 1), hop)
    frames = residual[starts[:, None] + np.arange(min(length, nd))[None, :]]
    win, power = _periodic_hann(frames.shape[1])      # (shorter: a record under one frame)
    spec = np.fft.rfft(frames * win, axis=1)
    spec = (spec.real ** 2 + spec.imag ** 2) * (2.0 / (fs_d * power))
    freq = np.fft.rfftfreq(frames.shape[1], 1.0 / fs_d)
    df = float(freq[1]) if freq.shape[0] > 1 else fs_d
    centre = starts + 0.5 * frames.shape[1]
    flat = (freq > 0) & (freq <= f_pass)
    if bw_d is None:
        bw_d = np.broadcast_to(np.asarray(b_med, float)[None, :], f_ord.shape)
    spec = spec / _notch_depth(f_ord, starts, frames.shape[1], win, freq, bw_d, trend_hz,
                               fs_d, p)
    # lower quartile of an exponential variable: ln(4/3) of its mean (robust to up to three
    # quarters of the bins holding lines of orders not tracked), per frame, to every sample
    reach = np.maximum(8.0 * np.asarray(b_med, float), 20.0 * df)
    return _vkf_noise.local_levels(spec, freq, flat, centre, f_ord, reach)


@functools.lru_cache(maxsize=8)
def _periodic_hann(length: int):
    """Periodic Hann window of ``length`` samples (read-only) and its power ``Σ w²``."""
    win = np.hanning(length + 1)[:length]
    win.flags.writeable = False
    return win, float(np.sum(win ** 2))


def _notch_depth(f_ord, starts, length, win, freq, bw_d, trend_hz, fs_d, p):
    """Expected residual power per (frame, bin) relative to the input's: ``∏_m (1 − H_m)²``
    over every tracked order (and its mirror) and the order-0 trend, ``H`` the filter's
    envelope response :func:`vkf_weight` at the order's bandwidth there (``bw_d``, per sample
    and order: an adaptive band widened around a resonance notches wider), averaged over 3
    instants of the frame weighted by the window's energy (in a sweep the notch moves within
    the frame); NaN below 1/4 (too empty to read). ``H`` < 1e-3 beyond
    ``(B/2)((1e3 − 1)/(√2 − 1))^{1/2p}`` of its line (3.50 B for ``p = 2``, 24.5 B for
    ``p = 1``): only those bins are computed (compiled: :func:`_vkf_noise.notch_depth`)."""
    nd, k = f_ord.shape
    frames, bins = starts.shape[0], freq.shape[0]
    df = float(freq[1] - freq[0]) if bins > 1 else fs_d
    offsets = (np.arange(3) + 0.5) / 3.0 * length
    weights = np.interp(offsets, np.arange(length), win ** 2)
    weights = weights / weights.sum()
    # H(ν) = 1/(1 + c (2ν/B)^{2p}) reaches 1e-3 at ν = reach · B
    reach_per_hz = 0.5 * ((1e3 - 1.0) / (np.sqrt(2.0) - 1.0)) ** (1.0 / (2 * p))
    if _vkf_noise.accelerated():
        return _vkf_noise.notch_depth(f_ord, bw_d, starts, offsets, weights, bins, df,
                                        trend_hz, fs_d, p, reach_per_hz)
    # every line at once (each order and its mirror, the trend's positive side) at each of the
    # 3 instants: the product of the (1 - H)² factors of one (instant, frame, bin) as the exp
    # of a sum of logs (one bincount, not a Python loop of small multiply.at scatters)
    order_of = np.repeat(np.arange(k), 2)
    signs = np.tile([1.0, -1.0], k)
    if trend_hz > 0:
        order_of = np.append(order_of, k)
        signs = np.append(signs, 1.0)
    if order_of.shape[0] == 0:
        return np.ones((frames, bins))
    grid = np.arange(nd)
    at = np.clip(starts[None, :] + offsets[:, None], 0, nd - 1)            # (3, frames)
    lines = order_of.shape[0]
    centres = np.zeros((3, lines, frames))
    band = np.full((3, lines, frames), float(trend_hz))
    for m in range(k):
        c = np.interp(at, grid, f_ord[:, m])
        b = np.maximum(np.interp(at, grid, bw_d[:, m]), 1e-12)
        centres[:, 2 * m], centres[:, 2 * m + 1] = c, -c
        band[:, 2 * m] = band[:, 2 * m + 1] = b
    r2 = vkf_weight(band, fs_d, p) ** 2
    span = np.ceil(reach_per_hz * band.max(axis=2) / df).astype(np.int64) + 1   # (3, lines)
    first = np.floor((centres - reach_per_hz * band) / df).astype(np.int64)
    t = np.arange(2 * int(span.max()) + 1)
    cols = first[..., None] + t                                     # (3, lines, frames, T)
    valid = (cols >= 0) & (cols < bins) & (t <= 2 * span[:, :, None, None])
    nu = cols * df - centres[..., None]
    h = 1.0 / (1.0 + 2.0 * r2[..., None] * (2.0 * np.sin(np.pi * nu / fs_d)) ** (2 * p))
    with np.errstate(divide="ignore"):
        log_factor = np.where(valid, 2.0 * np.log(np.abs(1.0 - h)), 0.0)
    inst = np.arange(3)[:, None, None, None]
    row = np.arange(frames)[None, None, :, None]
    flat = ((inst * frames + row) * bins + np.clip(cols, 0, bins - 1)).ravel()
    logs = np.bincount(flat, weights=log_factor.ravel(), minlength=3 * frames * bins)
    depth = np.tensordot(weights, np.exp(logs.reshape(3, frames, bins)), axes=1)
    return np.where(depth >= 0.25, depth, np.nan)
