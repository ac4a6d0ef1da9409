"""Lowest modes of long chains: bisection and inverse iteration, memory linear in the length.

:func:`chain_frequencies <predict.torsion.eigen.chain_frequencies>` computes every mode by dqds
(O(n²) time, all n values); the shapes of all modes are an n×n matrix (3.2 GB at 20 000
masses). A user of a long shaft line needs the lowest few. :func:`chain_lowest` computes them
alone, in O(n·k) time and O(n + n·k) memory:

Values
    The chain's factor (square bidiagonal ``F`` with ``FᵀF = J^{-1/2} K J^{-1/2}``: grounded,
    ``diag(√k) B J^{-1/2}``; free, the rigid-body-deflated factor of
    :mod:`predict.torsion.eigen`) has the Golub–Kahan form ``[[0, F], [Fᵀ, 0]]``, permuted to a
    zero-diagonal tridiagonal whose eigenvalues are ``±σ``. Bisection on it (LAPACK ``dstebz``
    with an absolute tolerance at the underflow threshold) finds the k smallest positive ones
    to high *relative* accuracy, since a zero-diagonal tridiagonal determines its eigenvalues
    to high relative accuracy and its Sturm counts are computed accurately (Demmel & Kahan,
    SIAM J. Sci. Stat. Comput. 11 (1990) 873, §5). Cost ≈ 2n × ~60-80 steps per mode.

Shapes
    Inverse iteration on the Golub–Kahan form of the (n−1)×n free or n×n grounded factor with
    the computed σ: two tridiagonal LU solves (LAPACK ``dgttrf``/``dgttrs``) per mode from a
    fixed pseudo-random start. The mode shape is the right-singular-vector half of the
    eigenvector; the ``−σ`` twin shares it, so only the neighbours ``σ_{i±1}`` and, for a free
    chain, the rigid-body mode pollute it, by about ``eps·‖F‖/gap`` (gaps of σ, not of ω²:
    1e-12 at 20 000 masses where inverse iteration on the scaled tridiagonal would give
    1e-7). Shapes are made orthogonal to the rigid-body mode and, within clusters of nearly
    equal σ, to each other, then mass-normalised (``xᵀ J x = 1``).

Memory: :func:`memory_bytes` states the estimate the size checks use.
"""

from __future__ import annotations

import numpy as np

from ..errors import AnalysisError

__all__ = ["chain_lowest", "chain_shapes", "lowest", "below", "memory_bytes", "memory_estimate",
           "CLUSTER_RTOL"]

TINY = np.finfo(float).tiny
EPS = np.finfo(float).eps
#: σ closer than this (relative) are orthogonalised against each other after inverse iteration
CLUSTER_RTOL = 1e-6


def memory_bytes(n_nodes: int, n_modes: int | None = None, *, shapes: bool = False) -> int:
    """Estimated peak working memory (bytes) of a chain eigen-solve.

    Parameters
    ----------
    n_nodes : int
        Number of masses.
    n_modes : int, optional
        Lowest modes wanted (the subset path of :func:`chain_lowest`); None = every mode
        (dqds for values; the dense n×n shape matrix when ``shapes``).
    shapes : bool
        Mode shapes too.

    Returns
    -------
    int
        Bytes. Subset: about ``8·n·(40 + 2k)`` (the Golub–Kahan arrays and LAPACK workspace,
        2n long, plus the n×k result); every mode: ``64·n`` for values, ``24·n²`` with shapes
        (matrix, its transpose and workspace).

    Examples
    --------
    >>> print(memory_bytes(100_000, 10) // 2**20, "MiB")
    30 MiB
    >>> print(memory_bytes(100_000, shapes=True) // 2**30, "GiB")
    223 GiB
    """
    n = int(n_nodes)
    if n_modes is not None:
        k = min(int(n_modes), n)
        return 8 * n * (40 + 2 * k) if shapes else 8 * n * 40
    return 24 * n * n if shapes else 64 * n


def _values_factor(inertias, stiffnesses, grounded):
    """Off-diagonal of the zero-diagonal Golub–Kahan tridiagonal of the square, nonsingular
    factor whose singular values are the elastic ω (see module docstring)."""
    if grounded:
        diag, off = np.sqrt(stiffnesses / inertias), np.sqrt(stiffnesses[1:] / inertias[:-1])
    else:
        from .eigen import _free_chain_factor

        diag, off = _free_chain_factor(inertias, stiffnesses)
    gk = np.empty(2 * diag.size - 1)
    gk[0::2] = diag
    gk[1::2] = off
    return gk


