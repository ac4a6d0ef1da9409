"""Lanchester dry-friction damper: slip/stick response, energy per cycle, optimum slip torque.

A free ring of inertia J is pressed against the hub through friction plates with slipping
torque T_s. With the hub moving harmonically, θ_h = a sin ωt, the ring's motion is found
exactly (piecewise: while slipping it accelerates at ±T_s/J, while sticking it moves with the
hub, which it can do as long as J ω² a |sin ωt| ≤ T_s). Everything depends on the one ratio

``x = T_s / (J ω² a)``  (x ≥ 1: the ring sticks all the time and acts as added inertia).

Continuous slip (x ≤ 1/√(1 + π²/4) ≈ 0.537) has the closed form of Den Hartog: the
friction torque is a square wave lagging the hub velocity, its fundamental on the hub is
``−Z a sin ωt``-like with the dynamic stiffness (phasors of e^{iωt}, hub angle reference)

``Z / (J ω²) = −2x² + i (4x/π) √(1 − π²x²/4)``,

the energy dissipated per cycle ``W = 4 T_s a √(1 − (π T_s/(2 J ω² a))²)``, largest at the
optimum slip torque ``T_s = (√2/π) J ω² a`` where ``W = (4/π) J ω² a²``. Between x ≈ 0.537 and 1
the ring sticks part of each cycle: the exact piecewise motion is computed (event by event) and
its fundamental taken.

Across a resonance (:func:`friction_damper_response`) the damper is attached to one node of a
linear :class:`~predict.torsion.system.TorsionalSystem` and the single-order steady state is
found by harmonic balance (first harmonic of the friction torque, the classical describing
function): at each speed the hub amplitude solves ``a = |x_F| / |1 + g Z(a)|`` with x_F the
linear system's response at the hub and g its driving-point receptance there. The neglected
higher harmonics of the square-wave torque are the method's error; it is measured against
time integration of the full non-linear equations (:func:`time_domain_sdof`, tests and the
``textbook`` bench suite): a few per cent at the resonant peak.

References
----------
.. [1] J. P. Den Hartog, *Mechanical Vibrations*, 4th ed., McGraw-Hill, 1956, §8.6 (Lanchester
   damper with dry friction: energy per cycle, optimum friction torque) and §8.2 (forced
   vibration with Coulomb damping, exact solution).
.. [2] J. P. Den Hartog, "Forced vibrations with combined Coulomb and viscous friction",
   Trans. ASME 53 (1931) APM-107.
.. [3] 梁守槃, 發動機動力學 (1948), 第七章 摩擦阻尼器.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass

import numpy as np

from .._validate import check_finite_array, check_positive
from ..errors import ModelError

__all__ = ["friction_dissipation", "friction_dynamic_stiffness", "optimum_slip_torque",
           "FrictionResponse", "friction_damper_response", "time_domain_sdof",
           "CONTINUOUS_SLIP_LIMIT", "FrictionDamper"]

log = logging.getLogger("crankbench")

#: largest x = T_s/(J ω² a) with slip through the whole cycle: at the switching instant the
#: hub's acceleration must exceed the ring's, √(1 − π²x²/4) ≥ x, i.e. x ≤ 1/√(1 + π²/4)
CONTINUOUS_SLIP_LIMIT = float(2.0 / np.pi / np.sqrt(1.0 + 4.0 / np.pi ** 2))


@dataclass(frozen=True)
class FrictionDamper:
    """A Lanchester friction ring kept as a non-linear element of a torsional system.

    Attributes
    ----------
    node : int
        Node carrying the hub (turning at crankshaft speed).
    ring_inertia : float
        kg·m².
    slip_torque : float
        N·m.
    name : str
    """

    node: int
    ring_inertia: float
    slip_torque: float
    name: str = "friction ring"

    def __post_init__(self):
        object.__setattr__(self, "ring_inertia", check_positive(
            self.ring_inertia, "ring_inertia", error=ModelError))
        object.__setattr__(self, "slip_torque", check_positive(
            self.slip_torque, "slip_torque", error=ModelError))


def _ring_cycle(x: float, samples: int = 4096):
    """Exact periodic ring motion under hub θ_h = sin u (J = ω = a = 1, T_s = x).

    Returns (A, B): the hub torque's fundamental ``A sin u + B cos u``.
    """
    from scipy.optimize import brentq

    if x >= 1.0:
        return 1.0, 0.0          # the ring sticks throughout: hub torque = J ω² a sin u
    # start in slip at the hub-velocity peak with the ring at rest; march event by event
    u, v, s = 0.0, 0.0, 1.0          # angle, ring velocity, slip sign (v_hub − v_ring)
    sticking = False
    segments = []                    # (u0, u1, sticking, v0, s)
    end = 14 * np.pi
    while u < end:
        if sticking:
            # stick until |sin u| exceeds x (hub acceleration beyond what friction transmits)
            k = np.floor(u / np.pi)
            u1 = None
            for cand in (k * np.pi + np.arcsin(x), (k + 1) * np.pi + np.arcsin(x)):
                if cand > u + 1e-12:
                    u1 = cand
                    break
            segments.append((u, u1, True, 0.0, 0.0))
            u = u1
            v = np.cos(u)
            s = -np.sign(np.sin(u))
            sticking = False
            continue
        # slip: ring velocity v + s x (w − u); find the next zero of the relative velocity
        f = lambda w: np.cos(w) - (v + s * x * (w - u))  # noqa: E731
        grid = u + np.linspace(1e-7, 4 * np.pi, 2049)
        vals = f(grid)
        # the relative velocity leaves zero with the sign s (near the continuous-slip limit it
        # leaves tangentially: skip the rounding noise right after the switch)
        start = int(np.argmax(np.sign(vals) == s))
        vals, grid = vals[start:], grid[start:]
        idx = np.flatnonzero(np.sign(vals[1:]) != np.sign(vals[:-1]))
        if idx.size == 0:
            raise ModelError(f"friction ring motion: no end of slip found (x={x!r})")
        i = int(idx[0])
        u1 = brentq(f, grid[i], grid[i + 1], xtol=1e-14)
        segments.append((u, u1, False, v, s))
        v = v + s * x * (u1 - u)
        u = u1
        if abs(np.sin(u)) <= x:
            sticking = True
        else:
            s = -s
    # fundamental of the hub torque −J θ̈_ring over the last full cycle
    uu = end - 2 * np.pi + (np.arange(samples) + 0.5) * 2 * np.pi / samples
    acc = np.empty_like(uu)
    for u0, u1, stick, _, sg in segments:
        sel = (uu >= u0) & (uu < u1)
        acc[sel] = -np.sin(uu[sel]) if stick else sg * x
    tau = -acc
    return (2.0 / samples * np.sum(tau * np.sin(uu)),
            2.0 / samples * np.sum(tau * np.cos(uu)))


@functools.lru_cache(maxsize=1)
def _stick_slip_table():
    xs = np.linspace(CONTINUOUS_SLIP_LIMIT, 1.0, 121)
    z = np.array([-(a + 1j * b) for a, b in (_ring_cycle(float(v)) for v in xs[1:])])
    # at the limit itself the slip ends tangentially: take the closed form there
    x0 = CONTINUOUS_SLIP_LIMIT
    z0 = -2 * x0 ** 2 + 1j * (4 * x0 / np.pi) * np.sqrt(1 - (np.pi * x0 / 2) ** 2)
    return xs, np.concatenate([[z0], z])


def friction_dynamic_stiffness(x):
    """Dimensionless dynamic stiffness Z/(J ω²) of a friction ring seen by its hub.

    Parameters
    ----------
    x : float or array_like
        T_s / (J ω² a) ≥ 0 (slip torque over the torque needed to carry the ring with the hub).

    Returns
    -------
    complex or ndarray
        Closed form for continuous slip (x ≤ ``CONTINUOUS_SLIP_LIMIT``), the exact stick-slip
        motion's fundamental between it and 1 (tabulated, linear interpolation, within 1e-3), and
        −1 (pure added inertia) for x ≥ 1. Torque on the hub = −Z·(hub angle).

    Examples
    --------
    >>> z = friction_dynamic_stiffness(2 ** 0.5 / np.pi)   # Den Hartog's optimum
    >>> print(round(z.real, 6), round(z.imag, 6))
    -0.405285 0.405285
    """
    xv = check_finite_array(x, "x", error=ModelError)
    if np.any(xv < 0):
        raise ModelError("x = T_s/(J ω² a) must be >= 0")
    out = np.empty(xv.shape, complex)
    cont = xv <= CONTINUOUS_SLIP_LIMIT
    xc = xv[cont]
    out[cont] = -2 * xc ** 2 + 1j * (4 * xc / np.pi) * np.sqrt(np.clip(
        1 - (np.pi * xc / 2) ** 2, 0.0, None))
    stick = xv >= 1.0
    out[stick] = -1.0
    mid = ~cont & ~stick
    if mid.any():
        xs, z = _stick_slip_table()
        out[mid] = np.interp(xv[mid], xs, z.real) + 1j * np.interp(xv[mid], xs, z.imag)
    return complex(out) if out.ndim == 0 else out


def friction_dissipation(*, slip_torque, ring_inertia, omega, hub_amplitude) -> float:
    """Energy dissipated per vibration cycle by a Lanchester friction damper, J.

    The hub moves harmonically with amplitude ``hub_amplitude`` (rad) at ``omega`` (rad/s):
    ``W = π a² J ω² Im Z`` — in continuous slip ``4 T_s a √(1 − (π T_s/(2 J ω² a))²)``
    (Den Hartog §8.6), 0 when the ring sticks throughout.

    Parameters
    ----------
    slip_torque : float
        T_s, N·m.
    ring_inertia : float
        J, kg·m².
    omega : float
        Vibration frequency, rad/s.
    hub_amplitude : float
        a, rad.

    Examples
    --------
    >>> w = friction_dissipation(slip_torque=100.0, ring_inertia=0.5, omega=300.0,
    ...                          hub_amplitude=0.006)
    >>> round(w, 4)    # 4 T_s a √(1 − (π·100/(2·0.5·300²·0.006))²)
    1.952
    """
    t = check_positive(slip_torque, "slip_torque", error=ModelError)
    j = check_positive(ring_inertia, "ring_inertia", error=ModelError)
    w = check_positive(omega, "omega", error=ModelError)
    a = check_positive(hub_amplitude, "hub_amplitude", error=ModelError)
    z = friction_dynamic_stiffness(t / (j * w * w * a))
    return float(np.pi * a * a * j * w * w * z.imag)


def optimum_slip_torque(*, ring_inertia, omega, hub_amplitude) -> dict:
    """Slip torque dissipating most energy at a given hub amplitude (Den Hartog §8.6).

    Returns
    -------
    dict
        ``slip_torque`` = (√2/π) J ω² a (N·m), ``energy_per_cycle`` = (4/π) J ω² a² (J) and
        ``equivalent_damping`` = W/(π ω a²) (N·m·s/rad, = 4 J ω/π²).

    Examples
    --------
    >>> r = optimum_slip_torque(ring_inertia=0.5, omega=300.0, hub_amplitude=0.004)
    >>> round(r["slip_torque"], 3), round(r["energy_per_cycle"], 4)
    (81.028, 0.9167)
    """
    j = check_positive(ring_inertia, "ring_inertia", error=ModelError)
    w = check_positive(omega, "omega", error=ModelError)
    a = check_positive(hub_amplitude, "hub_amplitude", error=ModelError)
    energy = 4.0 / np.pi * j * w * w * a * a
    return dict(slip_torque=float(np.sqrt(2.0) / np.pi * j * w * w * a),
                energy_per_cycle=float(energy),
                equivalent_damping=float(energy / (np.pi * w * a * a)))


@dataclass(frozen=True)
class FrictionResponse:
    """Single-order steady response of a shaft line with a friction damper, over speed.

    Attributes
    ----------
    speed_rpm : ndarray
    order : float
    hub_amplitude : ndarray
        Amplitude at the damper node, rad.
    angle : ndarray (n_s, n_nodes) complex
        Every node's angle phasor, rad (real, unreferred).
    state : ndarray of str
        "slip", "stick-slip" or "stick" per speed.
    energy_per_cycle : ndarray
        Energy the damper dissipates per vibration cycle, J.
    multiple_solutions : ndarray of bool
        Speeds where the harmonic balance has several amplitudes (the largest is reported).
    node_names : tuple
    method : str
    """

    speed_rpm: np.ndarray
    order: float
    hub_amplitude: np.ndarray
    angle: np.ndarray
    state: np.ndarray
    energy_per_cycle: np.ndarray
    multiple_solutions: np.ndarray
    node_names: tuple
    method: str

    def to_frame(self):
        """Per speed: hub amplitude (deg), state, energy per cycle (J)."""
        import pandas as pd

        return pd.DataFrame({"speed_rpm": self.speed_rpm,
                             "hub_amplitude_deg": np.rad2deg(self.hub_amplitude),
                             "state": self.state, "energy_per_cycle_j": self.energy_per_cycle,
                             "multiple_solutions": self.multiple_solutions})

    def plot(self, ax=None):
        """Hub amplitude (deg) against speed, stick/slip marked; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        deg = np.rad2deg(self.hub_amplitude)
        ax.plot(self.speed_rpm, deg, "k-")
        for st, mk in (("stick", "s"), ("stick-slip", "^")):
            sel = self.state == st
            ax.plot(self.speed_rpm[sel], deg[sel], mk, ms=3, label=st)
        ax.set_xlabel("speed [rpm]")
        ax.set_ylabel("hub amplitude [deg]")
        ax.legend()
        return fig


