"""Classical harmonic analysis of one period sampled at n equally spaced ordinates.

A periodic curve read off a record (a torsiograph or vibrograph trace, a turning-moment
diagram) at ``n`` equally spaced ordinates ``y_j = y(θ_j)``, ``θ_j = 2π j/n``, has the Fourier
coefficients

    a_0 = (1/n) Σ y_j,   a_k = (2/n) Σ y_j cos kθ_j,   b_k = (2/n) Σ y_j sin kθ_j,

with ``a_{n/2} = (1/n) Σ (−1)^j y_j`` for even ``n``. They are *exact* for a trigonometric
polynomial of degree < n/2; a harmonic of order ``m ≥ n/2`` aliases onto ``|m − l n|``,
which is the error of the method (state ``n`` > twice the highest harmonic present).

The textbooks did the sums by hand on printed "schedules": for n = 12 or 24 ordinates the
ordinates are first folded into sums and differences (``y_j ± y_{n−j}``) so that only the few
multipliers ``sin 30°, sin 60°, …`` occur (Runge's scheme). :func:`runge12` reproduces that
12-ordinate schedule step by step; :func:`ordinate_schedule` prints the multiplier table of any
``n``. Both are special cases of :func:`harmonics`, which evaluates the sums with an FFT.

References
----------
C. Runge, "Über die Zerlegung empirisch gegebener periodischer Functionen in Sinuswellen",
Z. Math. Phys. 48, 443–456 (1903).
E. T. Whittaker and G. Robinson, *The Calculus of Observations* (1924), ch. X, §§ 168–170
(the 12- and 24-ordinate schemes).
交通大学内燃机教研组, 《内燃机动力学、构造与计算》上册 (1958), 第二篇 第三章 §2
“干扰力的简谐分析” (harmonic analysis of the exciting torque), p. 132.
梁守槃, 《发动机动力学》 (1948), 第九章 “振动记录之分析” (analysis of vibration records), p. 105.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crankbench.predict._validate import check_finite_array, check_int
from crankbench.predict.errors import AnalysisError

__all__ = ["HarmonicCoefficients", "harmonics", "runge12", "ordinate_schedule"]


@dataclass(frozen=True)
class HarmonicCoefficients:
    """Fourier coefficients of one period: ``y(θ) = a_0 + Σ_k (a_k cos kθ + b_k sin kθ)``.

    Attributes
    ----------
    order : ndarray
        Harmonic orders ``k = 0 … K`` (per period of the analysed curve).
    a, b : ndarray
        Cosine and sine coefficients (units of ``y``); ``a[0]`` is the mean, ``b[0] = 0``.
    n : int
        Number of ordinates used.
    units : str
        Units of ``y``.
    method : str
        How the sums were formed.

    Notes
    -----
    ``amplitude = sqrt(a² + b²)`` (peak) and ``phase = atan2(−b, a)`` so that each harmonic is
    ``amplitude · cos(kθ + phase)`` — the convention of :func:`analysis.order_track`.
    Exact for trigonometric polynomials of degree < n/2 (see the module docstring).
    """

    order: np.ndarray
    a: np.ndarray
    b: np.ndarray
    n: int
    units: str = ""
    method: str = "n-ordinate DFT"

    @property
    def amplitude(self) -> np.ndarray:
        """Peak amplitude of each harmonic (units of ``y``; the mean for k = 0)."""
        amp = np.hypot(self.a, self.b)
        amp[0] = self.a[0]
        return amp

    @property
    def phase(self) -> np.ndarray:
        """Phase (rad) of each harmonic as ``amplitude · cos(kθ + phase)``."""
        return np.arctan2(-self.b, self.a)

    def evaluate(self, theta) -> np.ndarray:
        """The truncated Fourier series at angles ``theta`` (rad)."""
        theta = np.asarray(theta, dtype=float)
        k = self.order[:, None]
        return (self.a[:, None] * np.cos(k * theta.ravel()) + self.b[:, None]
                * np.sin(k * theta.ravel())).sum(axis=0).reshape(theta.shape)

    def to_frame(self):
        """Table of ``order, a, b, amplitude, phase_deg``."""
        import pandas as pd

        return pd.DataFrame({"order": self.order, "a": self.a, "b": self.b,
                             "amplitude": self.amplitude, "phase_deg": np.degrees(self.phase)})

    def plot(self, ax=None):
        """Bar chart of harmonic amplitudes; returns the figure (never shows it)."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(6, 3.5))
        else:
            fig = ax.figure
        ax.bar(self.order[1:], np.abs(self.amplitude[1:]), width=0.6)
        ax.set_xlabel("harmonic order k")
        ax.set_ylabel(f"amplitude [{self.units}]" if self.units else "amplitude")
        ax.set_title(f"harmonic analysis, {self.n} ordinates")
        return fig


