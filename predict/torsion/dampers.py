"""Torsional vibration dampers: elements for a :class:`~predict.torsion.elements.ShaftLine`
and their classical optimum tuning.

* viscous (Lanchester/Houdaille) damper: a free seismic ring coupled to the hub by viscous
  shear only (no spring) — left out of the undamped eigen-analysis;
* tuned spring-viscous damper (Den Hartog absorber): ring on a spring with viscous damping;
* order-tuned centrifugal pendulum: mass m on a pivot at radius R, length r; linearised it is
  an absorber of inertia ``J_a = m (R + r)²`` on a speed-proportional spring ``J_a (R/r) Ω²``,
  tuned to order ``n = √(R/r)`` at every speed (Den Hartog, ch. 5);
* Lanchester friction damper: ring driven through friction plates with slip torque T_s;
  modelled as the **equivalent viscous** damper that dissipates the same energy per cycle at a
  design relative amplitude a and frequency ω: ``c_eq = 4 T_s / (π ω a)`` — the real damper is
  non-linear, so the model is right only near that amplitude.

References
----------
.. [1] J. P. Den Hartog, *Mechanical Vibrations*, 4th ed., McGraw-Hill, 1956, ch. 3
   (damped vibration absorber, optimum tuning f = 1/(1+μ), ζ² = 3μ/(8(1+μ)³); untuned viscous
   damper, c_opt = 2 J_d ω_n / √(2(1+μ)(2+μ))), ch. 5 (centrifugal pendulum, friction dampers).
.. [2] 发动机设计 第三章, 减振器的型式 (dynamic, damping and compound dampers).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_int, check_nonnegative, check_option, check_positive
from ..errors import ModelError

__all__ = ["add_viscous_damper", "add_tuned_damper", "add_pendulum_absorber",
           "add_friction_damper", "friction_equivalent_damping", "den_hartog_optimum",
           "lanchester_optimum", "DamperTuning", "optimum_tuned_damper",
           "optimum_viscous_damper", "fixed_points", "tuned_absorber_response",
           "pendulum_length", "pendulum_order"]


def add_viscous_damper(line, node: str, *, ring_inertia: float, damping: float,
                       name: str | None = None) -> str:
    """Viscous (Houdaille) damper on ``node``: free ring (kg·m²) + viscous link (N·m·s/rad).

    Returns the ring's node name.
    """
    ring = name or f"{node} viscous ring"
    _, ratio = line._port(node)
    line.add_mass(ring, ring_inertia, ratio=ratio, eigen=False)
    line.add_spring(node, ring, stiffness=0.0,
                    damping=check_positive(damping, "damping", error=ModelError),
                    name=f"{ring} link")
    return ring


def add_tuned_damper(line, node: str, *, ring_inertia: float, stiffness: float,
                     damping: float = 0.0, loss_factor: float = 0.0,
                     name: str | None = None) -> str:
    """Tuned spring-viscous damper: ring (kg·m²) on a spring (N·m/rad) with viscous damping
    (N·m·s/rad) and/or hysteretic loss factor (rubber). Returns the ring's node name."""
    ring = name or f"{node} tuned ring"
    _, ratio = line._port(node)
    line.add_mass(ring, ring_inertia, ratio=ratio)
    line.add_spring(node, ring, stiffness=check_positive(stiffness, "stiffness",
                                                          error=ModelError),
                    damping=damping, loss_factor=loss_factor, name=f"{ring} spring")
    return ring


def add_pendulum_absorber(line, node: str, *, mass: float, pivot_radius: float, length: float,
                          damping: float = 0.0, name: str | None = None) -> str:
    """Order-tuned centrifugal pendulum on ``node`` (total pendulum mass kg, pivot radius R and
    pendulum length r in m); tuned order n = √(R/r). Returns the pendulum node name."""
    m = check_positive(mass, "mass", error=ModelError)
    big_r = check_positive(pivot_radius, "pivot_radius", error=ModelError)
    r = check_positive(length, "length", error=ModelError)
    j_a = m * (big_r + r) ** 2
    pend = name or f"{node} pendulum n={np.sqrt(big_r / r):.3g}"
    _, ratio = line._port(node)
    line.add_mass(pend, j_a, ratio=ratio, eigen=False)
    line.add_spring(node, pend, stiffness=0.0, stiffness_omega2=j_a * big_r / r,
                    damping=check_nonnegative(damping, "damping", error=ModelError),
                    name=f"{pend} link")
    return pend


