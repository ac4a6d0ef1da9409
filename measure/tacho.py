"""Tacho and encoder pulse processing: edges, tooth counting, speed and crank angle.

A speed reference on a test bench is a train of pulses: a once-per-revolution mark, an
``N``-per-revolution gear or encoder, or a missing-tooth wheel (``60-2``: sixty pitch positions,
two teeth left out so the gap marks a fixed angle). This module turns them into

* edge times from an analogue pick-up signal (:func:`detect_edges`, from :mod:`measure.edges`:
  levels following the signal's envelope, hysteresis from its noise, sub-sample interpolation
  of the mid-level crossing),
* a cleaned, counted pulse train (:func:`count_pitches`: dropouts and spurious pulses repaired,
  missing-tooth gap located — or its width inferred — from the wheel positions that never hold
  an edge (:mod:`measure.wheel_layout`), every edge given its pitch number),
* speed against time (:func:`speed_from_pulses`) and crank angle against time
  (:func:`angle_from_pulses`), referenced to the gap or to a once-per-revolution mark and to top
  dead centre of cylinder 1.

Method and its error
--------------------
Each edge ``k`` sits at a known pitch count ``c_k`` (integer; ``2 pi c_k / N`` rad of rotation
since the first edge). Mean speed over a window of ``m`` pitches centred on edge ``k`` is
``(c_{k+m/2} - c_{k-m/2}) (2 pi / N) / (t_{k+m/2} - t_{k-m/2})``; it is assigned to the mid time
of the two end edges, where it is *exact* for constant angular acceleration. Remaining errors:

* edge timing error ``sigma_t`` (jitter, timer resolution, noise): ``sigma_omega / omega =
  sqrt(2) sigma_t / T_w`` with ``T_w`` the window duration;
* curvature of the speed curve: ``|omega''| T_w**2 / 24``;
* tooth-spacing errors (a gear is not perfect): cancel exactly when the window is a whole number
  of revolutions (the default, one revolution), not for per-tooth speed.

References
----------
Liang Shoupan, *Engine dynamics* (發動機動力學), 1948, ch. 9 "Vibration measurement" (感振儀,
振動記錄之分析): timing marks on records and speed from the record.
Jiaotong University, *IC-engine dynamics* (内燃机动力学), 1958, part 2 ch. 5 §1 (torsiograph
instruments, time marks and crank-angle marks on torsiograms).
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict._validate import (
    check_finite_array,
    check_int,
    check_positive,
    check_range,
)
from crankbench.predict.errors import AnalysisError

from .edges import detect_edges  # noqa: F401 - public here since issue 6
from .record import RecordWarning
from .wheel_layout import locate_gap

__all__ = [
    "detect_edges",
    "count_pitches",
    "PitchCount",
    "speed_from_pulses",
    "SpeedTrace",
    "angle_from_pulses",
    "AngleTrace",
    "pulse_channel_speed",
]

log = logging.getLogger("crankbench")

TWO_PI = 2.0 * np.pi


# --------------------------------------------------------------------------------------------
# pitch counting, repair and gap synchronisation
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PitchCount:
    """A pulse train with every edge given its pitch number.

    Attributes
    ----------
    edge_times : numpy.ndarray
        Edge times after removing spurious pulses, s.
    pitch : numpy.ndarray of int
        Pitch count of each edge: the edge is ``2 pi pitch / pulses_per_rev`` rad after the
        reference (the first tooth after the gap for a missing-tooth wheel, else the first edge);
        negative before the reference.
    pulses_per_rev : int
        Pitch positions per revolution (60 for a 60-2 wheel).
    missing_teeth : int
    reference_index : int or None
        Index (into ``edge_times``) of the first edge at pitch 0, None if it lies before the record.
    filled : int
        Missing pulses (dropouts) bridged by counting more than one pitch in an interval.
    removed : int
        Spurious pulses removed.
    gaps : numpy.ndarray of int
        Indices of the edges that end a missing-tooth gap.
    lost_teeth : tuple of int
        Teeth (numbered from the reference) that gave no edge in any revolution (bridged).
    notes : tuple of str
        What the decoding warned about (lost or weak teeth, an inferred layout).
    """

    edge_times: np.ndarray
    pitch: np.ndarray
    pulses_per_rev: int
    missing_teeth: int
    reference_index: int | None
    filled: int
    removed: int
    gaps: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=int))
    lost_teeth: tuple = ()
    notes: tuple = ()

    @property
    def angle(self) -> np.ndarray:
        """Angle of each edge from the reference, rad."""
        return self.pitch * (TWO_PI / self.pulses_per_rev)

    @property
    def tooth(self) -> np.ndarray:
        """Pitch position on the wheel (0 .. pulses_per_rev - 1) of each edge."""
        return np.mod(self.pitch, self.pulses_per_rev)

    def to_frame(self):
        """Edge table: ``time_s``, ``pitch``, ``tooth``, ``angle_deg``."""
        import pandas as pd

        return pd.DataFrame({"time_s": self.edge_times, "pitch": self.pitch,
                             "tooth": self.tooth, "angle_deg": np.degrees(self.angle)})

    def plot(self, ax=None):
        """Interval per pitch (s) against time, gaps marked; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        dt = np.diff(self.edge_times) / np.diff(self.pitch)
        ax.plot(self.edge_times[1:], dt, ".", ms=2)
        if self.gaps.size:
            ax.plot(self.edge_times[self.gaps], dt[self.gaps - 1], "rx", label="gap end")
            ax.legend()
        ax.set_xlabel("time (s)")
        ax.set_ylabel("time per pitch (s)")
        ax.set_title(f"{self.pulses_per_rev}-{self.missing_teeth} wheel: {self.filled} bridged, "
                     f"{self.removed} removed")
        return fig


