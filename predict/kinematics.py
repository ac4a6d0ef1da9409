"""Slider-crank kinematics: exact motion and its harmonic series in λ = r/l.

Geometry (one cylinder, seen along the crankshaft): the crank of radius ``r`` turns through
``θ`` measured from top dead centre (TDC) in the direction of rotation, the rod of length ``l``
joins the crank pin to the piston pin, which moves on the cylinder axis, offset sideways by the
pin offset ``e`` (désaxé, positive towards the side the crank pin passes on its way down, i.e.
towards ``θ = 90°``).  The piston position measured from the crank axis along the cylinder axis,
positive towards the cylinder head, is

    x(θ) = r cos θ + l cos φ,     sin φ = (r sin θ − e) / l,

with φ the rod angle.  At constant speed ω the acceleration is

    a = ẍ = −r ω² (a₁ cos θ + a₂ cos 2θ + a₄ cos 4θ + a₆ cos 6θ + …)   (e = 0),

with a₁ = 1 and a₂ = λ + λ³/4 + 15λ⁵/128 + …, a₄ = −(λ³/4 + 3λ⁵/16 + …), … (Liang 1948,
ch. 1 §1-2, eq. (4)).  :func:`series_coefficients` gives the exact coefficients to any order
(every term of each coefficient's power series has the same sign, so they are summed to full
float64 accuracy); :func:`truncation_bound` bounds the error of the truncated series and
:func:`order_for_tolerance` picks the lowest order that meets a tolerance.

References
----------
Liang Shoupan, *Engine Dynamics* (發動機動力學), Commercial Press 1948, ch. 1 §1-2 to §1-4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ._validate import check_finite_array, check_int, check_positive
from .errors import ModelError

__all__ = [
    "check_geometry",
    "rod_angle",
    "rod_angular_velocity",
    "rod_angular_acceleration",
    "piston_position",
    "piston_displacement",
    "piston_velocity",
    "piston_acceleration",
    "series_coefficients",
    "displacement_coefficients",
    "truncation_bound",
    "order_for_tolerance",
    "acceleration_series",
    "AccelerationSeries",
    "series_error",
]

#: highest series order accepted (coefficients beyond it underflow float64 for λ ≤ 0.45)
MAX_SERIES_ORDER = 400


def check_geometry(crank_radius, rod_length, pin_offset=0.0) -> tuple[float, float, float]:
    """Validate a slider-crank geometry and return ``(r, l, e)`` as floats (m).

    Raises :class:`~predict.errors.ModelError` unless r > 0, l > r + |e| (the rod can always
    reach the cylinder axis).

    Examples
    --------
    >>> check_geometry(0.05, 0.2)
    (0.05, 0.2, 0.0)
    """
    r = check_positive(crank_radius, "crank_radius", error=ModelError)
    l = check_positive(rod_length, "rod_length", error=ModelError)
    try:
        e = float(pin_offset)
    except (TypeError, ValueError):
        raise ModelError(f"pin_offset={pin_offset!r} must be a real number (m)") from None
    if not np.isfinite(e):
        raise ModelError(f"pin_offset={pin_offset!r} must be finite")
    if l <= r + abs(e):
        raise ModelError(
            f"rod_length={l!r} must exceed crank_radius + |pin_offset| = {r + abs(e)!r} "
            "(otherwise the rod cannot follow the crank)")
    return r, l, e


def _theta(theta) -> np.ndarray:
    return check_finite_array(theta, "theta", error=ModelError)


def _omega(omega) -> float:
    try:
        w = float(omega)
    except (TypeError, ValueError):
        raise ModelError(f"omega={omega!r} must be a real number (rad/s)") from None
    if not np.isfinite(w):
        raise ModelError(f"omega={omega!r} must be finite (rad/s)")
    return w


def _out(values, theta):
    return float(values) if np.ndim(theta) == 0 else values


def _state(theta, r, l, e):
    """sin φ, cos φ of the rod and dφ/dθ, d²φ/dθ² (per unit ω)."""
    s = (r * np.sin(theta) - e) / l
    c = np.sqrt(1.0 - s * s)
    dphi = r * np.cos(theta) / (l * c)
    # differentiate l sin φ = r sin θ − e twice: l(cos φ φ'' − sin φ φ'²) = −r sin θ
    d2phi = (l * s * dphi**2 - r * np.sin(theta)) / (l * c)
    return s, c, dphi, d2phi


def rod_angle(theta, *, crank_radius, rod_length, pin_offset=0.0):
    """Connecting-rod angle φ from the cylinder axis (rad), sin φ = (r sin θ − e)/l.

    Parameters
    ----------
    theta : float or array_like
        Crank angle from TDC, rad.
    crank_radius, rod_length : float
        r and l, m.
    pin_offset : float, optional
        Piston-pin offset e (désaxé), m.

    Returns
    -------
    float or ndarray
        φ, rad; positive while the crank pin is on the θ = 90° side.

    References
    ----------
    Liang 1948, ch. 1 eq. (1).

    Examples
    --------
    >>> round(rod_angle(np.pi / 2, crank_radius=0.05, rod_length=0.2), 6)
    0.25268
    """
    r, l, e = check_geometry(crank_radius, rod_length, pin_offset)
    th = _theta(theta)
    return _out(np.arcsin((r * np.sin(th) - e) / l), theta)


def rod_angular_velocity(theta, *, crank_radius, rod_length, omega, pin_offset=0.0):
    """Rod angular velocity dφ/dt (rad/s) at constant crank speed ω (rad/s).

    dφ/dt = ω r cos θ / (l cos φ).

    Examples
    --------
    >>> round(rod_angular_velocity(0.0, crank_radius=0.05, rod_length=0.2, omega=100.0), 6)
    25.0
    """
    r, l, e = check_geometry(crank_radius, rod_length, pin_offset)
    w = _omega(omega)
    th = _theta(theta)
    return _out(_state(th, r, l, e)[2] * w, theta)


def rod_angular_acceleration(theta, *, crank_radius, rod_length, omega, pin_offset=0.0):
    """Rod angular acceleration d²φ/dt² (rad/s²) at constant crank speed ω.

    For e = 0 this is −λ ω² sin θ (1 − λ²) / (1 − λ² sin² θ)^{3/2}, whose harmonic series is
    Liang 1948 ch. 1 §1-4 (the series behind the residual couple, eq. (10)).

    Examples
    --------
    >>> round(rod_angular_acceleration(np.pi / 2, crank_radius=0.05, rod_length=0.2,
    ...                                omega=100.0), 3)
    -2581.989
    """
    r, l, e = check_geometry(crank_radius, rod_length, pin_offset)
    w = _omega(omega)
    th = _theta(theta)
    return _out(_state(th, r, l, e)[3] * w * w, theta)


def piston_position(theta, *, crank_radius, rod_length, pin_offset=0.0):
    """Piston-pin distance from the crank axis along the cylinder axis, x = r cos θ + l cos φ (m).

    Examples
    --------
    >>> piston_position(0.0, crank_radius=0.05, rod_length=0.2)
    0.25
    """
    r, l, e = check_geometry(crank_radius, rod_length, pin_offset)
    th = _theta(theta)
    s = (r * np.sin(th) - e) / l
    return _out(r * np.cos(th) + l * np.sqrt(1.0 - s * s), theta)


def piston_displacement(theta, *, crank_radius, rod_length, pin_offset=0.0):
    """Piston travel from the top of its stroke towards the crank (m), 0 at the top.

    With a pin offset the top of the stroke is not at θ = 0 but where the rod and crank are in
    line, x_max = sqrt((l + r)² − e²).

    Examples
    --------
    >>> round(piston_displacement(np.pi, crank_radius=0.05, rod_length=0.2), 12)
    0.1
    """
    r, l, e = check_geometry(crank_radius, rod_length, pin_offset)
    th = _theta(theta)
    s = (r * np.sin(th) - e) / l
    x = r * np.cos(th) + l * np.sqrt(1.0 - s * s)
    return _out(math.sqrt((l + r) ** 2 - e * e) - x, theta)


def piston_velocity(theta, *, crank_radius, rod_length, omega, pin_offset=0.0):
    """Piston velocity dx/dt (m/s), positive towards the cylinder head, at constant ω (rad/s).

    dx/dt = −ω r sin(θ + φ) / cos φ.

    Examples
    --------
    >>> round(piston_velocity(np.pi / 2, crank_radius=0.05, rod_length=0.2, omega=100.0), 6)
    -5.0
    """
    r, l, e = check_geometry(crank_radius, rod_length, pin_offset)
    w = _omega(omega)
    th = _theta(theta)
    s, c, _, _ = _state(th, r, l, e)
    return _out(-w * r * (np.sin(th) * c + np.cos(th) * s) / c, theta)


def _exact_acceleration(th, r, l, e, w):
    s, c, dphi, d2phi = _state(th, r, l, e)
    # x = r cos θ + l cos φ  ->  x'' = −r cos θ − l (cos φ φ'² + sin φ φ'')
    return -w * w * (r * np.cos(th) + l * (c * dphi**2 + s * d2phi))


def piston_acceleration(theta, *, crank_radius, rod_length, omega, max_order=None,
                        pin_offset=0.0, lambda_terms=None):
    """Piston acceleration (m/s²), positive towards the cylinder head, at constant ω.

    Parameters
    ----------
    theta : float or array_like
        Crank angle from TDC, rad.
    crank_radius, rod_length : float
        Crank radius r and rod length l (centre to centre), m.
    omega : float
        Crank angular speed, rad/s (constant).
    max_order : int or None
        None: exact closed form. An integer N ≥ 1: the harmonic series
        −r ω² Σ_{n≤N} aₙ cos nθ truncated after order N (its error is at most
        :func:`truncation_bound` · r ω²).
    lambda_terms : int, optional
        With ``max_order``: keep only the lowest ``lambda_terms`` powers of λ in each
        coefficient (``max_order=2, lambda_terms=1`` is the textbook cos θ + λ cos 2θ).
    pin_offset : float
        Piston-pin offset e, m (0: centred). With an offset the series has odd orders and sine
        terms; its coefficients then come from a 256-point FFT of the exact motion (absolute
        error ~1e-15 of r ω²).

    Returns
    -------
    float or ndarray
        Acceleration, m/s², same shape as ``theta``.

    References
    ----------
    Liang 1948, ch. 1 §1-2 eq. (4), (4A).

    Examples
    --------
    >>> w = 4000 * 2 * np.pi / 60
    >>> round(piston_acceleration(0.0, crank_radius=2 / 12, rod_length=7 / 12, omega=w))
    -37598
    >>> round(piston_acceleration(0.0, crank_radius=2 / 12, rod_length=7 / 12, omega=w,
    ...                           max_order=2))
    -37776
    """
    r, l, e = check_geometry(crank_radius, rod_length, pin_offset)
    w = _omega(omega)
    th = _theta(theta)
    if max_order is None:
        return _out(_exact_acceleration(th, r, l, e, w), theta)
    n = check_int(max_order, "max_order", minimum=1, error=ModelError)
    if e == 0.0:
        a = series_coefficients(r / l, n, lambda_terms=lambda_terms)
        acc = -r * w * w * (np.cos(th) + _clenshaw_even(a, th))
    else:
        if lambda_terms is not None:
            raise ModelError("lambda_terms needs a centred piston pin (pin_offset = 0)")
        cos_c, sin_c = _offset_coefficients(r, l, e, n)
        orders = np.arange(n + 1)
        ang = np.multiply.outer(th, orders)
        acc = -r * w * w * (np.cos(ang) @ cos_c + np.sin(ang) @ sin_c)
    return _out(acc, theta)


# --------------------------------------------------------------------------------------------
# harmonic series
# --------------------------------------------------------------------------------------------
def _clenshaw_even(a, th):
    """Σ_{k≥1} a_{2k} cos 2kθ by Clenshaw's recurrence in y = cos 2θ (N/2 multiply-adds)."""
    c = a[2::2]
    y2 = 2.0 * np.cos(2.0 * th)
    b1 = np.zeros_like(th)
    b2 = np.zeros_like(th)
    for ck in c[::-1]:
        b1, b2 = ck + y2 * b1 - b2, b1
    # Σ_{k≥1} c_k T_k(y) = y b₁ − b₂ (Chebyshev form of the cosine series, c₀ = 0)
    return b1 * (0.5 * y2) - b2
