"""Torsiograph from pulse timing: angular vibration from encoder, gear or zebra-tape edges.

A shaft turning at mean speed with a superposed angular vibration ``phi`` passes each tooth
(stripe, encoder line) a little early or late. With the edge times ``t_k`` and the angles
``theta_k`` of the teeth, the angular vibration at the edges is ``phi_k = theta_k - xbar(t_k)``,
``xbar`` being the mean (slowly varying) rotation. This module estimates the mean motion
``xbar`` from block averages over whole revolutions (the vibration averages out over a period)
and fits, block by block,

``theta_k - xbar(t_k) = c_0 + sum_q [C_q cos(q x_k) + S_q sin(q x_k)]``,  ``x_k = xbar(t_k)``,

so each order is measured against the mean-motion angle, not against the vibrating shaft angle
(which would fold ``q A**2`` products into the sum and difference orders).

Errors
------
* Edge timing error ``sigma_t`` (timer resolution ``1/(f_timer sqrt 12)``, jitter, sampled
  edges): angle error ``omega sigma_t`` per edge; each order coefficient then has a standard
  deviation ``omega sigma_t sqrt(2 / M)`` for ``M`` edges per block (:func:`error_floor`).
* Tooth-spacing errors ``e_j`` (pitch errors of a gear, a zebra tape's butt joint, encoder
  eccentricity) repeat every revolution and appear as false *integer* orders. They are removed
  with a :class:`ToothCalibration` (:func:`calibrate_teeth`, :func:`butt_joint_calibration`).
* With a per-block mean-motion polynomial (``mean_motion="block"``) the lowest orders are
  partly collinear with it and their noise is inflated (about 3x for order ``1/B``);
  ``amplitude_std`` in the result carries the exact figure from the least-squares covariance.
* A mean motion that changes within a block faster than a cubic spline through the block
  points can follow (a run-up much faster than one block) leaves a small bias in the lowest
  orders.
* Orders above ``max_order`` are not modelled; their energy stays in the residual (reported as
  ``residual_rms``) and, above the Nyquist order ``pulses_per_rev / 2``, aliases.

References
----------
Jiaotong University, *IC-engine dynamics* (内燃机动力学), 1958, part 2 ch. 5 §1 "Instruments for
measuring torsional vibration" and §2 "Use of torsiograms" (order content of a torsiogram).
Liang Shoupan, *Engine dynamics* (發動機動力學), 1948, ch. 9 §"振動記錄之分析" (harmonic analysis
of a vibration record).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict._threads import single_threaded_blas
from crankbench.predict._validate import (check_finite_array, check_int, check_option,
                               check_positive)
from crankbench.predict.errors import AnalysisError

from .tacho import SpeedTrace, count_pitches
from .torsiograph_floor import ErrorFloor, error_floor

__all__ = [
    "ToothCalibration",
    "calibrate_teeth",
    "butt_joint_calibration",
    "instantaneous_speed",
    "angular_vibration",
    "TorsiographResult",
    "error_floor",
    "ErrorFloor",
]

log = logging.getLogger("crankbench")

TWO_PI = 2.0 * np.pi


# --------------------------------------------------------------------------------------------
# synchronised pitch numbering
# --------------------------------------------------------------------------------------------
def _sync(edge_times, pulses_per_rev, missing_teeth, reference_times, butt_joint, repair):
    """Return (times, pitch, sync) with pitch 0 at the wheel's reference where there is one."""
    n = check_int(pulses_per_rev, "pulses_per_rev", minimum=2, error=AnalysisError)
    if butt_joint:
        if missing_teeth:
            raise AnalysisError("butt_joint=True describes a zebra tape; it cannot also have "
                                f"missing_teeth={missing_teeth}")
        t = check_finite_array(edge_times, "edge_times", ndim=1, min_length=2 * n + 1,
                               error=AnalysisError)
        if np.any(np.diff(t) <= 0):
            raise AnalysisError("edge_times must increase strictly")
        k0 = _find_joint(t, n)
        return t, np.arange(t.size) - k0, "butt joint"
    pc = count_pitches(edge_times, pulses_per_rev=n, missing_teeth=missing_teeth, repair=repair)
    t, pitch = pc.edge_times, pc.pitch
    sync = "gap" if missing_teeth else "first edge"
    if reference_times is not None:
        ref = check_finite_array(reference_times, "reference_times", ndim=1, min_length=1,
                                 error=AnalysisError)
        inside = ref[(ref >= t[0]) & (ref <= t[-1])]
        if inside.size == 0:
            raise AnalysisError("reference_times: no mark falls within the edge times")
        # pitch 0 = first edge at or after the first mark
        k = int(np.searchsorted(t, inside[0]))
        pitch = pitch - pitch[k]
        sync = "reference mark"
    return t, pitch, sync