def friction_damper_response(system, node, *, ring_inertia, slip_torque, speed_rpm, order,
                             torque) -> FrictionResponse:
    """Steady response of order ``order`` with a Lanchester friction damper on ``node``.

    Parameters
    ----------
    system : TorsionalSystem
        The linear shaft line *without* the damper (with cylinder nodes and firing angles).
    node : str or int
        Node carrying the damper hub (turning at crankshaft speed).
    ring_inertia : float
        kg·m².
    slip_torque : float
        N·m.
    speed_rpm : array_like
        Crankshaft speeds, rpm.
    order : float
        Excitation order.
    torque : complex or array_like
        Per-cylinder torque harmonic of that order, N·m (scalar, or one per speed).

    Returns
    -------
    FrictionResponse

    Examples
    --------
    >>> from crankbench.predict.torsion import chain
    >>> s = chain([1.0], [1.0e5]).replace(cylinder_nodes=[0], firing_angles_deg=[0.0],
    ...                                   node_damping=[5.0])
    >>> r = friction_damper_response(s, 0, ring_inertia=0.2, slip_torque=20.0,
    ...                              speed_rpm=[2000.0, 3020.0], order=1.0, torque=50.0)
    >>> [str(v) for v in r.state]
    ['stick', 'slip']
    """
    from .forced import cylinder_forcing, harmonic_solve

    if isinstance(node, str):
        if node not in system.node_names:
            raise ModelError(f"node {node!r} not in the system ({', '.join(system.node_names)})")
        node = system.node_names.index(node)
    n = int(node)
    if not 0 <= n < system.n_nodes:
        raise ModelError(f"node={node!r} out of range 0..{system.n_nodes - 1}")
    if not np.isclose(system.node_ratio[n], 1.0):
        raise ModelError("the damper node must turn at crankshaft speed (ratio 1)")
    j = check_positive(ring_inertia, "ring_inertia", error=ModelError)
    ts = check_positive(slip_torque, "slip_torque", error=ModelError)
    rpm = check_finite_array(speed_rpm, "speed_rpm", ndim=1, min_length=1, error=ModelError)
    if np.any(rpm <= 0):
        raise ModelError("speed_rpm must be > 0")
    q = check_positive(order, "order", error=ModelError)
    speed = rpm * np.pi / 30
    h = np.broadcast_to(np.asarray(torque, complex), rpm.shape).reshape(-1, 1)
    forcing = cylinder_forcing(system, h, np.array([q]), rpm.size)
    x_f = harmonic_solve(system, speed, [q], forcing)[:, 0, :]
    unit = np.zeros((rpm.size, 1, system.n_nodes), complex)
    unit[:, 0, n] = 1.0
    g = harmonic_solve(system, speed, [q], unit)[:, 0, :]
    amp = np.empty(rpm.size)
    state = np.empty(rpm.size, object)
    multi = np.zeros(rpm.size, bool)
    angle = np.empty((rpm.size, system.n_nodes), complex)
    energy = np.empty(rpm.size)
    for i, w in enumerate(speed * q):
        jw2 = j * w * w
        a, zc, multi[i] = _balance(x_f[i, n], g[i, n], jw2, ts, rpm[i])
        zz = zc * jw2
        theta_n = x_f[i, n] / (1 + g[i, n] * zz) if a > 0 else 0.0
        angle[i] = x_f[i] - g[i] * zz * theta_n
        amp[i] = a
        state[i] = _state(ts, jw2, a)
        energy[i] = np.pi * a * a * jw2 * np.imag(zc) if a > 0 else 0.0
    if multi.any():
        log.warning("friction_damper_response: several harmonic-balance amplitudes at %d "
                    "speed(s); the largest is reported", int(multi.sum()))
    return FrictionResponse(speed_rpm=rpm.copy(), order=q, hub_amplitude=amp, angle=angle,
                            state=state.astype(str), energy_per_cycle=energy,
                            multiple_solutions=multi, node_names=system.node_names,
                            method="harmonic balance (first harmonic of the exact stick-slip "
                                   "friction torque)")


