"""The iterative (block-preconditioned conjugate gradients) VKF solve: against the direct
banded Cholesky on the same normal equations, against analytic envelopes, on close orders,
and its fall-back when it does not converge."""

import logging

import numpy as np
import pytest

from crankbench.analysis import _vkf_kernels as kern
from crankbench.analysis import vkf_iterative
from crankbench.analysis.resample import shaft_angle
from crankbench.analysis.vkf import vold_kalman
from crankbench.predict.errors import AnalysisError


@pytest.fixture(params=["numpy", "compiled"])
def form(request, monkeypatch):
    """Both forms (the compiled one only with numba installed)."""
    if request.param == "numpy":
        monkeypatch.setenv("CRANKBENCH_NO_NUMBA", "1")
    else:
        pytest.importorskip("numba")
        monkeypatch.delenv("CRANKBENCH_NO_NUMBA", raising=False)
    kern._numba.cache_clear()
    vkf_iterative._numba.cache_clear()
    yield request.param
    kern._numba.cache_clear()
    vkf_iterative._numba.cache_clear()


def _system(n=1500, k=3, m=5, p=2, trend=True, seed=4):
    rng = np.random.default_rng(seed)
    phase = np.cumsum(rng.uniform(0.2, 0.9, (n, 1)), axis=0) * np.arange(1, k + 1)
    cols = 2 * k + (1 if trend else 0)
    n_coef = n if m == 1 else (n - 1) // m + 4
    weights = rng.uniform(0.5, 3.0, (n_coef - p, cols)) * 1e3
    return rng.normal(size=n), np.cos(phase), np.sin(phase), weights, n_coef, cols


@pytest.mark.parametrize("m, p, trend, group", [(5, 2, True, 2), (1, 2, True, 1),
                                                (4, 1, False, 4), (7, 2, True, 3)])
def test_pcg_solves_the_same_normal_equations_as_the_banded_cholesky(form, m, p, trend,
                                                                    group):
    x, cosp, sinp, weights, n_coef, cols = _system(m=m, p=p, trend=trend)
    weights = weights[:, :cols]
    band, rhs = kern.assemble(x, cosp, sinp, trend, m, n_coef, p, weights)
    direct = kern.solve(band, rhs).reshape(n_coef, cols)
    z, iterations = vkf_iterative.solve(x, cosp, sinp, trend, m, n_coef, p, weights,
                                        orders=[1.0, 2.0, 3.0], group=group)
    if group >= 3:                    # one group holds every column: the block solve is exact
        assert iterations == 0
    else:
        assert 0 < iterations < vkf_iterative.MAX_ITERATIONS
    np.testing.assert_allclose(z, direct, rtol=0, atol=1e-8 * np.abs(direct).max())


def _close_orders_runup(fs=2000.0, seconds=6.0):
    """Orders 2 and 2.5 (8.3 Hz apart at 1000 rpm: 4 bandwidths of 2 Hz) with analytic
    envelopes, plus order 1 and a mean."""
    t = np.arange(int(seconds * fs)) / fs
    rpm = 1000.0 + 100.0 * t
    phi = shaft_angle(rpm, fs)
    env = {1.0: 0.5 + 0 * t, 2.0: 1.0 + 0.3 * np.sin(2 * np.pi * 0.15 * t),
           2.5: 0.7 - 0.2 * np.cos(2 * np.pi * 0.1 * t)}
    x = sum(a * np.cos(o * phi + 0.2 * o) for o, a in env.items()) + 3.0
    return t, rpm, x, env


