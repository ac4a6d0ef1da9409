"""Limit checks: ISO zone boundaries, severity rms, torsional stress, residual unbalance."""

import numpy as np
import pytest

from crankbench.analysis.limits import (
    ISO_10816_1_CLASSES,
    ZoneBoundaries,
    check_residual_unbalance,
    check_torsional_stress,
    check_vibration_severity,
    vibration_severity,
    zone_boundaries,
)
from crankbench.predict.errors import AnalysisError
from crankbench.predict.torsion.stress import StressLimits


def test_iso_10816_1_table_b1_values():
    """ISO 10816-1:1995 Annex B, Table B.1, velocity rms boundaries in mm/s."""
    table_mm_s = {"I": (0.71, 1.8, 4.5), "II": (1.12, 2.8, 7.1), "III": (1.8, 4.5, 11.2),
                  "IV": (2.8, 7.1, 18.0)}
    for cls, values in table_mm_s.items():
        np.testing.assert_allclose(np.array(ISO_10816_1_CLASSES[cls]) * 1e3, values)
        z = zone_boundaries(cls)
        assert "ISO 10816-1:1995 Annex B Table B.1" in z.source


def test_zone_letters_at_and_around_boundaries():
    z = zone_boundaries("III")
    assert list(z.zone([1.0e-3, 1.8e-3, 2.0e-3, 4.6e-3, 11.3e-3])) == ["A", "B", "B", "C", "D"]


def test_class_names_and_unknown_class():
    assert zone_boundaries("iii") == zone_boundaries("III") == zone_boundaries(3)
    with pytest.raises(AnalysisError, match=r"machine_class='V' is not one of 'I', 'II', "
                                             r"'III', 'IV'"):
        zone_boundaries("V")


def test_custom_boundaries_must_ascend():
    with pytest.raises(AnalysisError, match="zone boundaries must ascend"):
        ZoneBoundaries(2e-3, 1e-3, 3e-3)


def test_severity_rms_of_sines_and_band():
    """rms of a two-tone velocity: in-band tone counts, the 5 Hz tone is outside 10–1000 Hz."""
    fs = 4096.0
    t = np.arange(0, 8, 1 / fs)
    v = 4e-3 * np.sin(2 * np.pi * 64 * t) + 3e-3 * np.sin(2 * np.pi * 5 * t)
    sev = vibration_severity(v, fs=fs, window_s=1.0)
    np.testing.assert_allclose(sev.velocity_rms, 4e-3 / np.sqrt(2), rtol=2e-3)
    # acceleration of the same 64 Hz tone integrates to the same velocity rms
    a = 4e-3 * 2 * np.pi * 64 * np.cos(2 * np.pi * 64 * t)
    sev_a = vibration_severity(a, fs=fs, quantity="acceleration", window_s=1.0)
    np.testing.assert_allclose(sev_a.velocity_rms, 4e-3 / np.sqrt(2), rtol=2e-3)


def test_severity_speed_per_window_and_check():
    fs = 2000.0
    t = np.arange(0, 10, 1 / fs)
    rpm = 600 + 60 * t
    v = (1e-3 + 6e-4 * t) * np.sqrt(2) * np.sin(2 * np.pi * 40 * t)
    sev = vibration_severity(v, fs=fs, speed_rpm=rpm, window_s=1.0, overlap=0.0)
    # mean speed over each window's samples (the window centre lies half a sample later)
    np.testing.assert_allclose(sev.speed_rpm, 600 + 60 * (np.arange(10) + 0.5), atol=0.02)
    check = check_vibration_severity(sev, machine_class="III")
    # the last window's rms is about 1e-3 + 6e-4 × 9.5 = 6.7 mm/s: zone C, fails B
    assert not check.passed
    assert check.value == pytest.approx(6.7e-3, rel=0.02)
    assert "zone C" in check.detail and "at 1170 rpm" in check.detail
    assert check.limit == pytest.approx(4.5e-3)
    assert check_vibration_severity(sev, machine_class="IV").passed
    assert check.plot().axes


def test_severity_bad_window():
    with pytest.raises(AnalysisError, match=r"window_s=5.0 \(5000 samples\) is longer than the "
                                             r"signal \(1000 samples\)"):
        vibration_severity(np.zeros(1000), fs=1000.0, window_s=5.0)


def test_torsional_stress_barred_and_transient():
    """User curves, propulsion at 1000 rpm rated: a barred range below λ = 0.8 is allowed."""
    lim = StressLimits([0, 1000], [30e6, 30e6], [60e6, 60e6], source="rule X")
    speed = np.array([100.0, 200.0, 300.0, 400.0])
    trans, cont = check_torsional_stress(speed, [10e6, 45e6, 10e6, 5e6], lim, section="crank 6",
                                         rated_speed_rpm=1000.0)
    # crossings of 30 MPa interpolated: 100 + 100·20/35 = 157.1, 200 + 100·15/35 = 242.9
    assert "barred 157–243 rpm" in cont.detail and "λ = 0.8" in cont.detail
    # the data stop at 400 rpm: the range up to the rated speed is not assessed
    assert cont.status == "inconclusive" and "400–1000 rpm" in cont.detail
    _, full = check_torsional_stress(np.append(speed, 1000.0), [10e6, 45e6, 10e6, 5e6, 5e6],
                                     lim, section="crank 6", rated_speed_rpm=1000.0)
    assert full.status == "pass"
    assert trans.passed and trans.value == pytest.approx(45e6) and trans.limit == 60e6
    assert trans.units == "Pa" and "rule X" in trans.source
    bad, _ = check_torsional_stress(speed, [10e6, 70e6, 10e6, 5e6], lim, rated_speed_rpm=1000.0)
    assert bad.status == "fail" and "transient limit exceeded" in bad.detail


