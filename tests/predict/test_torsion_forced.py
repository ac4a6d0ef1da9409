"""Forced response, excitation, resonance amplitudes and dampers of torsional systems."""

import numpy as np
import pytest

from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.torsion import TorsionalSystem, chain
from crankbench.predict.torsion import dampers
from crankbench.predict.torsion.elements import ShaftLine
from crankbench.predict.torsion.excitation import engine_excitation, tangential_torque
from crankbench.predict.torsion.forced import _superpose, cylinder_forcing, harmonic_solve
from crankbench.predict.torsion.resonance import resonance_amplitudes

FIRING_6 = [0, 480, 240, 600, 120, 360]


def six_cylinder_chain(damping=20.0):
    rng = np.random.default_rng(0)
    n = 10
    j = rng.uniform(1, 5, n)
    k = rng.uniform(1e6, 5e6, n - 1)
    return chain(j, k).replace(
        cylinder_nodes=list(range(1, 7)), firing_angles_deg=FIRING_6,
        edge_damping=np.full(n - 1, damping), node_damping=np.r_[np.full(n - 1, 2.0), 100.0],
        edge_loss_factor=np.full(n - 1, 0.01))


def dense_solve(system, speed, order, forcing):
    w = speed * order
    z = (system.stiffness_matrix(speed) + 1j * w * system.damping_matrix(w)
         - w * w * system.inertia_matrix())
    return np.linalg.solve(z, forcing)


def test_tree_elimination_matches_dense_solve():
    """Branched, geared, grounded, with every kind of damping and a pendulum spring."""
    s = TorsionalSystem(
        [2.0, 0.5, 3.0, 1.0, 4.0, 0.2], [(0, 1), (1, 2), (1, 3), (3, 4), (-1, 4), (2, 5), (1, 2)],
        [1e5, 2e6, 3e4, 5e5, 1e3, 0.0, 1e4], edge_damping=[1, 2, 3, 4, 5, 0.5, 0],
        edge_loss_factor=[0.01, 0, 0.05, 0, 0, 0, 0.1], node_damping=[0, 1, 0, 0, 10, 0],
        edge_stiffness_omega2=[0, 0, 0, 0, 0, 0.2 * 4, 0])
    speed = np.array([30.0, 90.0])
    orders = np.array([0.5, 3.0])
    rng = np.random.default_rng(1)
    f = rng.normal(size=(2, 2, 6)) + 1j * rng.normal(size=(2, 2, 6))
    x = harmonic_solve(s, speed, orders, f)
    for a in range(2):
        for b in range(2):
            ref = dense_solve(s, speed[a], orders[b], f[a, b])
            np.testing.assert_allclose(x[a, b], ref, rtol=1e-11, atol=1e-14 * abs(ref).max())


def test_loop_system_uses_dense_batch_and_matches():
    s = TorsionalSystem([1.0, 2.0, 3.0], [(0, 1), (1, 2), (2, 0)], [1e4, 2e4, 3e4],
                        edge_damping=[1.0, 1.0, 1.0])
    f = np.array([[[1.0, 0.0, -2.0j]]])
    x = harmonic_solve(s, np.array([50.0]), np.array([1.5]), f)
    np.testing.assert_allclose(x[0, 0], dense_solve(s, 50.0, 1.5, f[0, 0]), rtol=1e-12)


def test_superposition_peak_against_brute_force():
    rng = np.random.default_rng(5)
    orders = np.arange(0.5, 12.01, 0.5)
    v = rng.normal(size=(3, orders.size, 2)) + 1j * rng.normal(size=(3, orders.size, 2))
    v /= (orders ** 1.5)[None, :, None]
    peak, how = _superpose(v, orders, 4)
    theta = np.linspace(0, 4 * np.pi, 200001)
    wave = np.real(np.einsum("sox,ot->sxt", v, np.exp(1j * np.outer(orders, theta))))
    ref = np.abs(wave).max(axis=2)
    assert how.startswith("cycle synthesis")
    np.testing.assert_allclose(peak, ref, rtol=5e-3)
    upper, how2 = _superpose(v, orders + 0.1, 4)
    assert how2.startswith("sum of amplitudes") and np.all(upper >= ref)


