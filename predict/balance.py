"""Balance of any crank-train layout by rotating vectors: shaking forces and moments per order,
counterweights, Lanchester balance shafts and the balance residual table.

Every reciprocating force of order n along a cylinder axis is split into two vectors of half its
amplitude rotating at n·ω, one forward (with the crank) and one backward (Zhao, *Engine Design*
ch. 3 §2: the "equivalent centrifugal force" and its forward/backward parts A₁, B₁); rotating
masses add a forward vector at order 1.  Summing the vectors of all cylinders — and their
moments about the reference point, the midpoint between the first and last cylinders — gives
per order a forward phasor P and a backward phasor Q.  In-plane vectors are complex numbers
``vertical + 1j * horizontal`` (engine frame of :mod:`predict.engine`), so the order-n resultant
is ``P e^{inθ} + Q e^{−inθ}``: an ellipse whose largest magnitude over a revolution is
``|P| + |Q|``, vertical amplitude ``|P + conj(Q)|`` and horizontal ``|P − conj(Q)|``.  Nothing
is hard-coded per layout: e.g. the vanishing of every moment for a mirror-symmetric crankshaft
comes out of the sums.

Coefficients: plain rods use the exact series of :mod:`predict.kinematics` (centred pin) or an
FFT of the exact motion (pin offset, articulated rods), so each order is exact to round-off.

References
----------
Liang Shoupan, *Engine Dynamics* (1948) ch. 2-3 (single and multi-cylinder inline balance,
residual couples, V and radial engines); Zhao (ed.), *Engine Design* ch. 3 (balance of single-
and multi-cylinder inline engines by rotating vectors, general formulas).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_int, check_nonnegative, check_range
from .errors import ModelError
from .kinematics import series_coefficients

__all__ = [
    "unbalance",
    "shaking_forces",
    "Counterweight",
    "BalanceShaft",
    "counterweights",
    "lanchester_shafts",
    "balance_residuals",
    "BalanceResiduals",
]

_FFT_POINTS = 512


@dataclass(frozen=True)
class Counterweight:
    """A mass fixed to the crankshaft.

    Attributes
    ----------
    mass_radius : float
        Unbalance m·ρ of the counterweight, kg·m.
    angle_deg : float
        Angular position of its centre of mass ahead of throw 1, deg (180 + αᵢ: opposite
        throw i).
    position : float
        Axial position along the crankshaft, m (same axis as the cylinder positions).
    """

    mass_radius: float
    angle_deg: float
    position: float


@dataclass(frozen=True)
class BalanceShaft:
    """An eccentric on a balance shaft turning at ``order`` × crank speed.

    Attributes
    ----------
    order : int
        Speed ratio to the crankshaft (1 or 2 for Lanchester shafts).
    direction : int
        +1 turns with the crankshaft, −1 against it.
    mass_radius : float
        Unbalance m·ρ, kg·m.
    phase_deg : float
        Angle of the unbalance from the vertical (direction of its own rotation) when θ = 0, deg.
    position : float
        Axial position, m.
    """

    order: int
    direction: int
    mass_radius: float
    phase_deg: float
    position: float


def _not_rotary(engine):
    if getattr(engine, "rotary", False):
        raise ModelError(f"engine {engine.name!r} is a rotary engine (cylinders turning round a "
                         "fixed crank): its shaking forces are not modelled by predict.balance, "
                         "which assumes a stationary crankcase")


def _omega(omega) -> float:
    return check_range(omega, "omega", 0.0, None, error=ModelError)


def _orders(orders) -> np.ndarray:
    try:
        out = np.array([check_int(o, "orders", minimum=1, error=ModelError) for o in orders])
    except TypeError:
        raise ModelError(f"orders={orders!r} must be a sequence of positive integers") from None
    if out.size == 0:
        raise ModelError("orders must list at least one order")
    return out


def _axial_harmonics(engine, max_order):
    """H[i, n]: axial inertia force of cylinder i per unit ω², f_i = Σ Re(H e^{inθ})."""
    n_cyl = engine.n_cylinders
    H = np.zeros((n_cyl, max_order + 1), dtype=complex)
    n = np.arange(max_order + 1)
    alpha = np.deg2rad(engine.crank_angles_deg)
    beta = np.deg2rad(engine.bank_angles_deg)
    m = engine.reciprocating_mass
    r = engine.crank_radius
    plain = [i for i in range(n_cyl) if engine.articulated[i] is None]
    if engine.pin_offset == 0.0:
        a = series_coefficients(engine.lam, max_order)
        for i in plain:
            H[i] = m[i] * r * a * np.exp(1j * n * (alpha[i] - beta[i]))
        rest = [i for i in range(n_cyl) if i not in plain]
    else:
        rest = list(range(n_cyl))
    if rest:
        npts = max(_FFT_POINTS, 4 * (max_order + 1))
        theta = 2 * np.pi * np.arange(npts) / npts
        _, _, d2x = engine.piston_motion(theta)
        spec = np.fft.fft(-m[:, None] * d2x, axis=1) / npts
        for i in rest:
            H[i, 1:] = 2 * spec[i, 1:max_order + 1]
    return H


def _phasors(engine, omega, orders, counterweights=(), shafts=()):
    """Forward/backward force and moment phasors (N, N·m) per order."""
    _not_rotary(engine)
    orders = _orders(orders)
    w2 = omega * omega
    H = _axial_harmonics(engine, int(orders.max()))[:, orders] * w2
    e_beta = np.exp(1j * np.deg2rad(engine.bank_angles_deg))[:, None]
    dz = (engine.cylinder_positions - engine.reference_position)[:, None]
    P = 0.5 * H * e_beta
    Q = 0.5 * np.conj(H) * e_beta
    PF, QF = P.sum(axis=0), Q.sum(axis=0)
    PM, QM = (P * dz).sum(axis=0), (Q * dz).sum(axis=0)
    one = orders == 1
    if one.any():
        rot = engine.rotating_mass * engine.crank_radius * w2 * np.exp(
            1j * np.deg2rad(engine.crank_angles_deg))
        PF[one] += rot.sum()
        PM[one] += (rot * dz[:, 0]).sum()
        for cw in counterweights:
            f = cw.mass_radius * w2 * np.exp(1j * np.deg2rad(cw.angle_deg))
            PF[one] += f
            PM[one] += f * (cw.position - engine.reference_position)
    for s in shafts:
        sel = orders == s.order
        if not sel.any():
            continue
        f = s.mass_radius * (s.order * omega) ** 2 * np.exp(1j * s.direction
                                                             * np.deg2rad(s.phase_deg))
        dzs = s.position - engine.reference_position
        if s.direction > 0:
            PF[sel] += f
            PM[sel] += f * dzs
        else:
            QF[sel] += f
            QM[sel] += f * dzs
    return orders, PF, QF, PM, QM


def _dataset(engine, omega, orders, PF, QF, PM, QM, method):
    import xarray as xr

    def var(values, units, long_name):
        return ("order", values, {"units": units, "long_name": long_name})

    ds = xr.Dataset(
        {
            "force": var(np.abs(PF) + np.abs(QF), "N", "largest resultant shaking force"),
            "moment": var(np.abs(PM) + np.abs(QM), "N m",
                          "largest resultant shaking moment about the reference point"),
            "force_forward": var(np.abs(PF), "N", "forward-rotating force component"),
            "force_backward": var(np.abs(QF), "N", "backward-rotating force component"),
            "moment_forward": var(np.abs(PM), "N m", "forward-rotating moment component"),
            "moment_backward": var(np.abs(QM), "N m", "backward-rotating moment component"),
            "force_vertical": var(np.abs(PF + np.conj(QF)), "N", "vertical force amplitude"),
            "force_horizontal": var(np.abs(PF - np.conj(QF)), "N",
                                    "horizontal force amplitude"),
            "moment_pitch": var(np.abs(PM + np.conj(QM)), "N m",
                                "amplitude of the couple of the vertical forces"),
            "moment_yaw": var(np.abs(PM - np.conj(QM)), "N m",
                              "amplitude of the couple of the horizontal forces"),
            "force_forward_phasor": var(PF, "N", "P: forward phasor, vertical + 1j horizontal"),
            "force_backward_phasor": var(QF, "N", "Q: backward phasor"),
            "moment_forward_phasor": var(PM, "N m", "forward moment phasor"),
            "moment_backward_phasor": var(QM, "N m", "backward moment phasor"),
        },
        coords={"order": ("order", orders, {"units": "1", "long_name": "engine order"})},
        attrs={
            "engine": engine.name, "omega": float(omega),
            "speed_rpm": float(omega * 60 / (2 * np.pi)),
            "reference_position": engine.reference_position,
            "method": method,
            "convention": "resultant(theta) = P exp(i n theta) + Q exp(-i n theta), complex = "
                          "vertical + 1j*horizontal, theta = shaft angle of throw 1 from the "
                          "vertical in the direction of rotation; moments = sum of "
                          "(position - reference_position) * force",
            "amplitude": "peak",
        },
    )
    return ds


def unbalance(engine, *, omega, orders=(1, 2, 4, 6, 8), counterweights=(), shafts=()):
    """Resultant shaking forces and moments per engine order.

    Parameters
    ----------
    engine : Engine
    omega : float
        Crank speed, rad/s.
    orders : sequence of int
        Engine orders to report (any positive integers; odd orders beyond 1 are non-zero only
        with a pin offset or articulated rods).
    counterweights : sequence of Counterweight, optional
        Masses fixed to the crankshaft (act at order 1).
    shafts : sequence of BalanceShaft, optional
        Balance-shaft eccentrics.

    Returns
    -------
    xarray.Dataset
        Over dim ``order``: ``force`` (N) and ``moment`` (N·m), the largest magnitude over one
        revolution of that order's resultant; ``force_forward``/``force_backward`` and
        ``moment_forward``/``moment_backward`` (rotating components); ``force_vertical``,
        ``force_horizontal``, ``moment_pitch`` (couple of the vertical forces), ``moment_yaw``
        (couple of the horizontal forces) amplitudes; and the complex phasors. Exact to
        round-off per order (no truncation: each order's coefficient is exact).

    References
    ----------
    Zhao, *Engine Design* ch. 3 §2-3 (forward/backward rotating vectors, general formulas for
    ΣP and ΣM of inline engines); Liang 1948 ch. 2-3.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.04, rod_length=0.14,
    ...            reciprocating_mass=0.5, cylinder_positions=[0, 0.09, 0.18, 0.27])
    >>> ds = unbalance(e, omega=600.0, orders=(1, 2))
    >>> [round(float(v), 3) for v in ds["force"]]
    [0.0, 8403.251]
    """
    omega = _omega(omega)
    orders, PF, QF, PM, QM = _phasors(engine, omega, orders, tuple(counterweights),
                                      tuple(shafts))
    return _dataset(engine, omega, orders, PF, QF, PM, QM, "rotating vectors, exact coefficients")


def shaking_forces(engine, theta, *, omega, counterweights=(), shafts=(), pressure=None):
    """Shaking forces and moments on the engine block over shaft angle (time domain, exact).

    Sums the exact per-cylinder reciprocating inertia forces (along each cylinder axis), the
    centrifugal forces of the rotating masses, counterweights and balance shafts.

    Parameters
    ----------
    engine : Engine
    theta : array_like
        Shaft angle θ (rad): throw 1 from the vertical in the direction of rotation. For an
        angle from cylinder 1's firing TDC use ``engine.shaft_angle(angle)``.
    omega : float
        Crank speed, rad/s (constant).
    counterweights, shafts : optional
        As for :func:`unbalance`.
    pressure : PressureTrace, optional
        If given, ``moment_roll`` includes the gas torque reaction; otherwise inertia only.

    Returns
    -------
    xarray.Dataset
        Over dim ``angle`` (coordinate θ, rad): ``force_vertical`` (N, up), ``force_horizontal``
        (N, the way the top of the crank moves), ``moment_pitch`` = Σ (zᵢ − z_ref)·F_vertical,ᵢ
        and ``moment_yaw`` = Σ (zᵢ − z_ref)·F_horizontal,ᵢ (N·m, z along the cylinder
        positions), and ``moment_roll`` (N·m): the reaction torque on the block about the
        crankshaft axis, −(crankshaft torque), positive in the direction of rotation.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0, rotating_mass=1.0)
    >>> ds = shaking_forces(e, [0.0, np.pi / 2], omega=100.0)
    >>> [round(float(v), 3) for v in ds["force_vertical"]]
    [1750.0, -258.199]
    >>> round(float(ds["force_horizontal"][1]), 3)
    500.0
    """
    import xarray as xr

    from .forces import engine_torque

    omega = _omega(omega)
    _not_rotary(engine)
    th = check_finite_array(theta, "theta", ndim=1, error=ModelError)
    w2 = omega * omega
    _, _, d2x = engine.piston_motion(th)
    axial = -engine.reciprocating_mass[:, None] * w2 * d2x
    beta = np.deg2rad(engine.bank_angles_deg)[:, None]
    alpha = np.deg2rad(engine.crank_angles_deg)[:, None]
    rot = engine.rotating_mass[:, None] * engine.crank_radius * w2
    fv = axial * np.cos(beta) + rot * np.cos(th + alpha)
    fh = axial * np.sin(beta) + rot * np.sin(th + alpha)
    dz = (engine.cylinder_positions - engine.reference_position)[:, None]
    Fv, Fh = fv.sum(axis=0), fh.sum(axis=0)
    Mp, My = (fv * dz).sum(axis=0), (fh * dz).sum(axis=0)
    for cw in counterweights:
        ang = th + np.deg2rad(cw.angle_deg)
        f = cw.mass_radius * w2
        d = cw.position - engine.reference_position
        Fv, Fh = Fv + f * np.cos(ang), Fh + f * np.sin(ang)
        Mp, My = Mp + d * f * np.cos(ang), My + d * f * np.sin(ang)
    for s in shafts:
        ang = s.direction * (s.order * th + np.deg2rad(s.phase_deg))
        f = s.mass_radius * (s.order * omega) ** 2
        d = s.position - engine.reference_position
        Fv, Fh = Fv + f * np.cos(ang), Fh + f * np.sin(ang)
        Mp, My = Mp + d * f * np.cos(ang), My + d * f * np.sin(ang)
    roll = -engine_torque(engine, th - engine.firing_tdc_shaft_angle, omega=omega,
                          pressure=pressure)
    ds = xr.Dataset(
        {"force_vertical": ("angle", Fv, {"units": "N"}),
         "force_horizontal": ("angle", Fh, {"units": "N"}),
         "moment_pitch": ("angle", Mp, {"units": "N m"}),
         "moment_yaw": ("angle", My, {"units": "N m"}),
         "moment_roll": ("angle", np.atleast_1d(roll), {"units": "N m"})},
        coords={"angle": ("angle", th, {"units": "rad", "long_name": "shaft angle"})},
        attrs={"engine": engine.name, "omega": omega,
               "reference_position": engine.reference_position,
               "method": "exact time-domain sum over cylinders"})
    return ds


def counterweights(engine, *, balance_factor=0.0, rotating_fraction=1.0, radius=None):
    """One counterweight opposite each throw (per cylinder): rotating plus a share of the
    reciprocating mass.

    m_cw · ρ = (rotating_fraction · m_rot + balance_factor · m_rec) · r, placed at 180° + αᵢ.
    A balance factor of 0.5 halves a single cylinder's primary force (Liang 1948 §2-1); for a
    radial engine 0.5 per cylinder cancels the whole primary force.

    Parameters
    ----------
    engine : Engine
    balance_factor : float
        Fraction of the reciprocating mass balanced (0..1).
    rotating_fraction : float
        Fraction of the rotating mass balanced (0..1).
    radius : float, optional
        Radius of the counterweights' centre of mass, m (only changes the reported mass).

    Returns
    -------
    tuple of Counterweight

    References
    ----------
    Liang 1948 ch. 2 §2-1 (worked example: balance weight (4 + 8/2) × 3/3.5 = 6.86 lb).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=3.0, rod_length=12.0,
    ...            reciprocating_mass=8.0, rotating_mass=4.0)
    >>> cw = counterweights(e, balance_factor=0.5)
    >>> round(cw[0].mass_radius / 3.5, 2)   # mass at 3.5 in (Liang 1948 §2-1: 6.86 lb)
    6.86
    """
    k = check_range(balance_factor, "balance_factor", 0.0, 1.0, error=ModelError)
    f = check_range(rotating_fraction, "rotating_fraction", 0.0, 1.0, error=ModelError)
    if radius is not None:
        check_nonnegative(radius, "radius", error=ModelError)
    mr = (f * engine.rotating_mass + k * engine.reciprocating_mass) * engine.crank_radius
    return tuple(Counterweight(mass_radius=float(mr[i]),
                               angle_deg=float(engine.crank_angles_deg[i] + 180.0),
                               position=float(engine.cylinder_positions[i]))
                 for i in range(engine.n_cylinders) if mr[i] > 0)


def lanchester_shafts(engine, *, order, positions=None, counterweights=()):
    """Design forward and backward balance shafts that cancel one order's residual.

    With one plane (``positions`` None: at the reference point) a forward and a backward
    shaft cancel the order's force; with two planes (``positions=(z_a, z_b)``) four shafts
    cancel both force and moment.  Shaft unbalances are independent of speed.

    Parameters
    ----------
    engine : Engine
    order : int
        1 or 2 usually (any order allowed).
    positions : pair of float, optional
        Axial planes of the shaft pairs, m.
    counterweights : sequence of Counterweight
        Already fitted counterweights (their order-1 effect is cancelled too).

    Returns
    -------
    tuple of BalanceShaft

    References
    ----------
    Liang 1948 §2-1 (two counter-rotating weights cancel the primary force); Zhao, *Engine
    Design* ch. 3 §2 (balance shafts for the forward/backward vectors).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.04, rod_length=0.14,
    ...            reciprocating_mass=0.5, cylinder_positions=[0, 0.09, 0.18, 0.27])
    >>> s = lanchester_shafts(e, order=2)
    >>> [(x.direction, round(x.mass_radius * 1e3, 4)) for x in s]   # m r A2 / 2 each, g·m
    [(1, 2.9178), (-1, 2.9178)]
    """
    order = check_int(order, "order", minimum=1, error=ModelError)
    _, PF, QF, PM, QM = _phasors(engine, 1.0, [order], tuple(counterweights), ())
    scale = float(order) ** 2
    ref = engine.reference_position
    # residuals below round-off of the engine's own unbalances need no shaft
    tiny = 1e-12 * float(np.sum(engine.reciprocating_mass + engine.rotating_mass)
                         * engine.crank_radius) * max(1.0, scale)
    out = []
    if positions is None:
        for direction, X in ((1, PF[0]), (-1, QF[0])):
            if abs(X) <= tiny:
                continue
            out.append(BalanceShaft(order=order, direction=direction,
                                    mass_radius=float(abs(X) / scale),
                                    phase_deg=float(np.rad2deg(direction * np.angle(-X))),
                                    position=ref))
        return tuple(out)
    za, zb = (float(p) for p in positions)
    if za == zb:
        raise ModelError(f"positions={positions!r} must be two different planes")
    da, db = za - ref, zb - ref
    for direction, X, XM in ((1, PF[0], PM[0]), (-1, QF[0], QM[0])):
        # F_a + F_b = −X ; da F_a + db F_b = −XM
        fb = (-XM + da * X) / (db - da)
        fa = -X - fb
        for f, z in ((fa, za), (fb, zb)):
            if abs(f) <= tiny:
                continue
            out.append(BalanceShaft(order=order, direction=direction,
                                    mass_radius=float(abs(f) / scale),
                                    phase_deg=float(np.rad2deg(direction * np.angle(f))),
                                    position=z))
    return tuple(out)


@dataclass(frozen=True)
class BalanceResiduals:
    """The balance residual table: what each order shakes before and after the balancing
    measures.

    Attributes
    ----------
    engine : str
    omega : float
        rad/s.
    orders : ndarray
    force_unbalanced, moment_unbalanced : ndarray
        Largest force (N) / moment (N·m) per order without counterweights or shafts.
    force, moment : ndarray
        The same with the measures (the residuals).
    force_forward, force_backward, moment_forward, moment_backward : ndarray
        Rotating components of the residuals.
    force_vertical, force_horizontal, moment_pitch, moment_yaw : ndarray
        Component amplitudes of the residuals.
    measures : tuple of str
        What was fitted.
    counterweights, shafts : tuple
        The fitted elements.
    """

    engine: str
    omega: float
    orders: np.ndarray
    force_unbalanced: np.ndarray
    moment_unbalanced: np.ndarray
    force: np.ndarray
    moment: np.ndarray
    force_forward: np.ndarray
    force_backward: np.ndarray
    moment_forward: np.ndarray
    moment_backward: np.ndarray
    force_vertical: np.ndarray
    force_horizontal: np.ndarray
    moment_pitch: np.ndarray
    moment_yaw: np.ndarray
    measures: tuple = ()
    counterweights: tuple = ()
    shafts: tuple = ()
    round_off_force: float = 0.0
    round_off_moment: float = 0.0

    @property
    def speed_rpm(self) -> float:
        return self.omega * 60 / (2 * np.pi)

    def to_frame(self, *, clean=True):
        """One row per order: forces in N, moments in N·m.

        With ``clean`` (default) values below the round-off level of the sums
        (``round_off_force``, ``round_off_moment``: 1e-11 of the engine's total centrifugal
        force, resp. that times the engine length) are shown as 0.
        """
        import pandas as pd

        def c(values, level):
            values = np.asarray(values, dtype=float)
            return np.where(np.abs(values) < level, 0.0, values) if clean else values

        f, m = self.round_off_force, self.round_off_moment
        return pd.DataFrame({
            "order": self.orders,
            "force_unbalanced_n": c(self.force_unbalanced, f),
            "force_n": c(self.force, f),
            "force_forward_n": c(self.force_forward, f),
            "force_backward_n": c(self.force_backward, f),
            "force_vertical_n": c(self.force_vertical, f),
            "force_horizontal_n": c(self.force_horizontal, f),
            "moment_unbalanced_nm": c(self.moment_unbalanced, m),
            "moment_nm": c(self.moment, m),
            "moment_forward_nm": c(self.moment_forward, m),
            "moment_backward_nm": c(self.moment_backward, m),
            "moment_pitch_nm": c(self.moment_pitch, m),
            "moment_yaw_nm": c(self.moment_yaw, m),
        })

    def plot(self, ax=None):
        """Bars of force and moment per order, before (light) and after (dark); returns the
        figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
        else:
            fig = ax.figure
            axes = [ax, ax.twinx()]
        x = np.arange(self.orders.size)
        for a, before, after, unit, title in (
                (axes[0], self.force_unbalanced, self.force, "N", "force"),
                (axes[1], self.moment_unbalanced, self.moment, "N m", "moment")):
            a.bar(x - 0.2, before, 0.4, color="0.75", label="unbalanced")
            a.bar(x + 0.2, after, 0.4, color="C0", label="residual")
            a.set_xticks(x, [str(o) for o in self.orders])
            a.set_xlabel("order")
            a.set_ylabel(f"{title} ({unit})")
            a.legend()
        fig.suptitle(f"{self.engine}: balance residuals at {self.speed_rpm:.0f} rpm")
        return fig


