"""Crankshaft bearing loads and moments, finite life and combined-stress fatigue.

Sources:
* [Roark] Young & Budynas, *Roark's Formulas for Stress and Strain*, 7th ed., Table 8.1 /
  §8.6: continuous beam of two equal spans, point load P at mid-span of one: reactions
  13P/32, 11P/16, −3P/32.
* [Shigley] Budynas & Nisbett, *Shigley's Mechanical Engineering Design*, 9th ed.:
  Example 6-2 (S_u = 90 kpsi, S_e = 45 kpsi, f = 0.86: a = 133.1 kpsi, b = −0.0785,
  S_f(10⁴) = 64.6 kpsi, N(55 kpsi) ≈ 77 500 cycles); Tables 6-6, 6-7, 6-8 (intersections of
  the Goodman, Gerber and ASME-elliptic lines with the Langer yield line); §6-15 Miner.
* [GP] Gough & Pollard, Proc. IMechE 131 (1935): ellipse quadrant for combined stresses.
"""

import numpy as np
import pytest

from crankbench.predict.crankshaft import bearing_loads, continuous_beam_reactions
from crankbench.predict.engine import Engine
from crankbench.predict.fatigue import EnduranceDiagram, rainflow
from crankbench.predict.fatigue_life import (SNCurve, combined_safety_factor, fillet_stresses,
                                             miner_damage)
from crankbench.predict.pressure import synthetic_pressure

KSI = 6.894757e6


def test_roark_two_span_continuous_beam():
    r = continuous_beam_reactions([0.5, 1.5], [0.0, 1.0, 2.0], 7.0)
    np.testing.assert_allclose(-r[:, 0], [13 / 32, 11 / 16, -3 / 32], rtol=1e-12)
    np.testing.assert_allclose(-r[:, 1], [-3 / 32, 11 / 16, 13 / 32], rtol=1e-12)


@pytest.fixture(scope="module")
def i4():
    e = Engine.from_toml("sample_data/engines/i4.toml")
    zb = np.concatenate([[-0.0455], 0.5 * (e.cylinder_positions[1:] + e.cylinder_positions[:-1]),
                         [e.cylinder_positions[-1] + 0.0455]])
    return e, zb


@pytest.mark.parametrize("model", ["determinate", "continuous"])
def test_bearing_loads_balance_the_pin_forces(i4, model):
    """Statics: at every angle the bearing loads add up to the pin forces and their moments
    about the first bearing match."""
    e, zb = i4
    r = bearing_loads(e, omega=500.0, bearing_positions=zb, model=model, points=96,
                      pressure=synthetic_pressure(e))
    np.testing.assert_allclose(r.loads.sum(axis=1), r.pin_forces.sum(axis=1), rtol=1e-10,
                               atol=1e-6)
    np.testing.assert_allclose(r.loads @ (zb - zb[0]),
                               r.pin_forces @ (e.cylinder_positions - zb[0]), rtol=1e-10,
                               atol=1e-6)


def test_determinate_split_by_the_lever_rule_and_models_agree_for_one_throw():
    e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2, reciprocating_mass=2.0,
               rotating_mass=1.0, cylinder_positions=[0.03], bore=0.09,
               compression_ratio=10.0)
    kw = dict(omega=300.0, bearing_positions=[0.0, 0.1], points=48,
              pressure=synthetic_pressure(e, imep=1e6))
    d = bearing_loads(e, model="determinate", **kw)
    c = bearing_loads(e, model="continuous", **kw)
    np.testing.assert_allclose(d.loads[:, 0], 0.7 * d.pin_forces[:, 0], rtol=1e-12)
    np.testing.assert_allclose(d.loads, c.loads, rtol=1e-10, atol=1e-8)
    # bending moment at the pin = left bearing reaction × 0.03 m
    np.testing.assert_allclose(d.pin_moments[:, 0], -d.loads[:, 0] * 0.03, rtol=1e-12)


def test_shigley_example_6_2_sn_line():
    sn = SNCurve.from_ultimate(ultimate=90 * KSI, endurance=45 * KSI, fraction=0.86)
    a, b = sn.basquin
    assert a / KSI == pytest.approx(133.1, abs=0.05)
    assert b == pytest.approx(-0.0785, abs=5e-5)
    assert sn.strength(1e4) / KSI == pytest.approx(64.6, abs=0.05)
    assert sn.cycles(55 * KSI) == pytest.approx(77_500, rel=0.005)
    assert sn.cycles(40 * KSI) == np.inf


def test_miner_block_loading_and_rainflow_history():
    sn = SNCurve(endurance=200e6, knee_cycles=2e6, slope=6.0)
    blocks = [(300e6, 1000), (250e6, 5000), (150e6, 1e6)]
    expected = sum(n / (2e6 * (200e6 / s) ** 6) for s, n in blocks if s >= 200e6)
    history = np.concatenate([np.tile([s, -s], int(n)) for s, n in blocks[:2]])
    r = miner_damage(history, sn, mean_correction="none")
    assert r.damage == pytest.approx(expected, rel=2e-3)     # the end half-cycles
    # mean stress (Goodman): a cycle 0..2S has amplitude S and mean S
    su = 800e6
    r2 = miner_damage(rainflow([0, 500e6, 0, 500e6, 0]), sn, ultimate=su)
    eq = 250e6 / (1 - 250e6 / su)
    assert r2.cycles["equivalent"].max() == pytest.approx(eq, rel=1e-12)
    assert r2.damage == pytest.approx(2 / (2e6 * (200e6 / eq) ** 6), rel=1e-12)


