"""Classical approximations of a shaft's first critical speed: Rayleigh, Dunkerley, Stodola.

The shaft is a uniform beam (simply supported, cantilever or fixed-fixed) carrying concentrated
masses (disks, rotary inertia neglected) and optionally its own distributed mass. Each method
reports which side of the exact first frequency it lies on:

=============  ==============================================================================
Rayleigh       upper bound: stiffness Rayleigh quotient over the static deflection under the
               weights (exact static curve of the shaft weight + the disks).
Dunkerley      lower bound: 1/ω² = 1/ω_s² + Σ mᵢ αᵢᵢ (ω_s the shaft alone, exact closed form).
Stodola        iteration of the deflection curve; each step gives the Rayleigh-quotient
               estimate (upper bound) and the Collatz bracket min/max of yₖ/yₖ₊₁ (two-sided,
               valid because every influence coefficient of these supports is positive).
=============  ==============================================================================

Stodola works on a lumped model: the shaft mass is lumped at Gauss-Legendre points of
``n_segments`` segments (the fidelity knob; the lumped model's frequency converges to the
continuum as O(n⁻²)).

References
----------
.. [1] Shi Zhiqing, *Applied Mechanics vol. 2: Engine Dynamics*, ch. 4 §19 "Dunkerley's
   formula", §26 "beams with concentrated loads", §27 "critical speeds of shafts".
.. [2] W. T. Thomson, M. D. Dahleh, *Theory of Vibration with Applications*, 5th ed. (1998),
   §7.6 (Dunkerley's equation), §7.7-7.8 (Rayleigh, Rayleigh-Ritz), §7.3 (matrix iteration).
.. [3] L. Collatz, *Eigenwertaufgaben mit technischen Anwendungen* (1949) — inclusion theorem
   for positive kernels (the Stodola bracket).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_finite_array, check_int, check_option, check_positive, check_range
from ..errors import AnalysisError, ModelError
from .beams import beam_natural_frequencies, influence_coefficient

__all__ = ["MassShaft", "ApproxResult", "rayleigh", "dunkerley", "dunkerley_combine", "stodola",
           "lumped_exact"]

log = logging.getLogger("crankbench")

_SUPPORTS = ("simply-supported", "cantilever", "fixed-fixed")
_GAUSS = np.polynomial.legendre.leggauss(8)  # exact for the degree <= 10 Rayleigh integrands


@dataclass(frozen=True)
class MassShaft:
    """A uniform shaft carrying concentrated masses.

    Parameters
    ----------
    length : float
        Span between supports (cantilever: clamped end at x = 0), m.
    youngs_modulus : float
        E, Pa.
    area_moment : float
        Second moment of area I, m⁴.
    masses : array_like
        Disk masses, kg.
    positions : array_like
        Disk positions from x = 0, m (inside the span).
    support : {"simply-supported", "cantilever", "fixed-fixed"}
    mass_per_length : float
        Shaft ρA, kg/m; 0 for a massless shaft.

    Examples
    --------
    >>> s = MassShaft(length=1.0, youngs_modulus=2.1e11, area_moment=3.07e-7,
    ...               masses=[20.0], positions=[0.5])
    >>> s.n_masses
    1
    """

    length: float
    youngs_modulus: float
    area_moment: float
    masses: np.ndarray
    positions: np.ndarray
    support: str = "simply-supported"
    mass_per_length: float = 0.0

    def __post_init__(self):
        put = object.__setattr__
        put(self, "length", check_positive(self.length, "length", error=ModelError))
        put(self, "youngs_modulus", check_positive(self.youngs_modulus, "youngs_modulus",
                                                   error=ModelError))
        put(self, "area_moment", check_positive(self.area_moment, "area_moment", error=ModelError))
        put(self, "mass_per_length", check_range(self.mass_per_length, "mass_per_length", 0.0,
                                                 error=ModelError))
        put(self, "support", check_option(self.support, "support", _SUPPORTS, error=ModelError))
        m = check_finite_array(self.masses, "masses", ndim=1, error=ModelError)
        x = check_finite_array(self.positions, "positions", ndim=1, error=ModelError)
        if m.shape != x.shape:
            raise ModelError(f"masses has {m.size} values but positions has {x.size}")
        if np.any(m <= 0):
            raise ModelError(f"masses must be > 0 kg, got {m.tolist()}")
        if np.any((x <= 0) | (x > self.length)) or (
                self.support != "cantilever" and np.any(x >= self.length)):
            raise ModelError(f"positions={x.tolist()} must lie inside the span (0, {self.length:g}) m")
        if m.size == 0 and self.mass_per_length == 0:
            raise ModelError("the shaft carries no mass: give masses or mass_per_length > 0")
        put(self, "masses", m)
        put(self, "positions", x)

    @property
    def n_masses(self) -> int:
        """Number of concentrated masses."""
        return int(self.masses.size)

    def _beam(self) -> dict:
        return dict(length=self.length, youngs_modulus=self.youngs_modulus,
                    area_moment=self.area_moment, support=self.support)

    def flexibility(self, x=None) -> np.ndarray:
        """Influence-coefficient matrix α between points ``x`` (default: the disks), m/N."""
        x = self.positions if x is None else np.asarray(x, dtype=float)
        return influence_coefficient(x[:, None], x[None, :], **self._beam())

    def self_weight_deflection(self, x) -> np.ndarray:
        """Static deflection per unit gravity (m per m/s²) under the shaft's own weight."""
        x = np.asarray(x, dtype=float)
        w, L, ei = self.mass_per_length, self.length, self.youngs_modulus * self.area_moment
        if self.support == "simply-supported":
            return w * x * (L**3 - 2 * L * x**2 + x**3) / (24 * ei)
        if self.support == "cantilever":
            return w * x**2 * (6 * L**2 - 4 * L * x + x**2) / (24 * ei)
        return w * x**2 * (L - x) ** 2 / (24 * ei)

    def lumped(self, n_segments: int) -> tuple[np.ndarray, np.ndarray]:
        """(masses, positions) with the shaft mass lumped at Gauss points of n segments."""
        n_segments = check_int(n_segments, "n_segments", minimum=1, error=ModelError)
        if self.mass_per_length == 0:
            return self.masses, self.positions
        nodes, weights = np.polynomial.legendre.leggauss(2)
        edges = np.linspace(0.0, self.length, n_segments + 1)
        h = np.diff(edges)
        xs = (edges[:-1, None] + (nodes[None, :] + 1) * h[:, None] / 2).ravel()
        ms = (self.mass_per_length * weights[None, :] * h[:, None] / 2).ravel()
        return np.concatenate([self.masses, ms]), np.concatenate([self.positions, xs])


