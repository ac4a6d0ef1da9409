"""Measurement imperfections of the synthetic bench: what a real test bench adds to the truth.

Sampled channels get a gain error, a DC offset, white noise and a sensor DC drift (a speed or
IAS channel and an encoder angle carry their own DC and drift); analogue pulse signals may ring
(:func:`ring`: the pick-up chain as a damped second-order system); pulse trains get tooth-spacing errors
(a fixed pattern per wheel), a zebra-tape butt joint, timing jitter, counter (timer)
quantisation, dropouts (missed pulses) and spurious pulses. Every random draw comes from one
``numpy.random.Generator`` seeded by the scene, so a scene always gives the same record.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from crankbench.predict._validate import check_nonnegative, check_range
from crankbench.predict.errors import ConfigError

__all__ = ["Imperfections", "tooth_angles", "add_noise_and_drift", "degrade_edges", "ring"]

TWO_PI = 2.0 * np.pi

_KEYS = ("noise_rms", "drift_rate", "offset", "gain_error", "tooth_error_deg",
         "butt_joint_deg", "jitter_s", "timer_resolution_s", "dropout_rate", "spurious_rate")


#: unit and plausible range per key (noise and drift are in the channel's units: numbers only)
_UNITS = {
    "noise_rms": dict(unit=None), "drift_rate": dict(unit=None), "offset": dict(unit=None),
    "gain_error": dict(unit="1", plausible=(1e-6, 0.5)),
    "tooth_error_deg": dict(unit="deg", plausible=(1e-6, 10.0)),
    "butt_joint_deg": dict(unit="deg", plausible=(1e-6, 90.0)),
    "jitter_s": dict(unit="s", plausible=(1e-12, 1e-2)),
    "timer_resolution_s": dict(unit="s", plausible=(1e-12, 1e-2)),
    "dropout_rate": dict(unit="1", plausible=(1e-9, 0.5)),
    "spurious_rate": dict(unit="1", plausible=(1e-9, 0.5)),
}


@dataclass(frozen=True)
class Imperfections:
    """Imperfections of one sensor (or the scene's defaults).

    Attributes
    ----------
    noise_rms : float
        White noise on a sampled channel, rms, in the channel's SI units.
    drift_rate : float
        Sensor DC drift, SI units per second (a linear offset growing from 0 at t = 0).
    offset : float
        Constant DC offset of a sampled channel, SI units (a transducer's zero error).
    gain_error : float
        Relative gain error of a sampled channel (the reading is ``(1 + gain_error)`` times
        the truth), in (-1, 1).
    tooth_error_deg : float
        rms of the random angular position error of each tooth/line of a pulse wheel, deg
        (fixed per wheel, i.e. the same every revolution; tooth 0 is the reference, error 0).
    butt_joint_deg : float
        Zebra tape: error of the joint pitch, deg (the joint pitch is ``360/N + butt_joint_deg``
        and the other pitches share the difference equally).
    jitter_s : float
        Random timing noise of each edge, s rms.
    timer_resolution_s : float
        Period of the counter clock that time-stamps the edges, s (edge times are rounded down
        to whole ticks); 0 = exact.
    dropout_rate : float
        Probability that an edge is missed.
    spurious_rate : float
        Expected number of spurious edges per true edge (placed at random inside intervals).
    """

    noise_rms: float = 0.0
    drift_rate: float = 0.0
    offset: float = 0.0
    gain_error: float = 0.0
    tooth_error_deg: float = 0.0
    butt_joint_deg: float = 0.0
    jitter_s: float = 0.0
    timer_resolution_s: float = 0.0
    dropout_rate: float = 0.0
    spurious_rate: float = 0.0

    def __post_init__(self):
        for key in ("noise_rms", "tooth_error_deg", "jitter_s", "timer_resolution_s"):
            check_nonnegative(getattr(self, key), key, error=ConfigError)
        check_range(self.drift_rate, "drift_rate", error=ConfigError)
        check_range(self.offset, "offset", error=ConfigError)
        check_range(self.gain_error, "gain_error", -1.0, 1.0, inclusive=(False, False),
                    error=ConfigError)
        check_range(self.butt_joint_deg, "butt_joint_deg", -90.0, 90.0, error=ConfigError)
        check_range(self.dropout_rate, "dropout_rate", 0.0, 0.5, error=ConfigError)
        check_range(self.spurious_rate, "spurious_rate", 0.0, 0.5, error=ConfigError)

    @classmethod
    def from_table(cls, table, defaults=None):
        """Read the imperfection keys present in a TOML :class:`~predict._toml.Table`."""
        base = defaults or cls()
        values = {}
        for key in _KEYS:
            if key in table:
                values[key] = table.number(key, **_UNITS.get(key, {"unit": None}))
        try:
            return replace(base, **values)
        except ConfigError as exc:
            raise ConfigError(f"{table.where()}: {exc}") from None

    def as_dict(self) -> dict:
        """Plain dict of the settings."""
        return asdict(self)


def tooth_angles(pulses_per_rev, imperfections, rng):
    """Actual angle of each pitch position of a wheel, rad, tooth 0 at 0.

    Random tooth errors (rms ``tooth_error_deg``, tooth 0 exact) and a butt joint (the last
    pitch, N-1 -> N, off by ``butt_joint_deg``).

    Examples
    --------
    >>> ang = tooth_angles(4, Imperfections(butt_joint_deg=6.0), np.random.default_rng(0))
    >>> np.degrees(ang).round(6).tolist()                  # joint pitch 96 deg, others 88
    [0.0, 88.0, 176.0, 264.0]
    """
    n = int(pulses_per_rev)
    joint = np.radians(imperfections.butt_joint_deg)
    pitch = (TWO_PI - (TWO_PI / n + joint)) / (n - 1) if n > 1 else TWO_PI
    angles = np.arange(n) * pitch
    if imperfections.tooth_error_deg > 0 and n > 1:
        err = np.radians(imperfections.tooth_error_deg) * rng.standard_normal(n)
        err[0] = 0.0
        angles = angles + err
    return angles


def add_noise_and_drift(data, time, imperfections, rng):
    """Gain error, DC offset, white noise and linear DC drift on a sampled channel (new array).

    Examples
    --------
    >>> out = add_noise_and_drift(np.ones(3), [0.0, 1.0, 2.0],
    ...                           Imperfections(drift_rate=0.5, offset=0.1, gain_error=0.02),
    ...                           np.random.default_rng(0))
    >>> out.round(6).tolist()
    [1.12, 1.62, 2.12]
    """
    out = np.array(data, dtype=float, copy=True)
    if imperfections.gain_error:
        out *= 1.0 + imperfections.gain_error
    if imperfections.offset:
        out += imperfections.offset
    if imperfections.noise_rms > 0:
        out += imperfections.noise_rms * rng.standard_normal(out.size)
    if imperfections.drift_rate != 0:
        out += imperfections.drift_rate * np.asarray(time, float)
    return out


def degrade_edges(edges, imperfections, rng):
    """Jitter, drop, add spurious and quantise edge times (sorted result, s).

    Examples
    --------
    >>> t = degrade_edges([0.10004, 0.20007], Imperfections(timer_resolution_s=1e-4),
    ...                   np.random.default_rng(0))
    >>> np.round(t, 6).tolist()                      # rounded down to whole 100 us ticks
    [0.1, 0.2]
    """
    t = np.array(edges, dtype=float, copy=True)
    if imperfections.jitter_s > 0:
        t += imperfections.jitter_s * rng.standard_normal(t.size)
    if imperfections.spurious_rate > 0 and t.size > 1:
        n_extra = rng.binomial(t.size - 1, imperfections.spurious_rate)
        where = rng.integers(0, t.size - 1, n_extra)
        frac = rng.uniform(0.15, 0.85, n_extra)
        t = np.concatenate([t, t[where] + frac * (t[where + 1] - t[where])])
    if imperfections.dropout_rate > 0:
        t = t[rng.random(t.size) >= imperfections.dropout_rate]
    t.sort()
    if imperfections.timer_resolution_s > 0:
        tick = imperfections.timer_resolution_s
        t = np.floor(t / tick) * tick
        # two edges in one tick cannot be told apart by the counter
        t = t[np.concatenate([[True], np.diff(t) > 0])]
    return t


def ring(signal, fs, *, damping, frequency_hz):
    """Pass a pulse signal through a damped second-order system (a pick-up and its cable):
    flanks rise in about ``1 / (2 frequency_hz)`` and overshoot by ``exp(-pi z / sqrt(1 - z²))``
    (z = ``damping``), ringing at ``frequency_hz``.

    Parameters
    ----------
    signal : array_like
        Sampled pulse signal.
    fs : float
        Sample rate, Hz.
    damping : float
        Damping ratio, in (0, 1]; 0.2 gives 53 % overshoot.
    frequency_hz : float
        Natural frequency, Hz (below fs / 2).

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> step = np.r_[np.zeros(50), np.ones(450)]
    >>> out = ring(step, 100_000.0, damping=0.2, frequency_hz=10_000.0)
    >>> round(float(out.max()), 1), round(float(out[-1]), 3)       # 1 + exp(-pi 0.2/0.98)
    (1.5, 1.0)
    """
    from scipy.signal import bilinear, lfilter

    check_range(damping, "damping", 0.0, 1.0, inclusive=(False, True), error=ConfigError)
    check_range(frequency_hz, "frequency_hz", 0.0, 0.5 * fs, inclusive=(False, False),
                error=ConfigError)
    x = np.asarray(signal, float)
    w = 2.0 * np.pi * frequency_hz
    # pre-warped so the natural frequency is kept by the bilinear transform
    wp = 2.0 * fs * np.tan(w / (2.0 * fs))
    b, a = bilinear([wp * wp], [1.0, 2.0 * damping * wp, wp * wp], fs=fs)
    # start at rest on the first sample's level
    return x[0] + lfilter(b, a, x - x[0])
