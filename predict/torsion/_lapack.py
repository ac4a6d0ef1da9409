"""High-relative-accuracy bidiagonal SVD from the LAPACK that SciPy ships.

``scipy.linalg.lapack`` does not wrap ``dlasq1`` (dqds, singular values only) or ``dbdsqr``
(Demmel-Kahan implicit zero-shift QR, values and vectors), but ``scipy.linalg.cython_lapack``
exports both as C function pointers in PyCapsules. We call them through :mod:`ctypes`; when
that is impossible (an exotic SciPy build) we fall back to bisection on the Golub-Kahan
tridiagonal (``dstebz``), which is also relatively accurate, only slower.

Both LAPACK routines compute every singular value of a bidiagonal matrix to high relative
accuracy: the relative error of each value is a modest multiple of n·eps whatever its size
(Demmel & Kahan, SIAM J. Sci. Stat. Comput. 11 (1990) 873; Fernando & Parlett, Numer. Math.
67 (1994) 191).
"""

from __future__ import annotations

import ctypes
import functools
import logging

import numpy as np

from ..errors import AnalysisError
from . import _dqds

__all__ = ["bidiagonal_singular_values", "qd_singular_values", "lapack_qd_singular_values",
           "bidiagonal_svd"]

log = logging.getLogger("crankbench")

_IP = ctypes.POINTER(ctypes.c_int)
_DP = ctypes.POINTER(ctypes.c_double)

#: squared bidiagonal entries outside this range go through dlasq1, which scales first
_SAFE_SQUARES = (1e-290, 1e290)


@functools.lru_cache(maxsize=None)
def _function(name: str, argtypes: tuple):
    """ctypes callable for ``scipy.linalg.cython_lapack.<name>`` or None."""
    try:
        from scipy.linalg import cython_lapack

        capsule = cython_lapack.__pyx_capi__[name]
        get_name = ctypes.pythonapi.PyCapsule_GetName
        get_name.restype = ctypes.c_char_p
        get_name.argtypes = [ctypes.py_object]
        get_pointer = ctypes.pythonapi.PyCapsule_GetPointer
        get_pointer.restype = ctypes.c_void_p
        get_pointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
        address = get_pointer(capsule, get_name(capsule))
        return ctypes.CFUNCTYPE(None, *argtypes)(address)
    except Exception as exc:  # pragma: no cover - depends on the SciPy build
        log.debug("cython_lapack.%s not reachable through ctypes (%s)", name, exc)
        return None


def _ptr(a: np.ndarray, kind=_DP):
    """Pointer to the first element of a writable array (kept alive by the caller);
    ``from_buffer`` + ``byref`` costs a fraction of ``ndarray.ctypes`` (C-contiguous only)."""
    if not a.flags.c_contiguous:  # Fortran-ordered matrices
        return a.ctypes.data_as(kind)
    base = ctypes.c_int if kind is _IP else ctypes.c_double
    return ctypes.byref(base.from_buffer(a))


