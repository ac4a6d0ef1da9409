"""The VKF kernels (analysis._vkf_kernels): each against an independent reference (dense
normal equations, dense solve, the filter's own frequency response, np.percentile), and the
compiled forms against the numpy/SciPy twins on the same small records.

The numpy forms run by clearing the kernel cache with ``CRANKBENCH_NO_NUMBA`` set (as
tests/analysis/test_kernels.py does); without numba installed only the numpy forms exist and
the comparisons skip.
"""

import numpy as np
import pytest

from crankbench.analysis import _vkf_kernels as kern
from crankbench.analysis import _vkf_noise as noise_kern
from crankbench.analysis import vkf
from crankbench.analysis.resample import shaft_angle
from crankbench.predict.errors import AnalysisError


def _clear():
    kern._numba.cache_clear()
    noise_kern._numba.cache_clear()


def _numpy_forms(monkeypatch):
    monkeypatch.setenv("CRANKBENCH_NO_NUMBA", "1")
    _clear()
    assert not kern.accelerated() and not noise_kern.accelerated()


def _both(monkeypatch, call):
    """(numpy result, compiled result) of ``call()``; skips without numba."""
    pytest.importorskip("numba")
    _numpy_forms(monkeypatch)
    plain = call()
    monkeypatch.delenv("CRANKBENCH_NO_NUMBA")
    _clear()
    assert kern.accelerated() and noise_kern.accelerated()
    compiled = call()
    _clear()
    return plain, compiled


@pytest.fixture(params=["numpy", "compiled"])
def form(request, monkeypatch):
    """Run a test on both forms (the compiled one only when numba is installed)."""
    if request.param == "numpy":
        _numpy_forms(monkeypatch)
    else:
        pytest.importorskip("numba")
        monkeypatch.delenv("CRANKBENCH_NO_NUMBA", raising=False)
        _clear()
        assert kern.accelerated() and noise_kern.accelerated()
    yield request.param
    _clear()


def _small_system(n=203, k=2, m=5, p=2, trend=True, seed=4):
    rng = np.random.default_rng(seed)
    phase = np.cumsum(rng.uniform(0.2, 0.9, (n, k)), axis=0)
    cols = 2 * k + (1 if trend else 0)
    n_coef = n if m == 1 else (n - 1) // m + 4
    weights = rng.uniform(0.5, 3.0, (n_coef - p, cols))
    return rng.normal(size=n), np.cos(phase), np.sin(phase), weights, n_coef, cols


def _dense_reference(x, cosp, sinp, weights, n_coef, cols, m, p, trend):
    """CᵀC + Σ r² D_pᵀ D_p and Cᵀx built densely, column by column of the definition."""
    n, k = cosp.shape
    basis = np.empty((n, cols))
    basis[:, 0:2 * k:2] = cosp
    basis[:, 1:2 * k:2] = -sinp
    if trend:
        basis[:, -1] = 1.0
    design = np.zeros((n, n_coef * cols))
    for i in range(n):
        if m == 1:
            knots, w = [i], [1.0]
        else:
            g, f = divmod(i, m)
            f /= m
            knots = range(g, g + 4)        # uniform cubic B-spline, de Boor's closed form
            w = [(1 - f) ** 3 / 6, (3 * f ** 3 - 6 * f ** 2 + 4) / 6,
                 (-3 * f ** 3 + 3 * f ** 2 + 3 * f + 1) / 6, f ** 3 / 6]
        for c, wc in zip(knots, w):
            design[i, c * cols:(c + 1) * cols] = wc * basis[i]
    a = design.T @ design
    diff = {1: [-1.0, 1.0], 2: [1.0, -2.0, 1.0]}[p]
    for j in range(cols):
        d = np.zeros((n_coef - p, n_coef * cols))
        for r in range(n_coef - p):
            for t, c in enumerate(diff):
                d[r, (r + t) * cols + j] = c
        a += d.T @ (weights[:, j:j + 1] * d)
    return a, design.T @ x


def _dense(band):
    size, w1 = band.shape
    a = np.zeros((size, size))
    for d in range(w1):
        idx = np.arange(size - d)
        a[idx + d, idx] = band[: size - d, d]
        a[idx, idx + d] = band[: size - d, d]
    return a