@dataclass(frozen=True)
class ApproxResult:
    """First natural frequency of a :class:`MassShaft` by an approximate method.

    Attributes
    ----------
    method : str
        "rayleigh", "dunkerley", "stodola" or "lumped-exact".
    omega : float
        Estimate of the first natural frequency (= critical speed), rad/s.
    bound : str
        "upper", "lower", "bracket" (``lower <= exact <= upper``) or "exact".
    lower, upper : float
        Guaranteed bracket where known (rad/s), else NaN / the estimate itself.
    iterations : int
        Iterations used (Stodola), else 0.
    fidelity : str
        What the estimate depended on ("n_segments=20", "closed-form static curve").
    x, shape : ndarray
        Deflection shape used (positions m, normalised deflection), for ``plot``.
    """

    method: str
    omega: float
    bound: str
    lower: float
    upper: float
    iterations: int = 0
    fidelity: str = ""
    x: np.ndarray = field(default_factory=lambda: np.empty(0))
    shape: np.ndarray = field(default_factory=lambda: np.empty(0))
    history: tuple = ()

    def iterates(self):
        """Stodola's iterates one by one: iteration, omega (Rayleigh quotient), lower and
        upper (Collatz bracket), rad/s, and speed_rpm (empty for the other methods)."""
        import pandas as pd

        frame = pd.DataFrame(list(self.history),
                             columns=["iteration", "omega", "lower", "upper"])
        frame["speed_rpm"] = frame["omega"] * 30.0 / np.pi
        return frame

    @property
    def frequency_hz(self) -> float:
        """Estimate, Hz."""
        return self.omega / (2 * np.pi)

    @property
    def speed_rpm(self) -> float:
        """Estimated first critical speed, rpm."""
        return self.omega * 30.0 / np.pi

    @property
    def error_estimate(self) -> float:
        """Half-width of the guaranteed bracket relative to the estimate (NaN if one-sided)."""
        if np.isfinite(self.lower) and np.isfinite(self.upper):
            return float((self.upper - self.lower) / (2 * self.omega))
        return float("nan")

    def to_frame(self):
        """One-row table: method, bound, omega, frequency_hz, speed_rpm, bracket in rpm."""
        import pandas as pd

        return pd.DataFrame([{
            "method": self.method, "bound": self.bound, "omega": self.omega,
            "frequency_hz": self.frequency_hz, "speed_rpm": self.speed_rpm,
            "lower_rpm": self.lower * 30 / np.pi, "upper_rpm": self.upper * 30 / np.pi,
            "error_estimate": self.error_estimate, "iterations": self.iterations,
            "fidelity": self.fidelity}])

    def plot(self, ax=None):
        """Plot the deflection shape the estimate used; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        order = np.argsort(self.x)
        ax.plot(self.x[order], self.shape[order], "o-")
        ax.set_xlabel("position (m)")
        ax.set_ylabel("deflection (normalised)")
        ax.set_title(f"{self.method}: {self.speed_rpm:.5g} rpm ({self.bound} bound)")
        return fig


def _check(shaft) -> MassShaft:
    if not isinstance(shaft, MassShaft):
        raise ModelError(f"shaft must be a MassShaft, got {type(shaft).__name__}")
    return shaft


def rayleigh(shaft: MassShaft) -> ApproxResult:
    """Rayleigh's estimate from the static deflection curve (upper bound).

    ω² = g (∫ ρA y dx + Σ mᵢ yᵢ) / (∫ ρA y² dx + Σ mᵢ yᵢ²), y the static deflection under
    the weights of shaft and disks. The static curve is exact (closed forms) and the integrals
    are exact Gauss quadratures, so the only error is Rayleigh's: the estimate is above the
    exact first frequency, typically by 0.01-0.1 %.

    Parameters
    ----------
    shaft : MassShaft

    Returns
    -------
    ApproxResult
        ``bound="upper"``.

    References
    ----------
    Thomson & Dahleh, *Theory of Vibration with Applications*, §7.7 (Rayleigh's method with
    the static deflection curve); Shi, *Engine Dynamics* ch. 4 §27.

    Examples
    --------
    >>> s = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[],
    ...               positions=[], mass_per_length=1.0)
    >>> round(rayleigh(s).omega / 3.14159265358979**2, 5)  # exact: 1
    1.00071
    """
    s = _check(shaft)

    def y_at(x):  # static deflection per unit g
        x = np.atleast_1d(np.asarray(x, dtype=float))
        y = s.self_weight_deflection(x)
        if s.n_masses:
            y = y + influence_coefficient(x[:, None], s.positions[None, :], **s._beam()) @ s.masses
        return y

    num = den = 0.0
    if s.mass_per_length > 0:
        breaks = np.unique(np.concatenate([[0.0, s.length], s.positions]))
        nodes, weights = _GAUSS
        for lo, hi in zip(breaks[:-1], breaks[1:]):
            xs = lo + (nodes + 1) * (hi - lo) / 2
            ys = y_at(xs)
            num += s.mass_per_length * np.sum(weights * ys) * (hi - lo) / 2
            den += s.mass_per_length * np.sum(weights * ys**2) * (hi - lo) / 2
    if s.n_masses:
        yd = y_at(s.positions)
        num += np.sum(s.masses * yd)
        den += np.sum(s.masses * yd**2)
    omega = float(np.sqrt(num / den))
    xs = np.linspace(0.0, s.length, 41)
    ys = y_at(xs)
    return ApproxResult("rayleigh", omega, "upper", float("nan"), omega,
                        fidelity="closed-form static curve, exact quadrature", x=xs,
                        shape=ys / np.max(np.abs(ys)))


def dunkerley_combine(partial_omegas) -> float:
    """Dunkerley's combination 1/ω² = Σ 1/ωᵢ² of partial natural frequencies (rad/s).

    Each ωᵢ is the natural frequency of the shaft carrying only the i-th mass (or the shaft
    alone); the result is a lower bound of the combined system's first frequency.

    Parameters
    ----------
    partial_omegas : array_like
        Partial natural frequencies, rad/s (or any unit: the result has the same unit).

    Returns
    -------
    float

    References
    ----------
    Shi, *Engine Dynamics* ch. 4 §19 "Dunkerley's formula"; Thomson & Dahleh §7.6.

    Examples
    --------
    >>> round(dunkerley_combine([3.0, 4.0]), 6)  # 1/w² = 1/9 + 1/16
    2.4
    """
    w = check_finite_array(partial_omegas, "partial_omegas", ndim=1, min_length=1,
                           error=ModelError)
    if np.any(w <= 0):
        raise ModelError(f"partial_omegas must be > 0, got {w.tolist()}")
    return float(1.0 / np.sqrt(np.sum(1.0 / w**2)))


def dunkerley(shaft: MassShaft) -> ApproxResult:
    """Dunkerley's estimate (lower bound): 1/ω² = 1/ω_s² + Σ mᵢ αᵢᵢ.

    ω_s is the shaft's own first frequency (closed form, Euler-Bernoulli) and 1/(mᵢ αᵢᵢ) the
    frequency of the massless shaft with disk i alone. The estimate is below the exact first
    frequency, typically by 1-10 %.

    Parameters
    ----------
    shaft : MassShaft

    Returns
    -------
    ApproxResult
        ``bound="lower"``.

    References
    ----------
    Shi, *Engine Dynamics* ch. 4 §19; Thomson & Dahleh §7.6.

    Examples
    --------
    >>> s = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1.0, 1.0],
    ...               positions=[1/3, 2/3])
    >>> round(dunkerley(s).omega, 4)  # exact 5.6921
    5.5114
    """
    s = _check(shaft)
    partial = []
    if s.mass_per_length > 0:
        partial.append(beam_natural_frequencies(
            length=s.length, youngs_modulus=s.youngs_modulus, area_moment=s.area_moment,
            mass_per_length=s.mass_per_length, support=s.support, n_modes=1).omega[0])
    if s.n_masses:
        alpha = np.diag(s.flexibility())
        partial.extend(1.0 / np.sqrt(s.masses * alpha))
    omega = dunkerley_combine(partial)
    return ApproxResult("dunkerley", omega, "lower", omega, float("nan"),
                        fidelity="closed-form partial frequencies", x=s.positions,
                        shape=np.ones(s.n_masses))


def _lumped_system(s: MassShaft, n_segments: int):
    m, x = s.lumped(n_segments)
    alpha = influence_coefficient(x[:, None], x[None, :], **s._beam())
    return m, x, alpha


def lumped_exact(shaft: MassShaft, *, n_segments: int = 20) -> ApproxResult:
    """First frequency of the lumped model by a symmetric eigen-solve (reference, "exact").

    Exact for a massless shaft with point masses; with shaft mass it is the lumped model
    (``n_segments`` Gauss lumps, error O(n⁻²)).

    Examples
    --------
    >>> s = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1.0],
    ...               positions=[0.5])
    >>> round(lumped_exact(s).omega**2, 9)
    48.0
    """
    s = _check(shaft)
    m, x, alpha = _lumped_system(s, n_segments)
    root = np.sqrt(m)
    lam, vec = np.linalg.eigh(root[:, None] * alpha * root[None, :])
    omega = float(1.0 / np.sqrt(lam[-1]))
    shape = vec[:, -1] / root
    fid = f"n_segments={n_segments}" if s.mass_per_length > 0 else "exact (point masses)"
    return ApproxResult("lumped-exact", omega, "exact", omega, omega, fidelity=fid, x=x,
                        shape=shape / shape[np.argmax(np.abs(shape))])


def stodola(shaft: MassShaft, *, rtol: float = 1e-6, max_iter: int = 200,
            n_segments: int = 20, iterations: int | None = None) -> ApproxResult:
    """Stodola's iteration of the deflection curve with a guaranteed two-sided bracket.

    Start from the static deflection under the weights; repeat yₖ₊₁ = α M yₖ (deflection
    under the inertia loads of the previous curve). Each step gives the Rayleigh-quotient
    estimate ω² = yₖ₊₁ᵀ M yₖ / yₖ₊₁ᵀ M yₖ₊₁ (upper bound) and the Collatz bracket
    1/max(yₖ₊₁/yₖ) ≤ ω² ≤ 1/min(yₖ₊₁/yₖ). Iteration stops when the bracket half-width falls
    below ``rtol`` relative. Convergence is geometric with ratio ω₁²/ω₂².

    Parameters
    ----------
    shaft : MassShaft
    rtol : float
        Relative half-width of the bracket to reach.
    max_iter : int
        Iteration limit; :class:`~predict.errors.AnalysisError` if not converged.
    n_segments : int
        Lumping of the shaft mass (ignored for a massless shaft).
    iterations : int, optional
        The textbook fidelity: stop after exactly this many iterates (1-3 by hand), whatever
        the bracket; the bracket then states the error. ``rtol``/``max_iter`` are ignored.

    Returns
    -------
    ApproxResult
        ``bound="bracket"`` with ``lower``/``upper`` the Collatz bracket of the lumped model;
        :meth:`ApproxResult.iterates` lists every iterate.

    References
    ----------
    A. Stodola, *Steam and Gas Turbines* (1927), vol. 1 §§ on critical speeds; Thomson &
    Dahleh §7.3 (matrix iteration); Collatz (1949) inclusion theorem.

    Examples
    --------
    >>> s = MassShaft(length=1.0, youngs_modulus=1.0, area_moment=1.0, masses=[1.0, 1.0],
    ...               positions=[1/3, 2/3])
    >>> r = stodola(s)
    >>> round(r.omega, 4), r.lower <= r.omega <= r.upper
    (5.6921, True)
    """
    s = _check(shaft)
    rtol = check_range(rtol, "rtol", 0.0, 0.5, inclusive=(False, True), error=ModelError)
    max_iter = check_int(max_iter, "max_iter", minimum=1, error=ModelError)
    fixed = None if iterations is None else check_int(iterations, "iterations", minimum=1,
                                                       error=ModelError)
    m, x, alpha = _lumped_system(s, n_segments)
    d = alpha * m[None, :]
    y = d @ np.ones_like(m)  # static deflection under the weights (per unit g)
    lo = hi = est = float("nan")
    history = []
    for k in range(1, (fixed or max_iter) + 1):
        y_next = d @ y
        est = float(np.sqrt(np.dot(y_next * m, y) / np.dot(y_next * m, y_next)))
        ratio = y_next / y
        lo, hi = float(np.sqrt(1 / ratio.max())), float(np.sqrt(1 / ratio.min()))
        history.append((k, est, lo, min(hi, est)))
        y = y_next / np.max(np.abs(y_next))
        if fixed is None and (hi - lo) / (2 * est) <= rtol:
            break
    else:
        if fixed is not None:
            fid = f"n_segments={n_segments}" if s.mass_per_length > 0 else "point masses"
            return ApproxResult("stodola", est, "bracket", lo, min(hi, est), iterations=fixed,
                                fidelity=f"{fid}, {fixed} iterate(s)", x=x, shape=y,
                                history=tuple(history))
        raise AnalysisError(f"stodola did not reach rtol={rtol:g} in max_iter={max_iter} "
                            f"iterations (bracket {lo:.6g}..{hi:.6g} rad/s); raise max_iter")
    fid = f"n_segments={n_segments}" if s.mass_per_length > 0 else "point masses"
    return ApproxResult("stodola", est, "bracket", lo, min(hi, est), iterations=k,
                        fidelity=f"{fid}, rtol={rtol:g}", x=x, shape=y, history=tuple(history))
