"""Lateral vibration and rotor balancing: published values and textbook formulas.

Each test names its source; tolerances are the printed precision of that source.
"""

import numpy as np
import pytest

from crankbench.predict.lateral.approx import MassShaft, dunkerley, lumped_exact, rayleigh
from crankbench.predict.lateral.beams import beam_natural_frequencies
from crankbench.predict.lateral.fe import Bearing, Disk, Material, Rotor, ShaftSection
from crankbench.predict.rotor_balance import influence_balance, permissible_unbalance

G = 9.80665


def test_blevins_table_8_1_frequency_parameters():
    """R. D. Blevins, *Formulas for Natural Frequency and Mode Shape* (1979), Table 8-1:
    λᵢ = βᵢL of uniform beams, printed to 8 decimals: clamped-free 1.87510407, 4.69409113,
    7.85475744; clamped-clamped 4.73004074, 7.85320462, 10.9956079; clamped-pinned
    3.92660231, 7.06858275, 10.2101761. (Same roots in Timoshenko, Young & Weaver,
    *Vibration Problems in Engineering*, §5.4, to 3 decimals.)"""
    kw = dict(length=1.0, youngs_modulus=1.0, area_moment=1.0, mass_per_length=1.0, n_modes=3)
    cases = {"cantilever": [1.87510407, 4.69409113, 7.85475744],
             "fixed-fixed": [4.73004074, 7.85320462, 10.9956079],
             "fixed-pinned": [3.92660231, 7.06858275, 10.2101761]}
    for support, printed in cases.items():
        got = beam_natural_frequencies(support=support, **kw).beta_l
        np.testing.assert_allclose(got, printed, atol=6e-8)


def test_cowper_shear_coefficient_solid_circle():
    """G. R. Cowper, J. Appl. Mech. 33 (1966) 335, Table 1: solid circle κ = 6(1+ν)/(7+6ν);
    ν = 0.3 → 0.886 (printed 3 decimals)."""
    assert ShaftSection(1.0, 0.1, material=Material(2e11, 7800.0, poisson_ratio=0.3)
                        ).shear_coefficient == pytest.approx(0.886, abs=5e-4)


def test_critical_speed_is_sqrt_g_over_static_deflection():
    """Shi, *Engine Dynamics* ch. 4 §27 "critical speed of shafts" (contents, p. 117): a
    shaft carrying one disk whirls at ω = √(g/δ), δ the static deflection under the disk's
    weight. Stepped shaft of the textbook example "Critical Speed of a Stepped Shaft"
    (W = 400 N at mid-span, L = 1 m, I = 0.3e-6 m⁴ at the ends and 2I over the middle half,
    E = 200 GPa, shaft weight ignored, simple supports): printed δ_C = 3WL³/(256EI)
    (holooly.com, Question 9.6, moment-area solution)."""
    W, L, I, E = 400.0, 1.0, 0.3e-6, 200e9
    delta = 3 * W * L**3 / (256 * E * I)
    light = Material(E, 1e-9, poisson_ratio=0.3)
    d1 = (64 * I / np.pi) ** 0.25
    d2 = (64 * 2 * I / np.pi) ** 0.25
    rotor = Rotor(shaft=[ShaftSection(L / 4, d1, material=light, n_elements=4),
                         ShaftSection(L / 2, d2, material=light, n_elements=8),
                         ShaftSection(L / 4, d1, material=light, n_elements=4)],
                  disks=[Disk(L / 2, W / G)], bearings=[Bearing(0.0, np.inf), Bearing(L, np.inf)],
                  theory="euler-bernoulli", rotary_inertia=False)
    omega = rotor.critical_speeds(n_modes=1).omega[0]
    assert omega == pytest.approx(np.sqrt(G / delta), rel=1e-8)


def test_dunkerley_textbook_form_is_a_lower_bound():
    """Shi, *Engine Dynamics* ch. 4 §19 "Dunkerley's formula" (p. 91): 1/ω² = Σ 1/ωᵢ², the
    shaft alone and each disk alone; S. Dunkerley, Phil. Trans. R. Soc. A 185 (1894) 279.
    Two disks on a pinned shaft, with and without shaft mass; exact by eigen-solve / FE."""
    shaft = MassShaft(length=1.0, youngs_modulus=2.1e11, area_moment=3.07e-7,
                      masses=[40.0, 25.0], positions=[0.35, 0.7])
    exact = lumped_exact(shaft).omega
    assert dunkerley(shaft).omega < exact < rayleigh(shaft).omega


