"""Iterative solve of the Vold–Kalman normal equations for many orders.

The joint normal equations of :mod:`analysis.vkf` are ``A z = Cᵀx`` with
``A = CᵀC + Σ_j r_j² D_pᵀD_p``: ``C`` maps the spline coefficients of the ``2K + 1`` envelope
columns (``cos``/``−sin`` of each order, and the trend) to the samples. The direct solve
factorises ``A`` as one band of half-width ``u ≈ 4(2K+1)``: O((N/m) K³) work, cubic in the
orders. Here ``A`` is never formed:

* a product ``A v`` is one pass over the samples: at each sample the model
  ``y = Σ_j b_j (W v)_j`` (``b_j`` the basis column, ``W`` the four spline weights) and then
  ``Cᵀy`` scattered back — the coupling of the orders through a sample is rank one — plus
  the smoothness term per column: O(N K) (``N`` samples at the solve rate);
* the preconditioner is the block diagonal of ``A`` over groups of :data:`GROUP` orders
  neighbouring in frequency (the trend with the lowest): each group's own normal equations
  (its ``cos``/``sin`` columns with their own smoothness weights, exact), factorised once by
  banded Cholesky: O(N K) to build, O((N/m) K) per application;
* conjugate gradients (Hestenes–Stiefel, preconditioned) start from the block solution (each
  group alone) and stop when the preconditioned residual ``sqrt(rᵀP⁻¹r / bᵀP⁻¹b)`` is below
  :data:`TOLERANCE`.

What is left between the groups is the coupling of orders in different groups inside their
filter bands, so the iteration count depends on how close the orders are relative to their
bandwidths: orders far apart converge in a few iterations whatever ``K``; a chain of
neighbours whose bands overlap (0.5 orders apart at 600 rpm with 4 Hz bands, the bench's
scaling record) needs more as the chain grows — 23 to 40 iterations from 12 to 24 orders,
so the total cost there grows as about K^1.6 (bench suite ``scaling``). Orders 2 and 2.5 only
1.5 bandwidths apart (500 rpm, 2.8 Hz bands) converge within the cap
(``tests/analysis/test_vkf_iterative.py``); after :data:`MAX_ITERATIONS` the caller falls
back to the direct solve and says so (log warning and the result's ``solver`` attr).

Accuracy: at :data:`TOLERANCE` = 1e-10 the envelopes agree with the direct solve to better
than 1e-7 of the largest envelope (``tests/analysis/test_vkf_iterative.py``, which also checks
analytic envelopes).

References
----------
M. R. Hestenes and E. Stiefel, "Methods of conjugate gradients for solving linear systems",
J. Res. NBS 49 (1952); Y. Saad, *Iterative Methods for Sparse Linear Systems*, 2nd ed., SIAM
(2003), §9.2 (preconditioned CG) and §10.1 (block-Jacobi preconditioning).
"""

from __future__ import annotations

import functools

import numpy as np

from . import _vkf_kernels

__all__ = ["solve", "MIN_ORDERS", "TOLERANCE", "MAX_ITERATIONS"]

#: relative preconditioned residual at which the iteration stops
TOLERANCE = 1e-10
#: iterations before the caller falls back to the direct banded solve
MAX_ITERATIONS = 400
#: from this many orders :func:`analysis.vkf.vold_kalman` solves iteratively (below, the
#: direct banded Cholesky is faster: bench suite ``scaling``, rows "VKF ... solver")
MIN_ORDERS = 12
#: neighbouring orders solved together in each block of the preconditioner
GROUP = 4


@functools.lru_cache(maxsize=1)
def _numba():
    """The compiled forms, or None (numba missing or ``CRANKBENCH_NO_NUMBA`` set)."""
    kern = _vkf_kernels._numba()
    if kern is None:
        return None
    from numba import njit

    factor, substitute = kern["factor"], kern["substitute"]

    @njit(cache=True, fastmath=True)
    def apply(z, basis, m, p, weights, diff, wv, out):  # pragma: no cover - compiled
        # out = A z without A: data term sample by sample (basis (N, cols): every column's
        # value at a sample contiguous), smoothness term per column
        n, cols = basis.shape
        s = wv.shape[1]
        out[:, :] = 0.0
        v = np.empty(cols)
        for i in range(n):
            g = i // m
            t = i - g * m
            for j in range(cols):
                v[j] = 0.0
            for a in range(s):
                wa = wv[t, a]
                for j in range(cols):
                    v[j] += wa * z[g + a, j]
            y = 0.0
            for j in range(cols):
                y += basis[i, j] * v[j]
            for a in range(s):
                wy = wv[t, a] * y
                for j in range(cols):
                    out[g + a, j] += wy * basis[i, j]
        for r in range(weights.shape[0]):
            for j in range(cols):
                d = 0.0
                for t in range(p + 1):
                    d += diff[t] * z[r + t, j]
                d *= weights[r, j]
                for t in range(p + 1):
                    out[r + t, j] += diff[t] * d

    return {"apply": apply, "factor": factor, "substitute": substitute}


