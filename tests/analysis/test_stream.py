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
        order_track_stream(rec, "acc", orders=[20], speed_rpm=1200.0, samples_per_rev=64)
    with pytest.raises(AnalysisError, match="duplicates"):
        order_track_stream(rec, "acc", orders=[2, 2], speed_rpm=1200.0)
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


def test_streamed_angle_samples_are_the_in_memory_ones_bit_for_bit(runup):
    """One resampling engine (issue 22): the streamed path feeds segments to
    analysis.resample.resample_span with the shaft angle carried across them, so every angle
    sample, its time and speed equal the in-memory resampling exactly (not just to rounding)."""
    from crankbench.analysis.resample import resample_arrays
    from crankbench.analysis.stream import SpanSpeed, _angle_samples, _reader

    path, full, rpm = runup
    x = np.asarray(full["acc"].values, float)
    y, t, r, ang, _ = resample_arrays(x, FS, np.asarray(rpm.values, float))
    speed = SpanSpeed(x.size, FS, 0.0, speed_rpm=np.asarray(rpm.values, float))
    lazy = measure.open(path, chunk_seconds=10.0)
    parts = list(_angle_samples(_reader(lazy["acc"]), speed, samples_per_rev=64,
                                interpolation="auto", chunk=1 << 18, segment=60_000,
                                label="acc"))
    assert len(parts) > 3
    for got, want in zip((np.concatenate([p[i] for p in parts]) for i in range(4)),
                         (y, t, r, ang)):
        assert np.array_equal(got, want)


def test_stream_removes_a_speed_channels_mean_like_in_memory(tmp_path):
    """An IAS channel (mean speed 125-190 rad/s under 0.5 rad/s of order-1.5 vibration): the
    streamed and in-memory trackers both remove the mean speed (trend 'speed mean'), agree to
    1e-9, and read the vibration within 0.5 % of the truth (no mean leaking into orders)."""
    fs, T = 2000.0, 40.0
    t = np.arange(int(T * fs)) / fs
    rpm = 1200.0 + 15.0 * t
    phi = shaft_angle(rpm, fs)
    omega = rpm * 2 * np.pi / 60 + 0.5 * np.cos(1.5 * phi + 0.2) + 0.2 * np.cos(0.5 * phi)
    rec = make_record({"ias": dict(data=omega, sample_rate=fs, units="rad/s",
                                   quantity="angular_velocity")})
    path = tmp_path / "ias.h5"
    measure.write(rec, path)
    full = measure.read(path)
    ref = order_track(full["ias"], speed_rpm=rpm, orders=[0.5, 1.5], revolutions=8)
    res = order_track_stream(measure.open(path, chunk_seconds=5.0), "ias", speed_rpm=rpm,
                             orders=[0.5, 1.5], revolutions=8, segment_seconds=7.0)
    assert ref.attrs["trend_kind"] == res.attrs["trend_kind"] == "speed mean"
    np.testing.assert_allclose(res.amplitude, ref.amplitude, rtol=1e-9)
    np.testing.assert_allclose(res["mean"], ref["mean"], rtol=1e-9, atol=1e-9)
    inner = ((ref.time > 2) & (ref.time < T - 2)).values
    assert np.abs(ref.amplitude.sel(order=1.5).values[inner] / 0.5 - 1).max() < 5e-3
    assert np.abs(ref.amplitude.sel(order=0.5).values[inner] / 0.2 - 1).max() < 5e-3


def test_stream_with_a_pulse_train_equals_in_memory_and_refers_phases_to_tdc():
    """Issue 22 (one engine) with the angle from a 60-2 wheel that vibrates (3e-3 rad at order
    1.5 on its node): the streamed COT reads the same edge angle (its mean rotation, each span
    with its reach as margin) as speed_reference gives the in-memory path, so the tracks agree
    to 1e-9, and both refer the phases to TDC of cylinder 1 (truth: the phases written
    against the crank angle from TDC)."""
    import xarray as xr

    fs, T, ppr, tdc_deg = 2000.0, 24.0, 60, 84.0
    f0, rate = 10.0, 0.5                               # 600 -> 1320 rpm

    def theta(t):
        return 2 * np.pi * (f0 * t + 0.5 * rate * t * t)

    def vib(p):
        return 3e-3 * np.cos(1.5 * p + 0.3)

    k = np.arange(1, int(theta(T) / (2 * np.pi / ppr)) - 1)
    target = k * 2 * np.pi / ppr
    te = (-f0 + np.sqrt(f0 ** 2 + 2 * rate * target / (2 * np.pi))) / rate
    for _ in range(6):                                 # edges of the vibrating wheel
        p = theta(te)
        g = p + vib(p) - target
        te -= g / (2 * np.pi * (f0 + rate * te) * (1 - 4.5e-3 * np.sin(1.5 * p + 0.3)))
    te = te[np.mod(k, ppr) < ppr - 2]
    t = np.arange(int(T * fs)) / fs
    psi = theta(t) - np.radians(tdc_deg)
    truth = {1.5: (0.8, 20.0), 3.0: (0.4, -100.0)}
    x = sum(a * np.cos(o * psi + np.radians(p)) for o, (a, p) in truth.items())
    rec = xr.Dataset(
        {"acc": ("time", x, {"units": "m/s^2", "quantity": "acceleration", "sample_rate": fs}),
         "tacho": ("pulse", te, {"units": "s", "quantity": "pulse_times",
                                 "pulses_per_rev": ppr, "missing_teeth": 2,
                                 "tdc_offset_deg": tdc_deg})},
        coords={"time": t})
    n = speed_reference(rec, "acc")
    ref = order_track(rec["acc"], speed_rpm=n, orders=list(truth), method="cot", revolutions=8)
    res = order_track_stream(rec.chunk({"time": 4000}), "acc", orders=list(truth),
                             method="cot", revolutions=8, segment_seconds=3.0)
    assert "TDC of cylinder 1" in ref.attrs["phase_reference"]
    assert res.attrs["phase_reference"] == ref.attrs["phase_reference"]
    assert res.sizes == ref.sizes
    np.testing.assert_allclose(res.amplitude, ref.amplitude, rtol=1e-9)
    np.testing.assert_allclose(res.phase, ref.phase, rtol=0, atol=1e-9)
    # the same speed reference handed to the stream (its shaft_angle coordinate is used)
    res2 = order_track_stream(rec.chunk({"time": 4000}), "acc", speed_rpm=n,
                              orders=list(truth), method="cot", revolutions=8,
                              segment_seconds=3.0)
    assert res2.attrs["phase_reference"] == ref.attrs["phase_reference"]
    np.testing.assert_allclose(res2.phase, ref.phase, rtol=0, atol=1e-9)
    inner = ((ref.time > 2) & (ref.time < T - 2)).values
    for o, (a, p) in truth.items():
        assert np.abs(ref.amplitude.sel(order=o).values[inner] / a - 1).max() < 2e-3
        d = np.degrees(ref.phase.sel(order=o).values[inner]) - p
        # a once-per-revolution gap cannot tell which revolution of the cycle holds the firing
        # TDC: half orders are known to 180° (here the first gap is one revolution in)
        period = 180.0 if o % 1 else 360.0
        assert np.abs((d + period / 2) % period - period / 2).max() < 0.3