def balance_residuals(engine, *, omega, orders=(1, 2, 4, 6, 8), balance_factor=None,
                      rotating_fraction=1.0, shaft_orders=(), shaft_positions=None):
    """Balance residual table after counterweights and Lanchester shafts.

    Parameters
    ----------
    engine : Engine
    omega : float
        rad/s.
    orders : sequence of int
    balance_factor : float, optional
        If given, fit per-throw counterweights balancing ``rotating_fraction`` of the rotating
        and ``balance_factor`` of the reciprocating mass.
    rotating_fraction : float
        See :func:`counterweights`.
    shaft_orders : sequence of int
        Orders cancelled by balance shafts (e.g. (1, 2)); designed with
        :func:`lanchester_shafts` after the counterweights.
    shaft_positions : pair of float, optional
        Two planes for the shafts (cancel the moment as well).

    Returns
    -------
    BalanceResiduals

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.04, rod_length=0.14,
    ...            reciprocating_mass=0.5, cylinder_positions=[0, 0.09, 0.18, 0.27])
    >>> res = balance_residuals(e, omega=600.0, orders=(2, 4), shaft_orders=(2,))
    >>> [f"{v:.3g}" for v in res.force_unbalanced], [f"{v:.1e}" for v in res.force]
    (['8.4e+03', '179'], ['0.0e+00', '1.8e+02'])
    """
    omega = _omega(omega)
    orders = _orders(orders)
    measures = []
    cws: tuple = ()
    if balance_factor is not None:
        cws = counterweights(engine, balance_factor=balance_factor,
                             rotating_fraction=rotating_fraction)
        measures.append(f"counterweights: {rotating_fraction:g} of rotating and "
                        f"{balance_factor:g} of reciprocating mass per throw")
    shafts: list = []
    for o in shaft_orders:
        new = lanchester_shafts(engine, order=o, positions=shaft_positions,
                                counterweights=cws if o == 1 else ())
        shafts.extend(new)
        measures.append(f"balance shafts, order {o}: {len(new)} eccentric(s)")
    scale = 1e-11 * float(np.sum(engine.reciprocating_mass + engine.rotating_mass)
                          * engine.crank_radius) * omega**2
    span = max(float(np.ptp(engine.cylinder_positions)), engine.crank_radius)
    before = unbalance(engine, omega=omega, orders=orders)
    after = unbalance(engine, omega=omega, orders=orders, counterweights=cws, shafts=shafts)
    return BalanceResiduals(
        engine=engine.name, omega=omega, orders=orders,
        force_unbalanced=before["force"].values, moment_unbalanced=before["moment"].values,
        force=after["force"].values, moment=after["moment"].values,
        force_forward=after["force_forward"].values,
        force_backward=after["force_backward"].values,
        moment_forward=after["moment_forward"].values,
        moment_backward=after["moment_backward"].values,
        force_vertical=after["force_vertical"].values,
        force_horizontal=after["force_horizontal"].values,
        moment_pitch=after["moment_pitch"].values, moment_yaw=after["moment_yaw"].values,
        measures=tuple(measures) or ("none",), counterweights=tuple(cws), shafts=tuple(shafts),
        round_off_force=scale, round_off_moment=scale * span)