def test_iterative_envelopes_agree_with_the_direct_solve_and_the_truth(form, monkeypatch):
    """The documented figure: envelopes within 1e-7 of the largest of the direct solve's;
    both within 2e-3 of the analytic envelopes mid-record (the filter's own bias for a
    0.15 Hz modulation in a 2 Hz band). One order per preconditioner block, so the
    iteration, not the block solve, couples the orders."""
    monkeypatch.setattr(vkf_iterative, "GROUP", 1)
    fs = 2000.0
    t, rpm, x, env = _close_orders_runup(fs)
    kw = dict(fs=fs, speed_rpm=rpm, orders=list(env), bandwidth_hz=2.0)
    direct = vold_kalman(x, solver="direct", **kw)
    iterative = vold_kalman(x, solver="iterative", **kw)
    assert "conjugate gradients" in iterative.attrs["solver"]
    assert "banded Cholesky" in direct.attrs["solver"]
    scale = float(np.abs(direct.envelope).max())
    assert float(np.abs(iterative.envelope - direct.envelope).max()) < 1e-7 * scale
    assert float(np.abs(iterative["mean"] - direct["mean"]).max()) < 1e-7 * scale
    mid = (iterative.time.values > 1.5) & (iterative.time.values < 4.5)
    index = np.searchsorted(t, iterative.time.values[mid])
    for o, a in env.items():
        amp = np.abs(iterative.envelope.sel(order=o).values[mid])
        assert np.abs(amp - a[index]).max() < 2e-3, o


def test_close_orders_at_low_speed_converge_and_match(form, monkeypatch):
    """The slow case: orders 2 and 2.5 only 1.5 bandwidths apart (4.2 Hz at 500 rpm, 2.8 Hz
    bands) still converge within the cap and match the direct solve (one order per block)."""
    monkeypatch.setattr(vkf_iterative, "GROUP", 1)
    fs = 1000.0
    t = np.arange(int(8 * fs)) / fs
    rpm = 500.0 + 25.0 * t
    phi = shaft_angle(rpm, fs)
    x = np.cos(2 * phi) + 0.8 * np.cos(2.5 * phi + 0.4) + 0.3 * np.cos(3 * phi)
    kw = dict(fs=fs, speed_rpm=rpm, orders=[2.0, 2.5, 3.0], bandwidth_hz=2.8)
    direct = vold_kalman(x, solver="direct", **kw)
    iterative = vold_kalman(x, solver="iterative", **kw)
    used = int(iterative.attrs["solver"].split("at most ")[1].split()[0])
    assert 5 < used < vkf_iterative.MAX_ITERATIONS
    scale = float(np.abs(direct.envelope).max())
    assert float(np.abs(iterative.envelope - direct.envelope).max()) < 1e-7 * scale


def test_no_convergence_falls_back_to_the_direct_solve(monkeypatch, caplog):
    fs = 2000.0
    _, rpm, x, env = _close_orders_runup(fs, seconds=3.0)
    kw = dict(fs=fs, speed_rpm=rpm, orders=list(env), bandwidth_hz=2.0)
    direct = vold_kalman(x, solver="direct", **kw)
    monkeypatch.setattr(vkf_iterative, "MAX_ITERATIONS", 1)
    monkeypatch.setattr(vkf_iterative, "GROUP", 1)
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        res = vold_kalman(x, solver="iterative", **kw)
    assert "did not reach" in caplog.text
    assert res.attrs["solver"].startswith("direct (banded Cholesky) after conjugate gradients")
    np.testing.assert_array_equal(res.envelope.values, direct.envelope.values)


def test_auto_switches_to_the_iterative_solve_from_min_orders(monkeypatch):
    fs = 2000.0
    _, rpm, x, env = _close_orders_runup(fs, seconds=3.0)
    kw = dict(fs=fs, speed_rpm=rpm, orders=list(env), bandwidth_hz=2.0)
    assert vold_kalman(x, **kw).attrs["solver"].startswith("direct")
    monkeypatch.setattr(vkf_iterative, "MIN_ORDERS", 3)
    assert vold_kalman(x, **kw).attrs["solver"].startswith("iterative")
    with pytest.raises(AnalysisError, match="solver"):
        vold_kalman(x, solver="cg", **kw)