def test_forced_response_two_mass_closed_form():
    """Free two-mass system, torque T at mass 1: θ2 = T k / (k J... ) closed form with c."""
    j1, j2, k, c, t = 1.0, 3.0, 1e4, 2.0, 100.0
    s = chain([j1, j2], [k]).replace(cylinder_nodes=[0], firing_angles_deg=[0.0],
                                     edge_damping=[c])
    rpm = 600.0
    w = rpm * np.pi / 30
    r = s.forced_response([rpm], torque=[t], orders=[1.0])
    kc = k + 1j * w * c
    det = (kc - j1 * w * w) * (kc - j2 * w * w) - kc * kc
    x1 = t * (kc - j2 * w * w) / det
    x2 = t * kc / det
    np.testing.assert_allclose(r.angle[0, 0], [x1, x2], rtol=1e-12)
    np.testing.assert_allclose(r.torque[0, 0, 0], kc * (x2 - x1), rtol=1e-12)


def test_energy_balance_within_few_percent_for_light_damping():
    s = six_cylinder_chain(damping=5.0)
    t = resonance_amplitudes(s, torque=lambda q, w: 1000.0, orders=np.arange(0.5, 12.1, 0.5),
                             speed_range_rpm=(100, 1500), min_vector_sum=0.5)
    assert len(t) > 10
    assert t.method_error.abs().median() < 0.005
    assert t.method_error.abs().max() < 0.05
    # the gap is reported and not identically zero (the methods differ)
    assert t.method_error.abs().max() > 0
    # dynamic magnifier = 1 / 2ζ ≥ 1
    assert (t.dynamic_magnifier > 1).all()


def test_tangential_torque_mean_equals_indicated_work():
    """T₀ = W_i / (4π) for a 4-stroke; the inertia torque has zero mean."""
    from crankbench.predict.pressure import synthetic_pressure

    e = Engine(crank_angles_deg=[0], crank_radius=0.06, rod_length=0.22,
               reciprocating_mass=1.5, bore=0.11, compression_ratio=16.0)
    tr = synthetic_pressure(e, imep=1.2e6)
    psi = np.arange(14400) * 4 * np.pi / 14400
    torque = tangential_torque(e, psi, omega=200.0, pressure=tr.at(psi),
                               crankcase_pressure=0.0)
    w_i = tr.work(e)
    assert torque.mean() == pytest.approx(w_i / (4 * np.pi), rel=2e-3)


def test_excitation_harmonics_and_misfire():
    e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.045, rod_length=0.15,
               reciprocating_mass=0.6, bore=0.085, compression_ratio=10.0,
               firing_order=[1, 3, 4, 2])
    x = engine_excitation(e, imep=1.0e6)
    assert x.error_estimate < 1e-6
    # the inertia torque of one cylinder: second order dominates, T₂ ≈ m r² ω² / 2
    i2 = abs(x.inertia[np.isclose(x.orders, 2.0)][0])
    assert i2 == pytest.approx(0.6 * 0.045 ** 2 / 2, rel=0.05)
    assert np.all(x.inertia[~np.isclose(x.orders, np.round(x.orders))] == 0)
    h = x.harmonics([100.0], [0.5, 2.0], misfire=3)
    np.testing.assert_allclose(h[0, :, 2], 100.0 ** 2 * x.inertia[[0, 3]])
    np.testing.assert_allclose(h[0, :, 0], x.gas[[0, 3]] + 1e4 * x.inertia[[0, 3]])
    with pytest.raises(ModelError, match="misfire=5 but the engine has 4 cylinders"):
        x.harmonics([100.0], [1.0], misfire=5)


