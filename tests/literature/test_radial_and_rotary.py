"""Radial rows with articulated rods and the rotary engine (seed 000: 梁守槃, 發動機動力學,
1948, ch. 3 主連桿與副連桿 / 連桿斜連之影響, ch. 7 星型發動機之振動, ch. 10 轉缸發動機).

Closed forms and second methods:
* a radial row acts on one crank throw; with identical kinematics its resultant excitation has
  only the orders q with Σ_c e^{−iqφ_c} ≠ 0, i.e. multiples of z/2 for a 4-stroke row of odd z
  firing every 720°/z (Liang ch. 7); articulated rods give every cylinder its own motion, so
  the other orders no longer cancel exactly (ch. 3, effect of the link rod);
* the per-cylinder excitation summed with the firing phases must equal the harmonics of the
  whole engine's turning moment from virtual work (:func:`predict.forces.engine_torque`);
* rotary engine (ch. 10): the reciprocating mass also circles the axis at radius x, kinetic
  energy ½ m ω² (x'² + x²); its inertia torque −½ ω² dJ/dθ is checked against the kinetic
  energy of the piston computed from its inertial coordinates.
"""

from pathlib import Path

import numpy as np
import pytest

import crankbench.predict.torsion as pt
from crankbench.predict.engine import Engine
from crankbench.predict.forces import engine_torque
from crankbench.predict.pressure import synthetic_pressure
from crankbench.predict.torsion.excitation import engine_excitation

DATA = Path(__file__).resolve().parents[2] / "sample_data"


def _row_sum(exc, engine, speed):
    h = exc.harmonics([speed], exc.orders)[0]                     # (n_o, z)
    phase = np.exp(-1j * np.deg2rad(np.outer(exc.orders, engine.firing_angles_deg())))
    return np.sum(h * phase, axis=1)


def test_radial_row_excitation_equals_the_engine_turning_moment():
    e = Engine.from_toml(DATA / "engines/radial5.toml")
    p = synthetic_pressure(e)
    exc = engine_excitation(e, pressure=p, orders=np.arange(0.5, 12.01, 0.5), points=2880)
    assert exc.gas.shape == (24, 5)
    w = 2200 * np.pi / 30
    n = 2880
    th = np.arange(n) * 4 * np.pi / n
    t = engine_torque(e, th, omega=w, pressure=p)
    spec = np.fft.rfft(t) / n * 2
    ref = spec[np.rint(exc.orders * 2).astype(int)]
    np.testing.assert_allclose(_row_sum(exc, e, w), ref, atol=1e-6 * np.abs(ref).max())


def test_articulated_rods_break_the_cancellation_of_minor_orders():
    e = Engine.from_toml(DATA / "engines/radial5.toml")
    plain = Engine(crank_angles_deg=[0] * 5, bank_angles_deg=e.bank_angles_deg,
                   crank_radius=e.crank_radius, rod_length=e.rod_length,
                   reciprocating_mass=1.9, firing_order=list(e.firing_order), bore=e.bore,
                   compression_ratio=e.compression_ratio, combustion=e.combustion)
    orders = np.array([1.0, 2.5, 3.0, 5.0])
    w = 2000 * np.pi / 30
    s_art = np.abs(_row_sum(engine_excitation(e, orders=orders), e, w))
    s_plain = np.abs(_row_sum(engine_excitation(plain, orders=orders), plain, w))
    major = np.isin(orders, [2.5, 5.0])
    assert np.all(s_plain[~major] < 1e-9 * s_plain[major].max())
    assert np.all(s_art[~major] > 1e-3 * s_art[major].max())


def test_radial_shaftline_row_on_one_node_and_its_major_orders():
    s = pt.from_toml(DATA / "shaftlines/radial5.toml")
    assert set(s.cylinder_nodes) == {s.node_names.index("crank throw")}
    crit = s.critical_speeds([1.0, 1.5, 2.5, 3.0, 5.0, 7.5], (500, 8000))
    assert len(crit) >= 3 and set(crit[crit.major].order) == {2.5, 5.0, 7.5}
    assert np.allclose(crit[crit.major].vector_sum, 5.0)
    r = s.forced_response(np.linspace(900, 2500, 5), orders=[2.5, 5.0, 7.5])
    assert np.all(np.isfinite(r.angle_total)) and r.angle_total.max() > 0


def _piston_kinetic_inertia(engine, theta, i):
    """J(θ) = m |d r/dθ|² of piston i from its inertial coordinates (rotating block)."""
    x = engine.piston_motion(theta)[0][i]
    beta = np.deg2rad(engine.bank_angles_deg[i])
    ang = theta + beta                          # the cylinder axis turns with the block
    r = x * np.exp(1j * ang)
    d = np.gradient(r, theta)
    return engine.reciprocating_mass[i] * np.abs(d) ** 2


def test_rotary_engine_inertia_torque_from_the_kinetic_energy():
    e = Engine.from_toml(DATA / "engines/rotary9.toml")
    assert e.rotary
    n = 20000
    th = np.arange(n) * 2 * np.pi / n
    w = 1200 * np.pi / 30
    parts = engine_torque(e, th, omega=w, per_cylinder=True)
    inner = slice(5, -5)
    for i in (0, 4):
        ref = -0.5 * w * w * np.gradient(_piston_kinetic_inertia(e, th, i), th)
        np.testing.assert_allclose(parts[i][inner], ref[inner], atol=1e-6 * np.abs(ref).max())
    got = parts.sum(axis=0)
    # nine plain rods on one pin: the inertia torque has orders 9, 18, ... only
    spec = np.abs(np.fft.rfft(got)) / n
    assert spec[[1, 2, 3, 4, 5, 6, 7, 8]].max() < 1e-9 * spec[9]
    # the same engine standing (crank turning) has no x x' term: torques differ
    still = replace_rotary(e, False)
    assert np.abs(engine_torque(still, th, omega=w) - got).max() > 0.1 * np.abs(got).max()


def replace_rotary(engine, rotary):
    return Engine(crank_angles_deg=engine.crank_angles_deg, bank_angles_deg=engine.bank_angles_deg,
                  crank_radius=engine.crank_radius, rod_length=engine.rod_length,
                  reciprocating_mass=engine.reciprocating_mass, firing_order=engine.firing_order,
                  bore=engine.bore, rotary=rotary)


def test_rotary_excitation_is_per_cylinder_and_scales_with_speed():
    e = Engine.from_toml(DATA / "engines/rotary9.toml")
    exc = engine_excitation(e, imep=6e5, orders=[4.5, 9.0])
    assert exc.inertia.shape == (2, 9) and "rotary" in exc.source
    w = 1100 * np.pi / 30
    n = 2880
    th = np.arange(n) * 4 * np.pi / n
    spec = np.fft.rfft(engine_torque(e, th, omega=w)) / n * 2     # inertia part only
    row = np.sum(exc.inertia * np.exp(-1j * np.deg2rad(np.outer([4.5, 9.0],
                                                                e.firing_angles_deg()))), 1)
    np.testing.assert_allclose(w * w * row, spec[[9, 18]], atol=1e-6 * np.abs(spec).max())
