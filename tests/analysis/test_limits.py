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
    lim = StressLimits([0, 1000], [30e6, 30e6], [60e6, 60e6], source="rule X")
    speed = np.array([100.0, 200.0, 300.0, 400.0])
    ok = check_torsional_stress(speed, [10e6, 45e6, 10e6, 5e6], lim, section="crank 6")
    assert ok.passed and "barred 157–243 rpm" in ok.detail
    assert ok.value == pytest.approx(45 / 60)
    assert ok.source == "rule X"
    bad = check_torsional_stress(speed, [10e6, 70e6, 10e6, 5e6], lim)
    assert not bad.passed and "TRANSIENT LIMIT EXCEEDED" in bad.detail
    inside = check_torsional_stress(speed, [10e6, 45e6, 10e6, 5e6], lim,
                                    operating_range_rpm=(150, 450))
    assert not inside.passed and "inside the operating range at 200–200 rpm" in inside.detail


def test_torsional_stress_bad_inputs():
    lim = StressLimits([0, 1000], [30e6, 30e6], [60e6, 60e6])
    with pytest.raises(AnalysisError, match="stress has 2 values, speed_rpm 3"):
        check_torsional_stress([1, 2, 3], [1, 2], lim)
    with pytest.raises(AnalysisError, match="limits must be a predict.torsion.stress"):
        check_torsional_stress([1, 2, 3], [1, 2, 3], {"continuous": 1})


def test_residual_unbalance_against_grade():
    """U_per = G m / Ω (ISO 21940-11 §5): G 6.3, 100 kg, 3000 rpm → 2.005e-3 kg·m."""
    u_per = 6.3e-3 * 100.0 / (3000 * np.pi / 30)
    ok = check_residual_unbalance([0.9 * u_per / 2, 0.5 * u_per / 2], rotor_mass=100.0,
                                  speed_rpm=3000.0, grade=6.3)
    assert ok.passed and ok.value == pytest.approx(0.9)
    bad = check_residual_unbalance([1.2 * u_per / 2, 0.5 * u_per / 2], rotor_mass=100.0,
                                   speed_rpm=3000.0, grade=6.3)
    assert not bad.passed and "smallest standard grade met: G 16" in bad.detail
