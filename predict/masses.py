"""Mass reduction of the crank train: connecting-rod two- and three-point equivalents, the
residual couple of the two-point rod, crank-throw equivalent rotating mass, and rod inertia from
a compound-pendulum test.

Rod notation (Liang 1948 ch. 1 §1-4): mass m, centre-to-centre length l, centre of gravity a
distance ``cg_from_big_end`` = h·l from the crank-pin (big-end) centre and k·l = (1 − h)·l from the
piston-pin centre, moment of inertia J_G = m (q l)² about the CG.

* Two-point (statically equivalent): m_A = m k at the crank pin (rotating), m_B = m h at the
  piston pin (reciprocating). Its moment of inertia about the CG is m h k l², which differs from
  J_G: the missing couple is the residual couple ΔM = (J_G − m h k l²) · φ̈, φ the rod angle.
* Three-point (dynamically equivalent, Internal-combustion engine dynamics 1958 §1-1-3):
  m_B = J_G / (l_B l), m_A = J_G / (l_A l), m_G = m − J_G / (l_A l_B), with l_A, l_B the CG
  distances to the crank pin and piston pin.

References
----------
Liang Shoupan, *Engine Dynamics* (1948) ch. 1 §1-3, §1-4 (eq. (6)-(10), worked examples);
*Internal-combustion engine dynamics* (Jiaotong University lecture notes, 1957/58) part 1 ch. 1
§1 (three- and two-point distributions, crank-throw reduction (1), compound pendulum (3)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_nonnegative, check_positive
from .errors import ModelError
from .kinematics import check_geometry, rod_angular_acceleration

__all__ = [
    "Rod",
    "RodMasses",
    "rod_inertia_from_pendulum",
    "throw_rotating_mass",
    "STANDARD_GRAVITY",
]

STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True)
class RodMasses:
    """A point-mass equivalent of a connecting rod.

    Attributes
    ----------
    big_end : float
        Mass at the crank-pin centre (rotating), kg.
    small_end : float
        Mass at the piston-pin centre (reciprocating), kg.
    at_cg : float
        Mass at the centre of gravity (three-point model; 0 for two-point), kg.
    inertia_error : float
        J_G − (moment of inertia of the point masses about the CG), kg·m²; 0 for the
        dynamically equivalent model, the residual-couple inertia for the two-point model.
    kind : str
        "two-point" or "three-point".
    """

    big_end: float
    small_end: float
    at_cg: float
    inertia_error: float
    kind: str

    def to_frame(self):
        """One row: masses (kg) and inertia error (kg·m²)."""
        import pandas as pd

        return pd.DataFrame([{"kind": self.kind, "big_end_kg": self.big_end,
                              "small_end_kg": self.small_end, "at_cg_kg": self.at_cg,
                              "inertia_error_kgm2": self.inertia_error}])

    def plot(self, ax=None):
        """Bar chart of the point masses; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        ax.bar(["big end", "CG", "small end"], [self.big_end, self.at_cg, self.small_end])
        ax.set_ylabel("mass (kg)")
        ax.set_title(f"{self.kind} rod equivalent")
        return fig


