"""Influence-coefficient balancing on synthetic runs with a known unbalance."""

import warnings

import numpy as np
import pytest

from crankbench.predict.errors import ModelError
from crankbench.predict.lateral.fe import Bearing, Disk, Material, Rotor, ShaftSection
from crankbench.predict.rotor_balance import (BalanceWarning, grade_check, influence_balance,
                                   permissible_unbalance, phasor, single_plane, two_plane)


def _rotor(plane_2=1.0):
    steel = Material(2.1e11, 7850.0, poisson_ratio=0.3)
    return Rotor(shaft=[ShaftSection(length=1.5, outer_diameter=0.05, material=steel)],
                 disks=[Disk(0.5, 30.0, 0.2, 0.35), Disk(plane_2, 30.0, 0.2, 0.35)],
                 bearings=[Bearing(0.0, 1e6, cxx=300.0), Bearing(1.5, 1e6, cxx=300.0)],
                 max_element_length=0.05)


def _runs(rotor, unbalance, trials, speed, planes=(0.5, 1.0), probes=(0.0, 1.5)):
    """x-direction phasors at the bearings for the initial run and each trial run, from the FE
    unbalance response (unbalance m·e as complex kg·m at each plane)."""
    def measure(u):
        items = [(p, abs(v), np.angle(v)) for p, v in zip(planes, u) if abs(v) > 0]
        return rotor.unbalance_response([speed], items, probes=list(probes)).response[0, :, 0]

    v0 = measure(unbalance)
    return v0, np.array([measure(unbalance + t) for t in trials])


