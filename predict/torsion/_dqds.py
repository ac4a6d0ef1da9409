"""dqds on a qd array, compiled by numba: every eigenvalue of ``BᵀB`` to high relative accuracy.

The array is ``q`` (squared diagonal of an upper bidiagonal ``B``, > 0) and ``e`` (squared
superdiagonal, > 0). One dqds transform with shift τ (Fernando & Parlett, Numer. Math. 67
(1994) 191; Parlett & Marques, Linear Algebra Appl. 309 (2000) 217)::

    d = q₁ − τ;  for i: q̂ᵢ = d + eᵢ,  t = qᵢ₊₁ / q̂ᵢ,  êᵢ = eᵢ t,  d = d t − τ;  q̂ₙ = d

maps the array of ``BᵀB`` to that of ``BᵀB − τI`` with relative errors of a few ulps per
entry, as long as every pivot ``d`` stays ≥ 0 (τ below the smallest eigenvalue); the shifts
are summed in ``S`` (positive terms only), so an eigenvalue ``S + q̂ₙ`` carries no cancellation.

What this implementation does (its own choices, written from the published algorithm):

* **Shift**: the Rayleigh quotient of ``B``'s near-null vector, ``(v_k / v_n)² = Π eⱼ/qⱼ``
  (rows above the last give ``Bv = 0`` exactly), ``ρ = qₙ / (1 + a₂)`` with ``a₂ = Σ (v_k/v_n)²``;
  ρ ≥ λ_min, so the shift is ρ less a margin ``16·a₂·qₙ/qₙ₋₁`` (a multiple of its first-order
  overshoot, the multiple tuned on the bench chains: fewer failed transforms) and
  never above the smallest pivot of the last transform (every pivot is ≥ λ_min of the new
  array: it is the last pivot of a leading block). Without a usable ρ the shift is half the
  smallest pivot. Either is raised to Newton's step from below on ``f(x) = Σ 1/(λᵢ − x)``,
  ``1/tr(A⁻¹) ≤ λ_min``, when that is larger (graded arrays, where the smallest eigenvalue
  sits far from the bottom and ρ is useless): ``tr(A⁻¹) = ‖B⁻¹‖_F² = Σ cⱼ/qⱼ`` with
  ``c₁ = 1``, ``cⱼ₊₁ = 1 + cⱼ eⱼ/qⱼ`` (column norms of ``B⁻¹``: sums of positive terms),
  accumulated during the last transform (or in one pass at a block's start), less
  ``4·n·eps`` for its rounding. A transform with a negative pivot is discarded (the loop stops
  at the first negative pivot) and redone with a smaller shift: ``τ + dₙ`` when only the last
  pivot ``dₙ(τ)`` is negative (then exactly one eigenvalue lies below τ, Sylvester's law of
  inertia, and ``dₙ(x) = 1/(eₙᵀ(A − x)⁻¹eₙ)`` falls from 0 at λ_min with slope ≤ −1, so
  ``λ_min ≥ τ + dₙ``), else Newton's step, else the unraised shift or ρ(1 − a₂), then a
  quarter, then zero. The shift only decides the speed: a transform is kept only when every
  pivot is ≥ 0.
* **Three transforms per pass**: the inner loop is bound by the latency of one division
  chain; two unshifted transforms (dqd, which cannot fail on a positive array) follow the
  shifted one one and two elements behind in the same loop, so the three chains overlap. Their convergence factor at the bottom,
  ``(λₙ − S)/(λₙ₋₁ − S)``, is as small as the shifted one's because ``S`` already holds the
  shift.
* **Deflation and splitting** where ``e ≤ tol²·S`` (tol = 16 eps): zeroing ``√e`` in ``B`` moves
  each singular value σ by at most ``√e`` (Weyl), so ``λ = σ² + S`` moves by at most
  ``2σ√e + e ≤ tol·λ + tol²·S`` — a relative change (tests relative to neighbouring ``q``
  alone are not safe: a large ``e`` below can make the block's smallest value far smaller than
  its ``q``); Demmel-Kahan splits where ``e ≤ tol²·d`` (``d`` the zero-shift pivot above).
  The bottom row also deflates by a **gap test**: ``BᵀB = [[A₁, c], [cᵀ, qₙ + eₙ₋₁]]`` with
  ``‖c‖² = qₙ₋₁ eₙ₋₁`` and ``A₁`` the array without its last row, so if ``qₙ + eₙ₋₁`` lies
  below ``λ_min(A₁) ≥ 1/tr(A₁⁻¹)`` by ``g > 0``, dropping ``c`` moves every eigenvalue by at
  most ``‖c‖²/g`` (quadratic residual bound: Li & Li, Linear Algebra Appl. 395 (2005) 183;
  Mathias, SIAM J. Matrix Anal. Appl. 19 (1998) 541); the test ``qₙ₋₁ eₙ₋₁ ≤ eps·g·(S +
  1/tr(A⁻¹))`` keeps that below eps relative to every eigenvalue, and the deflated value is
  ``S + qₙ + eₙ₋₁``; with dqds converging faster than linearly it usually saves a pass.
  Blocks are reversed at their start when the bottom is larger than the top (dqds finds the
  small end at the bottom fastest; ``PBᵀP`` has the same singular values).

Any doubt — a non-finite value, a transform that fails even unshifted, too many passes —
returns a status ≠ 0 and the caller uses LAPACK ``dlasq2`` instead.
"""

