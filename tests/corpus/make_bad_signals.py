"""Bad signals, generated in memory: damaged tacho pulse trains and damaged vibration channels.

Each generator returns plain numpy data (and its ground truth where there is one), so tests can
feed it to :mod:`measure.tacho`, :mod:`measure.torsiograph`, :mod:`analysis.orders` or write it
into a record file of any format. ``SIGNALS`` maps a case name to its generator;
``tests/reliability/test_bad_signals.py`` asserts what each consumer must do with it (a clear
error naming the argument or channel, or a result with the damaged span masked and a warning).

The signals are deterministic (fixed seeds). Print a summary with::

    python tests/corpus/make_bad_signals.py
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Tacho", "Channel", "SIGNALS", "TACHO_CASES", "CHANNEL_CASES", "PULSES_PER_REV",
           "SPEED_RPM", "FS", "steady_edges", "analog_tacho", "vibration"]

PULSES_PER_REV = 60          # a 60-tooth wheel (60 pitch positions per revolution)
SPEED_RPM = 1000.0           # steady speed of the undamaged trains: 1000 pulses/s
FS = 2000.0                  # Hz, vibration channels
_N_REV = 12                  # revolutions in an undamaged pulse train


@dataclass(frozen=True)
class Tacho:
    """A (damaged) tacho pulse train.

    Attributes
    ----------
    edge_times : ndarray
        Edge times, s (``None`` for an analogue signal).
    signal : ndarray or None
        Analogue pick-up voltage sampled at ``fs`` (for :func:`measure.tacho.detect_edges`).
    fs : float
        Sample rate of ``signal``, Hz.
    true_rpm : float or None
        Steady speed of the undamaged train, rpm (None when the train carries no speed).
    span : tuple or None
        (start, end) times of the damaged stretch, s.
    """

    edge_times: np.ndarray | None
    signal: np.ndarray | None = None
    fs: float = 0.0
    true_rpm: float | None = SPEED_RPM
    span: tuple[float, float] | None = None


@dataclass(frozen=True)
class Channel:
    """A (damaged) vibration channel with its speed.

    Attributes
    ----------
    data : ndarray
        Samples (m/s²) at :data:`FS`.
    rpm : ndarray
        Shaft speed at each sample, rpm.
    spans : list of (int, int)
        Damaged sample ranges [a, b).
    truth : dict
        Order -> peak amplitude of the undamaged signal (m/s²).
    """

    data: np.ndarray
    rpm: np.ndarray
    spans: list = field(default_factory=list)
    truth: dict = field(default_factory=dict)


def steady_edges(n_rev: int = _N_REV, speed_rpm: float = SPEED_RPM,
                 pulses_per_rev: int = PULSES_PER_REV) -> np.ndarray:
    """Edge times (s) of a wheel turning at constant speed, first edge at t = 0."""
    pitch_time = 60.0 / (speed_rpm * pulses_per_rev)
    return np.arange(n_rev * pulses_per_rev) * pitch_time


def analog_tacho(edges: np.ndarray, fs: float = 50_000.0, duration=None) -> np.ndarray:
    """A magnetic pick-up-like square-ish wave (±1 V) switching high at each edge time."""
    duration = (edges[-1] + 0.01) if duration is None and edges.size else (duration or 0.1)
    t = np.arange(int(duration * fs)) / fs
    k = np.searchsorted(edges, t, side="right")
    return np.where(k % 2 == 1, 1.0, -1.0)


def vibration(n: int = 8000, *, speed_rpm: float = 1500.0, orders=(2.0, 4.0),
              amplitudes=(1.0, 0.3)) -> Channel:
    """Sum of shaft orders at steady speed, sampled at :data:`FS` (undamaged)."""
    t = np.arange(n) / FS
    phi = 2.0 * np.pi * speed_rpm / 60.0 * t
    x = sum(a * np.cos(q * phi) for q, a in zip(orders, amplitudes))
    return Channel(data=x, rpm=np.full(n, speed_rpm), truth=dict(zip(orders, amplitudes)))


# ----------------------------------------------------------------------------- tacho cases
def tacho_no_pulses() -> Tacho:
    """The tacho never fired: no edges at all."""
    return Tacho(edge_times=np.empty(0), true_rpm=None)


def tacho_one_pulse() -> Tacho:
    """A single edge (the logger stopped, or a once-per-rev mark over less than a turn)."""
    return Tacho(edge_times=np.array([0.0123]), true_rpm=None)


def tacho_two_pulses() -> Tacho:
    """Two edges: one interval, no way to tell a pitch from a dropout."""
    return Tacho(edge_times=np.array([0.0123, 0.0133]), true_rpm=None)


def tacho_reversed() -> Tacho:
    """Edge times in decreasing order (a channel read backwards / reversed direction)."""
    return Tacho(edge_times=steady_edges()[::-1].copy())


def tacho_duplicated_edge() -> Tacho:
    """One edge logged twice (same time stamp)."""
    e = steady_edges()
    return Tacho(edge_times=np.insert(e, 100, e[100]), span=(e[100], e[100]))


def tacho_half_missing() -> Tacho:
    """50 % of the pulses lost at random (a weak pick-up near its trigger level)."""
    e = steady_edges()
    keep = np.sort(np.random.default_rng(7).choice(e.size, e.size // 2, replace=False))
    return Tacho(edge_times=e[keep], span=(e[0], e[-1]))


def tacho_few_missing() -> Tacho:
    """3 % of the pulses lost at random (usable: the dropouts are bridged)."""
    e = steady_edges()
    drop = np.random.default_rng(3).choice(np.arange(10, e.size - 10), e.size * 3 // 100,
                                           replace=False)
    return Tacho(edge_times=np.delete(e, drop))


def tacho_stops() -> Tacho:
    """The shaft stands still for 5 s in the middle of the record, then runs again."""
    e = steady_edges()
    half = e.size // 2
    later = e[half:] + 5.0
    return Tacho(edge_times=np.concatenate([e[:half], later]), span=(e[half - 1], later[0]))


def tacho_nan_edge() -> Tacho:
    """A NaN edge time (a logger's fill value)."""
    e = steady_edges().copy()
    e[50] = np.nan
    return Tacho(edge_times=e, span=(e[49], e[51]))


def tacho_flat_analog() -> Tacho:
    """An analogue tacho channel that never switches (pick-up unplugged): constant 0.7 V."""
    return Tacho(edge_times=None, signal=np.full(5000, 0.7), fs=50_000.0, true_rpm=None)


def tacho_nan_analog() -> Tacho:
    """An analogue tacho channel with a dropout of NaN samples."""
    sig = analog_tacho(steady_edges(n_rev=2))
    sig[1000:1050] = np.nan
    return Tacho(edge_times=None, signal=sig, fs=50_000.0, span=(1000 / 5e4, 1050 / 5e4))


def tacho_plain_wheel_declared_60_2() -> Tacho:
    """A plain 60-tooth wheel processed as a 60-2 wheel: no gap to find."""
    return Tacho(edge_times=steady_edges())


def tacho_shorter_than_window() -> Tacho:
    """Half a revolution of edges: shorter than the one-revolution speed window."""
    return Tacho(edge_times=steady_edges()[:30])


TACHO_CASES = {f.__name__: f for f in (
    tacho_no_pulses, tacho_one_pulse, tacho_two_pulses, tacho_reversed, tacho_duplicated_edge,
    tacho_half_missing, tacho_few_missing, tacho_stops, tacho_nan_edge, tacho_flat_analog,
    tacho_nan_analog, tacho_plain_wheel_declared_60_2, tacho_shorter_than_window)}


# ----------------------------------------------------------------------------- channel cases
def channel_dropout_nan() -> Channel:
    """100 NaN samples (0.05 s) in the middle: a lost telemetry packet."""
    c = vibration()
    x = c.data.copy()
    x[4000:4100] = np.nan
    return Channel(data=x, rpm=c.rpm, spans=[(4000, 4100)], truth=c.truth)


def channel_dropout_inf() -> Channel:
    """5 samples of +inf (an overflowed integer converted to float)."""
    c = vibration()
    x = c.data.copy()
    x[2000:2005] = np.inf
    return Channel(data=x, rpm=c.rpm, spans=[(2000, 2005)], truth=c.truth)


def channel_clipped() -> Channel:
    """The amplifier saturates at ±0.8 m/s² (flat tops on every peak of a 1.3 peak signal)."""
    c = vibration()
    x = np.clip(c.data, -0.8, 0.8)
    flat = np.flatnonzero(np.abs(x) >= 0.8)
    return Channel(data=x, rpm=c.rpm, spans=[(int(flat[0]), int(flat[-1]) + 1)], truth=c.truth)


def channel_zero_speed_segment() -> Channel:
    """The speed reference reads 0 rpm for 0.25 s (engine stalled, or tacho lost)."""
    c = vibration()
    rpm = c.rpm.copy()
    rpm[3000:3500] = 0.0
    return Channel(data=c.data, rpm=rpm, spans=[(3000, 3500)], truth=c.truth)


def channel_negative_speed() -> Channel:
    """The speed reference is negative throughout (sensor sign / direction reversed)."""
    c = vibration()
    return Channel(data=c.data, rpm=-c.rpm, spans=[(0, c.rpm.size)], truth=c.truth)


def channel_nan_speed() -> Channel:
    """The speed reference has a NaN sample at the end (a short speed channel padded)."""
    c = vibration()
    rpm = c.rpm.copy()
    rpm[-1] = np.nan
    return Channel(data=c.data, rpm=rpm, spans=[(rpm.size - 1, rpm.size)], truth=c.truth)


def channel_speed_wrong_length() -> Channel:
    """The speed reference has fewer samples than the signal (different clocks)."""
    c = vibration()
    return Channel(data=c.data, rpm=c.rpm[:-100], truth=c.truth)


def channel_too_short() -> Channel:
    """Five samples only."""
    c = vibration(n=5)
    return Channel(data=c.data, rpm=c.rpm, truth=c.truth)


def channel_constant() -> Channel:
    """A dead sensor: constant 0.0 (valid data: every order amplitude is 0)."""
    return Channel(data=np.zeros(8000), rpm=np.full(8000, 1500.0), truth={2.0: 0.0, 4.0: 0.0})


CHANNEL_CASES = {f.__name__: f for f in (
    channel_dropout_nan, channel_dropout_inf, channel_clipped, channel_zero_speed_segment,
    channel_negative_speed, channel_nan_speed, channel_speed_wrong_length, channel_too_short,
    channel_constant)}

SIGNALS = {**TACHO_CASES, **CHANNEL_CASES}


def main() -> int:
    for name, make in SIGNALS.items():
        s = make()
        data = s.edge_times if isinstance(s, Tacho) and s.edge_times is not None else (
            s.signal if isinstance(s, Tacho) else s.data)
        print(f"{name:36s} {data.size:7d} values  {make.__doc__.splitlines()[0]}")
    print(f"{len(SIGNALS)} bad signals")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
