"""Closed forms for the lateral vibration of uniform beams and shafts.

Euler-Bernoulli theory (slender beams: shear deformation and rotary inertia neglected, which
overestimates the n-th frequency by roughly ``(n π r_g / L)²/2`` relative, ``r_g`` the radius of
gyration of the section; use :mod:`predict.lateral.fe` with ``theory="timoshenko"`` for thick
beams).

References
----------
.. [1] Shi Zhiqing, *Applied Mechanics vol. 2: Engine Dynamics*, Commercial Press (1940s),
   ch. 4 §25 "beams with distributed load, free lateral vibration", §26 "beams with
   concentrated loads", §27 "critical speeds of shafts".
.. [2] S. Timoshenko, D. H. Young, W. Weaver, *Vibration Problems in Engineering*, 4th ed.,
   Wiley (1974), §5.3-5.4 (uniform beams, frequency equations, Table of roots).
.. [3] W. C. Young, R. G. Budynas, *Roark's Formulas for Stress and Strain*, 7th ed.,
   Table 8.1 (deflection of beams under a concentrated load).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .._validate import check_int, check_option, check_positive, check_range
from ..errors import ModelError

__all__ = [
    "SUPPORTS",
    "BeamModes",
    "beam_natural_frequencies",
    "influence_coefficient",
    "point_stiffness",
    "disk_on_shaft_frequency",
]

#: end conditions understood by the closed forms (left-right)
SUPPORTS = ("simply-supported", "cantilever", "fixed-fixed", "fixed-pinned", "free-free")

_ALIASES = {"pinned-pinned": "simply-supported", "clamped-free": "cantilever",
            "clamped-clamped": "fixed-fixed", "clamped-pinned": "fixed-pinned"}


def _support(support: str) -> str:
    support = _ALIASES.get(support, support)
    return check_option(support, "support", SUPPORTS, error=ModelError)


def _characteristic(support: str):
    """Frequency equation f(βL) = 0 scaled to stay O(1) for large βL, and root estimates."""
    if support == "cantilever":  # cos x cosh x + 1 = 0
        return (lambda x: np.cos(x) + 1.0 / np.cosh(x)), (lambda n: (2 * n - 1) * np.pi / 2)
    if support in ("fixed-fixed", "free-free"):  # cos x cosh x - 1 = 0
        return (lambda x: np.cos(x) - 1.0 / np.cosh(x)), (lambda n: (2 * n + 1) * np.pi / 2)
    if support == "fixed-pinned":  # tan x - tanh x = 0
        return (lambda x: np.sin(x) - np.cos(x) * np.tanh(x)), (lambda n: (4 * n + 1) * np.pi / 4)
    return None, (lambda n: n * np.pi)


def _roots(support: str, n_modes: int) -> np.ndarray:
    func, guess = _characteristic(support)
    roots = np.empty(n_modes)
    for i in range(n_modes):
        x0 = guess(i + 1)
        roots[i] = x0 if func is None else brentq(func, x0 - 0.7, x0 + 0.7, xtol=1e-15,
                                                   rtol=1e-15)
    return roots


@dataclass(frozen=True)
class BeamModes:
    """Natural frequencies of a uniform Euler-Bernoulli beam (closed form).

    Attributes
    ----------
    support : str
        End conditions.
    length : float
        Span, m.
    beta_l : ndarray
        Roots βₙL of the frequency equation (dimensionless).
    omega : ndarray
        Circular natural frequencies ωₙ = (βₙL)² √(EI/(ρA L⁴)), rad/s.
    """

    support: str
    length: float
    beta_l: np.ndarray
    omega: np.ndarray

    @property
    def frequency_hz(self) -> np.ndarray:
        """Natural frequencies, Hz."""
        return self.omega / (2 * np.pi)

    @property
    def speed_rpm(self) -> np.ndarray:
        """Critical speeds of a shaft with these frequencies (1st order, no gyroscopics), rpm."""
        return self.omega * 30.0 / np.pi

    def mode_shape(self, mode: int, x: np.ndarray) -> np.ndarray:
        """Mode shape of ``mode`` (1-based) at positions ``x`` (m), scaled to max |φ| = 1."""
        mode = check_int(mode, "mode", minimum=1)
        if mode > self.beta_l.size:
            raise ModelError(f"mode={mode} exceeds the {self.beta_l.size} modes computed")
        bl = self.beta_l[mode - 1]
        z = bl * np.asarray(x, dtype=float) / self.length
        if self.support == "simply-supported":
            phi = np.sin(z)
        elif self.support == "free-free":
            sigma = (np.cosh(bl) - np.cos(bl)) / (np.sinh(bl) - np.sin(bl))
            phi = np.cosh(z) + np.cos(z) - sigma * (np.sinh(z) + np.sin(z))
        else:
            if self.support == "cantilever":
                sigma = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))
            else:
                sigma = (np.cosh(bl) - np.cos(bl)) / (np.sinh(bl) - np.sin(bl))
            phi = np.cosh(z) - np.cos(z) - sigma * (np.sinh(z) - np.sin(z))
        return phi / np.max(np.abs(phi))

    def to_frame(self):
        """Table with columns mode, beta_l, omega, frequency_hz, speed_rpm."""
        import pandas as pd

        return pd.DataFrame({"mode": np.arange(1, self.omega.size + 1), "beta_l": self.beta_l,
                             "omega": self.omega, "frequency_hz": self.frequency_hz,
                             "speed_rpm": self.speed_rpm})

    def plot(self, ax=None):
        """Plot the mode shapes along the beam; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        x = np.linspace(0.0, self.length, 201)
        for n in range(1, self.omega.size + 1):
            ax.plot(x, self.mode_shape(n, x), label=f"mode {n}: {self.frequency_hz[n - 1]:.4g} Hz")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel("position along the beam (m)")
        ax.set_ylabel("mode shape (normalised)")
        ax.set_title(f"{self.support} beam")
        ax.legend()
        return fig


