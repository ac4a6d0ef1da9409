"""Loads on the engine block per order and the receptance of the mounted block, each against a
second method.

* :func:`predict.mounts.block_excitation` — the phasors of every order against the Fourier
  coefficients of the exact time-domain sums of :func:`predict.balance.shaking_forces`
  (forces, pitch and yaw couples, counterweights included) and of
  :func:`predict.forces.engine_torque` (the torque reaction), for several layouts;
* :meth:`MountedEngine.receptance` against :meth:`MountedEngine.response` (the 6×6 solve with
  the loads applied one at a time) and the static limit ``1 / Σ k_z``;
* :mod:`predict.balance_tolerance` — the worst-case bound is never exceeded by random parts
  inside their tolerances and is reached by the worst combination.
"""

from pathlib import Path

import numpy as np
import pytest

from crankbench.predict.balance import Counterweight, shaking_forces
from crankbench.predict.balance_tolerance import BalanceSpec, allowed_residuals
from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.forces import engine_torque
from crankbench.predict.mounts import (Mount, MountedEngine, block_excitation,
                                       direction_vector)
from crankbench.predict.torsion.excitation import engine_excitation

ROOT = Path(__file__).resolve().parents[2]
ENGINES = ROOT / "sample_data" / "engines"


def _fourier(values, theta, n):
    """Complex coefficient A of Re(A e^{i n theta}) from samples over one revolution."""
    return 2.0 * np.mean(values * np.exp(-1j * n * theta))


@pytest.mark.parametrize("name", ["i4", "v6_90", "boxer4", "single", "v8_crossplane",
                                  "radial5"])
def test_inertia_loads_equal_the_exact_time_domain_sums(name):
    """Every integer order's force (y horizontal, z vertical) and couple (M_y = -pitch,
    M_z = yaw) phasor, referred to cylinder 1's firing TDC, equals the Fourier coefficient of
    the exact per-cylinder sums over one revolution (1024 points: exact to round-off for
    orders up to 8), with a counterweight added."""
    engine = Engine.from_toml(ENGINES / f"{name}.toml")
    cw = (Counterweight(mass_radius=0.003, angle_deg=130.0,
                        position=float(engine.cylinder_positions[-1])),)
    orders = [1.0, 2.0, 3.0, 4.0, 6.0, 8.0]
    omega = 200.0
    loads = block_excitation(engine, orders, counterweights=cw).at(omega)[0]   # (n_o, 6)
    psi = 2 * np.pi * np.arange(1024) / 1024
    ds = shaking_forces(engine, psi + engine.firing_tdc_shaft_angle, omega=omega,
                        counterweights=cw)
    scale = np.abs(ds["force_vertical"].values).max() + np.abs(ds["force_horizontal"]).max()
    span = max(float(np.ptp(engine.cylinder_positions)), 0.1)
    for k, n in enumerate(orders):
        ref = {1: _fourier(ds["force_horizontal"].values, psi, n),
               2: _fourier(ds["force_vertical"].values, psi, n),
               4: -_fourier(ds["moment_pitch"].values, psi, n),
               5: _fourier(ds["moment_yaw"].values, psi, n)}
        for j, value in ref.items():
            tol = 1e-9 * scale * (span if j >= 4 else 1.0)
            assert abs(loads[k, j] - value) <= tol, (name, n, j, loads[k, j], value)
        assert loads[k, 0] == 0.0          # no axial force from a crank train


def test_torque_reaction_equals_the_engine_torque():
    """The roll load M_x (about +x, the crank turning about -x) is the crankshaft's turning
    moment: gas and inertia harmonics of the I4 at 3000 rpm against the Fourier coefficients
    of predict.forces.engine_torque over the 4-stroke cycle, within 0.1 % of the largest
    (the excitation's 1440-point harmonic analysis)."""
    from crankbench.predict.pressure import synthetic_pressure

    engine = Engine.from_toml(ENGINES / "i4.toml")
    orders = np.arange(0.5, 8.01, 0.5)
    exc = engine_excitation(engine, imep=1.0e6, orders=orders)
    omega = 3000 * np.pi / 30
    loads = block_excitation(engine, orders, excitation=exc).at(omega)[0]
    psi = 4 * np.pi * np.arange(2880) / 2880
    torque = engine_torque(engine, psi, omega=omega,
                           pressure=synthetic_pressure(engine, imep=1.0e6))
    ref = np.array([2.0 * np.mean(torque * np.exp(-1j * q * psi)) for q in orders])
    assert np.abs(loads[:, 3] - ref).max() < 1e-3 * np.abs(ref).max()
    # the in-line four's turning moment has orders 2, 4, 6, ... only
    assert np.abs(loads[~np.isclose(orders % 2, 0), 3]).max() < 1e-9 * np.abs(ref).max()


def _mounted():
    mounts = [Mount(position=[x, y, -0.3], stiffness=[2e6, 3e6, 4e6], damping=[200, 300, 400],
                    loss_factor=0.1) for x in (0.0, 1.0) for y in (-0.4, 0.4)]
    return MountedEngine(mass=800.0, inertia=[[40.0, 2.0, 0.0], [2.0, 90.0, 1.0],
                                              [0.0, 1.0, 90.0]], cg=[0.5, 0.05, 0.1],
                         mounts=mounts)