def test_two_plane_recovers_known_unbalance_from_fe_runs():
    """Synthetic machine = the FE rotor (linear): the correction cancels the unbalance to 1 %
    (in fact to rounding, the data being exact)."""
    rotor = _rotor()
    radius = 0.1
    u0 = np.array([12e-3 * np.exp(0.7j), 8e-3 * np.exp(-2.1j)]) * radius  # kg·m
    trial = 10e-3 * radius
    trials = [np.array([trial, 0.0]), np.array([0.0, trial * 1j])]
    v0, runs = _runs(rotor, u0, trials, speed=250.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", BalanceWarning)
        result = two_plane(v0, runs, [trial / radius, 1j * trial / radius])
    np.testing.assert_allclose(result.corrections * radius, -u0, rtol=1e-8)
    assert np.all(np.abs(result.residual) < 1e-9 * np.abs(v0).max())
    frame = result.to_frame()
    assert frame.mass.to_numpy() == pytest.approx(np.abs(u0) / radius, rel=1e-8)
    assert result.plot().axes


def test_noise_stays_within_the_stated_bound():
    rng = np.random.default_rng(7)
    A = np.array([[2.0 + 1.0j, 0.6 - 0.2j], [0.4 + 0.5j, 1.5 - 0.7j]])
    u0 = np.array([0.01 * np.exp(0.3j), 0.007 * np.exp(2.0j)])
    trials = np.array([0.012, 0.012j])
    eps = 0.01
    for _ in range(20):
        noise = lambda v: v * (1 + eps * (rng.uniform(-1, 1, v.shape)  # noqa: E731
                                          * np.exp(1j * rng.uniform(0, 2 * np.pi, v.shape))))
        v0 = noise(A @ u0)
        runs = np.array([noise(A @ (u0 + np.array([trials[0], 0]))),
                         noise(A @ (u0 + np.array([0, trials[1]])))])
        result = two_plane(v0, runs, trials)
        err = np.linalg.norm(result.corrections + u0) / np.linalg.norm(u0)
        assert err <= result.error_bound(eps)


def test_small_trial_weight_and_ill_conditioning_warn():
    rotor = _rotor(plane_2=0.55)  # correction planes 50 mm apart: nearly the same influence
    radius = 0.1
    u0 = np.array([0.01, 0.005j]) * radius
    trial = 0.01 * radius
    v0, runs = _runs(rotor, u0, [np.array([trial, 0]), np.array([0, trial])], speed=100.0,
                     planes=(0.5, 0.55))
    with pytest.warns(BalanceWarning, match="influence matrix condition number"):
        result = two_plane(v0, runs, [trial / radius, trial / radius])
    assert result.condition_number > 30
    rotor = _rotor()
    v0, runs = _runs(rotor, u0, [np.array([1e-5 * trial, 0]), np.array([0, trial])],
                     speed=250.0)
    with pytest.warns(BalanceWarning, match=r"trial run 1 changed the vibration by only .* the "
                                            r"trial weight was too small"):
        result = two_plane(v0, runs, [1e-5 * trial / radius, trial / radius])
    assert any("too small" in w for w in result.warnings)


def test_single_plane_closed_form_and_least_squares():
    v0, v1, ut = phasor(100.0, 30.0), phasor(60.0, 120.0), phasor(0.01, 0.0)
    r = single_plane(v0, v1, ut)
    assert r.corrections[0] == pytest.approx(-v0 / ((v1 - v0) / ut), rel=1e-14)
    # three measurement planes, two correction planes: least squares, exact data recovered
    A = np.array([[1.0, 0.2j], [0.5 - 0.1j, 0.8], [0.3j, 1.2]])
    u0 = np.array([0.004 + 0.002j, -0.003j])
    runs = np.array([A @ (u0 + [0.01, 0]), A @ (u0 + [0, 0.01])])
    r = influence_balance(A @ u0, runs, [0.01, 0.01])
    np.testing.assert_allclose(r.corrections, -u0, rtol=1e-12)
    np.testing.assert_allclose(r.influence, A, rtol=1e-12)
    assert r.influence_frame().shape == (6, 4)


def test_trial_mass_matrix_form_and_residual_from_check_run():
    A = np.array([[2.0 + 1j, 0.5], [0.3j, 1.5 - 0.5j]])
    u0 = np.array([0.01, 0.006j])
    masses = np.array([[0.01, 0.0], [0.01, 0.012j]])  # first trial left on for run 2
    runs = np.array([A @ (u0 + m) for m in masses])
    r = influence_balance(A @ u0, runs, masses)
    np.testing.assert_allclose(r.corrections, -u0, rtol=1e-12)
    leftover = np.array([0.001, -0.0005j])
    np.testing.assert_allclose(r.residual_unbalance(A @ leftover), -leftover, rtol=1e-12)


def test_iso_permissible_unbalance():
    """G = e_per Ω: G 6.3 at 3000 rpm gives e_per = 6.3 mm/s / 314.16 rad/s = 20.05 µm."""
    omega = 3000 * np.pi / 30
    u = permissible_unbalance(6.3, rotor_mass=1.0, max_omega=omega)
    assert u == pytest.approx(20.05e-6, rel=1e-3)
    check = grade_check([3e-4, 5e-4], rotor_mass=50.0, max_omega=omega, grade=6.3)
    per_plane = permissible_unbalance(6.3, rotor_mass=50.0, max_omega=omega) / 2
    assert check.permissible == pytest.approx([per_plane, per_plane])
    assert check.passed == bool(5e-4 <= per_plane)
    assert check.smallest_grade == 6.3
    assert check.achieved_grade == pytest.approx(8e-4 / 50.0 * omega * 1e3)
    assert check.to_frame().shape[0] == 2 and check.plot().axes


def test_input_errors_are_named():
    with pytest.raises(ModelError, match="trial_runs has 3 measurement planes per run"):
        influence_balance([1.0, 1.0], np.ones((2, 3)), [1.0, 1.0])
    with pytest.raises(ModelError, match="trial_masses has 1 values for 2 trial runs"):
        influence_balance([1.0, 1.0], np.ones((2, 2)), [1.0])
    with pytest.raises(ModelError, match="initial vibration is zero"):
        influence_balance([0.0, 0.0], np.ones((2, 2)), [1.0, 1.0])
    with pytest.raises(ModelError, match="two_plane needs 2 measurement planes"):
        two_plane([1.0, 1.0, 1.0], np.ones((2, 3)), [1.0, 1.0])
    with pytest.raises(ModelError, match="amplitude must be >= 0"):
        phasor(-1.0, 0.0)


def test_nearly_dependent_trial_weight_sets_warn():
    """Both runs carry almost the same trial-weight set: the trial-mass matrix is
    ill-conditioned and the influence matrix cannot be separated reliably."""
    A = np.array([[2.0 + 1j, 0.5], [0.3j, 1.5 - 0.5j]])
    u0 = np.array([0.01, 0.006j])
    masses = np.array([[0.01, 0.01], [0.01, 0.0102]])
    runs = np.array([A @ (u0 + m) for m in masses])
    with pytest.warns(BalanceWarning, match=r"trial-mass matrix condition .* nearly dependent"):
        r = influence_balance(A @ u0, runs, masses)
    assert r.trial_condition > 30