def friction_equivalent_damping(slip_torque: float, omega: float,
                                relative_amplitude: float) -> float:
    """Equivalent viscous damping of a friction (Coulomb) link, N·m·s/rad.

    Equal energy per cycle: ``4 T_s a = π c ω a²`` ⇒ ``c = 4 T_s / (π ω a)``.

    Examples
    --------
    >>> print(round(friction_equivalent_damping(100.0, 200.0, 0.01), 3))
    63.662
    """
    t = check_positive(slip_torque, "slip_torque", error=ModelError)
    w = check_positive(omega, "omega", error=ModelError)
    a = check_positive(relative_amplitude, "relative_amplitude", error=ModelError)
    return 4.0 * t / (np.pi * w * a)


def add_friction_damper(line, node: str, *, ring_inertia: float, slip_torque: float,
                        design_frequency: float | None = None,
                        design_amplitude: float | None = None, model: str | None = None,
                        name: str | None = None) -> str:
    """Lanchester friction damper (free ring on friction plates) on ``node``.

    Parameters
    ----------
    line : ShaftLine
    node : str
        Hub node (at crankshaft speed for the non-linear model).
    ring_inertia : float
        kg·m².
    slip_torque : float
        N·m.
    design_frequency, design_amplitude : float, optional
        rad/s and relative rad: the design point of the linearised model.
    model : {"harmonic-balance", "linearised"}, optional
        ``"harmonic-balance"`` keeps the ring as a non-linear element of the system
        (slip/stick response across speed by :mod:`predict.torsion.friction_line`; the ring
        is not in the eigen-analysis); ``"linearised"`` adds the equivalent viscous damper at
        the design point. Default: linearised when a design point is given, else
        harmonic-balance.

    Returns
    -------
    str
        The ring's name.
    """
    lin = design_frequency is not None or design_amplitude is not None
    model = check_option(model if model is not None else
                         ("linearised" if lin else "harmonic-balance"), "model",
                         ("harmonic-balance", "linearised"), error=ModelError)
    ring = name or f"{node} friction ring"
    if model == "linearised":
        if design_frequency is None or design_amplitude is None:
            raise ModelError("the linearised friction damper needs design_frequency (rad/s) "
                             "and design_amplitude (rad)")
        c = friction_equivalent_damping(slip_torque, design_frequency, design_amplitude)
        return add_viscous_damper(line, node, ring_inertia=ring_inertia, damping=c, name=ring)
    if lin:
        raise ModelError("design_frequency/design_amplitude belong to the linearised model; "
                         "the harmonic-balance friction damper has no design point")
    line._port(node)
    line._friction.append(dict(node=node, name=ring,
                               ring_inertia=check_positive(ring_inertia, "ring_inertia",
                                                           error=ModelError),
                               slip_torque=check_positive(slip_torque, "slip_torque",
                                                          error=ModelError)))
    return ring


