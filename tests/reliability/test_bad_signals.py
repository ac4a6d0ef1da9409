"""Damaged tacho trains and vibration channels: a clear error, or a masked result with a warning.

The signals come from ``tests/corpus/make_bad_signals.py``. For every one the consumer either
raises an error of the project's family naming the argument/channel and what was expected, or —
where the data is usable in part (a few dropouts, NaN runs read with ``allow_nonfinite``) —
returns a result whose damaged span is masked and says so in a warning. Faults found are strict
xfails with the fault in ``reason``.
"""

from __future__ import annotations

import importlib.util
import json
import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from crankbench.analysis.orders import campbell_map, order_map, order_spectrum, order_track
from crankbench.measure import io as mio
from crankbench.measure.record import RecordWarning, make_record
from crankbench.measure.tacho import angle_from_pulses, count_pitches, detect_edges, speed_from_pulses
from crankbench.measure.torsiograph import angular_vibration
from crankbench.predict.errors import AnalysisError, CrankbenchError, RecordError

CORPUS = Path(__file__).resolve().parents[1] / "corpus"


def _load(name):
    key = f"crankbench_corpus_{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, CORPUS / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[key] = module
        spec.loader.exec_module(module)
    return sys.modules[key]


sig = _load("make_bad_signals")
PPR = sig.PULSES_PER_REV
FS = sig.FS

PULSE_FUNCS = {
    "count_pitches": lambda e, **kw: count_pitches(e, pulses_per_rev=PPR, **kw),
    "speed_from_pulses": lambda e, **kw: speed_from_pulses(e, pulses_per_rev=PPR, **kw),
    "angle_from_pulses": lambda e, **kw: angle_from_pulses(e, pulses_per_rev=PPR, **kw),
    "angular_vibration": lambda e, **kw: angular_vibration(e, pulses_per_rev=PPR, **kw),
}
ORDER_FUNCS = {
    "order_track": lambda x, rpm: order_track(x, speed_rpm=rpm, orders=[2.0, 4.0], revolutions=8),
    "order_map": lambda x, rpm: order_map(x, speed_rpm=rpm, revolutions=8),
    "order_spectrum": lambda x, rpm: order_spectrum(x, speed_rpm=rpm),
    "campbell_map": lambda x, rpm: campbell_map(x, speed_rpm=rpm, nperseg=1024),
}


def _channel(data, name="acc"):
    """A Record channel (so messages can name it), built without the finiteness check."""
    rec = make_record({name: dict(data=data, sample_rate=FS, units="m/s^2",
                                  quantity="acceleration")}, allow_nonfinite=True)
    return rec[name]


# ------------------------------------------------------------------------------ tacho
@pytest.mark.parametrize("func", list(PULSE_FUNCS))
@pytest.mark.parametrize("case, pattern", [
    ("tacho_no_pulses", r"edge_times has 0 edges; at least 3 are needed"),
    ("tacho_one_pulse", r"edge_times has 1 edges; at least 3 are needed"),
    ("tacho_two_pulses", r"edge_times has 2 edges; at least 3 are needed"),
    ("tacho_reversed", r"edge_times must increase strictly; edge 1 .* does not follow edge 0"),
    ("tacho_duplicated_edge", r"edge_times must increase strictly; edge 101 .* does not follow "
                              r"edge 100"),
])
def test_unusable_pulse_train_is_named_error(case, pattern, func):
    tacho = sig.TACHO_CASES[case]()
    with pytest.raises(AnalysisError, match=pattern):
        PULSE_FUNCS[func](tacho.edge_times)


@pytest.mark.parametrize("func", ["count_pitches", "speed_from_pulses", "angle_from_pulses"])
def test_plain_wheel_declared_with_gap_is_named_error(func):
    tacho = sig.tacho_plain_wheel_declared_60_2()
    with pytest.raises(AnalysisError, match=r"no gap of 2 missing teeth found in 720 edges, "
                                            r"12.0 revolutions of a 60-pitch wheel: every pitch "
                                            r"position holds edges \(a plain wheel or encoder: "
                                            r"missing_teeth=0\?"):
        PULSE_FUNCS[func](tacho.edge_times, missing_teeth=2)


