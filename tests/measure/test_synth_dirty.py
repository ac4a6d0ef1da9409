"""The synthetic bench makes dirty records with ground truth: analogue pick-ups with a runt
tooth, ringing and noise, a narrow TDC mark, speed and angle channels with gain, DC offset and
drift. Each decodes (or reads) back to the truth the scene put in."""

import warnings
from pathlib import Path

import numpy as np
import pytest

from crankbench.measure import io
from crankbench.measure.synth import synthesize

ROOT = Path(__file__).resolve().parents[2]

SCENE = """
[scene]
name = "dirty I4 bench"
engine = "{root}/sample_data/engines/i4.toml"
shaftline = "{root}/sample_data/shaftlines/i4.toml"
seed = 3
max_order = 4.0

[profile]
kind = "runup"
start_rpm = 1500.0
end_rpm = 1800.0
duration = 1.2

[[sensor]]
kind = "tacho"
name = "crank_v"
node = "flywheel"
pulses_per_rev = 60
missing_teeth = 2
output = "analogue"
sample_rate = 100000.0
shape = "square"
runt_teeth = [57]
runt_level = 0.11
ringing = 0.3
noise_rms = 0.03

[[sensor]]
kind = "tacho"
name = "crank_true"
node = "flywheel"
pulses_per_rev = 60
missing_teeth = 2

[[sensor]]
kind = "tacho"
name = "tdc_v"
node = "flywheel"
pulses_per_rev = 1
output = "analogue"
sample_rate = 100000.0
shape = "square"
mark_width_deg = 1.0
noise_rms = 0.02

[[sensor]]
kind = "speed"
name = "ias"
sample_rate = 1000.0
offset = 3.0                 # rad/s of DC
drift_rate = 0.5             # rad/s per s
gain_error = 0.01

[[sensor]]
kind = "torsiograph"
name = "tv"
node = "pulley hub"
quantity = "angle"
sample_rate = 5000.0
offset = 0.002
drift_rate = 0.001
"""

MAP = """
[channel.crank]
column = "crank_v"
role = "wheel"
pulses_per_rev = 60
missing_teeth = 2

[channel.tdc]
column = "tdc_v"
role = "tdc"

[source]
keep_unmapped = true
"""


@pytest.fixture(scope="module")
def dirty(tmp_path_factory):
    folder = tmp_path_factory.mktemp("dirty")
    scene = folder / "scene.toml"
    scene.write_text(SCENE.format(root=ROOT.as_posix()))
    run = synthesize(scene)
    path = folder / "dirty.h5"
    io.write(run.record, path)
    (folder / "map.toml").write_text(MAP)
    return run, path, folder / "map.toml"


def test_runt_ringing_pickup_decodes_to_the_true_edges(dirty):
    run, path, cmap = dirty
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rec = io.read(path, map=cmap)
    truth = run.record["crank_true"].values
    decoded = rec["crank"].values
    assert rec["crank"].attrs["runt_teeth"] == [57]
    assert any("tooth 57" in str(w.message) for w in caught)
    # the ringing chain delays every edge alike (by a fraction of a pitch)
    j = np.searchsorted(truth, decoded - 2e-4)
    matched = truth[j]
    delay = decoded - matched
    assert np.ptp(delay) < 0.5e-5                     # within half a sample of one delay
    assert 0 < np.median(delay) < 1e-4
    inside = truth[(truth >= matched[0]) & (truth <= matched[-1])]
    assert decoded.size == inside.size                # no edge lost, none added


def test_narrow_tdc_mark_once_per_revolution(dirty):
    run, path, cmap = dirty
    rec = io.read(path, map=cmap)
    marks = rec["tdc"].values
    revs = (run.scene.profile.angle(marks[-1]) - run.scene.profile.angle(marks[0])) / (2 * np.pi)
    assert marks.size - 1 == round(revs)
    assert np.allclose(np.diff(run.scene.profile.angle(marks)), 2 * np.pi, atol=0.01)


def test_speed_and_angle_channels_carry_gain_offset_and_drift(dirty):
    run, _, _ = dirty
    rec = run.record
    t = rec["ias"]["time_ias"].values if "time_ias" in rec["ias"].dims else \
        rec["ias"][rec["ias"].dims[0]].values
    truth = run.scene.profile.speed(t)
    np.testing.assert_allclose(rec["ias"].values, 1.01 * truth + 3.0 + 0.5 * t, rtol=1e-12)
    tv = rec["tv"].values
    tt = rec["tv"][rec["tv"].dims[0]].values
    # the vibration is micro-radians; the DC and drift dominate the channel's mean
    assert np.mean(tv - (0.002 + 0.001 * tt)) == pytest.approx(0.0, abs=1e-4)