@dataclass(frozen=True)
class DamperTuning:
    """Optimum damper parameters for one mode.

    Attributes
    ----------
    kind : str
    mass_ratio : float
        μ = J_damper / J_modal at the damper node.
    natural_frequency_hz : float
        Of the undamped mode being suppressed.
    stiffness : float
        N·m/rad (0 for untuned dampers).
    damping : float
        N·m·s/rad.
    frequency_ratio : float
        Damper frequency over mode frequency (tuned) or NaN.
    damping_ratio : float
        c / (2 J_d ω_n).
    max_magnification : float
        Peak amplitude over static deflection of the main mass with the optimum damper.
    """

    kind: str
    mass_ratio: float
    natural_frequency_hz: float
    stiffness: float
    damping: float
    frequency_ratio: float
    damping_ratio: float
    max_magnification: float

    def to_frame(self):
        import pandas as pd

        return pd.DataFrame([self.__dict__])

    def plot(self, ax=None):
        """Bar of the parameters; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        ax.bar(["μ", "f ratio", "ζ"], [self.mass_ratio, self.frequency_ratio,
                                       self.damping_ratio])
        ax.set_title(self.kind)
        return fig


def den_hartog_optimum(mass_ratio: float):
    """Den Hartog's optimum tuned absorber: f = 1/(1+μ), ζ = √(3μ/(8(1+μ)³)),
    peak magnification √(1 + 2/μ).

    Examples
    --------
    >>> f, z, m = den_hartog_optimum(0.25)
    >>> print(round(f, 4), round(z, 4), round(m, 4))
    0.8 0.2191 3.0
    """
    mu = check_positive(mass_ratio, "mass_ratio", error=ModelError)
    return 1.0 / (1.0 + mu), float(np.sqrt(3 * mu / (8 * (1 + mu) ** 3))), float(
        np.sqrt(1 + 2 / mu))


def lanchester_optimum(mass_ratio: float):
    """Optimum untuned viscous (Lanchester/Houdaille) damper: ζ = c/(2 J_d ω_n) =
    1/√(2(1+μ)(2+μ)), peak magnification 1 + 2/μ.

    Examples
    --------
    >>> z, m = lanchester_optimum(0.25)
    >>> print(round(z, 4), m)
    0.4216 9.0
    """
    mu = check_positive(mass_ratio, "mass_ratio", error=ModelError)
    return float(1.0 / np.sqrt(2 * (1 + mu) * (2 + mu))), 1.0 + 2.0 / mu


def _modal(system, node, mode):
    mode = check_int(mode, "mode", minimum=1, error=ModelError)
    if isinstance(node, str):
        if node not in system.node_names:
            raise ModelError(f"node {node!r} not in the system ({', '.join(system.node_names)})")
        node = system.node_names.index(node)
    omega, shapes, numbers, _, _ = system._eigen
    hit = np.flatnonzero(numbers == mode)
    if hit.size == 0:
        raise ModelError(f"mode={mode} does not exist (system has {numbers.max()} elastic modes)")
    a = shapes[node, hit[0]]
    if a == 0:
        raise ModelError(f"node {system.node_names[node]!r} is a node of mode {mode}: a damper "
                         "there has no effect")
    return omega[hit[0]], 1.0 / a ** 2


def optimum_tuned_damper(system, node, *, ring_inertia: float, mode: int = 1) -> DamperTuning:
    """Den Hartog optimum spring and damping of a tuned damper on ``node`` for ``mode``.

    The system is reduced to its modal one-degree-of-freedom equivalent at the damper node
    (modal inertia 1/a², a mass-normalised), valid for well-separated modes.
    """
    w, j_eff = _modal(system, node, mode)
    jd = check_positive(ring_inertia, "ring_inertia", error=ModelError)
    mu = jd / j_eff
    f, zeta, mag = den_hartog_optimum(mu)
    return DamperTuning("tuned (Den Hartog)", mu, w / (2 * np.pi), jd * (f * w) ** 2,
                        2 * zeta * jd * w, f, zeta, mag)


def optimum_viscous_damper(system, node, *, ring_inertia: float, mode: int = 1) -> DamperTuning:
    """Optimum damping of an untuned viscous (Houdaille) damper on ``node`` for ``mode``."""
    w, j_eff = _modal(system, node, mode)
    jd = check_positive(ring_inertia, "ring_inertia", error=ModelError)
    mu = jd / j_eff
    zeta, mag = lanchester_optimum(mu)
    return DamperTuning("viscous (Lanchester/Houdaille)", mu, w / (2 * np.pi), 0.0,
                        2 * zeta * jd * w, np.nan, zeta, mag)


def tuned_absorber_response(frequency, *, mass_ratio, frequency_ratio, damping_ratio):
    """Main-mass amplitude over its static deflection with a damped tuned absorber.

    Den Hartog (1956) §3.3: with g = ω/ω_n (forcing over main-system frequency), f = ω_a/ω_n,
    μ = J_a/J and ζ = c/(2 J_a ω_n),

    ``|x/x_st| = √[(2ζg)² + (g² − f²)²]
    / √[(2ζg)² (g² − 1 + μg²)² + (μf²g² − (g² − 1)(g² − f²))²]``.

    Parameters
    ----------
    frequency : float or array_like
        g, dimensionless forcing frequency.
    mass_ratio, frequency_ratio, damping_ratio : float
        μ, f, ζ.

    Examples
    --------
    >>> round(float(tuned_absorber_response(1.0, mass_ratio=0.25, frequency_ratio=1.0,
    ...                                     damping_ratio=0.0)), 12)
    0.0
    """
    g = np.asarray(frequency, float)
    mu = check_positive(mass_ratio, "mass_ratio", error=ModelError)
    f = check_positive(frequency_ratio, "frequency_ratio", error=ModelError)
    z = check_nonnegative(damping_ratio, "damping_ratio", error=ModelError)
    g2 = g * g
    num = (2 * z * g) ** 2 + (g2 - f * f) ** 2
    den = ((2 * z * g) ** 2 * (g2 - 1 + mu * g2) ** 2
           + (mu * f * f * g2 - (g2 - 1) * (g2 - f * f)) ** 2)
    out = np.sqrt(num / den)
    return float(out) if out.ndim == 0 else out


def fixed_points(*, mass_ratio, frequency_ratio):
    """Den Hartog's fixed points P and Q of the damped tuned absorber.

    Every damping curve of :func:`tuned_absorber_response` passes through two frequencies
    ``g²_{P,Q} = [1 + f²(1+μ) ∓ √((1 + f²(1+μ))² − 2f²(2+μ))]/(2+μ)`` with heights
    ``1/|1 − (1+μ) g²|``; optimum tuning f = 1/(1+μ) makes them equal, √(1 + 2/μ).

    Returns
    -------
    dict
        ``frequency_p``, ``frequency_q`` (g, dimensionless) and ``height_p``, ``height_q``.

    References
    ----------
    Den Hartog, *Mechanical Vibrations*, 4th ed. (1956) §3.3, eq. (3.29)-(3.31).

    Examples
    --------
    >>> p = fixed_points(mass_ratio=0.25, frequency_ratio=0.8)
    >>> round(p["height_p"], 6), round(p["height_q"], 6)
    (3.0, 3.0)
    """
    mu = check_positive(mass_ratio, "mass_ratio", error=ModelError)
    f = check_positive(frequency_ratio, "frequency_ratio", error=ModelError)
    b = 1 + f * f * (1 + mu)
    root = np.sqrt(b * b - 2 * f * f * (2 + mu))
    g2 = np.array([(b - root) / (2 + mu), (b + root) / (2 + mu)])
    h = 1.0 / np.abs(1 - (1 + mu) * g2)
    return dict(frequency_p=float(np.sqrt(g2[0])), frequency_q=float(np.sqrt(g2[1])),
                height_p=float(h[0]), height_q=float(h[1]))


def pendulum_length(order, *, pivot_radius) -> float:
    """Pendulum length r (m) tuning a centrifugal pendulum to ``order``: r = R/n².

    The linearised pendulum (pivot at radius R, length r) swings at n = √(R/r) times the
    shaft speed at every speed (Den Hartog §5.7). For bifilar and roller pendulums r is the
    effective length (hole minus pin diameter for a bifilar suspension).

    Examples
    --------
    >>> pendulum_length(4.5, pivot_radius=0.12)   # 0.12 / 20.25 m
    0.005925925925925926
    """
    n = check_positive(order, "order", error=ModelError)
    return check_positive(pivot_radius, "pivot_radius", error=ModelError) / (n * n)


def pendulum_order(*, pivot_radius, length) -> float:
    """Tuned order n = √(R/r) of a centrifugal pendulum (R, r in m).

    Examples
    --------
    >>> pendulum_order(pivot_radius=0.1, length=0.025)
    2.0
    """
    return float(np.sqrt(check_positive(pivot_radius, "pivot_radius", error=ModelError)
                         / check_positive(length, "length", error=ModelError)))
