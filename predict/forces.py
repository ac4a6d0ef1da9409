"""Crank-train forces and turning moment: gas and inertia forces, rod force, side thrust,
tangential and radial crank-pin force, single- and multi-cylinder torque.

Sign conventions: the *piston force* F (gas + reciprocating inertia) is positive towards the
crank (a gas load pushes it down); the rod force is positive in compression; the side thrust is
positive on the cylinder wall on the side the crank pin passes going down (θ = 90°); the
tangential crank-pin force is positive in the direction of rotation (driving), the radial one
positive towards the crank axis.  Torque = tangential force × crank radius, positive driving.

The torque comes from virtual work, T = F · (−dx/dθ), with the exact piston motion, so it holds
for pin offsets and articulated rods alike; for a plain rod it equals the textbook
F r sin(θ + φ)/cos φ (Liang 1948 ch. 5; Applied Mechanics vol. 2 ch. 1 §5).

References
----------
Liang Shoupan, *Engine Dynamics* (1948) ch. 5 (gas pressure and torque, multi-cylinder torque);
*Applied Mechanics* vol. 2 (Engine dynamics), ch. 1 §4-5 (piston thrust, crank-pin tangential
force and turning moment).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_int, check_nonnegative
from .errors import ModelError
from .kinematics import _omega
from .pressure import PressureTrace, as_trace

__all__ = [
    "gas_force",
    "inertia_force",
    "crank_forces",
    "CrankForces",
    "cylinder_torque",
    "engine_torque",
    "torque_harmonics",
]

#: default crankcase (back-side) pressure, Pa
CRANKCASE_PRESSURE = 1.0e5


def _cylinder(engine, cylinder) -> int:
    c = check_int(cylinder, "cylinder", minimum=1, error=ModelError)
    if c > engine.n_cylinders:
        raise ModelError(f"cylinder={c} must be <= {engine.n_cylinders} (1-based)")
    return c - 1


def _traces(engine, pressure):
    """One PressureTrace per cylinder (a single trace is shared by all)."""
    if pressure is None:
        return None
    if isinstance(pressure, (list, tuple)) and len(pressure) == engine.n_cylinders and all(
            isinstance(p, PressureTrace) for p in pressure):
        return [as_trace(p, cycle=engine.cycle) for p in pressure]
    trace = as_trace(pressure, cycle=engine.cycle)
    return [trace] * engine.n_cylinders


def gas_force(engine, crank_angle, pressure, *, crankcase_pressure=CRANKCASE_PRESSURE):
    """Gas force on one piston, (p − p_cc)·A, N, positive towards the crank (double-acting
    cylinders: minus the lower chamber's, see :meth:`Engine.net_gas_force`).

    Parameters
    ----------
    engine : Engine
        Needs ``bore``.
    crank_angle : array_like
        Crank angle from the cylinder's firing TDC, rad.
    pressure : PressureTrace or (angle, pressure) arrays
        Cylinder pressure over one cycle (absolute, Pa).
    crankcase_pressure : float
        Pressure under the piston, Pa.

    Returns
    -------
    ndarray
        N, shape of ``crank_angle``.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.pressure import PressureTrace
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=1.0, bore=0.1)
    >>> tr = PressureTrace.from_measured([0, 1, 2, 3], [5e6, 2e6, 1e5, 1e5])
    >>> round(float(gas_force(e, 0.0, tr)), 1)
    38484.5
    """
    trace = as_trace(pressure, cycle=engine.cycle)
    pcc = check_nonnegative(crankcase_pressure, "crankcase_pressure", error=ModelError)
    ang = check_finite_array(crank_angle, "crank_angle", error=ModelError)
    return engine.net_gas_force(trace, ang, pcc)


def inertia_force(engine, theta, *, omega):
    """Reciprocating inertia force of every cylinder along its axis, N, positive towards the head.

    F = −m_rec · ω² · d²x/dθ² with the exact piston motion (Liang 1948 ch. 1 §1-3, eq. (5)).

    Parameters
    ----------
    engine : Engine
    theta : array_like
        Shaft angle θ, rad (engine convention).
    omega : float
        Crank speed, rad/s.

    Returns
    -------
    ndarray, shape (n_cylinders, len(theta))

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0)
    >>> float(inertia_force(e, [0.0], omega=100.0)[0, 0])  # m r ω² (1 + λ)
    1250.0
    """
    w = _omega(omega)
    _, _, d2x = engine.piston_motion(theta)
    return -engine.reciprocating_mass[:, None] * w * w * d2x


@dataclass(frozen=True)
class CrankForces:
    """Forces in one cylinder's crank train over crank angle (all N, torque N·m).

    Attributes
    ----------
    crank_angle : ndarray
        Crank angle from the cylinder's firing TDC, rad.
    gas, inertia, piston : ndarray
        Gas force, reciprocating inertia force and their sum along the cylinder axis, positive
        towards the crank.
    rod : ndarray
        Rod force, positive in compression.
    side_thrust : ndarray
        Piston side thrust on the cylinder wall.
    tangential, radial : ndarray
        Crank-pin force components (driving; towards the crank axis).
    torque : ndarray
        tangential × crank radius.
    omega : float
        Crank speed, rad/s.
    """

    crank_angle: np.ndarray
    gas: np.ndarray
    inertia: np.ndarray
    piston: np.ndarray
    rod: np.ndarray
    side_thrust: np.ndarray
    tangential: np.ndarray
    radial: np.ndarray
    torque: np.ndarray
    omega: float

    def to_frame(self):
        """Table with one column per force (N) and torque (N·m) against ``crank_angle_deg``."""
        import pandas as pd

        return pd.DataFrame({
            "crank_angle_deg": np.rad2deg(self.crank_angle), "gas_n": self.gas,
            "inertia_n": self.inertia, "piston_n": self.piston, "rod_n": self.rod,
            "side_thrust_n": self.side_thrust, "tangential_n": self.tangential,
            "radial_n": self.radial, "torque_nm": self.torque})

    def plot(self, ax=None):
        """Forces (kN) against crank angle (deg); returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        deg = np.rad2deg(self.crank_angle)
        for name in ("piston", "side_thrust", "tangential", "radial"):
            ax.plot(deg, getattr(self, name) / 1e3, label=name.replace("_", " "))
        ax.set_xlabel("crank angle from firing TDC (deg)")
        ax.set_ylabel("force (kN)")
        ax.legend()
        return fig


