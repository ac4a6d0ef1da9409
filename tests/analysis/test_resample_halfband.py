"""The half-band decimation stages in front of the anti-alias FFT (issue 13/21: the order map's
FFT then runs on a quarter or half of the samples): the filter's response against its stated
bands (evaluated independently as a DTFT on a dense grid), the compiled and numpy kernels against
a direct convolution, and the plan choosing stages while the orders it must keep clean stay
in their pass band."""

import numpy as np
import pytest

from crankbench.analysis import _kernels
from crankbench.analysis.resample import _halfband_taps, plan_chunks


def _full_taps():
    odd = _halfband_taps()
    h = np.zeros(31)
    h[15] = 0.5
    h[16::2] = odd
    h[14::-2] = odd
    return h


def test_halfband_response_meets_its_stated_bands():
    """Pass band [0, fs/8] within 1.7e-7 of 1 and stop band [3fs/8, fs/2] below 1.7e-7 (the
    figure in analysis.resample), even taps 0 (half-band)."""
    h = _full_taps()
    n = np.arange(31) - 15
    f = np.linspace(0.0, 0.5, 40001)
    resp = np.exp(-2j * np.pi * np.outer(f, n)) @ h
    assert np.abs(resp.imag).max() < 1e-14              # symmetric: zero phase
    assert np.abs(resp[f <= 0.125].real - 1.0).max() <= 1.7e-7
    assert np.abs(resp[f >= 0.375]).max() <= 1.7e-7
    assert np.all(h[(n % 2 == 0) & (n != 0)] == 0.0)


@pytest.mark.parametrize("n", [1, 2, 3, 16, 17, 31, 32, 33, 101, 1000])
def test_halfband_kernels_match_a_direct_convolution(n, monkeypatch):
    x = np.random.default_rng(n).normal(size=n)
    h = _full_taps()
    want = np.convolve(x, h)[15:15 + n][::2]          # zero outside x, every second output
    got = _kernels.halfband_decimate(x, _halfband_taps())
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)
    monkeypatch.setenv("CRANKBENCH_NO_NUMBA", "1")
    _kernels._numba.cache_clear()
    try:
        plain = _kernels.halfband_decimate(x, _halfband_taps())
    finally:
        monkeypatch.delenv("CRANKBENCH_NO_NUMBA")
        _kernels._numba.cache_clear()
    np.testing.assert_allclose(plain, want, rtol=0, atol=1e-14)


def test_plan_uses_stages_while_the_clean_orders_stay_in_their_pass_band():
    """1000→3000 rpm at 20 kHz, 64 samples/rev: orders up to 16 at the chunks' top speeds
    (2000 and 3000 rpm) lie at 533 and 800 Hz, which a stage leaves flat and unfolded while it
    is within a quarter of the rate it leaves: 3 stages (to 2.5 kHz) and 2 (to 5 kHz), their
    margin (15·(2^s − 1) samples at either end: 210 of 200 000 for 3) within the 0.25 % rule.
    The output rates (4 samples per period of the 800 and 1600 Hz stop edges: 3.2 and 6.4
    kHz) may exceed the stages' rate (the FFT zero pads); cubic keeps the full rate. A map
    showing orders to 32 (1067 and 1600 Hz) takes 2 and 1; shorter records fewer."""
    fs = 20_000.0
    rpm = 1000.0 + 2000.0 * np.arange(200_000) / 200_000
    plan = plan_chunks(rpm, n=rpm.size, fs=fs)
    assert plan.halfband_stages == (3, 2)
    for (nfft, n_out), s, (lo, hi) in zip(plan.lengths, plan.halfband_stages,
                                          [(1000.0, 2000.0), (2000.0, 3000.0)]):
        assert nfft % (1 << s) == 0
        assert 16 * hi / 60.0 <= fs / (1 << (s + 2))
        assert n_out / nfft * fs == pytest.approx(4 * 48 * lo / 60.0, rel=0.08)
    assert plan.lengths[1][1] > plan.lengths[1][0] >> 2            # zero padded: 32768 > 25600
    assert plan_chunks(rpm, n=rpm.size, fs=fs, interpolation="cubic").halfband_stages == (0, 0)
    assert plan_chunks(rpm, n=rpm.size, fs=fs, clean_order=32).halfband_stages == (2, 1)
    longer = 1000.0 + 2000.0 * np.arange(400_000) / 400_000
    assert plan_chunks(longer, n=longer.size, fs=fs).halfband_stages == (3, 2)
    # a 2.5 s record: the stages' margin may take 0.25 % of it at most (125 samples): two
    # stages (90), not three (210); a 1 s record one (30 of 50), a 0.5 s record none (30 > 25)
    short = 1000.0 + 2000.0 * np.arange(50_000) / 50_000
    assert plan_chunks(short, n=short.size, fs=fs).halfband_stages == (2, 2)
    second = 1000.0 + 2000.0 * np.arange(20_000) / 20_000
    assert plan_chunks(second, n=second.size, fs=fs).halfband_stages == (1, 1)
    half = 1000.0 + 2000.0 * np.arange(10_000) / 10_000
    assert plan_chunks(half, n=half.size, fs=fs).halfband_stages == (0, 0)


