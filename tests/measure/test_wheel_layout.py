"""Wheel decoding robust to real rigs (measure.wheel_layout via count_pitches, measure.wheel).

Truth: exact edge times of theta(t) = omega0 t + alpha t^2 / 2 for every present tooth (the
tooth number of each edge is known), and raw signals built from them.
"""

import warnings

import numpy as np
import pytest

from crankbench.measure.record import RecordWarning
from crankbench.measure.synth.pulses import pulse_voltage
from crankbench.measure.tacho import angle_from_pulses, count_pitches, speed_from_pulses
from crankbench.measure.wheel import decode_marks, decode_wheel
from crankbench.predict.errors import AnalysisError

TWO_PI = 2 * np.pi
W0, ALPHA = 100.0, 30.0


def _train(revs, *, n=60, missing=2, lost=(), start=5, drop=()):
    """Edges of an n-missing wheel over ``revs`` revolutions from pitch ``start``; teeth in
    ``lost`` never fire; edge indices in ``drop`` are removed. Returns (edges, pitch)."""
    k = np.arange(start, start + int(revs * n))
    pos = np.mod(k, n)
    keep = pos < n - missing
    for tooth in lost:
        keep &= pos != tooth
    k = k[keep]
    theta = k * TWO_PI / n
    t = (-W0 + np.sqrt(W0 ** 2 + 2 * ALPHA * theta)) / ALPHA
    return np.delete(t, list(drop)), np.delete(k, list(drop))


def _caught(func, *args, **kwargs):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = func(*args, **kwargs)
    return out, [str(w.message) for w in caught if issubclass(w.category, RecordWarning)]


def test_tooth_lost_before_the_gap_decodes_with_warning_naming_it():
    """The genset case: tooth 57 of a 60-2 wheel is a runt in every revolution, so the gap
    spans 4 pitches. Decoded (pitch of every edge right, speed exact), warned with the numbers
    seen; the old decoder said 'the record must span at least one full revolution'."""
    t, k = _train(26, lost=(57,))
    pc, notes = _caught(count_pitches, t, pulses_per_rev=60, missing_teeth=2)
    np.testing.assert_array_equal(np.mod(pc.pitch, 60), np.mod(k, 60))
    assert pc.lost_teeth == (57,) and pc.filled == 0
    assert any("26 intervals of 4 pitches at one wheel position where a 60-2 wheel has 3: "
               "tooth 57 (the last before the gap" in n and "missing_teeth=3" in n
               for n in notes), notes
    sp, _ = _caught(speed_from_pulses, t, pulses_per_rev=60, missing_teeth=2)
    np.testing.assert_allclose(sp.omega, W0 + ALPHA * sp.time, rtol=1e-9)


def test_more_than_one_lost_tooth_beside_the_gap_is_an_error_with_the_numbers():
    t, _ = _train(26, lost=(56, 57))
    with pytest.raises(AnalysisError, match=r"26 intervals of 5 pitches at one wheel position, "
                                            r"where a 60-2 wheel has a gap of 3 pitches "
                                            r"\(1456 edges, 26.0 revolutions.*\): 2 teeth next to "
                                            r"the gap are lost, or missing_teeth is 4"):
        count_pitches(t, pulses_per_rev=60, missing_teeth=2)


def test_gap_narrower_than_declared_names_the_width_seen():
    t, _ = _train(12, missing=1)
    with pytest.raises(AnalysisError, match=r"no gap of 2 missing teeth found in .*: the widest "
                                            r"stretch without edges is 1 pitch\(es\) at one wheel "
                                            r"position \(passed 12 times\).*missing_teeth is 1\?"):
        count_pitches(t, pulses_per_rev=60, missing_teeth=2)


def test_double_dropout_never_ties_with_the_gap_by_array_order():
    """Issue 13: in 1-2 revolutions a double dropout empties two positions like the gap. When
    the gap was passed more often it wins; when both were passed once the error says the record
    is too short — never a silent guess."""
    t, k = _train(2, start=50)
    t, k = t[:120], k[:120]
    # the gap (58, 59) is passed twice, the dropout positions 30, 31 once
    drop = [int(np.flatnonzero(np.mod(k, 60) == 30)[0]), int(np.flatnonzero(np.mod(k, 60) == 31)[0])]
    t2 = np.delete(t, drop)
    trace = angle_from_pulses(t2, pulses_per_rev=60, missing_teeth=2)
    d = np.angle(np.exp(1j * (trace.angle - np.delete(k, drop) * TWO_PI / 60)))
    assert np.abs(d).max() < 1e-9
    # a 1.3-revolution record: gap and dropout each passed once -> refused
    t, k = _train(2, start=20)
    t3 = np.delete(t[:78], [20, 21])
    with pytest.raises(AnalysisError, match=r"cannot tell the gap of 2 missing teeth from "
                                            r"dropped pulses .*2 stretches of at least 2 empty "
                                            r"pitch positions .*each passed 1 time without an "
                                            r"edge; the record is too short"):
        count_pitches(t3, pulses_per_rev=60, missing_teeth=2)