def crank_forces(engine, crank_angle, *, omega, pressure=None, cylinder=1,
                 crankcase_pressure=CRANKCASE_PRESSURE):
    """Gas, inertia, rod, side-thrust, tangential and radial forces of one cylinder.

    Parameters
    ----------
    engine : Engine
    crank_angle : array_like
        Crank angle from that cylinder's firing TDC, rad.
    omega : float
        Crank speed, rad/s.
    pressure : PressureTrace or (angle, pressure) arrays, optional
        Cylinder pressure (None: inertia only).
    cylinder : int
        1-based cylinder number (must have a plain rod).
    crankcase_pressure : float
        Pa.

    Returns
    -------
    CrankForces
        Two-point rod model: the residual couple of the rod (``rod_inertia_correction``) is
        not in these forces; :func:`cylinder_torque` includes its torque.

    References
    ----------
    *Applied Mechanics* vol. 2, ch. 1 §4-5; Liang 1948 ch. 5.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0)
    >>> f = crank_forces(e, np.pi / 2, omega=100.0)
    >>> round(float(f.piston), 3), round(float(f.side_thrust), 3), round(float(f.torque), 3)
    (258.199, 66.667, 12.91)
    """
    i = _cylinder(engine, cylinder)
    if engine.articulated[i] is not None:
        raise ModelError(f"cylinder {cylinder} has an articulated rod: its crank-pin forces act "
                         "through the master rod; use cylinder_torque for its torque")
    w = _omega(omega)
    ang = check_finite_array(crank_angle, "crank_angle", error=ModelError)
    flat = ang.reshape(-1)
    theta = engine.shaft_angle(flat) + np.deg2rad(engine.firing_angles_deg()[i])
    x, dx, d2x = (v[i] for v in engine.piston_motion(theta))
    inertia = engine.reciprocating_mass[i] * w * w * d2x           # towards the crank
    gas = np.zeros_like(flat) if pressure is None else gas_force(
        engine, flat, pressure, crankcase_pressure=crankcase_pressure)
    piston = gas + inertia
    r, l, e = engine.crank_radius, engine.rod_length, engine.pin_offset
    psi = theta + np.deg2rad(engine.crank_angles_deg[i] - engine.bank_angles_deg[i])
    s = (r * np.sin(psi) - e) / l
    c = np.sqrt(1 - s * s)
    rod = piston / c
    side = piston * s / c
    tangential = rod * (np.sin(psi) * c + np.cos(psi) * s)
    radial = rod * (np.cos(psi) * c - np.sin(psi) * s)
    torque = piston * (-dx)
    shape = ang.shape

    def rs(v):
        return v.reshape(shape)

    return CrankForces(crank_angle=rs(flat), gas=rs(gas), inertia=rs(inertia), piston=rs(piston),
                       rod=rs(rod), side_thrust=rs(side), tangential=rs(tangential),
                       radial=rs(radial), torque=rs(torque), omega=w)


