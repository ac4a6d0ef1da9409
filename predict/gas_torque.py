"""Excitation from measured cylinder pressure: gas-torque harmonics beside the model's inertia.

The torsional forced response (:func:`predict.torsion.forced.forced_response`) and the block
on its mounts (:class:`predict.mounts.MountedEngine`) are driven by the cylinder torque
``T(ψ) = −x'(ψ) (A (p(ψ) − p_cc) + m_rec ω² x''(ψ))``. The parametric model takes ``p`` from
the Wiebe trace of :mod:`predict.pressure`; here ``p`` is a *measured* trace (an averaged
indicator diagram) and only the reciprocating inertia comes from the model, so a disagreement
between measured and predicted response points at the dynamic model, not at an assumed
pressure curve.

* :func:`excitation_from_pressure` — an :class:`~predict.torsion.excitation.Excitation` from one
  trace per measured cylinder. Cylinders without a trace get the mean harmonics of the measured
  ones (each in its own crank angle, i.e. delayed by its firing angle when placed on the
  shaft); with one measured cylinder that is the usual assumption of equal cylinders, stated
  in ``Excitation.source``.
* :func:`torque_reaction` — the gas part of the roll moment on the block at given speeds
  (per speed for a :class:`SpeedExcitation` measured on a run-up).
* :func:`mount_excitation` — the force and moment phasors on the engine block for one order
  (:func:`predict.mounts.block_excitation` fed with the measured excitation: the free forces
  and moments plus the reaction to the crankshaft torque, a roll moment), ready for
  :meth:`predict.mounts.MountedEngine.response`; :func:`mount_response` gives the motion of
  points on the block over speed and order from it.

The harmonics use the same quadrature as :func:`predict.torsion.excitation.engine_excitation`
(rectangle rule over one cycle, ``points`` samples; aliasing error estimated with half as many
points), so the model's own pressure fed through here gives the model's harmonics exactly.

References
----------
交通大学内燃机教研组, 内燃机动力学、构造与计算 (上册), 1958, 第二篇 第三章 (harmonic analysis of
the tangential force from an indicator diagram); Liang 1948 ch. 4 (reaction of the torque on
the foundation) and ch. 5 §5-3 (multi-cylinder torque).
"""

from __future__ import annotations

import numpy as np

from ._validate import check_finite_array, check_int
from .errors import ModelError
from dataclasses import dataclass

from .pressure import PressureTrace, as_trace
from .torsion.excitation import Excitation, torque_harmonics

__all__ = ["excitation_from_pressure", "mount_excitation", "mount_response", "SpeedExcitation",
           "torque_reaction"]


def _traces_by_cylinder(engine, pressure) -> dict:
    z = engine.n_cylinders
    if isinstance(pressure, dict):
        out = {}
        for c, tr in pressure.items():
            c = check_int(c, "cylinder", minimum=1, error=ModelError)
            if c > z:
                raise ModelError(f"pressure given for cylinder {c}, but the engine "
                                 f"{engine.name!r} has {z} cylinder(s)")
            out[c] = as_trace(tr, cycle=engine.cycle)
        if not out:
            raise ModelError("pressure: no cylinder traces given")
        return out
    if isinstance(pressure, (list, tuple)) and pressure and all(
            isinstance(p, PressureTrace) for p in pressure):
        if len(pressure) != z:
            raise ModelError(f"{len(pressure)} pressure traces given for an engine with {z} "
                             "cylinders; pass a dict {cylinder: trace} for some cylinders")
        return {i + 1: as_trace(p, cycle=engine.cycle) for i, p in enumerate(pressure)}
    return {1: as_trace(pressure, cycle=engine.cycle)}


