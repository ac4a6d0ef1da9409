"""Journal bearings against the literature and a second method.

* [RB] A. A. Raimondi, J. Boyd, ASLE Trans. 1 (1958) 159-209, full journal bearing L/D = 1
  (as tabulated in Shigley's *Mechanical Engineering Design*, 9th ed., §12-8): ε = 0.2, 0.4,
  0.6, 0.8, 0.9 → S = 0.631, 0.264, 0.121, 0.0446, 0.0188 and φ = 74.02°, 63.10°, 50.58°,
  36.24°, 26.45°.
* [Ocvirk] F. W. Ocvirk, NACA TN 2808 (1952); Hamrock, NASA RP-1255 (1991) ch. 19: short
  bearing W = μωR L³ ε √(π²(1−ε²) + 16ε²)/(4c²(1−ε²)²), tan φ = π√(1−ε²)/(4ε).
* Second method for the coefficients feeding the rotor model: the damped frequencies of a rigid
  rotor on two such bearings from the 4-state equations M ẍ + C ẋ + K x = 0 against the
  finite-element rotor built with :meth:`BearingCoefficients.bearing`.
"""

import numpy as np
import pytest

from crankbench.predict.lateral.elements import Disk, Material, ShaftSection
from crankbench.predict.lateral.fe import Rotor
from crankbench.predict.lateral.journal import JournalBearing, ocvirk_attitude, ocvirk_load

RB = [(0.2, 0.631, 74.02), (0.4, 0.264, 63.10), (0.6, 0.121, 50.58), (0.8, 0.0446, 36.24),
      (0.9, 0.0188, 26.45)]


def test_raimondi_boyd_l_over_d_1():
    b = JournalBearing(diameter=0.1, length=0.1, radial_clearance=5e-5, viscosity=0.02)
    for ecc, s_ref, phi_ref in RB:
        s, phi = b.sommerfeld_at(ecc)
        assert s == pytest.approx(s_ref, rel=0.015), ecc
        assert phi == pytest.approx(phi_ref, abs=0.6), ecc


@pytest.mark.parametrize("ecc", [0.2, 0.5, 0.8])
def test_short_bearing_is_ocvirks_closed_form(ecc):
    kw = dict(diameter=0.08, length=0.03, radial_clearance=4e-5, viscosity=0.015)
    b = JournalBearing(model="short", **kw)
    fx, fy = b.forces(ecc * 4e-5, 0.0, omega=400.0)
    assert np.hypot(fx, fy) == pytest.approx(ocvirk_load(ecc, omega=400.0, **kw), rel=1e-12)
    # the load line lies φ behind the line of centres (+x), against the rotation
    assert np.arctan2(-fy, -fx) == pytest.approx(-ocvirk_attitude(ecc), rel=1e-12)


def test_finite_solution_tends_to_the_short_bearing_for_small_l_over_d():
    kw = dict(diameter=0.1, radial_clearance=5e-5, viscosity=0.02)
    ratios = []
    for ld in (0.25, 0.125):
        f = JournalBearing(length=ld * 0.1, grid=(128, 8), **kw).coefficients(
            load=(0.0, -300.0 * ld), omega=300.0)
        s = JournalBearing(length=ld * 0.1, model="short", **kw).coefficients(
            load=(0.0, -300.0 * ld), omega=300.0)
        ratios.append(abs(f.eccentricity / s.eccentricity - 1))
        np.testing.assert_allclose(f.stiffness, s.stiffness, rtol=0.15,
                                   atol=0.02 * np.abs(s.stiffness).max())
    assert ratios[1] < ratios[0] < 0.05