def beam_natural_frequencies(*, length, youngs_modulus, area_moment, mass_per_length,
                             support="simply-supported", n_modes=3) -> BeamModes:
    """Natural frequencies of a uniform Euler-Bernoulli beam.

    ωₙ = (βₙL)² √(EI / (ρA L⁴)), with βₙL = nπ for a simply supported beam and the roots of
    cos βL cosh βL = −1 (cantilever), = 1 (fixed-fixed, free-free elastic modes) and
    tan βL = tanh βL (fixed-pinned), solved to machine precision.

    Parameters
    ----------
    length : float
        Span, m.
    youngs_modulus : float
        E, Pa.
    area_moment : float
        Second moment of area I of the section, m⁴.
    mass_per_length : float
        ρA, kg/m.
    support : {"simply-supported", "cantilever", "fixed-fixed", "fixed-pinned", "free-free"}
        End conditions ("pinned-pinned", "clamped-free", ... accepted as aliases).
    n_modes : int
        Number of modes (free-free: elastic modes only).

    Returns
    -------
    BeamModes

    References
    ----------
    Timoshenko, Young & Weaver, *Vibration Problems in Engineering*, §5.3-5.4; Shi, *Engine
    Dynamics* ch. 4 §25.

    Examples
    --------
    >>> m = beam_natural_frequencies(length=1.0, youngs_modulus=2.1e11, area_moment=1e-8,
    ...                              mass_per_length=7.85, support="cantilever", n_modes=2)
    >>> [round(float(v), 4) for v in m.beta_l]
    [1.8751, 4.6941]
    """
    length = check_positive(length, "length", error=ModelError)
    e = check_positive(youngs_modulus, "youngs_modulus", error=ModelError)
    i = check_positive(area_moment, "area_moment", error=ModelError)
    rho_a = check_positive(mass_per_length, "mass_per_length", error=ModelError)
    n_modes = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
    support = _support(support)
    beta_l = _roots(support, n_modes)
    omega = beta_l**2 * np.sqrt(e * i / (rho_a * length**4))
    return BeamModes(support=support, length=length, beta_l=beta_l, omega=omega)


def influence_coefficient(x, a, *, length, youngs_modulus, area_moment,
                          support="simply-supported"):
    """Deflection at ``x`` due to a unit force at ``a`` (flexibility influence coefficient).

    Parameters
    ----------
    x, a : float or array_like
        Positions from the left end, m (broadcast together).
    length, youngs_modulus, area_moment : float
        Span (m), E (Pa), I (m⁴).
    support : {"simply-supported", "cantilever", "fixed-fixed"}
        Cantilever: clamped at x = 0, free at x = L.

    Returns
    -------
    ndarray
        α(x, a), m/N. Symmetric in x and a (Maxwell's reciprocity).

    References
    ----------
    Roark's Formulas for Stress and Strain, 7th ed., Table 8.1 cases 1a, 1e, 2e.

    Examples
    --------
    >>> a = influence_coefficient(0.5, 0.5, length=1.0, youngs_modulus=1.0, area_moment=1.0)
    >>> round(float(a) * 48, 12)  # L³/(48 EI) at mid-span
    1.0
    """
    length = check_positive(length, "length", error=ModelError)
    e = check_positive(youngs_modulus, "youngs_modulus", error=ModelError)
    i = check_positive(area_moment, "area_moment", error=ModelError)
    support = check_option(_ALIASES.get(support, support), "support",
                           ("simply-supported", "cantilever", "fixed-fixed"), error=ModelError)
    x, a = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(a, dtype=float))
    if np.any((x < 0) | (x > length) | (a < 0) | (a > length)):
        raise ModelError(f"positions must lie on the beam [0, {length:g}] m")
    lo, hi = np.minimum(x, a), np.maximum(x, a)  # reciprocity: α(x, a) = α(min, max)
    ei = e * i
    if support == "simply-supported":
        b = length - hi  # load at hi, point at lo <= hi
        out = b * lo * (length**2 - b**2 - lo**2) / (6 * ei * length)
    elif support == "cantilever":
        out = lo**2 * (3 * hi - lo) / (6 * ei)
    else:
        b = length - hi
        out = b**2 * lo**2 * (3 * hi * length - (3 * hi + b) * lo) / (6 * ei * length**3)
    return out


