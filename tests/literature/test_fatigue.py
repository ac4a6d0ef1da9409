"""Fatigue: worked examples and formulas of the source texts at their printed precision.

Main source: Shi Zhiqing, *Applied Mechanics vol. 2: Engine Dynamics* (Commercial Press),
pre-reading 1 "simple varying stress", pp. 1-11 (seed file 002): eq. (1)-(5b), exercises and
the worked shaft example (S.A.E. 1055 shaft transmitting a torque varying between
+80,000 and −40,000 lb-in). Stresses are in psi there; the functions are unit-agnostic.
"""

import numpy as np
import pytest

from crankbench.predict.fatigue import (EnduranceDiagram, StressPoint, endurance_limit, max_stress_at_ratio,
                             rainflow, shear_strength)

PSI = 6894.757293168  # Pa


def test_eq1_endurance_limits():
    """Eq. (1): reversed bending S_e = S_u/2; reversed push-pull 2/3 of it (S.A.E. 3125 steel,
    S_u = 100,000 psi, push-pull endurance S_u/3, §(4))."""
    su = 100_000 * PSI
    assert endurance_limit(su) / PSI == pytest.approx(50_000)
    assert endurance_limit(su, loading="axial") / PSI == pytest.approx(100_000 / 3)


def test_worked_shaft_example_first_method():
    """Worked example, first method: q_e = 0.55 × ½ × 78,500 "= 22,000 psi" (printed, 2
    significant figures); r = −40,000/80,000 = −½; eq. (2a) q_r = 4/(3½) × 22,000
    "= 25,000 psi"; eq. (2b) q_r = 5/4 × 22,000 "= 27,500 psi"."""
    qe = endurance_limit(78_500 * PSI, loading="torsion") / PSI
    assert qe == pytest.approx(22_000, rel=0.02)  # 21,588 → printed 22,000
    point = StressPoint.from_extremes(80_000.0, -40_000.0)  # torque, lb-in
    assert point.ratio == -0.5
    assert max_stress_at_ratio(point.ratio, endurance=22_000.0) == pytest.approx(25_000, rel=0.01)
    assert max_stress_at_ratio(point.ratio, endurance=22_000.0, form="2b") == pytest.approx(
        27_500, rel=1e-12)


def test_worked_shaft_example_second_method_endurance_diagram():
    """Worked example, second method: q_u = 0.6 × 78,500 "= 47,000", q_yp = 0.6 × 44,000
    "= 26,400"; on the straight-line shear endurance diagram the load line of
    T_m = 20,000, T_a = 60,000 lb-in gives q_a "= 20,000 psi" and q_m "= 6,400 psi"
    (read off the drawing: q_m to 1 %, q_a to the 5 % a graph reading allows)."""
    assert shear_strength(78_500) == pytest.approx(47_000, rel=0.005)
    assert shear_strength(44_000) == pytest.approx(26_400, rel=1e-12)
    diagram = EnduranceDiagram(ultimate=47_000.0, endurance=22_000.0, yield_strength=26_400.0)
    limit = diagram.limit_point(alternating=60_000.0, mean=20_000.0)
    assert limit.mean == pytest.approx(6_400, rel=0.01)
    assert limit.alternating == pytest.approx(20_000, rel=0.05)
    assert limit.maximum < 26_400  # below the yield line: the straight line governs


def test_eq5_straight_line_and_parabola():
    """Eq. (5a) S_a = S_e(1 − S_m/S_u) and (5b) S_a = S_e(1 − S_m²/S_u²)."""
    su, se = 100_000.0, 100_000.0 / 3
    sm = np.array([0.0, 25_000.0, 50_000.0, 100_000.0])
    goodman = EnduranceDiagram(su, se, criterion="goodman").allowable_alternating(sm)
    gerber = EnduranceDiagram(su, se, criterion="gerber").allowable_alternating(sm)
    np.testing.assert_allclose(goodman, se * (1 - sm / su), rtol=1e-14)
    np.testing.assert_allclose(gerber, se * (1 - (sm / su) ** 2), rtol=1e-14)


def test_exercises_2_and_3_ratio_formulas():
    """Exercise 2 (Illinois Engineering Station: push-pull endurance = 2/3 of bending = S_u/3):
    S'_r = S_u/(2 − r) (3a) and (2 + r) S_u / 3 (3b). Exercise 3 (push-pull = 0.6 of bending):
    S'_r = 0.35 (1.86 + r) S_u, printed to 3 significant figures."""
    su = 1.0
    for r in (-1.0, -0.5, 0.0, 0.5, 1.0):
        assert max_stress_at_ratio(r, endurance=su / 3, ultimate=su) == pytest.approx(
            su / (2 - r), rel=1e-14)
        assert max_stress_at_ratio(r, endurance=su / 3, ultimate=su, form="2b") == pytest.approx(
            (2 + r) * su / 3, rel=1e-14)
        assert max_stress_at_ratio(r, endurance=0.3 * su, ultimate=su, form="2b") == (
            pytest.approx(0.35 * (1.86 + r) * su, abs=0.002))


def test_leaf_spring_example_repeating_stress():
    """Exercise 5 (leaf spring, S_u = 200,000 psi): a stress varying between a maximum and 0
    (r = 0) endures 2/3 S_u by eq. (2a)."""
    assert max_stress_at_ratio(0.0, endurance=100_000.0) == pytest.approx(2 / 3 * 200_000,
                                                                          rel=1e-14)


def test_astm_e1049_rainflow_example():
    """ASTM E1049-85 (2017) §5.4.4, Fig. 6 example history −2, 1, −3, 5, −1, 3, −4, 4, −2:
    ranges 3 (½ cycle), 4 (1½), 6 (½), 8 (1), 9 (½) — the standard's Table."""
    c = rainflow([-2, 1, -3, 5, -1, 3, -4, 4, -2])
    counted = {}
    for amp, n in zip(2 * c.alternating, c.count):
        counted[float(amp)] = counted.get(float(amp), 0.0) + float(n)
    assert counted == {3.0: 0.5, 4.0: 1.5, 6.0: 0.5, 8.0: 1.0, 9.0: 0.5}
