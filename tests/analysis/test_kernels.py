"""The compiled resampling kernels (numba, ``crankbench[fast]``) give the numpy twins' results.

Both forms are run in the same process: the numpy form by clearing the kernel cache with
``CRANKBENCH_NO_NUMBA`` set, the compiled one with it unset. Without numba installed the whole
module skips (then only the numpy forms exist, and every other test runs on them).
"""

import numpy as np
import pytest

pytest.importorskip("numba")

from crankbench.analysis import _kernels  # noqa: E402
from crankbench.analysis import resample  # noqa: E402


def _both(monkeypatch, call):
    """(numpy result, compiled result) of ``call()``."""
    monkeypatch.setenv("CRANKBENCH_NO_NUMBA", "1")
    _kernels._numba.cache_clear()
    assert not _kernels.accelerated()
    plain = call()
    monkeypatch.delenv("CRANKBENCH_NO_NUMBA")
    _kernels._numba.cache_clear()
    assert _kernels.accelerated()
    compiled = call()
    _kernels._numba.cache_clear()
    return plain, compiled


def test_speed_integration_and_angle_inversion_agree(monkeypatch):
    rng = np.random.default_rng(3)
    speed = 1500 + 300 * np.sin(np.linspace(0, 7, 20_001)) + rng.normal(0, 2, 20_001)
    fs = 10_000.0
    plain, compiled = _both(monkeypatch, lambda: _kernels.integrate_speed(speed, fs, 0.25))
    # trapezoid closed form for the first steps: phi[1] = start + (w0 + w1)/2 / fs (rad)
    w = speed * 2 * np.pi / 60
    assert plain[1] == pytest.approx(0.25 + 0.5 * (w[0] + w[1]) / fs, rel=1e-14)
    np.testing.assert_allclose(compiled, plain, rtol=1e-13, atol=1e-9)
    targets = np.linspace(plain[0], plain[-1], 5_001)[1:-1]
    plain_pos, compiled_pos = _both(monkeypatch, lambda: _kernels.positions(plain, targets, 7))
    np.testing.assert_allclose(compiled_pos, plain_pos, rtol=0, atol=1e-9)
    values = np.cos(np.arange(speed.size) * 0.01)
    plain_v, compiled_v = _both(monkeypatch, lambda: _kernels.lerp(values, plain_pos, 7))
    np.testing.assert_allclose(compiled_v, plain_v, rtol=0, atol=1e-12)


def test_positions_and_speed_in_one_pass_agree(monkeypatch):
    """The fused inversion + speed interpolation gives the two separate kernels' results, and a
    speed linear in the sample index is read exactly at the positions (closed form)."""
    rng = np.random.default_rng(8)
    fs = 8_000.0
    speed = 900 + 0.05 * np.arange(30_001) + rng.normal(0, 1, 30_001)
    phi = _kernels.integrate_speed(speed, fs, 0.0)
    targets = np.concatenate([[phi[0] - 1.0], np.linspace(phi[0], phi[-1], 4_001),
                              [phi[-1] + 1.0]])
    ramp = 3.0 + 0.5 * np.arange(speed.size)          # linear: lerp is exact
    for values in (speed, ramp):
        plain, compiled = _both(monkeypatch, lambda: _kernels.positions_and_values(
            phi, targets, 11, values))
        separate = (_kernels.positions(phi, targets, 11),)
        separate += (_kernels.lerp(values, separate[0], 11),)
        for got in (plain, compiled):
            np.testing.assert_allclose(got[0], separate[0], rtol=0, atol=1e-9)
            np.testing.assert_allclose(got[1], separate[1], rtol=1e-13, atol=1e-12)
    pos, at = _kernels.positions_and_values(phi, targets, 11, ramp)
    np.testing.assert_allclose(at, 3.0 + 0.5 * (pos - 11), rtol=1e-14)
    assert pos[0] == 11 and pos[-1] == 11 + speed.size - 1     # clamped outside the angle span


def test_band_limited_interpolation_agrees_and_is_accurate(monkeypatch):
    n = 4_000
    t = np.arange(n)
    u = np.sort(np.random.default_rng(5).uniform(40, n - 40, 3_000))
    for f in (0.0731, 0.2, 0.249):               # cycles per sample, up to a quarter of the rate
        x = np.sin(2 * np.pi * f * t + 0.3)
        plain, compiled = _both(monkeypatch, lambda: resample._interp(x, u, "sinc"))
        np.testing.assert_allclose(compiled, plain, rtol=0, atol=1e-13)
        # against the sine itself: the kernel's documented error, <= 5e-6 up to fs/4
        # (analysis/resample.py, _SINC_BETA)
        assert np.max(np.abs(plain - np.sin(2 * np.pi * f * u + 0.3))) <= 5e-6
