"""Harmonic analysis against the textbook's piston-acceleration series.

梁守槃《发动机动力学》(1948), 第一章 §1-2, eq. (4)/(4A): for constant ω,
a = −rω² (cos θ + a₂ cos 2θ + a₄ cos 4θ + a₆ cos 6θ + a₈ cos 8θ …) with
a₂ = p + p³/4 + 15p⁵/128 + 35p⁷/512 …, a₄ = −(p³/4 + 3p⁵/16 + 35p⁷/256 …),
a₆ = 9p⁵/128 + 45p⁷/512 …, a₈ = −(5p⁷/256 …); for p = r/l = 0.3 the book gives
a₆ = 0.00019 and a₈ = −0.000004 (seed text 000, p. 3).
"""

import mpmath
import numpy as np
import pytest

from crankbench.analysis.harmonic import harmonics

P = 0.3


def normalised_piston_acceleration(theta):
    """a / (−rω²) of the exact slider-crank, derived by differentiating x = r cos θ + l √(1 − p² sin² θ)."""
    s = np.sqrt(1 - P ** 2 * np.sin(theta) ** 2)
    return np.cos(theta) + P * np.cos(2 * theta) / s + P ** 3 * np.sin(2 * theta) ** 2 / (4 * s ** 3)


def test_24_ordinate_analysis_reproduces_book_coefficients():
    h = harmonics(normalised_piston_acceleration, 24)
    # the book's series, truncated after p⁷ (next terms ~p⁹ ≈ 2e-5 · coefficient)
    assert h.a[1] == pytest.approx(1.0, abs=1e-12)
    assert h.a[2] == pytest.approx(P + P ** 3 / 4 + 15 * P ** 5 / 128 + 35 * P ** 7 / 512, abs=2e-5)
    assert h.a[4] == pytest.approx(-(P ** 3 / 4 + 3 * P ** 5 / 16 + 35 * P ** 7 / 256), abs=2e-5)
    # the book's printed values for p = 0.3, to the digits printed
    assert round(h.a[6], 5) == 0.00019
    # a₈: the book keeps only the leading term −5p⁷/256 = −4.3e-6 and prints −0.000004; the
    # exact coefficient (higher powers of p included) is −5.0e-6, within the dropped p⁹ terms
    assert h.a[8] == pytest.approx(-0.000004, abs=1.5e-6)
    assert h.a[8] == pytest.approx(-5 * P ** 7 / 256, abs=P ** 9)
    # odd harmonics above 1 and all sine terms vanish (even function, book: n always even)
    assert np.abs(h.a[[3, 5, 7, 9]]).max() < 1e-14
    assert np.abs(h.b).max() < 1e-14


def test_against_mpmath_quadrature():
    """Second method: Fourier integrals by mpmath quadrature, 30 digits."""
    mpmath.mp.dps = 30

    def f(t):
        s = mpmath.sqrt(1 - mpmath.mpf(P) ** 2 * mpmath.sin(t) ** 2)
        return (mpmath.cos(t) + P * mpmath.cos(2 * t) / s
                + mpmath.mpf(P) ** 3 * mpmath.sin(2 * t) ** 2 / (4 * s ** 3))

    h = harmonics(normalised_piston_acceleration, 48)
    for k in (2, 4, 6, 8):
        ref = mpmath.quad(lambda t: f(t) * mpmath.cos(k * t), [0, mpmath.pi / 2, mpmath.pi]) * 2 / (2 * mpmath.pi) * 2
        assert h.a[k] == pytest.approx(float(ref), abs=1e-13)


def test_12_ordinate_schedule_on_the_book_example_shows_its_aliasing():
    """Runge's 12-ordinate schedule on the same curve: a₂ agrees with the 24-ordinate value
    to the size of a₁₀ (aliased onto 2), while a₄ picks up a₈ (8 aliases onto 12 − 8 = 4) —
    the stated error of an n-ordinate analysis."""
    from crankbench.analysis.harmonic import runge12

    theta = 2 * np.pi * np.arange(12) / 12
    h12 = runge12(normalised_piston_acceleration(theta))
    h48 = harmonics(normalised_piston_acceleration, 48)
    assert h12.a[2] == pytest.approx(h48.a[2] + h48.a[10] + h48.a[14], abs=1e-12)
    assert h12.a[4] == pytest.approx(h48.a[4] + h48.a[8] + h48.a[16] + h48.a[20], abs=1e-12)
    assert abs(h12.a[4] - h48.a[4]) == pytest.approx(abs(h48.a[8]), rel=0.05)
