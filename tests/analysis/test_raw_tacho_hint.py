"""A raw tacho voltage without a map: the refusal names the channel and the map lines that
decode it, and those lines, as written, give the true order amplitude."""

import numpy as np
import pytest

from crankbench.analysis import order_track
from crankbench.analysis.speedref import find_speed_channel, speed_reference
from crankbench.measure import read
from crankbench.predict.errors import AnalysisError


def _rig(tmp_path):
    fs = 20_000.0
    t = np.arange(int(3 * fs)) / fs
    rpm = 1200 + 100 * t
    phi = np.cumsum(rpm / 60 * 2 * np.pi / fs)
    rng = np.random.default_rng(1)
    acc = 0.5 * np.sin(2 * phi) + 0.01 * rng.standard_normal(t.size)
    tacho = np.where(phi % (2 * np.pi) < 0.2, 5.0, 0.0) + 0.05 * rng.standard_normal(t.size)
    path = tmp_path / "tacho.csv"
    path.write_text("time [s],tacho [V],acc [m/s^2]\n" + "".join(
        f"{a:.6f},{b:.4f},{c:.5f}\n" for a, b, c in zip(t, tacho, acc)))
    return path


def test_raw_tacho_refusal_gives_map_lines_that_work(tmp_path):
    path = _rig(tmp_path)
    rec = read(path)
    with pytest.raises(AnalysisError) as err:
        find_speed_channel(rec, "acc")
    text = str(err.value)
    assert "Channel 'tacho' looks like a raw pulse signal" in text
    lines = [ln.split("#")[0].rstrip() for ln in text.splitlines()[1:]
             if not ln.strip().startswith("(")]
    toml = "\n".join(ln.strip() for ln in lines).replace(
        "<teeth, or 1 for a once-per-revolution mark>", "1")
    (tmp_path / "map.toml").write_text(toml + "\n")
    mapped = read(path, map=tmp_path / "map.toml")
    rpm = speed_reference(mapped, "acc")
    tr = order_track(mapped["acc"], speed_rpm=rpm, orders=[2])
    amp = tr["amplitude"].sel(order=2).values
    inner = amp[len(amp) // 5: -len(amp) // 5]
    assert np.nanmax(np.abs(inner / 0.5 - 1)) < 0.01


def test_a_noisy_analog_channel_is_not_called_a_pulse_signal(tmp_path):
    path = tmp_path / "v.csv"
    t = np.arange(4000) / 1000.0
    path.write_text("time [s],sensor [V]\n" + "".join(
        f"{a:.4f},{np.sin(7 * a):.5f}\n" for a in t))
    with pytest.raises(AnalysisError) as err:
        find_speed_channel(read(path), None)
    assert "raw pulse" not in str(err.value)
