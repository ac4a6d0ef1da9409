"""Vibrograph channels at the engine mounts: balance residuals and torque reaction through the
mount model.

The engine block is a rigid body on elastic mounts (:class:`predict.mounts.MountedEngine`). Per
order it is shaken by the loads of :func:`predict.mounts.block_excitation` (the very loads the
prediction of :mod:`analysis.vibrograph` uses):

* the free inertia forces and moments of :func:`predict.balance.unbalance` (integer orders,
  amplitude exactly proportional to ``Omega**2``; counterweights and added masses included),
  and
* the reaction to the crankshaft torque, the roll moment ``-sum_c T_q,c`` about the crankshaft
  axis (all orders of the cycle, gas part scaled with the load plus ``Omega**2`` times the
  inertia part; :mod:`predict.torsion.excitation`).

The motion of a point is ``Re[(load H_gas(Omega) + Omega**2 H_in(Omega)) e^{i q psi(t)}]`` with
the harmonic response ``H`` of the mounted block at ``q Omega`` (:meth:`MountedEngine.response`,
exact 6x6 solve) tabulated on a speed grid and interpolated along the run: a **quasi-steady**
response at the instantaneous speed. It is exact at constant speed; during a sweep it omits the
transient of the mount modes, of relative order ``alpha q / (2 zeta omega_m**2)`` near a mount
resonance (``zeta`` = loss factor / 2; well-damped rubber mounts keep it small), which the
module states rather than models.

Frame: x along the crankshaft, y horizontal the way the top of the crank moves, z up; the
block's roll in the direction of rotation is a rotation about ``-x``.

References
----------
Liang Shoupan, *Engine dynamics* (發動機動力學), 1948, ch. 4 (effects of unbalanced forces on
the foundation) and ch. 9 (vibrographs).
"""

from __future__ import annotations

import numpy as np

from crankbench.predict._deprecate import renamed
from crankbench.predict.errors import ConfigError
from crankbench.predict.mounts import direction_vector

__all__ = ["MountChannels"]

TWO_PI = 2.0 * np.pi


