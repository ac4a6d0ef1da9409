"""Flywheel relations against published worked examples.

Sources:

* [Khurmi] R. S. Khurmi, J. K. Gupta, *A Textbook of Theory of Machines*, S. Chand, ch. 16
  "Turning moment diagrams and flywheel", Example 16.1 (p. 573): flywheel mass 6.5 t, radius of
  gyration 1.8 m, fluctuation of energy 56 kN·m, mean speed 120 rpm → maximum and minimum
  speeds 121 and 119 rpm (printed to the rpm).
* [Sanfoundry/Khurmi class] flywheel 7 t, radius of gyration 1.7 m, ΔE = 55 kN·m at 150 rpm →
  coefficient of fluctuation of speed 0.011 (printed to 3 decimals).
* [Applied Mechanics vol. 2] ch. 2 §6-8 (seed 002, contents): fluctuation of energy, limits of
  speed variation, flywheel — the relation ΔE = J ω² δ used by both examples.
"""

import numpy as np
import pytest

from crankbench.predict.flywheel import TurningMoment, flywheel_inertia


def _diagram(delta_e, omega, order=2):
    """A turning-moment diagram whose fluctuation of energy is ``delta_e`` (T = T_m + A sin kφ,
    ΔE = 2A/k)."""
    a = np.arange(1440) * 4 * np.pi / 1440
    amp = delta_e * order / 2
    return TurningMoment.from_torque(a, 5e4 + amp * np.sin(order * a), omega=omega)


def test_khurmi_example_16_1_max_min_speed():
    n_mean = 120.0
    tm = _diagram(56e3, n_mean * np.pi / 30)
    assert tm.fluctuation_of_energy == pytest.approx(56e3, rel=1e-12)
    inertia = 6500.0 * 1.8**2
    delta = tm.speed_fluctuation(inertia)
    n1, n2 = n_mean * (1 + delta / 2), n_mean * (1 - delta / 2)
    assert (round(n1), round(n2)) == (121, 119)
    # the speed curve from the energy equation spans the same range
    rpm = tm.speed(inertia) * 30 / np.pi
    assert (round(rpm.max()), round(rpm.min())) == (121, 119)
    assert (rpm.max() - rpm.min()) / n_mean == pytest.approx(delta, rel=1e-3)


def test_coefficient_of_fluctuation_example():
    tm = _diagram(55e3, 150 * np.pi / 30)
    delta = tm.speed_fluctuation(7000.0 * 1.7**2)
    assert round(delta, 3) == 0.011
    # and back: the inertia for that coefficient is the flywheel's
    assert flywheel_inertia(tm, delta) == pytest.approx(7000.0 * 1.7**2, rel=1e-12)
