"""Structured eigen-solvers for torsional systems: chains by bidiagonal SVD, trees by bisection.

All solvers take the *undamped* system ``K x = ω² J x`` with J > 0 diagonal and K the weighted
Laplacian of the spring graph (plus grounded springs), and return ω (rad/s, ascending).

Chains (``chain_frequencies``)
    Grounded at one end: ``K = Bᵀ diag(k) B`` with B square lower bidiagonal, so ω are the
    singular values of the bidiagonal ``A = diag(√k) B J^{-1/2}``.
    Free at both ends: A is (n−1)×n and has the rigid-body mode in its null space. We remove it
    analytically: ``A Aᵀ = diag(√k) M diag(√k)`` with ``M = B J⁻¹ Bᵀ`` tridiagonal, whose Cholesky
    factor has the closed form ``L[i,i] = √(S_{i+1}/(S_i J_{i+1}))``,
    ``L[i+1,i] = −√(S_i/(S_{i+1} J_{i+1}))`` with ``S_i = J_1+…+J_i`` (sums of positive numbers,
    no cancellation). The n−1 elastic ω are then the singular values of the square bidiagonal
    ``diag(√k) L``, and the rigid-body frequency is exactly 0.
    Every bidiagonal entry is a product/quotient of the data, so it carries only a few ulps of
    relative error; dqds (our compiled kernel, :mod:`predict.torsion._dqds`, from 64 masses;
    LAPACK ``dlasq2`` below that or on any doubt) then gives every ω to high relative accuracy
    (bound ≈ c·n·eps, measured ≤ 1e-14 for stiffness ratios 1e12 and inertia ratios 1e8).

Trees (``tree_frequencies``)
    The same factor ``A = diag(√k) B J^{-1/2}`` with B the tree's incidence matrix has an
    acyclic bipartite graph, so its singular values are determined to high relative accuracy and
    Sturm counts of the zero-diagonal augmented matrix ``[[0, A], [Aᵀ, 0]]`` are computed
    accurately by leaf-to-root elimination (Demmel & Gragg, Linear Algebra Appl. 185 (1993) 203).
    We bisect all ω at once (vectorised over the eigenvalues), starting from brackets found by
    a dense scaled symmetric eigensolver; exactly repeated frequencies (symmetric branches) come
    out as equal values. Cost O(n·m·iterations), fine for a few hundred masses.

Anything else (closed loops of springs) falls back to ``scipy.linalg.eigh`` on the scaled
symmetric matrix ``J^{-1/2} K J^{-1/2}`` (normwise accuracy, stated as such in the result).
"""

from __future__ import annotations

import numpy as np

from ._lapack import bidiagonal_svd, qd_singular_values

__all__ = ["chain_frequencies", "chain_modes", "tree_frequencies", "dense_modes", "EPS"]

EPS = np.finfo(float).eps


def _free_chain_factor(inertias: np.ndarray, stiffnesses: np.ndarray):
    """Diagonal and off-diagonal of the square (n−1) upper bidiagonal whose singular values are
    the elastic ω of a free-free chain (transpose of ``diag(√k) L``, see module docstring)."""
    q, e2 = _free_chain_squares(inertias, stiffnesses)
    return np.sqrt(q), np.sqrt(e2)


def _free_chain_squares(inertias: np.ndarray, stiffnesses: np.ndarray):
    """Squares of :func:`_free_chain_factor`'s entries (the qd array dqds works on), formed
    from the data by products and quotients only: ``k_i S_{i+1} / (S_i J_{i+1})`` and
    ``k_{i+1} S_i / (S_{i+1} J_{i+1})``."""
    s = np.cumsum(inertias)
    q = stiffnesses * s[1:]
    q /= s[:-1] * inertias[1:]
    e2 = stiffnesses[1:] * s[:-2]
    e2 /= s[1:-1] * inertias[1:-1]
    return q, e2


