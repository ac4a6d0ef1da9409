"""Dampers against Den Hartog, *Mechanical Vibrations*, 4th ed., McGraw-Hill, 1956.

* §8.6 Lanchester damper with dry friction: with the hub moving a sin ωt the ring slipping
  throughout dissipates W = 4 T_s a √(1 − (π T_s/(2 J ω² a))²) per cycle, largest at
  T_s = (√2/π) J ω² a, where W = (4/π) J ω² a². Second method: the exact piecewise (event by
  event) ring motion, and time integration of the non-linear hub + ring system.
* §3.3 damped vibration absorber: the fixed points P, Q through which every damping curve
  passes, equal heights √(1 + 2/μ) at optimum tuning f = 1/(1 + μ) (eq. 3.29-3.31).
"""

import numpy as np
import pytest

from crankbench.predict.torsion import chain, dampers
from crankbench.predict.torsion.friction import (CONTINUOUS_SLIP_LIMIT, _ring_cycle,
                                                 friction_damper_response,
                                                 friction_dissipation,
                                                 friction_dynamic_stiffness,
                                                 optimum_slip_torque, time_domain_sdof)


def test_den_hartog_optimum_slip_torque_and_energy():
    j, w, a = 0.5, 300.0, 0.004
    opt = optimum_slip_torque(ring_inertia=j, omega=w, hub_amplitude=a)
    assert opt["slip_torque"] == pytest.approx(np.sqrt(2) / np.pi * j * w * w * a, rel=1e-14)
    assert opt["energy_per_cycle"] == pytest.approx(4 / np.pi * j * w * w * a * a, rel=1e-14)
    # the closed form's maximum, located independently on the exact piecewise motion
    xs = np.linspace(0.3, 0.6, 61)
    sim = np.array([np.pi * -_ring_cycle(x)[1] for x in xs])       # W/(J ω² a²) = π Im Z
    k = int(np.argmax(sim))
    assert xs[k] == pytest.approx(np.sqrt(2) / np.pi, abs=0.006)
    assert sim[k] == pytest.approx(4 / np.pi, rel=1e-3)
    w_at_opt = friction_dissipation(slip_torque=opt["slip_torque"], ring_inertia=j, omega=w,
                                    hub_amplitude=a)
    assert w_at_opt == pytest.approx(opt["energy_per_cycle"], rel=1e-12)


@pytest.mark.parametrize("x", [0.1, 0.3, 0.5])
def test_continuous_slip_energy_formula(x):
    j, w, a = 0.8, 250.0, 0.01
    ts = x * j * w * w * a
    expected = 4 * ts * a * np.sqrt(1 - (np.pi * ts / (2 * j * w * w * a)) ** 2)
    got = friction_dissipation(slip_torque=ts, ring_inertia=j, omega=w, hub_amplitude=a)
    assert got == pytest.approx(expected, rel=1e-12)
    # and the exact ring motion agrees (sampling of the square wave: 1e-3)
    assert -np.pi * _ring_cycle(x)[1] * j * w * w * a * a == pytest.approx(expected, rel=2e-3)


def test_stick_slip_between_the_limit_and_full_stick_is_the_exact_motion():
    xs = np.linspace(CONTINUOUS_SLIP_LIMIT, 1.0, 37)[1:-1]
    sim = np.array([-(a + 1j * b) for a, b in (_ring_cycle(x) for x in xs)])
    np.testing.assert_allclose(friction_dynamic_stiffness(xs), sim, atol=1e-3)
    assert friction_dynamic_stiffness(1.2) == -1.0     # sticks: pure added inertia
    assert friction_dissipation(slip_torque=500.0, ring_inertia=0.5, omega=300.0,
                                hub_amplitude=0.004) == 0.0