class MountChannels:
    """Per-order harmonic responses of sensor points on the mounted block.

    Parameters
    ----------
    mounted : predict.mounts.MountedEngine
    engine : predict.engine.Engine
    excitation : predict.torsion.excitation.Excitation or None
        Cylinder torque harmonics (None: no torque reaction).
    orders : numpy.ndarray
        Orders of the cycle to model.
    points : numpy.ndarray (p, 3)
        Sensor points, m.
    omega_grid : numpy.ndarray
        Crankshaft speeds (rad/s) to tabulate the responses on.
    counterweights : sequence of predict.balance.Counterweight
        Masses fixed to the crankshaft besides the engine's own (counterweights, added or
        trial masses): order 1 of the shaking loads.

    Attributes
    ----------
    gas, inertia : numpy.ndarray (n_orders, p, 3, n_grid), complex
        Displacement (m) per unit load and per unit ``Omega**2`` at each grid speed.

    Examples
    --------
    >>> from pathlib import Path
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.mounts import MountedEngine
    >>> f = Path(__file__).resolve().parents[2] / "sample_data/engines/i4.toml"
    >>> mc = MountChannels(MountedEngine.from_toml(f), Engine.from_toml(f), None, [1.0, 2.0],
    ...                    [[0.2, 0.05, 0.1]], [314.159])
    >>> a = np.abs(mc.table(1, 0, "z", "acceleration"))[0]     # order 2 at 3000 rpm
    >>> bool(a > 10.0), float(np.abs(mc.table(0, 0, "z", "acceleration"))[0])  # order 1 balanced
    (True, 0.0)
    """

    def __init__(self, mounted, engine, excitation, orders, points, omega_grid, *,
                 counterweights=()):
        from crankbench.predict.mounts import block_excitation

        self.orders = np.asarray(orders, float)
        self.points = np.atleast_2d(np.asarray(points, float))
        self.omega_grid = np.asarray(omega_grid, float)
        n_o, n_p, n_g = self.orders.size, self.points.shape[0], self.omega_grid.size
        self.gas = np.zeros((n_o, n_p, 3, n_g), complex)
        self.inertia = np.zeros((n_o, n_p, 3, n_g), complex)
        exc = block_excitation(engine, self.orders, excitation=excitation,
                               counterweights=counterweights)
        self.excitation = exc
        # orders whose excitation cancels (balanced engines, minor orders of the torque
        # reaction) are skipped: relative 1e-9 of the largest excitation of each kind
        lever = max(1.0, float(np.ptp(np.asarray(engine.cylinder_positions))))
        size_in = np.abs(exc.inertia[:, :3]).max(axis=1) * lever + \
            np.abs(exc.inertia[:, 3:]).max(axis=1)
        size_gas = np.abs(exc.gas).max(axis=1)
        keep_in = size_in > 1e-9 * max(size_in.max(), 1e-300)
        keep_gas = size_gas > 1e-9 * max(size_gas.max(), 1e-300)
        for i, q in enumerate(self.orders):
            freq = q * self.omega_grid / TWO_PI
            for keep, loads, out in ((keep_in[i], exc.inertia[i], self.inertia),
                                     (keep_gas[i], exc.gas[i], self.gas)):
                if keep:
                    r = mounted.response(np.broadcast_to(loads[:3], (n_g, 3)),
                                         np.broadcast_to(loads[3:], (n_g, 3)), freq,
                                         point=exc.point, at=self.points)
                    out[i] = np.moveaxis(r.displacement, 0, -1)

    def table(self, order_index, point_index, direction, quantity, load_fn=None):
        """The response of one point per unit ``e^{i q psi}`` on the speed grid.

        ``(load(Omega) H_gas + Omega**2 H_in) (i q Omega)**p`` with ``p`` = 0, 1, 2 for
        displacement, velocity, acceleration: a smooth function of speed only, ready to be
        interpolated along the run. ``load_fn(Omega)`` gives the gas-load factor (default 1).
        """
        u = direction_vector(direction)
        q = self.orders[order_index]
        grid = self.omega_grid
        load = np.ones_like(grid) if load_fn is None else load_fn(grid)
        disp = load * (u @ self.gas[order_index, point_index]) + \
            grid**2 * (u @ self.inertia[order_index, point_index])
        power = {"displacement": 0, "velocity": 1, "acceleration": 2}.get(quantity)
        if power is None:
            raise ConfigError(f"quantity={quantity!r} is not one of 'acceleration', 'velocity', "
                              "'displacement'")
        return disp * (1j * q * grid) ** power

    @renamed(speed="omega")
    def transfer(self, order_index, point_index, direction, quantity, omega, load):
        """Complex amplitude of one point's motion along the run (quasi-steady).

        Returns ``A(t)`` such that the signal is ``Re[A(t) e^{i q psi(t)}]``, SI units of the
        quantity (m, m/s or m/s^2).
        """
        u = direction_vector(direction)
        q = self.orders[order_index]
        g = u @ self.gas[order_index, point_index]
        h = u @ self.inertia[order_index, point_index]
        grid = self.omega_grid
        if grid.size == 1:
            disp = load * g[0] + omega**2 * h[0]
        else:
            disp = (load * (np.interp(omega, grid, g.real) + 1j * np.interp(omega, grid, g.imag))
                    + omega**2 * (np.interp(omega, grid, h.real)
                                  + 1j * np.interp(omega, grid, h.imag)))
        w = q * omega
        if quantity == "displacement":
            return disp
        if quantity == "velocity":
            return 1j * w * disp
        if quantity == "acceleration":
            return -(w**2) * disp
        raise ConfigError(f"quantity={quantity!r} is not one of 'acceleration', 'velocity', "
                          "'displacement'")
