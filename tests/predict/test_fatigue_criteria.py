"""Fatigue criteria, endurance diagram and rainflow counting against second methods."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from crankbench.predict.errors import ModelError
from crankbench.predict.fatigue import (CRITERIA, EnduranceDiagram, StressPoint, assess, endurance_limit,
                             first_cycle_yield, rainflow, safety_factor, torsional_stress)

SU, SE, SY = 700e6, 300e6, 500e6
FAILURE_LINES = {  # f(σa, σm) = 1 on the failure line (Shigley Table 6-6/6-7)
    "goodman": lambda a, m: a / SE + m / SU,
    "gerber": lambda a, m: a / SE + (m / SU) ** 2,
    "soderberg": lambda a, m: a / SE + m / SY,
    "asme-elliptic": lambda a, m: np.hypot(a / SE, m / SY),
}


@pytest.mark.parametrize("criterion", CRITERIA)
@pytest.mark.parametrize("alt, mean", [(120e6, 80e6), (60e6, 250e6), (200e6, 1e6)])
def test_safety_factor_solves_failure_line_by_root_finding(criterion, alt, mean):
    """Second method: n is the root of f(nσa, nσm) = 1 along the load line (no yield cut)."""
    f = FAILURE_LINES[criterion]
    expected = brentq(lambda n: f(n * alt, n * mean) - 1.0, 1e-6, 1e3, xtol=1e-14)
    got = safety_factor(alt, mean, ultimate=SU, endurance=SE,
                        yield_strength=SY if criterion in ("soderberg", "asme-elliptic") else None,
                        criterion=criterion)
    if criterion in ("soderberg", "asme-elliptic"):
        expected = min(expected, SY / (alt + mean))  # yield cut applies with S_y given
    assert got == pytest.approx(expected, rel=1e-10)


def test_criteria_ordering_for_tensile_mean():
    """Soderberg ≤ Goodman ≤ Gerber (Sy < Su); ASME-elliptic ≥ Soderberg."""
    alt, mean = 100e6, 150e6
    n = {c: safety_factor(alt, mean, ultimate=SU, endurance=SE, yield_strength=SY, criterion=c)
         for c in CRITERIA}
    assert n["soderberg"] <= n["goodman"] <= n["gerber"]
    assert n["asme-elliptic"] >= n["soderberg"]


def test_compressive_mean_and_yield_cut():
    n = safety_factor(100e6, -200e6, ultimate=SU, endurance=SE)
    assert n == pytest.approx(SE / 100e6)
    n = safety_factor(100e6, -200e6, ultimate=SU, endurance=SE, yield_strength=SY)
    assert n == pytest.approx(SY / 300e6)  # first-cycle yield governs
    assert first_cycle_yield(100e6, -200e6, yield_strength=SY) == pytest.approx(SY / 300e6)
    assert safety_factor(0.0, 0.0, ultimate=SU, endurance=SE) == np.inf


def test_vectorised_over_operating_points():
    alt = np.array([50e6, 100e6, 150e6])
    mean = np.array([100e6, 100e6, 100e6])
    n = safety_factor(alt, mean, ultimate=SU, endurance=SE, criterion="gerber")
    assert n.shape == (3,)
    for i in range(3):
        assert n[i] == pytest.approx(safety_factor(alt[i], mean[i], ultimate=SU, endurance=SE,
                                                   criterion="gerber"), rel=1e-14)


@pytest.mark.parametrize("criterion", CRITERIA)
def test_diagram_boundary_has_unit_safety_factor(criterion):
    d = EnduranceDiagram(SU, SE, SY, criterion)
    frame = d.to_frame(41)
    inside = frame[frame.allowable_alternating > 1e3]
    n = d.safety_factor(inside.allowable_alternating.to_numpy(), inside["mean"].to_numpy())
    np.testing.assert_allclose(n, 1.0, rtol=1e-9)
    p = d.limit_point(alternating=50e6, mean=40e6)
    assert p.alternating / p.mean == pytest.approx(50 / 40)
    assert d.safety_factor(p.alternating, p.mean) == pytest.approx(1.0)
    assert d.plot(points=[(50e6, 40e6)]).axes


def test_assess_skips_criteria_needing_yield():
    a = assess(100e6, 50e6, ultimate=SU, endurance=SE)
    assert set(a.factors) == {"goodman", "gerber"}
    assert np.isnan(a.yield_factor)
    a = assess(100e6, 50e6, ultimate=SU, endurance=SE, yield_strength=SY)
    assert a.governing == "soderberg"
    assert list(a.to_frame().criterion)[-1] == "first-cycle yield"
    assert a.plot().axes


def test_torsional_stress_closed_form():
    """τ = 16 T D / (π (D⁴ − d⁴)) for a hollow shaft."""
    p = torsional_stress(mean_torque=2000.0, vibratory_torque=800.0, diameter=0.06,
                         inner_diameter=0.03, stress_concentration=1.5)
    per = 1.5 * 16 * 0.06 / (np.pi * (0.06**4 - 0.03**4))
    assert p.mean == pytest.approx(2000.0 * per, rel=1e-14)
    assert p.alternating == pytest.approx(800.0 * per, rel=1e-14)


def test_stress_point_extremes():
    p = StressPoint.from_extremes(30e6, -30e6)
    assert (p.alternating, p.mean, p.ratio) == (30e6, 0.0, -1.0)
    assert p.to_frame().loc[0, "maximum"] == 30e6


def test_endurance_limit_rules():
    assert endurance_limit(600e6) == pytest.approx(300e6)
    assert endurance_limit(600e6, loading="axial") == pytest.approx(200e6)
    assert endurance_limit(2000e6, rule="shigley") == pytest.approx(700e6)
    assert endurance_limit(600e6, rule="shigley", loading="torsion",
                           surface_factor=0.8) == pytest.approx(0.5 * 600e6 * 0.59 * 0.8)


def test_rainflow_simple_histories():
    c = rainflow(np.sin(np.linspace(0, 2 * np.pi * 10, 2001)))
    assert c.total_cycles == pytest.approx(10.0, abs=0.5)
    assert c.largest().alternating == pytest.approx(1.0, rel=1e-4)
    assert rainflow([1.0, 1.0, 1.0]).total_cycles == 0.0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(-50, 50), min_size=2, max_size=60))
def test_rainflow_counts_every_reversal_once(values):
    """Property: the counted half-cycles equal the number of reversal intervals (each range
    of the reduced history is used exactly once), and no amplitude exceeds half the span."""
    x = np.asarray(values, dtype=float)
    c = rainflow(x)
    x = x[np.concatenate([[True], np.diff(x) != 0])]
    if x.size > 2:
        d = np.diff(x)
        x = x[np.concatenate([[True], d[1:] * d[:-1] < 0, [True]])]
    assert 2 * c.total_cycles == pytest.approx(max(x.size - 1, 0))
    if c.count.size:
        assert c.alternating.max() <= (x.max() - x.min()) / 2 + 1e-12


def test_errors_name_the_argument():
    with pytest.raises(ModelError, match=r"criterion='goodmann' is not one of .*did you mean"):
        safety_factor(1.0, 1.0, ultimate=SU, endurance=SE, criterion="goodmann")
    with pytest.raises(ModelError, match=r"criterion='soderberg' needs yield_strength"):
        safety_factor(1.0, 1.0, ultimate=SU, endurance=SE, criterion="soderberg")
    with pytest.raises(ModelError, match="alternating stress must be >= 0"):
        safety_factor(-1.0, 1.0, ultimate=SU, endurance=SE)
    with pytest.raises(ModelError, match=r"yield_strength=8e\+08 Pa must not exceed"):
        safety_factor(1.0, 1.0, ultimate=SU, endurance=SE, yield_strength=800e6)
    with pytest.raises(ModelError, match=r"^surface_factor=1.5 must be <= 1.2"):
        endurance_limit(600e6, surface_factor=1.5)
    with pytest.raises(ModelError, match="history contains 1 NaN/inf"):
        rainflow([1.0, np.nan])


def test_result_plots_return_figures():
    c = rainflow([0.0, 2.0, -1.0, 3.0, -2.0, 1.0])
    assert c.plot().axes and c.to_frame().shape[1] == 3
    assert StressPoint(1e6, 2e6).plot().axes
