"""Speed-dependent natural frequencies (centrifugal pendulums) and their Campbell data.

A centrifugal pendulum absorber is a spring whose stiffness grows with the square of the
crankshaft speed Ω (``edge_stiffness_omega2``), so the modes it takes part in move with speed:
at Ω its node joins the eigen-analysis with stiffness ``k + k₂ Ω²``. At standstill the pendulum
has no restoring stiffness at all, which is why the speed-free eigen-analysis leaves it out.

Critical speeds of such a system are the roots of ``ω_m(Ω) = q Ω`` for each mode branch m and
order q (brentq on a bracketing grid); speed-independent systems keep the direct
``n_c = 60 f / q``.

References
----------
.. [1] J. P. Den Hartog, *Mechanical Vibrations*, 4th ed., 1956, §5.7 (centrifugal pendulum:
   natural frequency proportional to speed, n = √(R/r)).
.. [2] W. Ker Wilson, *Practical Solution of Torsional Vibration Problems*, vol. 4 (1968),
   pendulum absorbers in engine systems.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_finite_array
from ..errors import ModelError

__all__ = ["system_at_speed", "has_speed_dependence", "campbell_frequencies", "plot_campbell",
           "speed_dependent_criticals"]

TWO_PI = 2.0 * np.pi


def has_speed_dependence(system) -> bool:
    """True when some spring stiffness depends on speed (centrifugal pendulums)."""
    return bool(np.any(system.edge_stiffness_omega2 != 0))


def system_at_speed(system, speed_rpm: float):
    """The system frozen at crankshaft speed ``speed_rpm`` (rpm): speed-dependent springs turned
    into plain ones of stiffness ``k + k₂ Ω²`` and their nodes brought into the eigen-analysis.

    Examples
    --------
    >>> from crankbench.predict.torsion.elements import ShaftLine
    >>> from crankbench.predict.torsion import dampers
    >>> line = ShaftLine("p")
    >>> line.add_mass("hub", 1.0)
    >>> _ = dampers.add_pendulum_absorber(line, "hub", mass=0.5, pivot_radius=0.1,
    ...                                   length=0.025)
    >>> s = system_at_speed(line.build(), 3000.0)
    >>> print(s.natural_frequencies().round(3))   # n √(1 + J_a/J) Ω/2π, n = 2
    [  0.   100.39]
    """
    rpm = float(speed_rpm)
    if not np.isfinite(rpm) or rpm < 0:
        raise ModelError(f"speed_rpm={speed_rpm!r} must be finite and >= 0")
    w = rpm * TWO_PI / 60.0
    k2 = system.edge_stiffness_omega2
    k = system.stiffnesses + k2 * w * w
    mask = system.eigen_nodes
    e = system.edges
    if w > 0:
        moving = k2 != 0
        mask[e[moving, 1]] = True
        mask[e[moving & (e[:, 0] >= 0), 0]] = True
    return system.replace(stiffnesses=k, edge_stiffness_omega2=np.zeros_like(k),
                          eigen_nodes=mask)


def campbell_frequencies(system, speed_rpm):
    """Natural frequencies over speed (the Campbell diagram's curves).

    Parameters
    ----------
    system : TorsionalSystem
    speed_rpm : array_like
        Crankshaft speeds, rpm (> 0).

    Returns
    -------
    pandas.DataFrame
        Columns ``speed_rpm``, ``mode`` (1 = first elastic), ``frequency_hz``.
    """
    import pandas as pd

    rpm = check_finite_array(speed_rpm, "speed_rpm", ndim=1, min_length=1, error=ModelError)
    if np.any(rpm <= 0):
        raise ModelError("speed_rpm must be > 0")
    rows = []
    for r in rpm:
        s = system_at_speed(system, r)
        omega, numbers = s._values[:2]
        for m, w in zip(numbers, omega):
            if m > 0:
                rows.append((float(r), int(m), float(w / TWO_PI)))
    return pd.DataFrame(rows, columns=["speed_rpm", "mode", "frequency_hz"])


def speed_dependent_criticals(system, orders, lo: float, hi: float, *, grid: int = 64):
    """Crossings ω_m(Ω) = qΩ of every mode branch with every order line in [lo, hi] rpm.

    Returns rows ``(mode, order, speed_rpm, frequency_hz, vector_sum, major)``.
    """
    from scipy.optimize import brentq

    lo = max(float(lo), 1e-3)
    hi = float(hi)
    if not np.isfinite(hi):
        rated = getattr(system.engine, "rated_speed_rpm", None)
        hi = 2.0 * rated if rated else 1e5
    speeds = np.geomspace(lo, hi, grid)
    tables = [system_at_speed(system, r) for r in speeds]
    freqs = [t._values[0] for t in tables]
    nums = [t._values[1] for t in tables]
    n_el = min(int((n > 0).sum()) for n in nums)
    orders = np.atleast_1d(np.asarray(orders, float))
    major = system.major_orders(orders)
    rows = []

    def branch(r, m):
        s = system_at_speed(system, r)
        om, nn = s._values[:2]
        return om[np.flatnonzero(nn == m)[0]], s

    for m in range(1, n_el + 1):
        wm = np.array([f[np.flatnonzero(n == m)[0]] for f, n in zip(freqs, nums)])
        for j, q in enumerate(orders):
            g = wm - q * speeds * TWO_PI / 60.0
            for i in np.flatnonzero(np.sign(g[1:]) != np.sign(g[:-1])):
                root = brentq(lambda r: branch(r, m)[0] - q * r * TWO_PI / 60.0,
                              speeds[i], speeds[i + 1], xtol=1e-10 * speeds[i])
                w, s = branch(root, m)
                k = int(np.flatnonzero(s._values[1] == m)[0])
                vs = s.vector_sums([q])[k, 0]
                rows.append((m, float(q), float(root), float(w / TWO_PI), float(vs),
                             bool(major[j])))
    return rows


def _draw_branches(system, ax, lo: float, hi: float, points: int = 60):
    """Draw every mode's frequency against speed (rpm) on ``ax``; returns the figure."""
    camp = campbell_frequencies(system, np.linspace(max(lo, 1e-3), hi, points))
    for m, grp in camp.groupby("mode"):
        ax.plot(grp.speed_rpm, grp.frequency_hz, color="0.5", lw=0.8)
    return ax.figure


def plot_campbell(system, orders=None, speed_range_rpm=None, *, ax=None, modes=None):
    """Campbell diagram of a torsional system: natural frequencies (Hz, horizontal lines, or
    curves where pendulum modes move with speed) and order rays against speed (rpm), with the
    critical speeds marked (size ∝ relative vector sum).

    Parameters
    ----------
    system : TorsionalSystem
    orders : array_like, optional
        Orders drawn (default the system's default orders).
    speed_range_rpm : (float, float), optional
        Speed axis, rpm (default 0 to 1.1 × the highest critical speed).
    ax : matplotlib.axes.Axes, optional
    modes : iterable of int, optional
        Mode numbers shown (default all elastic modes).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    orders = system.default_orders() if orders is None else np.asarray(orders, float)
    crit = system.critical_speeds(orders, speed_range_rpm)
    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 5))
    else:
        fig = ax.figure
    lo, hi = (0.0, float(crit.speed_rpm.max()) * 1.1 if len(crit) else 1000.0) \
        if speed_range_rpm is None else map(float, speed_range_rpm)
    omega, numbers = system._values[:2]
    f = omega / TWO_PI
    shown = [i for i in np.flatnonzero(numbers > 0) if modes is None or numbers[i] in modes]

    if has_speed_dependence(system):      # pendulum modes move with speed: draw the curves
        _draw_branches(system, ax, max(lo, 1e-3), hi)
    else:
        for i in shown:
            ax.axhline(f[i], color="0.5", lw=0.8)
    rpm = np.array([lo, hi])
    for q in orders:
        ax.plot(rpm, rpm * q / 60.0, color="C0" if system.major_orders([q])[0] else "C1",
                lw=0.6)
    sel = crit[crit["mode"].isin(numbers[shown])]
    size = 10 + 30 * np.nan_to_num(sel.vector_sum.to_numpy(), nan=1.0)
    ax.scatter(sel.speed_rpm, sel.frequency_hz, s=size, color="k", zorder=3)
    ax.set_xlim(lo, hi)
    top = f[shown].max() * 1.15 if shown else 1.0
    ax.set_ylim(0, top)
    ax.set_xlabel("speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title("Campbell diagram (blue: major orders)")
    fig.tight_layout()
    return fig