def test_misfire_excites_minor_orders():
    """Even firing cancels order 0.5 on a rigid crankshaft; a misfire brings it back."""
    e = Engine(crank_angles_deg=[0, 240, 120, 120, 240, 0], crank_radius=0.06,
               rod_length=0.22, reciprocating_mass=1.5, bore=0.11, compression_ratio=16.0,
               firing_order=[1, 5, 3, 6, 2, 4])
    line = ShaftLine("rig", engine=e)
    for c in range(1, 7):
        line.add_mass(f"c{c}", 0.05, cylinder=c)
    line.add_mass("fly", 1.5)
    for c in range(1, 6):
        line.add_shaft(f"c{c}", f"c{c + 1}", stiffness=1e8)
    line.add_shaft("c6", "fly", stiffness=1e8)
    line.add_mass("load", 2.0, damping=5.0)
    line.add_coupling("fly", "load", stiffness=2e4, loss_factor=0.1)
    s = line.build()
    x = engine_excitation(e, imep=1.5e6)
    ok = s.forced_response([1500.0], torque=x, orders=[0.5, 3.0])
    bad = s.forced_response([1500.0], torque=x, orders=[0.5, 3.0], misfire=2)
    t_ok, t_bad = np.abs(ok.torque[0, :, -1]), np.abs(bad.torque[0, :, -1])
    assert t_ok[0] < 1e-3 * t_ok[1]
    assert t_bad[0] > 50 * t_ok[0]


def test_pendulum_absorber_stops_its_order():
    """An undamped pendulum tuned to order n = √(R/r) holds its hub still at order n."""
    line = ShaftLine("pendulum")
    line.add_mass("hub", 1.0)
    line.add_mass("load", 4.0)
    line.add_shaft("hub", "load", stiffness=5e4)
    name = dampers.add_pendulum_absorber(line, "hub", mass=0.8, pivot_radius=0.09,
                                         length=0.01)
    s = line.build().replace(cylinder_nodes=[0], firing_angles_deg=[0.0])
    assert s.mode_shapes().shapes[s.node_names.index(name)].max() == 0  # not in eigen
    r = s.forced_response([800.0, 900.0], torque=[10.0, 10.0], orders=[3.0, 2.0])
    assert np.all(np.abs(r.angle[:, 0, 0]) < 1e-12)  # order 3 = √(0.09/0.01)
    assert np.all(np.abs(r.angle[:, 1, 0]) > 1e-6)


def two_dof(main_j, main_k, ring_j, ring_k, ring_c, omegas):
    """|θ_main| / (T/k) of a grounded main inertia with a damper ring (closed form)."""
    w = omegas
    z_r = ring_k + 1j * w * ring_c
    z11 = main_k + z_r - main_j * w * w
    z22 = z_r - ring_j * w * w
    return np.abs(z22 / (z11 * z22 - z_r * z_r)) * main_k


def test_den_hartog_optimum_gives_equal_peaks():
    """With f = 1/(1+μ), ζ² = 3μ/8(1+μ)³ the peak magnification is ≈ √(1 + 2/μ)."""
    mu, jm, km = 0.1, 2.0, 8e4
    line = ShaftLine("dh")
    line.add_mass("main", jm)
    line.add_ground("main", stiffness=km)
    tune = dampers.optimum_tuned_damper(line.build(), "main", ring_inertia=mu * jm)
    w = np.linspace(0.5, 1.5, 200001) * np.sqrt(km / jm)
    mag = two_dof(jm, km, mu * jm, tune.stiffness, tune.damping, w)
    assert tune.mass_ratio == pytest.approx(mu)
    assert mag.max() == pytest.approx(np.sqrt(1 + 2 / mu), rel=0.02)


def test_lanchester_optimum_minimises_the_peak():
    mu, jm, km = 0.25, 1.0, 1e4
    line = ShaftLine("l")
    line.add_mass("main", jm)
    line.add_ground("main", stiffness=km)
    tune = dampers.optimum_viscous_damper(line.build(), "main", ring_inertia=mu * jm)
    w = np.linspace(0.3, 1.7, 40001) * np.sqrt(km / jm)
    peaks = {c: two_dof(jm, km, mu * jm, 0.0, c, w).max()
             for c in tune.damping * np.array([0.7, 1.0, 1.4])}
    best = peaks[tune.damping]
    assert best < min(v for c, v in peaks.items() if c != tune.damping)
    assert best == pytest.approx(1 + 2 / mu, rel=0.02)