def test_receptance_equals_the_response_to_each_load():
    """Each column of the receptance is the response (:meth:`response`) to that unit force or
    moment at the point, projected on the sensor directions, at frequencies across the mount
    modes."""
    eng = _mounted()
    pts = np.array([[0.1, 0.3, 0.4], [0.9, -0.2, 0.0], [0.5, 0.0, -0.3]])
    dirs = np.array([direction_vector("z"), direction_vector([1.0, 1.0, 0.0]),
                     direction_vector("-y")])
    f = np.array([0.0, 3.0, 11.0, 40.0])
    point = [0.3, 0.0, 0.0]
    g = eng.receptance(f, at=pts, directions=dirs, point=point)
    for k in range(6):
        unit = np.zeros(6)
        unit[k] = 1.0
        r = eng.response(unit[:3], unit[3:], f, point=point, at=pts)
        ref = np.einsum("fpa,pa->fp", r.displacement, dirs)
        np.testing.assert_allclose(g[:, :, k], ref, rtol=1e-10, atol=1e-18)


def test_direction_words_and_errors():
    assert direction_vector("Vertical").tolist() == [0.0, 0.0, 1.0]
    assert direction_vector("-axial").tolist() == [-1.0, 0.0, 0.0]
    with pytest.raises(ModelError, match=r"direction='up' is not one of x, y, z"):
        direction_vector("up")
    with pytest.raises(ModelError, match="must not be the zero vector"):
        direction_vector([0, 0, 0])


def test_tolerance_bound_holds_and_is_reached():
    """Random pistons and big ends inside ±5 g and a crankshaft residual of 1e-5 kg·m per end
    plane (200 draws, any angle): no order's forward or backward force or moment component
    exceeds the bound; the worst case (every deviation at its limit, phased to add up) reaches
    it within 1e-9."""
    engine = Engine.from_toml(ENGINES / "i4.toml")
    spec = BalanceSpec(reciprocating_mass_tolerance=0.005, rotating_mass_tolerance=0.005,
                       crankshaft_unbalance=1e-5, relative_tolerance=0.0)
    omega = 500.0
    orders = [1, 2, 4]
    out = allowed_residuals(engine, spec, omega=omega, orders=orders)
    tol, nominal = out["tolerance"], out["nominal"]
    rng = np.random.default_rng(3)
    base = dict(crank_angles_deg=engine.crank_angles_deg, crank_radius=engine.crank_radius,
                rod_length=engine.rod_length, cylinder_positions=engine.cylinder_positions)
    planes = [engine.cylinder_positions.min(), engine.cylinder_positions.max()]
    from crankbench.predict.balance import unbalance

    worst = {k: np.zeros(len(orders)) for k in tol}
    for _ in range(200):
        e = Engine(reciprocating_mass=engine.reciprocating_mass
                   + rng.uniform(-0.005, 0.005, 4),
                   rotating_mass=engine.rotating_mass + rng.uniform(-0.005, 0.005, 4), **base)
        cws = [Counterweight(mass_radius=1e-5 * rng.uniform(), angle_deg=rng.uniform(0, 360),
                             position=p) for p in planes]
        ds = unbalance(e, omega=omega, orders=orders, counterweights=cws)
        for key in tol:
            dev = np.abs(ds[f"{key}_phasor"].values - nominal[f"{key}_phasor"].values)
            worst[key] = np.maximum(worst[key], dev)
            assert np.all(dev <= tol[key] * (1 + 1e-9)), (key, dev, tol[key])
    # the order-1 forward force bound: rotating masses all at +5 g, in phase with their throws
    # cannot add (I4 throws oppose): the bound is the sum of magnitudes, reached by choosing
    # each deviation's sign to align - here with the crankshaft planes at angle 0
    signs = np.sign(np.cos(np.deg2rad(engine.crank_angles_deg)))
    e = Engine(reciprocating_mass=engine.reciprocating_mass + 0.005 * signs,
               rotating_mass=engine.rotating_mass + 0.005 * signs, **base)
    cws = [Counterweight(mass_radius=1e-5, angle_deg=0.0, position=p) for p in planes]
    ds = unbalance(e, omega=omega, orders=[1], counterweights=cws)
    reached = abs(ds["force_forward_phasor"].values[0] - nominal["force_forward_phasor"].values[0])
    assert reached == pytest.approx(tol["force_forward"][0], rel=1e-9)


def test_balance_table_errors(tmp_path):
    p = tmp_path / "e.toml"
    p.write_text("[balance]\nreciprocating_mass_tolerence = 0.01\n")
    with pytest.raises(ModelError, match=r"balance.reciprocating_mass_tolerence is not a "
                                         r"known key \(did you mean "
                                         r"'reciprocating_mass_tolerance'\?\)"):
        BalanceSpec.from_toml(p)
    p.write_text("[balance]\ncrankshaft_unbalance = -1e-5\n")
    with pytest.raises(ModelError, match=r"balance.crankshaft_unbalance = -1e-05 must be >= 0"):
        BalanceSpec.from_toml(p)
    p.write_text("[[balance.mass]]\nmass = 0.01\nradius = 0.05\n")
    with pytest.raises(ModelError, match=r"balance.mass\[0\].angle_deg is missing"):
        BalanceSpec.from_toml(p)
    assert not BalanceSpec.from_toml(ENGINES / "i4.toml").stated


def test_without_combustion_data_the_inertia_torque_reaction_remains():
    """An engine model without cylinder-pressure data: the torque reaction's inertia part
    (from predict.forces.engine_torque) equals the excitation's inertia harmonics."""
    engine = Engine.from_toml(ENGINES / "i4.toml")
    orders = np.arange(0.5, 8.01, 0.5)
    full = block_excitation(engine, orders,
                            excitation=engine_excitation(engine, imep=1e6, orders=orders))
    bare = block_excitation(engine, orders)
    assert np.abs(bare.gas).max() == 0.0
    np.testing.assert_allclose(bare.inertia[:, 3], full.inertia[:, 3],
                               atol=1e-6 * np.abs(full.inertia[:, 3]).max())
    none = block_excitation(engine, orders, torque_reaction=False)
    assert np.abs(none.inertia[:, 3]).max() == 0.0