def _stebz_fallback(d: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Singular values of the bidiagonal (d, e) by bisection on its Golub-Kahan tridiagonal."""
    from scipy.linalg import lapack

    n = d.size
    off = np.empty(2 * n - 1)
    off[0::2] = d
    off[1::2] = e
    m, w, _, _, info = lapack.dstebz(np.zeros(2 * n), off, 0, 0.0, 0.0, 0, 0,
                                    np.finfo(float).tiny, "E")
    if info != 0:
        raise AnalysisError(f"dstebz failed with info={info}")
    w = np.sort(np.asarray(w[:m]))
    return np.abs(w[-n:])[::-1]


def bidiagonal_singular_values(d, e) -> np.ndarray:
    """Singular values (descending) of the upper bidiagonal matrix with diagonal ``d`` and
    superdiagonal ``e``, to high relative accuracy (LAPACK ``dlasq1``, dqds).

    Parameters
    ----------
    d : array_like, shape (n,)
    e : array_like, shape (n-1,)

    Returns
    -------
    ndarray, shape (n,)
        Singular values, descending.
    """
    d = np.array(d, dtype=np.float64, copy=True)
    n = d.size
    if n == 0:
        return d
    work = np.zeros(max(4 * n, 1))
    e2 = np.zeros(max(n, 1))
    e2[: n - 1] = e
    f = _function("dlasq1", (_IP, _DP, _DP, _DP, _IP))
    if f is None:
        return _stebz_fallback(d, e2[: n - 1])
    nn = ctypes.c_int(n)
    info = ctypes.c_int(0)
    f(ctypes.byref(nn), _ptr(d), _ptr(e2), _ptr(work), ctypes.byref(info))
    if info.value != 0:
        raise AnalysisError(f"dlasq1 (dqds) did not converge, info={info.value}")
    return d


def qd_singular_values(q, e2) -> np.ndarray:
    """Singular values (descending) of the upper bidiagonal whose squared diagonal is ``q`` and
    squared superdiagonal ``e2``, to high relative accuracy (dqds).

    From ``_dqds.MIN_SIZE`` values on, the compiled dqds of :mod:`predict.torsion._dqds`
    runs first (three transforms per pass: 0.3-0.45x the time of LAPACK ``dlasq2`` from 300
    values on in the bench suite ``torsion``); where it reports any doubt (range,
    convergence), and for smaller arrays, LAPACK ``dlasq2`` does the work. Callers that know the squares exactly (a product of the
    data) skip the square roots of :func:`bidiagonal_singular_values` and dlasq1's scaling
    pass; squares outside ``[1e-290, 1e290]`` take that scaled route instead.

    Parameters
    ----------
    q : ndarray, shape (n,)
        Squared diagonal, > 0.
    e2 : ndarray, shape (n-1,)
        Squared superdiagonal, >= 0.

    Returns
    -------
    ndarray, shape (n,)
        Singular values, descending.
    """
    n = q.size
    if n == 0:
        return np.zeros(0)
    if n >= _dqds.MIN_SIZE:
        lam = _dqds.qd_eigenvalues(q, e2)
        if lam is not None:
            return np.sqrt(lam[::-1])
    return lapack_qd_singular_values(q, e2)


def lapack_qd_singular_values(q, e2) -> np.ndarray:
    """:func:`qd_singular_values` by LAPACK alone (``dlasq2``; ``dlasq1`` for squares outside
    ``[1e-290, 1e290]``): the fallback of the compiled kernel, and its bench baseline."""
    n = q.size
    if n == 0:
        return np.zeros(0)
    lo, hi = _SAFE_SQUARES
    f = _function("dlasq2", (_IP, _DP, _IP))
    if (f is None or not (q.min() > lo and q.max() < hi)
            or (n > 1 and not (e2.min() >= 0 and e2.max() < hi))):
        return bidiagonal_singular_values(np.sqrt(q), np.sqrt(e2))
    z = np.zeros(4 * n)
    z[0:2 * n:2] = q
    z[1:2 * n - 2:2] = e2
    ints = np.array([n, 0], dtype=np.intc)
    f(_ptr(ints, _IP), _ptr(z), ctypes.byref(ctypes.c_int.from_buffer(ints, ints.itemsize)))
    if ints[1] != 0:
        raise AnalysisError(f"dlasq2 (dqds) did not converge, info={int(ints[1])}")
    return np.sqrt(z[:n])


def bidiagonal_svd(d, e):
    """SVD of the upper bidiagonal matrix (d, e): ``B = U diag(s) Vt`` by LAPACK ``dbdsqr``.

    Returns
    -------
    s : ndarray, shape (n,)
        Singular values, descending, to high relative accuracy.
    u : ndarray, shape (n, n)
        Left singular vectors (columns).
    vt : ndarray, shape (n, n)
        Right singular vectors (rows).
    """
    d = np.array(d, dtype=np.float64, copy=True)
    n = d.size
    e2 = np.zeros(max(n, 1))
    e2[: n - 1] = e
    f = _function("dbdsqr", (ctypes.c_char_p, _IP, _IP, _IP, _IP, _DP, _DP, _DP, _IP, _DP, _IP,
                             _DP, _IP, _DP, _IP))
    if f is None:  # pragma: no cover - exotic SciPy build
        b = np.diag(d) + np.diag(e2[: n - 1], 1)
        import scipy.linalg as sl

        u, s, vt = sl.svd(b)
        s = _stebz_fallback(d, e2[: n - 1])
        return s, u, vt
    vt = np.asfortranarray(np.eye(n))
    u = np.asfortranarray(np.eye(n))
    c = np.zeros((1, 1), order="F")
    work = np.zeros(max(4 * n, 1))
    nn, ncvt, nru, ncc = (ctypes.c_int(v) for v in (n, n, n, 0))
    ld, ldc = ctypes.c_int(max(n, 1)), ctypes.c_int(1)
    info = ctypes.c_int(0)
    f(b"U", ctypes.byref(nn), ctypes.byref(ncvt), ctypes.byref(nru), ctypes.byref(ncc),
      _ptr(d), _ptr(e2), _ptr(vt), ctypes.byref(ld), _ptr(u), ctypes.byref(ld), _ptr(c),
      ctypes.byref(ldc), _ptr(work), ctypes.byref(info))
    if info.value != 0:
        raise AnalysisError(f"dbdsqr did not converge, info={info.value}")
    return d, np.ascontiguousarray(u), np.ascontiguousarray(vt)
