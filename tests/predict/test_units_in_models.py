"""Units in model files (issue 19): quantity strings accepted everywhere a number is, plain
numbers in the key's unit (SI unless the key's name says otherwise), and a value outside its
key's plausible range warns with the likely slip.

References: the conversion factors are exact SI definitions (BIPM SI brochure, 9th ed.,
tables 7-8: 1 mm = 1e-3 m, 1 GPa = 1e9 Pa, 1 bar = 1e5 Pa, 1 min = 60 s); a shaft turning at
f Hz makes f revolutions per second = 60 f rpm = 2π f rad/s.
"""

from __future__ import annotations

import ast
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from crankbench.predict._toml import Table
from crankbench.predict._units import PlausibilityWarning, UnitError, slip_message, to_unit
from crankbench.predict.errors import ModelError

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("text, unit, expected", [
    ("260 mm", "m", 0.26),
    ("81 GPa", "Pa", 81e9),
    ("22 bar", "Pa", 22e5),
    ("2.5 MN*m/rad", "N*m/rad", 2.5e6),
    ("250 kN m/rad", "N*m/rad", 2.5e5),
    ("3 kg*cm^2", "kg*m^2", 3e-4),
    ("100 g*mm", "kg*m", 1e-4),
    ("7.85 g/cm^3", "kg/m^3", 7850.0),
    ("1 kN/mm", "N/m", 1e6),
    ("5 %", "1", 0.05),
    ("20 ms", "s", 0.02),
    ("2 min", "s", 120.0),
    ("720 rpm", "rpm", 720.0),
    ("12 Hz", "rpm", 720.0),              # 12 revolutions per second
    ("720 1/min", "rpm", 720.0),
    ("1500 rpm", "Hz", 25.0),
    ("50 Hz", "rad/s", 2 * math.pi * 50),
    ("720 rpm", "rad/s", 720 * math.pi / 30),
    ("0.5 pi*rad", "deg", 90.0),
    ("2 kHz", "Hz", 2000.0),
])
def test_quantity_strings_convert_to_the_key_unit(text, unit, expected):
    assert to_unit(text, unit) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("text, unit, message", [
    ("81", "Pa", "'81' has no unit: write a plain number (in Pa)"),
    ("81 mm", "Pa", "'81 mm' has the wrong dimension; expected a quantity in Pa"),
    ("43 mmm", "m", "'43 mmm': unknown unit"),
    ("2 rpm", "deg", "'2 rpm' has the wrong dimension; expected a quantity in deg"),
    ("90 deg", "1", "'90 deg' has the wrong dimension; expected a dimensionless number"),
    ("2.5e5 N*m", "N*m/rad", "has the wrong dimension; expected a quantity in N·m/rad"),
])
def test_bad_quantity_strings_name_the_expected_unit(text, unit, message):
    with pytest.raises(UnitError) as info:
        to_unit(text, unit)
    assert message in str(info.value)


@pytest.mark.parametrize("value, unit, plausible, meant", [
    (81.0, "Pa", (1e9, 3e11), "81 GPa"),          # shear_modulus, GPa meant
    (260.0, "m", (1e-3, 3.0), "260 mm"),           # diameter, mm meant
    (22.0, "Pa", (1e4, 1e7), "22 bar"),            # imep, bar meant
    (211.0, "Pa", (1e9, 1e12), "211 GPa"),         # Young's modulus
    (7.85, "kg/m^3", (300.0, 25000.0), "7.85 g/cm³"),
    (720.0, "Hz", (0.1, 1e3), "720 rpm"),          # a speed written into a frequency key
])
def test_slip_message_names_the_unit_probably_meant(value, unit, plausible, meant):
    assert f": did you mean {meant}?" in slip_message(value, unit, plausible)


def test_absurd_value_warns_without_a_made_up_unit():
    """1e-7 m is no slip of 1e-7 km: no suggestion at the edge of the range."""
    text = slip_message(1e-7, "m", (1e-4, 100.0))
    assert "did you mean" not in text and "outside the plausible range" in text


def _table(**data):
    return Table(data, source="model.toml", prefix="shaftline")


def test_table_reads_numbers_and_quantities_alike():
    t = _table(diameter="300 mm", shear_modulus=80e9, speed_range_rpm=["200 rpm", "13.333333 Hz"])
    assert t.positive("diameter", unit="m") == pytest.approx(0.3)
    assert t.positive("shear_modulus", unit="Pa") == 80e9
    assert t.numbers("speed_range_rpm", unit="rpm") == pytest.approx([200.0, 800.0], rel=1e-6)


def test_table_messages_name_the_expected_unit():
    t = _table(stiffness=True, inertia=[1, 2], bore="-5 mm")
    with pytest.raises(ModelError, match=r"model\.toml: shaftline\.stiffness = True must be a "
                                         r"number in N·m/rad \(or a string with its unit"):
        t.positive("stiffness", unit="N*m/rad")
    with pytest.raises(ModelError, match=r"shaftline\.inertia = \[1, 2\] must be a number in "
                                         r"kg·m²"):
        t.positive("inertia", unit="kg*m^2")
    with pytest.raises(ModelError, match=r"shaftline\.bore = -0\.005 must be >= 0 m"):
        t.number("bore", unit="m", low=0.0)


