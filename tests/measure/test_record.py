"""The Record schema: builder, validator messages, helpers."""

import numpy as np
import pytest
import xarray as xr

from crankbench.measure.record import channel_time, clipped_spans, list_channels, make_record, \
    nonfinite_spans, validate
from crankbench.predict.errors import RecordError


def _rec(**over):
    spec = dict(data=np.sin(np.arange(1000) * 0.1), sample_rate=500.0, units="m/s^2",
                quantity="acceleration")
    spec.update(over)
    return make_record({"acc": spec})


def test_make_record_groups_clocks_without_resampling():
    rec = make_record({
        "acc": dict(data=np.zeros(5120), sample_rate=5120.0, units="g"),
        "acc2": dict(data=np.zeros(5120), sample_rate=5120.0, units="mm/s"),
        "rpm": dict(data=np.full(100, 1500.0), sample_rate=100.0, units="rpm"),
        "tacho": dict(data=np.arange(25) / 25.0, units="s", quantity="pulse_times",
                      pulses_per_rev=60, missing_teeth=2),
    }, start_time="2026-02-01T08:00:00+00:00", attrs={"engine_id": "I4", "test_id": "T1"})
    assert rec["acc"].dims == rec["acc2"].dims == ("time",)
    assert rec["rpm"].dims == ("time_rpm",)
    assert rec["tacho"].dims == ("pulse",)
    assert rec.sizes == {"time": 5120, "time_rpm": 100, "pulse": 25}
    # 1500 rpm = 1500 * 2 pi / 60 rad/s = 50 pi
    assert float(rec["rpm"][0]) == pytest.approx(50 * np.pi, rel=1e-15)
    assert rec["rpm"].attrs["quantity"] == "rotational_speed"
    assert rec["acc2"].attrs == {"units": "m/s", "quantity": "velocity", "sample_rate": 5120.0}
    assert rec["tacho"].attrs["pulses_per_rev"] == 60 and rec["tacho"].attrs["missing_teeth"] == 2
    assert rec.attrs["engine_id"] == "I4"
    np.testing.assert_array_equal(channel_time(rec, "rpm"), np.arange(100) / 100.0)
    np.testing.assert_array_equal(channel_time(rec, "tacho"), np.arange(25) / 25.0)


def test_several_pulse_trains_get_named_dims_and_list_channels():
    rec = make_record({
        "x": dict(data=np.zeros(10), sample_rate=10.0, units="V"),
        "cam": dict(data=[0.1, 0.3], units="s", quantity="pulse_times", pulses_per_rev=1),
        "crank": dict(data=[0.1, 0.2, 0.3], units="s", quantity="pulse_times", pulses_per_rev=60),
    })
    assert rec["cam"].dims == ("pulse_cam",) and rec["crank"].dims == ("pulse_crank",)
    table = list_channels(rec)
    assert list(table.columns) == ["name", "quantity", "units", "sample_rate", "n", "duration_s",
                                   "dim"]
    row = table.set_index("name").loc["x"]
    assert row["n"] == 10 and row["duration_s"] == 1.0 and row["dim"] == "time"
    assert table.set_index("name").loc["crank", "duration_s"] == pytest.approx(0.2)


def test_sensitivity_converted_to_si():
    rec = _rec(sensitivity=100.0, sensitivity_units="mV/g")
    assert rec["acc"].attrs["sensitivity"] == pytest.approx(0.1 / 9.80665, rel=1e-12)
    assert rec["acc"].attrs["sensitivity_units"] == "V/(m/s^2)"


def test_missing_units_named():
    rec = _rec()
    del rec["acc"].attrs["units"]
    with pytest.raises(RecordError, match=r"channel 'acc' has no 'units' attr; expected one of "):
        validate(rec)


def test_non_si_units_named():
    rec = _rec()
    rec["acc"].attrs["units"] = "g"
    with pytest.raises(RecordError, match=r"channel 'acc' has non-SI units 'g'; expected one of"):
        validate(rec)