def cylinder_torque(engine, theta, *, omega, pressure=None, cylinder=1,
                    crankcase_pressure=CRANKCASE_PRESSURE):
    """Single-cylinder tangential (gas + reciprocating inertia) torque, N·m.

    T(θ) = [(p − p_cc) A + m_rec ω² x''(θ)] · (−x'(θ)) − ΔJ ω² φ'(θ) φ''(θ), θ the crank angle
    from this cylinder's firing TDC, x the exact piston position, φ the rod angle and ΔJ the
    engine's ``rod_inertia_correction`` (the residual couple of the two-point rod; 0 by
    default) — virtual work, exact for any rod geometry.

    Parameters
    ----------
    engine : Engine
    theta : array_like
        Crank angle from the cylinder's firing TDC, rad (0..4π covers a 4-stroke cycle).
    omega : float
        Crank speed, rad/s (constant).
    pressure : PressureTrace or (angle, pressure) arrays, optional
        Cylinder pressure; None gives the inertia torque alone.
    cylinder : int
        1-based cylinder (default 1).
    crankcase_pressure : float
        Pa.

    Returns
    -------
    ndarray
        N·m, shape of ``theta``; positive drives the shaft.

    References
    ----------
    Liang 1948 ch. 5 §5-2; Applied Mechanics vol. 2 ch. 1 §5.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0)
    >>> round(float(cylinder_torque(e, np.pi / 2, omega=100.0)), 6)  # m r²ω²·λ/√(1−λ²)
    12.909944
    """
    i = _cylinder(engine, cylinder)
    w = _omega(omega)
    ang = check_finite_array(theta, "theta", error=ModelError)
    flat = ang.reshape(-1)
    shaft = engine.shaft_angle(flat) + np.deg2rad(engine.firing_angles_deg()[i])
    x, dx, d2x = (v[i] for v in engine.piston_motion(shaft))
    force = engine.reciprocating_mass[i] * w * w * d2x
    if pressure is not None:
        force = force + gas_force(engine, flat, pressure, crankcase_pressure=crankcase_pressure)
    out = force * -dx
    if getattr(engine, "rotary", False):
        # rotary engine: the piston also circles the axis at radius x (½ m ω² x² energy)
        out = out - engine.reciprocating_mass[i] * w * w * x * dx
    if engine.rod_inertia_correction[i] != 0.0:
        d1, d2 = (v[i] for v in engine.rod_motion(shaft))
        out = out - engine.rod_inertia_correction[i] * w * w * d1 * d2
    out = out.reshape(ang.shape)
    return float(out) if ang.ndim == 0 else out