@pytest.mark.parametrize("m, p, trend", [(5, 2, True), (1, 2, True), (4, 1, False)])
def test_assembly_equals_the_dense_normal_equations(form, m, p, trend):
    x, cosp, sinp, weights, n_coef, cols = _small_system(m=m, p=p, trend=trend)
    if not trend:
        weights = weights[:, :cols]
    band, rhs = kern.assemble(x, cosp, sinp, trend, m, n_coef, p, weights)
    a_ref, rhs_ref = _dense_reference(x, cosp, sinp, weights, n_coef, cols, m, p, trend)
    assert band.shape == (n_coef * cols, kern.band_width(cols, m, p) + 1)
    np.testing.assert_allclose(_dense(band), a_ref, rtol=0, atol=1e-12 * np.abs(a_ref).max())
    np.testing.assert_allclose(rhs, rhs_ref, rtol=0, atol=1e-12 * np.abs(rhs_ref).max())


def test_banded_solve_matches_a_dense_solve_and_refuses_indefinite(form):
    x, cosp, sinp, weights, n_coef, cols = _small_system()
    band, rhs = kern.assemble(x, cosp, sinp, True, 5, n_coef, 2, weights)
    z = kern.solve(band, rhs)
    ref = np.linalg.solve(_dense(band), rhs)
    np.testing.assert_allclose(z, ref, rtol=0, atol=1e-10 * np.abs(ref).max())
    bad = band.copy()
    bad[7, 0] = -1.0
    with pytest.raises(kern.NotPositiveDefinite):
        kern.solve(bad, rhs)


@pytest.mark.parametrize("fs, f_max, stages", [(20_000.0, 225.5, 2), (5000.0, 60.0, 2),
                                               (48_000.0, 100.0, 2), (20_000.0, 900.0, 1)])