def _find_joint(t, n):
    """Index of the edge that ends the butt-joint interval (the odd pitch of a zebra tape)."""
    dt = np.diff(t)
    revs = dt.size // n
    # compare each interval with its two neighbours (robust to speed change)
    nb = np.empty_like(dt)
    nb[1:-1] = 0.5 * (dt[:-2] + dt[2:])
    nb[0], nb[-1] = dt[1], dt[-2]
    dev = np.abs(np.log(dt / nb))[: revs * n].reshape(revs, n).mean(axis=0)
    j = int(np.argmax(dev))
    others = np.delete(dev, [j, (j - 1) % n, (j + 1) % n])
    if dev[j] < 3 * (np.median(others) + 1e-12):
        log.warning("butt joint: the odd pitch is not distinct (deviation %.2g vs %.2g of the "
                    "others); the joint position may be wrong", dev[j], np.median(others))
    return j + 1


# --------------------------------------------------------------------------------------------
# tooth-spacing calibration
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ToothCalibration:
    """Actual angles of the teeth (stripes, encoder lines) of a pulse wheel.

    Attributes
    ----------
    pulses_per_rev : int
    missing_teeth : int
    error : numpy.ndarray, shape (pulses_per_rev,)
        Angle of each pitch position minus its nominal ``2 pi j / N``, rad (0 at the reference
        tooth j = 0; NaN at missing teeth).
    scatter : numpy.ndarray
        Standard error of each ``error`` value, rad (scatter over revolutions / sqrt(revs)).
    n_revs : int
        Revolutions averaged.
    sync : str
        How tooth 0 is found in a record: "gap", "reference mark", "butt joint", or "first edge"
        (valid only for the record the calibration was taken from).
    excluded_orders : tuple of float
        Integer orders left out of the correction (genuine vibration lives there).
    consistency : float
        rms difference between the estimates from the low-speed and high-speed halves of the
        calibration record divided by its expected value from the scatter; about 1 when the
        per-tooth residuals are speed-independent (tooth errors), much larger when vibration
        contaminates the calibration. NaN if the record has too few revolutions.
    method : str
    """

    pulses_per_rev: int
    missing_teeth: int
    error: np.ndarray
    scatter: np.ndarray
    n_revs: int
    sync: str
    excluded_orders: tuple = ()
    consistency: float = float("nan")
    method: str = "per-tooth mean residual against once-per-revolution mean motion"

    @property
    def tooth_angle(self) -> np.ndarray:
        """Actual angle of each pitch position from tooth 0, rad (missing teeth nominal)."""
        nominal = np.arange(self.pulses_per_rev) * TWO_PI / self.pulses_per_rev
        return nominal + np.nan_to_num(self.error)

    def angles(self, pitch) -> np.ndarray:
        """Actual angle (rad) of edges with the given pitch counts."""
        pitch = np.asarray(pitch)
        rev, tooth = np.divmod(pitch, self.pulses_per_rev)
        return rev * TWO_PI + self.tooth_angle[tooth]

    def to_frame(self):
        """Table: ``tooth``, ``error_deg``, ``scatter_deg``."""
        import pandas as pd

        return pd.DataFrame({"tooth": np.arange(self.pulses_per_rev),
                             "error_deg": np.degrees(self.error),
                             "scatter_deg": np.degrees(self.scatter)})

    def plot(self, ax=None):
        """Tooth-spacing error (deg) per tooth with its standard error; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        ax.errorbar(np.arange(self.pulses_per_rev), np.degrees(self.error),
                    yerr=np.degrees(self.scatter), fmt=".")
        ax.set_xlabel("tooth")
        ax.set_ylabel("angle error (deg)")
        ax.set_title(f"tooth calibration ({self.n_revs} revs, sync: {self.sync})")
        return fig


@single_threaded_blas  # many small least-squares fits (issue 21)
def calibrate_teeth(edge_times, *, pulses_per_rev, missing_teeth=0, reference_times=None,
                    exclude_orders=(), repair=True):
    """Tooth-spacing errors of a pulse wheel from a calibration record.

    Every revolution, tooth 0 (the reference) is passed at times ``T_r``; a cubic spline through
    ``(T_r, 2 pi r)`` is the mean motion, free of tooth errors because the same tooth defines
    every point. The residual of each edge against it, averaged per tooth over the revolutions,
    is minus the tooth's angle error.

    **What this assumes.** The tooth errors are fixed in angle and identical at every speed,
    whereas the torsional vibration changes amplitude and phase with speed and load. The
    average then converges to the tooth errors when the vibration in the calibration record is
    small (a coast-down with the fuel cut off, motoring, a low-load run away from criticals) or
    when its phase wanders over the record. A calibration taken from the record under analysis
    would otherwise contain the mean synchronous vibration at integer orders and subtract it,
    wiping out genuine orders: in that case list the engine's excited integer orders in
    ``exclude_orders`` (their components are left out of the correction, so those orders are
    measured uncorrected), and check ``consistency``: the estimates from the low- and high-speed
    halves of the record must agree within their scatter. Half orders are never touched (a tooth
    error repeats every revolution).

    Parameters
    ----------
    edge_times : array_like
        Edge times of the calibration record, s (several hundred revolutions is typical).
    pulses_per_rev : int
        Pitch positions per revolution.
    missing_teeth : int
        Teeth missing to form the gap (sync to the gap).
    reference_times : array_like, optional
        Once-per-revolution mark times, s (sync to the mark).
    exclude_orders : sequence of int
        Integer orders of the tooth-error pattern not to correct.
    repair : bool
        Bridge dropouts and remove spurious pulses first.

    Returns
    -------
    ToothCalibration

    Examples
    --------
    >>> import numpy as np
    >>> n = 36
    >>> err = 0.001 * np.sin(np.arange(n))                  # rad, a fixed pattern
    >>> err -= err[0]
    >>> teeth = np.arange(n) * 2 * np.pi / n + err
    >>> theta = (np.arange(200)[:, None] * 2 * np.pi + teeth).ravel()
    >>> cal = calibrate_teeth(theta / 100.0, pulses_per_rev=n)   # 100 rad/s, no vibration
    >>> float(np.max(np.abs(cal.error - err))) < 1e-12
    True
    """
    t, pitch, sync = _sync(edge_times, pulses_per_rev, missing_teeth, reference_times, False,
                           repair)
    n = int(pulses_per_rev)
    residual, rev_of_edge, tooth, rev_speed = _residual_against_tooth0(t, pitch, n)
    n_revs = int(rev_of_edge.max() - rev_of_edge.min() + 1) if rev_of_edge.size else 0
    if n_revs < 4:
        raise AnalysisError(f"calibration record spans {n_revs} whole revolution(s) between "
                            "reference teeth; at least 4 are needed")
    error, scatter = _per_tooth_mean(-residual, tooth, n)
    # consistency: low-speed half vs high-speed half of the revolutions
    consistency = float("nan")
    if n_revs >= 8:
        slow_half = np.zeros(rev_speed.size, dtype=bool)
        slow_half[np.argsort(rev_speed, kind="stable")[: rev_speed.size // 2]] = True
        low = slow_half[rev_of_edge - rev_of_edge.min()]
        e_lo, s_lo = _per_tooth_mean(-residual[low], tooth[low], n)
        e_hi, s_hi = _per_tooth_mean(-residual[~low], tooth[~low], n)
        ok = np.isfinite(e_lo) & np.isfinite(e_hi) & (np.arange(n) != 0)
        expected = np.sqrt(np.mean(s_lo[ok] ** 2 + s_hi[ok] ** 2))
        diff = np.sqrt(np.mean((e_lo[ok] - e_hi[ok]) ** 2))
        consistency = float(diff / expected) if expected > 0 else float("inf")
        if consistency > 3:
            log.warning("tooth calibration: per-tooth residuals differ between low and high "
                        "speed by %.1f times their scatter; the record's vibration is "
                        "contaminating the calibration (see exclude_orders)", consistency)
    excluded = tuple(int(check_int(q, "exclude_orders[]", minimum=1)) for q in exclude_orders)
    if excluded:
        error = _remove_orders(error, excluded, n)
    if missing_teeth:
        error[n - missing_teeth:] = np.nan
        scatter[n - missing_teeth:] = np.nan
    return ToothCalibration(pulses_per_rev=n, missing_teeth=int(missing_teeth), error=error,
                            scatter=scatter, n_revs=n_revs, sync=sync, excluded_orders=excluded,
                            consistency=consistency)


def _residual_against_tooth0(t, pitch, n):
    from scipy.interpolate import CubicSpline

    rev, tooth = np.divmod(pitch, n)
    ref = tooth == 0
    t_ref, r_ref = t[ref], rev[ref]
    if t_ref.size < 2:
        raise AnalysisError("calibration: fewer than two passes of the reference tooth")
    spline = CubicSpline(t_ref, r_ref * TWO_PI)
    inside = (t >= t_ref[0]) & (t < t_ref[-1])
    nominal = pitch * (TWO_PI / n)
    residual = nominal[inside] - spline(t[inside])
    rev_speed = TWO_PI / np.diff(t_ref)
    return residual, rev[inside], tooth[inside], rev_speed


def _per_tooth_mean(values, tooth, n):
    count = np.bincount(tooth, minlength=n).astype(float)
    total = np.bincount(tooth, weights=values, minlength=n)
    sq = np.bincount(tooth, weights=values**2, minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        var = np.where(count > 1, (sq - count * mean**2) / np.maximum(count - 1, 1), np.nan)
        scatter = np.sqrt(np.maximum(var, 0.0) / np.maximum(count, 1))
    mean[0], scatter[0] = 0.0, 0.0  # tooth 0 defines the angle
    return mean, scatter


def _remove_orders(error, orders, n):
    """Subtract the least-squares components of the given integer orders (present teeth)."""
    j = np.arange(n)
    ok = np.isfinite(error)
    cols = [np.ones(n)]
    for q in orders:
        cols += [np.cos(TWO_PI * q * j / n), np.sin(TWO_PI * q * j / n)]
    a = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(a[ok], error[ok], rcond=None)
    out = error.copy()
    out[ok] = error[ok] - a[ok, 1:] @ coef[1:]
    return out - out[0]


@single_threaded_blas  # many small least-squares fits (issue 21)
def butt_joint_calibration(edge_times, *, pulses_per_rev):
    """Zebra-tape butt-joint correction from the record itself.

    A zebra tape glued round a shaft has ``N`` equal stripes except at the butt joint, where the
    tape ends meet and one pitch is longer or shorter. The joint is the pitch position whose
    interval deviates most from its neighbours, consistently every revolution; edge 0 is the
    one ending it. With the other ``N - 1`` pitches equal, the joint's angular fraction of a
    revolution follows from each passage as ``f = rho / (1 + rho)``, ``rho = dt_joint / ((N-1)
    dt_neighbours)`` (neighbour intervals averaged either side, exact for constant
    acceleration), averaged over revolutions.

    Assumes: the stripes other than the joint are equal (print accuracy), and the vibration's
    slope over one pitch averages out over the revolutions (a steady vibration at an integer
    order biases ``f`` by about ``q A / N``; much smaller than a typical joint error).

    Parameters
    ----------
    edge_times : array_like
        Edge times, s, of a record of at least two revolutions without dropouts.
    pulses_per_rev : int
        Stripes (edges) per revolution.

    Returns
    -------
    ToothCalibration
        With ``sync="butt joint"``; use ``butt_joint=True`` in :func:`angular_vibration`.

    Examples
    --------
    >>> import numpy as np
    >>> n, f = 40, 1.3 / 40                            # joint pitch 1.3 nominal pitches
    >>> p = (1 - f) / (n - 1) * 2 * np.pi
    >>> teeth = np.arange(n) * p                       # edge 0 ends the joint
    >>> theta = (np.arange(50)[:, None] * 2 * np.pi + teeth).ravel()[7:]
    >>> cal = butt_joint_calibration(theta / 80.0, pulses_per_rev=n)
    >>> round(float(np.degrees(cal.error[-1])), 6)     # 39 pitches of 8.930769 deg, not 9 deg
    -2.7
    """
    n = check_int(pulses_per_rev, "pulses_per_rev", minimum=3)
    t, pitch, sync = _sync(edge_times, n, 0, None, True, False)
    dt = np.diff(t)
    joint = np.flatnonzero(np.mod(pitch[1:], n) == 0)  # interval ending at tooth 0
    joint = joint[(joint >= 1) & (joint + 1 < dt.size)]
    if joint.size == 0:
        raise AnalysisError("butt joint: the record has no joint passage with neighbours")
    rho = dt[joint] / ((n - 1) * 0.5 * (dt[joint - 1] + dt[joint + 1]))
    f = rho / (1 + rho)
    frac = float(np.mean(f))
    pitch_angle = (1 - frac) * TWO_PI / (n - 1)
    j = np.arange(n)
    error = j * pitch_angle - j * TWO_PI / n
    scatter = j * (TWO_PI / (n - 1)) * (np.std(f, ddof=1) / np.sqrt(f.size) if f.size > 1
                                         else np.nan)
    return ToothCalibration(pulses_per_rev=n, missing_teeth=0, error=error, scatter=scatter,
                            n_revs=int(f.size), sync=sync,
                            method="butt joint: one odd pitch, the others equal")


# --------------------------------------------------------------------------------------------
# instantaneous speed and angular vibration
# --------------------------------------------------------------------------------------------
def _edge_angles(t, pitch, n, calibration, sync):
    if calibration is None:
        return pitch * (TWO_PI / n)
    if not isinstance(calibration, ToothCalibration):
        raise TypeError(f"calibration must be a ToothCalibration, got {type(calibration).__name__}")
    if calibration.pulses_per_rev != n:
        raise AnalysisError(f"calibration is for pulses_per_rev={calibration.pulses_per_rev}, "
                            f"the record has pulses_per_rev={n}")
    if calibration.sync != sync:
        raise AnalysisError(f"calibration synchronised by {calibration.sync!r} cannot be applied "
                            f"to edges synchronised by {sync!r}")
    if sync == "first edge":
        log.warning("tooth calibration without a reference (sync='first edge') is only valid "
                    "for the record it was taken from")
    return calibration.angles(pitch)


def instantaneous_speed(edge_times, *, pulses_per_rev, missing_teeth=0, calibration=None,
                        reference_times=None, butt_joint=False, repair=True):
    """Per-pitch angular speed from edge times, with tooth-spacing correction.

    ``omega = (theta_{k+1} - theta_k) / (t_{k+1} - t_k)`` at ``(t_k + t_{k+1}) / 2`` with the
    actual tooth angles from ``calibration``. Exact for constant acceleration; a timing error
    ``sigma_t`` gives ``sigma_omega / omega = sqrt(2) sigma_t / dt``.

    Parameters
    ----------
    edge_times : array_like
        Edge times, s.
    pulses_per_rev, missing_teeth : int
        Wheel geometry.
    calibration : ToothCalibration, optional
        Tooth angles (from :func:`calibrate_teeth` or :func:`butt_joint_calibration`).
    reference_times : array_like, optional
        Once-per-revolution mark (sync for a calibration of a plain encoder).
    butt_joint : bool
        Zebra tape: sync to the butt joint.
    repair : bool
        Bridge dropouts and remove spurious pulses.

    Returns
    -------
    tacho.SpeedTrace
        With ``window_pitches=1``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(121) / 3000.0                     # 60/rev at 50 rev/s
    >>> sp = instantaneous_speed(t, pulses_per_rev=60)
    >>> round(float(sp.speed_rpm.mean()), 6)
    3000.0
    """
    t, pitch, sync = _sync(edge_times, pulses_per_rev, missing_teeth, reference_times,
                           butt_joint, repair)
    theta = _edge_angles(t, pitch, int(pulses_per_rev), calibration, sync)
    omega = np.diff(theta) / np.diff(t)
    return SpeedTrace(time=0.5 * (t[1:] + t[:-1]), omega=omega, window_pitches=1,
                      timing_error_s=float("nan"), error_rpm=float("nan"),
                      method="per-pitch difference with tooth angles")


@dataclass(frozen=True)
class TorsiographResult:
    """Angular vibration from pulse timing.

    Attributes
    ----------
    orders : xarray.Dataset
        ``amplitude`` (rad, peak) and ``phase`` (rad) over dims (``order``, ``time``), with
        ``phi = sum_q amplitude cos(q x + phase)``, ``x`` the mean-motion crank angle from the
        reference (minus ``tdc_offset``); ``rpm`` (mean speed of each block) and
        ``residual_rms`` (rad) along ``time``; ``amplitude_std`` (rad): the standard deviation
        of each cos/sin coefficient from the fit residual and the least-squares covariance.
    edge_time : numpy.ndarray
        Edge times used, s.
    vibration : numpy.ndarray
        Angular vibration at each edge (angle minus fitted mean motion), rad; NaN outside whole
        blocks.
    revs_per_block : int
    calibration : ToothCalibration or None
    """

    orders: object
    edge_time: np.ndarray
    vibration: np.ndarray
    revs_per_block: int
    calibration: ToothCalibration | None = None
    method: str = field(default="joint least squares of quadratic mean motion and orders "
                                "per block of whole revolutions")

    def amplitude_deg(self, order) -> np.ndarray:
        """Amplitude (deg, peak) of one order along the blocks."""
        return np.degrees(self.orders["amplitude"].sel(order=order).values)

    def to_frame(self):
        """Long table: ``time_s``, ``speed_rpm``, ``order``, ``amplitude_deg``, ``phase_deg``."""
        import pandas as pd

        ds = self.orders
        n_order, n_time = ds.sizes["order"], ds.sizes["time"]
        return pd.DataFrame({
            "time_s": np.tile(ds["time"].values, n_order),
            "speed_rpm": np.tile(ds["rpm"].values, n_order),
            "order": np.repeat(ds["order"].values, n_time),
            "amplitude_deg": np.degrees(ds["amplitude"].values.ravel()),
            "phase_deg": np.degrees(ds["phase"].values.ravel()),
        })

    def plot(self, ax=None, orders=None):
        """Order amplitudes (deg) against speed (rpm); returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        ds = self.orders
        for q in ds["order"].values if orders is None else orders:
            ax.plot(ds["rpm"].values, np.degrees(ds["amplitude"].sel(order=q).values),
                    label=f"order {q:g}")
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel("angular vibration (deg, peak)")
        ax.legend(fontsize="small", ncol=2)
        return fig


