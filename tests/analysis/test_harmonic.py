"""n-ordinate harmonic analysis: exactness, aliasing, the 12-ordinate schedule."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crankbench.analysis.harmonic import harmonics, ordinate_schedule, runge12
from crankbench.predict.errors import AnalysisError


@settings(max_examples=40, deadline=None)
@given(n=st.integers(3, 64), seed=st.integers(0, 2**31))
def test_exact_for_trig_polynomials_below_half_n(n, seed):
    """Coefficients of a random trigonometric polynomial of degree < n/2 are returned exactly."""
    rng = np.random.default_rng(seed)
    degree = (n - 1) // 2
    a = rng.normal(size=degree + 1)
    b = rng.normal(size=degree + 1)
    b[0] = 0.0
    theta = 2 * np.pi * np.arange(n) / n
    k = np.arange(degree + 1)[:, None]
    y = (a[:, None] * np.cos(k * theta) + b[:, None] * np.sin(k * theta)).sum(axis=0)
    h = harmonics(y, n)
    assert np.allclose(h.a[: degree + 1], a, atol=1e-12)
    assert np.allclose(h.b[: degree + 1], b, atol=1e-12)
    assert np.allclose(h.evaluate(theta), y, atol=1e-11)


def test_aliasing_of_a_harmonic_at_or_above_half_n():
    """Harmonic m = n - 2 of unit amplitude is read as harmonic 2: the method's stated error."""
    n = 12
    theta = 2 * np.pi * np.arange(n) / n
    h = harmonics(np.cos(10 * theta), n)
    assert h.a[2] == pytest.approx(1.0)


def test_amplitude_and_phase_convention_matches_order_track():
    theta = 2 * np.pi * np.arange(36) / 36
    h = harmonics(lambda th: 2.5 * np.cos(3 * th + 0.4), 36)
    assert h.amplitude[3] == pytest.approx(2.5)
    assert h.phase[3] == pytest.approx(0.4)
    assert np.allclose(harmonics(2.5 * np.cos(3 * theta + 0.4)).a, h.a)


def test_chart_reading_every_mth_sample():
    fine = np.cos(2 * np.pi * np.arange(360) / 360 * 2)
    h = harmonics(fine, 24)
    assert h.n == 24 and h.a[2] == pytest.approx(1.0)


def test_runge_12_ordinate_schedule_equals_direct_sums():
    """The textbook schedule (folded sums, multipliers 1/2, √3/2) equals the direct sums
    a_k = (2/n) Σ y_j cos kθ_j evaluated independently here."""
    rng = np.random.default_rng(3)
    y = rng.normal(size=12)
    h = runge12(y)
    theta = 2 * np.pi * np.arange(12) / 12
    for k in range(1, 6):
        assert h.a[k] == pytest.approx(2 / 12 * np.sum(y * np.cos(k * theta)), abs=1e-14)
        assert h.b[k] == pytest.approx(2 / 12 * np.sum(y * np.sin(k * theta)), abs=1e-14)
    assert h.a[0] == pytest.approx(y.mean())
    assert h.a[6] == pytest.approx(np.sum(y * (-1) ** np.arange(12)) / 12)


def test_schedule_table_multipliers():
    tab = ordinate_schedule(12)
    assert set(np.round(np.abs(tab.drop(columns="angle_deg").values.ravel()), 4)) <= {
        0.0, 0.5, 0.866, 1.0}
    assert list(tab.angle_deg[:3]) == [0.0, 30.0, 60.0]


def test_result_frame_and_plot():
    h = harmonics(np.cos(2 * np.pi * np.arange(8) / 8), 8)
    assert list(h.to_frame().columns) == ["order", "a", "b", "amplitude", "phase_deg"]
    fig = h.plot()
    assert fig.axes


def test_errors():
    with pytest.raises(AnalysisError, match="y has 10 values; give exactly n=12"):
        harmonics(np.ones(10), 12)
    with pytest.raises(AnalysisError, match=r"max_order=7 exceeds n//2=6"):
        harmonics(np.ones(12), 12, max_order=7)
    with pytest.raises(AnalysisError, match="y contains 1 NaN"):
        harmonics(np.r_[np.ones(11), np.nan])
    with pytest.raises(AnalysisError, match="runge12 needs exactly 12 ordinates, got 11"):
        runge12(np.ones(11))
