"""Crankshaft as a beam: main-bearing loads and internal bending moments from gas and inertia
forces, statically determinate or continuous over all main bearings.

Loads: at every crank pin the force of the connecting rod (gas + reciprocating inertia, from
:func:`predict.forces.crank_forces`, two-point rod) plus the centrifugal force of the rotating
mass at crank radius (``Engine.rotating_mass``: big end and unbalanced throw; counterweights,
when given, as further rotating masses). Forces and moments are in-plane vectors written as
complex numbers ``vertical + 1j·horizontal`` in the engine frame (docs/DESIGN.md): a force
on the shaft, positive upwards / towards the side the top of the crank moves to. A bearing
load is the force the *shaft* exerts on the bearing (equal and opposite to the reaction).

Beam models (the shaft axis is the engine's cylinder-position axis, m):

``determinate``
    Each throw is a simple beam between the two main bearings on either side of its crank pin
    (the classical "split" crankshaft): a pin force F at distance a from the left bearing of a
    span of length L loads that bearing with F (L − a)/L and the right one with F a/L.
``continuous``
    One continuous Euler-Bernoulli beam on rigid supports at every main bearing (uniform or
    per-span bending stiffness), solved exactly by the stiffness method with a node at every
    bearing and load (cubic elements are exact for point loads); bearings share loads of
    neighbouring spans. Bending moments M(z) follow from statics with the solved reactions.

References
----------
.. [1] W. C. Young, R. G. Budynas, *Roark's Formulas for Stress and Strain*, 7th ed., Table 8.1
   and §8.6 (continuous beams: two equal spans, point load at mid-span: reactions 13P/32,
   11P/16, −3P/32).
.. [2] 交通大学内燃机教研组, 内燃机动力学、构造与计算 (上册), 1958, 第一篇 (crank-train forces);
   Liang 1948 ch. 5 (forces on the crank pin).
.. [3] IACS UR M53, *Calculation of crankshafts for I.C. engines*, §2 (bending moments
   from the statically determinate model over one throw); its fillet factors:
   :mod:`predict.crankshaft_scf`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_int, check_option, check_positive
from .errors import ModelError

__all__ = ["BearingLoads", "bearing_loads", "continuous_beam_reactions", "BEAM_MODELS",
           "web_stresses", "bearing_loads_from_toml"]

BEAM_MODELS = ("determinate", "continuous")


def _pin_forces(engine, angle, omega, pressure):
    """Force of each crank train on its pin, (n_cyl, n_angles) complex N (engine frame)."""
    from .forces import crank_forces

    theta_shaft = engine.shaft_angle(angle)
    fire = engine.firing_angles_deg()
    alpha = np.deg2rad(engine.crank_angles_deg)
    out = np.empty((engine.n_cylinders, angle.size), complex)
    for i in range(engine.n_cylinders):
        psi = np.mod(angle - np.deg2rad(fire[i]), engine.cycle_angle)
        f = crank_forces(engine, psi, omega=omega, pressure=pressure, cylinder=i + 1)
        u = np.exp(1j * (theta_shaft + alpha[i]))           # throw direction
        out[i] = (-f.radial + 1j * f.tangential) * u
        out[i] += engine.rotating_mass[i] * engine.crank_radius * omega ** 2 * u
    return out


def continuous_beam_reactions(positions, bearing_positions, bending_stiffness=1.0):
    """Influence matrix of a continuous beam on rigid supports: reactions per unit load.

    Parameters
    ----------
    positions : array_like (n_loads,)
        Load positions, m (inside or outside the supported length).
    bearing_positions : array_like (n_b,)
        Support positions, m, ascending (at least two).
    bending_stiffness : float or array_like (n_b − 1,)
        EI of each span, N·m² (the reactions depend only on their ratios). Overhangs take
        the stiffness of the nearest span.

    Returns
    -------
    ndarray (n_b, n_loads)
        Support reaction for a unit (upward) load at each position; each column sums to −1.

    Examples
    --------
    >>> r = continuous_beam_reactions([0.5], [0.0, 1.0, 2.0])   # Roark: 13/32, 11/16, −3/32
    >>> print((-r[:, 0] * 32).round(12))
    [13. 22. -3.]
    """
    z = check_finite_array(positions, "positions", ndim=1, error=ModelError)
    zb = check_finite_array(bearing_positions, "bearing_positions", ndim=1, min_length=2,
                            error=ModelError)
    if np.any(np.diff(zb) <= 0):
        raise ModelError("bearing_positions must be strictly ascending")
    ei = np.broadcast_to(np.asarray(bending_stiffness, float), (zb.size - 1,))
    if np.any(~np.isfinite(ei)) or np.any(ei <= 0):
        raise ModelError("bending_stiffness must be > 0 (N·m²)")
    nodes = np.unique(np.concatenate([z, zb]))
    n = nodes.size
    k = np.zeros((2 * n, 2 * n))
    for e in range(n - 1):
        h = nodes[e + 1] - nodes[e]
        span = int(np.clip(np.searchsorted(zb, 0.5 * (nodes[e] + nodes[e + 1])) - 1, 0,
                           zb.size - 2))
        c = ei[span] / h ** 3
        ke = c * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                           [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
        idx = np.arange(2 * e, 2 * e + 4)
        k[np.ix_(idx, idx)] += ke
    sup = 2 * np.searchsorted(nodes, zb)
    free = np.setdiff1d(np.arange(2 * n), sup)
    f = np.zeros((2 * n, z.size))
    f[2 * np.searchsorted(nodes, z), np.arange(z.size)] = 1.0
    w = np.zeros_like(f)
    w[free] = np.linalg.solve(k[np.ix_(free, free)], f[free])
    return (k @ w - f)[sup]


@dataclass(frozen=True)
class BearingLoads:
    """Main-bearing loads and bending moments over one working cycle.

    Attributes
    ----------
    angle : ndarray (n_a,)
        Crank angle from cylinder 1's firing TDC, rad.
    bearing_positions : ndarray (n_b,)
        m along the shaft.
    loads : ndarray (n_a, n_b) complex
        Force of the shaft on each main bearing, N (vertical + 1j·horizontal).
    pin_forces : ndarray (n_a, n_cyl) complex
        Force on each crank pin, N.
    pin_moments : ndarray (n_a, n_cyl) complex
        Bending moment at each crank-pin centre, N·m, as the in-plane vector of the bending
        force resultant (its direction is that of the forces producing it).
    pin_moment_radial : ndarray (n_a, n_cyl)
        Component of ``pin_moments`` along the throw (the crank-web bending of the fillets,
        positive for forces pointing outwards along the throw), N·m.
    journal_torque : ndarray (n_a, n_b)
        Twisting moment in the shaft at each bearing position (sum of the torques of the
        cylinders before it, counted from the first), N·m.
    model : str
    omega : float
    """

    angle: np.ndarray
    bearing_positions: np.ndarray
    loads: np.ndarray
    pin_forces: np.ndarray
    pin_moments: np.ndarray
    pin_moment_radial: np.ndarray
    journal_torque: np.ndarray
    model: str
    omega: float

    def to_frame(self):
        """Per bearing: largest and mean load magnitude (N) and the angle of the largest."""
        import pandas as pd

        mag = np.abs(self.loads)
        k = np.argmax(mag, axis=0)
        return pd.DataFrame({"bearing": np.arange(1, self.bearing_positions.size + 1),
                             "position_m": self.bearing_positions,
                             "max_load_n": mag.max(axis=0), "mean_load_n": mag.mean(axis=0),
                             "angle_of_max_deg": np.rad2deg(self.angle[k])})

    def plot(self, ax=None, *, bearing=None):
        """Polar load diagram of one bearing (default the most loaded); returns the figure."""
        import matplotlib.pyplot as plt

        b = int(np.argmax(np.abs(self.loads).max(axis=0))) if bearing is None else int(bearing)
        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        f = self.loads[:, b] / 1e3
        ax.plot(f.imag, f.real)
        ax.set_aspect("equal")
        ax.set_xlabel("horizontal (kN)")
        ax.set_ylabel("vertical (kN)")
        ax.set_title(f"main bearing {b + 1} ({self.model})")
        return fig


def bearing_loads(engine, *, omega, bearing_positions, pressure=None, model="continuous",
                  bending_stiffness=1.0, points=720) -> BearingLoads:
    """Main-bearing loads and crank-pin bending moments over one cycle.

    Parameters
    ----------
    engine : Engine
        Plain rods only (articulated rods act through their master rod).
    omega : float
        Crank speed, rad/s.
    bearing_positions : array_like
        Main-bearing positions along the shaft, m, ascending, in the frame of
        ``engine.cylinder_positions``; each crank pin must lie between two of them.
    pressure : PressureTrace, optional
        Cylinder pressure (None: inertia forces only).
    model : {"continuous", "determinate"}
    bending_stiffness : float or array_like
        EI per span for the continuous model, N·m².
    points : int
        Crank angles over the cycle.

    Returns
    -------
    BearingLoads

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0, cylinder_positions=[0.0])
    >>> r = bearing_loads(e, omega=100.0, bearing_positions=[-0.05, 0.05], points=8,
    ...                   model="determinate")
    >>> print(round(float(r.loads[0, 0].real), 3))   # half of m r ω² (1 + λ) upwards
    625.0
    """
    model = check_option(model, "model", BEAM_MODELS, error=ModelError)
    w = check_positive(omega, "omega", error=ModelError)
    n = check_int(points, "points", minimum=4, error=ModelError)
    zb = check_finite_array(bearing_positions, "bearing_positions", ndim=1, min_length=2,
                            error=ModelError)
    if np.any(np.diff(zb) <= 0):
        raise ModelError("bearing_positions must be strictly ascending")
    z = engine.cylinder_positions
    span = np.searchsorted(zb, z) - 1
    bad = (span < 0) | (span >= zb.size - 1) | np.isin(z, zb)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ModelError(f"crank pin of cylinder {i + 1} at {z[i]:g} m does not lie strictly "
                         f"between two main bearings ({zb.tolist()} m)")
    angle = np.arange(n) * engine.cycle_angle / n
    f = _pin_forces(engine, angle, w, pressure).T              # (n_a, n_cyl)
    if model == "determinate":
        infl = np.zeros((zb.size, z.size))
        for i, s in enumerate(span):
            length = zb[s + 1] - zb[s]
            a = z[i] - zb[s]
            infl[s, i] = -(length - a) / length
            infl[s + 1, i] = -a / length
    else:
        infl = continuous_beam_reactions(z, zb, bending_stiffness)
    reactions = f @ infl.T                                      # (n_a, n_b) on the shaft
    loads = -reactions
    # bending moment at each pin: moments of every force to its left (M = Σ F (z − z_k))
    mom = np.zeros((n, z.size), complex)
    for i in range(z.size):
        left_b = zb < z[i]
        left_p = z < z[i]
        mom[:, i] = (reactions[:, left_b] @ (z[i] - zb[left_b])
                     + f[:, left_p] @ (z[i] - z[left_p]))
    u = np.exp(1j * (engine.shaft_angle(angle)[:, None] + np.deg2rad(engine.crank_angles_deg)))
    radial = np.real(mom * np.conj(u))
    from .forces import engine_torque

    per = engine_torque(engine, angle, omega=w, pressure=pressure, per_cylinder=True).T
    tq = np.zeros((n, zb.size))
    for b in range(zb.size):
        before = z < zb[b]
        tq[:, b] = per[:, before].sum(axis=1) if before.any() else 0.0
    return BearingLoads(angle=angle, bearing_positions=zb.copy(), loads=loads, pin_forces=f,
                        pin_moments=mom, pin_moment_radial=radial, journal_torque=tq,
                        model=model, omega=w)


def web_stresses(*, bending_moment, radial_force, web_width, web_thickness, bending_scf=1.0,
                 compression_scf=1.0):
    """Nominal and fillet stresses of a crank web from its bending moment and radial force.

    The web is a rectangular section of width b (across the shaft) and thickness h (along it):
    ``σ_b = M / (b h²/6)``, ``σ_q = F / (b h)`` (IACS UR M53 §2.2: W_eqw = B W²/6,
    F = B W), the fillet stress ``α σ_b + β σ_q``. With the rule's empirical factors
    (:func:`predict.crankshaft_scf.stress_concentration_factors`, defined on this web basis):
    crank-pin fillet α = α_B, β = 0; journal fillet α = β_B, β = β_Q (UR M53 §2 (1)(C)).

    Parameters
    ----------
    bending_moment : array_like
        Bending moment in the web from the radial forces (e.g. ``BearingLoads.pin_moment_radial``
        carried to the web centre), N·m.
    radial_force : array_like
        Radial force through the web (positive outwards, tension), N.
    web_width, web_thickness : float
        b and h, m.
    bending_scf : float
        α ≥ 1, on the web bending stress.
    compression_scf : float
        β ≥ 0, on the web compressive stress (default 1: the nominal stress added).

    Returns
    -------
    dict
        ``bending``, ``axial`` and ``fillet`` stress arrays, Pa, and ``fillet_alternating``,
        ``fillet_mean``.

    Examples
    --------
    >>> r = web_stresses(bending_moment=[0.0, 600.0], radial_force=[0.0, 12000.0],
    ...                  web_width=0.12, web_thickness=0.03, bending_scf=2.0)
    >>> round(r["fillet_alternating"] / 1e6, 3)
    35.0
    """
    m = check_finite_array(bending_moment, "bending_moment", error=ModelError)
    f = check_finite_array(radial_force, "radial_force", error=ModelError)
    b = check_positive(web_width, "web_width", error=ModelError)
    h = check_positive(web_thickness, "web_thickness", error=ModelError)
    a = float(bending_scf)
    if not a >= 1:
        raise ModelError(f"bending_scf={bending_scf!r} must be >= 1")
    beta = float(compression_scf)
    if not beta >= 0:
        raise ModelError(f"compression_scf={compression_scf!r} must be >= 0")
    sb = m / (b * h * h / 6)
    sq = f / (b * h)
    fil = a * sb + beta * sq
    return dict(bending=sb, axial=sq, fillet=fil, fillet_alternating=float(np.ptp(fil) / 2),
                fillet_mean=float((fil.max() + fil.min()) / 2))


def bearing_loads_from_toml(path, *, omega, pressure=None, points=720) -> BearingLoads:
    """Main-bearing loads of the engine in a model file with a ``[crankshaft]`` table.

    Keys: ``bearing_positions`` (m, in the frame of the cylinder positions), ``model``
    ("continuous" default, or "determinate"), ``bending_stiffness`` (N·m², one value or one
    per span; default uniform)::

        [crankshaft]
        bearing_positions = [-0.076, 0.076, 0.228, 0.38, 0.532, 0.684, 0.836]
        model = "continuous"

    Parameters
    ----------
    path : str or Path
    omega : float
        rad/s.
    pressure : PressureTrace, optional
        Default: the engine's synthetic trace (``[engine.combustion]``).
    points : int
    """
    from ._toml import load_toml
    from .engine import Engine
    from .pressure import synthetic_pressure

    doc = load_toml(path)
    t = doc.table("crankshaft", None)
    if t is None:
        raise ModelError(f"{path}: has no [crankshaft] table (bearing_positions, model)")
    positions = t.numbers("bearing_positions", unit="m", plausible=(1e-4, 100.0))
    model = t.string("model", "continuous", options=BEAM_MODELS)
    raw = t.raw("bending_stiffness", 1.0)
    # EI, N·m²: only the ratios between spans matter, so no plausible range
    ei = (t.numbers("bending_stiffness", low=0.0, strict_low=True, unit="N*m^2")
          if isinstance(raw, list) else t.positive("bending_stiffness", 1.0, unit="N*m^2"))
    t.check_unknown(["description", "fillets"])     # fillets: predict.crankshaft_scf
    engine = Engine.from_toml(path)
    if pressure is None and engine.bore is not None and engine.compression_ratio is not None:
        pressure = synthetic_pressure(engine)
    try:
        return bearing_loads(engine, omega=omega, bearing_positions=positions, pressure=pressure,
                             model=model, bending_stiffness=ei, points=points)
    except ModelError as exc:
        raise ModelError(f"{t.where()} {exc}") from None