def _local_pitch_time(dt, size=9):
    from scipy.ndimage import median_filter

    size = min(size, dt.size if dt.size % 2 else dt.size - 1)
    if size < 3:
        return np.full_like(dt, np.median(dt))
    return median_filter(dt, size=size, mode="mirror")


def count_pitches(edge_times, *, pulses_per_rev, missing_teeth=0, repair=True,
                  spurious_ratio=0.5, max_bridge_pitches=None):
    """Count pitches between edges, repair dropouts and spurious pulses, find the gap.

    Each interval is divided by the running median of its neighbours (nine intervals, robust to
    the gap and to single faults) and rounded to a whole number of pitches. A ratio below
    ``spurious_ratio`` marks an extra pulse: of the two edges bounding that interval, the one whose
    removal leaves a merged interval closest to a whole number of pitches is dropped. A rounded
    ratio of 2 or more counts the missing pitches, so a dropout does not shift the angle of the
    following edges. For a missing-tooth wheel the gap is the stretch of wheel positions the
    record passes without ever finding an edge there (:mod:`measure.wheel_layout`): it is found
    from a start anywhere in the revolution, never confused with dropouts it could tie with (an
    error says when the record is too short to tell), and a tooth beside it that never fires (a
    runt pulse) is recognised, bridged and named in a :class:`~measure.record.RecordWarning`.

    Parameters
    ----------
    edge_times : array_like
        Edge times, s, ascending.
    pulses_per_rev : int
        Pitch positions per revolution, counting the missing teeth (60 for a 60-2 wheel).
    missing_teeth : int or None
        Teeth left out to form the reference gap (0 for a plain gear or encoder); None infers
        it from the pitch pattern (the record must pass every position at least twice).
    repair : bool
        Remove spurious pulses (with ``False`` every interval must be at least half a pitch).
    spurious_ratio : float
        Interval/pitch ratio below which an interval is taken to contain a spurious pulse.
    max_bridge_pitches : int, optional
        Most consecutive missing pulses bridged (default ``max(pulses_per_rev, 8)``, besides
        the wheel's own gap); a longer silence is a stop or a lost signal, not a dropout.

    Returns
    -------
    PitchCount

    Raises
    ------
    AnalysisError
        Too few edges, non-increasing times, a silence longer than ``max_bridge_pitches``,
        more than 10 % of the intervals further than a quarter pitch from a whole number of
        pitches (too many faults to count reliably), or a gap that is not there, is wider than
        a lost tooth explains, or cannot be told from dropouts — with the numbers seen.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(200) / 1000.0                         # 60/rev at 1000 pulses/s
    >>> t = np.delete(t, [57, 58, 117, 118, 177, 178])      # a 60-2 wheel
    >>> t = np.delete(t, 30)                                 # and one dropout
    >>> pc = count_pitches(t[5:], pulses_per_rev=60, missing_teeth=2)
    >>> int(pc.filled), float(pc.edge_times[pc.reference_index]), int(pc.pitch[0])
    (1, 0.059, -54)
    >>> count_pitches(t[5:], pulses_per_rev=60, missing_teeth=None).missing_teeth
    2
    """
    t = check_finite_array(edge_times, "edge_times", ndim=1, error=AnalysisError)
    n_rev = check_int(pulses_per_rev, "pulses_per_rev", minimum=1, error=AnalysisError)
    missing = None if missing_teeth is None else check_int(
        missing_teeth, "missing_teeth", minimum=0, error=AnalysisError)
    if missing is not None and missing >= n_rev - 1 and n_rev > 1:
        raise AnalysisError(f"missing_teeth={missing} must be less than pulses_per_rev - 1 "
                            f"= {n_rev - 1}")
    if n_rev == 1:
        missing = 0
    spurious_ratio = check_range(spurious_ratio, "spurious_ratio", 0.05, 0.95,
                                 error=AnalysisError)
    if t.size < 3:
        raise AnalysisError(f"edge_times has {t.size} edges; at least 3 are needed")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.flatnonzero(dt <= 0)[0])
        raise AnalysisError(f"edge_times must increase strictly; edge {i + 1} "
                            f"({float(t[i + 1]):.9g} s) does not follow edge {i} "
                            f"({float(t[i]):.9g} s)")
    removed = 0
    if repair:
        t, removed = _remove_spurious(t, spurious_ratio)
        dt = np.diff(t)
    ref = _local_pitch_time(dt)
    if missing != 0:
        # the gap is longer than its neighbours: take the median of ordinary intervals only
        ref = _local_pitch_time(np.where(dt > 1.5 * ref, np.nan_to_num(ref), dt))
    ratio = dt / ref
    counts = np.maximum(np.rint(ratio).astype(np.int64), 1)
    limit = max(n_rev, 8) if max_bridge_pitches is None else check_int(
        max_bridge_pitches, "max_bridge_pitches", minimum=1, error=AnalysisError)
    widest_gap = missing if missing is not None else max(n_rev // 2, 1)
    long = np.flatnonzero(counts - 1 > limit + widest_gap)
    if long.size:
        i = int(long[0])
        raise AnalysisError(
            f"edge_times: no pulse for {float(dt[i]):.4g} s between {float(t[i]):.6g} s and "
            f"{float(t[i + 1]):.6g} s ({int(counts[i]) - 1} pitches missing at the local pulse "
            f"rate, more than max_bridge_pitches={limit}): the shaft stopped or the signal was "
            "lost; analyse the parts on either side separately")
    off = np.abs(ratio - np.rint(ratio)) > 0.25
    if ratio.size >= 10 and off.mean() > 0.1:
        raise AnalysisError(
            f"edge_times: {100 * off.mean():.0f} % of the pulse intervals are not whole numbers "
            "of pitches (more than a quarter pitch off the local pitch time): too many missing "
            "or spurious pulses to count reliably, an irregular wheel, or a wrong "
            f"pulses_per_rev={n_rev}/missing_teeth={missing}")
    if not repair and np.any(ratio < spurious_ratio):
        i = int(np.flatnonzero(ratio < spurious_ratio)[0])
        raise AnalysisError(f"interval {i} is {ratio[i]:.2f} of a pitch (spurious pulse?); "
                            "pass repair=True to remove spurious pulses")
    pitch = np.concatenate([[0], np.cumsum(counts)])
    gaps = np.empty(0, dtype=int)
    reference_index = 0
    notes, lost = (), ()
    gap_positions = np.zeros(n_rev, bool)
    if n_rev > 1:
        layout = locate_gap(pitch, counts, pulses_per_rev=n_rev, missing_teeth=missing,
                            n_edges=t.size)
        missing, notes, lost = layout.missing_teeth, layout.notes, layout.lost
        if layout.phase is not None:
            phase = layout.phase
            pos = np.mod(pitch, n_rev)
            gaps = np.flatnonzero((pos[1:] == phase) & (counts >= layout.width + 1)) + 1
            if gaps.size:
                first_ref = int(pitch[gaps[0]])
                reference_index = int(gaps[0])
            else:  # no gap seen whole: the first edge at the reference position
                first_ref = int(pitch[0]) + int(np.mod(phase - pitch[0], n_rev))
                hit = np.flatnonzero(pitch == first_ref)
                reference_index = int(hit[0]) if hit.size else None
            pitch = pitch - first_ref
            gap_positions[np.mod(np.arange(n_rev - layout.width, n_rev), n_rev)] = True
    filled, notes = _bridged(pitch, counts, n_rev, gap_positions, lost, notes)
    for note in notes:
        warnings.warn(f"tacho: {note}", RecordWarning, stacklevel=3)
    if filled:
        log.info("tacho: %d missing pulse(s) bridged, %d spurious removed", filled, removed)
    return PitchCount(edge_times=t, pitch=pitch.astype(np.int64), pulses_per_rev=n_rev,
                      missing_teeth=missing, reference_index=reference_index, filled=filled,
                      removed=removed, gaps=gaps, lost_teeth=tuple(lost), notes=tuple(notes))


def _bridged(pitch, counts, n_rev, gap_positions, lost, notes):
    """Pitches bridged as dropouts (gap positions excluded) and a note where they pile up."""
    multi = np.flatnonzero(counts > 1)
    if multi.size == 0:
        return 0, notes
    c = counts[multi]
    starts = np.repeat(pitch[multi], c - 1) + (np.arange(int((c - 1).sum()))
                                               - np.repeat(np.cumsum(c - 1) - (c - 1), c - 1))
    skipped = np.mod(starts + 1, n_rev)
    skipped = skipped[~gap_positions[skipped]]
    filled = int(skipped.size)
    if n_rev > 1 and filled:
        per = np.bincount(skipped, minlength=n_rev)
        revs = (int(pitch[-1]) - int(pitch[0])) / n_rev
        weak = np.flatnonzero((per >= max(3.0, 0.5 * revs)) & (per > 5.0 * per.mean() + 2.0))
        weak = [int(k) for k in weak if int(k) not in lost]
        if weak:
            text = ", ".join(f"{k} ({per[k]} times)" for k in weak[:5])
            notes = tuple(notes) + (
                f"dropouts pile up at tooth {text} of {revs:.0f} revolutions (a weak or runt "
                "tooth, counting the first after the gap as 0): bridged, but check the "
                "pick-up and the trigger level",)
    return filled, notes


def _remove_spurious(t, spurious_ratio):
    removed = 0
    for _ in range(t.size):
        dt = np.diff(t)
        ratio = dt / _local_pitch_time(dt)
        short = np.flatnonzero(ratio < spurious_ratio)
        if short.size == 0:
            break
        i = int(short[0])  # interval between edges i and i+1
        # candidate merges: drop edge i (joins intervals i-1, i) or edge i+1 (joins i, i+1)
        err_a = abs(ratio[i - 1] + ratio[i] - np.rint(ratio[i - 1] + ratio[i])) if i > 0 else np.inf
        err_b = (abs(ratio[i] + ratio[i + 1] - np.rint(ratio[i] + ratio[i + 1]))
                 if i + 1 < ratio.size else np.inf)
        drop = i if err_a < err_b else i + 1
        if not np.isfinite(min(err_a, err_b)):
            drop = i + 1 if i + 1 < t.size - 1 else i
        t = np.delete(t, drop)
        removed += 1
        if t.size < 3:
            raise AnalysisError("edge_times: almost every pulse looks spurious; "
                                "check the edge detection")
    return t, removed


# --------------------------------------------------------------------------------------------
# speed
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SpeedTrace:
    """Rotational speed against time from pulse timing.

    Unpacks as ``t, omega = speed_from_pulses(...)``.

    Attributes
    ----------
    time : numpy.ndarray
        Times the speeds apply to, s.
    omega : numpy.ndarray
        Angular speed, rad/s.
    window_pitches : int
        Pitches averaged per value (``pulses_per_rev`` = one revolution; 1 = per tooth).
    timing_error_s : float
        Upper estimate of the edge-timing error (jitter, quantisation, tooth errors), s rms,
        from the second differences of the edge times (NaN, with a logged warning, for fewer
        than 5 edges).
    error_rpm : float
        Upper estimate of the rms speed error, rpm, at the median speed:
        ``sqrt(2) sigma_t / T_w * n`` (the gain of ``smoothing_revs`` is not counted, since
        edge-interpolation errors are correlated between neighbouring edges).
    method : str
    """

    time: np.ndarray
    omega: np.ndarray
    window_pitches: int
    timing_error_s: float
    error_rpm: float
    method: str = "centred difference of pitch angle over edge times"

    def __iter__(self):
        return iter((self.time, self.omega))

    def __len__(self):
        return 2

    @property
    def speed_rpm(self) -> np.ndarray:
        """Speed, rpm."""
        return self.omega * (60.0 / TWO_PI)

    def at(self, t):
        """Speed (rad/s) interpolated linearly at times ``t`` (s), clamped at the ends."""
        return np.interp(np.asarray(t, dtype=float), self.time, self.omega)

    def to_frame(self):
        """Table with ``time_s``, ``omega_rad_s``, ``speed_rpm``."""
        import pandas as pd

        return pd.DataFrame({"time_s": self.time, "omega_rad_s": self.omega,
                             "speed_rpm": self.speed_rpm})

    def plot(self, ax=None):
        """Speed (rpm) against time; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        ax.plot(self.time, self.speed_rpm)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("speed (rpm)")
        ax.set_title(f"speed from pulses (window {self.window_pitches} pitches)")
        return fig


def speed_from_pulses(edge_times, *, pulses_per_rev, missing_teeth=0, window_revs=1.0,
                      smoothing_revs=1.0, repair=True):
    """Speed against time from tacho/encoder edge times.

    Parameters
    ----------
    edge_times : array_like
        Edge times, s (e.g. from :func:`detect_edges` or a pulse channel of a Record).
    pulses_per_rev : int
        Pitch positions per revolution (1 for a once-per-rev mark; 60 for a 60-2 wheel).
    missing_teeth : int
        Teeth missing from the wheel (its gap); the gap is counted as ``missing_teeth + 1``
        pitches.
    window_revs : float
        Averaging window in revolutions, rounded to whole pitches (at least 1). The default, one
        revolution, cancels tooth-spacing errors and every integer order of torsional vibration
        (half orders are attenuated but not removed; use 2 for a four-stroke cycle). Use a
        small value (``1 / pulses_per_rev`` = per tooth, with ``smoothing_revs=0``) for the
        instantaneous speed.
    smoothing_revs : float
        The window speeds are then averaged (with their mid times) over window starts spanning
        this many revolutions (0 = no averaging). Averaging keeps the result exact for constant
        acceleration and still cancels tooth-spacing errors, while dividing the random
        edge-timing error by about ``sqrt(edges averaged)``; it widens the time support to
        ``window_revs + smoothing_revs`` revolutions and drops that much at the record ends.
    repair : bool
        Bridge dropouts and remove spurious pulses (see :func:`count_pitches`).

    Returns
    -------
    SpeedTrace
        ``time`` (s, mid-time of each window) and ``omega`` (rad/s); unpacks as
        ``(t, omega)``. The value is exact for constant angular acceleration; see the module
        docstring for the error terms, and ``error_rpm`` for the timing-error part.

    References
    ----------
    Jiaotong University, *IC-engine dynamics*, 1958, part 2 ch. 5 §1 (time and angle marks).

    Examples
    --------
    >>> import numpy as np
    >>> omega0, alpha = 100.0, 20.0                    # rad/s, rad/s^2: a run-up
    >>> theta = np.arange(1, 600) * (2 * np.pi / 60)   # 60 pulses/rev
    >>> t = (-omega0 + np.sqrt(omega0**2 + 2 * alpha * theta)) / alpha
    >>> tt, w = speed_from_pulses(t, pulses_per_rev=60)
    >>> float(np.max(np.abs(w - (omega0 + alpha * tt))))  < 1e-9
    True
    """
    window_revs = check_positive(window_revs, "window_revs", error=AnalysisError)
    pc = count_pitches(edge_times, pulses_per_rev=pulses_per_rev, missing_teeth=missing_teeth,
                       repair=repair)
    t, pitch = pc.edge_times, pc.pitch
    n_rev = pc.pulses_per_rev
    width = max(1, int(round(window_revs * n_rev)))
    if pitch[-1] - pitch[0] < width:
        raise AnalysisError(f"edge_times span {pitch[-1] - pitch[0]} pitches, fewer than the "
                            f"averaging window of {width} pitches (window_revs={window_revs})")
    # pair each edge k with the first edge at least `width` pitches later (gaps, dropouts)
    j = np.searchsorted(pitch, pitch + width, side="left")
    ok = j < t.size
    k = np.flatnonzero(ok)
    j = j[ok]
    dtheta = (pitch[j] - pitch[k]) * (TWO_PI / n_rev)
    span = t[j] - t[k]
    omega = dtheta / span
    tm = 0.5 * (t[j] + t[k])
    sigma_t = _timing_error(t, pitch)
    t_w = float(np.median(span))
    err = float(np.sqrt(2.0) * sigma_t / t_w * np.median(omega) * 60.0 / TWO_PI)
    smoothing_revs = check_range(smoothing_revs, "smoothing_revs", 0.0, None,
                                 error=AnalysisError)
    edges_per_rev = max(1, n_rev - pc.missing_teeth)
    length = int(round(smoothing_revs * edges_per_rev))
    if length > 1:
        if omega.size <= length:
            raise AnalysisError(f"edge_times span too few pitches for window_revs={window_revs}"
                                f" plus smoothing_revs={smoothing_revs}")
        omega = _moving_mean(omega, length)
        tm = _moving_mean(tm, length)
        # averaging divides white timing noise by ~sqrt(L/2), but interpolation errors of
        # sampled edges are correlated; the unsmoothed figure is kept as the upper estimate
    return SpeedTrace(time=tm, omega=omega, window_pitches=width, timing_error_s=sigma_t,
                      error_rpm=err)


def _moving_mean(x, length):
    c = np.concatenate([[0.0], np.cumsum(x - x[0])])
    return (c[length:] - c[:-length]) / length + x[0]


def _timing_error(t, pitch):
    """Robust upper estimate of the per-edge timing error from second differences, s rms.

    NaN (with a warning) for fewer than 5 edges: no second differences to estimate from.
    """
    if t.size < 5:
        log.warning("speed_from_pulses: %d edges are too few to estimate the timing error; "
                    "timing_error_s and error_rpm are NaN", t.size)
        return float("nan")
    dt = np.diff(t) / np.diff(pitch)  # per-pitch time
    d2 = np.diff(dt)
    # second difference of edge times: variance 6 sigma^2 for white timing noise
    mad = np.median(np.abs(d2 - np.median(d2)))
    return float(mad / 0.6745 / np.sqrt(6.0))


# --------------------------------------------------------------------------------------------
# crank angle
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AngleTrace:
    """Crank angle against time at the pulse edges.

    Attributes
    ----------
    time : numpy.ndarray
        Edge times, s.
    angle : numpy.ndarray
        Crank angle of cylinder 1 from its top dead centre, rad, cumulative (not wrapped):
        0 at the first TDC at or after the reference, ``2 pi`` one revolution later.
    pulses_per_rev : int
    reference : str
        What defined the zero: "gap", "reference mark" or "first edge".
    tdc_offset : float
        Angle from the reference to TDC of cylinder 1 in the direction of rotation, rad.
    """

    time: np.ndarray
    angle: np.ndarray
    pulses_per_rev: int
    reference: str
    tdc_offset: float

    def at(self, t):
        """Crank angle (rad) at times ``t`` (s) by cubic interpolation between edges.

        Outside the edges the angle is extrapolated from the nearest end at the end speed.
        The interpolation error is of order ``|omega''| dt**3 / 12`` per pitch time ``dt``.
        """
        from scipy.interpolate import CubicSpline

        t = np.asarray(t, dtype=float)
        spline = CubicSpline(self.time, self.angle, bc_type="not-a-knot", extrapolate=False)
        out = spline(t)
        w0 = (self.angle[1] - self.angle[0]) / (self.time[1] - self.time[0])
        w1 = (self.angle[-1] - self.angle[-2]) / (self.time[-1] - self.time[-2])
        before, after = t < self.time[0], t > self.time[-1]
        out = np.where(before, self.angle[0] + w0 * (t - self.time[0]), out)
        out = np.where(after, self.angle[-1] + w1 * (t - self.time[-1]), out)
        return out

    def wrapped_deg(self, cycle_deg=360.0):
        """Angle in degrees wrapped to ``[0, cycle_deg)``."""
        return np.mod(np.degrees(self.angle), cycle_deg)

    def to_frame(self):
        """Table with ``time_s``, ``angle_deg`` (cumulative)."""
        import pandas as pd

        return pd.DataFrame({"time_s": self.time, "angle_deg": np.degrees(self.angle)})

    def plot(self, ax=None):
        """Wrapped crank angle (deg) against time; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        ax.plot(self.time, self.wrapped_deg(), ".", ms=2)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("crank angle from TDC 1 (deg)")
        return fig


def angle_from_pulses(edge_times, *, pulses_per_rev, missing_teeth=0, reference_times=None,
                      tdc_offset_deg=0.0, repair=True):
    """Crank angle from TDC of cylinder 1 against time, from tacho/encoder edges.

    The zero is taken from, in order of preference: a separate once-per-revolution reference
    mark (``reference_times``), the gap of a missing-tooth wheel (the first tooth after the gap
    is at the reference), or the first edge. ``tdc_offset_deg`` then moves it to TDC of
    cylinder 1 (the angle by which TDC follows the reference mark in the direction of rotation).
    The record start can fall anywhere in a revolution: angles before the first reference come
    out negative.

    Parameters
    ----------
    edge_times : array_like
        Edge times, s.
    pulses_per_rev : int
        Pitch positions per revolution (including missing teeth).
    missing_teeth : int
        Teeth missing to form the gap.
    reference_times : array_like, optional
        Times of a once-per-revolution mark, s. The encoder angle interpolated at the first mark
        becomes the reference; the others are checked to lie whole revolutions later (a
        warning is logged if one is more than 2 % of a revolution off).
    tdc_offset_deg : float
        Angle from the reference to TDC of cylinder 1, degrees in the direction of rotation.
    repair : bool
        Bridge dropouts and remove spurious pulses.

    Returns
    -------
    AngleTrace

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(300) / 1500.0                  # 60 pitches/rev at 1500 rpm
    >>> keep = np.mod(np.arange(300) + 13, 60) < 58  # 60-2, record starts 13 teeth in
    >>> trace = angle_from_pulses(t[keep], pulses_per_rev=60, missing_teeth=2,
    ...                           tdc_offset_deg=90.0)
    >>> round(float(np.degrees(trace.at(0.0))), 6)    # -(47 teeth * 6 deg) - 90 deg
    -372.0
    """
    tdc_offset = np.radians(check_range(tdc_offset_deg, "tdc_offset_deg", -720.0, 720.0,
                                        error=AnalysisError))
    pc = count_pitches(edge_times, pulses_per_rev=pulses_per_rev, missing_teeth=missing_teeth,
                       repair=repair)
    angle = pc.angle.astype(float)
    reference = "gap" if pc.missing_teeth else "first edge"
    if reference_times is not None:
        ref = check_finite_array(reference_times, "reference_times", ndim=1, min_length=1,
                                 error=AnalysisError)
        if pc.edge_times.size < 4:
            raise AnalysisError("angle_from_pulses needs at least 4 edges to interpolate the "
                                "reference mark")
        trace = AngleTrace(pc.edge_times, angle, pc.pulses_per_rev, reference, 0.0)
        inside = ref[(ref >= pc.edge_times[0]) & (ref <= pc.edge_times[-1])]
        if inside.size == 0:
            raise AnalysisError("reference_times: no mark falls within the edge times "
                                f"[{pc.edge_times[0]:g}, {pc.edge_times[-1]:g}] s")
        at_marks = trace.at(inside)
        angle = angle - at_marks[0]
        revs = (at_marks - at_marks[0]) / TWO_PI
        off = np.abs(revs - np.rint(revs))
        if off.size > 1 and off.max() > 0.02:
            log.warning("reference_times: mark %d is %.1f%% of a revolution away from a whole "
                        "number of revolutions after the first mark", int(np.argmax(off)),
                        100 * off.max())
        reference = "reference mark"
    return AngleTrace(time=pc.edge_times, angle=angle - tdc_offset,
                      pulses_per_rev=pc.pulses_per_rev, reference=reference,
                      tdc_offset=float(tdc_offset))


def pulse_channel_speed(var, *, window_revs=1.0, smoothing_revs=1.0):
    """Crankshaft speed from a Record's pulse-train channel, its attrs read for the layout.

    ``pulses_per_rev`` and ``missing_teeth`` (None/absent: 0) describe the wheel; ``speed_ratio``
    (default 1) is the turns of the pulse source per crankshaft turn — 0.5 for a mark once per
    four-stroke cycle, which turns with the camshaft — and divides the wheel's speed.

    Parameters
    ----------
    var : xarray.DataArray
        Edge times (s) with the attrs above.
    window_revs, smoothing_revs : float
        As in :func:`speed_from_pulses`.

    Returns
    -------
    SpeedTrace
        Crankshaft speed (rad/s) at the window mid times.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> marks = xr.DataArray(np.arange(40) * 0.1, dims="pulse",
    ...                      attrs={"pulses_per_rev": 1, "speed_ratio": 0.5})
    >>> round(float(pulse_channel_speed(marks, smoothing_revs=0).speed_rpm[0]), 6)
    1200.0
    """
    ppr = var.attrs.get("pulses_per_rev")
    if ppr is None:
        raise AnalysisError(f"pulse channel {var.name!r} has no 'pulses_per_rev' attr")
    missing = var.attrs.get("missing_teeth", 0)
    ratio = float(var.attrs.get("speed_ratio", 1.0))
    if not np.isfinite(ratio) or ratio <= 0:
        raise AnalysisError(f"pulse channel {var.name!r}: speed_ratio={ratio!r}; expected > 0")
    trace = speed_from_pulses(np.asarray(var.values, dtype=float), pulses_per_rev=int(ppr),
                              missing_teeth=None if missing is None else int(missing),
                              window_revs=window_revs, smoothing_revs=smoothing_revs)
    if ratio == 1.0:
        return trace
    return SpeedTrace(time=trace.time, omega=trace.omega / ratio,
                      window_pitches=trace.window_pitches,
                      timing_error_s=trace.timing_error_s, error_rpm=trace.error_rpm / ratio,
                      method=trace.method + f", divided by speed_ratio {ratio:g}")
