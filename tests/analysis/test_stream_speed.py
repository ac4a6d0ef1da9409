"""Streamed trackers on dirty speed channels (issue 13): the same repairs as in memory.

A run-up from the synthetic bench's speed profile (:func:`measure.synth.profile.ramp`: exact
speed and crank angle) drives an accelerometer channel with known order amplitudes, and a
speed channel on the same 4 kHz clock carrying the shaft's torsional vibration (0.4 rad/s at
order 1.5) and noise — and counter glitches: a 65535 overflow spike, a 3-sample drop-out to 0,
a drop-out straddling a block boundary of the streamed reader and a spike exactly on one. Three
independent references: the in-memory path (:func:`analysis.speedref.speed_reference` +
:func:`analysis.order_track` on the record read whole), the tracker fed the profile's exact
speed, and the synthesised amplitudes.
"""

import logging

import numpy as np
import pytest

from crankbench import measure
from crankbench.analysis.orders import order_track
from crankbench.analysis.speedref import _repair_glitches, speed_reference
from crankbench.analysis.stream import _speed_for, order_track_stream
from crankbench.analysis import stream_speed
from crankbench.measure.record import make_record
from crankbench.measure.synth.profile import ramp
from crankbench.predict.errors import AnalysisError

FS, T, BLOCK = 4000.0, 8.0, 4096
A2, A45 = 0.5, 0.2
GLITCHES = {5000: 65535.0, 12000: 0.0, 12001: 0.0, 12002: 0.0,          # spike, drop-out
            3 * BLOCK - 1: 0.0, 3 * BLOCK: 0.0, 3 * BLOCK + 1: 0.0,       # across a block edge
            5 * BLOCK: 65535.0}                                           # on a block edge


def _bench(kind="dirty"):
    prof = ramp(1200.0, 2000.0, duration=T)
    t = np.arange(int(T * FS)) / FS
    theta = prof.angle(t)
    rng = np.random.default_rng(13)
    x = A2 * np.cos(2 * theta + 0.4) + A45 * np.cos(4.5 * theta - 1.0) \
        + 0.02 * rng.standard_normal(t.size)
    w = prof.speed(t) + 0.4 * np.cos(1.5 * theta) + 0.05 * rng.standard_normal(t.size)
    if kind in ("dirty", "negative"):
        for i, v in GLITCHES.items():
            w[i] = v
    if kind == "negative":
        w = -w
    if kind == "stop":                       # the shaft stands for 0.5 s (a real stop)
        w[(t > 5.0) & (t < 5.5)] = 0.0
        w[5000] = 65535.0
    if kind == "mixed":
        w = np.where(t < 4.0, w, -w)
    rec = make_record({"acc": dict(data=x, sample_rate=FS, units="m/s^2"),
                       "n": dict(data=w, sample_rate=FS, units="rad/s",
                                 quantity="rotational_speed")})
    return rec, prof.speed(t) * 60 / (2 * np.pi)


@pytest.fixture
def small_blocks(monkeypatch):
    monkeypatch.setattr(stream_speed, "BLOCK", BLOCK)


def _paths(rec, tmp_path):
    """(in-memory tracks, streamed tracks) of order 2 and 4.5 by COT, 8-revolution blocks."""
    path = tmp_path / "rec.h5"
    measure.write(rec, path)
    full = measure.read(path)
    mem = order_track(full["acc"], speed_rpm=speed_reference(full, "acc"), orders=[2, 4.5],
                      method="cot", revolutions=8)
    lazy = measure.open(path, chunk_seconds=1.0)
    res = order_track_stream(lazy, "acc", orders=[2, 4.5], method="cot", revolutions=8,
                             segment_seconds=1.5)
    return full, mem, res


def _warnings(caplog, text):
    return [r.getMessage() for r in caplog.records if text in r.getMessage()]