def test_pulse_train_shorter_than_speed_window_is_named_error():
    tacho = sig.tacho_shorter_than_window()
    with pytest.raises(AnalysisError, match=r"edge_times span 29 pitches, fewer than the "
                                            r"averaging window of 60 pitches \(window_revs=1"):
        speed_from_pulses(tacho.edge_times, pulses_per_rev=PPR)


def test_flat_analog_tacho_is_named_error():
    tacho = sig.tacho_flat_analog()
    with pytest.raises(AnalysisError, match=r"signal is constant \(no pulses\).*expected a "
                                            r"pulse train"):
        detect_edges(tacho.signal, fs=tacho.fs)


def test_few_dropouts_are_bridged_and_counted():
    """3 % lost pulses: usable — every dropout bridged (counted in ``filled``), speed exact."""
    tacho = sig.tacho_few_missing()
    n_lost = sig.steady_edges().size - tacho.edge_times.size
    pc = count_pitches(tacho.edge_times, pulses_per_rev=PPR)
    assert pc.filled == n_lost
    trace = speed_from_pulses(tacho.edge_times, pulses_per_rev=PPR)
    np.testing.assert_allclose(trace.speed_rpm, sig.SPEED_RPM, rtol=1e-9)


@pytest.mark.parametrize("func", list(PULSE_FUNCS))
def test_half_missing_pulses_are_named_error(func):
    """50 % of pulses lost at random: too damaged to count pitches; the error says so.
    (Found: the speed came out 12-33 % low without a word; fixed in 62522aa.)"""
    tacho = sig.tacho_half_missing()
    with pytest.raises(AnalysisError, match=r"edge_times: \d+ % of the pulse intervals are not "
                                            r"whole numbers of pitches.*too many missing or "
                                            r"spurious pulses.*pulses_per_rev=60"):
        PULSE_FUNCS[func](tacho.edge_times)


@pytest.mark.parametrize("func", list(PULSE_FUNCS))
def test_standstill_is_named_error_not_bridged(func):
    """A 5 s standstill is not 'missing pulses': the error names the silent stretch.
    (Found: bridged as 5000 dropouts at a constant 1000 rpm; fixed in 62522aa.)"""
    tacho = sig.tacho_stops()
    with pytest.raises(AnalysisError, match=r"edge_times: no pulse for 5\.001 s between "
                                            r"0\.359 s and 5\.36 s.*shaft stopped or the "
                                            r"signal was lost"):
        PULSE_FUNCS[func](tacho.edge_times)


@pytest.mark.parametrize("case, pattern", [
    ("tacho_nan_edge", r"edge_times contains 1 NaN/inf value\(s\), first at index 50"),
    ("tacho_nan_analog", r"signal contains 50 NaN/inf value\(s\), first at index 1000"),
])
def test_nan_in_tacho_is_our_error(case, pattern):
    """(Found: a bare ValueError outside the family; fixed in 62522aa.)"""
    tacho = sig.TACHO_CASES[case]()
    with pytest.raises(AnalysisError, match=pattern):
        if tacho.edge_times is not None:
            speed_from_pulses(tacho.edge_times, pulses_per_rev=PPR)
        else:
            detect_edges(tacho.signal, fs=tacho.fs)


def test_reversed_tacho_message_is_plain_numbers():
    """(Found: 'edge 1 (np.float64(0.718) s)'; fixed in 62522aa.)"""
    with pytest.raises(AnalysisError, match=r"edge_times must increase strictly; edge 1 "
                                            r"\(0\.718 s\) does not follow edge 0 \(0\.719 s\)"):
        speed_from_pulses(sig.tacho_reversed().edge_times, pulses_per_rev=PPR)


