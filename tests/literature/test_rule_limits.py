"""Torsional-vibration stress limits of IACS UR M68, hand-computed from the rule as printed.

No published worked example of the M68 limits was found, so each value below is worked out by
hand from the formulas as printed in a class-society rule that reproduces the UR, and written
out here as numbers (not computed through crankbench's helpers):

* [KR] Korean Register, *Rules for the Classification of Steel Ships* 2025 (RA-05-E), Pt 5
  Ch 4 "Torsional vibration of shaftings", Sec 2:
  202.1(1) τ_1 = (T_s + 160)/18 · C_k · C_d · (3 − 2λ²) for 0 ≤ λ ≤ 0.9,
  τ_1 = 1.38 (T_s + 160)/18 · C_k · C_d for 0.9 ≤ λ ≤ 1.05, C_d = 0.35 + 0.93 d^−0.2 (d in mm);
  Table 5.4.1 (C_k); 202.1(2) τ_2 = 1.7 τ_1/√C_k "within the range below 80 % of the maximum
  continuous revolutions", for transient operation only;
  206.1(1) barred range 16 N_c/(18 − λ) ≤ N ≤ (18 − λ) N_c/16.
* [LR] Lloyd's Register, Rules for Naval Ships (2023) Vol 2 Pt 3 Ch 2 §3.1.2/3.1.5: σ_B in the
  formulae limited to 760 N/mm² (carbon, C-Mn) and 800 N/mm² (alloy);
  [GL] GL/BKI Rules I-1-2 (2008) Sec 4 A.2: 600 N/mm² for propeller shafts.
* [M53] the λ = 0.8 clause, "no barred speed ranges above a speed ratio of λ ≥ 0.8 for normal
  firing conditions" (KR Guidance Annex 5-3 §2(2)(A)(d), reproducing UR M53).
"""

import numpy as np
import pytest

from crankbench.predict.torsion.rules import (
    M68_CK,
    SectionRule,
    judge_barred_ranges,
    m68_barred_range,
    m68_limits,
)

MPA = 1e6


def test_intermediate_shaft_with_tapered_keyway_by_hand():
    """[KR] 202.1: σ_B = 600 N/mm², d = 350 mm, keyway tapered (C_k = 0.6), n_0 = 120 rpm.

    By hand: 350^−0.2 = exp(−0.2 · ln 350) = exp(−1.17158) = 0.30990, so
    C_d = 0.35 + 0.93 · 0.30990 = 0.63818; (600 + 160)/18 = 42.222; × 0.6 × 0.63818 = 16.167.
    λ = 0.5: × (3 − 0.5) = 40.418; λ = 0.75: × 1.875 = 30.314; λ = 0.9 … 1.05: × 1.38 = 22.311.
    τ_T at λ = 0.75: 1.7/√0.6 = 2.19469 → 66.529 N/mm²; at λ = 0.5: 88.706 N/mm².
    """
    speed = np.array([60.0, 90.0, 108.0, 120.0, 126.0, 127.0])
    tc, tt = m68_limits(speed, tensile_strength=600 * MPA, diameter=0.350,
                        ck=M68_CK["keyway tapered"], rated_speed_rpm=120.0)
    np.testing.assert_allclose(tc[:5] / MPA, [40.418, 30.314, 22.311, 22.311, 22.311],
                               atol=0.002)
    assert np.isnan(tc[5])                     # λ = 1.058 > 1.05: the rule gives no value
    np.testing.assert_allclose(tt[:2] / MPA, [88.706, 66.529], atol=0.002)
    # from λ = 0.8 up no transient allowance ([KR] 202.1(2) "below 80 %"): τ_T = τ_C
    np.testing.assert_allclose(tt[2:5] / MPA, [22.311] * 3, atol=0.002)


def test_propeller_shaft_caps_tensile_strength_at_600():
    """[GL] Sec 4 A.2, [KR] 202.1(1): a propeller shaft of σ_B = 700 N/mm² enters the formula
    with 600. d = 420 mm, key-fitted propeller (C_k = 0.55), λ = 0.5:
    420^−0.2 = exp(−0.2 · 6.04025) = 0.29878 → C_d = 0.62786;
    (600 + 160)/18 · 0.55 · 0.62786 · 2.5 = 36.451 N/mm²."""
    rule = SectionRule("propeller shaft", 700 * MPA, design="propeller key", kind="propeller",
                       diameter=0.420)
    tc, _ = rule.limits([60.0], rated_speed_rpm=120.0)
    assert tc[0] / MPA == pytest.approx(36.451, abs=0.002)
    # [LR] §3.1.2: carbon 760, alloy 800 for intermediate shafts
    assert SectionRule("s", 900 * MPA).sigma_used == 760 * MPA
    assert SectionRule("s", 900 * MPA, material="alloy").sigma_used == 800 * MPA


def test_ck_table_as_printed():
    """[KR] Table 5.4.1, row by row."""
    printed = {"integral flange": 1.0, "shrink fit coupling": 1.0, "keyway tapered": 0.6,
               "keyway cylindrical": 0.45, "radial hole": 0.50, "longitudinal slot": 0.30,
               "thrust collar": 0.85, "axial roller bearing": 0.85, "propeller flange": 0.55,
               "propeller key": 0.55, "stern tube seal": 0.8}
    assert M68_CK == printed


def test_barred_range_extent_by_hand():
    """[KR] 206.1(1): n_c = 90 rpm, n_0 = 120 rpm, λ_c = 0.75:
    16 · 90 / 17.25 = 83.478 rpm, 17.25 · 90 / 16 = 97.031 rpm."""
    lo, hi = m68_barred_range(90.0, 120.0)
    assert lo == pytest.approx(83.478, abs=1e-3) and hi == pytest.approx(97.031, abs=1e-3)


def test_no_barred_range_above_lambda_08():
    """[M53] / [KR] 202.1(2): with n_0 = 120 rpm, 0.8 n_0 = 96 rpm. The calculated range
    around a 90 rpm critical (83.5–97.0 rpm) reaches above 96 rpm: not acceptable in normal
    firing; around an 80 rpm critical (λ_c = 0.667: 16·80/17.333 = 73.85 to 17.333·80/16 =
    86.67 rpm) it is."""
    assert judge_barred_ranges([(83.478, 97.031)], application="propulsion",
                               rated_speed_rpm=120.0)[0] == "fail"
    lo, hi = m68_barred_range(80.0, 120.0)
    assert (lo, hi) == pytest.approx((73.846, 86.667), abs=1e-3)
    assert judge_barred_ranges([(lo, hi)], application="propulsion",
                               rated_speed_rpm=120.0)[0] == "pass"