def _shape_factor(inertias, stiffnesses, grounded):
    """Golub–Kahan off-diagonal of the factor ``diag(√k) B J^{-1/2}`` and the positions of an
    eigenvector that hold its right singular vector (the mode shape ``y = J^{1/2} x``).

    Grounded (n×n, lower bidiagonal G): eigenvector ordered ``[u1, v1, u2, v2, ...]``,
    couplings ``G[0,0], G[1,0], G[1,1], ...``. Free ((n−1)×n, A[i,i] = −√k_i/√J_i,
    A[i,i+1] = √k_i/√J_{i+1}): ordered ``[v1, u1, v2, ..., u_{n−1}, v_n]``.
    """
    rj = 1.0 / np.sqrt(inertias)
    sk = np.sqrt(stiffnesses)
    n = inertias.size
    if grounded:
        gk = np.empty(2 * n - 1)
        gk[0::2] = sk * rj
        gk[1::2] = -sk[1:] * rj[:-1]
        return gk, slice(1, None, 2)
    gk = np.empty(2 * n - 2)
    gk[0::2] = -sk * rj[:-1]
    gk[1::2] = sk * rj[1:]
    return gk, slice(0, None, 2)


def _bisect(gk, n_modes, omega_max):
    """Smallest positive eigenvalues of the zero-diagonal tridiagonal with off-diagonal ``gk``
    (size 2m, eigenvalues ±σ, none zero): the ``n_modes`` lowest or all σ <= ``omega_max``."""
    from scipy.linalg import lapack

    m = (gk.size + 1) // 2
    d = np.zeros(gk.size + 1)
    if omega_max is None:
        count = min(int(n_modes), m)
        if count <= 0:
            return np.zeros(0)
        found, w, _, _, info = lapack.dstebz(d, gk, 2, 0.0, 0.0, m + 1, m + count, TINY, b"E")
    else:
        # eigenvalues in (0, omega_max]; the count at 0 is exactly m (σ > 0, none zero)
        found, w, _, _, info = lapack.dstebz(d, gk, 1, 0.0, float(omega_max), 0, 0, TINY, b"E")
    if info != 0:
        raise AnalysisError(f"bisection (LAPACK dstebz) failed, info={info}")
    return np.sort(np.asarray(w[:found], float))


def _inverse_iteration(gk, where, sigma):
    """Right-singular-vector halves (unit norm, columns) of the Golub–Kahan eigenvectors at σ."""
    from scipy.linalg import lapack

    size = gk.size + 1
    scale = float(np.max(np.abs(gk))) if gk.size else 1.0
    off = gk / scale
    rng = np.random.default_rng(20240611)  # fixed start: the same shapes on every run
    n_shape = len(range(size)[where])
    out = np.empty((n_shape, sigma.size))
    for i, s in enumerate(sigma / scale):
        dl, d, du, du2, ipiv, info = lapack.dgttrf(off, np.full(size, -s), off)
        if info < 0:
            raise AnalysisError(f"tridiagonal LU (LAPACK dgttrf) failed, info={info}")
        d[d == 0.0] = EPS  # exactly singular at an exact eigenvalue: perturb the pivot
        x = rng.uniform(-1.0, 1.0, (size, 1))
        for _ in range(2):
            x, info = lapack.dgttrs(dl, d, du, du2, ipiv, x)
            norm = np.linalg.norm(x)
            if info != 0 or not np.isfinite(norm) or norm == 0.0:
                raise AnalysisError(f"inverse iteration at σ = {s * scale:.6g} failed "
                                    f"(dgttrs info={info})")
            x /= norm
        y = x[where, 0]
        out[:, i] = y / np.linalg.norm(y)
    return out


def _orthogonalise(y, sigma, rigid):
    """Make the unit columns of ``y`` orthogonal to ``rigid`` (unit vector or None) and, within
    clusters of σ closer than :data:`CLUSTER_RTOL`, to each other (modified Gram-Schmidt)."""
    if rigid is not None:
        y -= np.outer(rigid, rigid @ y)
    start = 0
    for i in range(1, sigma.size + 1):
        if i == sigma.size or sigma[i] - sigma[i - 1] > CLUSTER_RTOL * sigma[i]:
            for c in range(start, i):
                for p in range(start, c):
                    y[:, c] -= (y[:, p] @ y[:, c]) * y[:, p]
                y[:, c] /= np.linalg.norm(y[:, c])
            start = i
    return y


