"""Crank-train kinematics and mass reduction against the worked examples of the source texts.

Sources (seeds in /work/shared/seeds):

* [Liang 1948] Liang Shoupan, *Engine Dynamics* (發動機動力學), Commercial Press, Shanghai 1948,
  ch. 1 §1-2 (acceleration series, eq. (4)), §1-3 (worked example: reciprocating inertia
  force), §1-4 (residual couple, eq. (10) and worked example), ch. 2 §2-1 (single-cylinder
  balance weight example). Imperial units (lb, in, ft) as printed; slide-rule results
  printed to three figures.
* [ICE dynamics 1958] *Internal-combustion engine dynamics* (內燃機動力學), Jiaotong University
  lecture notes 1957/58, part 1 ch. 1 §1 (two- and three-point rod masses, eq. (1)-(3)).
"""

import numpy as np
import pytest

from crankbench.predict import kinematics as kin
from crankbench.predict.balance import counterweights
from crankbench.predict.engine import Engine
from crankbench.predict.masses import Rod, rod_inertia_from_pendulum, throw_rotating_mass

G_FT = 32.2                      # ft/s², the value used in [Liang 1948]
OMEGA_4000 = 4000 * 2 * np.pi / 60


def test_liang_1948_series_coefficients_of_eq_4():
    """[Liang 1948] §1-2 eq. (4): the coefficients a₂…a₈ as power series in p = r/l; the
    printed low-order terms are the leading terms of the exact coefficients."""
    for lam in (1e-3, 2e-3):
        a = kin.series_coefficients(lam, 8)
        # leading coefficient of each series: 1, -1/4, 9/128, -5/256 (a_n divided by λ^(n-1))
        assert a[2] / lam == pytest.approx(1.0, rel=lam)
        assert a[4] / lam**3 == pytest.approx(-1 / 4, rel=4 * lam**2)
        assert a[6] / lam**5 == pytest.approx(9 / 128, rel=4 * lam**2)
        assert a[8] / lam**7 == pytest.approx(-5 / 256, rel=4 * lam**2)


def test_liang_1948_a6_a8_at_p_0_3():
    """[Liang 1948] §1-2: with p = 0.3, a₆ = 9/128·0.3⁵ + 45/512·0.3⁷ = .00019 and
    a₈ = −5/256·0.3⁷ = −.000004 (leading term only, "one part in a million": negligible)."""
    a = kin.series_coefficients(0.3, 8)
    assert round(a[6], 5) == 0.00019
    assert 9 / 128 * 0.3**5 + 45 / 512 * 0.3**7 == pytest.approx(a[6], rel=0.01)
    # the book keeps only the leading term of a₈: −5/256·0.3⁷ = −4.3e-6, printed −.000004;
    # the exact coefficient is −5.0e-6, still "微乎其微" next to a₁ = 1
    assert round(-5 / 256 * 0.3**7, 6) == -0.000004
    assert -6e-6 < a[8] < -4e-6


def test_liang_1948_example_reciprocating_inertia_force():
    """[Liang 1948] §1-3 example: crank 2 in, rod 7 in and 2.75 lb with its CG 2 in from the
    crank pin, piston 0.8 lb, pin 0.15 lb, rings 0.05 lb, 4000 rpm.
    Printed: reciprocating weight 1.79 lb, acceleration 37400 ft/s², force 2080 lb (slide rule;
    the exact TDC acceleration r ω² (1 + λ) is 37598 ft/s², 0.5 % above the printed value)."""
    rod = Rod(mass=2.75, length=7.0, cg_from_big_end=2.0, inertia_cg=1.0)  # lb, in
    recip = 0.8 + 0.15 + 0.05 + rod.two_point().small_end
    assert round(recip, 2) == 1.79
    acc = -kin.piston_acceleration(0.0, crank_radius=2 / 12, rod_length=7 / 12,
                                   omega=OMEGA_4000)
    assert acc == pytest.approx(37400, rel=0.01)
    # the largest magnitude over the revolution is at TDC
    th = np.linspace(0, 2 * np.pi, 7201)
    allacc = kin.piston_acceleration(th, crank_radius=2 / 12, rod_length=7 / 12,
                                     omega=OMEGA_4000)
    assert np.abs(allacc).max() == pytest.approx(acc, rel=1e-12)
    force = recip / G_FT * acc
    assert force == pytest.approx(2080, rel=0.01)


def test_liang_1948_example_residual_couple():
    """[Liang 1948] §1-4 example: the rod of the previous example with a triangular mass
    distribution (h k = 2/9, q² = 1/18 in units of l²). Printed maximum residual couple:
    253 ft·lb at 4000 rpm."""
    l_ft = 7 / 12
    mass = 2.75 / G_FT                                     # slug
    rod = Rod(mass=mass, length=l_ft, cg_from_big_end=l_ft / 3,
              inertia_cg=mass * l_ft**2 / 18)
    assert rod.h * rod.k == pytest.approx(2 / 9)
    th = np.linspace(0, 2 * np.pi, 14401)
    couple = rod.residual_couple(th, crank_radius=2 / 12, omega=OMEGA_4000)
    assert np.abs(couple).max() == pytest.approx(253, rel=0.005)


def test_liang_1948_single_cylinder_balance_weight():
    """[Liang 1948] §2-1 example: 5 in × 6 in single cylinder, crank pin 1 lb, rod 3 lb at the
    crank pin and 2 lb at the piston pin, reciprocating parts 6 lb; counterweight CG at 3.5 in.
    Balance weight = (4 + 8/2) × 3/3.5 = 6.86 lb (rotating + half the reciprocating mass)."""
    e = Engine(crank_angles_deg=[0], crank_radius=3.0, rod_length=12.0,
               reciprocating_mass=2 + 6, rotating_mass=throw_rotating_mass(
                   pin_mass=1.0, web_mass=0.0, web_cg_radius=0.0, crank_radius=3.0) + 3.0)
    cw = counterweights(e, balance_factor=0.5)
    assert round(cw[0].mass_radius / 3.5, 2) == 6.86


def test_ice_dynamics_1958_three_point_rod_and_pendulum():
    """[ICE dynamics 1958] eq. (2): m₁ = J₀/(l₁ l), m₂ = J₀/((l − l₁) l),
    m₃ = m − J₀/(l₁(l − l₁)); eq. (3): J₀ from the swing period about the piston pin."""
    m, l, l1 = 2.1, 0.21, 0.14          # l1: CG to piston-pin centre
    j0 = 0.0085
    rod = Rod(mass=m, length=l, cg_from_big_end=l - l1, inertia_cg=j0)
    three = rod.three_point()
    assert three.small_end == pytest.approx(j0 / (l1 * l), rel=1e-14)
    assert three.big_end == pytest.approx(j0 / ((l - l1) * l), rel=1e-14)
    assert three.at_cg == pytest.approx(m - j0 / (l1 * (l - l1)), rel=1e-14)
    period = 2 * np.pi * np.sqrt((j0 + m * l1**2) / (m * 9.80665 * l1))
    assert rod_inertia_from_pendulum(mass=m, period=period, pivot_to_cg=l1) == pytest.approx(
        j0, rel=1e-12)
