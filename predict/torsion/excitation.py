"""Exciting torque: harmonic analysis of the cylinder tangential (gas + inertia) torque.

One cylinder's torque on the crankshaft, as a function of its crank angle ψ from firing TDC,
is (plain connecting rod, constant speed ω)

``T(ψ) = −x'(ψ) · (A (p(ψ) − p_cc) + m_rec ω² x''(ψ))``,

with x the piston-pin distance from the crank axis (``Engine.piston_motion``), A the piston
area, p the cylinder pressure and m_rec the reciprocating mass. Its Fourier series over the
working cycle, ``T(ψ) = T₀ + Re Σ_q T_q e^{i q ψ}``, has orders q = 0.5, 1, 1.5, … for a
4-stroke (q = 1, 2, … for a 2-stroke). The gas part does not depend on speed; the inertia part
is ω² times a speed-free series with integer orders only (q ≤ 6 carry practically all of it),
so an :class:`Excitation` stores the two apart: ``T_q(Ω) = G_q + Ω² I_q`` (and a misfiring
cylinder keeps only ``Ω² I_q``).

Fidelity: the harmonics come from the trace sampled at N points per cycle (rectangle rule,
exact for orders below N/2 − q_max of a band-limited trace); the aliasing error is estimated by
comparing with N/2 points and reported in ``error_estimate``.

References
----------
.. [1] 交通大学内燃机教研组, 内燃机动力学、构造与计算 (上册), 1958, 第二篇 第三章
   (单气缸切向力; 干扰力的简谐分析).
.. [2] W. Ker Wilson, *Practical Solution of Torsional Vibration Problems*, vol. 2, 1963,
   ch. 16-17 (harmonic components of the turning moment, vs mean indicated pressure).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crankbench.predict._deprecate import renamed

from .._validate import check_finite_array, check_int, check_positive
from ..errors import ModelError

__all__ = ["Excitation", "tangential_torque", "torque_harmonics", "engine_excitation",
           "harmonic_coefficient_table", "excitation_from_coefficients"]


def tangential_torque(engine, psi, *, omega, pressure, crankcase_pressure=1.0e5):
    """Tangential torque of one cylinder vs its crank angle from firing TDC.

    ``T = −x'(A (p − p_cc) + m_rec ω² x'') − ΔJ ω² φ' φ''`` with cylinder 1's geometry and
    masses (the shared-harmonics path of :func:`engine_excitation`, cylinders alike): the same
    virtual-work torque as :func:`predict.forces.cylinder_torque`, including the residual couple
    of the two-point rod through ``Engine.rod_inertia_correction`` ΔJ (φ the rod angle).

    Parameters
    ----------
    engine : predict.engine.Engine
    psi : array_like
        Crank angle from firing TDC, rad.
    omega : float
        Crankshaft speed, rad/s.
    pressure : array_like
        Absolute cylinder pressure at ``psi``, Pa.
    crankcase_pressure : float
        Pa.

    Returns
    -------
    ndarray
        Torque, N·m (positive drives the shaft).

    Examples
    --------
    >>> import numpy as np
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=0.0, bore=0.1)
    >>> t = tangential_torque(e, [np.pi / 2], omega=100.0, pressure=[2e5])
    >>> print(round(float(t[0]), 3))  # (2e5-1e5)·A·r at 90°
    39.27
    """
    psi = np.asarray(psi, float)
    p = np.broadcast_to(np.asarray(pressure, float), psi.shape)
    if engine.bore is None:
        raise ModelError(f"engine {engine.name!r} has no bore; gas torque needs it")
    theta = psi + engine.firing_tdc_shaft_angle
    _, dx, d2x = engine.piston_motion(theta)
    area = np.pi * engine.bore ** 2 / 4
    m = float(engine.reciprocating_mass[0])
    out = -dx[0] * (area * (p - crankcase_pressure) + m * omega ** 2 * d2x[0])
    corr = float(engine.rod_inertia_correction[0])
    if corr != 0.0:
        d1, d2 = engine.rod_motion(np.ravel(theta))
        out = out - corr * omega ** 2 * (d1[0] * d2[0]).reshape(np.shape(out))
    return out


def _cylinders_alike(engine) -> bool:
    """True when one shared harmonic column describes every cylinder (same masses, rods)."""
    return (not any(a is not None for a in engine.articulated)
            and not getattr(engine, "rotary", False)
            and np.ptp(engine.reciprocating_mass) == 0
            and np.ptp(engine.rod_inertia_correction) == 0)


def _series(values: np.ndarray, psi_period: float, orders: np.ndarray) -> np.ndarray:
    """Complex T_q of samples over one period (rectangle rule): T_q = (2/N) Σ T e^{−iqψ}."""
    n = values.shape[-1]
    psi = np.arange(n) * psi_period / n
    basis = np.exp(-1j * np.outer(psi, orders))
    return values @ basis * (2.0 / n)


def torque_harmonics(engine, *, pressure, orders, omega=0.0, points=None):
    """Harmonic amplitudes T_q (complex, N·m) of one cylinder's tangential torque.

    Parameters
    ----------
    engine : predict.engine.Engine
    pressure : PressureTrace
        Cylinder pressure over one cycle (``predict.pressure``).
    orders : array_like
        Orders q.
    omega : float
        Speed for the inertia part, rad/s (0: gas only).
    points : int, optional
        Samples per cycle (default: the trace's own, at least 720).

    Returns
    -------
    ndarray (n_o,), complex
        ``T(ψ) = T₀ + Re Σ T_q e^{iqψ}``.
    """
    orders = check_finite_array(orders, "orders", ndim=1, min_length=1, error=ModelError)
    period = np.pi * engine.cycle
    n = points or max(720, len(pressure.angle))
    psi = np.arange(n) * period / n
    if getattr(engine, "double_acting", False):
        from ..forces import cylinder_torque

        t = cylinder_torque(engine, psi, omega=omega, pressure=pressure)
    else:
        t = tangential_torque(engine, psi, omega=omega, pressure=pressure.at(psi))
    return _series(t, period, orders)


@dataclass(frozen=True)
class Excitation:
    """Per-cylinder torque harmonics as gas part plus ω² × inertia part.

    Attributes
    ----------
    orders : ndarray (n_o,)
    gas : ndarray (n_o,) or (n_o, z), complex
        Gas-torque harmonics G_q, N·m; one column per cylinder when the cylinders' kinematics
        differ (articulated rods of a radial row, rotary engines) or each cylinder's pressure
        was measured (:func:`predict.gas_torque.excitation_from_pressure`), each cylinder's
        own harmonics about its own firing TDC.
    inertia : ndarray (n_o,) or (n_o, z), complex
        Inertia-torque harmonics per unit ω², N·m·s² (``T_q = G_q + Ω² I_q``).
    n_cylinders : int
    source : str
        What the harmonics came from.
    error_estimate : float
        Relative aliasing/quadrature error of the harmonics (largest order).
    """

    orders: np.ndarray
    gas: np.ndarray
    inertia: np.ndarray
    n_cylinders: int
    source: str
    error_estimate: float = 0.0

    def describe(self) -> str:
        return self.source

    @renamed(speed="omega")
    def harmonics(self, omega, orders, *, misfire=None) -> np.ndarray:
        """Per-cylinder harmonics at each speed: (n_s, n_o, z) complex, N·m.

        Parameters
        ----------
        omega : array_like
            Crankshaft speeds, rad/s.
        orders : array_like
            Must be a subset of ``self.orders``.
        misfire : int, optional
            Cylinder number (1-based) whose gas torque is missing.
        """
        omega = np.atleast_1d(np.asarray(omega, float))
        orders = np.atleast_1d(np.asarray(orders, float))
        idx = []
        for q in orders:
            hit = np.flatnonzero(np.isclose(self.orders, q))
            if hit.size == 0:
                raise ModelError(f"order {q:g} is not in the excitation (orders "
                                 f"{self.orders.min():g}..{self.orders.max():g})")
            idx.append(hit[0])
        g, i = self.gas[idx], self.inertia[idx]
        if g.ndim == 2:      # per cylinder (articulated rods, rotary engines, measured pressure)
            i = i if i.ndim == 2 else np.repeat(i[:, None], self.n_cylinders, axis=1)
            out = g[None] + (omega ** 2)[:, None, None] * i[None]
        else:
            out = g[None, :, None] + (omega ** 2)[:, None, None] * i[None, :, None]
            out = np.repeat(out, self.n_cylinders, axis=2)
            g = np.repeat(g[:, None], self.n_cylinders, axis=1)
        if misfire is not None:
            c = check_int(misfire, "misfire", minimum=1, error=ModelError)
            if c > self.n_cylinders:
                raise ModelError(f"misfire={c} but the engine has {self.n_cylinders} cylinders")
            out[:, :, c - 1] -= g[None, :, c - 1]
        return out

    def to_frame(self):
        """Orders with |G_q|, |I_q| and phases (deg) (cylinder 1's when per cylinder)."""
        import pandas as pd

        g = self.gas if self.gas.ndim == 1 else self.gas[:, 0]
        i = self.inertia if self.inertia.ndim == 1 else self.inertia[:, 0]
        return pd.DataFrame({"order": self.orders, "gas_nm": np.abs(g),
                             "gas_phase_deg": np.rad2deg(np.angle(g)),
                             "inertia_nm_s2": np.abs(i),
                             "inertia_phase_deg": np.rad2deg(np.angle(i))})

    def plot(self, ax=None, *, speed_rpm=None):
        """Bar chart of |T_q| (gas, and total at ``speed_rpm``); returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 3.5))
        else:
            fig = ax.figure
        g = self.gas if self.gas.ndim == 1 else self.gas[:, 0]
        i = self.inertia if self.inertia.ndim == 1 else self.inertia[:, 0]
        ax.bar(self.orders - 0.1, np.abs(g), width=0.2, label="gas")
        if speed_rpm is not None:
            w = speed_rpm * np.pi / 30
            ax.bar(self.orders + 0.1, np.abs(g + w * w * i), width=0.2,
                   label=f"gas + inertia at {speed_rpm:g} rpm")
        ax.set_xlabel("order")
        ax.set_ylabel("|T_q| [N m]")
        ax.legend()
        fig.tight_layout()
        return fig


def engine_excitation(system_or_engine, *, imep=None, pressure=None, orders=None,
                      points=1440) -> Excitation:
    """Excitation of an engine from a pressure trace (given, or the synthetic Wiebe model).

    Parameters
    ----------
    system_or_engine : TorsionalSystem or Engine
    imep : float, optional
        Mean indicated pressure, Pa, for the synthetic trace (default: the engine's
        ``[engine.combustion]`` load).
    pressure : PressureTrace, optional
        Measured or synthetic trace; overrides ``imep``.
    orders : array_like, optional
        Default 0.5..24 (4-stroke) or 1..24 (2-stroke).
    points : int
        Samples per cycle (fidelity); the error estimate compares with ``points // 2``.

    Returns
    -------
    Excitation

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.045, rod_length=0.15,
    ...            reciprocating_mass=0.6, bore=0.085, compression_ratio=10.0,
    ...            firing_order=[1, 3, 4, 2])
    >>> x = engine_excitation(e, imep=1.0e6)
    >>> print(x.orders[:3], x.n_cylinders)
    [0.5 1.  1.5] 4
    """
    engine = getattr(system_or_engine, "engine", system_or_engine)
    if engine is None or not hasattr(engine, "piston_motion"):
        raise ModelError("the torsional system has no engine attached; give torque harmonics "
                         "or build the system with an engine (from_toml with [shaftline] engine)")
    points = check_int(points, "points", minimum=64, error=ModelError)
    step = 0.5 if engine.cycle == 4 else 1.0
    orders = np.arange(step, 24 + step / 2, step) if orders is None else check_finite_array(
        orders, "orders", ndim=1, min_length=1, error=ModelError)
    if pressure is None:
        from ..pressure import synthetic_pressure

        if imep is not None:
            check_positive(imep, "imep", error=ModelError)
            pressure = synthetic_pressure(engine, imep=imep)
        else:
            pressure = synthetic_pressure(engine)
        source = (f"synthetic Wiebe pressure (predict.pressure), imep "
                  f"{pressure.imep(engine) / 1e5:.3g} bar")
    else:
        source = "given pressure trace"
    if not _cylinders_alike(engine):
        return _per_cylinder_excitation(engine, pressure, np.asarray(orders, float), points,
                                        source)
    gas = torque_harmonics(engine, pressure=pressure, orders=orders, omega=0.0, points=points)
    coarse = torque_harmonics(engine, pressure=pressure, orders=orders, omega=0.0,
                              points=points // 2)
    unit = torque_harmonics(engine, pressure=pressure, orders=orders, omega=1.0, points=points)
    inertia = unit - gas
    # the inertia torque repeats every revolution: its half orders vanish exactly
    inertia[~np.isclose(orders, np.round(orders))] = 0.0
    scale = np.abs(gas).max() or 1.0
    err = float(np.abs(gas - coarse).max() / scale)
    return Excitation(orders=np.asarray(orders, float), gas=gas, inertia=inertia,
                      n_cylinders=engine.n_cylinders, source=source, error_estimate=err)


def _per_cylinder_excitation(engine, pressure, orders, points, source):
    """Exact per-cylinder harmonics from :func:`predict.forces.cylinder_torque` (virtual work
    with each cylinder's own piston motion: articulated rods of radial engines, the rotary
    engine's extra inertia torque)."""
    from ..forces import cylinder_torque

    period = engine.cycle_angle
    z = engine.n_cylinders
    gas = np.empty((orders.size, z), complex)
    inertia = np.empty((orders.size, z), complex)
    coarse = np.empty((orders.size, z), complex)
    integer = np.isclose(orders, np.round(orders))
    for c in range(z):
        for n, target in ((points, gas), (points // 2, coarse)):
            psi = np.arange(n) * period / n
            t = cylinder_torque(engine, psi, omega=0.0, pressure=pressure, cylinder=c + 1)
            target[:, c] = _series(t, period, orders)
        psi = np.arange(points) * period / points
        unit = cylinder_torque(engine, psi, omega=1.0, cylinder=c + 1)
        inertia[:, c] = np.where(integer, _series(unit, period, orders), 0.0)
    scale = np.abs(gas).max() or 1.0
    err = float(np.abs(gas - coarse).max() / scale)
    kind = ("rotary engine" if getattr(engine, "rotary", False) else "articulated rods"
            if any(a is not None for a in engine.articulated) else "cylinders' masses differ")
    return Excitation(orders=orders, gas=gas, inertia=inertia, n_cylinders=z,
                      source=f"{source}; per-cylinder exact kinematics ({kind})",
                      error_estimate=err)


def harmonic_coefficient_table(engine, imep_values, *, orders=None):
    """Gas tangential-pressure harmonic coefficients vs mean indicated pressure.

    Own model, clearly labelled: each row is the synthetic single-zone Wiebe trace of
    :func:`predict.pressure.synthetic_pressure` at that IMEP, analysed like a measured indicator
    diagram. Coefficients are |G_q| / (A r), Pa (the classical "tangential pressure" form of
    Ker Wilson's and the 1958 text's tables), so they can be compared with published tables.

    Parameters
    ----------
    engine : Engine
    imep_values : array_like
        Mean indicated pressures, Pa.
    orders : array_like, optional

    Returns
    -------
    pandas.DataFrame
        Index imep (Pa), one column per order.
    """
    import pandas as pd

    imeps = check_finite_array(imep_values, "imep_values", ndim=1, min_length=1,
                               error=ModelError)
    area_r = np.pi * engine.bore ** 2 / 4 * engine.crank_radius
    rows = {}
    for p in imeps:
        x = engine_excitation(engine, imep=float(p), orders=orders)
        rows[float(p)] = np.abs(x.gas) / area_r
    frame = pd.DataFrame.from_dict(rows, orient="index", columns=[f"{q:g}" for q in x.orders])
    frame.index.name = "imep_pa"
    frame.attrs["model"] = "own: synthetic Wiebe single-zone trace (predict.pressure)"
    return frame


def excitation_from_coefficients(engine, *, orders, imep_values, coefficients, imep,
                                 phases_deg=None, source="user table") -> Excitation:
    """Excitation from a table of tangential-pressure harmonic coefficients vs IMEP.

    Published tables (e.g. Ker Wilson vol. 2, or the engine maker's) give |G_q|/(A r) in Pa
    against mean indicated pressure; the gas harmonic at ``imep`` is interpolated linearly in
    IMEP and multiplied by A·r. The inertia part comes from the engine's reciprocating mass.
    Without ``phases_deg`` the gas harmonics are taken in phase (0°): per-order amplitudes and
    vector sums are right, the cycle superposition of several orders is then only indicative.

    Parameters
    ----------
    engine : Engine
    orders : array_like (n_o,)
    imep_values : array_like (n_p,)
        Ascending IMEP of the table rows, Pa.
    coefficients : array_like (n_p, n_o)
        Tangential-pressure coefficients, Pa.
    imep : float
        Operating IMEP, Pa.
    phases_deg : array_like (n_o,), optional
        Phase of each gas harmonic, deg (``T(ψ) = Re Σ G_q e^{iqψ}``).
    source : str
        Citation of the table.

    Returns
    -------
    Excitation
    """
    orders = check_finite_array(orders, "orders", ndim=1, min_length=1, error=ModelError)
    p = check_finite_array(imep_values, "imep_values", ndim=1, min_length=1, error=ModelError)
    c = check_finite_array(coefficients, "coefficients", ndim=2, error=ModelError)
    if c.shape != (p.size, orders.size):
        raise ModelError(f"coefficients have shape {c.shape}, expected (len(imep_values), "
                         f"len(orders)) = ({p.size}, {orders.size})")
    if p.size > 1 and np.any(np.diff(p) <= 0):
        raise ModelError("imep_values must be strictly ascending")
    imep = check_positive(imep, "imep", error=ModelError)
    if engine.bore is None:
        raise ModelError(f"engine {engine.name!r} has no bore; the coefficients need A·r")
    area_r = np.pi * engine.bore ** 2 / 4 * engine.crank_radius
    mag = np.array([np.interp(imep, p, c[:, i]) for i in range(orders.size)]) * area_r
    ph = np.zeros(orders.size) if phases_deg is None else np.deg2rad(check_finite_array(
        phases_deg, "phases_deg", ndim=1, error=ModelError))
    gas = mag * np.exp(1j * ph)
    n = 1440
    period = np.pi * engine.cycle
    psi = np.arange(n) * period / n
    # no gas force (cylinder = crankcase pressure): the inertia torque at ω = 1 rad/s
    unit = _series(tangential_torque(engine, psi, omega=1.0, pressure=1.0e5,
                                     crankcase_pressure=1.0e5), period, orders)
    inertia = np.where(np.isclose(orders, np.round(orders)), unit, 0.0)
    return Excitation(orders=np.asarray(orders, float), gas=gas, inertia=inertia,
                      n_cylinders=engine.n_cylinders,
                      source=f"{source}, imep {imep / 1e5:.3g} bar"
                             + ("" if phases_deg is not None else " (phases assumed 0)"))