from __future__ import annotations

import functools
import os

import numpy as np

__all__ = ["available", "qd_eigenvalues"]

#: deflation tolerance, a multiple of eps (see the module docstring)
TOL_EPS = 16.0

#: smaller arrays go to LAPACK ``dlasq2``: there the call costs microseconds either way, and a
#: one-shot solve of a small engine model should not pay numba's start-up (about 0.5-1 s once
#: per process when no other compiled kernel has run yet; about 10 ms after one has)
MIN_SIZE = 64

#: qd entries outside this range (and eigenvalues outside its square) go to LAPACK ``dlasq2``,
#: which scales: intermediate pivots far below an eigenvalue must stay clear of underflow
_SAFE_RANGE = (1e-60, 1e60)


@functools.lru_cache(maxsize=1)
def _kernel():
    """The compiled kernel, or None (numba missing, or ``CRANKBENCH_NO_NUMBA`` set)."""
    if os.environ.get("CRANKBENCH_NO_NUMBA"):
        return None
    try:
        from numba import njit
    except ImportError:  # pragma: no cover - numba is a core dependency
        return None

    # error_model='numpy': a division by zero gives inf/NaN (caught below), not an exception
    @njit(cache=True, error_model="numpy")
    def dqds(q0, e0, tol, lo, hi):  # pragma: no cover - compiled
        n = q0.shape[0]
        eps = np.finfo(np.float64).eps
        tol2 = tol * tol
        for i in range(n):
            if not (lo < q0[i] < hi):
                return q0, 5
        for i in range(n - 1):
            if not (lo < e0[i] < hi):
                return q0, 5
        Q = np.empty((4, n))
        E = np.zeros((4, n))
        for i in range(n):
            Q[0, i] = q0[i]
        for i in range(n - 1):
            E[0, i] = e0[i]
        lam = np.empty(n)
        st_top = np.empty(n, np.int64)
        st_bot = np.empty(n, np.int64)
        st_s = np.empty(n)
        st_p = np.empty(n, np.int64)
        splits = np.empty(n, np.int64)
        # Demmel-Kahan splits of the input (m: zero-shift pivots, top down)
        ns = 0
        top = 0
        m = Q[0, 0]
        for j in range(n - 1):
            if E[0, j] <= tol2 * m:
                E[0, j] = 0.0
                st_top[ns] = top
                st_bot[ns] = j
                st_s[ns] = 0.0
                st_p[ns] = 0
                ns += 1
                top = j + 1
                m = Q[0, j + 1]
            else:
                m = Q[0, j + 1] * (m / (m + E[0, j]))
        st_top[ns] = top
        st_bot[ns] = n - 1
        st_s[ns] = 0.0
        st_p[ns] = 0
        ns += 1
        passes = 0
        max_passes = 30 * n + 100
        while ns > 0:
            ns -= 1
            i0 = st_top[ns]
            n0 = st_bot[ns]
            S = st_s[ns]
            p = st_p[ns]
            q = Q[p]
            e = E[p]
            if n0 > i0 and 1.5 * q[i0] < q[n0]:      # small end to the bottom
                q[i0:n0 + 1] = q[i0:n0 + 1][::-1].copy()
                e[i0:n0] = e[i0:n0][::-1].copy()
            up0 = np.inf      # upper bound on the block's smallest eigenvalue (min pivot)
            up1 = np.inf      # the same without the last row
            up2 = np.inf      # ... without the last two
            # trace of the block's inverse (Σ 1/λ: 1/tr0 ≤ λ_min), the same without the last
            # row and without the last two (column norms of B⁻¹: cⱼ₊₁ = 1 + cⱼ eⱼ/qⱼ)
            tc = 1.0
            tt = 0.0
            tt1 = 0.0
            tt2 = 0.0
            for j in range(i0, n0 + 1):
                w = tc * (1.0 / Q[p, j])
                tt2 = tt1
                tt1 = tt
                tt += w
                tc = 1.0 + E[p, j] * w
            tr0 = tt if tt == tt else np.inf
            tr1 = tt1 if tt1 == tt1 else np.inf
            tr2 = tt2 if tt2 == tt2 else np.inf
            while n0 >= i0:
                q = Q[p]
                e = E[p]
                if n0 == i0:
                    lam[n0] = q[n0] + S
                    n0 -= 1
                    continue
                el = e[n0 - 1]
                # quadratic (gap) test: BᵀB = [[A₁, c], [cᵀ, qₙ + e]] with ‖c‖² = qₙ₋₁ e;
                # every eigenvalue moves by at most ‖c‖²/g, g = λ_min(A₁) − qₙ − e and
                # λ_min(A₁) ≥ 1/tr1; all eigenvalues are ≥ S + 1/tr0
                gap = (1.0 - 4.0 * (n0 - i0 + 1) * eps) / tr1 - (q[n0] + el)
                if el <= tol2 * S or (gap > 0.0 and q[n0 - 1] * el
                                      <= eps * gap * (S + 1.0 / tr0)):
                    lam[n0] = q[n0] + el + S
                    n0 -= 1
                    up0 = up1
                    up1 = up2
                    up2 = np.inf
                    tr0 = tr1
                    tr1 = tr2
                    tr2 = np.inf
                    continue
                if n0 == i0 + 1 or e[n0 - 2] <= tol2 * S:
                    # 2x2 block [[q1, √(q1 e)], [√(q1 e), q2 + e]]: product q1 q2, sum
                    # q1 + q2 + e, discriminant (q1 − q2 − e)² + 4 q1 e (no cancellation)
                    a = q[n0 - 1]
                    b = q[n0]
                    c = el
                    d = a - b - c
                    big = 0.5 * (a + b + c + np.sqrt(d * d + 4.0 * a * c))
                    lam[n0] = a * (b / big) + S
                    lam[n0 - 1] = big + S
                    n0 -= 2
                    up0 = up2
                    up1 = np.inf
                    up2 = np.inf
                    tr0 = tr2
                    tr1 = np.inf
                    tr2 = np.inf
                    continue
                passes += 1
                if passes > max_passes:
                    return lam, 3
                # shift from the Rayleigh quotient of B's near-null vector
                dn = q[n0]
                a2 = 0.0
                prod = 1.0
                k = n0 - 1
                while k >= i0:
                    prod *= e[k] / q[k]
                    a2 += prod
                    if prod <= 1e-3 * a2 or k <= n0 - 30:
                        break
                    k -= 1
                rq = dn / (1.0 + a2)
                safe = 0.0
                if a2 < 0.25 and rq < up0:
                    safe = rq * (1.0 - a2)
                    margin = max(16.0 * a2 * min(1.0, dn / q[n0 - 1]), 64.0 * eps)
                    tau = rq * (1.0 - min(margin, 1.0))
                else:
                    tau = 0.5 * min(up0, dn)
                # Newton's step from below on Σ 1/(λᵢ − x): 1/tr0 ≤ λ_min, less its rounding
                newton = (1.0 - 4.0 * (n0 - i0 + 1) * eps) / tr0
                if newton > tau:
                    if tau > 0.0:
                        safe = tau
                    tau = newton
                if not (tau >= 0.0 and tau < np.inf):
                    tau = 0.0
                p1 = (p + 1) % 4
                p2 = (p + 2) % 4
                p3 = (p + 3) % 4
                qa = Q[p1]
                ea = E[p1]
                qb = Q[p2]
                eb = E[p2]
                qc = Q[p3]
                ec = E[p3]
                fails = 0
                while True:
                    # transform 1 (shift tau) into qa/ea; transforms 2 and 3 (no shift) one
                    # and two elements behind it, qa/ea -> qb/eb -> qc/ec
                    d = q[i0] - tau
                    dmin = d
                    ok = d >= 0.0
                    qh = d + e[i0]
                    qa[i0] = qh
                    t = q[i0 + 1] / qh
                    ea[i0] = e[i0] * t
                    d = d * t - tau
                    dmin = min(dmin, d)
                    d2 = qh
                    d3 = 0.0
                    m0 = np.inf
                    m1 = np.inf
                    m2 = np.inf
                    tc = 1.0          # ‖B⁻¹eⱼ‖² qⱼ of transform 3's array, top down
                    tt = 0.0          # Σ ‖B⁻¹eⱼ‖² so far (its bottom block's)
                    tt1 = 0.0
                    tt2 = 0.0
                    n_split = 0
                    last_only = False
                    for i in range(i0 + 1, n0):
                        qh = d + e[i]
                        qa[i] = qh
                        t = q[i + 1] / qh
                        ea[i] = e[i] * t
                        d = d * t - tau
                        if d < 0.0:              # shift too large: stop here
                            dmin = d
                            last_only = i == n0 - 1
                            break
                        # transform 2 at i - 1 (needs qa[i], just written)
                        j = i - 1
                        qh2 = d2 + ea[j]
                        qb[j] = qh2
                        t2 = qa[i] / qh2
                        eb[j] = ea[j] * t2
                        d2 = d2 * t2
                        if j == i0:
                            d3 = qh2
                            m0 = d3
                            continue
                        # transform 3 at i - 2 (needs qb[i - 1], just written)
                        j = i - 2
                        ebj = eb[j]
                        if ebj <= tol2 * d3:
                            # Demmel-Kahan split of qb: d3 is the j-th zero-shift pivot, so
                            # dropping ebj moves every σ by a factor within 1 ± tol
                            qc[j] = d3
                            ec[j] = 0.0
                            d3 = qb[j + 1]
                            splits[n_split] = j
                            n_split += 1
                            m2 = np.inf
                            m1 = np.inf
                            m0 = d3
                            tc = 1.0
                            tt = 0.0
                            tt1 = 0.0
                            tt2 = 0.0
                            continue
                        qh3 = d3 + ebj
                        qc[j] = qh3
                        t3 = qb[j + 1] / qh3
                        eh3 = ebj * t3
                        ec[j] = eh3
                        d3 = d3 * t3
                        m2 = m1
                        m1 = m0
                        m0 = min(m0, d3)
                        # trace of the inverse (column norms of B⁻¹: cⱼ₊₁ = 1 + cⱼ eⱼ/qⱼ)
                        w = tc * (1.0 / qh3)
                        tt2 = tt1
                        tt1 = tt
                        tt += w
                        tc = 1.0 + eh3 * w
                        if eh3 <= tol2 * (S + tau):   # Weyl split of qc
                            ec[j] = 0.0
                            splits[n_split] = j
                            n_split += 1
                            tc = 1.0
                            tt = 0.0
                            tt1 = 0.0
                            tt2 = 0.0
                    qa[n0] = d
                    if dmin >= 0.0 and ok and d == d:
                        # finish transform 2 at n0 - 1, transform 3 at n0 - 2 and n0 - 1
                        j = n0 - 1
                        qh2 = d2 + ea[j]
                        qb[j] = qh2
                        t2 = d / qh2
                        eb[j] = ea[j] * t2
                        qb[n0] = d2 * t2
                        if n0 - 2 == i0:
                            d3 = qb[i0]
                            m0 = d3
                        for j in range(n0 - 2, n0):
                            qh3 = d3 + eb[j]
                            qc[j] = qh3
                            t3 = qb[j + 1] / qh3
                            eh3 = eb[j] * t3
                            ec[j] = eh3
                            d3 = d3 * t3
                            m2 = m1
                            m1 = m0
                            m0 = min(m0, d3)
                            w = tc / qh3
                            tt2 = tt1
                            tt1 = tt
                            tt += w
                            tc = 1.0 + eh3 * w
                        qc[n0] = d3
                        tt2 = tt1
                        tt1 = tt
                        tt += tc / d3
                        break
                    fails += 1
                    if fails < 3 and last_only and ok and tau + d > 0.0:
                        # only the last pivot dₙ(τ) < 0: one eigenvalue below τ (Sylvester),
                        # and dₙ(x) falls with slope ≤ −1 from 0 at λ_min, so λ_min ≥ τ + dₙ
                        tau = tau + d - 8.0 * eps * tau
                    elif 0.0 < newton < tau:     # a lower bound on λ_min (up to rounding)
                        tau = newton
                    elif fails == 1 and 0.0 < safe < tau:
                        tau = safe
                    elif fails >= 3 or tau == 0.0:
                        if tau == 0.0:
                            return lam, 2
                        tau = 0.0
                    else:
                        tau = 0.25 * tau
                S += tau
                if m0 >= 0.0 and d3 == d3 and qc[n0 - 1] > 0.0:
                    p = p3
                    up0 = m0
                    up1 = m1
                    up2 = m2
                    tr0 = tt if tt == tt else np.inf
                    tr1 = tt1 if tt1 == tt1 else np.inf
                    tr2 = tt2 if tt2 == tt2 else np.inf
                    # blocks above the splits wait on the stack, the bottom one goes on
                    for k in range(n_split):
                        j = splits[k]
                        st_top[ns] = i0
                        st_bot[ns] = j
                        st_s[ns] = S
                        st_p[ns] = p
                        ns += 1
                        i0 = j + 1
                else:                    # keep the shifted transform alone
                    p = p1
                    up0 = np.inf         # (its pivots were not kept)
                    up1 = np.inf
                    up2 = np.inf
                    tr0 = np.inf
                    tr1 = np.inf
                    tr2 = np.inf
        for i in range(n):
            if not (lam[i] >= 0.0 and lam[i] < np.inf):
                return lam, 4
        lam.sort()
        return lam, 0

    return dqds


