"""Operating profiles: shaft speed against time, and its exact integral (crank angle).

Every profile is a piecewise-linear speed table ``(time, speed_rpm)``: steady running, a linear
run-up or coast-down (with optional holds before and after), an exponential coast-down
(approximated by linear pieces to a stated tolerance), or any table. Between table points the
speed is linear in time, so the crank angle is piecewise quadratic and computed exactly, and
its inverse (the time a given angle is reached, needed for pulse trains) is exact too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crankbench.predict._validate import check_finite_array, check_positive, check_range
from crankbench.predict.errors import ConfigError

__all__ = ["SpeedProfile", "steady", "ramp", "exponential_coastdown", "from_table"]

RPM = 2.0 * np.pi / 60.0


@dataclass(frozen=True)
class SpeedProfile:
    """Shaft speed as a piecewise-linear function of time.

    Attributes
    ----------
    time : numpy.ndarray
        Break points, s, strictly increasing from 0.
    speed_rpm : numpy.ndarray
        Speed at the break points, rpm (> 0).
    kind : str
        "steady", "runup", "coastdown" or "table".

    Examples
    --------
    >>> p = ramp(600.0, 1200.0, duration=10.0)
    >>> float(p.speed(5.0) / RPM), round(float(p.angle(10.0) / (2 * np.pi)), 6)
    (900.0, 150.0)
    """

    time: np.ndarray
    speed_rpm: np.ndarray
    kind: str = "table"

    def __post_init__(self):
        t = check_finite_array(self.time, "profile time", ndim=1, min_length=2, error=ConfigError)
        n = check_finite_array(self.speed_rpm, "profile speed_rpm", ndim=1, min_length=2,
                               error=ConfigError)
        if t.size != n.size:
            raise ConfigError(f"profile: {t.size} times but {n.size} speeds; expected equal "
                              "lengths")
        if t[0] != 0.0 or np.any(np.diff(t) <= 0):
            raise ConfigError("profile time must start at 0 and increase strictly, got "
                              f"{t.tolist()[:6]}")
        if np.any(n <= 0):
            i = int(np.flatnonzero(n <= 0)[0])
            raise ConfigError(f"profile speed_rpm[{i}]={n[i]:g} must be > 0 (the synthetic bench "
                              "needs the shaft turning)")
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "speed_rpm", n)
        # cumulative angle at the break points (trapezoid = exact for linear speed)
        w = n * RPM
        object.__setattr__(self, "_angle_at_breaks",
                           np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1])
                                                            * np.diff(t))]))

    @property
    def duration(self) -> float:
        """Length of the profile, s."""
        return float(self.time[-1])

    def speed(self, t):
        """Angular speed, rad/s, at times ``t`` (s); held constant outside the table."""
        return np.interp(t, self.time, self.speed_rpm) * RPM

    def acceleration(self, t):
        """Angular acceleration, rad/s², at times ``t`` (piecewise constant)."""
        t = np.asarray(t, dtype=float)
        slope = np.diff(self.speed_rpm) * RPM / np.diff(self.time)
        i = np.clip(np.searchsorted(self.time, t, side="right") - 1, 0, slope.size - 1)
        out = slope[i]
        return np.where((t < self.time[0]) | (t > self.time[-1]), 0.0, out)

    def angle(self, t):
        """Shaft angle turned since t = 0, rad (exact integral of the piecewise-linear speed)."""
        t = np.asarray(t, dtype=float)
        tc = np.clip(t, self.time[0], self.time[-1])
        i = np.clip(np.searchsorted(self.time, tc, side="right") - 1, 0, self.time.size - 2)
        w0 = self.speed_rpm[i] * RPM
        a = (self.speed_rpm[i + 1] - self.speed_rpm[i]) * RPM / (self.time[i + 1] - self.time[i])
        dt = tc - self.time[i]
        out = self._angle_at_breaks[i] + w0 * dt + 0.5 * a * dt * dt
        # constant speed outside the table
        out = out + np.where(t > self.time[-1], (t - self.time[-1]) * self.speed_rpm[-1] * RPM,
                             0.0)
        out = out + np.where(t < self.time[0], (t - self.time[0]) * self.speed_rpm[0] * RPM, 0.0)
        return out

    def time_at_angle(self, angle):
        """Inverse of :meth:`angle`: the time (s) at which the shaft has turned ``angle`` rad.

        Exact (root of the quadratic of each piece, in the cancellation-free form).
        """
        angle = np.asarray(angle, dtype=float)
        total = self._angle_at_breaks
        i = np.clip(np.searchsorted(total, angle, side="right") - 1, 0, self.time.size - 2)
        w0 = self.speed_rpm[i] * RPM
        a = (self.speed_rpm[i + 1] - self.speed_rpm[i]) * RPM / (self.time[i + 1] - self.time[i])
        d = angle - total[i]
        # w0 dt + a dt^2 / 2 = d  ->  dt = 2 d / (w0 + sqrt(w0^2 + 2 a d))
        disc = np.maximum(w0 * w0 + 2.0 * a * d, 0.0)
        dt = 2.0 * d / (w0 + np.sqrt(disc))
        out = self.time[i] + dt
        beyond = angle > total[-1]
        out = np.where(beyond, self.time[-1] + (angle - total[-1]) / (self.speed_rpm[-1] * RPM),
                       out)
        before = angle < 0
        return np.where(before, angle / (self.speed_rpm[0] * RPM), out)

    def max_sweep_rate(self) -> float:
        """Largest |d(speed)/dt|, rpm/s."""
        return float(np.max(np.abs(np.diff(self.speed_rpm) / np.diff(self.time))))

    def to_frame(self):
        """Break-point table: ``time_s``, ``speed_rpm``."""
        import pandas as pd

        return pd.DataFrame({"time_s": self.time, "speed_rpm": self.speed_rpm})

    def plot(self, ax=None):
        """Speed (rpm) against time; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        ax.plot(self.time, self.speed_rpm)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("speed (rpm)")
        ax.set_title(f"operating profile ({self.kind})")
        return fig