def test_missing_quantity_and_mismatch():
    rec = _rec()
    del rec["acc"].attrs["quantity"]
    with pytest.raises(RecordError, match=r"channel 'acc' has no 'quantity' attr"):
        validate(rec)
    rec["acc"].attrs["quantity"] = "velocity"
    with pytest.raises(RecordError, match=r"channel 'acc': quantity 'velocity' needs units "
                                          r"'m/s', got 'm/s\^2'"):
        validate(rec)


@pytest.mark.parametrize("fs", [0.0, -10.0, float("nan")])
def test_bad_sample_rate_named(fs):
    with pytest.raises(RecordError, match=r"channel 'acc': sample_rate=.* Hz; expected a finite "
                                          r"value > 0"):
        _rec(sample_rate=fs)


def test_sample_rate_inconsistent_with_time():
    rec = _rec()
    rec["acc"].attrs["sample_rate"] = 1000.0
    with pytest.raises(RecordError, match=r"channel 'acc': sample_rate=1000 Hz is inconsistent "
                                          r"with its time coordinate 'time'"):
        validate(rec)


def test_non_monotonic_and_duplicated_time():
    t = np.arange(10) / 10.0
    t_back = t.copy()
    t_back[5] = 0.35
    with pytest.raises(RecordError, match=r"channel 'acc': non-monotonic time stamp in 'time' "
                                          r"at index 5 .*expected strictly increasing time"):
        make_record({"acc": dict(data=np.zeros(10), time=t_back, sample_rate=10.0,
                                 units="m/s^2")})
    t_dup = t.copy()
    t_dup[4] = t_dup[3]
    with pytest.raises(RecordError, match=r"channel 'acc': duplicated time stamp in 'time' at "
                                          r"index 4"):
        make_record({"acc": dict(data=np.zeros(10), time=t_dup, sample_rate=10.0,
                                 units="m/s^2")})


def test_time_gap_detected():
    t = np.arange(10) / 10.0
    t[6:] += 0.1  # one missing sample
    with pytest.raises(RecordError, match=r"time step 0.2 s at index 6 .*deviates from "
                                          r"1/sample_rate"):
        make_record({"acc": dict(data=np.zeros(10), time=t, sample_rate=10.0, units="g")})


def test_nonfinite_runs_named_with_spans():
    x = np.ones(100)
    x[10:13] = np.nan
    x[50] = np.inf
    with pytest.raises(RecordError, match=r"channel 'acc' has 4 NaN/inf sample\(s\) in 2 run\(s\): "
                                          r"samples 10..12 \(t = 0.02..0.024 s\); samples 50..50"):
        _rec(data=x)
    rec = _rec(data=x, ) if False else make_record(
        {"acc": dict(data=x, sample_rate=500.0, units="g")}, allow_nonfinite=True)
    assert np.isnan(rec["acc"][10])


def test_pulse_attrs_checked():
    with pytest.raises(RecordError, match=r"pulse-time channel 'tacho': spec needs "
                                          r"'pulses_per_rev'"):
        make_record({"tacho": dict(data=[0.1, 0.2], units="s", quantity="pulse_times")})
    with pytest.raises(RecordError, match=r"missing_teeth=60; expected an integer in \[0, 59\]"):
        make_record({"tacho": dict(data=[0.1, 0.2], units="s", quantity="pulse_times",
                                   pulses_per_rev=60, missing_teeth=60)})
    with pytest.raises(RecordError, match=r"pulse-time channel 'tacho': duplicated edge time at "
                                          r"index 1"):
        make_record({"tacho": dict(data=[0.1, 0.1], units="s", quantity="pulse_times",
                                   pulses_per_rev=1)})


def test_quantity_required_when_unit_is_ambiguous():
    with pytest.raises(RecordError, match=r"channel 'w': units 'rad/s' do not imply a quantity"):
        make_record({"w": dict(data=np.zeros(4), sample_rate=1.0, units="rad/s")})