@dataclass(frozen=True)
class SpeedExcitation:
    """Cylinder torque harmonics whose gas part was measured at several speeds.

    A run-up with cylinder pressure gives the gas torque at each speed it passed; this object
    holds it per speed bin and interpolates linearly between the bins (holding the end bins
    outside the measured range), with the model's inertia torque added: ``T_q(Ω) = G_q(Ω) +
    Ω² I_q``. It is used wherever an :class:`~predict.torsion.excitation.Excitation` is (its
    ``harmonics`` has the same signature); the gas part is already at the measured load, so no
    load law applies (``speed_dependent`` is True).

    Attributes
    ----------
    speed_rpm : ndarray (n_b,)
        Bin centres, rpm, ascending.
    orders : ndarray (n_o,)
    gas : ndarray (n_b, n_o, n_cylinders), complex
        Gas-torque harmonics per bin, N·m, in each cylinder's own crank angle.
    inertia : ndarray (n_o,), complex
        Inertia harmonics per unit Ω², N·m·s².
    n_cylinders : int
    source : str
    cycles : ndarray (n_b,)
        Cycles averaged in each bin.
    """

    speed_rpm: np.ndarray
    orders: np.ndarray
    gas: np.ndarray
    inertia: np.ndarray
    n_cylinders: int
    source: str
    cycles: np.ndarray
    speed_dependent: bool = True

    def describe(self) -> str:
        return self.source

    def harmonics(self, omega, orders, *, misfire=None) -> np.ndarray:
        """Per-cylinder harmonics at each speed: (n_s, n_o, z) complex, N·m.

        Examples
        --------
        >>> x = SpeedExcitation(speed_rpm=np.array([1000.0, 2000.0]), orders=np.array([1.0]),
        ...                     gas=np.array([[[10.0]], [[20.0]]]), inertia=np.array([0.0]),
        ...                     n_cylinders=1, source="two bins", cycles=np.array([5, 5]))
        >>> x.harmonics([1500 * np.pi / 30, 3000 * np.pi / 30], [1.0])[:, 0, 0].real.tolist()
        [15.0, 20.0]
        """
        omega = np.atleast_1d(np.asarray(omega, float))
        idx = []
        for q in np.atleast_1d(np.asarray(orders, float)):
            hit = np.flatnonzero(np.isclose(self.orders, q))
            if hit.size == 0:
                raise ModelError(f"order {q:g} is not in the measured excitation (orders "
                                 f"{self.orders.min():g}..{self.orders.max():g})")
            idx.append(hit[0])
        rpm = omega * 30.0 / np.pi
        g = self.gas[:, idx, :]
        if self.speed_rpm.size == 1:
            gs = np.repeat(g, rpm.size, axis=0)
        else:
            u = np.interp(rpm, self.speed_rpm, np.arange(self.speed_rpm.size, dtype=float))
            j = np.minimum(u.astype(int), self.speed_rpm.size - 2)
            w = (u - j)[:, None, None]
            gs = (1 - w) * g[j] + w * g[j + 1]
        out = gs + (omega ** 2)[:, None, None] * self.inertia[idx][None, :, None]
        if misfire is not None:
            c = check_int(misfire, "misfire", minimum=1, error=ModelError)
            if c > self.n_cylinders:
                raise ModelError(f"misfire={c} but the engine has {self.n_cylinders} cylinders")
            out[:, :, c - 1] -= gs[:, :, c - 1]
        return out

    def to_frame(self):
        """|G_q| of the cylinders' mean per bin and order: columns ``speed_rpm``, ``order``,
        ``gas_nm``, ``cycles``."""
        import pandas as pd

        g = np.abs(self.gas.mean(axis=2))
        return pd.DataFrame({"speed_rpm": np.repeat(self.speed_rpm, self.orders.size),
                             "order": np.tile(self.orders, self.speed_rpm.size),
                             "gas_nm": g.ravel(),
                             "cycles": np.repeat(self.cycles, self.orders.size)})

    def plot(self, ax=None):
        """|G_q| against speed for the strongest orders; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 3.5)) if ax is None else (ax.figure, ax)
        g = np.abs(self.gas.mean(axis=2))
        for k in np.argsort(-g.max(axis=0))[:6]:
            ax.plot(self.speed_rpm, g[:, k], "o-", ms=3, label=f"order {self.orders[k]:g}")
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel("|gas torque harmonic| (N m)")
        ax.legend(fontsize=8)
        return fig


def excitation_from_pressure(engine, pressure, *, orders=None, points=1440,
                             source="measured pressure") -> Excitation:
    """Cylinder torque harmonics from measured pressure and the model's inertia torque.

    Parameters
    ----------
    engine : predict.engine.Engine
        Geometry (bore, crank radius, rod) and reciprocating mass; cylinder 1's geometry is
        used for every cylinder, as in :func:`~predict.torsion.excitation.engine_excitation`.
    pressure : PressureTrace, (angle, pressure) pair, list of PressureTrace or dict
        One cycle of absolute pressure against crank angle from that cylinder's firing TDC:
        one trace (cylinder 1, taken for every cylinder), one per cylinder (a list), or
        ``{cylinder: trace}`` for the measured ones (the others get their mean).
    orders : array_like, optional
        Default 0.5..24 (4-stroke) or 1..24 (2-stroke).
    points : int
        Samples per cycle of the quadrature (fidelity; the error estimate compares with half).
    source : str
        What the traces are (goes into ``Excitation.source``).

    Returns
    -------
    Excitation
        ``gas`` of shape (n_o,) when one trace serves all cylinders, else (n_o, n_cylinders).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.pressure import synthetic_pressure
    >>> from crankbench.predict.torsion.excitation import engine_excitation
    >>> e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.045, rod_length=0.15,
    ...            reciprocating_mass=0.6, bore=0.085, compression_ratio=10.0,
    ...            firing_order=[1, 3, 4, 2])
    >>> tr = synthetic_pressure(e, imep=1.0e6)
    >>> x = excitation_from_pressure(e, {1: tr})
    >>> ref = engine_excitation(e, imep=1.0e6)
    >>> x.gas.shape                       # measured cylinder 1, the others its mean (stated)
    (48, 4)
    >>> print(round(float(abs(x.gas[1, 3])), 3), round(float(abs(ref.gas[1])), 3))
    94.756 94.756
    """
    points = check_int(points, "points", minimum=64, error=ModelError)
    step = 0.5 if engine.cycle == 4 else 1.0
    orders = np.arange(step, 24 + step / 2, step) if orders is None else check_finite_array(
        orders, "orders", ndim=1, min_length=1, error=ModelError)
    traces = _traces_by_cylinder(engine, pressure)
    gas = {c: torque_harmonics(engine, pressure=tr, orders=orders, omega=0.0, points=points)
           for c, tr in traces.items()}
    coarse = {c: torque_harmonics(engine, pressure=tr, orders=orders, omega=0.0,
                                  points=points // 2) for c, tr in traces.items()}
    first = next(iter(traces.values()))
    unit = torque_harmonics(engine, pressure=first, orders=orders, omega=1.0, points=points)
    inertia = unit - gas[next(iter(traces))]
    inertia[~np.isclose(orders, np.round(orders))] = 0.0
    z = engine.n_cylinders
    measured = sorted(traces)
    missing = [c for c in range(1, z + 1) if c not in traces]
    if len(traces) == 1 and not isinstance(pressure, dict) or z == 1:
        g = gas[measured[0]]
        how = f"{source} of cylinder {measured[0]}"
        if z > 1:
            how += f", taken for all {z} with their firing offsets (assumption: equal cylinders)"
    else:
        mean = np.mean([gas[c] for c in measured], axis=0)
        g = np.stack([gas.get(c, mean) for c in range(1, z + 1)], axis=1)
        how = f"{source} of cylinder(s) {', '.join(map(str, measured))}"
        if missing:
            how += (f"; cylinder(s) {', '.join(map(str, missing))} not measured: the mean of "
                    "the measured ones with their firing offsets (assumption)")
    scale = max(np.abs(v).max() for v in gas.values()) or 1.0
    err = float(max(np.abs(gas[c] - coarse[c]).max() for c in gas) / scale)
    return Excitation(orders=np.asarray(orders, float), gas=g, inertia=inertia,
                      n_cylinders=z, source=how + "; inertia torque from the model",
                      error_estimate=err)


def mount_excitation(engine, excitation, *, order, omega, load=1.0):
    """Force and moment phasors on the engine block for one order (balance + torque reaction).

    Parameters
    ----------
    engine : predict.engine.Engine
    excitation : Excitation
        Cylinder torque harmonics (measured or modelled); must contain ``order``.
    order : float
        Order (multiple of the crankshaft speed).
    omega : float
        Crankshaft speed, rad/s.
    load : float
        Factor on the gas part (1: the excitation as given).

    Returns
    -------
    dict
        ``force`` (3,) complex N and ``moment`` (3,) complex N·m about ``point`` in the mount
        frame (x along the crankshaft, y horizontal, z up: :mod:`predict.mounts`), ``point``
        (m), ``freq_hz``; the real signal is ``Re(amplitude · e^{i q ω t})`` with the crank
        angle of cylinder 1 from its firing TDC ``ψ = ω t``. The roll moment on the block is
        the reaction to the crankshaft torque (gas pressure on the head, side force on the
        liner): ``+T`` about x, since the shaft turns about −x in the mount frame (the same
        convention as the synthetic bench, :mod:`measure.synth.vibrograph`).

    References
    ----------
    Liang 1948 ch. 4 (reaction of the torque on the frame).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.torsion.excitation import engine_excitation
    >>> e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.045, rod_length=0.15,
    ...            reciprocating_mass=0.6, bore=0.085, compression_ratio=10.0,
    ...            firing_order=[1, 3, 4, 2])
    >>> x = engine_excitation(e, imep=1.0e6, orders=[0.5, 1.0, 2.0])
    >>> m = mount_excitation(e, x, order=2.0, omega=300.0)
    >>> round(float(abs(m["moment"][0])), 1), round(float(abs(m["force"][2])), 1)
    (91.2, 2984.5)
    """
    from .mounts import block_excitation

    w = float(omega)
    if not np.isfinite(w) or w <= 0:
        raise ModelError(f"omega={omega!r} must be > 0 (rad/s)")
    q = float(order)
    # the block model's loads (predict.mounts.block_excitation: free forces and moments of any
    # layout and the torque reaction) with this excitation
    block = block_excitation(engine, [q], excitation=excitation)
    loads = block.at(np.array([w]), load=float(load))[0, 0]
    if getattr(excitation, "speed_dependent", False):      # the gas roll measured at this speed
        loads[3] += float(load) * (torque_reaction(engine, excitation, [q], [w])[0, 0]
                                   - block.gas[0, 3])
    return {"force": loads[:3].copy(), "moment": loads[3:].copy(),
            "point": np.asarray(block.point, float), "freq_hz": q * w / (2 * np.pi)}


def torque_reaction(engine, excitation, orders, omega) -> np.ndarray:
    """Gas part of the roll moment on the engine block per speed and order, N·m.

    The reaction to the crankshaft's gas torque, ``M_x = Σ_c G_q,c e^{−i q φ_c}`` (``φ_c`` the
    firing angle of cylinder c), about +x in the mount frame, the convention of
    :func:`predict.mounts.block_excitation`; for a :class:`SpeedExcitation` the gas harmonics
    are those measured at each speed, for an :class:`~predict.torsion.excitation.Excitation`
    the same at every speed (a load law applies outside).

    Parameters
    ----------
    engine : predict.engine.Engine
    excitation : Excitation or SpeedExcitation
    orders : array_like
        Orders, each in the excitation.
    omega : array_like
        Crankshaft speeds, rad/s (>= 0).

    Returns
    -------
    ndarray (n_s, n_o), complex

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.mounts import block_excitation
    >>> from crankbench.predict.torsion.excitation import engine_excitation
    >>> e = Engine.from_toml("sample_data/engines/i4.toml")
    >>> x = engine_excitation(e, imep=1.0e6, orders=[2.0, 4.0])
    >>> m = torque_reaction(e, x, [2.0, 4.0], [300.0])
    >>> bool(np.allclose(m[0], block_excitation(e, [2.0, 4.0], excitation=x).gas[:, 3]))
    True
    """
    orders = check_finite_array(orders, "orders", ndim=1, min_length=1, error=ModelError)
    w = np.atleast_1d(check_finite_array(omega, "omega", error=ModelError))
    if np.any(w < 0):
        raise ModelError("omega must be >= 0 (rad/s)")
    unit = excitation.harmonics(np.ones(1), orders)[0] - excitation.harmonics(np.zeros(1),
                                                                              orders)[0]
    gas = excitation.harmonics(w, orders) - (w**2)[:, None, None] * unit[None]
    phase = np.exp(-1j * np.deg2rad(np.outer(orders, engine.firing_angles_deg())))
    return (gas * phase[None]).sum(axis=2)


def mount_response(mounted, engine, excitation, *, speed_rpm, orders, points, load=1.0):
    """Motion of points on the block on its mounts, per speed and order (quasi-steady).

    Parameters
    ----------
    mounted : predict.mounts.MountedEngine
    engine : predict.engine.Engine
    excitation : Excitation
        Measured (:func:`excitation_from_pressure`) or modelled cylinder torque harmonics.
    speed_rpm : array_like
        Crankshaft speeds, rpm (> 0).
    orders : array_like
        Orders (each in ``excitation.orders``).
    points : array_like (n_p, 3)
        Points on the block, m (mount frame).
    load : float or array_like
        Factor on the gas part, scalar or one per speed.

    Returns
    -------
    ndarray (n_s, n_o, n_p, 3), complex
        Displacement phasors, m: the motion is ``Re(u e^{i q ψ})``, ψ the crank angle of
        cylinder 1 from its firing TDC (velocity ``i q ω u``, acceleration ``−(q ω)² u``).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.mounts import MountedEngine
    >>> from crankbench.predict.pressure import synthetic_pressure
    >>> e = Engine.from_toml("sample_data/engines/i4.toml")
    >>> m = MountedEngine.from_toml("sample_data/engines/i4.toml")
    >>> x = excitation_from_pressure(e, synthetic_pressure(e, imep=1.0e6), orders=[2.0])
    >>> u = mount_response(m, e, x, speed_rpm=[3000.0], orders=[2.0], points=[[0.2, 0, 0]])
    >>> round(float(abs(u[0, 0, 0, 2]) * 1e6), 3)     # vertical, µm
    51.507
    """
    speed = check_finite_array(speed_rpm, "speed_rpm", ndim=1, min_length=1,
                               error=ModelError)
    if np.any(speed <= 0):
        raise ModelError("speed_rpm must be > 0")
    orders = check_finite_array(orders, "orders", ndim=1, min_length=1, error=ModelError)
    pts = np.atleast_2d(check_finite_array(points, "points", error=ModelError))
    loads = np.broadcast_to(np.asarray(load, float), speed.shape)
    omega = speed * np.pi / 30.0
    out = np.empty((speed.size, orders.size, pts.shape[0], 3), complex)
    for k, q in enumerate(orders):
        ex = [mount_excitation(engine, excitation, order=q, omega=w, load=f)
              for w, f in zip(omega, loads)]
        r = mounted.response(np.array([e["force"] for e in ex]),
                             np.array([e["moment"] for e in ex]),
                             np.array([e["freq_hz"] for e in ex]), point=ex[0]["point"],
                             at=pts)
        out[:, k] = r.displacement
    return out
