"""Slider-crank kinematics: exact motion against independent derivatives, the harmonic series
against mpmath quadrature and the textbook power series, truncation bounds."""

import math

import mpmath as mp
import numpy as np
import pytest

from crankbench.predict import kinematics as kin
from crankbench.predict.errors import ModelError


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures the result objects' plot() made (matplotlib warns past 20)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


R, L = 0.05, 0.2


def _mp_coefficient(lam, n):
    """a_n by mpmath quadrature of the Fourier integral of sqrt(1 − λ² sin²θ) (n even)."""
    with mp.workdps(60):
        lam = mp.mpf(lam)
        c = mp.quad(lambda t: mp.sqrt(1 - lam**2 * mp.sin(t) ** 2) * mp.cos(n * t),
                    [0, mp.pi / 2, mp.pi]) * 2 / mp.pi
        return float(n**2 * c / lam)


@pytest.mark.parametrize("lam", [0.1, 0.25, 0.45])
def test_series_coefficients_match_mpmath_quadrature(lam):
    a = kin.series_coefficients(lam, 24)
    for n in range(2, 25, 2):
        ref = _mp_coefficient(lam, n)
        assert a[n] == pytest.approx(ref, rel=1e-13, abs=1e-300)
    assert a[1] == 1.0 and a[0] == 0.0
    assert np.all(a[3::2] == 0.0)


def test_series_coefficients_agree_with_textbook_power_series():
    """Liang 1948 ch. 1 eq. (4): a2 = λ + λ³/4 + 15λ⁵/128 + 35λ⁷/512 + O(λ⁹), etc."""
    lam = 0.05
    a = kin.series_coefficients(lam, 8)
    assert a[2] == pytest.approx(lam + lam**3 / 4 + 15 * lam**5 / 128 + 35 * lam**7 / 512,
                                 rel=2 * lam**8)
    assert a[4] == pytest.approx(-(lam**3 / 4 + 3 * lam**5 / 16 + 35 * lam**7 / 256),
                                 rel=2 * lam**6)
    assert a[6] == pytest.approx(9 * lam**5 / 128 + 45 * lam**7 / 512, rel=2 * lam**4)
    assert a[8] == pytest.approx(-5 * lam**7 / 256, rel=2 * lam**2)


@mp.workdps(30)
def test_exact_acceleration_matches_mpmath_derivative_of_position():
    w = 120.0
    for th in [0.0, 0.3, 1.1, 2.0, 3.0, 4.4, 5.9]:
        x = lambda t: R * mp.cos(t) + L * mp.sqrt(1 - (R / L * mp.sin(t)) ** 2)  # noqa: E731
        ref = float(mp.diff(x, th, 2)) * w * w
        got = kin.piston_acceleration(th, crank_radius=R, rod_length=L, omega=w)
        assert got == pytest.approx(ref, rel=1e-12, abs=1e-9)
        vref = float(mp.diff(x, th, 1)) * w
        assert kin.piston_velocity(th, crank_radius=R, rod_length=L, omega=w) == pytest.approx(
            vref, rel=1e-12, abs=1e-12)


@mp.workdps(30)
def test_pin_offset_motion_matches_mpmath_derivatives():
    e, w = 0.012, 90.0
    x = lambda t: R * mp.cos(t) + mp.sqrt(L**2 - (R * mp.sin(t) - e) ** 2)  # noqa: E731
    for th in [0.0, 0.7, 2.5, 4.0]:
        acc = kin.piston_acceleration(th, crank_radius=R, rod_length=L, omega=w, pin_offset=e)
        assert acc == pytest.approx(float(mp.diff(x, th, 2)) * w * w, rel=1e-12)
        # series with odd orders and sine terms converges to the exact value
        ser = kin.piston_acceleration(th, crank_radius=R, rod_length=L, omega=w, pin_offset=e,
                                      max_order=40)
        assert ser == pytest.approx(acc, rel=1e-12)
    # the stroke with an offset exceeds 2r: sqrt((l+r)²−e²) − sqrt((l−r)²−e²)
    th = np.linspace(0, 2 * np.pi, 20001)
    disp = kin.piston_displacement(th, crank_radius=R, rod_length=L, pin_offset=e)
    stroke = math.sqrt((L + R) ** 2 - e * e) - math.sqrt((L - R) ** 2 - e * e)
    assert disp.max() == pytest.approx(stroke, rel=1e-7)
    assert disp.min() == pytest.approx(0.0, abs=1e-9)


