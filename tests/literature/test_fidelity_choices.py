"""Textbook approximations as explicit lower fidelities, with their error against the exact
model.

* [Liang] 梁守槃, 發動機動力學 (1948), ch. 1 §1-2 eq. (4): the acceleration coefficients as
  power series in λ: a₂ = λ + λ³/4 + 15λ⁵/128 + 35λ⁷/512 + …, a₄ = −(λ³/4 + 3λ⁵/16 +
  35λ⁷/256 + …), a₆ = 9λ⁵/128 + 45λ⁷/512 + …; the two-term form a = rω²(cos θ + λ cos 2θ)
  and x = r cos θ + l − (λr/4)(1 − cos 2θ).
* [Taylor] C. F. Taylor, *The Internal-Combustion Engine in Theory and Practice*, vol. 2
  (1968) ch. 8: with the two-term piston motion the reciprocating inertia torque is
  T = m r² ω² (λ/4 sin θ − ½ sin 2θ − 3λ/4 sin 3θ − λ²/4 sin 4θ).
* [Stodola] matrix iteration of the deflection curve, one iterate at a time (Thomson &
  Dahleh §7.3), against the exact eigen-solve of the same lumped model.
"""

import numpy as np
import pytest

from crankbench.predict.engine import Engine
from crankbench.predict.forces import engine_torque
from crankbench.predict.kinematics import piston_acceleration, series_coefficients, series_error
from crankbench.predict.lateral.approx import MassShaft, lumped_exact, stodola


@pytest.mark.parametrize("lam", [0.25, 0.3])
def test_lambda_power_truncations_are_liangs_series(lam):
    a2 = [lam, lam ** 3 / 4, 15 * lam ** 5 / 128, 35 * lam ** 7 / 512]
    a4 = [-lam ** 3 / 4, -3 * lam ** 5 / 16, -35 * lam ** 7 / 256]
    a6 = [9 * lam ** 5 / 128, 45 * lam ** 7 / 512]
    for k in range(1, 4):
        c = series_coefficients(lam, 8, lambda_terms=k)
        assert c[2] == pytest.approx(sum(a2[:k]), rel=1e-14)
        assert c[4] == pytest.approx(sum(a4[:k]), rel=1e-14)
        if k <= 2:
            assert c[6] == pytest.approx(sum(a6[:k]), rel=1e-14)
    # more terms converge to the exact coefficients
    exact = series_coefficients(lam, 8)
    assert abs(series_coefficients(lam, 8, lambda_terms=12)[2] - exact[2]) < 1e-12


def test_two_term_textbook_acceleration_and_its_error():
    r, l, w = 0.05, 0.2, 300.0
    th = np.linspace(0, 2 * np.pi, 721)
    two = piston_acceleration(th, crank_radius=r, rod_length=l, omega=w, max_order=2,
                              lambda_terms=1)
    np.testing.assert_allclose(two, -r * w * w * (np.cos(th) + r / l * np.cos(2 * th)),
                               rtol=1e-13, atol=1e-10)
    exact = piston_acceleration(th, crank_radius=r, rod_length=l, omega=w)
    err = series_error(r / l, max_order=2, lambda_terms=1)
    assert np.max(np.abs(two - exact)) / (r * w * w) == pytest.approx(err, rel=1e-3)
    # the exact coefficients of the same order are better, at the rigorous tail bound
    assert series_error(r / l, max_order=2) < err


def test_engine_with_textbook_motion_gives_taylors_inertia_torque():
    r, l, m, w = 0.05, 0.2, 2.0, 300.0
    lam = r / l
    e = Engine(crank_angles_deg=[0], crank_radius=r, rod_length=l, reciprocating_mass=m,
               series_order=2, lambda_terms=1)
    th = np.linspace(0, 2 * np.pi, 361)
    x, _, _ = e.piston_motion(th)
    np.testing.assert_allclose(x[0], r * np.cos(th) + l - lam * r / 4 * (1 - np.cos(2 * th)),
                               rtol=1e-14)
    t = engine_torque(e, th, omega=w)
    taylor = m * r * r * w * w * (lam / 4 * np.sin(th) - 0.5 * np.sin(2 * th)
                                  - 3 * lam / 4 * np.sin(3 * th)
                                  - lam ** 2 / 4 * np.sin(4 * th))
    np.testing.assert_allclose(t, taylor, atol=1e-9 * m * r * r * w * w)
    exact = engine_torque(Engine(crank_angles_deg=[0], crank_radius=r, rod_length=l,
                                 reciprocating_mass=m), th, omega=w)
    # the lower fidelity costs a few per cent of m r² ω² at λ = 0.25
    assert 1e-3 < np.max(np.abs(t - exact)) / (m * r * r * w * w) < 0.05


def test_stodola_iterates_one_by_one():
    s = MassShaft(length=2.0, youngs_modulus=2.1e11, area_moment=np.pi * 0.05 ** 4 / 64,
                  mass_per_length=15.0, masses=[40.0, 25.0, 60.0], positions=[0.5, 1.1, 1.6])
    ref = lumped_exact(s).omega
    r = stodola(s, iterations=4)
    it = r.iterates()
    assert list(it.iteration) == [1, 2, 3, 4] and r.iterations == 4
    err = np.abs(it.omega - ref) / ref
    assert np.all(np.diff(err) <= 1e-15)                      # never worse than before
    assert np.all(it.lower <= ref * (1 + 1e-12)) and np.all(it.upper >= ref * (1 - 1e-12))
    assert err.iloc[0] < 1e-2                                 # one iterate: within 1 %


def test_double_acting_cylinder_with_and_without_the_piston_rod_area():
    """Double-acting cylinder (both chambers fire, half a cycle apart): the force is
    (p(ψ) − p_cc)A − (p(ψ − π) − p_cc)(A − a) for a 2-stroke; neglecting the rod (a = 0, the
    textbook lower fidelity) makes it antisymmetric, F(ψ + π) = −F(ψ), and costs p_bottom·a."""
    from crankbench.predict.forces import gas_force
    from crankbench.predict.pressure import synthetic_pressure
    from crankbench.predict.torsion.excitation import engine_excitation

    kw = dict(crank_angles_deg=[0], crank_radius=0.3, rod_length=1.2, reciprocating_mass=900.0,
              bore=0.5, cycle=2, compression_ratio=12.0, double_acting=True)
    with_rod = Engine(piston_rod_diameter=0.18, **kw)
    no_rod = Engine(piston_rod_diameter=0.0, **kw)
    p = synthetic_pressure(Engine(**{**kw, "double_acting": False}), imep=8e5)
    psi = np.linspace(0, 2 * np.pi, 361)[:-1]
    f0 = gas_force(no_rod, psi, p)
    np.testing.assert_allclose(gas_force(no_rod, psi + np.pi, p), -f0, atol=1e-6 * np.abs(f0).max())
    f1 = gas_force(with_rod, psi, p)
    rod = np.pi * 0.18 ** 2 / 4
    np.testing.assert_allclose(f1 - f0, (p.at(psi - np.pi) - 1e5) * rod, rtol=1e-12, atol=1e-6)
    # the torsional excitation follows the engine's turning moment (second method: FFT)
    exc = engine_excitation(with_rod, pressure=p, orders=[1.0, 2.0, 3.0], points=1440)
    n = 1440
    th = np.arange(n) * 2 * np.pi / n
    spec = np.fft.rfft(engine_torque(with_rod, th, omega=0.0, pressure=p)) / n * 2
    np.testing.assert_allclose(exc.gas, spec[1:4], rtol=1e-9, atol=1e-6 * np.abs(spec).max())