# ------------------------------------------------------------------------------ channels
@pytest.mark.parametrize("func", list(ORDER_FUNCS))
@pytest.mark.parametrize("case, pattern", [
    ("channel_dropout_nan", r"acc contains 100 NaN/inf value\(s\), first at index 4000"),
    ("channel_dropout_inf", r"acc contains 5 NaN/inf value\(s\), first at index 2000"),
    # (message wording under revision; every form names the speed found and the first sample)
    ("channel_zero_speed_segment", r"rpm must be > 0 throughout.*(min 0 rpm|found "
                                   r"(np\.float64\()?0\.0).*at samples? 3000\b"),
    ("channel_negative_speed", r"rpm must be > 0 throughout.*(min -1500 rpm|found "
                               r"(np\.float64\()?-1500\.0).*at samples? 0\b"),
    ("channel_nan_speed", r"rpm contains 1 NaN/inf value\(s\), first at index 7999"),
    ("channel_speed_wrong_length", r"rpm has 7900 samples but the signal has 8000"),
])
def test_unusable_channel_is_named_error(case, pattern, func):
    if func == "order_track" and case.startswith("channel_dropout"):
        pytest.skip("order_track masks dropouts instead (see the masked-dropout test below)")
    if func == "order_track" and case == "channel_zero_speed_segment":
        pytest.skip("order_track tracks the running spans around a stop (tests/hard_cases/"
                    "test_hard_orders.py::test_a_stop_is_tracked_around_and_named)")
    c = sig.CHANNEL_CASES[case]()
    if func in ("order_map", "campbell_map") and case == "channel_zero_speed_segment":
        # the order map is computed in each running span, named in a warning (as the tracks
        # are); the Campbell map's time frames take the standing span at 0 rpm
        from crankbench.analysis.orders import OrderWarning

        a, b = (v / FS for v in c.spans[0])
        if func == "order_map":
            with pytest.warns(OrderWarning, match="order map is computed in each running span"):
                m = ORDER_FUNCS[func](_channel(c.data), c.rpm)
            t = m["time"].values
            assert not np.any((t > a) & (t < b)) and np.isfinite(m.values).all()
        else:
            m = ORDER_FUNCS[func](_channel(c.data), c.rpm)
            assert np.isfinite(m.values).all()
            assert float(m["rpm"].min()) < 0.8 * float(np.median(c.rpm))   # the stop shows
        return
    with pytest.raises(AnalysisError, match=pattern):
        ORDER_FUNCS[func](_channel(c.data), c.rpm)


@pytest.mark.parametrize("func", ["order_track", "order_map", "order_spectrum"])
def test_too_short_channel_is_named_error(func):
    c = sig.channel_too_short()
    with pytest.raises(AnalysisError, match=r"acc must have at least 8 values, got 5"):
        ORDER_FUNCS[func](_channel(c.data), c.rpm)


def test_dead_sensor_gives_zero_orders_not_nan():
    c = sig.channel_constant()
    res = order_track(_channel(c.data), speed_rpm=c.rpm, orders=[2.0, 4.0], revolutions=8)
    amp = res.amplitude.values
    assert np.all(np.isfinite(amp)) and np.all(amp == 0.0)


@pytest.mark.parametrize("ext", [".h5", ".csv", ".nc", ".tdms", ".mf4", ".wav"])
def test_dropouts_in_a_file_are_an_error_naming_channel_and_span(tmp_path, ext):
    c = sig.channel_dropout_nan()
    path = tmp_path / f"drop{ext}"
    mio.write(make_record({"acc": dict(data=c.data, sample_rate=FS, units="m/s^2",
                                       quantity="acceleration")}, allow_nonfinite=True), path)
    with pytest.raises(RecordError, match=rf"drop{ext}: channel 'acc' has 100 NaN/inf sample\(s\) "
                                          r"in 1 run\(s\): samples 4000\.\.4099 \(t = 2\.\.2\.0495 s\).*"
                                          r"allow_nonfinite=True"):
        mio.read(path)