def point_stiffness(position, *, length, youngs_modulus, area_moment, support="simply-supported"):
    """Lateral stiffness of a massless beam at ``position`` (N/m): 1/α(a, a).

    Simply supported: 3EIL/(a²b²); cantilever: 3EI/a³; fixed-fixed: 3EIL³/(a³b³).

    Examples
    --------
    >>> round(point_stiffness(1.0, length=1.0, youngs_modulus=1.0, area_moment=1.0,
    ...                       support="cantilever"), 12)
    3.0
    """
    alpha = influence_coefficient(position, position, length=length,
                                  youngs_modulus=youngs_modulus, area_moment=area_moment,
                                  support=support)
    if np.any(alpha <= 0):
        raise ModelError(f"position={position!r} is at a support: the beam is rigid there")
    return 1.0 / alpha if np.ndim(alpha) else float(1.0 / alpha)


def disk_on_shaft_frequency(*, mass, position, length, youngs_modulus, area_moment,
                            support="simply-supported", mass_per_length=0.0, n_points=400):
    """Natural frequency of a shaft carrying one disk (rad/s): ω = √(k / (m + m_eff)).

    With a massless shaft (``mass_per_length=0``) this is exact for a point mass (the classical
    critical speed ω = √(g/δ_st), δ_st the static deflection under the disk). With shaft mass,
    the shaft is represented by its Rayleigh effective mass m_eff = ρA ∫ y² dx / y(a)² over the
    static deflection y under a point load at the disk — an upper bound (17/35 of the shaft
    mass for a central disk on a simply supported shaft, 33/140 for a cantilever tip mass).

    Parameters
    ----------
    mass : float
        Disk mass, kg (rotary inertia neglected).
    position : float
        Disk position from the left end, m.
    length, youngs_modulus, area_moment : float
        Span (m), E (Pa), I (m⁴).
    support : str
        "simply-supported", "cantilever" or "fixed-fixed".
    mass_per_length : float
        Shaft ρA, kg/m (0 = massless shaft).
    n_points : int
        Quadrature points (Gauss-Legendre per side of the disk) for m_eff; the integrand is a
        polynomial so 4 points per side are already exact; kept as a knob.

    Returns
    -------
    float
        ω, rad/s.

    References
    ----------
    Shi, *Engine Dynamics* ch. 4 §27 (critical speed of a shaft, ω² = g/δ); Rayleigh's
    effective mass: Thomson & Dahleh, *Theory of Vibration with Applications*, 5th ed., §2.3.

    Examples
    --------
    >>> w = disk_on_shaft_frequency(mass=1.0, position=0.5, length=1.0, youngs_modulus=1.0,
    ...                             area_moment=1.0)
    >>> round(w**2, 9)  # 48 EI / (m L³)
    48.0
    """
    mass = check_positive(mass, "mass", error=ModelError)
    rho_a = check_range(mass_per_length, "mass_per_length", 0.0, error=ModelError)
    n_points = check_int(n_points, "n_points", minimum=2, error=ModelError)
    kw = dict(length=length, youngs_modulus=youngs_modulus, area_moment=area_moment,
              support=support)
    k = point_stiffness(position, **kw)
    m_eff = 0.0
    if rho_a > 0:
        nodes, weights = np.polynomial.legendre.leggauss(min(n_points, 64))
        total = 0.0
        for lo, hi in ((0.0, position), (position, length)):
            if hi > lo:
                xs = lo + (nodes + 1) * (hi - lo) / 2
                total += np.sum(weights * influence_coefficient(xs, position, **kw) ** 2) * (
                    hi - lo) / 2
        m_eff = rho_a * total * k**2  # y(a) = α(a, a) = 1/k
    return float(np.sqrt(k / (mass + m_eff)))