def test_glitch_repair_is_the_in_memory_one_for_any_block_size():
    """The streamed repair (median and glitch runs carried across blocks) gives the speed
    speedref._repair_glitches gives for the whole channel, whatever the block size — also for
    the drop-out straddling a block edge and the spike exactly on one."""
    rec, truth_rpm = _bench()
    w = rec["n"].values
    t = np.arange(w.size) / FS
    whole = _repair_glitches(t, w, "n") * 60 / (2 * np.pi)
    for block in (1024, BLOCK, 5000, 1 << 20):
        s = stream_speed.RepairedChannel(w, fs=FS, t0=0.0, ratio=1.0, source="n", block=block)
        assert s.glitches == len(GLITCHES)
        got = np.concatenate([s[a:a + 3333] for a in range(0, w.size, 3333)])
        np.testing.assert_allclose(got, whole, rtol=0, atol=1e-9)
    # the bridges are close to the true speed (the glitches were 65535 rad/s and 0)
    i = np.array(sorted(GLITCHES))
    assert np.abs(got[i] - truth_rpm[i]).max() < 10.0


def test_dirty_speed_channel_streamed_equals_in_memory_and_truth(tmp_path, small_blocks,
                                                                caplog):
    """Eight glitch samples bridged with the same warning on both paths; the streamed order
    amplitudes equal the in-memory ones (1e-9), and both equal the tracker fed the profile's
    exact speed within 1e-3 (the in-memory glitch test's tolerance) and the synthesised
    amplitudes within the 8-revolution COT's noise (2 % peak for order 4.5, 0.6 % order 2)."""
    rec, truth_rpm = _bench()
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        full, mem, res = _paths(rec, tmp_path)
    found = _warnings(caplog, "glitch sample(s)")
    assert len(found) == 2 and all(f"{len(GLITCHES)} glitch sample(s)" in m for m in found)
    assert found[0] == found[1]                               # same text on both paths
    exact = order_track(full["acc"], speed_rpm=truth_rpm, orders=[2, 4.5], method="cot",
                        revolutions=8)
    assert res.sizes == mem.sizes == exact.sizes
    np.testing.assert_allclose(res.amplitude, mem.amplitude, rtol=1e-9)
    np.testing.assert_allclose(res.phase, mem.phase, rtol=0, atol=1e-9)
    inner = ((res.time > 0.5) & (res.time < T - 0.5)).values
    assert np.abs(res.amplitude.values / exact.amplitude.values - 1)[:, inner].max() < 1e-3
    for order, amp, tol in ((2, A2, 6e-3), (4.5, A45, 2e-2)):
        err = res.amplitude.sel(order=order).values[inner] / amp - 1
        assert np.abs(err).max() < tol
        assert abs(err.mean()) < tol / 4                     # no bias from the glitches


def test_streamed_speed_is_cycle_averaged_like_in_memory(small_blocks):
    """A fast speed channel (120-200 samples a revolution) carries the shaft's vibration: the
    streamed speed is its cycle average, span by span across angle checkpoints, equal to
    speed_reference's to 1e-6 rpm, and within 1 rpm of the profile's exact speed away from
    the ends (the 0.4 rad/s = 3.8 rpm order-1.5 vibration averaged out)."""
    rec, truth_rpm = _bench()
    ref = speed_reference(rec, "acc").values
    speed = _speed_for(rec, "acc", rec["acc"], speed_rpm=None, speed_channel=None)
    assert isinstance(speed._rpm, stream_speed.CycleAveraged)
    got = np.concatenate([speed(a, min(speed.n, a + 2777)) for a in range(0, speed.n, 2777)])
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6)
    inner = slice(int(FS), -int(FS))
    assert np.abs(got[inner] - truth_rpm[inner]).max() < 1.0
    raw = rec["n"].values[inner] * 60 / (2 * np.pi)
    assert np.abs(np.delete(raw, [i - int(FS) for i in GLITCHES]) -
                  np.delete(truth_rpm[inner], [i - int(FS) for i in GLITCHES])).max() > 3.0


def test_speed_negative_throughout_streamed_by_its_magnitude(tmp_path, small_blocks, caplog):
    rec, _ = _bench("negative")
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        _, mem, res = _paths(rec, tmp_path)
    assert len(_warnings(caplog, "negative throughout")) == 2
    np.testing.assert_allclose(res.amplitude, mem.amplitude, rtol=1e-9)
    inner = ((res.time > 0.5) & (res.time < T - 0.5)).values
    assert np.abs(res.amplitude.sel(order=2).values[inner] / A2 - 1).max() < 6e-3
    mixed, _ = _bench("mixed")
    with pytest.raises(AnalysisError, match="turning one way"):
        order_track_stream(mixed, "acc", orders=[2])


