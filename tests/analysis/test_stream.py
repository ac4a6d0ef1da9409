"""Streamed order tracking (analysis.stream) against the in-memory functions on the same record.

The reference is a second, independent path: :func:`analysis.order_track` /
:func:`analysis.order_map` on the record read whole (``measure.read``), with the speed from
:func:`analysis.speedref.speed_reference`; the streamed path reads the record lazily
(``measure.open``) segment by segment. Closed-form truth: the synthesised order amplitudes and
phases of a run-up whose shaft angle is integrated from the record start.
"""

import numpy as np
import pytest

from crankbench import measure
from crankbench.analysis.orders import order_map, order_track
from crankbench.analysis.resample import shaft_angle
from crankbench.analysis.speedref import speed_reference
from crankbench.analysis.stream import order_map_stream, order_track_stream
from crankbench.measure.record import make_record
from crankbench.predict.errors import AnalysisError, RecordError

FS = 2000.0


@pytest.fixture(scope="module")
def runup(tmp_path_factory):
    """400 s run-up 300 -> 2700 rpm at 2 kHz (800 000 samples: several resampling chunks, one
    split for the 2:1 speed rule) with a 100 Hz rotational_speed channel, written to .h5."""
    T = 400.0
    n = int(T * FS)
    t = np.arange(n) / FS
    rpm = 300.0 + 6.0 * t
    phi = shaft_angle(rpm, FS)
    x = (1.3 * np.cos(2 * phi + 0.4) + 0.2 * np.cos(0.5 * phi - 1.0)
         + 0.01 * np.random.default_rng(0).standard_normal(n))
    ts = np.arange(int(T * 100) + 1) / 100.0
    rec = make_record({"acc": dict(data=x, sample_rate=FS, units="m/s^2"),
                       "n": dict(data=(300.0 + 6.0 * ts) * 2 * np.pi / 60, sample_rate=100.0,
                                 units="rad/s", quantity="rotational_speed")})
    path = tmp_path_factory.mktemp("stream") / "runup.h5"
    measure.write(rec, path)
    full = measure.read(path)
    return path, full, speed_reference(full, "acc")


def test_cot_stream_equals_in_memory(runup):
    """Every block of the streamed COT equals the in-memory one (1e-9 relative), and the phase
    is referred to the shaft angle from the record start across segments (truth 0.4, -1.0)."""
    path, full, rpm = runup
    ref = order_track(full["acc"], speed_rpm=rpm, orders=[0.5, 2], revolutions=8)
    lazy = measure.open(path, chunk_seconds=10.0)
    res = order_track_stream(lazy, "acc", orders=[0.5, 2], revolutions=8, segment_seconds=30.0)
    assert res.sizes == ref.sizes
    np.testing.assert_allclose(res.time, ref.time, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.rpm, ref.rpm, rtol=1e-9)
    np.testing.assert_allclose(res.amplitude, ref.amplitude, rtol=1e-9)
    np.testing.assert_allclose(res.phase, ref.phase, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.amplitude_noise, ref.amplitude_noise, rtol=1e-9)
    assert np.all(np.diff(res.time.values) > 0)          # each output time once
    assert np.abs(res.amplitude.sel(order=2) / 1.3 - 1).max() < 5e-3
    assert np.abs(res.phase.sel(order=2) - 0.4).max() < 5e-3
    assert np.abs(res.phase.sel(order=0.5) + 1.0).max() < 5e-2


def test_order_map_stream_equals_in_memory(runup):
    path, full, rpm = runup
    ref = order_map(full["acc"], speed_rpm=rpm, revolutions=8, scaling="power")
    res = order_map_stream(measure.open(path), "acc", revolutions=8, scaling="power",
                           segment_seconds=50.0)
    assert res.dims == ref.dims and res.shape == ref.shape
    np.testing.assert_allclose(res.values, ref.values, rtol=1e-9, atol=1e-12 * ref.values.max())
    np.testing.assert_allclose(res.order, ref.order)