def available() -> bool:
    """True when the compiled kernel is in use (else callers use LAPACK ``dlasq2``)."""
    return _kernel() is not None


def qd_eigenvalues(q: np.ndarray, e2: np.ndarray):
    """Eigenvalues (ascending) of ``BᵀB`` for the qd array ``q`` (n, > 0), ``e2`` (n−1, > 0),
    or None when the array is small (:data:`MIN_SIZE`), outside the safe range, the compiled
    kernel is unavailable or it reports any doubt (the caller then uses LAPACK ``dlasq2``).

    Parameters
    ----------
    q : ndarray, shape (n,)
        Squared diagonal of the upper bidiagonal ``B``.
    e2 : ndarray, shape (n−1,)
        Squared superdiagonal.

    Returns
    -------
    ndarray or None
        Squared singular values of ``B``, ascending.
    """
    if q.size < MIN_SIZE:
        return None
    kernel = _kernel()
    if kernel is None:
        return None
    lo, hi = _SAFE_RANGE
    lam, status = kernel(np.ascontiguousarray(q, dtype=np.float64),
                         np.ascontiguousarray(e2, dtype=np.float64),
                         TOL_EPS * np.finfo(float).eps, lo, hi)    # status 5: out of range
    # far from under/overflow, intermediate pivots keep their relative accuracy; an
    # eigenvalue outside the range (or any status) hands the array to LAPACK
    if status != 0 or not (lam[0] > lo and lam[-1] < hi):
        return None
    return lam