def test_a_real_stop_is_kept_and_tracked_per_running_span(tmp_path, small_blocks):
    """0.5 s at 0 rpm: not bridged (a shaft can stop that slowly); both paths track the two
    running spans, with the same stopped span and the same amplitudes."""
    rec, _ = _bench("stop")
    speed = _speed_for(rec, "acc", rec["acc"], speed_rpm=None, speed_channel=None)
    stand = np.asarray(speed._rpm[int(5.05 * FS):int(5.45 * FS)])
    assert np.abs(stand).max() < 1e-9
    with pytest.warns(UserWarning, match="shaft stands"):
        _, mem, res = _paths(rec, tmp_path)
    assert res.attrs["stopped_spans_s"] == pytest.approx(mem.attrs["stopped_spans_s"])
    assert res.attrs["stopped_spans_s"] == pytest.approx([5.0 + 1 / FS, 5.5 - 1 / FS],
                                                         abs=1e-9)
    np.testing.assert_allclose(res.time, mem.time, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.amplitude, mem.amplitude, rtol=1e-9)


def test_analyse_command_streams_a_dirty_speed_channel(tmp_path, small_blocks, monkeypatch,
                                                       capsys):
    """``crankbench analyse`` above the streaming threshold (lowered so this record streams)
    gives the in-memory summary on the dirty record, and warns of the glitches."""
    import json

    from crankbench.analysis.cli import main
    from crankbench.analysis.commands import analyse

    rec, _ = _bench()
    path = tmp_path / "dirty.h5"
    measure.write(rec, path)
    args = ["analyse", str(path), "--channel", "acc", "--orders", "2,4.5", "--method", "cot",
            "--revolutions", "8", "--json"]
    assert main(args) == 0
    whole = json.loads(capsys.readouterr().out)
    monkeypatch.setattr(analyse, "STREAM_BYTES", 0)
    assert main(args) == 0
    out = capsys.readouterr()
    streamed = json.loads(out.out)
    assert streamed["parameters"]["streamed_segment_seconds"] > 0
    assert f"{len(GLITCHES)} glitch sample(s)" in out.err          # the CLI's log on stderr
    for a, b in zip(whole["summary"], streamed["summary"]):
        assert a["order"] == b["order"]
        assert b["max_amplitude"] == pytest.approx(a["max_amplitude"], rel=1e-9)
        assert b["mean_amplitude"] == pytest.approx(a["mean_amplitude"], rel=1e-9)


def _encoder_record(unwrapped=False):
    """The run-up with an encoder angle channel on the signal's clock, counting backwards and
    carrying 2e-3 rad of order-1.5 torsional vibration; wrapped to [0, 2π) unless
    ``unwrapped``."""
    prof = ramp(1200.0, 2000.0, duration=T)
    t = np.arange(int(T * FS)) / FS
    theta = prof.angle(t)
    x = A2 * np.cos(2 * theta + 0.4) + A45 * np.cos(4.5 * theta - 1.0) \
        + 0.02 * np.random.default_rng(5).standard_normal(t.size)
    enc = -(theta + 2e-3 * np.cos(1.5 * theta))
    return make_record({"acc": dict(data=x, sample_rate=FS, units="m/s^2"),
                        "enc": dict(data=enc if unwrapped else np.mod(enc, 2 * np.pi),
                                    sample_rate=FS, units="rad", quantity="angle",
                                    attrs={"tdc_offset_deg": 30.0})})


