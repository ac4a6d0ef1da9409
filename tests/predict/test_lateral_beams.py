"""Closed-form beam frequencies and influence coefficients against independent references."""

import mpmath
import numpy as np
import pytest

from crankbench.predict.errors import ModelError
from crankbench.predict.lateral.beams import (beam_natural_frequencies, disk_on_shaft_frequency,
                                   influence_coefficient, point_stiffness)

BEAM = dict(length=1.3, youngs_modulus=2.0e11, area_moment=4.0e-7)


def _mp_root(func, guess):
    return float(mpmath.findroot(func, guess))


@pytest.mark.parametrize("support, equation, guesses", [
    ("cantilever", lambda x: mpmath.cos(x) * mpmath.cosh(x) + 1, [1.9, 4.7, 7.9, 11.0]),
    ("fixed-fixed", lambda x: mpmath.cos(x) * mpmath.cosh(x) - 1, [4.7, 7.9, 11.0, 14.1]),
    ("free-free", lambda x: mpmath.cos(x) * mpmath.cosh(x) - 1, [4.7, 7.9, 11.0, 14.1]),
    ("fixed-pinned", lambda x: mpmath.tan(x) - mpmath.tanh(x), [3.9, 7.1, 10.2, 13.35]),
])
def test_frequency_equation_roots_match_mpmath(support, equation, guesses):
    """The scaled frequency equations give the same roots as mpmath on the raw equations."""
    mpmath.mp.dps = 30
    modes = beam_natural_frequencies(support=support, n_modes=4, mass_per_length=3.0, **BEAM)
    expected = [_mp_root(equation, g) for g in guesses]
    np.testing.assert_allclose(modes.beta_l, expected, rtol=1e-13)


def test_simply_supported_closed_form():
    """ω_n = (nπ/L)² √(EI/ρA) (Euler-Bernoulli pinned-pinned beam)."""
    rho_a = 15.0
    modes = beam_natural_frequencies(support="pinned-pinned", n_modes=5, mass_per_length=rho_a,
                                     **BEAM)
    n = np.arange(1, 6)
    expected = (n * np.pi / BEAM["length"]) ** 2 * np.sqrt(
        BEAM["youngs_modulus"] * BEAM["area_moment"] / rho_a)
    np.testing.assert_allclose(modes.omega, expected, rtol=1e-14)
    np.testing.assert_allclose(modes.speed_rpm, expected * 30 / np.pi, rtol=1e-14)
    frame = modes.to_frame()
    assert list(frame.columns) == ["mode", "beta_l", "omega", "frequency_hz", "speed_rpm"]


def test_mode_shapes_satisfy_boundary_conditions():
    modes = beam_natural_frequencies(support="cantilever", n_modes=3, mass_per_length=1.0, **BEAM)
    L = BEAM["length"]
    for n in (1, 2, 3):
        x = np.array([0.0, 1e-6, L - 1e-6, L])
        phi = modes.mode_shape(n, x)
        assert abs(phi[0]) < 1e-12  # clamped: w(0) = 0
        assert abs(phi[1] - phi[0]) / 1e-6 < 1e-4  # w'(0) = 0
    fig = modes.plot()
    assert fig.axes


def test_influence_coefficients_classical_values():
    """Mid-span L³/48EI, cantilever tip L³/3EI, fixed-fixed centre L³/192EI; reciprocity."""
    L, E, I = BEAM["length"], BEAM["youngs_modulus"], BEAM["area_moment"]
    ss = influence_coefficient(L / 2, L / 2, **BEAM)
    assert ss == pytest.approx(L**3 / (48 * E * I), rel=1e-14)
    tip = influence_coefficient(L, L, support="cantilever", **BEAM)
    assert tip == pytest.approx(L**3 / (3 * E * I), rel=1e-14)
    ff = influence_coefficient(L / 2, L / 2, support="fixed-fixed", **BEAM)
    assert ff == pytest.approx(L**3 / (192 * E * I), rel=1e-14)
    x = np.linspace(0.05, L - 0.05, 7)
    for support in ("simply-supported", "cantilever", "fixed-fixed"):
        a = influence_coefficient(x[:, None], x[None, :], support=support, **BEAM)
        np.testing.assert_allclose(a, a.T, rtol=1e-14)
        assert np.all(np.linalg.eigvalsh(a) > 0)  # flexibility is positive definite


def test_point_stiffness_off_centre():
    """k = 3EIL/(a²b²) for a simply supported beam loaded at a."""
    a = 0.4
    b = BEAM["length"] - a
    k = point_stiffness(a, **BEAM)
    ei = BEAM["youngs_modulus"] * BEAM["area_moment"]
    assert k == pytest.approx(3 * ei * BEAM["length"] / (a**2 * b**2), rel=1e-14)


@pytest.mark.parametrize("support, position, fraction", [
    ("simply-supported", 0.5, 17 / 35), ("cantilever", 1.0, 33 / 140)])
def test_rayleigh_effective_shaft_mass(support, position, fraction):
    """Effective mass of the shaft: 17/35 (centre, pinned-pinned), 33/140 (cantilever tip)
    — Thomson & Dahleh, Theory of Vibration with Applications, §2.3 examples."""
    L = 1.0
    rho_a, mass = 2.0, 5.0
    w = disk_on_shaft_frequency(mass=mass, position=position * L, length=L, youngs_modulus=1.0,
                                area_moment=1.0, support=support, mass_per_length=rho_a)
    k = point_stiffness(position * L, length=L, youngs_modulus=1.0, area_moment=1.0,
                        support=support)
    assert w**2 == pytest.approx(k / (mass + fraction * rho_a * L), rel=1e-12)


def test_errors_name_the_argument():
    with pytest.raises(ModelError, match=r"support='pinned' is not one of .*"):
        beam_natural_frequencies(support="pinned", mass_per_length=1.0, **BEAM)
    with pytest.raises(ModelError, match=r"^mass_per_length=-1.0 must be > 0$"):
        beam_natural_frequencies(mass_per_length=-1.0, **BEAM)
    with pytest.raises(ModelError, match=r"positions must lie on the beam \[0, 1.3\] m"):
        influence_coefficient(2.0, 0.5, **BEAM)
    with pytest.raises(ModelError, match="is at a support"):
        point_stiffness(0.0, **BEAM)
    with pytest.raises(ModelError, match=r"^n_modes=0 must be >= 1$"):
        beam_natural_frequencies(mass_per_length=1.0, n_modes=0, **BEAM)