def _grounded_chain_factor(inertias: np.ndarray, stiffnesses: np.ndarray):
    """Square bidiagonal ``diag(√k) B J^{-1/2}`` (transposed to upper) of a chain grounded at
    its first mass: stiffnesses[0] ties mass 0 to ground, stiffnesses[i] ties i−1 to i."""
    diag = np.sqrt(stiffnesses / inertias)
    off = np.sqrt(stiffnesses[1:] / inertias[:-1])
    return diag, off


def chain_frequencies(inertias, stiffnesses, *, grounded: bool) -> np.ndarray:
    """Natural circular frequencies ω (rad/s, ascending) of a chain, to high relative accuracy.

    Parameters
    ----------
    inertias : ndarray, shape (n,)
        Mass moments of inertia, kg·m², > 0.
    stiffnesses : ndarray
        Torsional stiffnesses, N·m/rad, > 0: shape (n−1,) for a free chain, (n,) for a chain
        whose first stiffness ties the first mass to ground.
    grounded : bool
        Which of the two layouts.

    Returns
    -------
    ndarray
        ω, rad/s, ascending; for a free chain the first value is exactly 0.0.

    Notes
    -----
    dqds (:func:`predict.torsion._lapack.qd_singular_values`: the compiled kernel from 64
    masses, LAPACK ``dlasq2`` otherwise) runs on the squared bidiagonal entries formed straight
    from the data, so no square root is taken before the solve.
    """
    inertias = np.asarray(inertias, float)
    stiffnesses = np.asarray(stiffnesses, float)
    if grounded:
        return qd_singular_values(stiffnesses / inertias, stiffnesses[1:] / inertias[:-1])[::-1]
    n = inertias.size
    out = np.empty(n)
    out[0] = 0.0
    if n > 1:
        out[1:] = qd_singular_values(*_free_chain_squares(inertias, stiffnesses))[::-1]
    return out


#: chains up to this many masses get relatively accurate (dbdsqr) mode shapes; O(n³) above
SVD_MODES_MAX = 400


def _chain_singular_vectors(rj: np.ndarray, sk: np.ndarray, grounded: bool) -> np.ndarray:
    """Orthonormal eigenvectors ``y`` of ``J^{-1/2} K J^{-1/2}``, ascending, from the SVD of the
    bidiagonal ``G = diag(√k) B J^{-1/2}`` (``rj`` = J^{-1/2}, ``sk`` = √k)."""
    if grounded:
        # (Bx)_0 = x_0, (Bx)_i = x_i − x_{i−1}: G is lower bidiagonal, Gᵀ upper; the wanted
        # vectors (right singular vectors of G) are the left singular vectors of Gᵀ
        s, u, _ = bidiagonal_svd(sk * rj, -sk[1:] * rj[:-1])
        y = u
    else:
        # (Bx)_i = x_{i+1} − x_i for the n−1 springs; a zero last row makes G square (n×n
        # upper bidiagonal) and gives the rigid-body mode an exactly zero singular value
        d = np.zeros(rj.size)
        d[:-1] = -sk * rj[:-1]
        s, _, vt = bidiagonal_svd(d, sk * rj[1:])
        y = vt.T
    return y[:, np.argsort(s, kind="stable")]