def test_encoder_angle_channel_streamed_as_in_memory(tmp_path, small_blocks):
    """A wrapped encoder angle (2π count carried across blocks) as the speed source: the
    streamed speed and mean-rotation angle equal speed_reference's (1e-6 rpm, 1e-9 rad), its
    zero is the encoder's moved by tdc_offset_deg, the tracks equal the in-memory ones, and
    order 2 is within the COT noise of the truth."""
    rec = _encoder_record()
    path = tmp_path / "enc.h5"
    measure.write(rec, path)
    full = measure.read(path)
    ref = speed_reference(full, "acc")
    speed = _speed_for(full, "acc", full["acc"], speed_rpm=None, speed_channel=None)
    got = np.concatenate([speed(a, min(speed.n, a + 3001)) for a in range(0, speed.n, 3001)])
    ang = np.concatenate([speed.angle(a, min(speed.n, a + 3001))
                          for a in range(0, speed.n, 3001)])
    np.testing.assert_allclose(got, ref.values, rtol=0, atol=1e-6)
    np.testing.assert_allclose(ang, ref["shaft_angle"].values, rtol=0, atol=1e-9)
    assert speed.angle_reference == ref.attrs["angle_reference"]
    assert "tdc_offset_deg 30" in speed.angle_reference
    mem = order_track(full["acc"], speed_rpm=ref, orders=[2, 4.5], method="cot", revolutions=8)
    res = order_track_stream(measure.open(path, chunk_seconds=1.0), "acc", orders=[2, 4.5],
                             method="cot", revolutions=8, segment_seconds=1.5)
    np.testing.assert_allclose(res.amplitude, mem.amplitude, rtol=1e-9)
    np.testing.assert_allclose(res.phase, mem.phase, rtol=0, atol=1e-9)
    inner = ((res.time > 0.5) & (res.time < T - 0.5)).values
    assert np.abs(res.amplitude.sel(order=2).values[inner] / A2 - 1).max() < 6e-3


def test_encoder_angle_analysed_against_itself_loses_its_ramp(tmp_path, small_blocks):
    """The encoder channel tracked against itself: the angle ramp is removed on both paths
    and order 1.5 reads the 2e-3 rad vibration (0.5 %), streamed equal to in-memory."""
    rec = _encoder_record(unwrapped=True)[["enc"]]
    path = tmp_path / "enc.h5"
    measure.write(rec, path)
    full = measure.read(path)
    mem = order_track(full["enc"], speed_rpm=speed_reference(full, "enc"), orders=[1.5],
                      method="cot", revolutions=8)
    res = order_track_stream(measure.open(path, chunk_seconds=1.0), "enc", orders=[1.5],
                             method="cot", revolutions=8, segment_seconds=1.5)
    assert mem.attrs["trend_kind"] == res.attrs["trend_kind"] == "angle ramp"
    np.testing.assert_allclose(res.amplitude, mem.amplitude, rtol=1e-9)
    inner = ((res.time > 0.5) & (res.time < T - 0.5)).values
    assert np.abs(res.amplitude.values[0, inner] / 2e-3 - 1).max() < 5e-3


def test_speed_channel_covering_part_of_the_record_is_checked_as_in_memory():
    """A speed channel on its own clock that covers 40 % of the channel is refused, one that
    stops 0.5 s early (12 revolutions) is held with the in-memory path's warning."""
    from crankbench.analysis.speedref import SpeedReferenceWarning

    fs = 2000.0
    x = np.cos(2 * np.pi * 50.0 * np.arange(int(10 * fs)) / fs)

    def record(t0, seconds):
        return make_record({"acc": dict(data=x, sample_rate=fs, units="m/s^2"),
                            "n": dict(data=np.full(int(seconds * 100), 157.08), t0=t0,
                                      sample_rate=100.0, units="rad/s",
                                      quantity="rotational_speed")})

    with pytest.raises(AnalysisError, match="known for only 39.9 %"):
        order_track_stream(record(6.0, 4.0), "acc", orders=[2])
    with pytest.warns(SpeedReferenceWarning, match="held constant"):
        order_track_stream(record(0.0, 9.5), "acc", orders=[2], revolutions=8)


