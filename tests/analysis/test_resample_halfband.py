"""The half-band decimation stages in front of the anti-alias FFT (issue 13/21: the order map's
FFT then runs on a quarter or half of the samples): the filter's response against its stated
bands (evaluated independently as a DTFT on a dense grid), the compiled and numpy kernels against
a direct convolution, and the plan choosing stages only where the output rate allows."""

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


def test_plan_uses_stages_only_where_the_output_rate_allows():
    """1000→3000 rpm at 20 kHz, 64 samples/rev: stop edges 800 and 1600 Hz, output rates 3.2
    and 6.4 kHz: two stages (to 5 kHz) and one (to 10 kHz); cubic keeps the full rate."""
    fs = 20_000.0
    rpm = 1000.0 + 2000.0 * np.arange(200_000) / 200_000
    plan = plan_chunks(rpm, n=rpm.size, fs=fs)
    assert plan.halfband_stages == (2, 1)
    for (nfft, n_out), s, (_, f_stop) in zip(plan.lengths, plan.halfband_stages, plan.bands):
        assert nfft % (1 << s) == 0 and n_out <= nfft >> s
        assert f_stop <= fs / (1 << (s + 2))
    assert plan_chunks(rpm, n=rpm.size, fs=fs, interpolation="cubic").halfband_stages == (0, 0)
    # a 2.5 s record: the stages' margin (15·(2^s − 1) samples at either end) may take 0.1 %
    # of it at most (50 samples): one stage for the second chunk, none for the first
    short = 1000.0 + 2000.0 * np.arange(50_000) / 50_000
    assert plan_chunks(short, n=short.size, fs=fs).halfband_stages == (0, 1)


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