def _check_lam(lam) -> float:
    lam = check_positive(lam, "lam", error=ModelError)
    if lam >= 1.0:
        raise ModelError(f"lam={lam!r} must be < 1 (crank radius / rod length)")
    return lam


@lru_cache(maxsize=256)
def _sqrt_coefficients(lam: float, max_k: int, terms: int | None = None) -> tuple[float, ...]:
    """Fourier cosine coefficients c_{2k}, k = 0..max_k, of sqrt(1 − λ² sin²θ).

    sqrt(1 − u) = Σ_m binom(½, m)(−u)^m and sin^{2m}θ = 4^{−m}[C(2m,m) + 2 Σ_k (−1)^k
    C(2m, m−k) cos 2kθ], so c_{2k} = Σ_{m≥k} binom(½,m)(−1)^{m+k} C(2m,m−k) λ^{2m} 2^{1−2m}
    (half that for k = 0).  For m ≥ 1 every term of one coefficient has the same sign
    (binom(½,m)(−1)^m < 0), so the sum is accurate to a few ulp; it stops when a term no longer
    changes the sum.
    """
    q = lam * lam
    out = []
    for k in range(max_k + 1):
        total = 0.0
        m = k
        # binom(1/2, m) (-1)^m = -|.| for m >= 1; build the term with floats step by step
        while True:
            if terms is not None and m - k >= terms + (1 if k == 0 else 0):
                break  # λ-power truncation: keep the lowest ``terms`` powers of λ
            if m == 0:
                term = 1.0  # the constant 1 of sqrt(1 - u), k = 0 only
            else:
                b = _binom_half_signed(m)  # binom(1/2, m) (-1)^m
                ratio = math.comb(2 * m, m - k) / 4**m
                term = b * ((-1) ** k) * ratio * q**m * (1.0 if k == 0 else 2.0)
            total_new = total + term
            if m > k + 2 and (term == 0.0 or abs(term) <= 1e-18 * abs(total_new)):
                total = total_new
                break
            total = total_new
            m += 1
            if m > k + 20000:
                raise ModelError(f"lam={lam!r}: series for order {2 * k} did not converge")
        out.append(total)
    return tuple(out)


