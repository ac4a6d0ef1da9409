"""Forces and torque: mean torque against ∮p dV, two torque formulas against each other, the
inertia torque against the kinetic-energy derivative, force-triangle identities, pressure model."""

import numpy as np
import pytest

from crankbench.predict import forces
from crankbench.predict import kinematics as kin
from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.pressure import PressureTrace, synthetic_pressure


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures the result objects' plot() made (matplotlib warns past 20)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


W = 2 * np.pi * 3000 / 60


@pytest.fixture(scope="module")
def i4():
    return Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.043, rod_length=0.145,
                  reciprocating_mass=0.55, rotating_mass=0.4,
                  cylinder_positions=[0, 0.09, 0.18, 0.27], firing_order=[1, 3, 4, 2],
                  bore=0.086, compression_ratio=10.5)


@pytest.fixture(scope="module")
def trace(i4):
    return synthetic_pressure(i4, peak_pressure=7e6)


def test_mean_engine_torque_equals_indicated_work_per_cycle(i4, trace):
    """Mean turning moment = n · ∮p dV / (4π) for a 4-stroke (Liang 1948 ch. 5 §5-3)."""
    n = 4 * 1440 * 4
    theta = np.arange(n) * 4 * np.pi / n
    torque = forces.engine_torque(i4, theta, omega=W, pressure=trace)
    work = trace.work(i4)                        # Stieltjes sum over the exact volume
    assert torque.mean() == pytest.approx(4 * work / (4 * np.pi), rel=2e-5)
    # and the imep route: W = imep · V_s
    assert work == pytest.approx(trace.imep(i4) * i4.swept_volume, rel=1e-12)


def test_inertia_torque_has_zero_mean_and_equals_minus_dEk_dtheta(i4):
    n = 2048
    theta = np.arange(n) * 2 * np.pi / n
    t = forces.cylinder_torque(i4, theta, omega=W)
    assert abs(t.mean()) < 1e-12 * np.abs(t).max()
    # T_inertia = −d/dθ (½ m v²) at constant ω; v from the kinematics module
    h = 1e-5
    m = i4.reciprocating_mass[0]

    def ek(th):
        v = kin.piston_velocity(th, crank_radius=i4.crank_radius, rod_length=i4.rod_length,
                                omega=W)
        return 0.5 * m * v**2

    ref = -(ek(theta + h) - ek(theta - h)) / (2 * h)
    np.testing.assert_allclose(t, ref, atol=1e-6 * np.abs(t).max())


def test_inertia_torque_series_leading_terms():
    """T = m r²ω² [λ/4 sin θ − ½ sin 2θ − 3λ/4 sin 3θ − λ²/4 sin 4θ + O(λ³)] (small λ)."""
    lam = 0.01
    e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.05 / lam,
               reciprocating_mass=1.0, cycle=2)
    h = forces.torque_harmonics(e, omega=100.0, max_order=4)
    scale = 1.0 * 0.05**2 * 100.0**2
    np.testing.assert_allclose(h["sin"].values / scale,
                               [lam / 4, -0.5, -3 * lam / 4, -lam**2 / 4], atol=3 * lam**3)
    np.testing.assert_allclose(h["cos"].values, 0.0, atol=1e-12 * scale)


def test_tangential_force_formula_matches_virtual_work_torque(i4, trace):
    th = np.linspace(0, 4 * np.pi, 721)
    f = forces.crank_forces(i4, th, omega=W, pressure=trace, cylinder=3)
    np.testing.assert_allclose(f.tangential * i4.crank_radius, f.torque,
                               atol=1e-9 * np.abs(f.torque).max())
    # force triangle at the piston pin and at the crank pin
    np.testing.assert_allclose(f.rod**2, f.piston**2 + f.side_thrust**2,
                               rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(f.rod**2, f.tangential**2 + f.radial**2, rtol=1e-12, atol=1e-6)
    t = forces.cylinder_torque(i4, th, omega=W, pressure=trace, cylinder=3)
    np.testing.assert_allclose(t, f.torque, rtol=1e-12, atol=1e-9)
    frame = f.to_frame()
    assert "torque_nm" in frame and len(frame) == th.size
    assert f.plot() is not None


def test_engine_torque_is_sum_of_phase_shifted_cylinder_torques(i4, trace):
    th = np.linspace(0, 4 * np.pi, 97)
    total = forces.engine_torque(i4, th, omega=W, pressure=trace)
    fire = np.deg2rad(i4.firing_angles_deg())
    ref = sum(forces.cylinder_torque(i4, th - fire[i], omega=W, pressure=trace, cylinder=i + 1)
              for i in range(4))
    np.testing.assert_allclose(total, ref, rtol=1e-12, atol=1e-9)


def test_gas_force_is_pressure_times_area():
    e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
               reciprocating_mass=1.0, bore=0.1)
    tr = PressureTrace.from_measured([0, 1, 2, 3], [5e6, 2e6, 1e5, 1e5])
    assert forces.gas_force(e, 0.0, tr, crankcase_pressure=0.0) == pytest.approx(
        5e6 * np.pi * 0.01 / 4)