@single_threaded_blas  # many small least-squares fits (issue 21)
def angular_vibration(edge_times, *, pulses_per_rev, missing_teeth=0, max_order=12.0,
                      revs_per_block=2, calibration=None, reference_times=None,
                      butt_joint=False, tdc_offset_deg=0.0, mean_motion="spline",
                      trend_degree=2, repair=True):
    """Angular vibration per order from encoder/gear/zebra-tape edge times.

    The record is cut into blocks of ``revs_per_block`` whole revolutions from the wheel
    reference. The mean motion ``xbar(t)`` is, by default (``mean_motion="spline"``), a cubic
    spline through one point per block, the block's mean edge time and mean edge angle
    (corrected iteratively so that the vibration has zero mean over every block): over a whole
    period the vibration averages out, so these points lie on the mean motion to within
    ``sigma / sqrt(M)``, and the orders fitted against ``x = xbar(t_k)`` (constant + cos/sin of
    every order, orthogonal over a whole period) carry the white-noise floor
    ``sigma sqrt(2 / M)``. With ``mean_motion="block"`` each block fits its own polynomial of
    degree ``trend_degree`` jointly with the orders instead (needed when the record holds fewer
    than two blocks); that inflates the noise of the lowest orders, which are partly collinear
    with the polynomial, and ``amplitude_std`` reports it.

    Parameters
    ----------
    edge_times : array_like
        Edge times, s.
    pulses_per_rev : int
        Pitch positions per revolution (including missing teeth).
    missing_teeth : int
        Teeth missing to form a reference gap.
    max_order : float
        Highest order fitted; all multiples of ``1 / revs_per_block`` up to it are fitted
        jointly. Must be below the Nyquist order ``(pulses_per_rev - missing_teeth) / 2``.
    revs_per_block : int
        Revolutions per analysis block (2 = one four-stroke cycle, resolving half orders).
        Without a cam signal the phase of half orders is ambiguous by pi.
    calibration : ToothCalibration, optional
        Tooth-spacing correction (:func:`calibrate_teeth`, :func:`butt_joint_calibration`).
    reference_times : array_like, optional
        Once-per-revolution mark times, s (sync of a plain encoder).
    butt_joint : bool
        Zebra tape with a butt joint: sync to the joint.
    tdc_offset_deg : float
        Angle from the wheel reference to TDC of cylinder 1, deg; phases refer to TDC.
    mean_motion : {"spline", "block"}
        How the mean rotation is estimated (see above).
    trend_degree : int
        Degree in time of the per-block polynomial for ``mean_motion="block"``.
    repair : bool
        Bridge dropouts and remove spurious pulses.

    Returns
    -------
    TorsiographResult

    References
    ----------
    Jiaotong University, *IC-engine dynamics*, 1958, part 2 ch. 5 §2 (torsiogram analysis).

    Examples
    --------
    >>> import numpy as np
    >>> omega, amp = 2 * np.pi * 25.0, np.radians(0.2)       # 1500 rpm, 0.2 deg at order 3
    >>> theta = np.arange(6000) * 2 * np.pi / 60
    >>> x = theta.copy()
    >>> for _ in range(5):                                  # solve theta = x + amp sin(3x)
    ...     x = theta - amp * np.sin(3 * x)
    >>> res = angular_vibration(x / omega, pulses_per_rev=60, max_order=6)
    >>> round(float(res.amplitude_deg(3.0).mean()), 6)
    0.2
    """
    import xarray as xr

    max_order = check_positive(max_order, "max_order")
    blocks_revs = check_int(revs_per_block, "revs_per_block", minimum=1)
    check_option(mean_motion, "mean_motion", ("spline", "block"))
    trend_degree = check_int(trend_degree, "trend_degree", minimum=1)
    if trend_degree > 3:
        raise AnalysisError(f"trend_degree={trend_degree} must be 1, 2 or 3")
    n = check_int(pulses_per_rev, "pulses_per_rev", minimum=2)
    nyquist = (n - missing_teeth) / 2.0
    if max_order >= nyquist:
        raise AnalysisError(f"max_order={max_order:g} must be below the Nyquist order "
                            f"{nyquist:g} of a wheel with {n - missing_teeth} edges per rev")
    offset = np.radians(float(tdc_offset_deg))
    t, pitch, sync = _sync(edge_times, n, missing_teeth, reference_times, butt_joint, repair)
    theta = _edge_angles(t, pitch, n, calibration, sync)
    orders = np.arange(1, int(np.floor(max_order * blocks_revs + 1e-9)) + 1) / blocks_revs
    per_block = n * blocks_revs
    block = np.floor_divide(pitch, per_block)
    # only whole blocks: the block must contain its first and its last pitch position
    whole = []
    for b in range(int(block.min()), int(block.max()) + 1):
        sel = np.flatnonzero(block == b)
        if sel.size and pitch[sel[0]] == b * per_block and \
                pitch[sel[-1]] >= (b + 1) * per_block - 1 - missing_teeth:
            whole.append(sel)
    if not whole:
        raise AnalysisError(f"edge_times contain no whole block of {blocks_revs} revolution(s) "
                            f"({per_block} pitches) after the reference")
    n_par = 1 + 2 * orders.size + (trend_degree if mean_motion == "block" else 0)
    if min(sel.size for sel in whole) < n_par + 4:
        raise AnalysisError(f"blocks of {min(sel.size for sel in whole)} edges are too short "
                            f"for {n_par} parameters; lower max_order or raise revs_per_block")
    if mean_motion == "spline" and len(whole) < 2:
        log.info("angular_vibration: one whole block only, using mean_motion='block'")
        mean_motion = "block"
    vib = np.full(t.size, np.nan)
    if mean_motion == "spline":
        xbar = _mean_motion_spline(t, theta, whole)
        rows = [_fit_orders(t[sel], theta[sel], xbar, orders, offset) for sel in whole]
    else:
        rows = [_fit_block(t[sel], theta[sel], orders, trend_degree, offset) for sel in whole]
    for sel, fit in zip(whole, rows):
        vib[sel] = fit["vibration"]
    coef = np.array([r["coef"] for r in rows]).T  # (order, block) complex
    std = np.array([r["std"] for r in rows]).T
    time = np.array([r["time"] for r in rows])
    ds = xr.Dataset(
        {
            "amplitude": (("order", "time"), np.abs(coef),
                          {"units": "rad", "amplitude": "peak", "long_name": "angular vibration"}),
            "phase": (("order", "time"), np.angle(coef),
                      {"units": "rad", "convention": "phi = A cos(q x + phase), x from TDC 1"}),
            "amplitude_std": (("order", "time"), std,
                              {"units": "rad", "long_name": "std of each cos/sin coefficient"}),
            "residual_rms": ("time", np.array([r["residual"] for r in rows]), {"units": "rad"}),
        },
        coords={"order": ("order", orders, {"units": "1"}),
                "time": ("time", time, {"units": "s", "long_name": "block mean edge time"}),
                "rpm": ("time", np.array([r["rpm"] for r in rows]), {"units": "rpm"})},
        attrs={"method": f"least squares of orders against mean motion ({mean_motion})",
               "revs_per_block": blocks_revs, "max_order": float(max_order),
               "pulses_per_rev": n, "missing_teeth": int(missing_teeth), "sync": sync,
               "tooth_calibration": "none" if calibration is None else calibration.method,
               "amplitude": "peak"},
    )
    return TorsiographResult(orders=ds, edge_time=t, vibration=vib, revs_per_block=blocks_revs,
                             calibration=calibration)