def chain_modes(inertias, stiffnesses, *, grounded: bool, omega=None):
    """Mode shapes of a chain, columns ordered like :func:`chain_frequencies`.

    Up to :data:`SVD_MODES_MAX` masses the shapes are the singular vectors of the bidiagonal
    factor ``G = diag(√k) B J^{-1/2}`` (``K = Bᵀ diag(k) B``, ``GᵀG = J^{-1/2} K J^{-1/2}``) by
    LAPACK ``dbdsqr`` (Demmel-Kahan zero-shift QR), whose vectors are accurate relative to the
    *relative* gaps: at stiffness ratio 1e12 and inertia ratio 1e8 every shape is within ~1e-14
    (J-norm) of a 60-digit reference, where MRRR on the scaled tridiagonal is off by 3e-5 (free)
    or entirely wrong (grounded). It costs O(n³) (0.2 s at 500 masses), so longer chains use
    inverse iteration on the Golub-Kahan form of the same factor at the dqds frequencies
    (:func:`predict.torsion.subset.chain_shapes`, O(n²)): within ~5e-14 of ``dbdsqr`` at 1000
    to 1500 masses and ratios up to 1e12 / 1e8, where MRRR (``dstemr``) on the scaled
    tridiagonal is off by 1e-6 to 1.4 (tests/hard_cases/test_hard_torsion.py); about twice
    MRRR's time. Shapes are mapped back by ``x = J^{-1/2} y`` (``xᵀ J x = 1``); the rigid-body
    mode of a free chain is set exactly to the constant vector.

    Parameters
    ----------
    omega : ndarray, optional
        The chain's frequencies (rad/s, :func:`chain_frequencies`) when already known.

    Returns
    -------
    ndarray, shape (n, n)
    """
    inertias = np.asarray(inertias, float)
    stiffnesses = np.asarray(stiffnesses, float)
    n = inertias.size
    if n > SVD_MODES_MAX:
        from .subset import chain_shapes

        if omega is None:
            omega = chain_frequencies(inertias, stiffnesses, grounded=grounded)
        return chain_shapes(inertias, stiffnesses, omega, grounded=grounded)
    rj = 1.0 / np.sqrt(inertias)
    vectors = (np.ones((1, 1)) if n == 1
               else _chain_singular_vectors(rj, np.sqrt(stiffnesses), grounded))
    x = vectors * rj[:, None]
    if not grounded:
        x[:, 0] = 1.0 / np.sqrt(inertias.sum())
    return x


def dense_modes(inertias: np.ndarray, stiffness: np.ndarray):
    """ω (rad/s) and mass-normalised modes of ``K x = ω² J x`` by dense scaled ``eigh``.

    Normwise accuracy: |Δω²| ≲ n·eps·‖J^{-1/2} K J^{-1/2}‖.
    """
    import scipy.linalg as sl

    rj = 1.0 / np.sqrt(inertias)
    h = stiffness * rj[:, None] * rj[None, :]
    lam, y = sl.eigh(h)
    lam = np.clip(lam, 0.0, None)
    return np.sqrt(lam), y * rj[:, None]


# --------------------------------------------------------------------------- trees --------

def _elimination_order(n: int, parent: np.ndarray) -> np.ndarray:
    """Post-order (children before parents) of a forest given parent indices (−1 = root)."""
    children = [[] for _ in range(n)]
    roots = []
    for v in range(n):
        (roots if parent[v] < 0 else children[parent[v]]).append(v)
    order = []
    stack = [(r, False) for r in roots]
    while stack:
        v, done = stack.pop()
        if done:
            order.append(v)
            continue
        stack.append((v, True))
        stack.extend((c, False) for c in children[v])
    return np.asarray(order, int)


def _augmented_tree(inertias, edges_a, edges_b, stiffnesses):
    """Vertices/edges of the acyclic augmented matrix [[0, A], [Aᵀ, 0]].

    Vertices 0..n−1 are masses, n..n+m−1 are springs; spring e couples to mass a with weight
    −√(k/J_a) and to mass b with √(k/J_b) (a = −1: grounded spring, single coupling).
    Returns (parent, weight) of a spanning forest rooted anywhere, weight = coupling value.
    """
    n = inertias.size
    m = stiffnesses.size
    nv = n + m
    adj = [[] for _ in range(nv)]
    for e in range(m):
        a, b, k = int(edges_a[e]), int(edges_b[e]), stiffnesses[e]
        if a >= 0:
            w = np.sqrt(k / inertias[a])
            adj[a].append((n + e, w))
            adj[n + e].append((a, w))
        w = np.sqrt(k / inertias[b])
        adj[b].append((n + e, w))
        adj[n + e].append((b, w))
    parent = np.full(nv, -1)
    weight = np.zeros(nv)
    seen = np.zeros(nv, bool)
    for root in range(nv):
        if seen[root]:
            continue
        seen[root] = True
        stack = [root]
        while stack:
            v = stack.pop()
            for u, w in adj[v]:
                if not seen[u]:
                    seen[u] = True
                    parent[u] = v
                    weight[u] = w
                    stack.append(u)
    return parent, weight