@pytest.mark.parametrize("ext", [".h5", ".csv", ".nc", ".tdms", ".mf4", ".wav"])
def test_dropouts_read_with_allow_nonfinite_are_masked_with_warning(tmp_path, ext):
    """Usable in part: the span is NaN-masked, listed in ``masked_spans_s`` and warned about;
    every other sample is unchanged."""
    c = sig.channel_dropout_nan()
    path = tmp_path / f"drop{ext}"
    mio.write(make_record({"acc": dict(data=c.data, sample_rate=FS, units="m/s^2",
                                       quantity="acceleration")}, allow_nonfinite=True), path)
    with pytest.warns(RecordWarning, match=rf"drop{ext}: channel 'acc': 100 NaN/inf sample\(s\) "
                                           r"masked as NaN in 1 span\(s\): 2\.\.2\.0495 s"):
        rec = mio.read(path, allow_nonfinite=True)
    values = rec["acc"].values
    np.testing.assert_array_equal(np.flatnonzero(np.isnan(values)), np.arange(4000, 4100))
    np.testing.assert_allclose(rec["acc"].attrs["masked_spans_s"], [2.0, 2.0495])
    good = np.isfinite(c.data)
    tol = 1e-4 if ext == ".wav" else 1e-12      # WAV stores 32-bit float samples
    np.testing.assert_allclose(values[good], c.data[good], atol=tol)


def test_uff_keeps_or_refuses_dropouts(tmp_path):
    """UFF 58 cannot hold NaN: the writer must refuse (naming the channel) rather than store
    zeros, or the reader must flag them. (Found writing NaN as 0.0 and inf as 1.8e308; fixed
    in 5311e14.)"""
    c = sig.channel_dropout_nan()
    path = tmp_path / "drop.uff"
    rec = make_record({"acc": dict(data=c.data, sample_rate=FS, units="m/s^2",
                                   quantity="acceleration")}, allow_nonfinite=True)
    try:
        mio.write(rec, path)
    except RecordError as exc:
        assert "acc" in str(exc) and "NaN" in str(exc)
        return
    with pytest.raises(RecordError, match="NaN/inf"):
        mio.read(path)


def test_masked_dropout_gives_masked_order_track_with_warning():
    c = sig.channel_dropout_nan()
    with pytest.warns(UserWarning, match=r"acc.*(masked|NaN).*2(\.0)?\.\.2\.0495 s"):
        res = order_track(_channel(c.data), speed_rpm=c.rpm, orders=[2.0], revolutions=8)
    amp = res.amplitude.sel(order=2.0)
    t = res.time.values
    assert np.isnan(amp.values[np.abs(t - 2.02) < 0.05]).all()
    far = np.abs(t - 2.02) > 0.5
    np.testing.assert_allclose(amp.values[far], 1.0, rtol=1e-2)


def test_clipped_channel_is_flagged(tmp_path):
    """Usable in part: read gives the data with the flat-topped spans listed and a warning."""
    c = sig.channel_clipped()
    path = tmp_path / "clip.h5"
    mio.write(make_record({"acc": dict(data=c.data, sample_rate=FS, units="m/s^2",
                                       quantity="acceleration")}), path)
    with pytest.warns(RecordWarning, match=r"clip\.h5: channel 'acc'.*clip"):
        rec = mio.read(path)
    assert "clipped_spans_s" in rec["acc"].attrs


def test_clipped_channel_order_amplitude_is_wrong_without_flag():
    """Why clipping must be flagged: the 2nd-order amplitude of the clipped channel is off by
    more than 10 % from the truth (1.0), a silent error."""
    c = sig.channel_clipped()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = order_track(_channel(c.data), speed_rpm=c.rpm, orders=[2.0], revolutions=8)
    amp = float(res.amplitude.sel(order=2.0).mean())
    assert abs(amp - c.truth[2.0]) > 0.1


def test_record_without_resonances_is_compared_not_crashed():
    import pandas as pd

    from crankbench.analysis.compare import match_criticals
    from crankbench.analysis.resonance import Resonance

    measured = pd.DataFrame([], columns=list(Resonance.__dataclass_fields__))  # = empty table
    predicted = pd.DataFrame({"mode": [1], "order": [2.0], "speed_rpm": [3000.0]})
    try:
        result = match_criticals(measured, predicted)
    except CrankbenchError as exc:
        assert "resonance" in str(exc)
        return
    assert result is not None


