"""Rod mass reduction: equivalence conditions, the residual couple against the point masses'
own inertia moments computed from the kinematics, pendulum round trip, crank-throw reduction."""

import numpy as np
import pytest

from crankbench.predict import kinematics as kin
from crankbench.predict.errors import ModelError
from crankbench.predict.masses import Rod, rod_inertia_from_pendulum, throw_rotating_mass


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures the result objects' plot() made (matplotlib warns past 20)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


ROD = Rod(mass=1.3, length=0.16, cg_from_big_end=0.045, inertia_cg=0.0042)


def test_two_point_is_statically_equivalent():
    m = ROD.two_point()
    assert m.big_end + m.small_end == pytest.approx(ROD.mass)
    # same CG: m_A l_A = m_B l_B
    assert m.big_end * ROD.cg_from_big_end == pytest.approx(
        m.small_end * (ROD.length - ROD.cg_from_big_end))
    assert m.inertia_error == pytest.approx(
        ROD.inertia_cg - ROD.mass * 0.045 * 0.115, rel=1e-12)


def test_three_point_is_dynamically_equivalent():
    m = ROD.three_point()
    la, lb = 0.045, 0.115
    assert m.big_end + m.small_end + m.at_cg == pytest.approx(ROD.mass, rel=1e-14)
    assert m.big_end * la == pytest.approx(m.small_end * lb, rel=1e-14)
    assert m.big_end * la**2 + m.small_end * lb**2 == pytest.approx(ROD.inertia_cg, rel=1e-14)
    assert m.inertia_error == 0.0
    heavy = Rod(mass=1.0, length=0.2, cg_from_big_end=0.05, inertia_cg=0.02)
    with pytest.raises(ModelError, match="no positive three-point equivalent"):
        heavy.three_point()


def test_residual_couple_closes_the_moment_balance_of_the_point_masses():
    """Moment about the CG of the two point masses' inertia forces, computed from the crank-pin
    and piston accelerations, plus the residual couple = −J_G φ̈ of the real rod."""
    r, w = 0.04, 420.0
    l = ROD.length
    th = np.linspace(0, 2 * np.pi, 25)
    phi = kin.rod_angle(th, crank_radius=r, rod_length=l)
    phi2 = kin.rod_angular_acceleration(th, crank_radius=r, rod_length=l, omega=w)
    # accelerations in (axial, sideways) coordinates
    a_pin = np.stack([-r * w**2 * np.cos(th), -r * w**2 * np.sin(th)])
    a_piston = np.stack([kin.piston_acceleration(th, crank_radius=r, rod_length=l, omega=w),
                         np.zeros_like(th)])
    two = ROD.two_point()
    h = ROD.cg_from_big_end / l
    # positions of the crank pin and piston pin relative to the CG
    rod_dir = np.stack([np.cos(phi), -np.sin(phi)])        # unit vector crank pin → piston pin
    r_a = -h * l * rod_dir
    r_b = (1 - h) * l * rod_dir
    a_g = (1 - h) * a_pin + h * a_piston

    def cross(u, v):
        return u[0] * v[1] - u[1] * v[0]

    # d'Alembert moment of the point masses about G, relative acceleration only
    moment_points = -(two.big_end * cross(r_a, a_pin - a_g)
                      + two.small_end * cross(r_b, a_piston - a_g))
    # for a rigid body this is −I_points · (angular acceleration about the axial→sideways axis);
    # the rod turns by −φ in that orientation, so the real rod's moment is +J_G φ̈
    moment_real = ROD.inertia_cg * phi2
    residual = ROD.residual_couple(th, crank_radius=r, omega=w)
    np.testing.assert_allclose(moment_points + residual, moment_real,
                               atol=1e-9 * np.abs(moment_real).max())


def test_pendulum_round_trip():
    m, a, g = 1.3, 0.115, 9.80665
    j = 0.0042
    period = 2 * np.pi * np.sqrt((j + m * a * a) / (m * g * a))
    assert rod_inertia_from_pendulum(mass=m, period=period, pivot_to_cg=a) == pytest.approx(
        j, rel=1e-12)
    with pytest.raises(ModelError, match="swings slower than the simple pendulum"):
        rod_inertia_from_pendulum(mass=m, period=0.1, pivot_to_cg=a)


def test_throw_reduction_and_result_objects():
    assert throw_rotating_mass(pin_mass=1.0, web_mass=3.0, web_cg_radius=-0.01,
                               crank_radius=0.05) == pytest.approx(0.4)
    assert ROD.to_frame().shape[0] == 2
    assert ROD.plot() is not None and ROD.two_point().plot() is not None
    with pytest.raises(ModelError, match=r"cg_from_big_end=0.3 must be < length=0.16"):
        Rod(mass=1.0, length=0.16, cg_from_big_end=0.3, inertia_cg=0.001)