def chain_lowest(inertias, stiffnesses, *, grounded: bool, n_modes: int | None = None,
                 omega_max: float | None = None, shapes: bool = False):
    """The lowest modes of a chain without computing the others.

    Parameters
    ----------
    inertias : ndarray, shape (n,)
        kg·m², > 0.
    stiffnesses : ndarray
        N·m/rad, > 0: (n−1,) free chain, (n,) first mass grounded.
    grounded : bool
        Which layout.
    n_modes : int, optional
        How many of the lowest modes, counting a free chain's rigid-body mode (ω = 0) as the
        first: the first ``n_modes`` values of the full ascending list.
    omega_max : float, optional
        Instead of ``n_modes``: every mode with ω <= ``omega_max`` (rad/s).
    shapes : bool
        Also return mass-normalised mode shapes.

    Returns
    -------
    omega : ndarray
        ω, rad/s, ascending, relative error ~ a few ulps (bisection to 2 ulps on a matrix
        whose entries carry a few ulps from the data).
    shapes : ndarray (n, len(omega)) or None
        ``xᵀ J x = 1``; the rigid-body mode of a free chain is exactly the constant vector.

    Examples
    --------
    >>> import numpy as np
    >>> n = 2000
    >>> w, x = chain_lowest(np.ones(n), np.full(n - 1, 1e6), grounded=False, n_modes=3,
    ...                     shapes=True)
    >>> exact = 2e3 * np.sin(np.arange(3) * np.pi / (2 * n))   # 2√(k/J) sin(jπ/2n)
    >>> print(w[0], bool(np.allclose(w[1:], exact[1:], rtol=1e-13)), x.shape)
    0.0 True (2000, 3)
    """
    inertias = np.asarray(inertias, float)
    stiffnesses = np.asarray(stiffnesses, float)
    if (n_modes is None) == (omega_max is None):
        raise ValueError("give exactly one of n_modes and omega_max")
    n = inertias.size
    n_rigid = 0 if grounded else 1
    if n_modes is not None:
        n_modes = min(int(n_modes), n)
    elastic = np.zeros(0)
    if n > n_rigid:
        gk = _values_factor(inertias, stiffnesses, grounded)
        if n_modes is not None:
            elastic = _bisect(gk, n_modes - n_rigid, None)
        elif omega_max >= 0:
            elastic = _bisect(gk, None, omega_max)
    if n_modes is not None and n_modes < n_rigid:
        omega = np.zeros(n_modes)
    else:
        omega = np.concatenate([np.zeros(n_rigid), elastic])
    if not shapes:
        return omega, None
    return omega, chain_shapes(inertias, stiffnesses, omega, grounded=grounded)


def chain_shapes(inertias, stiffnesses, omega, *, grounded: bool) -> np.ndarray:
    """Mass-normalised mode shapes of a chain at its natural frequencies ``omega`` (rad/s,
    ascending, computed to high relative accuracy; a free chain's first value is its rigid-body
    0), by inverse iteration on the Golub–Kahan form (module docstring). O(n) memory and time
    per mode.

    Returns
    -------
    ndarray (n, len(omega))
        ``xᵀ J x = 1``, largest amplitude of each shape positive; the rigid-body mode of a free
        chain is exactly the constant vector.
    """
    inertias = np.asarray(inertias, float)
    stiffnesses = np.asarray(stiffnesses, float)
    omega = np.asarray(omega, float)
    n = inertias.size
    n_rigid = 0 if grounded else min(1, omega.size)
    x = np.empty((n, omega.size))
    rigid = None
    if n_rigid:
        rigid = np.sqrt(inertias / inertias.sum())
        x[:, 0] = 1.0 / np.sqrt(inertias.sum())
    elastic = omega[n_rigid:]
    if elastic.size:
        gk, where = _shape_factor(inertias, stiffnesses, grounded)
        y = _orthogonalise(_inverse_iteration(gk, where, elastic), elastic, rigid)
        peak = np.argmax(np.abs(y), axis=0)  # sign: largest amplitude positive
        y *= np.sign(y[peak, np.arange(y.shape[1])])
        x[:, n_rigid:] = y / np.sqrt(inertias)[:, None]
    return x


#: a chain longer than this gets its lowest shapes by inverse iteration (dbdsqr below it)
SHAPES_MIN_NODES = 400
#: values by bisection when n_modes * VALUES_RATIO < n (bisection ~ 2n·70 steps a mode,
#: dqds ~ 2n² for all)
VALUES_RATIO = 64