def engine_torque(engine, theta, *, omega, pressure=None,
                  crankcase_pressure=CRANKCASE_PRESSURE, per_cylinder=False):
    """Multi-cylinder turning moment (gas + inertia), N·m, for the engine's firing order.

    Parameters
    ----------
    engine : Engine
    theta : array_like
        Crank angle from cylinder 1's firing TDC, rad.
    omega : float
        Crank speed, rad/s.
    pressure : PressureTrace, (angle, pressure) arrays, or list of PressureTrace, optional
        One trace for all cylinders (each shifted by its firing angle) or one per cylinder.
        None: inertia torque only.
    crankcase_pressure : float
        Pa.
    per_cylinder : bool
        Return the (n_cylinders, len(theta)) contributions instead of their sum.

    Returns
    -------
    ndarray
        N·m.

    References
    ----------
    Liang 1948 ch. 5 §5-3 (torque of multi-cylinder engines).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0, 180], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0, firing_order=[1, 2])
    >>> round(float(engine_torque(e, np.pi / 4, omega=100.0)), 4)
    -50.052
    """
    w = _omega(omega)
    ang = check_finite_array(theta, "theta", error=ModelError)
    flat = ang.reshape(-1)
    x, dx, d2x = engine.piston_motion(engine.shaft_angle(flat))
    force = engine.reciprocating_mass[:, None] * w * w * d2x
    traces = _traces(engine, pressure)
    if traces is not None:
        pcc = check_nonnegative(crankcase_pressure, "crankcase_pressure", error=ModelError)
        fire = np.deg2rad(engine.firing_angles_deg())
        for i, tr in enumerate(traces):
            force[i] += engine.net_gas_force(tr, flat - fire[i], pcc)
    parts = force * -dx
    if getattr(engine, "rotary", False):
        parts = parts - engine.reciprocating_mass[:, None] * w * w * x * dx
    corr = engine.rod_inertia_correction
    if np.any(corr != 0.0):
        # residual couple ΔM = ΔJ φ̈ through virtual work: −ΔJ ω² φ' φ''
        d1, d2 = engine.rod_motion(engine.shaft_angle(flat))
        parts = parts - corr[:, None] * w * w * d1 * d2
    if per_cylinder:
        return parts.reshape((engine.n_cylinders,) + ang.shape)
    out = parts.sum(axis=0).reshape(ang.shape)
    return float(out) if ang.ndim == 0 else out


def torque_harmonics(engine, *, omega, pressure=None, cylinder=1, max_order=24,
                     points_per_cycle=None, crankcase_pressure=CRANKCASE_PRESSURE):
    """Harmonic coefficients of one cylinder's torque (orders in steps of 2/cycle).

    T(θ) = T₀ + Σ_ν [a_ν cos νθ + b_ν sin νθ], θ from the cylinder's firing TDC, ν = ½, 1,
    1½, … (4-stroke) or 1, 2, … (2-stroke), from an FFT of the exact torque over one cycle.
    With a sampled pressure the error is set by the trace resolution; for the inertia part the
    FFT is exact to round-off once ``points_per_cycle`` exceeds a few times ``max_order``.

    Returns
    -------
    xarray.Dataset
        Over dim ``order``: ``cos`` and ``sin`` (N·m), ``amplitude`` (N·m, peak), ``phase``
        (rad, T = amplitude·cos(νθ − phase)); attrs ``units``, ``method``, ``points_per_cycle``.

    References
    ----------
    Liang 1948 ch. 7; Zhao, *Engine Design* ch. 3 §4 (harmonic analysis of the exciting torque).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0, cycle=2)
    >>> h = torque_harmonics(e, omega=100.0, max_order=3)
    >>> [round(float(v), 4) for v in h["sin"].sel(order=[1.0, 2.0, 3.0])]
    [3.1753, -25.0065, -9.6028]
    """
    import xarray as xr

    period_orders = engine.cycle // 2                    # samples of order 1 per cycle
    n = points_per_cycle or max(720 * period_orders, 8 * max_order * period_orders)
    n = check_int(n, "points_per_cycle", minimum=16, error=ModelError)
    max_order = check_int(max_order, "max_order", minimum=1, error=ModelError)
    ang = np.arange(n) * engine.cycle_angle / n
    t = cylinder_torque(engine, ang, omega=omega, pressure=pressure, cylinder=cylinder,
                        crankcase_pressure=crankcase_pressure)
    spec = np.fft.rfft(t) / n
    k = np.arange(1, max_order * period_orders + 1)
    if k[-1] >= n // 2:
        raise ModelError(f"points_per_cycle={n} too small for max_order={max_order}")
    orders = k / period_orders
    cos = 2 * spec.real[k]
    sin = -2 * spec.imag[k]
    ds = xr.Dataset(
        {"cos": ("order", cos), "sin": ("order", sin),
         "amplitude": ("order", np.hypot(cos, sin)), "phase": ("order", np.arctan2(sin, cos))},
        coords={"order": orders},
        attrs={"units": "N m", "mean_torque": float(spec.real[0]), "method": "fft",
               "points_per_cycle": n, "cylinder": int(cylinder), "omega": float(omega)})
    ds["phase"].attrs["units"] = "rad"
    return ds