def test_decimator_response_is_flat_and_rejects_aliases(fs, f_max, stages):
    """The FIR cascade's own frequency response (each stage Σ h cos(2π f n/f_s), folded at
    each stage's output rate): pass band [0, f_max] flat to 1e-5, everything that lands in
    the output band [0, fs/2q] from elsewhere attenuated below 1e-5 (100 dB), as _decimate
    documents."""
    q = int(fs // (4 * f_max))
    design = vkf._decimator(fs, f_max, q)
    assert np.prod([s for s, _ in design]) == q and len(design) == stages
    f = np.linspace(0.0, fs / 2, 100_001)
    gain = np.ones_like(f)
    folded, rate = f.copy(), fs
    for qs, h in design:
        gain *= np.abs(_response(h, folded, rate))
        rate /= qs
        folded = np.abs(folded - rate * np.round(folded / rate))       # alias at the new rate
    passband = f <= f_max
    assert np.abs(gain[passband] - 1).max() < 1e-5
    aliased = (folded <= 0.5 * rate) & (f > 0.5 * rate)
    assert aliased.any() and gain[aliased].max() < 1e-5


def _response(h, f, rate):
    """Zero-phase response of the symmetric FIR ``h`` at frequencies ``f`` (chunked)."""
    n = np.arange(h.shape[0]) - h.shape[0] // 2
    out = np.empty(f.shape[0])
    for i in range(0, f.shape[0], 20_000):
        out[i:i + 20_000] = np.cos(2 * np.pi * np.outer(f[i:i + 20_000], n) / rate) @ h
    return out


def test_decimation_keeps_a_tone_and_its_timing(form):
    """A tone inside the pass band comes through at the output's sample times (zero phase)."""
    fs = 20_000.0
    t = np.arange(60_000) / fs
    x = np.cos(2 * np.pi * 180.0 * t + 0.4)
    y, index, fs_d = vkf._decimate(x, fs, 225.5)
    assert fs_d == fs / 22
    np.testing.assert_allclose(y, x[index], rtol=0, atol=2e-5)


def test_lower_quartiles_match_numpy_percentile(form):
    """Bins beside each frame's own line, NaN bins (a notch) left out, as numpy reads them."""
    rng = np.random.default_rng(7)
    spec = rng.exponential(size=(6, 300))
    freq = np.linspace(0.0, 150.0, 300)
    flat = (freq > 0) & (freq < 120.0)
    f_frame = np.array([10.0, 50.0, 119.0, 300.0, 60.0, 0.5])
    spec[4, np.abs(freq - 64.0) < 5.0] = np.nan       # another order's notch beside frame 4's
    spec[:, freq < 3.0] = np.nan                      # order 0's
    got = noise_kern.lower_quartiles(spec, freq, flat, f_frame, 20.0)
    for i, f0 in enumerate(f_frame):
        ok = flat & ~np.isnan(spec[i])
        near = ok & (np.abs(freq - f0) <= 20.0)
        near = near if near.sum() >= 5 else ok
        assert got[i] == pytest.approx(np.percentile(spec[i, near], 25), rel=1e-14)
    assert np.isfinite(got).all()


@pytest.mark.parametrize("frames", [1, 7])
def test_local_levels_compiled_equals_numpy(monkeypatch, frames):
    """Per-frame quartiles beside each order, interpolated to every sample (np.interp both
    ways in the numpy form; one frame: constant)."""
    rng = np.random.default_rng(2)
    nd, bins = 3000, 257
    spec = rng.exponential(size=(frames, bins))
    spec[:, 40:44] = np.nan
    freq = np.linspace(0.0, 128.0, bins)
    flat = (freq > 0) & (freq < 110.0)
    centre = 256.0 + 400.0 * np.arange(frames) + 0.5
    f_ord = np.stack([np.linspace(10.0, 30.0, nd), np.linspace(45.0, 95.0, nd)], axis=1)
    reach = np.array([6.0, 12.0])
    plain, compiled = _both(monkeypatch, lambda: noise_kern.local_levels(spec, freq, flat, centre,
                                                                   f_ord, reach))
    assert plain.shape == (nd, 2) and np.isfinite(plain).all()
    np.testing.assert_allclose(compiled, plain, rtol=1e-14, atol=0)
    if frames > 1:            # the first and last frames' levels held beyond their centres
        f0 = np.interp(centre[:1], np.arange(nd), f_ord[:, 0])
        first = noise_kern.lower_quartiles(spec, freq, flat, f0, 6.0)[0] / np.log(4 / 3)
        assert plain[0, 0] == pytest.approx(first, rel=1e-14)


def _notch_case(p, trend_hz, sweep=True):
    nd, fs_d, length = 5000, 500.0, 1024
    rpm = np.linspace(1000.0, 3000.0, nd) if sweep else np.full(nd, 1500.0)
    orders = np.array([1.0, 2.0, 4.5])
    f_ord = orders[None, :] * rpm[:, None] / 60.0
    bw = np.full((nd, 3), 0.5)
    if sweep:
        bw[1500:3500, 2] = np.linspace(0.5, 4.0, 2000)      # an adaptive band widened
    starts = np.arange(0, nd - length + 1, length // 2)
    win = np.hanning(length + 1)[:length]
    freq = np.fft.rfftfreq(length, 1.0 / fs_d)
    return (f_ord, starts, length, win, freq, bw, trend_hz, fs_d, p)


@pytest.mark.parametrize("p", [1, 2])
def test_notch_depth_is_the_filter_response_on_a_steady_record(form, p):
    """At constant speed and band every instant of a frame sees the same lines: the depth is
    ∏ (1 − H(ν − f_m))² over the orders, their mirrors and the trend, H the envelope
    response 1/(1 + 2 r² (2 sin(πν/fs))^{2p}) of ``vkf_weight`` (NaN below 1/4)."""
    case = _notch_case(p, 0.3, sweep=False)
    f_ord, freq, bw, fs_d = case[0], case[4], case[5], case[7]
    depth = vkf._notch_depth(*case)

    def gain(nu, b):
        return 1.0 / (1.0 + 2.0 * vkf.vkf_weight(b, fs_d, p) ** 2
                      * (2.0 * np.sin(np.pi * nu / fs_d)) ** (2 * p))

    expect = np.ones_like(freq)
    for c, b in [(f, 0.5) for f in f_ord[0]] + [(-f, 0.5) for f in f_ord[0]] + [(0.0, 0.3)]:
        expect *= (1.0 - gain(freq - c, b)) ** 2          # every bin (the code: H ≥ 1e-3)
    expect = np.where(expect >= 0.25, expect, np.nan)
    assert np.isnan(depth).any() and (depth[np.isfinite(depth)] < 0.99).any()
    for row in depth:
        np.testing.assert_array_equal(np.isnan(row), np.isnan(expect))
        ok = np.isfinite(expect)
        # each line's factor is cut where it is within 2e-3 of 1 (two tails may overlap)
        np.testing.assert_allclose(row[ok], expect[ok], rtol=0, atol=2e-3 if p == 2 else 4e-3)


@pytest.mark.parametrize("p, trend_hz", [(1, 0.0), (2, 0.3)])
def test_notch_depth_compiled_equals_numpy(monkeypatch, p, trend_hz):
    """A sweep with a band widened in time (the compiled per-frame form against the numpy
    scatter of log factors): equal to rounding, NaN at the same bins."""
    case = _notch_case(p, trend_hz)
    plain, compiled = _both(monkeypatch, lambda: vkf._notch_depth(*case))
    np.testing.assert_array_equal(np.isnan(plain), np.isnan(compiled))
    ok = np.isfinite(plain)
    assert (plain[ok] < 0.9).sum() > 50
    np.testing.assert_allclose(compiled[ok], plain[ok], rtol=1e-13, atol=1e-15)


def test_compiled_and_numpy_forms_agree_on_a_record(monkeypatch):
    """The whole filter (decimation, assembly, solve, envelopes, noise and smearing) on a
    small run-up with noise: compiled and numpy forms agree to rounding."""
    fs = 4000.0
    t = np.arange(int(6 * fs)) / fs
    rpm = 900 + 150 * t
    phi = shaft_angle(rpm, fs)
    x = ((1 + 0.3 * np.sin(1.3 * t)) * np.cos(2 * phi + 0.2) + 0.4 * np.cos(3.5 * phi) + 2.0
         + np.random.default_rng(1).normal(0, 0.05, t.size))

    def run():
        knots = vkf.vold_kalman(x, fs=fs, speed_rpm=rpm, orders=[2, 3.5], bandwidth_hz=1.5)
        classical = vkf.vold_kalman(x[:3000], fs=fs, speed_rpm=rpm[:3000], orders=[2],
                                    bandwidth_hz=20.0, decimate=False, filter_order=1,
                                    knots_per_bandwidth=None)
        return knots, classical

    plain, compiled = _both(monkeypatch, run)
    for a, b in zip(plain, compiled):
        assert a.attrs["solve_rate_hz"] == b.attrs["solve_rate_hz"]
        scale = float(np.abs(a.envelope).max())
        np.testing.assert_allclose(b.envelope, a.envelope, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(b["mean"], a["mean"], rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(b.amplitude_noise, a.amplitude_noise, rtol=1e-9)
        np.testing.assert_allclose(b.amplitude_uncertainty, a.amplitude_uncertainty,
                                   rtol=1e-7, atol=1e-12 * scale)
    knots = plain[0]
    assert knots.attrs["decimation"] > 1 and knots.attrs["knot_spacing_samples"] > 1
    # and both are right: order 3.5 at 0.4 and the trend at 2.0 mid-record, within a few
    # noise sigmas (0.05 rms at 4 kHz through ENBW 1.04·1.5 Hz: σ ≈ 1.4e-3)
    mid = slice(knots.time.size // 4, 3 * knots.time.size // 4)
    assert np.abs(np.abs(knots.envelope[1].values[mid]) - 0.4).max() < 6e-3
    assert np.abs(knots["mean"].values[mid] - 2.0).max() < 6e-3


def test_not_positive_definite_is_our_error(monkeypatch):
    def refuse(band, rhs):
        raise kern.NotPositiveDefinite("pivot 0 is not positive")

    monkeypatch.setattr(kern, "solve", refuse)
    x = np.cos(np.arange(4000) * 0.02)
    with pytest.raises(AnalysisError, match="not positive definite; the bandwidth is too narrow"):
        vkf.vold_kalman(x, fs=1000.0, speed_rpm=191.0, orders=[1], bandwidth_hz=1.0)


def test_order_basis_matches_numpy_cos_and_sin(form):
    """cos/sin of o·φ: the compiled reduction + Taylor form within 4e-16 of np.cos/np.sin up
    to the largest phase it takes (|o φ| < 2^20 rad), and numpy beyond."""
    phi = np.concatenate([np.linspace(0.0, 7.0e5, 200_001), [-3.3, 1e-300]])
    orders = np.array([0.5, 1.0, 1.5, 2.5])
    cos, sin = kern.order_basis(phi, orders)
    phase = np.multiply.outer(phi, orders)
    assert cos.shape == sin.shape == (phi.size, orders.size)
    np.testing.assert_allclose(cos, np.cos(phase), rtol=0, atol=4e-16)
    np.testing.assert_allclose(sin, np.sin(phase), rtol=0, atol=4e-16)
    far = np.array([0.0, 4.0e6])                       # beyond BASIS_MAX_PHASE: numpy
    np.testing.assert_array_equal(kern.order_basis(far, orders)[0], np.cos(np.multiply.outer(
        far, orders)))
