"""Rayleigh ≥ exact ≥ Dunkerley, Stodola's bracket, against exact references."""

import numpy as np
import pytest

from crankbench.predict.errors import AnalysisError, ModelError
from crankbench.predict.lateral.approx import (MassShaft, dunkerley, dunkerley_combine, lumped_exact,
                                    rayleigh, stodola)
from crankbench.predict.lateral.fe import Bearing, Disk, Material, Rotor, ShaftSection


def test_two_equal_masses_at_third_points_closed_form():
    """Massless pinned shaft, masses m at L/3 and 2L/3: α₁₁ = 4L³/243EI, α₁₂ = 7L³/486EI,
    symmetric mode ω² = 1/(m(α₁₁+α₁₂)) = 486EI/(15 m L³). Rayleigh ≥ exact ≥ Dunkerley."""
    shaft = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1.0, 1.0],
                      positions=[1 / 3, 2 / 3])
    exact = np.sqrt(486 / 15)
    r, d, s = rayleigh(shaft), dunkerley(shaft), stodola(shaft, rtol=1e-12)
    assert r.bound == "upper" and d.bound == "lower" and s.bound == "bracket"
    assert d.omega < exact <= r.omega * (1 + 1e-15)
    assert d.omega == pytest.approx(1 / np.sqrt(2 * 4 / 243), rel=1e-13)  # 1/ω² = 2 m α₁₁
    assert s.omega == pytest.approx(exact, rel=1e-12)
    assert lumped_exact(shaft).omega == pytest.approx(exact, rel=1e-13)


def _fe_reference(shaft_len, diameter, masses, positions, density):
    """Euler-Bernoulli FE (no rotary inertia), fine mesh: the continuum reference."""
    mat = Material(2.1e11, density, poisson_ratio=0.3)
    rotor = Rotor(shaft=[ShaftSection(length=shaft_len, outer_diameter=diameter, material=mat)],
                  disks=[Disk(p, m) for m, p in zip(masses, positions)],
                  bearings=[Bearing(0.0, np.inf), Bearing(shaft_len, np.inf)],
                  theory="euler-bernoulli", rotary_inertia=False,
                  max_element_length=shaft_len / 60)
    return rotor.natural_frequencies(n_modes=1, error_estimate=False).omega[0]


@pytest.mark.parametrize("masses, positions", [
    ([30.0, 50.0, 20.0], [0.3, 0.6, 1.0]),
    ([80.0], [0.35]),
    ([5.0, 5.0], [0.2, 1.0]),
])
def test_bounds_bracket_the_continuum_with_shaft_mass(masses, positions):
    """Shaft mass + disks: Rayleigh (upper) ≥ FE continuum reference ≥ Dunkerley (lower)."""
    L, d, rho = 1.2, 0.05, 7850.0
    shaft = MassShaft(length=L, youngs_modulus=2.1e11, area_moment=np.pi * d**4 / 64,
                      masses=masses, positions=positions, mass_per_length=rho * np.pi * d**2 / 4)
    exact = _fe_reference(L, d, masses, positions, rho)
    r, dk = rayleigh(shaft), dunkerley(shaft)
    assert dk.omega < exact < r.omega
    assert (r.omega - exact) / exact < 2e-3  # Rayleigh with the static curve is close
    assert (exact - dk.omega) / exact < 0.1
    s = stodola(shaft, rtol=1e-9, n_segments=40)
    assert s.lower <= s.omega <= s.upper * (1 + 1e-15)
    assert s.omega == pytest.approx(exact, rel=2e-5)  # lumping error only


def test_uniform_beam_rayleigh_static_curve():
    """Uniform pinned beam: Rayleigh with the static curve ω = 9.8767 √(EI/ρAL⁴) > π²."""
    shaft = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[], positions=[],
                      mass_per_length=1.0)
    w = rayleigh(shaft).omega
    # closed form: ω² = ∫y / ∫y² with y = x(1 - 2x² + x³)/24 → ω² = 3024/31
    assert w**2 == pytest.approx(3024 / 31, rel=1e-13)
    assert w > np.pi**2


def test_stodola_converges_geometrically_and_brackets():
    shaft = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1.0, 3.0, 2.0],
                      positions=[0.2, 0.5, 0.9], support="cantilever")
    exact = lumped_exact(shaft).omega
    prev = None
    for tol in (1e-2, 1e-4, 1e-8):
        s = stodola(shaft, rtol=tol)
        assert s.lower <= exact <= s.upper * (1 + 1e-14)
        assert abs(s.omega - exact) / exact <= 2 * tol
        if prev is not None:
            assert s.iterations >= prev
        prev = s.iterations
    with pytest.raises(AnalysisError, match=r"stodola did not reach rtol=1e-12 in max_iter=1"):
        stodola(shaft, rtol=1e-12, max_iter=1)


def test_dunkerley_combine_and_result_frame():
    assert dunkerley_combine([3.0, 4.0]) == pytest.approx(2.4, rel=1e-15)
    shaft = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[2.0],
                      positions=[0.5], support="fixed-fixed")
    frame = dunkerley(shaft).to_frame()
    assert frame.loc[0, "bound"] == "lower"
    # single mass on a massless shaft: Dunkerley is exact, ω² = 192EI/(mL³)
    assert frame.loc[0, "omega"] ** 2 == pytest.approx(96.0, rel=1e-13)
    assert frame.loc[0, "speed_rpm"] == pytest.approx(np.sqrt(96.0) * 30 / np.pi, rel=1e-13)
    assert rayleigh(shaft).plot().axes


def test_mass_shaft_validation_messages():
    with pytest.raises(ModelError, match="masses has 2 values but positions has 1"):
        MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1, 2], positions=[0.5])
    with pytest.raises(ModelError, match=r"positions=\[1.5\] must lie inside the span"):
        MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1], positions=[1.5])
    with pytest.raises(ModelError, match="the shaft carries no mass"):
        MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[], positions=[])
    with pytest.raises(ModelError, match=r"support='free-free' is not one of"):
        MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1], positions=[0.5],
                  support="free-free")
