"""Unit spellings -> SI, checked against the defining constants (not against the table)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crankbench.measure.units import SI_UNITS, known_units, sensitivity_to_si, to_si
from crankbench.predict.errors import RecordError

# Independent definitions: 1 g = 9.80665 m/s^2 (3rd CGPM 1901); 1 in = 25.4 mm (1959
# international yard and pound); 1 lbf = 4.4482216152605 N; 1 bar = 1e5 Pa.
G0 = 9.80665
LBF = 0.45359237 * G0
CASES = [
    ("g", 2.0, 2 * G0, "m/s^2", "acceleration"),
    ("m/s²", 3.0, 3.0, "m/s^2", "acceleration"),
    ("m/s^2", 3.0, 3.0, "m/s^2", "acceleration"),
    ("mm/s", 12.5, 0.0125, "m/s", "velocity"),
    ("in/s", 1.0, 0.0254, "m/s", "velocity"),
    ("µm", 40.0, 40e-6, "m", "displacement"),
    ("um", 40.0, 40e-6, "m", "displacement"),
    ("mm", 2.0, 2e-3, "m", "displacement"),
    ("m", 2.0, 2.0, "m", "displacement"),
    ("deg", 180.0, math.pi, "rad", "angle"),
    ("°", 90.0, math.pi / 2, "rad", "angle"),
    ("rad", 1.0, 1.0, "rad", "angle"),
    ("rpm", 60.0, 2 * math.pi, "rad/s", "rotational_speed"),
    ("1/min", 3000.0, 100 * math.pi, "rad/s", "rotational_speed"),
    ("Hz", 50.0, 100 * math.pi, "rad/s", "rotational_speed"),
    ("rad/s", 10.0, 10.0, "rad/s", None),
    ("deg/s", 360.0, 2 * math.pi, "rad/s", "angular_velocity"),
    ("bar", 150.0, 150e5, "Pa", "pressure"),
    ("kPa", 1.0, 1e3, "Pa", "pressure"),
    ("MPa", 12.0, 12e6, "Pa", "pressure"),
    ("psi", 1.0, LBF / 0.0254**2, "Pa", "pressure"),
    ("Pa", 7.0, 7.0, "Pa", "pressure"),
    ("V", 1.5, 1.5, "V", "voltage"),
    ("mV", 1500.0, 1.5, "V", "voltage"),
    ("N", 3.0, 3.0, "N", "force"),
    ("kN", 3.0, 3000.0, "N", "force"),
    ("N·m", 4.0, 4.0, "N*m", "torque"),
    ("Nm", 4.0, 4.0, "N*m", "torque"),
    ("kN·m", 4.0, 4000.0, "N*m", "torque"),
    ("[mm/s]", 1.0, 1e-3, "m/s", "velocity"),
    ("RPM", 60.0, 2 * math.pi, "rad/s", "rotational_speed"),
]


@pytest.mark.parametrize("unit, value, expected, si, hint", CASES)
def test_to_si_matches_definition(unit, value, expected, si, hint):
    out, si_unit, quantity = to_si(np.array([value]), unit, channel="x")
    assert out[0] == pytest.approx(expected, rel=1e-12)
    assert si_unit == si and si_unit in SI_UNITS
    assert quantity == hint


@pytest.mark.parametrize("unit, value, expected, si", [
    ("mV/g", 100.0, 0.1 / G0, "V/(m/s^2)"),
    ("mV/(m/s^2)", 10.2, 0.0102, "V/(m/s^2)"),
    ("V/(mm/s)", 0.02, 20.0, "V/(m/s)"),
    ("pC/g", 10.0, 10e-12 / G0, "C/(m/s^2)"),
    ("mV/um", 8.0, 8000.0, "V/m"),
])
def test_sensitivity_to_si(unit, value, expected, si):
    out, su = sensitivity_to_si(value, unit, channel="acc")
    assert out == pytest.approx(expected, rel=1e-12)
    assert su == si
    # to_si accepts sensitivities too and says so
    v, su2, hint = to_si(value, unit)
    assert v == pytest.approx(expected, rel=1e-12) and su2 == si and hint == "sensitivity"


def test_unknown_unit_names_channel_unit_and_close_spellings():
    with pytest.raises(RecordError, match=r"channel 'acc1': unknown unit 'mm/ss'; close known "
                                          r"spellings: .*mm/s"):
        to_si([1.0], "mm/ss", channel="acc1")


def test_unknown_sensitivity_unit():
    with pytest.raises(RecordError, match=r"channel 'acc': unknown sensitivity unit 'mV/furlong'"):
        sensitivity_to_si(1.0, "mV/furlong", channel="acc")


def test_float32_stays_float32_and_input_not_modified():
    x = np.ones(4, dtype=np.float32)
    out, _, _ = to_si(x, "g")
    assert out.dtype == np.float32 and np.all(x == 1.0)
    assert out[0] == np.float32(G0)


@settings(max_examples=50, deadline=None)
@given(st.text(max_size=12))
def test_any_unit_string_converts_or_raises_record_error(text):
    """Fuzz: a unit string either converts to a finite SI value or raises RecordError."""
    try:
        out, si, _ = to_si(np.array([1.0]), text, channel="fuzz")
    except RecordError as exc:
        assert "fuzz" in str(exc)
        return
    assert np.all(np.isfinite(out))
    assert si in SI_UNITS or si.startswith(("V/", "C/"))


@settings(max_examples=50, deadline=None)
@given(st.sampled_from(known_units()), st.floats(-1e6, 1e6))
def test_every_known_unit_gives_finite_si(unit, value):
    out, si, _ = to_si(value, unit)
    assert math.isfinite(out) and si in SI_UNITS


@pytest.mark.parametrize("unit, rpm_per_unit", [("U/min", 1.0), ("min-1", 1.0), ("1/min", 1.0),
                                                ("1/s", 60.0), ("U/s", 60.0), ("s-1", 60.0)])
def test_rig_spellings_of_rotational_speed(unit, rpm_per_unit):
    """German and DIN-style speed units of rig exports (n [U/min], n [1/s]): 1 U/min =
    2π/60 rad/s, 1 1/s = 2π rad/s (one revolution per second)."""
    values, si, quantity = to_si(np.array([1500.0]), unit)
    assert si == "rad/s" and quantity == "rotational_speed"
    assert values[0] == pytest.approx(1500.0 * rpm_per_unit * np.pi / 30, rel=1e-15)