def _subset_applies(system, n_modes: int, shapes: bool) -> bool:
    kind, info = system._layout()
    n = info["nodes"].size
    if kind != "chain" or n_modes >= n:
        return False
    if shapes:
        return n > SHAPES_MIN_NODES and "_eigen" not in system.__dict__
    return n_modes * VALUES_RATIO < n and "_values" not in system.__dict__


def lowest(system, n_modes: int, *, shapes: bool = False):
    """The lowest ``n_modes`` modes of a :class:`~predict.torsion.system.TorsionalSystem`.

    A chain long enough for it to pay solves for them alone (:func:`chain_lowest`,
    :func:`chain_shapes`); anything else, or a system whose full solution is already cached,
    takes the first ``n_modes`` of the full solution.

    Returns
    -------
    omega : ndarray
        rad/s, ascending.
    numbers : ndarray of int
        Mode numbers (0 = rigid body).
    method : str
    bound : float
        Relative error bound of each frequency.
    shapes : ndarray (n_nodes, n_modes) or None
        Mass-normalised shapes (when ``shapes``), zero at nodes outside the eigen-analysis.
    """
    cache = system.__dict__.setdefault("_lowest_cache", {})
    key = (n_modes, shapes)
    if key in cache:
        return cache[key]
    if not _subset_applies(system, n_modes, shapes):
        if shapes:
            omega, all_shapes, numbers, method, bound = system._eigen
            return (omega[:n_modes], numbers[:n_modes], method, bound,
                    all_shapes[:, :n_modes])
        omega, numbers, method, bound = system._values[:4]
        return omega[:n_modes], numbers[:n_modes], method, bound, None
    _, info = system._layout()
    nodes, order = info["nodes"], info["order"]
    jn = system.inertias[nodes][order]
    grounded = info["grounded"]
    if "_values" in system.__dict__:
        omega = system._values[0][:n_modes]
        method = "bidiagonal dqds + inverse iteration (lowest modes)"
    else:
        omega, _ = chain_lowest(jn, info["chain_k"], grounded=grounded, n_modes=n_modes)
        method = "Golub-Kahan bisection" + (" + inverse iteration" if shapes else "") + \
            " (lowest modes)"
    numbers = np.arange(n_modes) + (1 if grounded else 0)
    bound = 8 * nodes.size * EPS
    full_shapes = None
    if shapes:
        full_shapes = np.zeros((system.n_nodes, n_modes))
        full_shapes[nodes[order]] = chain_shapes(jn, info["chain_k"], omega, grounded=grounded)
    result = (omega, numbers, method, bound, full_shapes)
    cache[key] = result
    return result


def memory_estimate(system, n_modes: int | None, *, shapes: bool) -> int:
    """Working-memory estimate (bytes) of :func:`lowest` or the full solution of ``system``."""
    kind, info = system._layout()
    n = int(info["nodes"].size)
    if kind != "chain":
        return 32 * n * n  # dense scaled matrix, eigenvectors and LAPACK workspace
    if n_modes is not None and _subset_applies(system, n_modes, shapes):
        return memory_bytes(n, n_modes, shapes=shapes)
    return memory_bytes(n, None, shapes=shapes)


def below(system, omega_max: float):
    """(ω rad/s, mode numbers, shapes (n_nodes, m)) of every mode with ω <= ``omega_max``.

    A long chain whose shapes are not yet cached solves for those modes alone (the critical
    speeds of a 20 000-mass shaft line below its top speed need a handful of shapes, not the
    n×n matrix); anything else selects them from the full solution.
    """
    kind, info = system._layout()
    n = info["nodes"].size
    if kind != "chain" or n <= SHAPES_MIN_NODES or "_eigen" in system.__dict__:
        omega, shapes, numbers = system._eigen[:3]
        keep = omega <= omega_max
        return omega[keep], numbers[keep], shapes[:, keep]
    nodes, order = info["nodes"], info["order"]
    jn = system.inertias[nodes][order]
    grounded = info["grounded"]
    if "_values" in system.__dict__:
        omega = system._values[0]
        omega = omega[omega <= omega_max]
    else:
        omega, _ = chain_lowest(jn, info["chain_k"], grounded=grounded, omega_max=omega_max)
    numbers = np.arange(omega.size) + (1 if grounded else 0)
    shapes = np.zeros((system.n_nodes, omega.size))
    shapes[nodes[order]] = chain_shapes(jn, info["chain_k"], omega, grounded=grounded)
    return omega, numbers, shapes
