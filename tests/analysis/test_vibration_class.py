"""ISO 10816-6 class choice in the pipeline: rated power from the model, rigid or resilient
mounting from the model, and the basis text saying which power and mounting were used."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

from crankbench.analysis.pipeline_limits import _engine_power_and_mounting, _severity_checks
from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError

ROOT = Path(__file__).resolve().parents[2]


def _record(rms_mm_s=2.0, fs=2000.0):
    """A vibrograph velocity channel: a 40 Hz sine of the given rms (no speed channel)."""
    t = np.arange(int(2 * fs)) / fs
    v = rms_mm_s * 1e-3 * np.sqrt(2) * np.sin(2 * np.pi * 40.0 * t)
    return xr.Dataset({"vib": ("time", v, {"quantity": "velocity", "sample_rate": fs})})


def _vib(**kw):
    base = {"standard": "ISO 10816-6", "machine_class": None, "boundaries_mm_s": None,
            "source": "model [limits.vibration]", "rated_power_kw": None, "mounting": None}
    base.update(kw)
    return base


@pytest.mark.parametrize("rated_rpm, expected", [(500.0, "2"), (1000.0, "3")])
def test_rigid_mounting_from_the_model_key(rated_rpm, expected):
    """mounting = "rigid" reaches the rigid classes (2 up to 600 rpm, else 3) — never chosen
    before, when only an engine's [mounts] could decide."""
    system = SimpleNamespace(engine=SimpleNamespace(rated_speed_rpm=rated_rpm, source=None),
                             limits=SimpleNamespace(vibration=_vib(rated_power_kw=1200.0,
                                                                   mounting="rigid")))
    check = _severity_checks(_record(), system, None, None)[0]
    assert check.status == "pass"
    assert f"class {expected}: rigidly mounted" in check.source
    assert "rated power 1200 kW from [limits.vibration] rated_power_kw" in check.basis
    assert "rigid mounting from [limits.vibration] mounting" in check.basis


def test_mounts_in_engine_model_mean_resilient_and_indicated_power_is_said_so():
    """marine_6l.toml has [mounts] and no rated power: resilient (class 5 at 720 rpm) and the
    indicated power P_i = p_mi V_d n/120 = 2.7e6 · (π/4 · 0.32² · 0.4 · 6) · 720/120
    = 3126.9 kW, named as indicated, not rated."""
    engine = Engine.from_toml(ROOT / "sample_data/engines/marine_6l.toml")
    why = _engine_power_and_mounting(SimpleNamespace(engine=engine), {})
    assert why["resilient"] is True and "engine model has [mounts]" in why["mounting_note"]
    assert why["power_w"] == pytest.approx(2.7e6 * np.pi / 4 * 0.32**2 * 0.4 * 6 * 720 / 120,
                                           rel=1e-12)
    assert why["power_note"].startswith("indicated power 3127 kW at the rated 720 rpm")
    assert "rated_power_kw" in why["power_note"]
    system = SimpleNamespace(engine=engine, limits=SimpleNamespace(vibration=None))
    check = _severity_checks(_record(), system, None, None)[0]
    assert "class 5: resiliently mounted" in check.source and "indicated power" in check.basis


def test_rated_power_key_wins_over_indicated_and_mounting_key_over_mounts():
    engine = Engine.from_toml(ROOT / "sample_data/engines/marine_6l.toml")
    why = _engine_power_and_mounting(SimpleNamespace(engine=engine),
                                     _vib(rated_power_kw=2880.0, mounting="rigid"))
    assert why["power_w"] == 2.88e6 and why["resilient"] is False
    assert why["power_note"].startswith("rated power 2880 kW")


def test_unknown_mounting_is_not_assessed_with_the_key_to_give():
    """i6.toml has no [mounts] and no key: no class, inconclusive, naming the model key."""
    engine = Engine.from_toml(ROOT / "sample_data/engines/i6.toml")
    system = SimpleNamespace(engine=engine, limits=SimpleNamespace(vibration=None))
    check = _severity_checks(_record(), system, None, None)[0]
    assert check.status == "inconclusive"
    assert "mounting" in check.detail and '[limits.vibration] mounting = "rigid"' in check.detail


def test_limits_vibration_keys_from_toml(tmp_path):
    from crankbench.predict.torsion import from_toml

    s = from_toml(ROOT / "sample_data/shaftlines/marine_6l.toml")
    assert s.limits.vibration["rated_power_kw"] == 3000.0
    assert s.limits.vibration["mounting"] == "resilient"
    why = _engine_power_and_mounting(s, s.limits.vibration)
    assert why["power_note"].startswith("rated power 3000 kW from [limits.vibration]")
    text = (ROOT / "sample_data/shaftlines/marine_6l.toml").read_text().replace(
        'engine = "../engines/marine_6l.toml"',
        f'engine = "{ROOT / "sample_data/engines/marine_6l.toml"}"')
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('mounting = "resilient"', 'mounting = "springs"'))
    with pytest.raises(ModelError, match="mounting"):
        from_toml(bad)


def test_calculated_stress_gets_the_rule_barred_extent():
    """predicted=True: a calculated exceedance 350–370 rpm around a 360 rpm critical (n_0 =
    720, λ_c = 0.5) is barred over the rule's 16·360/17.5 = 329.1 to 17.5·360/16 = 393.75 rpm;
    measured stress keeps its measured range."""
    from crankbench.analysis.torsional_limits import check_torsional_stress
    from crankbench.predict.torsion.rules import MakerLimit, RuleLimits

    lim = RuleLimits(rated_speed_rpm=720.0, crankshaft=MakerLimit(("crank",), 42e6, 105e6))
    speed = np.linspace(200.0, 760.0, 561)
    tau = 20e6 + 40e6 * np.exp(-((speed - 360.0) / 14.0) ** 2)
    _, measured = check_torsional_stress(speed, tau, lim, section="crank")
    _, calc = check_torsional_stress(speed, tau, lim, section="crank", predicted=True)
    assert "barred 349–371 rpm" in measured.detail
    assert "barred 329–394 rpm" in calc.detail and "16 n_c/(18 − λ_c)" in calc.source
    assert calc.status == "pass"      # below λ = 0.8 (576 rpm)
