"""Forced response of a shaft line carrying a non-linear Lanchester friction damper.

The shaft line without the ring is linear; the ring (:class:`~.friction.FrictionDamper` on a
hub node at crankshaft speed) exerts the first harmonic of its exact stick-slip torque,
``−Z(a)·θ_hub`` with Z of :func:`~.friction.friction_dynamic_stiffness` at the hub amplitude a.
For each order q and speed the hub amplitude solves the scalar harmonic balance
``a |1 + g Z(a)| = |x_F|`` (x_F the linear line's hub response to the cylinder torques, g its
driving-point receptance at the hub) and every node follows as ``x = x_F − g_col Z θ_hub``.

Each order is balanced alone: the friction torque of a real multi-order motion is not the
sum of its single-order describing functions, so the cycle superposition of the orders is an
approximation (exact when one order dominates, which is the resonance case the damper is for).
Its single-order accuracy against time integration of the full non-linear equations is a few
per cent at the resonance peak (tests/literature/test_dampers.py, the ``textbook`` bench).

References
----------
.. [1] J. P. Den Hartog, *Mechanical Vibrations*, 4th ed., 1956, §8.6 (Lanchester damper).
.. [2] A. Gelb, W. E. Vander Velde, *Multiple-Input Describing Functions and Nonlinear System
   Design*, McGraw-Hill, 1968, ch. 2 (sinusoidal-input describing function).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from .forced import (SAMPLES_PER_PERIOD, ForcedResponse, check_speeds_orders, cylinder_forcing,
                     cylinder_harmonics, harmonic_solve, response_from_angles)
from .friction import _balance, _state

__all__ = ["FrictionForcedResponse", "friction_forced_response"]

log = logging.getLogger("crankbench")


@dataclass(frozen=True)
class FrictionForcedResponse:
    """Forced response of a shaft line with a friction damper, per order and speed.

    Attributes
    ----------
    forced : ForcedResponse
        Node angles, section torques and stresses with the ring's harmonic-balance torque,
        orders superposed over the cycle (see the module note on superposition).
    damper : str
        Name of the friction ring.
    node : str
        Its hub node.
    hub_amplitude : ndarray (n_s, n_o)
        Hub angle amplitude per order, rad.
    state : ndarray (n_s, n_o) of str
        "slip", "stick-slip" or "stick".
    energy_per_cycle : ndarray (n_s, n_o)
        Energy the ring dissipates per vibration cycle of that order, J.
    multiple_solutions : ndarray (n_s, n_o) of bool
        Several harmonic-balance amplitudes (the largest is kept).
    """

    forced: ForcedResponse
    damper: str
    node: str
    hub_amplitude: np.ndarray
    state: np.ndarray
    energy_per_cycle: np.ndarray
    multiple_solutions: np.ndarray

    def peaks(self):
        """Per order: the speed of the largest hub amplitude, that amplitude (deg), the ring's
        state and energy per cycle there, and the largest section stress of the order (MPa)."""
        import pandas as pd

        f = self.forced
        i = np.argmax(self.hub_amplitude, axis=0)
        cols = np.arange(f.orders.size)
        stress = np.nanmax(np.where(np.isfinite(f.stress), f.stress, -np.inf), axis=(0, 2))
        return pd.DataFrame({
            "order": f.orders, "speed_rpm": f.speed_rpm[i],
            "hub_amplitude_deg": np.rad2deg(self.hub_amplitude[i, cols]),
            "state": self.state[i, cols], "energy_per_cycle_j": self.energy_per_cycle[i, cols],
            "max_stress_mpa": np.where(np.isfinite(stress), stress / 1e6, np.nan)})

    def to_frame(self):
        """Per speed and order: hub amplitude (deg), state, energy per cycle (J)."""
        import pandas as pd

        f = self.forced
        s, o = np.meshgrid(f.speed_rpm, f.orders, indexing="ij")
        return pd.DataFrame({"speed_rpm": s.ravel(), "order": o.ravel(),
                             "hub_amplitude_deg": np.rad2deg(self.hub_amplitude).ravel(),
                             "state": self.state.ravel(),
                             "energy_per_cycle_j": self.energy_per_cycle.ravel()})

    def plot(self, ax=None, *, orders=None):
        """Hub amplitude (deg) per order against speed; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        f = self.forced
        show = range(f.orders.size) if orders is None else [
            int(np.flatnonzero(np.isclose(f.orders, q))[0]) for q in orders]
        for k in show:
            ax.plot(f.speed_rpm, np.rad2deg(self.hub_amplitude[:, k]), label=f"{f.orders[k]:g}")
        ax.set_xlabel("speed [rpm]")
        ax.set_ylabel(f"{self.node} amplitude [deg]")
        ax.set_title(f"{self.damper}: harmonic balance per order")
        ax.legend(title="order", fontsize=7)
        return fig


