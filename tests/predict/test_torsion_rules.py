"""IACS UR M68 limits: closed-form values, continuity, caps, the λ = 0.8 clause, TOML."""

import numpy as np
import pytest

from crankbench.predict.errors import ModelError
from crankbench.predict.torsion.rules import (
    M68_CK,
    SectionRule,
    judge_barred_ranges,
    m68_limits,
    size_factor,
)


def test_size_factor_closed_form():
    # C_D = 0.35 + 0.93 d^-0.2, d in mm (UR M68; LR Naval Ships Vol 2 Pt 5 Ch 1 §3.1.1)
    assert size_factor(0.4) == pytest.approx(0.35 + 0.93 * 400.0 ** -0.2, rel=1e-12)
    assert size_factor(0.1) == pytest.approx(0.35 + 0.93 / 100.0 ** 0.2, rel=1e-12)


def test_m68_continuous_and_transient_by_hand():
    """σ_B = 600, d = 400 mm, C_K = 0.55 at λ = 0.5, 0.9, 1.0; τ_T = 1.7 τ_C / √C_K below
    λ = 0.8 only (no transient allowance above: τ_T = τ_C there)."""
    base = (600 + 160) / 18 * 0.55 * (0.35 + 0.93 * 400 ** -0.2)
    tc, tt = m68_limits([360.0, 648.0, 720.0], tensile_strength=600e6, diameter=0.4, ck=0.55,
                        rated_speed_rpm=720.0)
    np.testing.assert_allclose(tc / 1e6, [base * 2.5, base * 1.38, base * 1.38], rtol=1e-12)
    np.testing.assert_allclose(tt[0], 1.7 * tc[0] / np.sqrt(0.55), rtol=1e-12)
    np.testing.assert_allclose(tt[1:], tc[1:], rtol=1e-12)


def test_m68_branches_meet_at_lambda_09_and_stop_above_105():
    lam = np.array([0.9 - 1e-9, 0.9, 1.05, 1.06])
    tc, _ = m68_limits(lam * 100.0, tensile_strength=500e6, diameter=0.3, ck=1.0,
                       rated_speed_rpm=100.0)
    assert tc[0] == pytest.approx(tc[1], rel=1e-8)   # 3 − 2·0.81 = 1.38
    assert np.isfinite(tc[2]) and np.isnan(tc[3])


def test_tensile_strength_caps():
    r = SectionRule("s", 900e6, material="alloy")
    assert r.sigma_used == 800e6
    assert SectionRule("s", 900e6, kind="propeller").sigma_used == 600e6
    assert SectionRule("s", 700e6).sigma_used == 700e6
    with pytest.raises(ModelError, match="design"):
        SectionRule("s", 600e6, design="splined")
    assert M68_CK["keyway tapered"] == 0.6 and M68_CK["integral flange"] == 1.0


def test_barred_range_placement():
    assert judge_barred_ranges([(709, 744)], application="propulsion",
                               rated_speed_rpm=720)[0] == "fail"
    assert judge_barred_ranges([(560, 580)], application="propulsion",
                               rated_speed_rpm=720)[0] == "fail"     # ends above 576 rpm
    assert judge_barred_ranges([(300, 330)], application="propulsion",
                               rated_speed_rpm=720)[0] == "pass"
    # the tachometer tolerance widens the range past 0.8 n0
    assert judge_barred_ranges([(560, 572)], application="propulsion", rated_speed_rpm=720,
                               tachometer_tolerance_rpm=5)[0] == "fail"
    assert judge_barred_ranges([(300, 330)], application="propulsion",
                               rated_speed_rpm=None)[0] == "inconclusive"
    aux = dict(application="auxiliary", rated_speed_rpm=1500, operating_range_rpm=(1425, 1575))
    assert judge_barred_ranges([(900, 1000)], **aux)[0] == "pass"
    assert judge_barred_ranges([(1400, 1450)], **aux)[0] == "fail"


def test_marine_model_limits_from_toml(tmp_path):
    from pathlib import Path

    from crankbench.predict.torsion import from_toml

    root = Path(__file__).resolve().parents[2]
    s = from_toml(root / "sample_data/shaftlines/marine_6l.toml")
    lim = s.limits
    assert lim.rated_speed_rpm == 720.0 and lim.operating_range_rpm == (500.0, 750.0)
    tc, tt, rule = lim.limits_for("propeller shaft", np.array([720.0]))
    expected = 760 / 18 * 0.55 * (0.35 + 0.93 * 340 ** -0.2) * 1.38
    assert tc[0] / 1e6 == pytest.approx(expected, rel=1e-12) and "M68.5" in rule
    text = (root / "sample_data/shaftlines/marine_6l.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('section = "propeller shaft"', 'section = "no such shaft"')
                   .replace('engine = "../engines/marine_6l.toml"',
                            f'engine = "{root / "sample_data/engines/marine_6l.toml"}"'))
    with pytest.raises(ModelError, match="no such shaft"):
        from_toml(bad)
