"""Scene files and operating profiles of the synthetic bench."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from crankbench.measure.synth import Scene
from crankbench.measure.synth.imperfections import Imperfections, degrade_edges, tooth_angles
from crankbench.measure.synth.profile import exponential_coastdown, from_table, ramp, steady
from crankbench.predict.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "sample_data/scenes"
TWO_PI = 2 * np.pi


def test_profile_angle_is_exact_integral_and_inverts():
    """Angle = integral of the piecewise-linear speed (checked by quad); time_at_angle inverts
    it to round-off, also beyond the table ends."""
    p = from_table([0, 2, 5, 9], [600, 600, 1500, 900])
    for t in (0.7, 2.0, 3.3, 8.9):
        ref, _ = quad(lambda s: float(p.speed(s)), 0, t, points=[2, 5], epsabs=1e-12)
        assert float(p.angle(t)) == pytest.approx(ref, rel=1e-12)
    t = np.linspace(-0.5, 10.0, 997)
    np.testing.assert_allclose(p.time_at_angle(p.angle(t)), t, atol=1e-10)
    assert p.max_sweep_rate() == pytest.approx(300.0)
    assert ramp(800, 400, duration=4).kind == "coastdown"
    assert steady(1000, duration=1).kind == "steady"


def test_exponential_coastdown_within_tolerance():
    p = exponential_coastdown(1500.0, 500.0, time_constant=8.0, tolerance_rpm=0.2)
    t = np.linspace(0, p.duration, 2001)
    exact = 1500.0 * np.exp(-t / 8.0)
    assert np.max(np.abs(p.speed(t) * 60 / TWO_PI - exact)) <= 0.2 + 1e-9


def test_sample_scenes_load():
    marine = Scene.from_toml(SCENES / "marine_6l_runup.toml")
    assert marine.profile.kind == "runup" and marine.shaftline is not None
    assert marine.mounts is not None  # from the engine file's [mounts]
    kinds = {s.kind for s in marine.sensors}
    assert {"torsiograph", "encoder", "tacho", "vibrograph"} <= kinds
    i4 = Scene.from_toml(SCENES / "i4_runup.toml")
    assert i4.engine.n_cylinders == 4


def _write(tmp_path, text):
    (tmp_path / "engines").mkdir(exist_ok=True)
    src = ROOT / "sample_data/engines/i4.toml"
    (tmp_path / "engines/i4.toml").write_text(src.read_text())
    p = tmp_path / "scene.toml"
    p.write_text(text)
    return p


BASE = """
[scene]
name = "t"
engine = "engines/i4.toml"
[profile]
kind = "steady"
speed_rpm = 3000.0
duration = 1.0
[[sensor]]
kind = "vibrograph"
name = "acc"
mount = "engine side"
sample_rate = 4000.0
"""


def test_scene_errors_name_file_and_key(tmp_path):
    ok = Scene.from_toml(_write(tmp_path, BASE))
    assert ok.sensors[0].params["direction"] == "z"
    with pytest.raises(ConfigError, match=r"scene.toml: sensor\[0\].smaple_rate is not a known key "
                                          r"\(did you mean 'sample_rate'\?\)"):
        Scene.from_toml(_write(tmp_path, BASE.replace("sample_rate = 4000.0",
                                                      "sample_rate = 4000.0\nsmaple_rate = 1")))
    with pytest.raises(ConfigError, match=r"profile.kind = 'stedy' is not one of .*did you mean "
                                          r"'steady'"):
        Scene.from_toml(_write(tmp_path, BASE.replace('kind = "steady"', 'kind = "stedy"')))
    with pytest.raises(ConfigError, match="need a shaft line"):
        Scene.from_toml(_write(tmp_path, BASE + '[[sensor]]\nkind = "encoder"\nname = "enc"\n'
                                                'node = "flywheel"\npulses_per_rev = 60\n'))
    with pytest.raises(FileNotFoundError, match="scene.engine = 'engines/none.toml'"):
        Scene.from_toml(_write(tmp_path, BASE.replace("engines/i4.toml", "engines/none.toml")))
    with pytest.raises(ConfigError, match="end_rpm = 500 must be above start_rpm = 900"):
        Scene.from_toml(_write(tmp_path, BASE.replace(
            'kind = "steady"\nspeed_rpm = 3000.0\nduration = 1.0',
            'kind = "runup"\nstart_rpm = 900.0\nend_rpm = 500.0\nduration = 1.0')))
    with pytest.raises(ConfigError, match="sensor names must be unique, repeated: acc"):
        Scene.from_toml(_write(tmp_path, BASE + BASE[BASE.index("[[sensor]]"):]))
    with pytest.raises(ConfigError, match=r"dropout_rate=0.9 must lie in \[0, 0.5\]"):
        Scene.from_toml(_write(tmp_path, BASE + "dropout_rate = 0.9\n"))


def test_tooth_angles_and_edge_degradation_statistics():
    rng = np.random.default_rng(1)
    ang = tooth_angles(360, Imperfections(tooth_error_deg=0.05), rng)
    err = np.degrees(ang - np.arange(360) * TWO_PI / 360)
    assert err[0] == 0 and 0.04 < err[1:].std() < 0.06
    edges = np.arange(100_000) * 1e-3
    out = degrade_edges(edges, Imperfections(dropout_rate=0.01, timer_resolution_s=1e-6,
                                             spurious_rate=0.002), rng)
    assert abs((edges.size - out.size) / edges.size - (0.01 - 0.002)) < 0.002
    assert np.all(np.abs(out / 1e-6 - np.round(out / 1e-6)) < 1e-6)   # whole ticks