def test_fast_speed_channel_on_its_own_clock_is_repaired_and_averaged_as_in_memory(caplog):
    """A 1 kHz speed channel (30-50 samples a revolution, carrying 0.4 rad/s of order-1.5
    vibration and a 65535 spike) for a 2 kHz signal: bridged with the warning, interpolated and
    cycle-averaged on the signal's clock, equal to speed_reference's speed (1e-6 rpm)."""
    fs, seconds = 2000.0, 8.0
    prof = ramp(1200.0, 2000.0, duration=seconds)
    t = np.arange(int(seconds * fs)) / fs
    ts = np.arange(int(seconds * 1000)) / 1000.0
    w = prof.speed(ts) + 0.4 * np.cos(1.5 * prof.angle(ts))
    w[3000] = 65535.0
    rec = make_record({"acc": dict(data=np.cos(2 * prof.angle(t)), sample_rate=fs,
                                   units="m/s^2"),
                       "n": dict(data=w, sample_rate=1000.0, units="rad/s",
                                 quantity="rotational_speed")})
    ref = speed_reference(rec, "acc").values
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        speed = _speed_for(rec, "acc", rec["acc"], speed_rpm=None, speed_channel=None)
    assert _warnings(caplog, "1 glitch sample(s)")
    assert isinstance(speed._rpm, stream_speed.CycleAveraged)
    got = np.concatenate([speed(a, min(speed.n, a + 2999)) for a in range(0, speed.n, 2999)])
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6)
    inner = slice(int(fs), -int(fs))
    assert np.abs(got[inner] - prof.speed(t)[inner] * 60 / (2 * np.pi)).max() < 1.0


def test_a_record_that_stops_gets_its_order_map_and_plots(tmp_path, small_blocks, monkeypatch):
    """The order map of a record that stops is the map of each running span (it was refused,
    in memory and streamed, so `analyse --plot` failed on the run that had tracked fine): no
    block inside the stop, order 2 at its true 0.5 in both spans, the two paths equal; the
    Campbell map (time frames) takes the standing frames at 0 rpm."""
    from crankbench.analysis import order_map
    from crankbench.analysis.cli import main
    from crankbench.analysis.commands import analyse
    from crankbench.analysis.orders import OrderWarning
    from crankbench.analysis.stream import order_map_stream

    rec, _ = _bench("stop")
    path = tmp_path / "stop.h5"
    measure.write(rec, path)
    full = measure.read(path)
    with pytest.warns(OrderWarning, match="order map is computed in each running span"):
        mem = order_map(full["acc"], speed_rpm=speed_reference(full, "acc"), revolutions=8)
    t = mem["time"].values
    assert not np.any((t > 5.0) & (t < 5.5))
    assert np.median(mem.sel(order=2.0).values) == pytest.approx(A2, rel=0.01)
    with pytest.warns(OrderWarning):
        lazy = order_map_stream(measure.open(path, chunk_seconds=1.0), "acc", revolutions=8,
                                segment_seconds=1.5)
    np.testing.assert_allclose(lazy.sel(order=2.0).values, mem.sel(order=2.0).values,
                               rtol=1e-6)
    for streamed in (False, True):
        if streamed:
            monkeypatch.setattr(analyse, "STREAM_BYTES", 0)
        out = tmp_path / f"plots{int(streamed)}"
        assert main(["analyse", str(path), "--channel", "acc", "--orders", "2,4.5",
                     "--plot", str(out), "-q"]) == 0
        assert sorted(p.name for p in out.iterdir()) == ["campbell.png", "order_map.png",
                                                         "order_tracks.png"]


def test_allow_nonfinite_on_a_streamed_file_is_refused_up_front(tmp_path, monkeypatch, capsys):
    """The streamed trackers refuse NaN runs; --allow-nonfinite on a file streamed must say so
    (and what to do) before any work, not fail mid-stream with advice to use the option given."""
    from crankbench.analysis.cli import main
    from crankbench.analysis.commands import analyse

    rec, _ = _bench()
    path = tmp_path / "r.h5"
    measure.write(rec, path)
    monkeypatch.setattr(analyse, "STREAM_BYTES", 0)
    assert main(["analyse", str(path), "--channel", "acc", "--orders", "2",
                 "--allow-nonfinite"]) == 2
    err = capsys.readouterr().err
    assert "--allow-nonfinite" in err and "do not mask NaN/inf runs" in err
