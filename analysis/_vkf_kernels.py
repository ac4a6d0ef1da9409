"""Inner loops of the Vold–Kalman filter (:mod:`analysis.vkf`), compiled when numba is present.

Each function has a numpy/SciPy twin that gives the same result to rounding (the twins are the
reference: ``tests/analysis/test_vkf_kernels.py`` runs both on the same small records). The
compiled forms do in one pass over the samples what the twins do in several whole-array
passes and library calls:

* :func:`fir_decimate` — one stage of a polyphase FIR decimator (twin:
  :func:`scipy.signal.upfirdn`);
* :func:`order_basis` — ``cos``/``sin`` of every order's phase (twin: ``np.cos``/``np.sin``);
* :func:`assemble` — the block-banded normal equations ``CᵀC + Σ r² D_pᵀD_p`` and ``Cᵀx`` of
  the spline-envelope least squares, accumulated knot interval by knot interval (twin: grouped
  products and ``np.bincount`` scatters);
* :func:`solve` — banded Cholesky ``LLᵀ`` for the small bandwidth of this problem with one step
  of iterative refinement (twin: LAPACK ``dpbtrf``/``dpbtrs`` through SciPy, one BLAS thread);
* :func:`envelopes` — the complex envelopes, the trend and the model at every sample.

The noise and smearing estimates are in :mod:`analysis._vkf_noise`.

Matrix storage: a symmetric band matrix of half-bandwidth ``u`` is held by columns,
``band[j, d] = A[j + d, j]`` for ``0 ≤ d ≤ u`` (the transpose of LAPACK's lower band form), so
that the column updates of the factorisation run over contiguous memory.

``CRANKBENCH_NO_NUMBA=1`` forces the twins (as for :mod:`analysis._kernels`);
:func:`accelerated` says which are in use.
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["accelerated", "fir_decimate", "order_basis", "assemble", "solve", "envelopes",
           "NotPositiveDefinite"]

_DIFF = {1: np.array([-1.0, 1.0]), 2: np.array([1.0, -2.0, 1.0])}

# π/2 in three parts of 33, 33 and 53 bits (the leading digits of π/2: 1.5707963267341256 +
# 6.077100506303966e-11 + 2.0222662487959506e-21), for the exact argument reduction of basis()
_PIO2 = (1.5707963267341256, 6.077100506303966e-11, 2.0222662487959506e-21)
_TWO_OVER_PI = 2.0 / np.pi
# Taylor coefficients of sin (r³ … r¹⁷) and cos (r² … r¹⁸)
_S = tuple((-1.0) ** i / float(np.prod(np.arange(1, 2 * i + 2))) for i in range(1, 9))
_C = tuple((-1.0) ** i / float(np.prod(np.arange(1, 2 * i + 1))) for i in range(1, 10))
#: largest |o φ| (rad) of the compiled basis (|q| < 2^20 keeps the reduction exact)
BASIS_MAX_PHASE = 2.0 ** 20


#: compiled helpers called by other compiled kernels (set by :func:`_numba`)
_JIT_SPLINE_W = _JIT_FACTOR = _JIT_SUBSTITUTE = _JIT_MATVEC = _JIT_DOTS = None


class NotPositiveDefinite(ArithmeticError):
    """The banded matrix has a non-positive pivot (raised by :func:`solve`)."""


def njit_or_none():
    """numba's ``njit``, or None (numba missing, or ``CRANKBENCH_NO_NUMBA`` set)."""
    import os

    if os.environ.get("CRANKBENCH_NO_NUMBA"):
        return None
    try:
        from numba import njit
    except ImportError:
        return None
    return njit