def test_synthetic_pressure_meets_load_targets(i4):
    tr = synthetic_pressure(i4, imep=1.1e6)
    assert tr.imep(i4) == pytest.approx(1.1e6, rel=1e-10)
    tr = synthetic_pressure(i4, peak_pressure=8e6)
    assert tr.pressure.max() == pytest.approx(8e6, rel=1e-12)
    assert tr.error_estimate < 1e-5
    # polytropic compression before combustion: p V^k constant
    k = tr.parameters["polytropic_exponent"]
    ang = np.deg2rad([-150.0, -60.0]) + 4 * np.pi
    v = i4.cylinder_volume(i4.shaft_angle(ang))[0]
    p = tr.at(ang)
    assert p[0] * v[0] ** k == pytest.approx(p[1] * v[1] ** k, rel=1e-9)
    assert tr.to_frame().shape == (1440, 2)
    assert tr.plot() is not None


def test_pressure_errors():
    e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2, reciprocating_mass=1.0,
               bore=0.1, compression_ratio=9.0)
    with pytest.raises(ModelError, match="give exactly one of peak_pressure"):
        synthetic_pressure(e)
    with pytest.raises(ModelError, match=r"peak_pressure=1000000.0 Pa is not above the motored"):
        synthetic_pressure(e, peak_pressure=1e6)
    with pytest.raises(ModelError, match="angle must increase strictly"):
        PressureTrace.from_measured([0, 2, 1, 3], [1, 1, 1, 1])
    with pytest.raises(ModelError, match=r"pressure trace is for a 2-stroke cycle"):
        forces.gas_force(e, 0.0, PressureTrace.from_measured([0, 1, 2, 3], [1, 1, 1, 1],
                                                             cycle=2))
    with pytest.raises(ModelError, match=r"cylinder=2 must be <= 1"):
        forces.cylinder_torque(e, 0.0, omega=1.0, cylinder=2)


def test_two_stroke_mean_torque_and_trace():
    e = Engine(crank_angles_deg=[0, 120, 240], crank_radius=0.2, rod_length=0.8,
               reciprocating_mass=210.0, cylinder_positions=[0, 0.5, 1.0], cycle=2,
               firing_order=[1, 3, 2], bore=0.32, compression_ratio=15.0)
    tr = synthetic_pressure(e, imep=1.8e6, intake_pressure=2.5e5, exhaust_pressure=2.3e5)
    assert tr.angle[-1] < 2 * np.pi and tr.imep(e) == pytest.approx(1.8e6, rel=1e-10)
    n = 2880
    theta = np.arange(n) * 2 * np.pi / n
    torque = forces.engine_torque(e, theta, omega=60.0, pressure=tr)
    assert torque.mean() == pytest.approx(3 * tr.work(e) / (2 * np.pi), rel=2e-5)
    np.testing.assert_allclose(np.diff(np.sort(e.firing_angles_deg())), [120, 120])


def test_rod_residual_couple_torque_is_minus_derivative_of_its_kinetic_energy():
    """With the residual-couple inertia ΔJ the extra torque is −d/dθ(½ ΔJ φ̇²) (energy)."""
    from crankbench.predict.masses import Rod

    rod = Rod(mass=0.6, length=0.145, cg_from_big_end=0.04, inertia_cg=0.0021)
    dj = rod.two_point().inertia_error
    base = dict(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.043, rod_length=0.145,
                reciprocating_mass=0.55, firing_order=[1, 3, 4, 2], bore=0.086)
    plain = Engine(**base)
    corrected = Engine(**base, rod_inertia_correction=dj)
    th = np.linspace(0, 4 * np.pi, 181)
    extra = forces.engine_torque(corrected, th, omega=W) - forces.engine_torque(plain, th,
                                                                                 omega=W)
    h = 1e-5
    fire = np.deg2rad(plain.firing_angles_deg())

    def ek(t):
        return sum(0.5 * dj * kin.rod_angular_velocity(t - f, crank_radius=0.043,
                                                       rod_length=0.145, omega=W) ** 2
                   for f in fire)

    ref = -(ek(th + h) - ek(th - h)) / (2 * h)
    np.testing.assert_allclose(extra, ref, atol=1e-6 * np.abs(ref).max())
    assert np.abs(extra).max() > 0.01
    # single cylinder: same energy relation for cylinder 1 alone
    one = forces.cylinder_torque(corrected, th, omega=W) - forces.cylinder_torque(plain, th,
                                                                                  omega=W)

    def ek1(t):
        return 0.5 * dj * kin.rod_angular_velocity(t, crank_radius=0.043, rod_length=0.145,
                                                   omega=W) ** 2

    np.testing.assert_allclose(one, -(ek1(th + h) - ek1(th - h)) / (2 * h),
                               atol=1e-6 * np.abs(one).max())
    with pytest.raises(ModelError, match=r"rod_inertia_correction has 2 values, expected 4"):
        Engine(**base, rod_inertia_correction=[dj, dj])
