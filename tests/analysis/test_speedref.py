"""Speed reference from a speed channel on another clock or from a pulse train."""

import numpy as np
import pytest
import xarray as xr

from crankbench.analysis.speedref import find_speed_channel, speed_reference
from crankbench.predict.errors import AnalysisError, RecordError


def _record_with_pulses(ppr=60, missing=0, fs=5000.0, duration=4.0):
    # run-up at constant angular acceleration: θ(t) = ω0 t + α t²/2 (edge times in closed form)
    omega0, alpha = 2 * np.pi * 1000 / 60, 2 * np.pi * 500 / 60        # rpm 1000 + 500 t
    theta = np.arange(1, int((omega0 * duration + alpha * duration ** 2 / 2) / (2 * np.pi / ppr)))
    theta = theta * (2 * np.pi / ppr)
    edges = (-omega0 + np.sqrt(omega0 ** 2 + 2 * alpha * theta)) / alpha
    if missing:
        keep = np.mod(np.arange(edges.size), ppr) < ppr - missing
        edges = edges[keep]
    t = np.arange(int(duration * fs)) / fs
    return xr.Dataset(
        {"acc": ("time", np.zeros(t.size), {"units": "m/s^2", "quantity": "acceleration",
                                             "sample_rate": fs}),
         "tacho": ("pulse", edges, {"units": "s", "quantity": "pulse_times",
                                    "pulses_per_rev": ppr, "missing_teeth": missing})},
        coords={"time": t}), 1000 + 500 * t


@pytest.mark.parametrize("missing", [0, 2])
def test_pulses_give_the_run_up_speed(missing):
    """Closed-form truth: speed 1000 + 500 t rpm from edge times of constant acceleration."""
    rec, truth = _record_with_pulses(missing=missing)
    rpm = speed_reference(rec, "acc")
    inner = slice(1000, -1000)      # the one-revolution window leaves the ends held constant
    assert np.abs(rpm[inner] - truth[inner]).max() < 1e-3


def test_speed_channel_on_other_clock_is_interpolated():
    t = np.arange(1000) / 1000.0
    ts = np.arange(0, 1.0001, 0.01)
    rec = xr.Dataset(
        {"x": ("time", np.zeros(t.size), {"units": "m", "sample_rate": 1000.0}),
         "speed": ("time_slow", 2 * np.pi * (20 + 10 * ts), {"units": "rad/s",
                                                             "quantity": "rotational_speed"})},
        coords={"time": t, "time_slow": ts})
    assert find_speed_channel(rec, "x") == "speed"
    assert np.allclose(speed_reference(rec, "x"), 60 * (20 + 10 * t), rtol=1e-12)


def test_errors():
    rec = xr.Dataset({"x": ("time", np.zeros(10), {"units": "m"})}, coords={"time": np.arange(10.0)})
    with pytest.raises(AnalysisError, match="record has no speed reference"):
        speed_reference(rec, "x")
    with pytest.raises(RecordError, match="record has no channel 'y'"):
        speed_reference(rec, "y")
    rec["n"] = ("time", np.zeros(10), {"units": "rad/s", "quantity": "rotational_speed"})
    with pytest.raises(AnalysisError, match="needs the shaft turning"):
        speed_reference(rec, "x")
