"""Crankshaft fillet and oil-bore stress-concentration factors, IACS UR M53 §3.

Source read: Korean Register, Rules for the Classification of Steel Ships, Guidance RA-05-E
(2025), Part 5 Annex 5-3 "Guidance for Calculation of Crankshaft Stress" §2-§6, which reproduces
UR M53's empirical formulas and validity ranges. No published worked example with factor values
was found; these tests check what the formulas must satisfy independently of their coefficients:

* oil bore: γ_B → 3 and γ_T → 4 as d_O → 0 (Kirsch 1898: circular hole in a plate under uniaxial
  tension and under pure shear);
* β_T is α_T's formula with the journal's own fillet ratio, so it equals α_T for equal pin and
  journal (§3 (3)(C)(a)) and follows r = R_G/D_G otherwise;
* normalisation of the bore factors: f(d_G), f(d_H) ≈ 1 for solid pins and journals;
* monotony the rule's data imply (larger fillet radius → smaller factors);
* the low-s extension (§3 (1)(H)): f(s,·) frozen below s = −0.5, f(recess) not below 1;
* validity-range refusals naming the parameter, and the stresses and strength of §2, §5, §6.
"""

import logging
from pathlib import Path

import numpy as np
import pytest

from crankbench.predict.crankshaft import web_stresses
from crankbench.predict.crankshaft_scf import (FilletGeometry, fillet_geometry_from_toml,
                                               m53_fatigue_strength, m53_fillet_stresses,
                                               stress_concentration_factors)
from crankbench.predict.errors import ModelError

BASE = dict(pin_diameter=0.30, journal_diameter=0.30, crank_radius=0.20, web_thickness=0.12,
            web_width=0.45, pin_fillet_radius=0.015, journal_fillet_radius=0.015)


def scf(**changes):
    return stress_concentration_factors(FilletGeometry(**{**BASE, **changes}))


def test_oil_bore_factors_tend_to_kirsch_hole_values():
    for d_o in (1e-4, 3e-3):
        k = scf(oil_bore=d_o * 0.30)
        assert abs(k.gamma_b - 3.0) < 6 * d_o and abs(k.gamma_t - 4.0) < 6.1 * d_o
    assert np.isnan(scf().gamma_b)               # no oil bore: no factor


def test_journal_torsion_factor_is_the_pin_formula_on_the_journal_ratio():
    k = scf()
    assert k.beta_t == k.alpha_t                  # same diameters and radii (§3 (3)(C)(a))
    # a journal of its own diameter and radius: β_T = α_T evaluated at r = R_G/D_G (other
    # parameters on the pin): the same value as a pin with that ratio
    k2 = scf(journal_diameter=0.34, journal_fillet_radius=0.02, crank_radius=0.22)
    ref = scf(journal_diameter=0.34, journal_fillet_radius=0.02, crank_radius=0.22,
              pin_fillet_radius=0.02 / 0.34 * 0.30)
    assert k2.beta_t == pytest.approx(ref.alpha_t, rel=1e-13)
    assert k2.beta_t != pytest.approx(k2.alpha_t, rel=1e-3)


def test_bore_factors_are_normalised_to_the_solid_shaft():
    solid = scf()
    for key in ("pin_bore", "journal_bore"):
        bored = scf(**{key: 1e-6})
        assert bored.alpha_b == pytest.approx(solid.alpha_b, rel=1e-5)
    # the polynomials' constant terms (0.9993, 0.9978, 1.0012, 1.0022, 0.9937) are within
    # 0.7 % of 1: the reference crank is solid
    d = FilletGeometry(**BASE)
    assert d.parameters()["d_g"] == 0 and d.parameters()["d_h"] == 0


def test_larger_fillet_radius_lowers_every_fillet_factor():
    small, large = scf(pin_fillet_radius=0.010, journal_fillet_radius=0.010), \
        scf(pin_fillet_radius=0.035, journal_fillet_radius=0.035)
    for name in ("alpha_b", "alpha_t", "beta_b", "beta_q", "beta_t"):
        assert getattr(large, name) < getattr(small, name), name
        assert getattr(large, name) > 1.0, name
    # f(r) = 0.2081 r^−0.5231: α_B scales exactly as r^−0.5231 with everything else fixed
    assert small.alpha_b / large.alpha_b == pytest.approx((0.010 / 0.035) ** -0.5231,
                                                          rel=1e-12)


def test_low_overlap_extension_freezes_the_overlap_functions_below_minus_half():
    # s = S/D with S = D − E here: E = 0.45 → s = −0.5, E = 0.60 → s = −1.0
    a, b = scf(crank_radius=0.45), scf(crank_radius=0.60)
    assert a.parameters["s"] == pytest.approx(-0.5) and b.parameters["s"] == pytest.approx(-1.0)
    for name in ("alpha_b", "alpha_t", "beta_b", "beta_q"):
        assert getattr(b, name) == pytest.approx(getattr(a, name), rel=1e-12), name
    # a recess with strongly negative s would make f(recess) < 1: not credited (taken as 1)
    r = scf(crank_radius=0.60, pin_recess=0.003, journal_recess=0.003)
    assert r.alpha_b == pytest.approx(b.alpha_b, rel=1e-12)
    # with overlap a recess raises the factors by 1 + (t_H + t_G)(1.8 + 3.2 s)
    k0, k1 = scf(), scf(pin_recess=0.003, journal_recess=0.003)
    s = k0.parameters["s"]
    assert k1.alpha_b / k0.alpha_b == pytest.approx(1 + 0.02 * (1.8 + 3.2 * s), rel=1e-12)