def test_vkf_stream_matches_in_memory_interior():
    """VKF per overlapping segment: the complex envelope (amplitude and phase from the record
    start) agrees with the whole-record solve to 1e-4 relative away from the record ends."""
    fs, T = 1000.0, 60.0
    n = int(T * fs)
    rpm = 600.0 + 20.0 * np.arange(n) / fs
    phi = shaft_angle(rpm, fs)
    x = 1.3 * np.cos(2 * phi + 0.4) + 0.2 * np.cos(0.5 * phi)
    rec = make_record({"acc": dict(data=x, sample_rate=fs, units="m/s^2")})
    ref = order_track(rec["acc"], speed_rpm=rpm, orders=[0.5, 2], method="vkf", bandwidth_hz=2.0)
    res = order_track_stream(rec.chunk({"time": 5000}), "acc", speed_rpm=rpm, orders=[0.5, 2],
                             method="vkf", bandwidth_hz=2.0, segment_seconds=10.0)
    assert np.all(np.diff(res.time.values) > 0)
    e0 = ref.amplitude.values * np.exp(1j * ref.phase.values)
    e1 = res.amplitude.values * np.exp(1j * res.phase.values)
    tq = ref.time.values
    e1 = np.array([np.interp(tq, res.time.values, z.real) + 1j * np.interp(tq, res.time.values,
                                                                            z.imag) for z in e1])
    inner = (tq > 5.0) & (tq < T - 5.0)
    err = np.abs(e1 - e0)[:, inner] / np.abs(e0)[:, inner]
    assert err.max() < 1e-4
    assert np.abs(np.angle(e1[1, inner]) - 0.4).max() < 1e-4


def test_errors_name_channel():
    rec = make_record({"acc": dict(data=np.zeros(4000), sample_rate=1000.0, units="m/s^2")})
    with pytest.raises(RecordError, match="acx"):
        order_track_stream(rec, "acx", orders=[1], speed_rpm=1200.0)
    with pytest.raises(AnalysisError, match="samples_per_rev"):
        order_track_stream(rec, "acc", orders=[20], speed_rpm=1200.0)
    with pytest.raises(AnalysisError, match="rpm has 3 samples"):
        order_track_stream(rec, "acc", orders=[1], speed_rpm=[1.0, 2.0, 3.0])


def test_analyse_command_streams_large_files(runup, monkeypatch, capsys, tmp_path):
    """``crankbench analyse`` on a file above the streaming threshold gives the same JSON as the
    in-memory path (threshold lowered so the small test record streams), and writes the plots."""
    import json

    from crankbench.analysis.cli import main
    from crankbench.analysis.commands import analyse

    path = runup[0]
    args = ["analyse", str(path), "--channel", "acc", "--orders", "0.5,2", "--revolutions", "8",
            "--json"]
    assert main(args) == 0
    whole = json.loads(capsys.readouterr().out)
    monkeypatch.setattr(analyse, "STREAM_BYTES", 0)
    assert main(args + ["--plot", str(tmp_path / "p")]) == 0
    streamed = json.loads(capsys.readouterr().out)
    assert streamed["parameters"]["streamed_segment_seconds"] > 0
    for a, b in zip(whole["summary"], streamed["summary"]):
        assert a["order"] == b["order"]
        assert b["max_amplitude"] == pytest.approx(a["max_amplitude"], rel=1e-9)
        assert b["mean_amplitude"] == pytest.approx(a["mean_amplitude"], rel=1e-9)
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == [
        "campbell.png", "order_map.png", "order_tracks.png"]


def test_order_above_nyquist_refused_before_reading():
    rec = make_record({"acc": dict(data=np.zeros(8000), sample_rate=200.0, units="m/s^2")})
    with pytest.raises(AnalysisError, match="Nyquist"):
        order_track_stream(rec, "acc", orders=[8], speed_rpm=1200.0)      # 160 Hz > 100 Hz