def _balance(xf, gn, jw2, ts, rpm):
    """Hub amplitude of the first-harmonic balance ``a |1 + g Z(a)| = |x_F|`` at one speed.

    While the ring sticks (a ≤ T_s/(J ω²)) Z is the added inertia −J ω² and the balance is
    linear: its root is taken directly; above, the roots are bracketed on a log grid and
    bisected. Returns (a, Z/(J ω²) at a, several roots?); the largest root is taken.
    """
    if abs(xf) == 0:
        return 0.0, -1.0 + 0j, False
    a_stick = ts / jw2                       # a below this: the ring sticks
    roots = []
    a0 = abs(xf) / abs(1 - gn * jw2)         # stuck ring: added inertia
    if a0 <= a_stick:
        roots.append(a0)
    top = max(1e6 * a_stick, 10.0 * abs(xf) * (1 + abs(gn) * 4 * ts / np.pi))
    grid = a_stick * np.geomspace(1.0, top / a_stick, 1200)
    z = friction_dynamic_stiffness(ts / (jw2 * grid)) * jw2
    phi = grid * np.abs(1 + gn * z) - abs(xf)
    for k in np.flatnonzero(np.sign(phi[1:]) != np.sign(phi[:-1])):
        lo, hi = grid[k], grid[k + 1]
        for _ in range(48):          # bisection on the bracket: to round-off
            mid = np.sqrt(lo * hi)
            zm = friction_dynamic_stiffness(ts / (jw2 * mid)) * jw2
            if np.sign(mid * abs(1 + gn * zm) - abs(xf)) == np.sign(phi[k]):
                lo = mid
            else:
                hi = mid
        roots.append(float(np.sqrt(lo * hi)))
    if not roots:
        raise ModelError(f"friction damper: no harmonic-balance amplitude found at {rpm:g} rpm")
    a = max(roots)
    return a, complex(friction_dynamic_stiffness(ts / (jw2 * a))), len(roots) > 1