def test_coefficients_feed_the_rotor_model():
    """Rigid rotor of mass m on two identical bearings: its translational whirl modes are the
    eigenvalues of m ẍ + 2C ẋ + 2K x = 0 (x, y); the FE rotor must contain them."""
    m, omega = 40.0, 600.0
    b = JournalBearing(diameter=0.06, length=0.03, radial_clearance=4e-5, viscosity=0.01)
    co = b.coefficients(load=(0.0, -3000.0), omega=omega)
    assert 0.5 < co.eccentricity < 0.7
    light = Material(youngs_modulus=2e14, density=1.0, poisson_ratio=0.3)
    rotor = Rotor(shaft=[ShaftSection(length=0.4, outer_diameter=0.12, material=light)],
                  disks=[Disk(0.2, mass=m, diametral_inertia=50.0, polar_inertia=1e-3)],
                  bearings=[co.bearing(0.0), co.bearing(0.4)], theory="euler-bernoulli")
    modes = rotor.natural_frequencies(omega, n_modes=4, error_estimate=False)
    k, c = 2 * co.stiffness, 2 * co.damping
    a = np.block([[np.zeros((2, 2)), np.eye(2)], [-k / m, -c / m]])
    s = np.linalg.eigvals(a)
    for w in s.imag[s.imag > 0]:
        assert np.min(np.abs(modes.omega / w - 1)) < 1e-4


def test_toml_journal_bearing_is_the_api_coefficients():
    from crankbench.predict.lateral.toml import load_rotor

    m = load_rotor("sample_data/rotors/journal_rotor.toml")
    co = JournalBearing(diameter=0.06, length=0.03, radial_clearance=4e-5,
                        viscosity=0.02).coefficients(load=(0.0, -230.0), omega=5700 * np.pi / 30)
    b = m.rotor.bearings[1]
    np.testing.assert_allclose([[b.kxx, b.kxy], [b.kyx, b.kyy]], co.stiffness, rtol=1e-12)
    np.testing.assert_allclose([[b.cxx, b.cxy], [b.cyx, b.cyy]], co.damping, rtol=1e-12)


def test_speed_dependent_journals_in_the_campbell_data_and_the_whirl_onset():
    """Rigid rotor on two short bearings, coefficients re-evaluated at every speed: the FE
    rotor's translational modes match the 4-state model, and the onset of instability
    (damping ratio through zero) is the 4-state model's, found here by root finding; at the
    onset the rotor whirls near half the spin speed (oil whirl, Newkirk & Taylor 1925)."""
    from scipy.optimize import brentq

    from crankbench.predict.lateral.elements import Bearing
    from crankbench.predict.lateral.journal import journal_campbell

    m = 20.0
    light = Material(youngs_modulus=2e14, density=1.0, poisson_ratio=0.3)
    rotor = Rotor(shaft=[ShaftSection(length=0.4, outer_diameter=0.12, material=light)],
                  disks=[Disk(0.2, mass=m, diametral_inertia=1e-3, polar_inertia=1e-3)],
                  bearings=[Bearing(0.0, 1e7), Bearing(0.4, 1e7)], theory="euler-bernoulli")
    b = JournalBearing(diameter=0.05, length=0.02, radial_clearance=5e-5, viscosity=0.01,
                       model="short")
    load = (0.0, -m * 9.81 / 2)
    speeds = np.linspace(2000, 20000, 10)
    camp = journal_campbell(rotor, [(0.0, b, load), (0.4, b, load)], speeds, n_modes=4)

    def four_state(rpm):
        co = b.coefficients(load=load, omega=rpm * np.pi / 30)
        k, c = 2 * co.stiffness, 2 * co.damping
        s = np.linalg.eigvals(np.block([[np.zeros((2, 2)), np.eye(2)], [-k / m, -c / m]]))
        s = s[s.imag > 0]
        i = int(np.argmin(-s.real / np.abs(s)))
        return -s[i].real / abs(s[i]), s[i].imag

    z, _ = four_state(2000.0)
    assert np.min(np.abs(camp[camp.speed_rpm == 2000.0].damping_ratio - z)) < 1e-4
    onset = brentq(lambda r: four_state(r)[0], 2000.0, 20000.0, xtol=1.0)
    assert camp.attrs["onset_speed_rpm"] == pytest.approx(onset, rel=0.01)
    ratio = four_state(onset)[1] / (onset * np.pi / 30)
    assert 0.4 < ratio < 0.55
