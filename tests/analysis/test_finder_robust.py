"""Resonance finder robustness (issue 13, point 4): peaks judged against the track's own noise,
one peak seen twice is one resonance, no sweep correction on a dwell (stepped) test.

Truth: a single-degree-of-freedom resonance (closed-form FRF, or the exact swept envelope of
``analysis.bench.suite_orders.sdof_sweep``) and orders that carry no resonance at all."""

import warnings

import numpy as np
import pytest
import xarray as xr

from crankbench.analysis.bench.suite_orders import sdof_sweep
from crankbench.analysis.orders import OrderWarning, order_track
from crankbench.analysis.resample import shaft_angle
from crankbench.analysis.resonance import find_resonances


@pytest.mark.parametrize("noise", [0.5, 5.0])
def test_noise_makes_no_confident_spurious_resonance(noise):
    """Order 3 crosses a Q = 20 resonance at 2000 rpm; orders 4.5 and 6 carry a
    constant amplitude and noise only (1400 → 2600 rpm at 100 rpm/s). With noise up to 5 rms (the resonance peak is 20, the
    other orders 0.3–0.5) only the true resonance is reported, within 0.1 % of its speed."""
    case = sdof_sweep(100.0, natural_frequency=100.0, q_factor=20.0, order=3.0, span=0.3)
    fs, rpm = case["fs"], case["rpm"]
    phi = shaft_angle(rpm, fs)
    rng = np.random.default_rng(4)
    x = (case["x"] + 0.5 * np.cos(4.5 * phi + 0.2) + 0.3 * np.cos(6.0 * phi)
         + rng.normal(0.0, noise, rpm.size))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OrderWarning)
        tr = order_track(x, fs=fs, speed_rpm=rpm, orders=[3.0, 4.5, 6.0])
    found = list(find_resonances(tr))
    assert len(found) == 1
    assert found[0].order == 3.0
    assert found[0].speed_rpm == pytest.approx(2000.0, rel=1e-3)


def _frf_track(rpm, t, *, order=3.0, critical=545.0, zeta=0.03, noise=0.0, seed=0):
    f = order * rpm / 60.0
    fn = critical * order / 60.0
    h = 1.0 / (1.0 - (f / fn) ** 2 + 2j * zeta * f / fn)
    rng = np.random.default_rng(seed)
    amp = np.abs(h) * 1e-3 * (1.0 + noise * rng.standard_normal(rpm.size))
    return xr.Dataset({"amplitude": (("order", "time"), amp[None], {"units": "rad"}),
                       "phase": (("order", "time"), np.angle(h)[None], {"units": "rad"})},
                      coords={"order": [order], "time": t, "rpm": ("time", rpm)})


def test_one_peak_crossed_twice_is_one_resonance():
    """A partial run-up (400 → 560, back to 530, on to 700 rpm) crosses the 545 rpm resonance
    in two up-sweeps: one resonance (the other detection merged), not two (543.3 and 541.8
    rpm once flipped ``model_agrees``)."""
    seg = [(400.0, 560.0), (560.0, 530.0), (530.0, 700.0)]
    rpm = np.concatenate([np.linspace(a, b, int(abs(b - a) / 5.0 * 20)) for a, b in seg])
    t = np.arange(rpm.size) / 20.0
    found = [r for r in find_resonances(_frf_track(rpm, t, noise=0.01))
             if r.direction == "up"]
    assert len(found) == 1 and found[0].merged >= 1
    assert found[0].speed_rpm == pytest.approx(545.0, rel=0.01)


def test_dwell_test_gets_no_sweep_correction():
    """A stepped (dwell) test: each speed held 1 s, the response the exact steady FRF. The
    time axis must not trigger the sweep correction (it moved an exact steady FRF by
    −0.046 %): the resonance is the FRF's, to 0.01 %."""
    steps = np.arange(400.0, 700.0 + 1e-9, 2.0)
    rpm = np.repeat(steps, 20)
    t = np.arange(rpm.size) / 20.0
    found = list(find_resonances(_frf_track(rpm, t)))
    assert len(found) == 1
    assert not found[0].sweep_corrected
    assert found[0].speed_rpm == pytest.approx(545.0, rel=1e-4)