def test_slip_stick_response_across_resonance_against_time_integration():
    jh, k, c, jr, t = 1.0, 1e5, 5.0, 0.25, 60.0
    s = chain([jh], [k]).replace(cylinder_nodes=[0], firing_angles_deg=[0.0], node_damping=[c])
    wn = np.sqrt(k / jh)
    rpm = np.array([0.88, 0.95, 1.0, 1.05]) * wn * 30 / np.pi
    for ts in (10.0, 80.0):
        r = friction_damper_response(s, 0, ring_inertia=jr, slip_torque=ts, speed_rpm=rpm,
                                     order=1.0, torque=t)
        ref = [time_domain_sdof(inertia=jh, stiffness=k, damping=c, ring_inertia=jr,
                                slip_torque=ts, omega=w, torque=t, cycles=120,
                                steps_per_cycle=240) for w in rpm * np.pi / 30]
        # first-harmonic balance: within 5 % of the exact non-linear steady state
        np.testing.assert_allclose(r.hub_amplitude, ref, rtol=0.05)
    assert {"stick", "stick-slip"} & set(r.state)


def test_friction_damper_lowers_the_resonance_most_near_the_optimum_torque():
    jh, k, c, jr, t = 1.0, 1e5, 2.0, 0.25, 60.0
    s = chain([jh], [k]).replace(cylinder_nodes=[0], firing_angles_deg=[0.0], node_damping=[c])
    rpm = np.linspace(0.8, 1.1, 121) * np.sqrt(k / jh) * 30 / np.pi
    peaks = {ts: friction_damper_response(s, 0, ring_inertia=jr, slip_torque=ts, speed_rpm=rpm,
                                          order=1.0, torque=t).hub_amplitude.max()
             for ts in (2.0, 20.0, 2000.0)}
    assert peaks[20.0] < peaks[2.0] and peaks[20.0] < peaks[2000.0]


def test_fixed_points_are_independent_of_damping():
    mu, f = 0.2, 0.9
    p = dampers.fixed_points(mass_ratio=mu, frequency_ratio=f)
    for g, h in ((p["frequency_p"], p["height_p"]), (p["frequency_q"], p["height_q"])):
        for z in (0.01, 0.1, 0.5, 5.0):
            assert dampers.tuned_absorber_response(g, mass_ratio=mu, frequency_ratio=f,
                                                   damping_ratio=z) == pytest.approx(h, rel=1e-9)
    opt = dampers.fixed_points(mass_ratio=mu, frequency_ratio=1 / (1 + mu))
    assert opt["height_p"] == pytest.approx(np.sqrt(1 + 2 / mu), rel=1e-12)
    assert opt["height_q"] == pytest.approx(np.sqrt(1 + 2 / mu), rel=1e-12)


def test_absorber_formula_against_the_two_mass_forced_response():
    """Second method: the same 2-DOF system through the torsional solver."""
    j, k, mu, f, z = 2.0, 8.0e4, 0.25, 0.8, 0.12
    wn = np.sqrt(k / j)
    ja, ka = mu * j, mu * j * (f * wn) ** 2
    ca = 2 * z * ja * wn
    s = chain([j, ja], [k, ka]).replace(edge_damping=[0.0, ca], cylinder_nodes=[0],
                                        firing_angles_deg=[0.0])
    g = np.linspace(0.5, 1.5, 41)
    r = s.forced_response(g * wn * 30 / np.pi, torque=[1.0], orders=[1.0], superpose=False)
    np.testing.assert_allclose(np.abs(r.angle[:, 0, 0]) * k,
                               dampers.tuned_absorber_response(g, mass_ratio=mu,
                                                               frequency_ratio=f,
                                                               damping_ratio=z), rtol=1e-10)
    # Den Hartog's optimum (f = 1/(1+μ), ζ² = 3μ/(8(1+μ)³)): peak ≈ √(1 + 2/μ)
    fo, zo, mag = dampers.den_hartog_optimum(mu)
    gg = np.linspace(0.6, 1.3, 20001)
    peak = dampers.tuned_absorber_response(gg, mass_ratio=mu, frequency_ratio=fo,
                                           damping_ratio=zo).max()
    assert peak == pytest.approx(mag, rel=0.02)


def test_pendulum_length_for_an_order():
    r = dampers.pendulum_length(4.5, pivot_radius=0.12)
    assert dampers.pendulum_order(pivot_radius=0.12, length=r) == pytest.approx(4.5, rel=1e-15)
