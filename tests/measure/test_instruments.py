"""Seismic instrument models against closed forms and an ODE integration (a second method)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from crankbench.measure.instruments import (SeismicInstrument, accelerometer, torsiograph,
                                 velocity_pickup, vibrograph)


def test_vibrograph_frf_matches_textbook_amplitude_ratio():
    """Relative motion of a seismic mass under base displacement X sin(wt):
    Z/X = r^2 / sqrt((1 - r^2)^2 + (2 zeta r)^2), phase lag atan2(2 zeta r, 1 - r^2)
    (Liang, Engine dynamics 1948, ch. 9 'seismic instruments'); 1/(2 zeta) at resonance."""
    zeta, fn = 0.25, 8.0
    r = np.array([0.3, 1.0, 2.0, 5.0, 20.0])
    h = vibrograph(natural_frequency=fn, damping_ratio=zeta).frf(r * fn)
    np.testing.assert_allclose(np.abs(h), r**2 / np.sqrt((1 - r**2) ** 2 + (2 * zeta * r) ** 2),
                               rtol=1e-12)
    # reading = -z: lag of z behind the base motion minus pi
    lag = np.arctan2(2 * zeta * r, 1 - r**2)
    np.testing.assert_allclose(np.angle(-h), -lag, atol=1e-12)
    assert abs(h[1]) == pytest.approx(1 / (2 * zeta))


def test_simulate_agrees_with_ode_integration():
    """The filtered reading equals the seismic-mass ODE z'' + 2 zeta wn z' + wn^2 z = -x''
    integrated by solve_ivp (reading = -z) for a two-tone base displacement."""
    fs, fn, zeta = 5000.0, 6.0, 0.4
    t = np.arange(int(3.0 * fs)) / fs
    w1, w2 = 2 * np.pi * 9.0, 2 * np.pi * 31.0

    def x_dd(tt):
        return -(w1**2) * np.sin(w1 * tt) - 0.3 * w2**2 * np.cos(w2 * tt)

    x = np.sin(w1 * t) + 0.3 * np.cos(w2 * t) - 0.3  # start at rest: x(0) = 0, x'(0) = w1
    wn = 2 * np.pi * fn
    # the filter starts from rest with zero input history; match the base motion's initial
    # velocity with z'(0) = -x'(0) (the mass stays still while the case starts moving)
    sol = solve_ivp(lambda tt, s: [s[1], -x_dd(tt) - 2 * zeta * wn * s[1] - wn**2 * s[0]],
                    (0, t[-1]), [0.0, -w1], t_eval=t, rtol=1e-10, atol=1e-12)
    reading = vibrograph(natural_frequency=fn, damping_ratio=zeta).simulate(x, fs=fs)
    settled = t > 1.0
    np.testing.assert_allclose(reading[settled], -sol.y[0][settled], atol=2e-3)


def test_simulate_steady_state_gain_and_phase_follow_frf():
    """Settled response to a sine equals frf(f) within the stated hold error (pi f/fs)^2/3."""
    fs = 20_000.0
    acc = accelerometer(natural_frequency=1000.0, damping_ratio=0.05)
    for f in (100.0, 700.0, 1500.0):
        t = np.arange(int(1.0 * fs)) / fs
        y = acc.simulate(np.sin(2 * np.pi * f * t), fs=fs)
        seg = slice(int(0.5 * fs), None)
        basis = np.column_stack([np.sin(2 * np.pi * f * t[seg]), np.cos(2 * np.pi * f * t[seg])])
        (s, c), *_ = np.linalg.lstsq(basis, y[seg], rcond=None)
        measured = complex(s, c)  # response to sin: Im part is cos coefficient
        expected = complex(acc.frf(f))
        bound = (np.pi * f / fs) ** 2 / 3
        assert abs(measured - expected) < 1.2 * bound * abs(expected)
        fft = acc.simulate(np.sin(2 * np.pi * f * t), fs=fs, method="fft")  # periodic record
        (s, c), *_ = np.linalg.lstsq(basis, fft[seg], rcond=None)
        assert abs(complex(s, c) - expected) < 1e-9 * abs(expected)


def test_correction_recovers_signal_within_stated_band():
    """A vibrograph (fn = 10 Hz, zeta = 0.3) records 6, 12.3, 40 and 300 Hz plus a 1 Hz
    component below its correction band: the corrected signal equals the in-band part of the
    true signal (the 1 Hz part is removed, as stated) within 0.5 % of its peak away from the
    record ends."""
    fs = 4000.0
    t = np.arange(int(20 * fs)) / fs
    in_band = (np.sin(2 * np.pi * 6.0 * t) + 0.5 * np.sin(2 * np.pi * 12.3 * t + 1)
               + 0.2 * np.sin(2 * np.pi * 40.0 * t) + 0.05 * np.sin(2 * np.pi * 300.0 * t))
    below = 0.8 * np.sin(2 * np.pi * 1.0 * t)
    vib = vibrograph(natural_frequency=10.0, damping_ratio=0.3)
    reading = vib.simulate(np.tile(in_band + below, 2), fs=fs)[t.size:]   # settled
    lo, hi = vib.correction_band(fs=fs, min_gain=0.1)
    assert 2.0 < lo < 6.0 and hi == 0.45 * fs
    out = vib.correct(reading, fs=fs)
    k = int(out.end_effect_s * fs)
    err = np.abs(out.data[k:-k] - in_band[k:-k])
    assert err.max() < 0.005 * np.abs(in_band).max()
    assert 2.0 < out.max_gain <= 10.0  # at most 1/min_gain


def test_accelerometer_correction_extends_flat_band_to_resonance():
    """A lightly damped accelerometer (fn = 2 kHz) over-reads 1.8 kHz by 5x; corrected, the
    reading matches within 0.5 % (sampled at 100 kHz so the simulation's hold error is 0.1 %)."""
    fs = 100_000.0
    t = np.arange(int(2 * fs)) / fs
    true = np.sin(2 * np.pi * 200.0 * t) + 0.3 * np.sin(2 * np.pi * 1800.0 * t)
    acc = accelerometer(natural_frequency=2000.0, damping_ratio=0.05)
    raw = acc.simulate(np.tile(true, 2), fs=fs)[t.size:]
    assert np.abs(raw).max() > 1.5 * np.abs(true).max()
    lo, hi = acc.usable_band(tolerance=0.05)
    assert hi < 1800.0                               # 1.8 kHz is outside the raw usable band
    out = acc.correct(raw, fs=fs)
    k = int(out.end_effect_s * fs) + 1
    assert np.abs(out.data[k:-k] - true[k:-k]).max() < 0.005 * np.abs(true).max()


def test_usable_band_closed_forms():
    """Undamped: accelerometer |1/(1-r^2)| <= 1.05 up to r = sqrt(1 - 1/1.05); vibrograph
    r^2/(r^2 - 1) <= 1.05 from r = sqrt(21)."""
    _, hi = accelerometer(natural_frequency=1000.0, damping_ratio=0.0).usable_band(tolerance=0.05)
    assert hi == pytest.approx(1000.0 * np.sqrt(1 - 1 / 1.05), rel=1e-3)
    lo, _ = vibrograph(natural_frequency=2.0, damping_ratio=0.0).usable_band(tolerance=0.05)
    assert lo == pytest.approx(2.0 * np.sqrt(21.0), rel=1e-3)
    # seismic torsiograph and velocity pick-up share the vibrograph's dynamics
    np.testing.assert_allclose(torsiograph(natural_frequency=2.0, damping_ratio=0.5).frf([1, 5]),
                               velocity_pickup(natural_frequency=2.0,
                                               damping_ratio=0.5).frf([1, 5]))


def test_bad_parameters_are_named():
    with pytest.raises(ValueError, match="natural_frequency=-1 must be > 0"):
        vibrograph(natural_frequency=-1, damping_ratio=0.1)
    with pytest.raises(ValueError, match="kind='force' is not one of"):
        SeismicInstrument(10.0, 0.1, "force")
    with pytest.raises(ValueError, match="signal contains 1 NaN"):
        accelerometer(natural_frequency=1e3).simulate([0.0, np.nan, 1.0], fs=100.0)