def test_viscous_damper_lowers_resonance():
    line = ShaftLine("d")
    line.add_mass("hub", 1.0)
    line.add_mass("fly", 10.0)
    line.add_shaft("hub", "fly", stiffness=1e5, loss_factor=0.002)
    plain = line.build().replace(cylinder_nodes=[0], firing_angles_deg=[0.0])
    c = dampers.optimum_viscous_damper(plain, "hub", ring_inertia=0.5).damping
    dampers.add_viscous_damper(line, "hub", ring_inertia=0.5, damping=c)
    damped = line.build().replace(cylinder_nodes=[0], firing_angles_deg=[0.0])
    rpm = np.linspace(300, 4500, 4000)
    a = plain.forced_response(rpm, torque=[10.0], orders=[1.0]).torque_total[:, 0].max()
    b = damped.forced_response(rpm, torque=[10.0], orders=[1.0]).torque_total[:, 0].max()
    assert b < a / 10


def test_forced_response_validation():
    s = six_cylinder_chain()
    with pytest.raises(ModelError, match="speed_rpm must be > 0 everywhere"):
        s.forced_response([0.0, 100.0], torque=[1.0], orders=[1.0])
    with pytest.raises(ModelError, match=r"cylinder torque harmonics have shape \(3,\), "
                                         r"expected \(2,\), \(1, 2\) or \(1, 2, 6\)"):
        s.forced_response([100.0], torque=[1.0, 2.0, 3.0], orders=[1.0, 2.0])
    with pytest.raises(ModelError, match="misfire needs an Excitation"):
        s.forced_response([100.0], torque=[1.0], orders=[1.0], misfire=1)
    with pytest.raises(ModelError, match="the torsional system has no engine attached"):
        s.forced_response([100.0], orders=[1.0])
    bare = chain([1.0, 1.0], [1.0])
    with pytest.raises(ModelError, match="the system has no cylinder_nodes"):
        cylinder_forcing(bare, [1.0], np.array([1.0]), 1)


def test_response_outputs(tmp_path):
    s = six_cylinder_chain().replace(edge_outer_diameter=np.full(9, 0.1),
                                     edge_inner_diameter=np.zeros(9))
    r = s.forced_response(np.linspace(200, 1200, 50), torque=np.ones(24) * 500.0)
    ds = r.to_dataset()
    assert ds.stress.attrs["units"] == "Pa" and ds.sizes["order"] == 24
    # τ = 16 T / (π D³) for a solid shaft
    np.testing.assert_allclose(r.stress, np.abs(r.torque) * 16 / (np.pi * 0.1 ** 3))
    frame = r.to_frame()
    assert list(frame.columns) == ["speed_rpm", "max_angle_deg", "node", "max_stress_mpa",
                                   "section"]
    fig = r.plot(section=3)
    fig.savefig(tmp_path / "r.png")


def test_excitation_from_coefficient_table_round_trip():
    """A coefficient table made from the synthetic model reproduces its |G_q| at a table IMEP
    and interpolates linearly between rows."""
    from crankbench.predict.torsion.excitation import (excitation_from_coefficients,
                                            harmonic_coefficient_table)

    e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.045, rod_length=0.15,
               reciprocating_mass=0.6, bore=0.085, compression_ratio=10.0,
               firing_order=[1, 3, 4, 2])
    orders = np.arange(0.5, 6.01, 0.5)
    table = harmonic_coefficient_table(e, [0.6e6, 1.2e6], orders=orders)
    direct = engine_excitation(e, imep=1.2e6, orders=orders)
    x = excitation_from_coefficients(e, orders=orders, imep_values=table.index.to_numpy(),
                                     coefficients=table.to_numpy(), imep=1.2e6,
                                     phases_deg=np.rad2deg(np.angle(direct.gas)))
    np.testing.assert_allclose(x.gas, direct.gas, rtol=1e-12)
    np.testing.assert_allclose(x.inertia, direct.inertia, rtol=1e-9, atol=1e-12)
    mid = excitation_from_coefficients(e, orders=orders, imep_values=table.index.to_numpy(),
                                       coefficients=table.to_numpy(), imep=0.9e6)
    np.testing.assert_allclose(np.abs(mid.gas), 0.5 * (np.abs(direct.gas) + np.abs(
        engine_excitation(e, imep=0.6e6, orders=orders).gas)), rtol=1e-12)
    assert "phases assumed 0" in mid.source