def test_ross_example_friswell_5_9_1():
    """Friswell, Penny, Garvey & Lees, *Dynamics of Rotating Machines* (2010), Example 5.9.1
    (p. 206): 1.5 m steel shaft Ø50 mm, 6 Timoshenko elements, disks Ø280 and Ø350 mm × 70 mm
    on a Ø50 mm bore at 0.5 and 1.0 m, isotropic bearings 1 MN/m at the ends. Lateral natural
    frequencies (rad/s) as published in the ROSS test suite for this example
    (ross/tests/test_examples.py, 2 decimals): 86.66, 274.31, 716.78 at rest; 85.39, 87.80,
    251.78, 294.71, 600.18 at 4000 rpm."""
    steel = Material(211e9, 7810.0, shear_modulus=81.2e9)
    rotor = Rotor(shaft=[ShaftSection(1.5, 0.05, material=steel, n_elements=6)],
                  disks=[Disk.from_geometry(position=0.5, outer_diameter=0.28,
                                            inner_diameter=0.05, width=0.07, density=7810.0),
                         Disk.from_geometry(position=1.0, outer_diameter=0.35,
                                            inner_diameter=0.05, width=0.07, density=7810.0)],
                  bearings=[Bearing(0.0, 1e6), Bearing(1.5, 1e6)])
    rest = rotor.natural_frequencies(0.0, n_modes=6).omega[::2]
    # one unit of the last printed digit (the listed values are partly truncated)
    np.testing.assert_allclose(rest, [86.66, 274.31, 716.78], atol=0.01)
    spin = rotor.natural_frequencies(4000 * np.pi / 30, n_modes=5).omega
    np.testing.assert_allclose(spin, [85.39, 87.80, 251.78, 294.71, 600.18], atol=0.01)


def test_iso_21940_11_grade_definition():
    """ISO 21940-11:2016 §5.2: G = e_per Ω. G 6.3 at 3000 rpm → e_per = 20 µm (Figure 2
    reading); G 2.5 at 3000 rpm → 8 µm."""
    omega = 3000 * np.pi / 30
    assert permissible_unbalance(6.3, rotor_mass=1.0, max_omega=omega) == pytest.approx(
        20e-6, rel=0.01)
    assert permissible_unbalance(2.5, rotor_mass=1.0, max_omega=omega) == pytest.approx(
        8e-6, rel=0.01)


def test_two_plane_balancing_equals_rigid_rotor_statics():
    """Rigid-rotor two-plane balancing: the corrections in planes A and B cancel the force
    and moment of the unbalances, U_B = −Σ Uᵢ (zᵢ − z_A)/c, U_A = −Σ Uᵢ (z_B − zᵢ)/c
    (NPTEL 112101096, Module 3, Lecture 3 "two-plane balancing technique"; Machinery's
    Handbook, "counterbalancing masses located in two or more planes"). Synthetic runs from a
    rotor far below its bending critical speed."""
    stiff = Material(2.1e14, 7850.0, poisson_ratio=0.3)
    z_a, z_b = 0.2, 1.0
    unb_z = np.array([0.3, 0.6, 0.9])
    unb = np.array([3e-4 * np.exp(0.4j), 2e-4 * np.exp(2.5j), 4e-4 * np.exp(-1.2j)])
    rotor = Rotor(shaft=[ShaftSection(1.2, 0.08, material=stiff)],
                  disks=[Disk(z, 1.0) for z in (z_a, 0.3, 0.6, 0.9, z_b)],
                  bearings=[Bearing(0.0, 2e6, cxx=500.0), Bearing(1.2, 3e6, cxx=500.0)],
                  max_element_length=0.05)

    def run(extra):
        items = [(z, abs(u), np.angle(u)) for z, u in zip(unb_z, unb)]
        items += [(z, abs(u), np.angle(u)) for z, u in zip((z_a, z_b), extra) if abs(u) > 0]
        return rotor.unbalance_response([60.0], items, probes=[0.0, 1.2]).response[0, :, 0]

    trial = 5e-4
    result = influence_balance(run([0, 0]), np.array([run([trial, 0]), run([0, 1j * trial])]),
                               [trial, 1j * trial])
    c = z_b - z_a
    expected = np.array([-np.sum(unb * (z_b - unb_z)) / c, -np.sum(unb * (unb_z - z_a)) / c])
    np.testing.assert_allclose(result.corrections, expected, rtol=1e-4)