def test_fft_lowpass_upsamples_exactly_past_the_stages_rate():
    """Two stages take 20 kHz to 5 kHz; the output at 6.4 kHz (more samples than the stages
    leave) is the zero-padded spectrum's inverse: a tone in the pass band comes out as the
    tone at the output instants (closed form) within the filter's ripple, 1e-5."""
    from crankbench.analysis.antialias import _fft_lowpass

    fs, nfft, n_out = 20_000.0, 102_400, 32_768
    t = np.arange(nfft) / fs
    for f in (50.0, 433.0, 790.0):
        x = np.cos(2 * np.pi * f * t + 0.4)
        y = _fft_lowpass(x, fs, 800.0, 1600.0, nfft, n_out, stages=2)
        t_out = np.arange(n_out) * (nfft / n_out) / fs
        inner = slice(400, n_out - 400)                 # the filter's incomplete ends
        np.testing.assert_allclose(y[inner], np.cos(2 * np.pi * f * t_out[inner] + 0.4),
                                   rtol=0, atol=1e-5)


@pytest.mark.parametrize("speed", ["runup", "steady", "wobbly"])
@pytest.mark.parametrize("compiled", [True, False])
def test_angle_grid_matches_integration_and_inverse_interpolation(speed, compiled, monkeypatch):
    """The fused pass (integration + positions of the angle samples + speed there) against
    the separate steps it replaces: the trapezoidal angle, and numpy.interp inverting it."""
    from crankbench.analysis._kernels import angle_grid

    fs, n = 5000.0, 20_000
    t = np.arange(n) / fs
    rpm = {"runup": 600.0 + 300.0 * t, "steady": np.full(n, 1500.0),
           "wobbly": 1200.0 + 40.0 * np.sin(2 * np.pi * 3.0 * t)}[speed]
    dphi = 2 * np.pi / 32
    first, last = 37, n - 41
    if not compiled:
        monkeypatch.setenv("CRANKBENCH_NO_NUMBA", "1")
    _kernels._numba.cache_clear()
    try:
        phi, j0, pos, at = angle_grid(rpm, fs, dphi, first, last)
    finally:
        monkeypatch.delenv("CRANKBENCH_NO_NUMBA", raising=False)
        _kernels._numba.cache_clear()
    inc = (rpm[1:] + rpm[:-1]) * (np.pi / (60.0 * fs))
    want_phi = np.concatenate([[0.0], np.cumsum(inc)])
    np.testing.assert_allclose(phi, want_phi, rtol=1e-12, atol=1e-9)
    j1 = int(np.floor(phi[last] / dphi))
    assert j0 == int(np.ceil(phi[first] / dphi)) and pos.shape[0] == j1 - j0 + 1
    grid = np.arange(j0, j1 + 1) * dphi
    want_pos = np.interp(grid, phi, np.arange(n, dtype=float))
    np.testing.assert_allclose(pos, want_pos, rtol=0, atol=1e-9)
    np.testing.assert_allclose(at, np.interp(grid, phi, rpm), rtol=1e-12)


def test_span_extremes_equal_a_direct_reduction():
    """The plan's span extremes from block extremes (analysis.speed_spans.SpanExtremes) equal
    numpy's min and max of the span itself, for spans inside one block, across blocks and
    at the record's ends; NaN propagates."""
    from crankbench.analysis.speed_spans import SpanExtremes

    rng = np.random.default_rng(4)
    v = rng.normal(1500.0, 300.0, 10_007)
    ext = SpanExtremes(v, block=1000)
    assert ext.limits() == (v.min(), v.max())
    spans = [(0, 10_007), (3, 17), (999, 1001), (1000, 2000), (1500, 9_999), (9_000, 10_007)]
    spans += [tuple(sorted(rng.integers(0, 10_008, 2))) for _ in range(200)]
    for a, b in spans:
        if b > a:
            assert ext(a, b) == (v[a:b].min(), v[a:b].max()), (a, b)
    v[4321] = np.nan
    ext = SpanExtremes(v, block=1000)
    assert np.isnan(ext(4000, 5000)[0]) and ext(0, 4000) == (v[:4000].min(), v[:4000].max())


def test_the_stop_edge_stays_within_the_stages_nyquist_frequency():
    """A steady 1500 rpm record at 8 kHz: the FFT low-pass stops from 1200 Hz (order 48), above
    the 1 kHz Nyquist frequency two stages would leave; what they folded there (the window
    ends' transients) stayed in the spectrum's top bin and the zero padded transform spread it
    over the whole record: the angle samples of orders 2 and 12 read 3.4e-4 off (60 s). One
    stage now; every chunk's stop edge within its stages' Nyquist frequency; the samples within
    the interpolator's documented 5e-6 of the closed form."""
    from crankbench.analysis.resample import angle_resample, shaft_angle

    fs = 8000.0
    rpm = np.full(int(60 * fs), 1500.0)
    phi = shaft_angle(rpm, fs)
    plan = plan_chunks(rpm, n=rpm.size, fs=fs)
    assert plan.halfband_stages == (1, 1)
    for (f_pass, f_stop), s in zip(plan.bands, plan.halfband_stages):
        assert f_stop <= fs / 2 ** (s + 1)
    y = angle_resample(np.cos(2 * phi) + 0.3 * np.sin(12 * phi), fs=fs, speed_rpm=rpm)
    a = y.angle.values
    assert np.abs(y.values - (np.cos(2 * a) + 0.3 * np.sin(12 * a))).max() < 5e-6
