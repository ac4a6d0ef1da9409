"""Independent reference frequencies of a chain: bisection on Sturm counts in extended precision.

The count of eigenvalues ω² < σ of ``K x = ω² J x`` for a chain comes from the LDLᵀ pivots of
``K − σJ`` in series-spring form (a Holzer-type recursion from the first mass,
``q₁ = k₀ − σJ₁``, ``q_i = k_{i−1} q_{i−1} / (q_{i−1} + k_{i−1}) − σJ_i``, pivots
``q_i + k_i``; Sylvester's law of inertia), evaluated in numpy ``longdouble`` (80-bit on x86,
eps ≈ 1.1e-19). The series-spring form has no cancellation between large stiffnesses, so the
counts stay exact to within a few extended ulps whatever the stiffness and inertia ratios. It
shares nothing with the solvers it checks (no bidiagonal factor, no LAPACK).
"""

from __future__ import annotations

import numpy as np

__all__ = ["sturm_count", "chain_reference", "EXTENDED"]

#: True where numpy's long double is wider than double (the reference needs it)
EXTENDED = bool(np.finfo(np.longdouble).eps < 1e-18)


def sturm_count(inertias, stiffnesses, sigma, *, grounded: bool) -> np.ndarray:
    """Number of eigenvalues ω² < σ of a chain, for each σ (rad²/s², vector).

    Examples
    --------
    >>> n = 20   # uniform free chain: ω_k = 2√(k/J) sin(kπ/2n), k = 0..n-1
    >>> w = 2 * np.sqrt(3.0) * np.sin(np.arange(n) * np.pi / (2 * n))
    >>> sturm_count(np.ones(n), np.full(n - 1, 3.0), (w[5] * (1 + 1e-12)) ** 2,
    ...             grounded=False).item()
    6
    """
    j = np.asarray(inertias, np.longdouble)
    k = np.asarray(stiffnesses, np.longdouble)
    if grounded:
        k0, k = k[0], k[1:]
    else:
        k0 = np.longdouble(0)
    sigma = np.atleast_1d(np.asarray(sigma, np.longdouble))
    count = np.zeros(sigma.shape, int)
    q = k0 - sigma * j[0]
    tiny = np.finfo(np.longdouble).tiny
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i in range(1, j.size):
            p = q + k[i - 1]
            p = np.where(p == 0, -tiny, p)
            count += p < 0
            q = k[i - 1] * q / p - sigma * j[i]
    count += q < 0
    return count


def chain_reference(inertias, stiffnesses, *, grounded: bool, start,
                    rtol: float = 1e-17) -> np.ndarray:
    """Every ω (rad/s, ascending) of a chain by bisection on :func:`sturm_count`.

    Parameters
    ----------
    start : ndarray
        Approximate ω from any method: brackets start at ±1e-6 relative, and one the counts
        reject restarts from [0, Gershgorin bound], so ``start`` only saves iterations.
    rtol : float
        Relative bracket width at which bisection stops.

    Returns
    -------
    ndarray
        ω, rad/s; a free chain's rigid-body value is 0.
    """
    if not EXTENDED:
        raise RuntimeError("numpy's long double is not wider than double on this platform")
    j = np.asarray(inertias, float)
    k = np.asarray(stiffnesses, float)
    n = j.size
    first = 0 if grounded else 1
    target = np.arange(first, n)          # eigenvalues below the i-th (counting the 0)
    w = np.abs(np.asarray(start, np.longdouble)[first:])
    lo = (w * (1 - np.longdouble(1e-6))) ** 2
    hi = (w * (1 + np.longdouble(1e-6))) ** 2
    # a bracket the counts reject restarts from [0, Gershgorin bound of J⁻¹K]
    row = np.zeros(n)
    row[:-1] += 2 * k[-(n - 1):] if n > 1 else 0.0
    row[1:] += 2 * k[-(n - 1):] if n > 1 else 0.0
    if grounded:
        row[0] += 2 * k[0]
    top = np.longdouble(np.max(row / j)) * (1 + np.longdouble(1e-12))
    bad = ((sturm_count(j, k, lo, grounded=grounded) > target)
           | (sturm_count(j, k, hi, grounded=grounded) <= target))
    lo = np.where(bad, 0, lo)
    hi = np.where(bad, top, hi)
    while np.any(hi - lo > rtol * hi):  # (a zero-width bracket stops: hi - lo = 0)
        mid = (lo + hi) / 2
        left = sturm_count(j, k, mid, grounded=grounded) > target
        hi = np.where(left, mid, hi)
        lo = np.where(left, lo, mid)
    omega = np.sqrt((lo + hi) / 2).astype(float)
    return np.concatenate([np.zeros(first), omega])