def _mean_motion_spline(t, theta, blocks, iterations=3):
    """Spline through (block mean time, block mean angle), corrected for curvature."""
    from scipy.interpolate import CubicSpline, make_interp_spline

    tb = np.array([t[sel].mean() for sel in blocks])
    mean_theta = np.array([theta[sel].mean() for sel in blocks])
    target = mean_theta.copy()
    k = min(3, tb.size - 1)

    def build(values):
        if k == 3:
            return CubicSpline(tb, values, bc_type="not-a-knot")
        return make_interp_spline(tb, values, k=k)

    spline = build(target)
    for _ in range(iterations):
        # make the spline's own block means equal the measured block means
        own = np.array([spline(t[sel]).mean() for sel in blocks])
        target = target + (mean_theta - own)
        spline = build(target)
    return spline


def _fit_orders(t, theta, xbar, orders, offset):
    x = xbar(t)
    qx = np.outer(x - offset, orders)
    a = np.hstack([np.ones((t.size, 1)), np.cos(qx), np.sin(qx)])
    phi = theta - x
    coef, *_ = np.linalg.lstsq(a, phi, rcond=None)
    return _summarise(a, coef, phi, 1, orders.size, time=float(t.mean()),
                      omega=float(xbar(t.mean(), 1)), vibration=phi)