@pytest.mark.parametrize("change, name", [
    (dict(pin_fillet_radius=0.006), "r_pin = 0.02"),
    (dict(web_thickness=0.27), "w = 0.9"),
    (dict(web_width=0.30), "b = 1"),
    (dict(crank_radius=0.12), "s = 0.6"),
    (dict(oil_bore=0.075), "d_o = 0.25"),
    (dict(pin_bore=0.255), "d_h = 0.85"),
])
def test_outside_the_range_the_formulas_are_refused(change, name, caplog):
    with pytest.raises(ModelError, match=f"outside the range of the UR M53 empirical formulas "
                                         f"\\({name}"):
        scf(**change)
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        k = stress_concentration_factors(FilletGeometry(**{**BASE, **change}), extrapolate=True)
    assert not k.within_validity and name in k.violations[0]
    assert "extrapolating" in caplog.text


def test_semi_built_cranks_have_no_journal_factors_and_a_reduced_web():
    g = FilletGeometry(**{**BASE, "pin_recess": 0.02, "semi_built": True})
    assert g.effective_web_thickness == pytest.approx(0.12 - (0.02 - 0.015))
    k = stress_concentration_factors(g)
    assert np.isnan(k.beta_b) and np.isnan(k.beta_q) and np.isnan(k.beta_t)
    assert k.parameters["w"] == pytest.approx(0.115 / 0.30)


def test_rule_stresses_on_the_web_basis_and_the_equivalent_stress():
    k = scf()
    m, q, t = np.array([-2.0e4, 6.0e4]), np.array([-1e5, 3e5]), np.array([-3e4, 3e4])
    r = m53_fillet_stresses(k, bending_moment=m, radial_force=q, torque=t)
    w, b, d = 0.12, 0.45, 0.30
    assert r["sigma_bfn"] == pytest.approx(4.0e4 / (b * w * w / 6), rel=1e-14)
    assert r["tau_n_pin"] == pytest.approx(3e4 * 16 / (np.pi * d ** 3), rel=1e-14)
    assert r["equivalent_pin"] == pytest.approx(
        np.sqrt((k.alpha_b * r["sigma_bfn"] + 10e6) ** 2 + 3 * (k.alpha_t * r["tau_n_pin"]) ** 2))
    # the same fillet stresses through predict.crankshaft.web_stresses on the web basis
    pin = web_stresses(bending_moment=m, radial_force=q, web_width=b, web_thickness=w,
                       bending_scf=k.alpha_b, compression_scf=0.0)
    jnl = web_stresses(bending_moment=m, radial_force=q, web_width=b, web_thickness=w,
                       bending_scf=k.beta_b, compression_scf=k.beta_q)
    assert pin["fillet_alternating"] == pytest.approx(r["sigma_bh"], rel=1e-13)
    assert jnl["fillet_alternating"] == pytest.approx(r["sigma_bg"], rel=1e-13)
    two = m53_fillet_stresses(k, bending_moment=m, radial_force=q, torque=t, cycle=2,
                              engine_type="crosshead")
    assert two["sigma_bfn"] == pytest.approx(0.8 * r["sigma_bfn"]) and two["sigma_add"] == 30e6


def test_fatigue_strength_formula_by_hand():
    # σ_B = 800 N/mm², D = 300 mm, R_H = 15 mm, K = 1:
    # (0.42·800 + 39.3)(0.264 + 1.073·300^−0.2 + (785 − 800)/4900 + 196/800 /√15)
    hand = 375.3 * (0.264 + 1.073 * 300 ** -0.2 - 15 / 4900 + 0.245 / np.sqrt(15))
    assert m53_fatigue_strength(tensile_strength=800e6, diameter=0.3,
                                fillet_radius=0.015) == pytest.approx(hand * 1e6, rel=1e-13)
    # fillet radii below 2 mm are taken as 2 mm
    assert m53_fatigue_strength(tensile_strength=800e6, diameter=0.3, fillet_radius=0.001) == \
        m53_fatigue_strength(tensile_strength=800e6, diameter=0.3, fillet_radius=0.002)


def test_fillet_table_of_the_sample_engine():
    path = Path(__file__).resolve().parents[2] / "sample_data/engines/i6.toml"
    g = fillet_geometry_from_toml(path)
    assert g.crank_radius == pytest.approx(0.08)          # from the engine's stroke
    k = stress_concentration_factors(g)
    assert k.within_validity and 1.5 < k.alpha_t < k.alpha_b < k.beta_q


def test_toml_errors_name_the_key(tmp_path):
    p = tmp_path / "m.toml"
    p.write_text("[crankshaft.fillets]\npin_diameter = 0.3\njournal_diameter = 0.3\n"
                 "crank_radius = 0.2\nweb_thickness = 0.12\nweb_width = 0.45\n"
                 "pin_fillet_radius = 0.015\njournal_filet_radius = 0.015\n")
    with pytest.raises(ModelError, match="crankshaft.fillets.journal_fillet_radius is missing"):
        fillet_geometry_from_toml(p)