@dataclass(frozen=True)
class Rod:
    """A connecting rod.

    Parameters
    ----------
    mass : float
        kg.
    length : float
        Crank-pin centre to piston-pin centre, m.
    cg_from_big_end : float
        Distance crank-pin centre → centre of gravity, m (0 < value < length).
    inertia_cg : float
        Moment of inertia about the CG, kg·m² (e.g. from :func:`rod_inertia_from_pendulum`).

    Examples
    --------
    >>> rod = Rod(mass=1.2, length=0.15, cg_from_big_end=0.04, inertia_cg=0.0045)
    >>> m = rod.two_point()
    >>> round(m.big_end, 4), round(m.small_end, 4), round(m.inertia_error, 6)
    (0.88, 0.32, -0.00078)
    """

    mass: float
    length: float
    cg_from_big_end: float
    inertia_cg: float

    def __post_init__(self):
        check_positive(self.mass, "mass", error=ModelError)
        check_positive(self.length, "length", error=ModelError)
        check_nonnegative(self.inertia_cg, "inertia_cg", error=ModelError)
        h = check_positive(self.cg_from_big_end, "cg_from_big_end", error=ModelError)
        if h >= self.length:
            raise ModelError(f"cg_from_big_end={h!r} must be < length={self.length!r}")

    @property
    def h(self) -> float:
        """CG distance from the crank pin as a fraction of the length."""
        return self.cg_from_big_end / self.length

    @property
    def k(self) -> float:
        """CG distance from the piston pin as a fraction of the length."""
        return 1.0 - self.h

    @property
    def radius_of_gyration(self) -> float:
        """sqrt(J_G / m), m."""
        return float(np.sqrt(self.inertia_cg / self.mass))

    def two_point(self) -> RodMasses:
        """Statically equivalent two-point rod (Liang 1948 §1-3; 1958 notes §1-1-3(2)).

        The inertia error J_G − m h k l² is what the residual couple acts through.
        """
        m, h, k, l = self.mass, self.h, self.k, self.length
        return RodMasses(big_end=m * k, small_end=m * h, at_cg=0.0,
                         inertia_error=self.inertia_cg - m * h * k * l * l, kind="two-point")

    def three_point(self) -> RodMasses:
        """Dynamically equivalent three-point rod (1958 notes eq. (2)).

        Raises ModelError when J_G exceeds m·l_A·l_B (the CG mass would be negative: the rod
        cannot be represented by positive masses at these three points).
        """
        l = self.length
        la, lb = self.cg_from_big_end, l - self.cg_from_big_end
        j = self.inertia_cg
        m_small = j / (lb * l)
        m_big = j / (la * l)
        m_cg = self.mass - j / (la * lb)
        if m_cg < -1e-12 * self.mass:
            raise ModelError(f"inertia_cg={j!r} exceeds mass·l_A·l_B={self.mass * la * lb:.6g}: "
                             "no positive three-point equivalent exists")
        return RodMasses(big_end=m_big, small_end=m_small, at_cg=max(m_cg, 0.0),
                         inertia_error=0.0, kind="three-point")

    def residual_couple(self, theta, *, crank_radius, omega):
        """Residual couple of the two-point rod, N·m: ΔM = (J_G − m h k l²) · φ̈.

        The couple to add to the two-point model's forces to reproduce the real rod (Liang 1948
        §1-4, eq. (10)); positive in the sense of increasing rod angle φ.

        Parameters
        ----------
        theta : array_like
            Crank angle from TDC, rad.
        crank_radius : float
            m.
        omega : float
            rad/s.

        Examples
        --------
        >>> rod = Rod(mass=1.2, length=0.15, cg_from_big_end=0.04, inertia_cg=0.0045)
        >>> round(float(rod.residual_couple(np.pi / 2, crank_radius=0.045, omega=300.0)), 3)
        22.077
        """
        check_geometry(crank_radius, self.length)
        phi2 = rod_angular_acceleration(theta, crank_radius=crank_radius, rod_length=self.length,
                                        omega=omega)
        return self.two_point().inertia_error * phi2

    def to_frame(self):
        """Both equivalents, one row each."""
        import pandas as pd

        rows = [self.two_point().to_frame()]
        try:
            rows.append(self.three_point().to_frame())
        except ModelError:
            pass
        return pd.concat(rows, ignore_index=True)

    def plot(self, ax=None):
        """Two- and three-point masses side by side; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        df = self.to_frame()
        x = np.arange(3)
        for j, row in df.iterrows():
            ax.bar(x + 0.35 * j, [row.big_end_kg, row.at_cg_kg, row.small_end_kg], 0.35,
                   label=row.kind)
        ax.set_xticks(x + 0.175, ["big end", "CG", "small end"])
        ax.set_ylabel("mass (kg)")
        ax.legend()
        return fig


def rod_inertia_from_pendulum(*, mass, period, pivot_to_cg, gravity=STANDARD_GRAVITY):
    """Rod moment of inertia about its CG from a compound-pendulum swing test.

    J_G = m g a T² / (4π²) − m a², a = pivot-to-CG distance, T the period of small swings
    (1958 notes eq. (3); Liang 1948 eq. (8)).

    Parameters
    ----------
    mass : float
        kg.
    period : float
        Period of small oscillations, s.
    pivot_to_cg : float
        Distance from the pivot (e.g. the piston-pin centre) to the CG, m.
    gravity : float
        m/s².

    Returns
    -------
    float
        kg·m².

    Examples
    --------
    >>> round(rod_inertia_from_pendulum(mass=1.2, period=0.7, pivot_to_cg=0.11), 6)
    0.001547
    """
    m = check_positive(mass, "mass", error=ModelError)
    t = check_positive(period, "period", error=ModelError)
    a = check_positive(pivot_to_cg, "pivot_to_cg", error=ModelError)
    g = check_positive(gravity, "gravity", error=ModelError)
    j = m * g * a * t * t / (4 * np.pi**2) - m * a * a
    if j <= 0:
        t_min = 2 * np.pi * np.sqrt(a / g)
        raise ModelError(f"period={t!r} s is too short for pivot_to_cg={a!r} m: a compound "
                         f"pendulum swings slower than the simple pendulum ({t_min:.6g} s)")
    return float(j)


def throw_rotating_mass(*, pin_mass, web_mass, web_cg_radius, crank_radius):
    """Crank-throw mass reduced to the crank radius: m_pin + m_web · ρ / r.

    The webs' centrifugal force m_web ρ ω² is reproduced by m_web ρ / r at the crank radius
    (1958 notes eq. (1)); main journals contribute nothing.

    Parameters
    ----------
    pin_mass : float
        Crank-pin mass, kg.
    web_mass : float
        Mass of both webs of one throw (unbalanced part), kg.
    web_cg_radius : float
        Radius of the webs' centre of gravity, m (negative if it lies on the counterweight side).
    crank_radius : float
        m.

    Examples
    --------
    >>> throw_rotating_mass(pin_mass=1.1, web_mass=2.0, web_cg_radius=0.02, crank_radius=0.04)
    2.1
    """
    mp = check_nonnegative(pin_mass, "pin_mass", error=ModelError)
    mw = check_nonnegative(web_mass, "web_mass", error=ModelError)
    r = check_positive(crank_radius, "crank_radius", error=ModelError)
    rho = check_finite_array(web_cg_radius, "web_cg_radius", error=ModelError)
    return float(mp + mw * float(rho) / r)