def _ordinates(y, n: int) -> tuple[np.ndarray, str]:
    units = ""
    if callable(y):
        theta = 2.0 * np.pi * np.arange(n) / n
        values = np.asarray(y(theta), dtype=float)
        if values.shape != (n,):
            raise AnalysisError(f"y(theta) returned shape {values.shape}, expected ({n},)")
        return check_finite_array(values, "y(theta)", error=AnalysisError), units
    if hasattr(y, "attrs") and hasattr(y, "values"):
        units = str(y.attrs.get("units", ""))
        y = y.values
    values = check_finite_array(y, "y", ndim=1, min_length=1, error=AnalysisError)
    m = values.shape[0]
    if m == n:
        return values, units
    if m > n and m % n == 0:
        return values[:: m // n], units
    raise AnalysisError(
        f"y has {m} values; give exactly n={n} ordinates of one period (θ_j = 2πj/n, the end "
        f"point not repeated), a multiple of n equally spaced samples, or a callable y(θ)")


def harmonics(y, n: int | None = None, *, max_order: int | None = None) -> HarmonicCoefficients:
    """Fourier coefficients of one period from n equally spaced ordinates.

    Parameters
    ----------
    y : array_like, xarray.DataArray or callable
        One period of the curve: ``n`` ordinates at ``θ_j = 2π j/n`` (the end point not
        repeated), or a multiple of ``n`` equally spaced samples (every m-th is taken, as one
        reads n ordinates off a chart), or a function ``y(θ)`` of the angle in rad.
    n : int, optional
        Number of ordinates (default ``len(y)``); ≥ 2.
    max_order : int, optional
        Highest harmonic returned (default ``n // 2``, all that n ordinates determine).

    Returns
    -------
    HarmonicCoefficients
        ``a``, ``b``, ``amplitude``, ``phase`` for orders ``0 … max_order``.

    References
    ----------
    Whittaker & Robinson (1924) ch. X; 交通大学 (1958) 第二篇 第三章 §2 — see the module
    docstring. Exact for trigonometric polynomials of degree < n/2.

    Examples
    --------
    >>> theta = 2 * np.pi * np.arange(12) / 12
    >>> y = 1.0 + 3.0 * np.cos(theta) - 2.0 * np.sin(2 * theta) + 0.5 * np.cos(5 * theta)
    >>> h = harmonics(y, 12)
    >>> [round(float(v), 12) + 0.0 for v in h.a[:6]]
    [1.0, 3.0, 0.0, 0.0, 0.0, 0.5]
    >>> [round(float(v), 12) + 0.0 for v in h.b[:3]]
    [0.0, 0.0, -2.0]
    """
    if n is None:
        if callable(y):
            raise AnalysisError("n is required when y is a function y(theta)")
        n = len(y)
    n = check_int(n, "n", minimum=2, error=AnalysisError)
    values, units = _ordinates(y, n)
    top = n // 2 if max_order is None else check_int(max_order, "max_order", minimum=0,
                                                     error=AnalysisError)
    if top > n // 2:
        raise AnalysisError(f"max_order={top} exceeds n//2={n // 2}: {n} ordinates determine "
                            f"harmonics up to {n // 2} only")
    spec = np.fft.rfft(values) / n
    a = 2.0 * spec.real
    b = -2.0 * spec.imag
    a[0] *= 0.5
    if n % 2 == 0:
        a[n // 2] *= 0.5
        b[n // 2] = 0.0
    b[0] = 0.0
    return HarmonicCoefficients(order=np.arange(top + 1), a=a[: top + 1].copy(),
                                b=b[: top + 1].copy(), n=n, units=units)


def runge12(y) -> HarmonicCoefficients:
    """The textbook 12-ordinate schedule (Runge's folding scheme), step by step.

    The twelve ordinates ``y_0 … y_11`` (every 30°) are folded into sums ``u`` and differences
    ``v`` of ordinates symmetric about 180°, then folded again about 90°, so the coefficients
    need only the multipliers ``1/2`` and ``√3/2``. It gives the same numbers as
    :func:`harmonics` with ``n = 12`` (to rounding) — the schedule is a special case.

    Parameters
    ----------
    y : array_like
        Twelve ordinates of one period, units of the curve.

    Returns
    -------
    HarmonicCoefficients
        Orders 0–6.

    References
    ----------
    Runge (1903); Whittaker & Robinson (1924) §168 (the 12-ordinate scheme).

    Examples
    --------
    >>> y = [0, 5, 9, 12, 10, 6, 2, -3, -7, -9, -6, -2]
    >>> h = runge12(y)
    >>> round(float(h.a[1]), 4), round(float(h.b[1]), 4)
    (-0.3333, 9.4521)
    """
    y = check_finite_array(y, "y", ndim=1, error=AnalysisError)
    if y.shape[0] != 12:
        raise AnalysisError(f"runge12 needs exactly 12 ordinates, got {y.shape[0]}")
    s, c = 0.5, np.sqrt(3.0) / 2.0  # sin 30°, sin 60°
    # first fold about 180°: u_j = y_j + y_{12-j} (j = 0..6), v_j = y_j - y_{12-j} (j = 1..5)
    u = np.array([y[0]] + [y[j] + y[12 - j] for j in range(1, 6)] + [y[6]])
    v = np.array([0.0] + [y[j] - y[12 - j] for j in range(1, 6)])
    # second fold about 90°: p_j = u_j + u_{6-j}, q_j = u_j - u_{6-j} (j = 0..3)
    p = np.array([u[0] + u[6], u[1] + u[5], u[2] + u[4], u[3]])
    q = np.array([u[0] - u[6], u[1] - u[5], u[2] - u[4]])
    # and for the sines: r_j = v_j + v_{6-j}, t_j = v_j - v_{6-j} (j = 1..3)
    r = np.array([0.0, v[1] + v[5], v[2] + v[4], v[3]])
    t = np.array([0.0, v[1] - v[5], v[2] - v[4]])
    a = np.empty(7)
    b = np.zeros(7)
    a[0] = (p[0] + p[1] + p[2] + p[3]) / 12.0
    a[1] = (q[0] + c * q[1] + s * q[2]) / 6.0
    a[2] = (p[0] + s * p[1] - s * p[2] - p[3]) / 6.0
    a[3] = (q[0] - q[2]) / 6.0
    a[4] = (p[0] - s * p[1] - s * p[2] + p[3]) / 6.0
    a[5] = (q[0] - c * q[1] + s * q[2]) / 6.0
    a[6] = (p[0] - p[1] + p[2] - p[3]) / 12.0
    b[1] = (s * r[1] + c * r[2] + r[3]) / 6.0
    b[2] = c * (t[1] + t[2]) / 6.0
    b[3] = (r[1] - r[3]) / 6.0
    b[4] = c * (t[1] - t[2]) / 6.0
    b[5] = (s * r[1] - c * r[2] + r[3]) / 6.0
    return HarmonicCoefficients(order=np.arange(7), a=a, b=b, n=12,
                                method="Runge 12-ordinate schedule")


def ordinate_schedule(n: int):
    """The multiplier table of the n-ordinate schedule: cos kθ_j and sin kθ_j for each ordinate.

    Parameters
    ----------
    n : int
        Number of ordinates (≥ 2).

    Returns
    -------
    pandas.DataFrame
        Rows ``j = 0 … n−1`` (ordinate angle in degrees), columns ``cos k`` and ``sin k`` for
        ``k = 1 … n//2``: the numbers a hand computation multiplies each ordinate by.

    Examples
    --------
    >>> tab = ordinate_schedule(12)
    >>> [round(float(v), 4) for v in tab["cos 1"][:4]]
    [1.0, 0.866, 0.5, 0.0]
    """
    import pandas as pd

    n = check_int(n, "n", minimum=2, error=AnalysisError)
    j = np.arange(n)
    cols = {"angle_deg": 360.0 * j / n}
    for k in range(1, n // 2 + 1):
        cols[f"cos {k}"] = np.round(np.cos(2 * np.pi * k * j / n), 15) + 0.0
        cols[f"sin {k}"] = np.round(np.sin(2 * np.pi * k * j / n), 15) + 0.0
    return pd.DataFrame(cols)
