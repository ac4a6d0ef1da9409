"""Hard case λ = r/l = 0.45 (an extreme short rod): exact motion and the harmonic series with
the order chosen from a tolerance, against mpmath derivatives of the exact position.

Already covered: series coefficients at λ = 0.45 against mpmath quadrature and the truncation
bound at λ = 0.45 against the exact formula — ``tests/predict/test_kinematics.py``.
"""

import mpmath as mp
import numpy as np
import pytest

from crankbench.predict import kinematics as kin

LAM = 0.45
R = 0.09
L = R / LAM
W = 3000 * 2 * np.pi / 60
ANGLES = np.linspace(0.0, 2 * np.pi, 37)


def _mp_acceleration(theta):
    """d²x/dt² of x = r cos θ + √(l² − r² sin² θ) at constant ω, by mpmath (40 digits),
    with the sign of the module: positive towards the cylinder head."""
    with mp.workdps(40):
        x = lambda t: R * mp.cos(t) + mp.sqrt(L ** 2 - (R * mp.sin(t)) ** 2)  # noqa: E731
        return float(mp.diff(x, mp.mpf(float(theta)), 2)) * W * W


def test_exact_acceleration_at_lambda_045_against_mpmath():
    ref = np.array([_mp_acceleration(t) for t in ANGLES])
    got = kin.piston_acceleration(ANGLES, crank_radius=R, rod_length=L, omega=W)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-13 * R * W * W)


@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-10, 1e-13])
def test_series_order_from_tolerance_meets_it_at_lambda_045(tol):
    """The order picked for ``tol`` meets it against mpmath (not against our own exact form),
    and the stated bound is not loose by more than 10× (it is attained at TDC)."""
    s = kin.acceleration_series(LAM, tol=tol)
    ref = np.array([_mp_acceleration(t) for t in ANGLES])
    got = s.acceleration(ANGLES, crank_radius=R, omega=W)
    err = np.abs(got - ref).max() / (R * W * W)
    assert err <= tol * (1 + 1e-6) + 2e-15
    assert s.error_bound <= tol
    assert err >= 0.1 * s.error_bound or s.error_bound < 1e-14


def test_long_series_converges_to_machine_precision_at_lambda_045():
    """N = 60 (terms ~ λ^60): the Clenshaw-summed series equals mpmath to 2e-15 r ω²."""
    ref = np.array([_mp_acceleration(t) for t in ANGLES])
    got = kin.piston_acceleration(ANGLES, crank_radius=R, rod_length=L, omega=W, max_order=60)
    np.testing.assert_allclose(got, ref, rtol=0, atol=2e-15 * R * W * W * 4)