def _fit_block(t, theta, orders, degree, offset):
    tm = 0.5 * (t[0] + t[-1])
    scale = t[-1] - t[0]
    tau = (t - tm) / scale
    trend = np.vander(tau, degree + 1, increasing=True)
    x = theta
    for _ in range(2):
        qx = np.outer(x - offset, orders)
        a = np.hstack([trend, np.cos(qx), np.sin(qx)])
        coef, *_ = np.linalg.lstsq(a, theta, rcond=None)
        x = trend @ coef[: degree + 1]
    return _summarise(a, coef, theta, degree + 1, orders.size, time=tm,
                      omega=coef[1] / scale, vibration=theta - x)


def _summarise(a, coef, y, n_trend, q, *, time, omega, vibration):
    c, s = coef[n_trend: n_trend + q], coef[n_trend + q:]
    resid = y - a @ coef
    dof = max(y.size - a.shape[1], 1)
    sigma = np.sqrt(np.sum(resid**2) / dof)
    # coefficient covariance sigma^2 (A^T A)^-1 from the QR factor (includes any variance
    # inflation of the lowest orders by their correlation with a per-block trend)
    r = np.linalg.qr(a, mode="r")
    rinv = np.linalg.solve(r, np.eye(r.shape[0]))
    var = np.sum(rinv**2, axis=1)
    var_c, var_s = var[n_trend: n_trend + q], var[n_trend + q:]
    return {"coef": c - 1j * s, "std": sigma * np.sqrt(0.5 * (var_c + var_s)),
            "time": time, "rpm": omega * 60 / TWO_PI, "residual": sigma,
            "vibration": vibration}