@lru_cache(maxsize=2048)
def _binom_half_signed(m: int) -> float:
    """binom(1/2, m) · (−1)^m as a float (negative for m ≥ 1)."""
    # binom(1/2, m)(-1)^m = -(2m)! / ((2m-1) 4^m (m!)^2) = -C(2m,m) / ((2m-1) 4^m)
    return -math.comb(2 * m, m) / ((2 * m - 1) * 4**m)


def _terms(lambda_terms):
    if lambda_terms is None:
        return None
    return check_int(lambda_terms, "lambda_terms", minimum=1, error=ModelError)


def displacement_coefficients(lam, max_order, *, lambda_terms=None):
    """Coefficients dₙ of x/l = λ cos θ + Σ dₙ cos nθ (n even, d₀ the mean) for e = 0.

    Returns an array indexed by order 0..max_order (odd entries besides order 1, which holds
    λ, are zero). Same series as Liang 1948 ch. 1 eq. (3).

    Examples
    --------
    >>> d = displacement_coefficients(0.25, 4)
    >>> print(", ".join(f"{v:.8g}" for v in d))
    0.98418696, 0.25, 0.015876565, 0, -6.4032987e-05
    """
    lam = _check_lam(lam)
    n = check_int(max_order, "max_order", minimum=0, error=ModelError)
    if n > MAX_SERIES_ORDER:
        raise ModelError(f"max_order={n} must be <= {MAX_SERIES_ORDER}")
    c = _sqrt_coefficients(lam, n // 2, _terms(lambda_terms))
    out = np.zeros(n + 1)
    out[0::2] = c[: len(out[0::2])]
    if n >= 1:
        out[1] = lam
    return out


def series_coefficients(lam, max_order, *, lambda_terms=None):
    """Acceleration-series coefficients aₙ, n = 0..max_order, for a centred pin: exact, or each
    truncated after ``lambda_terms`` powers of λ (the textbook fidelity).

    a(θ) = −r ω² Σₙ aₙ cos nθ with a₀ = 0, a₁ = 1, odd aₙ = 0 (n ≥ 3) and
    a_{2k} = (2k)² c_{2k} / λ, c_{2k} the Fourier coefficients of sqrt(1 − λ² sin²θ).
    Accurate to a few ulp of each coefficient for any λ < 1 (checked against mpmath
    quadrature for λ up to 0.45).

    Parameters
    ----------
    lam : float
        λ = r / l, 0 < λ < 1.
    max_order : int
        Highest order returned (≤ 400).
    lambda_terms : int, optional
        None (default): each coefficient summed to full accuracy. k: only the k lowest powers
        of λ of each coefficient (k = 1 with ``max_order=2`` is the textbook
        a = r ω² (cos θ + λ cos 2θ)); the error is :func:`series_error`.

    Returns
    -------
    ndarray
        Coefficients indexed by order, shape (max_order + 1,).

    References
    ----------
    Liang 1948, ch. 1 eq. (4): a₂ = λ + λ³/4 + 15λ⁵/128 + 35λ⁷/512 + …,
    a₄ = −(λ³/4 + 3λ⁵/16 + 35λ⁷/256 + …), a₆ = 9λ⁵/128 + 45λ⁷/512 + …, a₈ = −5λ⁷/256 − …

    Examples
    --------
    >>> a = series_coefficients(0.3, 8)
    >>> print(", ".join(f"{v:.6g}" for v in a[[2, 4, 6, 8]]))
    0.307051, -0.00723769, 0.000191937, -5.02721e-06
    """
    lam = _check_lam(lam)
    n = check_int(max_order, "max_order", minimum=0, error=ModelError)
    if n > MAX_SERIES_ORDER:
        raise ModelError(f"max_order={n} must be <= {MAX_SERIES_ORDER}")
    c = _sqrt_coefficients(lam, n // 2, _terms(lambda_terms))
    a = np.zeros(n + 1)
    if n >= 1:
        a[1] = 1.0
    for k in range(1, n // 2 + 1):
        a[2 * k] = (2 * k) ** 2 * c[k] / lam
    return a


@lru_cache(maxsize=64)
def _offset_coefficients(r, l, e, max_order):
    """Cosine and sine coefficients of −a/(r ω²) for a pin offset, from a 256-point FFT."""
    npts = max(256, 4 * (max_order + 1))
    th = 2 * np.pi * np.arange(npts) / npts
    y = -_exact_acceleration(th, r, l, e, 1.0) / r
    spec = np.fft.rfft(y) / npts
    cos_c = np.zeros(max_order + 1)
    sin_c = np.zeros(max_order + 1)
    m = min(max_order, npts // 2 - 1)
    cos_c[: m + 1] = 2 * spec.real[: m + 1]
    sin_c[: m + 1] = -2 * spec.imag[: m + 1]
    cos_c[0] /= 2
    return cos_c, sin_c


def truncation_bound(lam, max_order):
    """Bound on |a_exact − a_series| / (r ω²) when the series stops after ``max_order``.

    The bound is Σ_{n > N} |aₙ| (since |cos nθ| ≤ 1), summed until the terms underflow, so it
    is rigorous up to rounding and attained (within a few per cent) at TDC where every
    cos nθ = 1.

    Examples
    --------
    >>> print(f"{truncation_bound(0.25, 2):.3e}")
    4.174e-03
    """
    lam = _check_lam(lam)
    n = check_int(max_order, "max_order", minimum=1, error=ModelError)
    top = n + 2 + n % 2          # even, so the last coefficient examined is a non-zero one
    while True:
        a = series_coefficients(lam, min(top, MAX_SERIES_ORDER))
        tail = np.abs(a[n + 1:])
        if top >= MAX_SERIES_ORDER or tail[-1] <= 1e-30 or tail[-1] <= 1e-17 * tail.sum():
            break
        top *= 2
    return float(tail.sum())


def order_for_tolerance(lam, tol):
    """Lowest even truncation order N whose :func:`truncation_bound` is ≤ ``tol``.

    Parameters
    ----------
    lam : float
        λ = r/l.
    tol : float
        Allowed error relative to r ω² (e.g. 1e-6).

    Returns
    -------
    int
        The order (2, 4, 6, …); ``1`` is never returned since the order-2 term is the largest.

    Examples
    --------
    >>> order_for_tolerance(0.25, 1e-6), order_for_tolerance(0.45, 1e-12)
    (8, 20)
    """
    lam = _check_lam(lam)
    tol = check_positive(tol, "tol", error=ModelError)
    # one set of coefficients, reaching far enough that the neglected terms are < 1e-6 tol;
    # the reversed cumulative sum then gives every truncation bound at once
    top = 16
    while True:
        a = np.abs(series_coefficients(lam, min(top, MAX_SERIES_ORDER)))
        if top >= MAX_SERIES_ORDER or a[-1] <= 1e-6 * tol or a[-1] <= 1e-30:
            break
        top *= 2
    tails = np.cumsum(a[::-1])[::-1]            # tails[m] = Σ_{k >= m} |a_k|
    for n in range(2, a.size - 1, 2):
        if tails[n + 1] <= tol:
            return n
    raise ModelError(f"tol={tol!r} cannot be met below order {MAX_SERIES_ORDER} for lam={lam}")


@dataclass(frozen=True)
class AccelerationSeries:
    """A truncated acceleration series and its error bound.

    Attributes
    ----------
    lam : float
        λ = r/l.
    max_order : int
        Truncation order N.
    coefficients : ndarray
        aₙ, n = 0..N (dimensionless; multiply by −r ω² cos nθ).
    error_bound : float
        Bound on the truncation error relative to r ω².
    """

    lam: float
    max_order: int
    coefficients: np.ndarray
    error_bound: float

    def acceleration(self, theta, *, crank_radius, omega):
        """Series acceleration (m/s²) at crank angles ``theta`` (rad)."""
        th = _theta(theta)
        return _out(-crank_radius * omega**2 * (np.cos(th) + _clenshaw_even(self.coefficients,
                                                                            th)), theta)

    def to_frame(self):
        """Table with columns ``order``, ``coefficient``."""
        import pandas as pd

        n = np.arange(self.max_order + 1)
        keep = self.coefficients != 0
        return pd.DataFrame({"order": n[keep], "coefficient": self.coefficients[keep]})

    def plot(self, ax=None):
        """Bar chart of |aₙ| on a log scale; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        df = self.to_frame()
        ax.bar(df["order"], np.abs(df["coefficient"]))
        ax.set_yscale("log")
        ax.set_xlabel("order")
        ax.set_ylabel("|a_n|")
        ax.set_title(f"acceleration series, λ = {self.lam:.4g}, bound {self.error_bound:.2e}")
        return fig


def acceleration_series(lam, *, max_order=None, tol=None):
    """Truncated acceleration series at a given order or the lowest order meeting ``tol``.

    Exactly one of ``max_order`` and ``tol`` must be given.

    Examples
    --------
    >>> s = acceleration_series(0.3, tol=1e-6)
    >>> s.max_order, f"{s.error_bound:.2e}"
    (8, '1.33e-07')
    """
    if (max_order is None) == (tol is None):
        raise ModelError("give exactly one of max_order (int) or tol (relative to r ω²)")
    lam = _check_lam(lam)
    n = order_for_tolerance(lam, tol) if tol is not None else check_int(
        max_order, "max_order", minimum=1, error=ModelError)
    return AccelerationSeries(lam=lam, max_order=n, coefficients=series_coefficients(lam, n),
                              error_bound=truncation_bound(lam, n))



def series_error(lam, *, max_order, lambda_terms=None, points=3600) -> float:
    """Largest error of a truncated piston-acceleration series relative to r ω².

    max over θ of |a_series − a_exact| / (r ω²), on ``points`` crank angles (TDC included,
    where the truncation error peaks), against the exact closed form.

    Examples
    --------
    >>> print(f"{series_error(0.25, max_order=2, lambda_terms=1):.3e}")   # cos θ + λ cos 2θ
    8.199e-03
    """
    lam = _check_lam(lam)
    n = check_int(max_order, "max_order", minimum=1, error=ModelError)
    th = np.arange(check_int(points, "points", minimum=8, error=ModelError)) * 2 * np.pi / points
    a = series_coefficients(lam, n, lambda_terms=lambda_terms)
    approx = -(np.cos(th) + _clenshaw_even(a, th))
    exact = _exact_acceleration(th, lam, 1.0, 0.0, 1.0) / lam
    return float(np.max(np.abs(approx - exact)))
