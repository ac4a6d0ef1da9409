"""The series order chosen for a tolerance is the lowest even order whose bound meets it.

Second route: a brute-force search calling truncation_bound order by order."""

import pytest

from crankbench.predict.kinematics import order_for_tolerance, truncation_bound


@pytest.mark.parametrize("lam", [0.05, 0.25, 0.45])
@pytest.mark.parametrize("tol", [1e-2, 1e-3, 1e-6, 1e-10, 1e-13, 1e-15])
def test_order_for_tolerance_matches_brute_force(lam, tol):
    brute = next(n for n in range(2, 200, 2) if truncation_bound(lam, n) <= tol)
    assert order_for_tolerance(lam, tol) == brute