def steady(speed_rpm, *, duration):
    """Constant speed for ``duration`` s.

    Examples
    --------
    >>> round(float(steady(1500.0, duration=2.0).angle(2.0) / (2 * np.pi)), 9)
    50.0
    """
    n = check_positive(speed_rpm, "speed_rpm", error=ConfigError)
    d = check_positive(duration, "duration", error=ConfigError)
    return SpeedProfile(np.array([0.0, d]), np.array([n, n]), "steady")


def ramp(start_rpm, end_rpm, *, duration, hold_start=0.0, hold_end=0.0):
    """Linear run-up (``end > start``) or coast-down, with optional steady holds at the ends.

    Parameters
    ----------
    start_rpm, end_rpm : float
        Speeds, rpm.
    duration : float
        Length of the ramp, s.
    hold_start, hold_end : float
        Steady running before and after the ramp, s.

    Examples
    --------
    >>> p = ramp(200.0, 800.0, duration=30.0, hold_start=2.0)
    >>> p.kind, p.duration, round(p.max_sweep_rate(), 3)
    ('runup', 32.0, 20.0)
    """
    n0 = check_positive(start_rpm, "start_rpm", error=ConfigError)
    n1 = check_positive(end_rpm, "end_rpm", error=ConfigError)
    d = check_positive(duration, "duration", error=ConfigError)
    h0 = check_range(hold_start, "hold_start", 0.0, None, error=ConfigError)
    h1 = check_range(hold_end, "hold_end", 0.0, None, error=ConfigError)
    t, n = [0.0], [n0]
    if h0 > 0:
        t.append(h0)
        n.append(n0)
    t.append(t[-1] + d)
    n.append(n1)
    if h1 > 0:
        t.append(t[-1] + h1)
        n.append(n1)
    kind = "runup" if n1 > n0 else "coastdown" if n1 < n0 else "steady"
    return SpeedProfile(np.array(t), np.array(n), kind)


def exponential_coastdown(start_rpm, end_rpm, *, time_constant, tolerance_rpm=0.5):
    """Coast-down with speed ``n0 exp(-t / tau)`` until ``end_rpm``, as linear pieces.

    The break points are spaced so the linear interpolation of the exponential deviates by at
    most ``tolerance_rpm`` (the chord error of ``n0 e^{-t/tau}`` over a piece of length ``h``
    is ``n h^2 / (8 tau^2)``).

    Examples
    --------
    >>> p = exponential_coastdown(1500.0, 500.0, time_constant=10.0)
    >>> round(p.duration, 4), p.kind
    (10.9861, 'coastdown')
    """
    n0 = check_positive(start_rpm, "start_rpm", error=ConfigError)
    n1 = check_positive(end_rpm, "end_rpm", error=ConfigError)
    if n1 >= n0:
        raise ConfigError(f"exponential coast-down needs end_rpm={n1:g} < start_rpm={n0:g}")
    tau = check_positive(time_constant, "time_constant", error=ConfigError)
    tol = check_positive(tolerance_rpm, "tolerance_rpm", error=ConfigError)
    total = tau * np.log(n0 / n1)
    h = tau * np.sqrt(8.0 * tol / n0)
    pieces = max(1, int(np.ceil(total / h)))
    t = np.linspace(0.0, total, pieces + 1)
    return SpeedProfile(t, n0 * np.exp(-t / tau), "coastdown")


def from_table(time, speed_rpm):
    """Any speed profile from a table (linear between points).

    Examples
    --------
    >>> p = from_table([0, 5, 10], [700, 700, 1000])
    >>> float(p.speed(7.5) / RPM)
    850.0
    """
    return SpeedProfile(np.asarray(time, float), np.asarray(speed_rpm, float), "table")