def _bench_file(tmp_path, case, name):
    """A record file with the damaged channel ``acc`` and a speed channel on the same clock."""
    c = sig.CHANNEL_CASES[case]()
    rec = make_record({
        "acc": dict(data=c.data, sample_rate=FS, units="m/s^2", quantity="acceleration"),
        "speed": dict(data=c.rpm * np.pi / 30.0, sample_rate=FS, units="rad/s",
                      quantity="rotational_speed"),
    }, allow_nonfinite=True)
    path = tmp_path / name
    mio.write(rec, path)
    return path, c


def test_cli_analyse_of_dropout_record_names_file_channel_and_span(tmp_path, capsys):
    from crankbench.analysis.cli import main as cli_main

    path, _ = _bench_file(tmp_path, "channel_dropout_nan", "drop.h5")
    assert cli_main(["analyse", str(path), "--channel", "acc", "--orders", "2"]) == 2
    err = capsys.readouterr().err
    assert re.search(r"drop\.h5: channel 'acc' has 100 NaN/inf sample\(s\) in 1 run\(s\): "
                     r"samples 4000\.\.4099 \(t = 2\.\.2\.0495 s\)", err), err
    assert "Traceback" not in err


def test_cli_analyse_of_clipped_record_warns_and_still_analyses(tmp_path, capsys):
    """Usable in part: the analysis runs, and the user is told which spans are clipped."""
    from crankbench.analysis.cli import main as cli_main

    path, _ = _bench_file(tmp_path, "channel_clipped", "clip.h5")
    with pytest.warns(RecordWarning, match=r"clip\.h5: channel 'acc' looks clipped.*"
                                           r"clipped_spans_s"):
        status = cli_main(["analyse", str(path), "--channel", "acc", "--orders", "2", "--json"])
    assert status == 0
    out = json.loads(capsys.readouterr().out)
    assert out


@pytest.mark.parametrize("case, pattern", [
    ("tacho_reversed", r"pulse-time channel 'tacho': non-monotonic edge time at index 1 "
                       r"\(0\.719 s then 0\.718 s\); expected strictly increasing"),
    ("tacho_duplicated_edge", r"pulse-time channel 'tacho': duplicated edge time at index 101"),
    ("tacho_nan_edge", r"pulse-time channel 'tacho' has NaN/inf edge time at index 50"),
])
def test_damaged_pulse_channel_is_refused_by_the_record_schema(case, pattern):
    """A damaged edge-time channel cannot even become a Record: the schema names it."""
    tacho = sig.TACHO_CASES[case]()
    with pytest.raises(RecordError, match=pattern):
        make_record({"tacho": dict(data=tacho.edge_times, quantity="pulse_times", units="s",
                                   pulses_per_rev=PPR)})


@pytest.mark.parametrize("ext", [".h5", ".tdms", ".csv"])
@pytest.mark.parametrize("case, n_edges", [("tacho_no_pulses", 0), ("tacho_one_pulse", 1)])
def test_empty_pulse_channel_round_trips_and_consumer_names_the_problem(case, n_edges, ext,
                                                                        tmp_path):
    """A tacho that never fired is a valid (empty) channel on disk; speed from it is our
    error saying how many edges there are."""
    tacho = sig.TACHO_CASES[case]()
    fs, n = 1000.0, 100
    rec = make_record({
        "acc": dict(data=np.zeros(n), sample_rate=fs, units="m/s^2", quantity="acceleration"),
        "tacho": dict(data=tacho.edge_times, quantity="pulse_times", units="s",
                      pulses_per_rev=PPR),
    })
    path = tmp_path / f"tacho{ext}"
    try:
        mio.write(rec, path)
    except RecordError as exc:           # a format that cannot hold it must say so
        assert "tacho" in str(exc)
        return
    back = mio.read(path)
    edges = back["tacho"].values
    assert edges.size == n_edges
    with pytest.raises(AnalysisError, match=rf"edge_times has {n_edges} edges; at least 3"):
        speed_from_pulses(edges, pulses_per_rev=int(back["tacho"].attrs["pulses_per_rev"]))


def test_every_generated_signal_is_exercised():
    """Each case of make_bad_signals.py is named in this module's tests."""
    source = Path(__file__).read_text()
    unused = [name for name in sig.SIGNALS if f'"{name}"' not in source
              and f"sig.{name}(" not in source]
    assert unused == []