def _weight_pattern(n: int, m: int) -> np.ndarray:
    """Spline weights (min(m, n), s) of the positions inside a knot interval (uniform knots:
    every interval has the first one's), s = 4 (1 for ``m == 1``)."""
    if m == 1:
        return np.ones((1, 1))
    return _vkf_kernels.spline_weights(min(m, n), m)[1]


def _basis(cosp, sinp, trend):
    """The columns ``cos(o_k φ)``, ``−sin(o_k φ)`` (and 1) at every sample, (N, 2K [+1])."""
    n, k = cosp.shape
    basis = np.empty((n, 2 * k + (1 if trend else 0)))
    basis[:, 0:2 * k:2] = cosp
    basis[:, 1:2 * k:2] = -sinp
    if trend:
        basis[:, -1] = 1.0
    return basis


def _groups(orders, trend, size):
    """Column groups of the preconditioner: the orders sorted by value in runs of ``size``
    (neighbours in frequency couple most), the trend with the lowest run. Each group is
    (order indices, with trend)."""
    idx = [int(i) for i in np.argsort(orders, kind="stable")]
    runs = [idx[i:i + size] for i in range(0, len(idx), size)] or [[]]
    return [(run, trend and g == 0) for g, run in enumerate(runs)]


def _group_columns(run, with_trend, cols):
    """Global column indices of a group, in the order :func:`analysis._vkf_kernels.assemble`
    lays out its sub-problem (cos, sin per order, then the trend)."""
    return [c for j in run for c in (2 * j, 2 * j + 1)] + ([cols - 1] if with_trend else [])


def _blocks(x, cosp, sinp, trend, m, n_coef, p, weights, groups):
    """Each group's own normal equations (column band form) with its right side: the
    group-diagonal blocks of ``A`` and, together, the whole ``Cᵀx``."""
    n, k = cosp.shape
    cols = 2 * k + (1 if trend else 0)
    rhs = np.empty((n_coef, cols))
    bands, columns = [], []
    for run, with_trend in groups:
        gc = _group_columns(run, with_trend, cols)
        band, r = _vkf_kernels.assemble(x, cosp[:, run], sinp[:, run], with_trend, m, n_coef,
                                        p, weights[:, gc])
        bands.append(band)
        columns.append(gc)
        rhs[:, gc] = r.reshape(n_coef, len(gc))
    return bands, columns, rhs