def test_start_time_must_be_iso():
    with pytest.raises(RecordError, match=r"start_time='yesterday' is not ISO 8601"):
        _rec().pipe(lambda r: r.assign_attrs(start_time="yesterday")).pipe(validate)


def test_validate_rejects_non_dataset_and_2d():
    with pytest.raises(RecordError, match="must be an xarray.Dataset"):
        validate(np.zeros(3))
    ds = xr.Dataset({"m": (("time", "x"), np.zeros((2, 2)), {"units": "V", "quantity": "voltage",
                                                            "sample_rate": 1.0})})
    with pytest.raises(RecordError, match=r"channel 'm' has dims \('time', 'x'\); expected one"):
        validate(ds)


def test_nonfinite_spans_against_hand_count():
    x = np.array([np.nan, 1, 1, np.inf, -np.inf, 2, np.nan])
    assert nonfinite_spans(x) == [(0, 1), (3, 5), (6, 7)]
    assert nonfinite_spans(np.ones(3)) == []


def test_clipped_spans_against_hand_count():
    """Flat runs (>= 3 samples) at the signal's own max/min; shorter touches are not clipping."""
    x = np.sin(np.linspace(0, 4 * np.pi, 400)) * 1.3
    clipped = np.clip(x, -0.8, 0.8)
    spans = clipped_spans(clipped)
    # |1.3 sin| >= 0.8 on 4 arcs; every span lies inside one of them and covers it
    expected = np.abs(x) >= 0.8
    got = np.zeros(400, bool)
    for a, b in spans:
        got[a:b] = True
    np.testing.assert_array_equal(got, expected)
    assert len(spans) == 4
    assert clipped_spans(x) == []                      # unclipped sine: single peak samples
    assert clipped_spans(np.ones(10)) == []            # constant channel is not "clipped"
    assert clipped_spans(np.array([0, 1, 1, 0, -1])) == []   # run of 2 < min_run
    assert clipped_spans(np.array([0, 2, 2, 2, 0])) == []    # one flat peak is no evidence
    assert clipped_spans(np.array([np.nan, 2, 2, 2, 0.1, 0.2, 2, 2, 2])) == [(1, 4), (6, 9)]


def test_quantised_slow_sine_is_not_clipping():
    """A 5 Hz sine at 51.2 kHz stored as 16-bit codes has crests flat for dozens of samples
    (entered one quantisation step below the crest value): not clipping. The same codes with
    ADC noise clipped at 80 % of the crest are."""
    t = np.arange(51200) / 51200.0
    codes = np.round(30000 * np.sin(2 * np.pi * 5 * t))
    assert clipped_spans(codes) == []
    noisy = np.round(30000 * np.sin(2 * np.pi * 5 * t)
                     + np.random.default_rng(1).normal(0, 2.0, t.size))
    assert len(clipped_spans(np.clip(noisy, -24000, 24000))) == 10


def test_runs_at_a_level_match_a_boolean_edge_count():
    """``_runs_at`` (indices of the level, split at gaps) equals the runs found from the edges
    of the boolean mask, on random 3-level signals, whole and by blocks."""
    from crankbench.measure.scan import _SCAN_BLOCK, _runs_at

    rng = np.random.default_rng(1)
    for _ in range(300):
        x = rng.integers(0, 3, int(rng.integers(1, 400))).astype(float)
        for level in (0.0, 2.0, 5.0):
            edges = np.diff(np.concatenate(([0], (x == level).view(np.int8), [0])))
            starts, stops = _runs_at(x, level, None)
            np.testing.assert_array_equal(starts, np.flatnonzero(edges == 1))
            np.testing.assert_array_equal(stops, np.flatnonzero(edges == -1))
    x = np.zeros(3 * _SCAN_BLOCK)
    x[_SCAN_BLOCK - 2:_SCAN_BLOCK + 3] = 1.0  # a run across a block edge, blocks 0 and 1
    starts, stops = _runs_at(x, 1.0, np.array([0, 1]))
    assert starts.tolist() == [_SCAN_BLOCK - 2] and stops.tolist() == [_SCAN_BLOCK + 3]