def test_rod_angular_motion_closed_forms():
    lam, w = R / L, 80.0
    th = np.linspace(0, 2 * np.pi, 13)
    s = np.sin(th)
    ref_acc = -lam * w**2 * s * (1 - lam**2) / (1 - lam**2 * s**2) ** 1.5
    got = kin.rod_angular_acceleration(th, crank_radius=R, rod_length=L, omega=w)
    np.testing.assert_allclose(got, ref_acc, rtol=1e-13, atol=1e-10)
    ref_vel = lam * w * np.cos(th) / np.sqrt(1 - lam**2 * s**2)
    got = kin.rod_angular_velocity(th, crank_radius=R, rod_length=L, omega=w)
    np.testing.assert_allclose(got, ref_vel, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(kin.rod_angle(th, crank_radius=R, rod_length=L),
                               np.arcsin(lam * s), atol=1e-15)


def test_displacement_is_zero_at_tdc_and_stroke_at_bdc():
    assert kin.piston_displacement(0.0, crank_radius=R, rod_length=L) == pytest.approx(0, abs=1e-15)
    assert kin.piston_displacement(np.pi, crank_radius=R, rod_length=L) == pytest.approx(2 * R)


@pytest.mark.parametrize("lam", [0.25, 0.45])
@pytest.mark.parametrize("order", [2, 4, 6, 8, 12])
def test_truncation_error_within_bound_and_bound_tight_at_tdc(lam, order):
    th = np.linspace(0, 2 * np.pi, 3601)
    l = 1.0 / lam
    exact = kin.piston_acceleration(th, crank_radius=1.0, rod_length=l, omega=1.0)
    series = kin.piston_acceleration(th, crank_radius=1.0, rod_length=l, omega=1.0,
                                     max_order=order)
    err = np.abs(exact - series).max()
    bound = kin.truncation_bound(lam, order)
    assert err <= bound * (1 + 1e-9) + 1e-15
    # at TDC every cos nθ = 1 and the tail alternates in sign: the bound is within 15 %
    assert err >= 0.85 * bound


def test_order_for_tolerance_is_lowest_meeting_tolerance():
    for lam, tol in [(0.25, 1e-6), (0.45, 1e-10), (0.3, 1e-3)]:
        n = kin.order_for_tolerance(lam, tol)
        assert kin.truncation_bound(lam, n) <= tol
        if n > 2:
            assert kin.truncation_bound(lam, n - 2) > tol
    s = kin.acceleration_series(0.3, tol=1e-8)
    assert s.error_bound <= 1e-8
    frame = s.to_frame()
    assert list(frame["order"])[:3] == [1, 2, 4]


def test_series_acceleration_object_evaluates_like_function():
    s = kin.acceleration_series(0.25, max_order=6)
    th = np.linspace(0, 6, 7)
    np.testing.assert_allclose(
        s.acceleration(th, crank_radius=R, omega=50.0),
        kin.piston_acceleration(th, crank_radius=R, rod_length=R / 0.25, omega=50.0,
                                max_order=6), rtol=1e-14)
    fig = s.plot()
    assert fig is not None


def test_bad_geometry_is_named():
    with pytest.raises(ModelError, match=r"rod_length=0.04 must exceed crank_radius"):
        kin.piston_acceleration(0.0, crank_radius=0.05, rod_length=0.04, omega=1.0)
    with pytest.raises(ModelError, match=r"crank_radius=-1 must be > 0"):
        kin.piston_position(0.0, crank_radius=-1, rod_length=0.2)
    with pytest.raises(ModelError, match=r"max_order=0 must be >= 1"):
        kin.piston_acceleration(0.0, crank_radius=R, rod_length=L, omega=1.0, max_order=0)
    with pytest.raises(ModelError, match=r"theta contains 1 NaN"):
        kin.piston_acceleration([0.0, np.nan], crank_radius=R, rod_length=L, omega=1.0)
    with pytest.raises(ModelError, match=r"lam=1.2 must be < 1"):
        kin.series_coefficients(1.2, 4)
    with pytest.raises(ModelError, match="exactly one of max_order"):
        kin.acceleration_series(0.3)


def test_truncation_bound_of_odd_order_equals_the_even_order_below():
    # odd coefficients vanish, so truncating after 2k+1 drops exactly what 2k drops
    for lam in (0.25, 0.45):
        for n in (2, 4, 10):
            assert kin.truncation_bound(lam, n + 1) == pytest.approx(
                kin.truncation_bound(lam, n), rel=1e-15)
