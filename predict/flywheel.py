"""Turning-moment diagram, fluctuation of energy, coefficient of speed fluctuation, flywheel
inertia for a required coefficient, and flywheel rim/disc stresses.

With a constant load torque equal to the mean engine torque, the excess energy
E(φ) = ∫₀^φ (T − T_mean) dφ' swings between E_max and E_min; the fluctuation of energy is
ΔE = E_max − E_min.  Energy conservation gives ½ J (ω_max² − ω_min²) = ΔE exactly, so with
ω_mean = (ω_max + ω_min)/2 the coefficient of speed fluctuation δ = (ω_max − ω_min)/ω_mean is
exactly ΔE / (J ω_mean²) (classical formula; it is exact for this definition of the mean speed,
and differs from the time-averaged speed by O(δ²)).  :meth:`TurningMoment.speed` integrates the
energy equation for the speed over the cycle, giving δ against the time-mean speed as well.

Rim stress of a thin rim (hoop stress, arms and hub neglected): σ = ρ v², v = ω R.  Solid disc
of uniform thickness: σ_max = (3 + ν)/8 · ρ ω² R² at the centre.

References
----------
*Applied Mechanics* vol. 2 (Engine dynamics), ch. 2 §6-8a (fluctuation of energy, limits of
speed variation, flywheel, stresses in flywheels); Liang 1948 ch. 5 §5-4 (speed variation and
flywheel).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_int, check_positive, check_range
from .errors import ModelError

__all__ = [
    "TurningMoment",
    "turning_moment",
    "flywheel_inertia",
    "FlywheelDesign",
    "design_flywheel",
    "rim_stress",
    "disc_stress",
    "harmonic_load",
    "load_from_toml",
]


@dataclass(frozen=True)
class TurningMoment:
    """A turning-moment diagram over one working cycle.

    Attributes
    ----------
    angle : ndarray
        Crank angle from cylinder 1's firing TDC, rad, evenly spaced over one period
        (endpoint excluded).
    torque : ndarray
        Engine torque, N·m.
    omega : float
        Mean crank speed, rad/s.
    period : float
        Angle of one period of the diagram, rad.
    load_torque : float
        Mean resisting torque, N·m; the mean engine torque by default.
    load_variation : ndarray or None
        The load's own variation about its mean at ``angle`` (N·m), for a load with harmonics
        (compressor, pump, propeller blade passing); None for a constant load.
    """

    angle: np.ndarray
    torque: np.ndarray
    omega: float
    period: float
    load_torque: float
    load_is_mean: bool = True
    load_variation: np.ndarray | None = None

    @property
    def load(self) -> np.ndarray:
        """Resisting torque at ``angle``, N·m (mean plus its own variation)."""
        base = np.full(self.angle.shape, self.load_torque)
        return base if self.load_variation is None else base + self.load_variation

    @classmethod
    def from_torque(cls, angle, torque, *, omega, load_torque=None):
        """Wrap a sampled torque (evenly spaced angles over one period, endpoint excluded).

        ``load_torque``: None (a constant load equal to the mean engine torque), a constant
        (N·m), an array of the load at ``angle`` or a callable ``load(angle_rad) -> N·m``
        (see :func:`harmonic_load`).

        Examples
        --------
        >>> a = np.arange(360) * 2 * np.pi / 360
        >>> tm = TurningMoment.from_torque(a, 100 + 50 * np.sin(2 * a), omega=100.0)
        >>> round(tm.fluctuation_of_energy, 6)   # 2·A/n = 50 J
        50.0
        """
        a = check_finite_array(angle, "angle", ndim=1, min_length=8, error=ModelError)
        t = check_finite_array(torque, "torque", ndim=1, error=ModelError)
        if t.size != a.size:
            raise ModelError(f"torque has {t.size} values, angle {a.size}")
        step = np.diff(a)
        if np.any(step <= 0) or np.ptp(step) > 1e-9 * step.mean():
            raise ModelError("angle must be evenly spaced and increasing")
        w = check_positive(omega, "omega", error=ModelError)
        period = float(step.mean() * a.size)
        variation = None
        if load_torque is None:
            load = float(t.mean())
        elif callable(load_torque) or np.ndim(load_torque) > 0:
            arr = load_torque(a) if callable(load_torque) else load_torque
            arr = check_finite_array(arr, "load_torque", ndim=1, error=ModelError)
            if arr.size != a.size:
                raise ModelError(f"load_torque has {arr.size} values, angle {a.size}")
            load = float(arr.mean())
            variation = arr - load
        else:
            load = float(load_torque)
        return cls(angle=a, torque=t, omega=w, period=period, load_torque=load,
                   load_is_mean=load_torque is None, load_variation=variation)

    @property
    def mean_torque(self) -> float:
        """Mean engine torque over the period, N·m."""
        return float(self.torque.mean())

    @property
    def power(self) -> float:
        """Mean power T_mean·ω, W."""
        return self.mean_torque * self.omega

    def excess_energy(self) -> np.ndarray:
        """E(φ) = ∫ (T − T_load) dφ from the start, J, at ``angle`` (trapezoidal rule, with the
        periodic wrap so a sinusoid's integral is exact to round-off for ≥ 3 points per wave)."""
        d = self.torque - self.load
        h = self.period / self.angle.size
        steps = 0.5 * (d + np.roll(d, -1)) * h
        return np.concatenate([[0.0], np.cumsum(steps[:-1])])

    @property
    def fluctuation_of_energy(self) -> float:
        """ΔE = max E − min E, J (sample maximum; see :meth:`fluctuation_error`)."""
        e = self._fine_energy()
        return float(e.max() - e.min())

    def _fine_energy(self):
        # E between samples from the spectral (trigonometric) interpolant of the torque:
        # exact for band-limited torque, so ΔE is not underestimated between samples
        d = self.torque - self.load
        n = d.size
        spec = np.fft.rfft(d) / n
        m = 8 * n
        k = np.arange(1, spec.size)
        c = spec[1:].copy()
        if n % 2 == 0:
            c[-1] *= 0.5
        g = np.zeros(m // 2 + 1, dtype=complex)
        g[k] = c / (1j * 2 * np.pi * k / self.period)
        periodic = np.fft.irfft(g, m) * m          # Σ 2 Re(g_k e^{i w_k x})
        x = np.arange(m) * self.period / m
        return periodic - periodic[0] + spec[0].real * x

    def fluctuation_error(self) -> float:
        """Estimate of the error in ΔE from the sampling, J: the change when every second
        sample is dropped (about 3× the actual error for the O(h²) convergence of a torque curve
        with kinks; spectrally small for smooth torque). It covers the sampling of the torque only,
        not the resolution of a sampled pressure trace behind it."""
        t2 = self.torque[::2]
        half = TurningMoment(angle=self.angle[::2], torque=t2, omega=self.omega,
                             period=self.period,
                             load_torque=float(t2.mean()) if self.load_is_mean else
                             self.load_torque, load_is_mean=self.load_is_mean,
                             load_variation=None if self.load_variation is None else
                             self.load_variation[::2])
        return abs(self.fluctuation_of_energy - half.fluctuation_of_energy)

    def speed_fluctuation(self, inertia) -> float:
        """Coefficient of speed fluctuation δ = ΔE / (J ω²) for total inertia J (kg·m²).

        Exact for δ = (ω_max − ω_min)/ω_mean with ω_mean = (ω_max + ω_min)/2 (energy
        conservation, constant load torque).
        """
        j = check_positive(inertia, "inertia", error=ModelError)
        return self.fluctuation_of_energy / (j * self.omega**2)

    def speed(self, inertia):
        """Crank speed over the cycle from ½ J ω² = ½ J ω₀² + E(φ), rad/s.

        ω₀ is set so that the *time*-mean speed equals ``omega`` (fixed-point iteration to
        1e-14). Returns the speed at ``angle``.

        Examples
        --------
        >>> a = np.arange(360) * 2 * np.pi / 360
        >>> tm = TurningMoment.from_torque(a, 100 + 50 * np.sin(2 * a), omega=100.0)
        >>> w = tm.speed(0.5)
        >>> round(float((w.max() - w.min()) / 100.0), 6)   # ≈ ΔE / (J ω²) = 50 / 5000
        0.009999
        """
        j = check_positive(inertia, "inertia", error=ModelError)
        e = self.excess_energy()
        w0 = self.omega
        for _ in range(200):
            w2 = w0**2 + 2 * e / j
            if np.any(w2 <= 0):
                raise ModelError(f"inertia={j!r} kg m² is too small: the engine would stop "
                                 "within the cycle")
            # time-mean speed = period / time of one period = harmonic mean of ω over angle
            mean_speed = 1.0 / np.mean(1.0 / np.sqrt(w2))
            w0_new = w0 * self.omega / mean_speed
            if abs(w0_new - w0) <= 1e-14 * w0:
                w0 = w0_new
                break
            w0 = w0_new
        return np.sqrt(w0**2 + 2 * e / j)

    def crossings(self):
        """Crossing angles of the engine torque with the load, and the energy of each loop.

        The classical reading of the turning-moment diagram: between successive crossings the
        area between the curves is the energy gained (+) or given up (−); the excess energy is
        largest at a downward crossing (speed maximum) and smallest at an upward one (speed
        minimum). Crossings by linear interpolation of T − T_load between samples; loop areas
        by the trapezoidal rule with the crossing points inserted.

        Returns
        -------
        pandas.DataFrame
            ``angle_deg`` (from cylinder 1's firing TDC), ``direction`` ("up": torque rises
            above the load, "down"), ``energy_j`` (excess energy E there, relative to the
            start of the period), ``loop_area_j`` (area to the next crossing, J).

        Examples
        --------
        >>> a = np.arange(360) * 2 * np.pi / 360
        >>> tm = TurningMoment.from_torque(a, 100 + 50 * np.sin(2 * a), omega=100.0)
        >>> print(tm.crossings()[["angle_deg", "direction", "loop_area_j"]].round(3))
           angle_deg direction  loop_area_j
        0        0.0        up       49.995
        1       90.0      down      -49.995
        2      180.0        up       49.995
        3      270.0      down      -49.995
        """
        import pandas as pd

        d = self.torque - self.load
        n = d.size
        h = self.period / n
        nxt = np.roll(d, -1)
        idx = np.flatnonzero(((d <= 0) & (nxt > 0)) | ((d >= 0) & (nxt < 0)))
        idx = idx[~((d[idx] == 0) & (np.roll(d, 1)[idx] == 0))]
        if idx.size == 0:
            return pd.DataFrame(columns=["angle_deg", "direction", "energy_j", "loop_area_j"])
        frac = np.where(d[idx] != nxt[idx], d[idx] / (d[idx] - nxt[idx]), 0.0)
        ang = self.angle[0] + (idx + frac) * h
        e = self.excess_energy()
        # E at the crossing: E(sample) + trapezoid over the fraction
        e_cross = e[idx] + 0.5 * (d[idx] + 0.0) * frac * h
        direction = np.where(nxt[idx] > d[idx], "up", "down")
        total = float(np.sum(0.5 * (d + nxt)) * h)        # net energy over the period
        areas = np.diff(np.concatenate([e_cross, [e_cross[0] + total]]))
        return pd.DataFrame({"angle_deg": np.rad2deg(ang), "direction": direction,
                             "energy_j": e_cross, "loop_area_j": areas})

    def speed_statistics(self, inertia) -> dict:
        """Speed extremes and the mean speeds the texts define, for total inertia J (kg·m²).

        From :meth:`speed` (the energy equation, time-mean speed = ``omega``):

        * ``omega_max``, ``omega_min`` (rad/s) and their angles (deg);
        * ``mean_extremes`` = (ω_max + ω_min)/2 — with it ΔE = J ω δ (ω_max − ω_min) holds
          exactly and δ = ΔE/(J ω²) (Applied Mechanics vol. 2 §7);
        * ``mean_time`` = 2π/(time of a revolution) — what a tachometer shows, = ``omega``;
        * ``mean_angle`` = average of ω over the crank angle;
        * ``mean_rms`` = √(mean of ω² over angle) — the kinetic-energy mean;
        * ``coefficient_<mean>`` = (ω_max − ω_min)/that mean, for each.

        Examples
        --------
        >>> a = np.arange(720) * 2 * np.pi / 720
        >>> tm = TurningMoment.from_torque(a, 100 + 50 * np.sin(2 * a), omega=20.0)
        >>> st = tm.speed_statistics(0.5)
        >>> round(st["coefficient_mean_extremes"], 4), round(st["mean_time"], 12)
        (0.2481, 20.0)
        """
        w = self.speed(inertia)
        i_max, i_min = int(np.argmax(w)), int(np.argmin(w))
        wmax, wmin = float(w[i_max]), float(w[i_min])
        means = {"mean_extremes": 0.5 * (wmax + wmin),
                 "mean_time": float(1.0 / np.mean(1.0 / w)),
                 "mean_angle": float(np.mean(w)),
                 "mean_rms": float(np.sqrt(np.mean(w * w)))}
        out = dict(omega_max=wmax, omega_min=wmin,
                   angle_max_deg=float(np.rad2deg(self.angle[i_max])),
                   angle_min_deg=float(np.rad2deg(self.angle[i_min])), **means)
        for k, v in means.items():
            out[f"coefficient_{k}"] = (wmax - wmin) / v
        return out

    def to_frame(self):
        """Columns crank_angle_deg, torque_nm, excess_energy_j."""
        import pandas as pd

        return pd.DataFrame({"crank_angle_deg": np.rad2deg(self.angle),
                             "torque_nm": self.torque, "excess_energy_j": self.excess_energy()})

    def plot(self, ax=None):
        """Turning-moment diagram with the mean/load line; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        deg = np.rad2deg(self.angle)
        ax.plot(deg, self.torque, label="engine torque")
        ax.plot(deg, self.load, color="k", lw=0.8, ls="--", label="load")
        ax.fill_between(deg, self.torque, self.load, alpha=0.2)
        ax.set_xlabel("crank angle from cylinder 1 firing TDC (deg)")
        ax.set_ylabel("torque (N m)")
        ax.set_title(f"turning moment, ΔE = {self.fluctuation_of_energy:.4g} J")
        ax.legend()
        return fig


def turning_moment(engine, *, omega, pressure=None, points_per_cycle=None, load_torque=None):
    """Turning-moment diagram of ``engine`` over one working cycle.

    Parameters
    ----------
    engine : Engine
    omega : float
        Mean crank speed, rad/s.
    pressure : PressureTrace, optional
        Cylinder pressure (default: the engine's ``[engine.combustion]`` synthetic trace).
    points_per_cycle : int, optional
        Samples over the cycle (default 2880 for 4-stroke: 0.25°).
    load_torque : float, array_like or callable, optional
        Resisting torque, N·m: constant (default the mean engine torque), sampled at the
        diagram's angles, or a callable of the crank angle (:func:`harmonic_load`).

    Returns
    -------
    TurningMoment

    References
    ----------
    Applied Mechanics vol. 2 ch. 1 §5, ch. 2 §6; Liang 1948 ch. 5.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.pressure import synthetic_pressure
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.032, rod_length=0.105,
    ...            reciprocating_mass=0.42, bore=0.088, compression_ratio=8.5)
    >>> tm = turning_moment(e, omega=377.0, pressure=synthetic_pressure(e, imep=1.0e6))
    >>> round(tm.mean_torque, 2), round(tm.fluctuation_of_energy, 1)
    (30.98, 406.8)
    """
    from .forces import engine_torque
    from .pressure import synthetic_pressure

    w = check_positive(omega, "omega", error=ModelError)
    n = points_per_cycle or 720 * engine.cycle
    n = check_int(n, "points_per_cycle", minimum=16, error=ModelError)
    if pressure is None:
        pressure = synthetic_pressure(engine)
    angle = np.arange(n) * engine.cycle_angle / n
    torque = engine_torque(engine, angle, omega=w, pressure=pressure)
    return TurningMoment.from_torque(angle, torque, omega=w, load_torque=load_torque)


def harmonic_load(*, mean, orders, amplitudes, phases_deg=None):
    """A load torque with its own harmonics, T(φ) = T_m + Σ A_q cos(q φ − β_q), as a callable
    of the crank angle φ (rad) for :meth:`TurningMoment.from_torque` / :func:`turning_moment`.

    Parameters
    ----------
    mean : float
        T_m, N·m.
    orders : array_like
        q, per crankshaft revolution (a driven machine turning at the crank speed has integer
        orders; choose orders that repeat within the engine cycle).
    amplitudes : array_like
        A_q, N·m.
    phases_deg : array_like, optional
        β_q, deg (default 0).

    Examples
    --------
    >>> load = harmonic_load(mean=100.0, orders=[2], amplitudes=[30.0])
    >>> print(load(np.array([0.0, np.pi / 2])))
    [130.  70.]
    """
    m = float(mean)
    q = check_finite_array(orders, "orders", ndim=1, min_length=1, error=ModelError)
    amp = check_finite_array(amplitudes, "amplitudes", ndim=1, error=ModelError)
    if amp.size != q.size:
        raise ModelError(f"amplitudes has {amp.size} values, orders {q.size}")
    ph = np.zeros(q.size) if phases_deg is None else np.deg2rad(check_finite_array(
        phases_deg, "phases_deg", ndim=1, error=ModelError))
    if ph.size != q.size:
        raise ModelError(f"phases_deg has {ph.size} values, orders {q.size}")

    def load(angle):
        a = np.asarray(angle, float)
        return m + np.cos(np.multiply.outer(a, q) - ph) @ amp

    return load


def load_from_toml(path):
    """The ``[load]`` table of a model file as a load-torque callable, or None if absent.

    Keys: ``orders`` (per crank revolution), ``amplitudes_nm`` (N·m), ``phases_deg``
    (optional) and ``mean_nm`` (optional: default the engine's mean torque, given at use as
    the diagram's mean)::

        [load]                  # e.g. a reciprocating compressor driven by the engine
        orders = [1, 2]
        amplitudes_nm = [350.0, 120.0]
        phases_deg = [30.0, 0.0]

    Returns
    -------
    callable or None
        ``load(angle_rad, mean_nm)`` when ``mean_nm`` is not in the file, else
        ``load(angle_rad)`` wrapped to ignore the mean argument.
    """
    from ._toml import load_toml

    doc = load_toml(path)
    t = doc.table("load", None)
    if t is None:
        return None
    orders = t.numbers("orders", low=0.0, strict_low=True, unit="1", plausible=(1e-2, 100.0))
    amps = t.numbers("amplitudes_nm", length=orders.size, low=0.0, unit="N*m",
                     plausible=(1e-3, 1e8))
    phases = t.numbers("phases_deg", None, length=orders.size, unit="deg",
                       plausible=(1e-3, 720.0))
    mean = t.number("mean_nm", None, unit="N*m", plausible=(1e-3, 1e8))
    t.check_unknown(["description"])

    def load(angle, mean_nm=None):
        m = mean if mean is not None else (0.0 if mean_nm is None else mean_nm)
        return harmonic_load(mean=m, orders=orders, amplitudes=amps, phases_deg=phases)(angle)

    load.fixed_mean = mean
    return load


def flywheel_inertia(turning, coefficient, *, other_inertia=0.0):
    """Flywheel inertia for a required coefficient of speed fluctuation, kg·m².

    J_total = ΔE / (δ ω²); the flywheel supplies J_total − ``other_inertia`` (the rest of the
    crank train).

    Examples
    --------
    >>> a = np.arange(720) * 4 * np.pi / 720
    >>> tm = TurningMoment.from_torque(a, 300 + 400 * np.sin(2 * a), omega=300.0)
    >>> round(flywheel_inertia(tm, 0.01), 4)   # ΔE = 400 J
    0.4444
    """
    d = check_range(coefficient, "coefficient", 0.0, 1.0, inclusive=(False, False),
                    error=ModelError)
    j = turning.fluctuation_of_energy / (d * turning.omega**2) - float(other_inertia)
    if j <= 0:
        raise ModelError(f"other_inertia={other_inertia!r} kg m² already meets "
                         f"coefficient={d!r}; no flywheel needed")
    return float(j)


def rim_stress(*, omega, radius, density):
    """Hoop stress of a thin rotating rim, σ = ρ (ω R)², Pa.

    Examples
    --------
    >>> rim_stress(omega=100.0, radius=0.3, density=7200.0)   # v = 30 m/s
    6480000.0
    """
    w = check_positive(omega, "omega", error=ModelError)
    r = check_positive(radius, "radius", error=ModelError)
    rho = check_positive(density, "density", error=ModelError)
    return float(rho * (w * r) ** 2)


def disc_stress(*, omega, radius, density, poisson=0.3):
    """Largest stress (radial = hoop, at the centre) of a solid uniform disc,
    σ = (3 + ν)/8 · ρ ω² R², Pa (Timoshenko, *Strength of Materials* II §35).

    Examples
    --------
    >>> round(disc_stress(omega=100.0, radius=0.3, density=7800.0) / 1e6, 4)
    2.8958
    """
    w = check_positive(omega, "omega", error=ModelError)
    r = check_positive(radius, "radius", error=ModelError)
    rho = check_positive(density, "density", error=ModelError)
    nu = check_range(poisson, "poisson", 0.0, 0.5, error=ModelError)
    return float((3 + nu) / 8 * rho * w * w * r * r)


@dataclass(frozen=True)
class FlywheelDesign:
    """A flywheel sized for a coefficient of speed fluctuation.

    Attributes
    ----------
    coefficient : float
        Required δ.
    inertia : float
        Flywheel inertia, kg·m².
    fluctuation_of_energy : float
        ΔE, J.
    mean_torque : float
        N·m.
    shape : str
        "rim" or "disc".
    outer_radius : float
        m.
    mass : float
        kg.
    rim_speed : float
        Peripheral speed at the largest speed of the cycle, m/s.
    stress : float
        Largest stress at the cycle's top speed, Pa.
    speed_rpm : float
        Mean speed, rpm.
    """

    coefficient: float
    inertia: float
    fluctuation_of_energy: float
    mean_torque: float
    shape: str
    outer_radius: float
    mass: float
    rim_speed: float
    stress: float
    speed_rpm: float

    def to_frame(self):
        """One row, SI units named in the columns."""
        import pandas as pd

        return pd.DataFrame([{
            "speed_rpm": self.speed_rpm, "mean_torque_nm": self.mean_torque,
            "fluctuation_of_energy_j": self.fluctuation_of_energy,
            "coefficient": self.coefficient, "inertia_kgm2": self.inertia, "shape": self.shape,
            "outer_radius_m": self.outer_radius, "mass_kg": self.mass,
            "rim_speed_m_s": self.rim_speed, "stress_mpa": self.stress / 1e6}])

    def plot(self, ax=None):
        """Coefficient of speed fluctuation against flywheel inertia (the design point marked);
        returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        j = self.inertia * np.geomspace(0.25, 4, 50)
        w = self.speed_rpm * np.pi / 30
        ax.loglog(j, self.fluctuation_of_energy / (j * w * w))
        ax.plot([self.inertia], [self.coefficient], "o")
        ax.set_xlabel("inertia (kg m²)")
        ax.set_ylabel("coefficient of speed fluctuation")
        return fig


def design_flywheel(turning, *, coefficient, outer_radius, density=7200.0, shape="rim",
                    other_inertia=0.0, poisson=0.3):
    """Size a flywheel: inertia for the coefficient, mass and stress for a rim or a disc.

    Parameters
    ----------
    turning : TurningMoment
    coefficient : float
        Required δ = (ω_max − ω_min)/ω_mean.
    outer_radius : float
        Rim mean radius (shape "rim") or disc radius (shape "disc"), m.
    density : float
        kg/m³ (cast iron 7200, steel 7850).
    shape : {"rim", "disc"}
        Thin rim (J = m R²) or solid disc (J = m R²/2).
    other_inertia : float
        Inertia of the rest of the crank train, kg·m².

    Returns
    -------
    FlywheelDesign

    References
    ----------
    Applied Mechanics vol. 2 ch. 2 §8, §8a.

    Examples
    --------
    >>> a = np.arange(720) * 4 * np.pi / 720
    >>> tm = TurningMoment.from_torque(a, 300 + 400 * np.sin(2 * a), omega=300.0)
    >>> d = design_flywheel(tm, coefficient=0.01, outer_radius=0.2)
    >>> round(d.inertia, 4), round(d.mass, 2), round(d.stress / 1e6, 3)
    (0.4444, 11.11, 26.18)
    """
    from ._validate import check_option

    shape = check_option(shape, "shape", ["rim", "disc"], error=ModelError)
    j = flywheel_inertia(turning, coefficient, other_inertia=other_inertia)
    r = check_positive(outer_radius, "outer_radius", error=ModelError)
    rho = check_positive(density, "density", error=ModelError)
    mass = j / r**2 if shape == "rim" else 2 * j / r**2
    w_top = turning.omega * (1 + coefficient / 2)
    if shape == "rim":
        stress = rim_stress(omega=w_top, radius=r, density=rho)
    else:
        stress = disc_stress(omega=w_top, radius=r, density=rho, poisson=poisson)
    return FlywheelDesign(coefficient=float(coefficient), inertia=j,
                          fluctuation_of_energy=turning.fluctuation_of_energy,
                          mean_torque=turning.mean_torque, shape=shape, outer_radius=r,
                          mass=float(mass), rim_speed=float(w_top * r), stress=stress,
                          speed_rpm=float(turning.omega * 30 / np.pi))