def test_table_warns_once_for_a_slip_and_not_for_defaults_or_zero():
    t = _table(shear_modulus=81, damping=0.0)
    with pytest.warns(PlausibilityWarning, match=r"model\.toml: shaftline\.shear_modulus = 81 "
                                                 r"Pa: did you mean 81 GPa\?"):
        t.positive("shear_modulus", unit="Pa", plausible=(1e9, 3e11))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        t.number("damping", 0.0, unit="N*m*s/rad", plausible=(1e-6, 1e9))      # zero: fine
        t.positive("length", 1e-9, unit="m", plausible=(1e-3, 100.0))          # default
    with pytest.warns(PlausibilityWarning, match=r"shaftline\.orders\[1\] = 500: "):
        _table(orders=[2, 500]).numbers("orders", unit="1", plausible=(0.01, 100.0))


def _i4_line(folder: Path, replace: dict) -> Path:
    """The i4 sample shaft line (its engine beside it as ../engines/i4.toml), with the first
    occurrence of each ``old`` text replaced by ``new``."""
    (folder / "engines").mkdir(parents=True)
    (folder / "shaftlines").mkdir()
    (folder / "engines" / "i4.toml").write_text((ROOT / "sample_data/engines/i4.toml").read_text())
    text = (ROOT / "sample_data/shaftlines/i4.toml").read_text()
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new, 1)
    path = folder / "shaftlines" / "i4.toml"
    path.write_text(text)
    return path


def test_model_with_units_gives_the_same_frequencies_as_plain_si(tmp_path):
    """i4 shaft line: inertias, damping and the speed range written with units give the
    frequencies and ranges of the SI file (to rounding of the conversion factors)."""
    from crankbench.predict.torsion import from_toml

    base = from_toml(_i4_line(tmp_path / "si", {}))
    units = from_toml(_i4_line(tmp_path / "units", {
        "speed_range_rpm = [800, 6500]": 'speed_range_rpm = ["13.333333333333334 Hz", "6500 rpm"]',
        "inertia = 0.0025": 'inertia = "25 kg*cm^2"',
        "throw_inertia = 0.0022": 'throw_inertia = "2200 kg*mm^2"',
    }))
    np.testing.assert_allclose(units.natural_frequencies(), base.natural_frequencies(),
                               rtol=1e-12)
    lo, hi = units.operating["speed_range_rpm"]
    assert lo == pytest.approx(800.0, rel=1e-12) and hi == 6500.0


def test_issue_cases_warn_on_load():
    """shear_modulus = 81 (GPa meant) gave modes at 0.00025 Hz and diameter = 260 (mm meant)
    stresses 1e9 too small, silently; both now warn naming the unit meant."""
    from crankbench.predict.torsion import from_toml

    corpus = ROOT / "tests/corpus/bad/models"
    for name, meant in (("shaftline_shear_modulus_in_gpa_slip", "81 GPa"),
                        ("shaftline_diameter_in_mm_slip", "55 mm")):
        with pytest.warns(PlausibilityWarning, match=f"did you mean {meant}"):
            from_toml(corpus / f"{name}.toml")


def test_every_sample_model_is_plausible():
    """No sample model trips a plausibility range (the ranges are not too tight)."""
    import tomllib

    from crankbench.measure.synth.scene import Scene
    from crankbench.predict.engine import Engine
    from crankbench.predict.lateral import load_rotor
    from crankbench.predict.mounts import MountedEngine
    from crankbench.predict.torsion import from_toml

    data = ROOT / "sample_data"
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        for p in sorted((data / "engines").glob("*.toml")):
            Engine.from_toml(p)
            if "mounts" in tomllib.loads(p.read_text()):
                MountedEngine.from_toml(p)
        for p in sorted((data / "shaftlines").glob("*.toml")):
            from_toml(p)
        for p in sorted((data / "rotors").glob("*.toml")):
            load_rotor(p)
        for p in sorted((data / "scenes").glob("*.toml")):
            Scene.from_toml(p)


_ACCESSORS = {"number", "positive", "numbers"}


def test_every_quantity_accessor_call_names_its_unit():
    """Every ``Table.number/positive/numbers`` call in the package passes ``unit=`` (or a
    ``**`` dict carrying it): a key without a unit can neither take "260 mm" nor say what
    it expects. (``unit=None`` is allowed where the unit depends on the data, e.g. noise in
    channel units.)"""
    missing = []
    for folder in ("predict", "measure", "analysis"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path.name == "_toml.py":
                continue
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                        and node.func.attr in _ACCESSORS and node.args
                        and isinstance(node.args[0], (ast.Constant, ast.Name, ast.JoinedStr))):
                    kw = {k.arg for k in node.keywords}
                    if "unit" not in kw and None not in kw:
                        missing.append(f"{path.relative_to(ROOT)}:{node.lineno} "
                                       f"{ast.unparse(node)[:70]}")
    assert not missing, "quantity accessors without unit=:\n" + "\n".join(missing)