def _sturm_counts(order, parent, weight, shifts):
    """Number of eigenvalues < shift of the zero-diagonal acyclic symmetric matrix, per shift.

    Leaf-to-root LDLᵀ: pivot_v = −σ − Σ_children w_c² / pivot_c; count negative pivots.
    """
    nv = parent.size
    acc = np.zeros((nv, shifts.size))
    count = np.zeros(shifts.size, int)
    tiny = np.finfo(float).tiny
    with np.errstate(over="ignore", invalid="ignore"):
        for v in order:
            piv = -shifts - acc[v]
            piv = np.where(piv == 0.0, -tiny, piv)
            count += piv < 0
            p = parent[v]
            if p >= 0:
                acc[p] += weight[v] ** 2 / piv
    return count


def tree_frequencies(inertias, edges_a, edges_b, stiffnesses, *, rtol: float = 4 * EPS,
                     estimate=None) -> np.ndarray:
    """ω (rad/s, ascending) of a tree-shaped system by bisection on Sturm counts of the
    zero-diagonal augmented factor matrix (high relative accuracy, repeated values exact).

    Parameters
    ----------
    inertias : ndarray (n,)
        kg·m².
    edges_a, edges_b : ndarray of int
        Spring ends; ``edges_a = −1`` ties ``edges_b`` to ground. The spring graph plus ground
        must be a forest (no closed loop).
    stiffnesses : ndarray
        N·m/rad.
    rtol : float
        Relative width at which bisection stops (default 4 eps).
    estimate : ndarray, optional
        Approximate ω (ascending, length n) to start the brackets from.

    Returns
    -------
    ndarray
        ω, rad/s, ascending; free components contribute exact zeros.
    """
    inertias = np.asarray(inertias, float)
    n = inertias.size
    m = len(stiffnesses)
    parent, weight = _augmented_tree(inertias, edges_a, edges_b, np.asarray(stiffnesses, float))
    order = _elimination_order(n + m, parent)
    # eigenvalues of the augmented matrix: ±σ_i (min(n, m) pairs) and |n − m| exact zeros
    n_zero = max(n - m, 0)
    n_elastic = n - n_zero
    target = np.arange(n_elastic)  # want the (k+1)-th positive singular value, k = 0..
    # bracket: count(σ) − (n_neg + n_zero) = number of positive σ_i below σ
    neg = n_elastic
    if estimate is None:
        # Gershgorin bound on the augmented matrix
        row = np.zeros(n + m)
        has = parent >= 0
        np.add.at(row, np.flatnonzero(has), weight[has])
        np.add.at(row, parent[has], weight[has])
        lo = np.zeros(n_elastic)
        hi = np.full(n_elastic, row.max() * (1 + 1e-12) + 1e-300)
    else:
        est = np.asarray(estimate, float)[n_zero:]
        lo = est * (1 - 1e-6)
        hi = est * (1 + 1e-6) + 1e-300
        for _ in range(60):  # widen until the bracket is valid
            below_lo = _sturm_counts(order, parent, weight, lo) - neg - n_zero
            below_hi = _sturm_counts(order, parent, weight, hi) - neg - n_zero
            bad_lo = below_lo > target
            bad_hi = below_hi <= target
            if not (bad_lo.any() or bad_hi.any()):
                break
            lo = np.where(bad_lo, lo * 0.5, lo)
            hi = np.where(bad_hi, hi * 2.0 + 1e-300, hi)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        below = _sturm_counts(order, parent, weight, mid) - neg - n_zero
        left = below > target
        hi = np.where(left, mid, hi)
        lo = np.where(left, lo, mid)
        if np.all(hi - lo <= rtol * hi):
            break
    omega = np.sort(0.5 * (lo + hi))
    # values equal within the bisection tolerance are one repeated eigenvalue: make them equal
    start = 0
    for i in range(1, omega.size + 1):
        if i == omega.size or omega[i] - omega[start] > 2 * rtol * omega[i]:
            if i - start > 1:
                omega[start:i] = omega[start:i].mean()
            start = i
    return np.concatenate([np.zeros(n_zero), omega])
