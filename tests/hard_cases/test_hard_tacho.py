"""Hard case: 5 % of the tacho pulses missing at random during a fast run-up (pulses lost in
pairs included). Repair must restore the exact speed law and, for a missing-tooth wheel, the
angle reference. Truth: exact edge times of θ(t) = ω₀t + αt²/2.

Already covered: 3 % missing at steady speed (``tests/reliability/test_bad_signals.py``), two
dropouts plus two spurious pulses (``tests/measure/test_tacho.py``), light random damage
(``tests/reliability/test_fuzz_pulses.py``).
"""

import numpy as np
import pytest

from crankbench.measure.tacho import angle_from_pulses, count_pitches, speed_from_pulses

TWO_PI = 2 * np.pi
W0, ALPHA = 100.0, 20 * TWO_PI    # 955 rpm, +1200 rpm/s


def _train(ppr, missing, seed, revs=60):
    k = np.arange(1, revs * ppr)
    if missing:
        k = k[(k % ppr) < ppr - missing]
    theta = k * TWO_PI / ppr
    t = (-W0 + np.sqrt(W0 ** 2 + 2 * ALPHA * theta)) / ALPHA
    keep = np.random.default_rng(seed).random(t.size) > 0.05
    keep[[0, -1]] = True           # losses before the first / after the last edge are invisible
    return t[keep], theta[keep], int((~keep).sum())


@pytest.mark.parametrize("ppr, missing", [(60, 0), (60, 2), (36, 1)])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_five_percent_missing_pulses_repaired_to_exact_speed(ppr, missing, seed):
    edges, _, lost = _train(ppr, missing, seed)
    assert lost > 0.04 * (edges.size + lost)
    pc = count_pitches(edges, pulses_per_rev=ppr, missing_teeth=missing)
    assert pc.filled == lost
    trace = speed_from_pulses(edges, pulses_per_rev=ppr, missing_teeth=missing)
    truth = W0 + ALPHA * trace.time
    assert np.abs(trace.omega / truth - 1).max() < 1e-9


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_five_percent_missing_pulses_keep_the_60_minus_2_angle_reference(seed):
    """The first tooth after the gap is angle 0: every kept edge's angle equals its true
    angle (whole revolutions aside) within 1e-9 rad."""
    edges, theta, _ = _train(60, 2, seed)
    trace = angle_from_pulses(edges, pulses_per_rev=60, missing_teeth=2)
    assert trace.reference == "gap"
    d = np.angle(np.exp(1j * (trace.angle - theta)))
    assert np.abs(d).max() < 1e-9
    # cumulative angle advances exactly as the truth between the first and the last edge
    assert trace.angle[-1] - trace.angle[0] == pytest.approx(theta[-1] - theta[0], abs=1e-9)