def _state(ts, jw2, a):
    xr = ts / (jw2 * a) if a > 0 else np.inf
    return "stick" if xr >= 1 else "slip" if xr <= CONTINUOUS_SLIP_LIMIT else "stick-slip"


def time_domain_sdof(*, inertia, stiffness, damping, ring_inertia, slip_torque, omega,
                     torque, cycles=200, steps_per_cycle=400):
    """Reference: time integration of hub + friction ring under T cos ωt (steady amplitude).

    Hub J on a spring k to ground with viscous damping c; the ring (J_r) is coupled by Coulomb
    friction T_s (stick when the torque needed is below T_s). Integrated with a fixed step and
    exact stick/slip switching per step (semi-implicit Euler on the hub, the ring advanced by
    its constant friction acceleration); the amplitude is the hub's half peak-to-peak over the
    last 20 % of the cycles.

    Returns
    -------
    float
        Steady hub amplitude, rad.
    """
    jh, k, c = (check_positive(v, n, error=ModelError) for v, n in
                ((inertia, "inertia"), (stiffness, "stiffness"), (damping + 1e-300, "damping")))
    jr = check_positive(ring_inertia, "ring_inertia", error=ModelError)
    ts = check_positive(slip_torque, "slip_torque", error=ModelError)
    w = check_positive(omega, "omega", error=ModelError)
    dt = 2 * np.pi / w / steps_per_cycle
    n = int(cycles * steps_per_cycle)
    th = vh = vr = 0.0
    keep = []
    for i in range(n):
        t = i * dt
        drive = torque * np.cos(w * t) - k * th - c * vh
        rel = vh - vr
        if abs(rel) < 1e-12 * max(abs(vh), 1e-30) + 1e-15:
            # stuck: common acceleration, friction needed = J_r·acc
            acc = drive / (jh + jr)
            if abs(jr * acc) <= ts:
                vh = vr = vh + acc * dt
                th += vh * dt
                if i >= 0.8 * n:
                    keep.append(th)
                continue
            f = ts * np.sign(jr * acc)
        else:
            f = ts * np.sign(rel)
        ah = (drive - f) / jh
        ar = f / jr
        vh_new = vh + ah * dt
        vr_new = vr + ar * dt
        if np.sign(vh_new - vr_new) != np.sign(rel) and rel != 0:
            # relative velocity crosses zero in this step: meet at the common velocity
            vh_new = vr_new = (jh * vh_new + jr * vr_new) / (jh + jr)
        vh, vr = vh_new, vr_new
        th += vh * dt
        if i >= 0.8 * n:
            keep.append(th)
    keep = np.asarray(keep)
    return float(0.5 * (keep.max() - keep.min()))