def test_barred_range_at_rated_speed_fails():
    """IACS UR M68.5: no barred range above λ = 0.8 in normal operation; one at the rated
    speed fails, and the overall verdict with it."""
    from crankbench.analysis.verdict import combine
    from crankbench.predict.torsion.rules import MakerLimit, RuleLimits

    lim = RuleLimits(rated_speed_rpm=720.0, operating_range_rpm=(500.0, 750.0),
                     crankshaft=MakerLimit(("crank",), 42e6, 105e6))
    speed = np.linspace(400.0, 760.0, 73)
    tau = 20e6 + 40e6 * np.exp(-((speed - 720.0) / 15.0) ** 2)
    trans, cont = check_torsional_stress(speed, tau, lim, section="crank")
    assert trans.status == "pass" and cont.status == "fail"
    # closed form of the crossings: 20 + 40 exp(−x²) = 42 → x = √ln(40/22) = 0.7732 → ±11.6 rpm
    half = 15.0 * np.sqrt(np.log(40 / 22))
    lo, hi = cont.data.barred_ranges_rpm[0]
    assert lo == pytest.approx(720 - half, abs=0.3) and hi == pytest.approx(720 + half, abs=0.3)
    assert "contains the rated speed 720 rpm" in cont.detail
    assert combine([trans.verdict, cont.verdict]).status == "fail"
    # the same resonance at 300 rpm (λ = 0.42 < 0.8): barred range allowed
    tau_low = 20e6 + 40e6 * np.exp(-((speed - 450.0) / 15.0) ** 2)
    _, low = check_torsional_stress(speed, tau_low, lim, section="crank")
    assert low.status == "pass" and "below λ = 0.8 (576 rpm)" in low.detail


def test_model_without_limit_data_is_not_assessed():
    from crankbench.analysis.torsional_limits import not_assessed
    from crankbench.analysis.verdict import combine

    c = not_assessed("measured torsional stress", "the model has no stress limit data")
    assert c.status == "inconclusive" and not c.passed and c.detail.startswith("not assessed")
    assert combine([c.verdict]).status == "inconclusive"


def test_run_not_covering_the_operating_range_is_inconclusive():
    from crankbench.predict.torsion.rules import MakerLimit, RuleLimits

    lim = RuleLimits(rated_speed_rpm=720.0, operating_range_rpm=(500.0, 750.0),
                     crankshaft=MakerLimit(("crank",), 42e6, 105e6))
    speed = np.linspace(200.0, 600.0, 41)
    _, cont = check_torsional_stress(speed, np.full(41, 10e6), lim, section="crank")
    assert cont.status == "inconclusive" and "600–750 rpm of the operating range" in cont.detail


def test_torsional_stress_bad_inputs():
    lim = StressLimits([0, 1000], [30e6, 30e6], [60e6, 60e6])
    with pytest.raises(AnalysisError, match="stress has 2 values, speed_rpm 3"):
        check_torsional_stress([1, 2, 3], [1, 2], lim)
    with pytest.raises(AnalysisError, match="limits must be a predict.torsion.rules.RuleLimits"):
        check_torsional_stress([1, 2, 3], [1, 2, 3], {"continuous": 1})


def test_iso_10816_6_classes_and_choice():
    """Severity grades step by 10^0.2 (1.12 ... 178 mm/s); classes are flagged unverified."""
    from crankbench.analysis.limits import ISO_10816_6_GRADES, reciprocating_class

    g = np.array(ISO_10816_6_GRADES) * 1e3
    np.testing.assert_allclose(g[1:] / g[:-1], 10 ** 0.2, rtol=0.01)
    z = zone_boundaries(5, standard="ISO 10816-6")
    assert not z.verified and "NOT verified" in z.source and z.merged_ab
    assert list(z.zone([5e-3, 15e-3, 30e-3])) == ["A/B", "C", "D"]
    assert reciprocating_class(power_w=3.1e6, rated_speed_rpm=720, resilient=True)[0] == 5
    assert reciprocating_class(power_w=80e3, rated_speed_rpm=3000, resilient=True)[0] is None
    assert check_vibration_severity([2e-3], machine_class=None).status == "inconclusive"
    with pytest.raises(AnalysisError, match="not an ISO 10816-6 class"):
        zone_boundaries(8, standard="ISO 10816-6")


def test_residual_unbalance_against_grade():
    """U_per = G m / Ω (ISO 21940-11 §5): G 6.3, 100 kg, 3000 rpm → 2.005e-3 kg·m."""
    u_per = 6.3e-3 * 100.0 / (3000 * np.pi / 30)
    ok = check_residual_unbalance([0.9 * u_per / 2, 0.5 * u_per / 2], rotor_mass=100.0,
                                  speed_rpm=3000.0, grade=6.3)
    assert ok.passed and ok.value == pytest.approx(0.9)
    bad = check_residual_unbalance([1.2 * u_per / 2, 0.5 * u_per / 2], rotor_mass=100.0,
                                   speed_rpm=3000.0, grade=6.3)
    assert not bad.passed and "smallest standard grade met: G 16" in bad.detail
