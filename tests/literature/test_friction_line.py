"""The non-linear Lanchester friction damper from a model TOML, through the forced response
and ``crankbench predict torsion``.

Reference: time integration of the full non-linear hub + ring equations
(``predict.torsion.friction.time_domain_sdof``: exact stick/slip switching), the check the
single-order harmonic balance already meets (Den Hartog, *Mechanical Vibrations*, 4th ed.,
§8.6 for the ring's slip torque and energy per cycle).
"""

import json
from pathlib import Path

import numpy as np
import pytest

import crankbench.predict.torsion as pt
from crankbench.predict.errors import ModelError
from crankbench.predict.torsion.friction import time_domain_sdof

ROOT = Path(__file__).resolve().parents[2]

HUB = """
[shaftline]
name = "hub on a spring with a friction ring"

[[shaftline.mass]]
name = "hub"
inertia = 1.0
damping = 5.0

[[shaftline.ground]]
node = "hub"
stiffness = 1.0e5

[[shaftline.damper]]
type = "friction"
node = "hub"
ring_inertia = 0.25
slip_torque = {ts}
{extra}
"""


def _model(tmp_path, ts=30.0, extra=""):
    p = tmp_path / "hub.toml"
    p.write_text(HUB.format(ts=ts, extra=extra))
    return p


def test_friction_damper_from_toml_is_kept_non_linear(tmp_path):
    s = pt.from_toml(_model(tmp_path))
    assert len(s.friction_dampers) == 1 and s.friction_dampers[0].slip_torque == 30.0
    assert s.node_names == ("hub",)                    # the ring is no linear node
    np.testing.assert_allclose(s.natural_frequencies("rad/s"), [np.sqrt(1e5)], rtol=1e-12)


@pytest.mark.parametrize("ts", [10.0, 80.0])
def test_toml_model_forced_response_against_time_integration(tmp_path, ts):
    s = pt.from_toml(_model(tmp_path, ts)).replace(cylinder_nodes=[0], firing_angles_deg=[0.0])
    wn = np.sqrt(1e5)
    rpm = np.array([0.9, 1.0, 1.05]) * wn * 30 / np.pi
    r = s.forced_response(rpm, torque=[60.0], orders=[1.0])       # dispatches to the balance
    assert r.method.startswith("harmonic balance of the friction ring")
    hub = np.abs(r.angle[:, 0, 0])
    ref = [time_domain_sdof(inertia=1.0, stiffness=1e5, damping=5.0, ring_inertia=0.25,
                            slip_torque=ts, omega=w, torque=60.0, cycles=120,
                            steps_per_cycle=240) for w in rpm * np.pi / 30]
    np.testing.assert_allclose(hub, ref, rtol=0.05)
    # the ground spring carries k θ: section torque from the balanced hub angle
    np.testing.assert_allclose(np.abs(r.torque[:, 0, 0]), 1e5 * hub, rtol=1e-12)


def test_linearised_friction_damper_still_available(tmp_path):
    s = pt.from_toml(_model(tmp_path, extra="design_frequency = 316.0\n"
                                             "design_amplitude = 0.004"))
    assert not s.friction_dampers and "hub friction ring" in s.node_names


@pytest.mark.parametrize("extra, match", [
    ('model = "harmonic-balance"\ndesign_frequency = 316.0',
     "design_frequency belongs to model = \"linearised\""),
    ('model = "linearised"', 'model = "linearised" needs design_frequency'),
    ('model = "exact"', "model = 'exact' is not one of"),
])
def test_friction_damper_keys_are_checked(tmp_path, extra, match):
    with pytest.raises(ModelError, match=match):
        pt.from_toml(_model(tmp_path, extra=extra))


def test_predict_torsion_cli_reports_the_friction_damper(tmp_path, capsys):
    from crankbench.analysis.cli import main as cli_main

    engine = (ROOT / "sample_data/engines/i4.toml").as_posix()
    model = tmp_path / "i4_friction.toml"
    text = (ROOT / "sample_data/shaftlines/i4.toml").read_text()
    text = text.replace('engine = "../engines/i4.toml"', f'engine = "{engine}"')
    head, _, _ = text.partition("[[shaftline.damper]]")
    assert "[[shaftline.damper]]" in text
    model.write_text(head + '[[shaftline.damper]]\ntype = "friction"\nnode = "pulley hub"\n'
                            'ring_inertia = 0.004\nslip_torque = 15.0\n')
    assert cli_main(["predict", "torsion", str(model), "--json", "--speeds", "40",
                     "--max-order", "6"]) == 0
    out = json.loads(capsys.readouterr().out)
    fd = out["friction_damper"]
    assert fd["node"] == "pulley hub" and "resonances" not in out
    peaks = fd["peaks"]
    rows = peaks if isinstance(peaks, list) else peaks.get("data", peaks)
    assert len(rows) > 0
    assert out["worst_stresses"]