@functools.lru_cache(maxsize=1)
def _numba():
    """The compiled kernels, or None (numba missing, or ``CRANKBENCH_NO_NUMBA`` set)."""
    njit = njit_or_none()
    if njit is None:
        return None
    # kernels that call kernels reach them as module globals, not closure cells: numba keys
    # its on-disk cache on the pickled closure cells, and a pickled dispatcher differs from
    # process to process, so a closure reference recompiled the caller (8 s) in every process
    global _JIT_SPLINE_W, _JIT_FACTOR, _JIT_SUBSTITUTE, _JIT_MATVEC, _JIT_DOTS

    @njit(cache=True, fastmath=True)
    def fir(x, h, q, first, n_out):          # pragma: no cover - compiled
        taps = h.shape[0]
        half = taps // 2
        y = np.empty(n_out)
        for k in range(n_out):
            c = (first + k) * q - half
            # a slice, not x[c + t]: a signed index makes numba check for wrap-around at
            # every tap, which keeps LLVM from vectorising the dot product (6x slower)
            xs = x[c:c + taps]
            acc = 0.0
            for t in range(taps):
                acc += h[t] * xs[t]
            y[k] = acc
        return y

    @njit(cache=True, error_model="numpy")
    def basis(phi, orders, cos_out, sin_out):  # pragma: no cover - compiled
        # cos/sin of o_j φ_i, written (K, N): Cody–Waite reduction by π/2 in three parts (33,
        # 33 and 53 bits, so q·P1 and q·P2 are exact for |q| < 2^20) and the Taylor series on
        # |r| ≤ π/4 (first omitted terms < 1e-19); no fastmath (the reduction's order of
        # operations matters), no library call, so LLVM vectorises the loop (8-15x np.cos)
        for j in range(orders.shape[0]):
            o = orders[j]
            for i in range(phi.shape[0]):
                x = phi[i] * o
                q = np.rint(x * _TWO_OVER_PI)
                r = ((x - q * _PIO2[0]) - q * _PIO2[1]) - q * _PIO2[2]
                z = r * r
                s = r + r * z * (_S[0] + z * (_S[1] + z * (_S[2] + z * (_S[3] + z * (
                    _S[4] + z * (_S[5] + z * (_S[6] + z * _S[7])))))))
                c = 1.0 + z * (_C[0] + z * (_C[1] + z * (_C[2] + z * (_C[3] + z * (
                    _C[4] + z * (_C[5] + z * (_C[6] + z * (_C[7] + z * _C[8]))))))))
                quadrant = np.int64(q)
                odd = (quadrant & 1) == 1
                a = c if odd else s
                b = s if odd else c
                sin_out[j, i] = -a if (quadrant & 2) else a
                cos_out[j, i] = -b if ((quadrant + 1) & 2) else b

    @njit(cache=True)
    def spline_w(i, m, w):                    # pragma: no cover - compiled
        # uniform cubic B-spline weights of sample i (knots every m samples); the same float
        # operations as analysis.vkf._spline_weights
        pos = i / m
        g = np.floor(pos)
        f = pos - g
        f2 = f * f
        f3 = f2 * f
        w[0] = (1.0 - f) ** 3 / 6.0
        w[1] = (3.0 * f3 - 6.0 * f2 + 4.0) / 6.0
        w[2] = (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0) / 6.0
        w[3] = f3 / 6.0

    _JIT_SPLINE_W = spline_w

    @njit(cache=True, fastmath=True)
    def dots(a, b, cnt, out):                  # pragma: no cover - compiled
        # out[i, e] = Σ_{t < cnt} a[i, t] b[e, t]: contiguous dot products
        for i in range(out.shape[0]):
            for e in range(out.shape[1]):
                acc = 0.0
                for t in range(cnt):
                    acc += a[i, t] * b[e, t]
                out[i, e] = acc

    _JIT_DOTS = dots

    @njit(cache=True, fastmath=True)
    def assemble(x, cosp, sinp, trend, m, n_coef, p, weights, diff, u):  # pragma: no cover
        k = cosp.shape[0]                      # (K, N): one order's samples contiguous
        n = x.shape[0]                         # (K may be 0: the trend alone)
        cols = 2 * k + (1 if trend else 0)
        s = 1 if m == 1 else 4
        size = n_coef * cols
        band = np.zeros((size, u + 1))
        rhs = np.zeros(size)
        npair = cols * (cols + 1) // 2
        pair = np.empty((cols, cols), np.int64)
        idx = 0
        for j in range(cols):
            for jj in range(j, cols):
                pair[j, jj] = idx
                pair[jj, j] = idx
                idx += 1
        nslot = s * (s + 1) // 2
        sums = np.zeros((nslot, npair))
        rsum = np.zeros((s, cols))
        span = min(m, n)
        # the knots are uniform: every interval has the first one's weight pattern (as the
        # numpy form), stored (slot pair, position) so that each sum is a contiguous dot
        w = np.ones(4)
        wpat = np.ones((nslot, span))
        wv = np.ones((s, span))
        if s > 1:
            for t in range(span):
                _JIT_SPLINE_W(t, m, w)
                idx = 0
                for a in range(s):
                    wv[a, t] = w[a]
                    for c in range(a, s):
                        wpat[idx, t] = w[a] * w[c]
                        idx += 1
        basis = np.empty((cols, span))          # the interval's basis, column by sample
        prod = np.empty((npair, span))          # and its products, pair by pair
        basis_x = np.empty((cols, span))
        groups = (n - 1) // m + 1
        for g in range(groups):
            lo = g * m
            cnt = min(n, lo + m) - lo
            for j in range(k):
                for t in range(cnt):
                    basis[2 * j, t] = cosp[j, lo + t]
                    basis[2 * j + 1, t] = -sinp[j, lo + t]
            if trend:
                for t in range(cnt):
                    basis[cols - 1, t] = 1.0
            idx = 0
            for j in range(cols):
                for t in range(cnt):
                    basis_x[j, t] = basis[j, t] * x[lo + t]
                for jj in range(j, cols):
                    for t in range(cnt):
                        prod[idx, t] = basis[j, t] * basis[jj, t]
                    idx += 1
            # (slot pair, product) and (slot, column) sums over the interval's samples
            _JIT_DOTS(wpat, prod, cnt, sums)
            _JIT_DOTS(wv, basis_x, cnt, rsum)
            # scatter the interval's sums: A[J, I] (J >= I) at band[I, J - I]
            ab = 0
            for a in range(s):
                for c in range(a, s):
                    for j in range(cols):
                        row_i = (g + a) * cols + j
                        for jj in range(cols):
                            if a == c and jj < j:
                                continue
                            col_j = (g + c) * cols + jj
                            band[row_i, col_j - row_i] += sums[ab, pair[j, jj]]
                    ab += 1
                for j in range(cols):
                    rhs[(g + a) * cols + j] += rsum[a, j]
        # smoothness: r² D_pᵀ D_p per column
        for r in range(weights.shape[0]):
            for a in range(p + 1):
                for c in range(a, p + 1):
                    cc = diff[a] * diff[c]
                    for j in range(cols):
                        band[(r + a) * cols + j, (c - a) * cols] += cc * weights[r, j]
        return band, rhs

    @njit(cache=True, fastmath=True)
    def factor(band):                          # pragma: no cover - compiled
        # in place, column by column (LAPACK dpbtf2's order): band -> L in the same storage;
        # returns the first bad pivot or -1
        size, w1 = band.shape
        u = w1 - 1
        # the envelope: column j of L reaches no lower than the lowest non-zero of A's columns
        # up to j (a row's first non-zero bounds its fill-in); the block structure leaves the
        # last (u - j mod cols) entries of each column zero, ~20 % of the band's work
        last = 0
        for j in range(size):
            d = band[j, 0]
            if not d > 0.0:
                return j
            d = np.sqrt(d)
            band[j, 0] = d
            nz = min(u, size - 1 - j)
            while nz > 0 and band[j, nz] == 0.0:
                nz -= 1
            last = max(last, j + nz)
            reach = last - j
            inv = 1.0 / d
            for t in range(1, reach + 1):
                band[j, t] *= inv
            # trailing update A[j + t2, j + t1] -= L[j + t2, j] L[j + t1, j], t1 <= t2
            for t1 in range(1, reach + 1):
                l1 = band[j, t1]
                row = j + t1
                for t2 in range(t1, reach + 1):
                    band[row, t2 - t1] -= band[j, t2] * l1
        return -1

    @njit(cache=True, fastmath=True)
    def substitute(low, y):                    # pragma: no cover - compiled
        # solves L Lᵀ z = y in place
        size, w1 = low.shape
        u = w1 - 1
        for j in range(size):
            y[j] /= low[j, 0]
            yj = y[j]
            for t in range(1, min(u, size - 1 - j) + 1):
                y[j + t] -= low[j, t] * yj
        for j in range(size - 1, -1, -1):
            acc = y[j]
            for t in range(1, min(u, size - 1 - j) + 1):
                acc -= low[j, t] * y[j + t]
            y[j] = acc / low[j, 0]

    @njit(cache=True, fastmath=True)
    def matvec(band, z):                       # pragma: no cover - compiled
        size, w1 = band.shape
        u = w1 - 1
        y = np.zeros(size)
        for j in range(size):
            zj = z[j]
            acc = band[j, 0] * zj
            for t in range(1, min(u, size - 1 - j) + 1):
                a = band[j, t]
                acc += a * z[j + t]
                y[j + t] += a * zj
            y[j] += acc
        return y

    _JIT_FACTOR, _JIT_SUBSTITUTE, _JIT_MATVEC = factor, substitute, matvec

    @njit(cache=True)
    def solve(band, rhs):                      # pragma: no cover - compiled
        low = band.copy()
        bad = _JIT_FACTOR(low)
        if bad >= 0:
            return rhs, bad
        z = rhs.copy()
        _JIT_SUBSTITUTE(low, z)
        # one step of iterative refinement
        res = rhs - _JIT_MATVEC(band, z)
        _JIT_SUBSTITUTE(low, res)
        z += res
        return z, -1

    @njit(cache=True)
    def envelopes(coef, cosp, sinp, m, trend):  # pragma: no cover - compiled
        k, n = cosp.shape
        cols = coef.shape[1]
        s = 1 if m == 1 else 4
        env = np.empty((n, k), np.complex128)
        mean = np.zeros(n)
        model = np.empty(n)
        # uniform knots: the spline weights of position t in every interval (as assemble)
        span = min(m, n)
        wpat = np.ones((span, 4))
        w = np.ones(4)
        if s > 1:
            for t in range(span):
                _JIT_SPLINE_W(t, m, w)
                wpat[t, :] = w
        for g in range((n - 1) // m + 1):
            for i in range(g * m, min(n, g * m + m)):
                w = wpat[i - g * m]
                tot = 0.0
                for j in range(k):
                    re = 0.0
                    im = 0.0
                    for a in range(s):
                        re += w[a] * coef[g + a, 2 * j]
                        im += w[a] * coef[g + a, 2 * j + 1]
                    env[i, j] = re + 1j * im
                    tot += re * cosp[j, i] - im * sinp[j, i]
                if trend:
                    c0 = 0.0
                    for a in range(s):
                        c0 += w[a] * coef[g + a, cols - 1]
                    mean[i] = c0
                    tot += c0
                model[i] = tot
        return env, mean, model

    return {"fir": fir, "basis": basis, "assemble": assemble, "solve": solve, "matvec": matvec,
            "factor": factor, "substitute": substitute, "spline_w": spline_w,
            "envelopes": envelopes}


def accelerated() -> bool:
    """True when the compiled VKF kernels are in use."""
    return _numba() is not None


# ---------------------------------------------------------------------------- decimation


def fir_decimate(x: np.ndarray, h: np.ndarray, q: int, first: int, n_out: int) -> np.ndarray:
    """``y[k] = Σ_t h[t] x[(first + k) q − L//2 + t]`` for a symmetric odd-length ``h``: the
    zero-phase filtered signal at input samples ``(first + k) q`` (all taps inside ``x``)."""
    x = np.ascontiguousarray(x, dtype=float)
    kernels = _numba()
    if kernels is not None:
        return kernels["fir"](x, h, int(q), int(first), int(n_out))
    from scipy.signal import upfirdn

    half = h.shape[0] // 2
    # upfirdn: out[j] = Σ_t h[t] x[q j − t]; with h symmetric, out[j] of x[o:], o = half mod q,
    # is the sample centred on input q (j − half // q) + ... = (first + k) q for j below
    o = half % q
    start = first + half // q
    stop = start + n_out
    # only the inputs the wanted outputs reach (upfirdn computes every output of its input)
    hi = min(x.shape[0], o + (stop - 1) * q + 1)
    return upfirdn(h, x[o:hi], down=q)[start:stop]


# ---------------------------------------------------------------------------- order basis


def order_basis(phi: np.ndarray, orders: np.ndarray):
    """``(cos(o_k φ), sin(o_k φ))``, each (N, K), for the shaft angle ``phi`` (rad, (N,)).

    The compiled form (|o φ| < :data:`BASIS_MAX_PHASE`) agrees with ``np.cos``/``np.sin`` to
    a few units in the last place (``tests/analysis/test_vkf_kernels.py``); its arrays are
    stored order by order (the returned (N, K) arrays are transposed views)."""
    phi = np.ascontiguousarray(phi, dtype=float)
    orders = np.ascontiguousarray(orders, dtype=float)
    kernels = _numba()
    top = float(np.abs(phi).max() * np.abs(orders).max()) if phi.size else 0.0
    if kernels is None or not top < BASIS_MAX_PHASE:          # (a NaN phase: numpy's NaN)
        phase = np.multiply.outer(phi, orders)
        return np.cos(phase), np.sin(phase)
    cos = np.empty((orders.shape[0], phi.shape[0]))
    sin = np.empty_like(cos)
    kernels["basis"](phi, orders, cos, sin)
    return cos.T, sin.T


# ---------------------------------------------------------------------------- normal equations


@functools.lru_cache(maxsize=32)
def _layout(m: int, s: int, u: int):
    """Where each (slot a, slot b, column j, column jj) product goes in upper banded storage
    of ``m`` unknowns per knot and ``s`` knots per sample: for slot pairs a ≤ b, the row
    ``u − d`` and column offset of every entry, with the index of its symmetric column pair."""
    pairs = [(j, jj) for j in range(m) for jj in range(j, m)]
    pair_index = {pr: i for i, pr in enumerate(pairs)}
    slot_pairs = [(a, b) for a in range(s) for b in range(a, s)]
    rows, col_off, src_slot, src_pair = [], [], [], []
    for ia, (a, b) in enumerate(slot_pairs):
        for j in range(m):
            for jj in range(m):
                d = (b - a) * m + (jj - j)
                if d < 0 or (a == b and jj < j):
                    continue
                rows.append(u - d)
                col_off.append(b * m + jj)
                src_slot.append(ia)
                src_pair.append(pair_index[(min(j, jj), max(j, jj))])
    return (np.array(pairs), slot_pairs, np.array(rows), np.array(col_off),
            np.array(src_slot), np.array(src_pair))


def spline_weights(n: int, m: int):
    """Envelope representation on knots every ``m`` samples.

    ``m == 1``: one unknown per sample (the classical VKF). ``m > 1``: uniform cubic B-spline
    coefficients; sample ``i`` uses coefficients ``q_i … q_i + 3``. Returns (q, W, n_coef)."""
    if m == 1:
        return np.arange(n), np.ones((n, 1)), n
    pos = np.arange(n) / m
    q = np.floor(pos).astype(np.int64)
    f = pos - q
    f2, f3 = f * f, f * f * f
    w = np.empty((n, 4))
    w[:, 0] = (1.0 - f) ** 3 / 6.0
    w[:, 1] = (3.0 * f3 - 6.0 * f2 + 4.0) / 6.0
    w[:, 2] = (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0) / 6.0
    w[:, 3] = f3 / 6.0
    return q, w, int(q[-1]) + 4


def band_width(cols: int, m: int, p: int) -> int:
    """Half-bandwidth ``u`` of the normal equations: ``cols`` unknowns per knot, each sample on
    ``s`` = 4 knots (1 for ``m == 1``), differences of order ``p``."""
    s = 1 if m == 1 else 4
    return cols * max(p, s - 1) + cols - 1


def assemble(x, cosp, sinp, trend: bool, m: int, n_coef: int, p: int, weights):
    """Column band form (module docstring) of ``A = CᵀC + Σ r² D_pᵀ D_p`` and ``Cᵀx``.

    ``C`` has the columns ``cos(o_k φ)``, ``−sin(o_k φ)`` (and 1 with ``trend``) times the
    spline weights of each sample's knots; unknown (knot c, column j) has the flat index
    ``cols c + j``. ``weights``: (n_coef − p, cols) r² per difference row and column.
    Work O(N (2K+1)² ) for the data part, O(n_coef (2K+1) p²) for the smoothness part.
    """
    k = cosp.shape[1]
    cols = 2 * k + (1 if trend else 0)
    u = band_width(cols, m, p)
    kernels = _numba()
    if kernels is not None:
        return kernels["assemble"](np.ascontiguousarray(x, dtype=float),
                                   np.ascontiguousarray(cosp.T), np.ascontiguousarray(sinp.T),
                                   bool(trend), int(m), int(n_coef), int(p),
                                   np.ascontiguousarray(weights, dtype=float), _DIFF[p], u)
    n = cosp.shape[0]
    basis = np.empty((n, cols))
    basis[:, 0:2 * k:2] = cosp
    basis[:, 1:2 * k:2] = -sinp
    if trend:
        basis[:, -1] = 1.0
    q, w, n_coef_w = spline_weights(n, m)
    assert n_coef_w == n_coef
    ab, rhs = _assemble_upper(basis, x, q, w, n_coef, weights, p, u)
    band = np.zeros((n_coef * cols, u + 1))
    for d in range(u + 1):                   # A[j + d, j] = upper[u - d, j + d]
        band[: band.shape[0] - d, d] = ab[u - d, d:]
    return band, rhs


def _assemble_upper(basis, x, q, w, n_coef, weights, p, u):
    """numpy form: upper banded storage (LAPACK) of the same matrix, and the right side."""
    n, m = basis.shape
    s = w.shape[1]
    size = n_coef * m
    pairs, slot_pairs, rows, col_off, src_slot, src_pair = _layout(m, s, u)
    prod = basis[:, pairs[:, 0]] * basis[:, pairs[:, 1]]            # (N, P)
    groups = int(q[-1]) + 1
    if s > 1:
        span = int(np.max(np.bincount(q)))
        # sample i sits at position i - span*q_i of its knot interval (uniform knots): lay the
        # products out as (position, interval, pair) and sum each interval with the spline
        # weights of every position in one matrix product
        pos = np.arange(n) - span * q
        lay = np.zeros((span, groups, prod.shape[1]))
        lay[pos, q] = prod
        wpat = np.zeros((len(slot_pairs), span))
        wpat[:, pos[:span]] = np.stack([w[:span, a] * w[:span, b] for a, b in slot_pairs])
        sums = (wpat @ lay.reshape(span, -1)).reshape(len(slot_pairs), groups, -1)
        lay_x = np.zeros((span, groups, m))
        lay_x[pos, q] = basis * x[:, None]
        wv = np.zeros((s, span))
        wv[:, pos[:span]] = w[:span].T
        rsum = (wv @ lay_x.reshape(span, -1)).reshape(s, groups, m)
    else:
        sums = prod[None]                                            # (1, N, P)
        rsum = (basis * x[:, None])[None]                            # (1, N, m)
    # scatter: entry (row, g m + col_off) gets sums[src_slot, g, src_pair]
    g = np.arange(groups)
    flat_cols = (g[:, None] * m + col_off[None, :]).ravel()
    flat_rows = np.broadcast_to(rows, (groups, rows.shape[0])).ravel()
    vals = sums[src_slot, :, src_pair].T.ravel()
    ab = np.bincount(flat_rows * size + flat_cols, weights=vals,
                     minlength=(u + 1) * size).reshape(u + 1, size)
    c = _DIFF[p]
    rowsd = np.arange(weights.shape[0])
    for a in range(p + 1):
        for b in range(a, p + 1):
            cols = ((rowsd[:, None] + b) * m + np.arange(m)[None, :]).ravel()
            ab[u - (b - a) * m, cols] += c[a] * c[b] * weights.ravel()
    rhs = np.bincount(((g[None, :, None] + np.arange(s)[:, None, None]) * m
                       + np.arange(m)[None, None, :]).ravel(), weights=rsum.ravel(),
                      minlength=size)
    return ab, rhs


# ---------------------------------------------------------------------------- banded solve


#: widest band (u + 1 columns) factorised by the compiled kernel; wider bands (K ≥ 5 orders
#: with the trend) go to LAPACK's blocked ``dpbtrf``, whose BLAS-3 trailing updates win there
#: (measured: equal at 36 columns, 3x faster at 68, 4x at 132)
COMPILED_MAX_BAND = 40


def solve(band: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``z = A⁻¹ rhs`` for ``A`` in column band form, by Cholesky with one refinement step.

    Raises :class:`NotPositiveDefinite` on a non-positive pivot. O(n u²) work, O(n u) memory;
    bands wider than :data:`COMPILED_MAX_BAND` (and the numpy form) use LAPACK ``dpbtrf`` /
    ``dpbtrs`` with one BLAS thread.
    """
    kernels = _numba()
    if kernels is not None and band.shape[1] <= COMPILED_MAX_BAND:
        z, bad = kernels["solve"](band, np.ascontiguousarray(rhs, dtype=float))
        if bad >= 0:
            raise NotPositiveDefinite(f"pivot {bad} is not positive")
        return z
    from scipy.linalg import cho_solve_banded, cholesky_banded

    from crankbench.predict._threads import limit_blas

    matvec = _matvec if kernels is None else kernels["matvec"]
    # LAPACK's lower band form (dpbtrf 'L') is the transpose; OpenBLAS's threaded upper-form
    # path can be ~100x slower on a busy machine
    low = np.ascontiguousarray(band.T)
    with limit_blas():
        try:
            factor = cholesky_banded(low, lower=True, check_finite=False)
        except np.linalg.LinAlgError as exc:
            raise NotPositiveDefinite(str(exc)) from None
        z = cho_solve_banded((factor, True), rhs, check_finite=False)
        z += cho_solve_banded((factor, True), rhs - matvec(band, z), check_finite=False)
    return z


def _matvec(band, z):
    """y = A z for a symmetric matrix in column band form."""
    u = band.shape[1] - 1
    y = band[:, 0] * z
    for d in range(1, u + 1):
        diag = band[:-d, d]                    # A[j + d, j]
        y[d:] += diag * z[:-d]
        y[:-d] += diag * z[d:]
    return y


# ---------------------------------------------------------------------------- envelopes


def envelopes(coef, cosp, sinp, m: int, trend: bool):
    """(complex envelopes (N, K), trend (N,), model (N,)) from the spline coefficients
    ``coef`` (n_coef, cols) at every sample; the model is ``Σ Re{A_k e^{iφ_k}} + trend``."""
    kernels = _numba()
    if kernels is not None:
        return kernels["envelopes"](np.ascontiguousarray(coef), np.ascontiguousarray(cosp.T),
                                    np.ascontiguousarray(sinp.T), int(m), bool(trend))
    n, k = cosp.shape
    q, w, _ = spline_weights(n, m)
    cplx = coef[:, 0:2 * k:2] + 1j * coef[:, 1:2 * k:2]
    env = np.zeros((n, k), dtype=complex)
    mean = np.zeros(n)
    for a in range(w.shape[1]):
        env += w[:, a:a + 1] * cplx[q + a]
        if trend:
            mean += w[:, a] * coef[q + a, -1]
    model = (env.real * cosp - env.imag * sinp).sum(axis=1) + mean
    return env, mean, model