def solve(x, cosp, sinp, trend: bool, m: int, n_coef: int, p: int, weights, *,
          orders=None, tol: float | None = None, max_iter: int | None = None,
          group: int | None = None):
    """Spline coefficients of the joint VKF least squares by block-preconditioned conjugate
    gradients (module docstring): the problem of ``analysis._vkf_kernels.solve(*assemble(...))``.

    Parameters
    ----------
    x : ndarray (N,)
        Samples at the solve rate (any unit).
    cosp, sinp : ndarray (N, K)
        ``cos``/``sin`` of each order's phase at every sample.
    trend : bool
        With the order-0 trend column.
    m : int
        Knot spacing, samples (1: one unknown per sample).
    n_coef : int
        Spline coefficients per column.
    p : {1, 2}
        Difference order of the smoothness term.
    weights : ndarray (n_coef - p, 2K [+1])
        ``r²`` per difference row and column.
    orders : array_like (K,), optional
        The orders (only to group neighbours in the preconditioner).
    tol : float, optional
        Relative preconditioned residual to stop at (default :data:`TOLERANCE`).
    max_iter : int, optional
        Iteration cap (default :data:`MAX_ITERATIONS`).
    group : int, optional
        Orders per preconditioner block (default :data:`GROUP`).

    Returns
    -------
    coef : ndarray (n_coef, 2K [+1])
        Coefficients, column ``2k``/``2k+1`` the real/imaginary envelope of order ``k``.
    iterations : int
        Iterations used; -1 when ``tol`` was not reached (the caller solves directly).

    Raises
    ------
    analysis._vkf_kernels.NotPositiveDefinite
        A block of the preconditioner is not positive definite.

    Examples
    --------
    >>> from crankbench.analysis import _vkf_kernels
    >>> rng = np.random.default_rng(0)
    >>> phi = np.cumsum(rng.uniform(0.2, 0.6, 2000))
    >>> cosp, sinp = np.cos(np.outer(phi, [1.0, 2.0, 3.0])), np.sin(np.outer(phi, [1.0, 2.0, 3.0]))
    >>> x = rng.normal(size=2000)
    >>> weights = np.full(((2000 - 1) // 10 + 4 - 2, 7), 50.0)
    >>> z, its = solve(x, cosp, sinp, True, 10, 203, 2, weights, group=1)
    >>> band, rhs = _vkf_kernels.assemble(x, cosp, sinp, True, 10, 203, 2, weights)
    >>> direct = _vkf_kernels.solve(band, rhs).reshape(203, 7)
    >>> bool(np.abs(z - direct).max() < 1e-8 * np.abs(direct).max()), 0 < its < 50
    (True, True)
    """
    n, k = cosp.shape
    tol = TOLERANCE if tol is None else tol
    max_iter = MAX_ITERATIONS if max_iter is None else max_iter
    groups = _groups(np.arange(k) if orders is None else np.asarray(orders), trend,
                     GROUP if group is None else group)
    bands, columns, rhs = _blocks(x, cosp, sinp, trend, m, n_coef, p, weights, groups)
    diff = _vkf_kernels._DIFF[p]
    basis = _basis(cosp, sinp, trend)
    weights = np.ascontiguousarray(weights, dtype=float)
    kernels = _numba()
    if kernels is None:
        apply, precondition = _numpy_operators(rhs.shape, bands, columns, basis, m, weights,
                                               diff)
    else:
        factors = []
        for g, band in enumerate(bands):
            low = band.copy()
            if kernels["factor"](low) >= 0:
                raise _vkf_kernels.NotPositiveDefinite(f"block {g} is not positive definite")
            factors.append(low)
        wv = _weight_pattern(n, m)

        def apply(z):
            out = np.empty_like(z)
            kernels["apply"](z, basis, int(m), int(p), weights, diff, wv, out)
            return out

        def precondition(r):
            out = np.empty_like(r)
            for low, gc in zip(factors, columns):
                y = r[:, gc].ravel()
                kernels["substitute"](low, y)
                out[:, gc] = y.reshape(n_coef, len(gc))
            return out

    return _pcg(rhs, apply, precondition, tol, max_iter)


def _pcg(rhs, apply, precondition, tol, max_iter):
    """Preconditioned conjugate gradients from ``P⁻¹ rhs`` until
    ``rᵀP⁻¹r ≤ tol² · rhsᵀP⁻¹rhs``: (solution, iterations or -1)."""
    z = precondition(rhs)
    b_norm = float(np.vdot(rhs, z))
    res = rhs - apply(z)
    pr = precondition(res)
    direction = pr.copy()
    rz = float(np.vdot(res, pr))
    for it in range(max_iter + 1):
        if rz <= tol * tol * b_norm:
            return z, it
        if it == max_iter:
            break
        ad = apply(direction)
        alpha = rz / float(np.vdot(direction, ad))
        z += alpha * direction
        res -= alpha * ad
        pr = precondition(res)
        rz_new = float(np.vdot(res, pr))
        direction *= rz_new / rz
        direction += pr
        rz = rz_new
    return z, -1


def _numpy_operators(shape, bands, columns, basis, m, weights, diff):
    """numpy/SciPy twins of the compiled ``A v`` and ``P⁻¹ r`` (LAPACK band Cholesky)."""
    from scipy.linalg import cho_solve_banded, cholesky_banded

    n = basis.shape[0]
    n_coef, cols = shape
    try:
        factors = [cholesky_banded(np.ascontiguousarray(b.T), lower=True, check_finite=False)
                   for b in bands]
    except np.linalg.LinAlgError as exc:
        raise _vkf_kernels.NotPositiveDefinite(str(exc)) from None
    q, w, _ = _vkf_kernels.spline_weights(n, m)
    starts = np.flatnonzero(np.diff(q, prepend=-1))
    groups = starts.shape[0]
    rows = weights.shape[0]

    def apply(z):
        v = sum(w[:, a:a + 1] * z[q + a] for a in range(w.shape[1]))
        y = np.einsum("ij,ij->i", basis, v)
        out = np.zeros_like(z)
        for a in range(w.shape[1]):
            out[a:a + groups] += np.add.reduceat((w[:, a] * y)[:, None] * basis, starts, axis=0)
        d = sum(c * z[t:t + rows] for t, c in enumerate(diff)) * weights
        for t, c in enumerate(diff):
            out[t:t + rows] += c * d
        return out

    def precondition(r):
        out = np.empty_like(r)
        for factor, gc in zip(factors, columns):
            out[:, gc] = cho_solve_banded((factor, True), r[:, gc].ravel(),
                                          check_finite=False).reshape(n_coef, len(gc))
        return out

    return apply, precondition