@pytest.mark.parametrize("n, missing", [(60, 2), (36, 1), (36, 2), (12, 1), (360, 0)])
def test_layout_inferred_from_the_pitch_pattern(n, missing):
    t, k = _train(6, n=n, missing=missing, start=7)
    pc = count_pitches(t, pulses_per_rev=n, missing_teeth=None)
    assert pc.missing_teeth == missing
    if missing:
        np.testing.assert_array_equal(np.mod(pc.pitch, n), np.mod(k, n))


def test_inferred_unusual_layout_says_what_else_it_could_be():
    t, _ = _train(10, lost=(57,))
    pc, notes = _caught(count_pitches, t, pulses_per_rev=60, missing_teeth=None)
    assert pc.missing_teeth == 3
    assert any("missing_teeth inferred as 3" in n and "60-2 wheel whose tooth next to the gap "
               "never triggers reads the same" in n for n in notes), notes


def test_gap_declared_as_plain_wheel_is_named_not_silently_bridged():
    t, _ = _train(10)
    pc, notes = _caught(count_pitches, t, pulses_per_rev=60, missing_teeth=0)
    assert any("give no edge in any of the 10 revolutions passing them: the wheel has a gap "
               "(missing_teeth=2?)" in n for n in notes), notes


def test_weak_tooth_dropouts_piling_up_are_named():
    """Tooth 20 missed in half the revolutions: bridged (speed right) and named."""
    t, k = _train(20)
    drop = np.flatnonzero((np.mod(k, 60) == 20) & (k // 60 % 2 == 0))
    pc, notes = _caught(count_pitches, np.delete(t, drop), pulses_per_rev=60, missing_teeth=2)
    assert pc.filled == drop.size
    assert any("dropouts pile up at tooth 20" in n for n in notes), notes


@pytest.mark.parametrize("runt_tooth", [57, 0])
def test_runt_tooth_on_either_side_of_the_gap_is_recovered_from_the_signal(runt_tooth):
    """Raw 0-5 V pick-up, the tooth before (57) or after (0) the gap a runt at 11 %: its edges
    are taken from the runt, so every edge is there and the angle reference is right either
    way (from edges alone the side cannot be told)."""
    fs = 100_000.0
    t_edges, k = _train(8, start=3)
    t = np.arange(int((t_edges[-1] + 2e-3) * fs)) / fs
    levels = np.where(np.mod(k, 60) == runt_tooth, 0.11, 1.0)
    pitch_t = np.r_[np.diff(t_edges), np.diff(t_edges)[-1]]
    v = pulse_voltage(t_edges, t, widths=0.4 * pitch_t, levels=levels, high=5.0)
    v = v + 0.02 * np.random.default_rng(4).standard_normal(t.size)
    dec, notes = _caught(decode_wheel, v, fs=fs, pulses_per_rev=60, missing_teeth=2,
                         name="crank")
    assert dec.runt_teeth == (runt_tooth,)
    assert dec.edges.size == t_edges.size
    np.testing.assert_allclose(dec.edges, t_edges, atol=1.5 / fs)
    assert any("crank: tooth" in n and "is a runt pulse: it reaches only" in n for n in notes)
    trace = angle_from_pulses(dec.edges, pulses_per_rev=60, missing_teeth=2)
    d = np.angle(np.exp(1j * (trace.angle - k * TWO_PI / 60)))
    assert np.abs(d).max() < 1e-6


def test_tdc_mark_per_cycle_checked_against_the_wheel():
    """A mark every two revolutions declared per revolution: the error names what was seen and
    the setting that fits."""
    fs = 50_000.0
    t_edges, k = _train(10, start=3)
    t = np.arange(int((t_edges[-1] + 1e-3) * fs)) / fs
    wheel_v = pulse_voltage(t_edges, t, widths=3e-4, high=5.0)
    wheel = decode_wheel(wheel_v, fs=fs, pulses_per_rev=60, missing_teeth=2)
    cycle_marks = t_edges[np.mod(k, 120) == 0]
    mark_v = pulse_voltage(cycle_marks, t, widths=2.0 / fs, high=3.0)
    with pytest.raises(AnalysisError, match=r"tdc: \d of \d intervals between marks are not "
                                            r"one revolution of the wheel \(median 2 revolutions "
                                            r"between marks\); set per_cycle = true"):
        decode_marks(mark_v, fs=fs, wheel=wheel, name="tdc")
    dec = decode_marks(mark_v, fs=fs, wheel=wheel, per_cycle=True, name="tdc")
    np.testing.assert_allclose(dec.edges, cycle_marks, atol=1.0 / fs)
    assert dec.speed_ratio == 0.5
