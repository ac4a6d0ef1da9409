"""Mode shapes of badly scaled chains are as accurate as their frequencies.

Reference: eigenvectors of J^{-1/2} K J^{-1/2} at 60 digits (mpmath.eigsy), an independent
route from the LAPACK bidiagonal SVD the solver uses.
"""

import mpmath
import numpy as np
import pytest

from crankbench.predict.torsion import chain


def _mp_shapes(j, k, grounded):
    n = j.size
    with mpmath.workdps(60):
        r = [1 / mpmath.sqrt(mpmath.mpf(float(v))) for v in j]
        h = mpmath.zeros(n, n)
        springs = [(-1, 0)] if grounded else []
        springs += [(i, i + 1) for i in range(n - 1)]
        for (a, b), kv in zip(springs, k):
            kv = mpmath.mpf(float(kv))
            h[b, b] += kv * r[b] ** 2
            if a >= 0:
                h[a, a] += kv * r[a] ** 2
                h[a, b] -= kv * r[a] * r[b]
                h[b, a] -= kv * r[a] * r[b]
        ev, q = mpmath.eigsy(h)
        order = sorted(range(n), key=lambda i: ev[i])
        return np.array([[float(q[i, c] * r[i]) for c in order] for i in range(n)])


@pytest.mark.parametrize("grounded", [False, True])
def test_shapes_at_stiffness_ratio_1e12_inertia_ratio_1e8_match_60_digit_reference(grounded):
    rng = np.random.default_rng(11)
    n = 16
    j = 10 ** rng.uniform(0, 8, n)
    j[[0, 1]] = [1.0, 1e8]
    k = 10 ** rng.uniform(0, 12, n - (0 if grounded else 1))
    k[[0, 1]] = [1.0, 1e12]
    x = chain(j, k).mode_shapes().shapes
    ref = _mp_shapes(j, k, grounded)
    sign = np.sign(np.sum(ref * j[:, None] * x, axis=0))
    err = np.sqrt(np.sum((x * sign - ref) ** 2 * j[:, None], axis=0))  # J-norm per mode
    assert err.max() < 1e-12
    np.testing.assert_allclose(x.T @ (j[:, None] * x), np.eye(n), atol=1e-13)