def friction_forced_response(system, speed_rpm, *, torque=None, orders=None, misfire=None,
                             imep=None, superpose=True,
                             samples_per_period=SAMPLES_PER_PERIOD) -> FrictionForcedResponse:
    """Forced response with the system's friction damper by harmonic balance, order by order.

    Parameters
    ----------
    system : TorsionalSystem
        With one entry in ``friction_dampers`` (from a ``type = "friction"`` damper without a
        design point in the model TOML, or ``dampers.add_friction_damper(...,
        model="harmonic-balance")``).
    speed_rpm : array_like
        Crankshaft speeds, rpm (> 0).
    torque, orders, misfire, imep, superpose, samples_per_period
        As in :func:`predict.torsion.forced.forced_response` (default excitation: the engine's).

    Returns
    -------
    FrictionForcedResponse

    Examples
    --------
    >>> from crankbench.predict.torsion import chain
    >>> from crankbench.predict.torsion.friction import FrictionDamper
    >>> s = chain([1.0], [1.0e5]).replace(cylinder_nodes=[0], firing_angles_deg=[0.0],
    ...     node_damping=[5.0], friction_dampers=[FrictionDamper(0, 0.2, 20.0, "ring")])
    >>> r = friction_forced_response(s, [2000.0, 3020.0], torque=[50.0], orders=[1.0])
    >>> [str(v) for v in r.state[:, 0]]
    ['stick', 'slip']
    """
    if len(system.friction_dampers) != 1:
        raise ModelError(f"friction_forced_response: the system has "
                         f"{len(system.friction_dampers)} friction dampers; the harmonic "
                         "balance here handles exactly one")
    d = system.friction_dampers[0]
    rpm, orders = check_speeds_orders(system, speed_rpm, orders)
    speed = rpm * np.pi / 30.0
    harmonics, label = cylinder_harmonics(system, speed, orders, torque=torque,
                                          misfire=misfire, imep=imep)
    x_f = harmonic_solve(system, speed, orders,
                         cylinder_forcing(system, harmonics, orders, speed.size))
    n = d.node
    unit = np.zeros((speed.size, orders.size, system.n_nodes), complex)
    unit[:, :, n] = 1.0
    g = harmonic_solve(system, speed, orders, unit)
    ns, no = speed.size, orders.size
    amp = np.zeros((ns, no))
    state = np.empty((ns, no), object)
    energy = np.zeros((ns, no))
    multi = np.zeros((ns, no), bool)
    x = x_f.copy()
    for i in range(ns):
        for k in range(no):
            jw2 = d.ring_inertia * (speed[i] * orders[k]) ** 2
            a, zc, multi[i, k] = _balance(x_f[i, k, n], g[i, k, n], jw2, d.slip_torque, rpm[i])
            if a > 0:
                zz = zc * jw2
                x[i, k] = x_f[i, k] - g[i, k] * zz * (x_f[i, k, n] / (1 + g[i, k, n] * zz))
                energy[i, k] = np.pi * a * a * jw2 * zc.imag
            amp[i, k] = a
            state[i, k] = _state(d.slip_torque, jw2, a)
    if multi.any():
        log.warning("friction_forced_response: several harmonic-balance amplitudes at %d "
                    "(speed, order) points; the largest is reported", int(multi.sum()))
    forced = response_from_angles(
        system, rpm, orders, x, superpose=superpose, samples_per_period=samples_per_period,
        method=(f"harmonic balance of the friction ring {d.name!r} (first harmonic of the exact "
                f"stick-slip torque), each order alone, orders superposed; linear line by the "
                f"exact harmonic solve; excitation: {label}"))
    return FrictionForcedResponse(forced=forced, damper=d.name, node=system.node_names[n],
                                  hub_amplitude=amp, state=state.astype(str),
                                  energy_per_cycle=energy, multiple_solutions=multi)