@pytest.mark.parametrize("criterion", ["goodman", "gerber", "asme-elliptic"])
def test_langer_crossover_lies_on_both_lines(criterion):
    su, se, sy = 600e6, 250e6, 450e6
    d = EnduranceDiagram(ultimate=su, endurance=se, yield_strength=sy, criterion=criterion)
    p = d.crossover()
    assert p.alternating + p.mean == pytest.approx(sy, rel=1e-12)
    fatigue = {"goodman": se * (1 - p.mean / su), "gerber": se * (1 - (p.mean / su) ** 2),
               "asme-elliptic": se * np.sqrt(1 - (p.mean / sy) ** 2)}[criterion]
    assert p.alternating == pytest.approx(fatigue, rel=1e-12)
    # Shigley Table 6-7 (Gerber-Langer) and 6-8 (ASME-elliptic-Langer) printed forms
    if criterion == "gerber":
        sm = su ** 2 / (2 * se) * (1 - np.sqrt(1 + (2 * se / su) ** 2 * (1 - sy / se)))
        assert p.mean == pytest.approx(sm, rel=1e-12)
    if criterion == "asme-elliptic":
        assert p.alternating == pytest.approx(2 * se ** 2 * sy / (se ** 2 + sy ** 2), rel=1e-12)


def test_combined_criteria_limits_and_gough_pollard_ellipse():
    se, su = 300e6, 900e6
    kw = dict(bending_endurance=se, ultimate=su)
    for crit in ("von-mises", "gough-pollard"):
        assert combined_safety_factor(bending_alternating=100e6, torsion_alternating=0.0,
                                      criterion=crit, **kw) == pytest.approx(3.0)
        # with τ_e = σ_e/√3 (default) both criteria agree in pure torsion
        assert combined_safety_factor(bending_alternating=0.0, torsion_alternating=50e6,
                                      criterion=crit, **kw) == pytest.approx(
            se / np.sqrt(3) / 50e6)
    # points on the Gough-Pollard ellipse (σ/σ_e)² + (τ/τ_e)² = 1 have n = 1
    te = 200e6
    for phi in np.linspace(0.1, 1.4, 5):
        n = combined_safety_factor(bending_alternating=se * np.cos(phi),
                                   torsion_alternating=te * np.sin(phi), torsion_endurance=te,
                                   **kw)
        assert n == pytest.approx(1.0, rel=1e-12)
    # a mean stress reduces both endurance limits (Goodman on the von Mises mean)
    n = combined_safety_factor(bending_alternating=100e6, torsion_alternating=0.0,
                               bending_mean=300e6, **kw)
    assert n == pytest.approx(3.0 * (1 - 300 / 900), rel=1e-12)


def test_fillet_stresses_are_nominal_times_scf():
    r = fillet_stresses(bending_moment=[-500.0, 1500.0], torque=[200.0, 1000.0], diameter=0.08,
                        bore=0.02, bending_scf=2.5, torsion_scf=1.8)
    z = np.pi * (0.08 ** 4 - 0.02 ** 4) / (32 * 0.08)
    assert r["bending_alternating"] == pytest.approx(2.5 * 1000.0 / z, rel=1e-12)
    assert r["torsion_mean"] == pytest.approx(1.8 * 600.0 / (2 * z), rel=1e-12)


def test_web_stresses_rectangular_section():
    from crankbench.predict.crankshaft import web_stresses

    r = web_stresses(bending_moment=[-200.0, 900.0], radial_force=[-5e3, 2e4], web_width=0.15,
                     web_thickness=0.035, bending_scf=2.4)
    z = 0.15 * 0.035 ** 2 / 6
    a = 0.15 * 0.035
    hi, lo = 2.4 * 900 / z + 2e4 / a, 2.4 * -200 / z - 5e3 / a
    assert r["fillet_alternating"] == pytest.approx((hi - lo) / 2, rel=1e-12)
    assert r["fillet_mean"] == pytest.approx((hi + lo) / 2, rel=1e-12)


def test_crankshaft_table_in_the_engine_file():
    from crankbench.predict.crankshaft import bearing_loads_from_toml

    r = bearing_loads_from_toml("sample_data/engines/i6.toml", omega=200.0, points=72)
    e = Engine.from_toml("sample_data/engines/i6.toml")
    ref = bearing_loads(e, omega=200.0, pressure=synthetic_pressure(e), points=72,
                        bearing_positions=[-0.076, 0.076, 0.228, 0.38, 0.532, 0.684, 0.836])
    np.testing.assert_allclose(r.loads, ref.loads, rtol=1e-12)
    # mirror-symmetric I6: end bearings carry the same largest load
    mx = np.abs(r.loads).max(axis=0)
    assert mx[0] == pytest.approx(mx[-1], rel=1e-9)
