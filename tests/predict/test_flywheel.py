"""Flywheel: energy fluctuation closed forms, speed fluctuation against an ODE integration of the
crankshaft's motion, sizing round trip, stresses, CLI."""

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from crankbench.predict import flywheel as fw
from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.forces import engine_torque
from crankbench.predict.pressure import synthetic_pressure


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures the result objects' plot() made (matplotlib warns past 20)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


ENGINES_DIR = Path(__file__).resolve().parents[2] / "sample_data" / "engines"


def _sinusoid(n_points=720, mean=300.0, amp=400.0, order=2, period=4 * np.pi, omega=300.0):
    a = np.arange(n_points) * period / n_points
    return fw.TurningMoment.from_torque(a, mean + amp * np.sin(order * 2 * np.pi / period * a),
                                        omega=omega)


def test_energy_fluctuation_of_a_harmonic_torque():
    """T = T_m + A sin(kφ): E swings by 2A/k (Applied Mechanics vol. 2 §6)."""
    for order in (1, 2, 3, 7):
        tm = _sinusoid(order=order, period=2 * np.pi)
        assert tm.fluctuation_of_energy == pytest.approx(2 * 400.0 / order, rel=1e-12)
        assert tm.fluctuation_error() < 1e-9


def test_energy_fluctuation_converges_for_engine_torque():
    e = Engine.from_toml(ENGINES_DIR / "i4.toml")
    tr = synthetic_pressure(e)
    w = 3000 * np.pi / 30
    coarse = fw.turning_moment(e, omega=w, pressure=tr, points_per_cycle=1440)
    fine = fw.turning_moment(e, omega=w, pressure=tr, points_per_cycle=11520)
    assert coarse.fluctuation_of_energy == pytest.approx(fine.fluctuation_of_energy, rel=1e-4)
    assert coarse.mean_torque == pytest.approx(4 * tr.work(e) / (4 * np.pi), rel=2e-5)


def test_fluctuation_error_estimate_bounds_the_error_for_a_kinked_torque():
    """Rectified sine T = |sin φ| over a period π: ΔE = 2 cos φ₁ − 2 + 4φ₁/π, sin φ₁ = 2/π."""
    p1 = np.arcsin(2 / np.pi)
    exact = 2 * np.cos(p1) - 2 + 4 * p1 / np.pi
    for n in (90, 720):
        a = np.arange(n) * np.pi / n
        tm = fw.TurningMoment.from_torque(a, np.abs(np.sin(a)), omega=1.0)
        err = abs(tm.fluctuation_of_energy - exact)
        assert err <= tm.fluctuation_error() <= 10 * err


def test_speed_fluctuation_matches_ode_integration():
    """Integrate J dω/dt = T(φ) − T_load, dφ/dt = ω and measure (ω_max − ω_min)/ω_mid."""
    e = Engine.from_toml(ENGINES_DIR / "single.toml")
    tr = synthetic_pressure(e)
    w = 3000 * np.pi / 30
    tm = fw.turning_moment(e, omega=w, pressure=tr, points_per_cycle=2880)
    inertia = 0.35
    load = tm.mean_torque

    def rhs(t, y):
        return [y[1], (engine_torque(e, np.array([y[0]]), omega=w, pressure=tr)[0] - load)
                / inertia]

    w_start = tm.speed(inertia)[0]
    sol = solve_ivp(rhs, (0, 4 * np.pi / w * 1.02), [0.0, w_start], rtol=1e-10, atol=1e-10,
                    max_step=4 * np.pi / w / 2000, dense_output=True)
    t = np.linspace(0, sol.t[-1], 20001)
    phi, omega = sol.sol(t)
    keep = phi <= 4 * np.pi
    wmax, wmin = omega[keep].max(), omega[keep].min()
    delta_ode = (wmax - wmin) / (0.5 * (wmax + wmin))
    delta = tm.fluctuation_of_energy / (inertia * (0.5 * (wmax + wmin)) ** 2)
    assert delta_ode == pytest.approx(delta, rel=2e-4)
    # and the speed curve from the energy equation agrees with the ODE
    np.testing.assert_allclose(np.interp(tm.angle, phi[keep], omega[keep]),
                               tm.speed(inertia), rtol=2e-6)
    # the speed curve's time-mean is the nominal speed
    sp = tm.speed(inertia)
    assert 1 / np.mean(1 / sp) == pytest.approx(w, rel=1e-12)


def test_flywheel_sizing_round_trip_and_stresses():
    tm = _sinusoid()
    j = fw.flywheel_inertia(tm, 0.02)
    assert tm.speed_fluctuation(j) == pytest.approx(0.02, rel=1e-12)
    assert fw.flywheel_inertia(tm, 0.02, other_inertia=0.1) == pytest.approx(j - 0.1)
    with pytest.raises(ModelError, match="already meets"):
        fw.flywheel_inertia(tm, 0.02, other_inertia=10.0)
    d = fw.design_flywheel(tm, coefficient=0.02, outer_radius=0.25, shape="disc",
                           density=7850.0)
    assert d.mass == pytest.approx(2 * j / 0.25**2)
    w_top = 300.0 * 1.01
    assert d.stress == pytest.approx((3.3 / 8) * 7850.0 * w_top**2 * 0.25**2)
    assert fw.rim_stress(omega=100.0, radius=0.5, density=7200.0) == pytest.approx(
        7200.0 * 50.0**2)
    assert d.to_frame().shape == (1, 10) and d.plot() is not None
    assert tm.to_frame().shape[1] == 3 and tm.plot() is not None


def test_predict_flywheel_cli_json(capsys):
    from crankbench.analysis.cli import main

    rc = main(["predict", "flywheel", str(ENGINES_DIR / "i4.toml"), "--speed-rpm", "2000",
               "--json", "--inertia", "0.2"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["engine"] == "I4 2.0 l"
    assert out["coefficient_of_speed_fluctuation"] == pytest.approx(
        out["fluctuation_of_energy_j"] / (0.2 * (2000 * np.pi / 30) ** 2))
    assert out["flywheel"][0]["coefficient"] == 0.01
