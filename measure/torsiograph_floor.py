"""Error floor of a torsiograph from pulse timing: what timer resolution, edge sampling and
jitter leave as the smallest measurable angular vibration per order.

Split from :mod:`measure.torsiograph` (which re-exports these names).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crankbench.predict._validate import check_int, check_nonnegative, check_positive

__all__ = ["ErrorFloor", "error_floor"]

TWO_PI = 2.0 * np.pi


# --------------------------------------------------------------------------------------------
# error floor
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ErrorFloor:
    """Noise floor of a pulse-timing torsiograph.

    Attributes
    ----------
    timing_rms : float
        Edge-timing error, s rms (all sources combined in quadrature).
    edge_angle_rms : float
        Resulting angle error per edge, rad rms.
    order_coefficient_std : float
        Standard deviation of each cos/sin coefficient of an order, rad.
    order_amplitude_mean : float
        Mean amplitude an order shows from noise alone (Rayleigh mean), rad.
    speed_rms_rpm : float
        Per-pitch speed error, rpm rms.
    components : dict
        Each source's timing rms, s.
    """

    timing_rms: float
    edge_angle_rms: float
    order_coefficient_std: float
    order_amplitude_mean: float
    speed_rms_rpm: float
    components: dict

    @property
    def order_amplitude_mean_deg(self) -> float:
        """Noise-only order amplitude, deg."""
        return float(np.degrees(self.order_amplitude_mean))

    def to_frame(self):
        """One-row table of the figures (angles in degrees)."""
        import pandas as pd

        return pd.DataFrame([{"timing_rms_s": self.timing_rms,
                              "edge_angle_rms_deg": np.degrees(self.edge_angle_rms),
                              "order_coefficient_std_deg": np.degrees(self.order_coefficient_std),
                              "order_amplitude_mean_deg": self.order_amplitude_mean_deg,
                              "speed_rms_rpm": self.speed_rms_rpm}])

    def plot(self, ax=None):
        """Timing-error components (s rms) as bars; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        names = list(self.components) + ["total"]
        ax.bar(names, [*self.components.values(), self.timing_rms])
        ax.set_ylabel("edge timing error (s rms)")
        ax.set_title(f"order noise floor {self.order_amplitude_mean_deg:.2e} deg")
        return fig


def error_floor(*, speed_rpm, pulses_per_rev, timer_resolution=0.0, sample_rate=None,
                interpolated=True, jitter=0.0, revs_per_block=2, missing_teeth=0):
    """Noise floor of angular vibration measured from pulse timing.

    Sources (independent, added in quadrature as edge-timing errors):

    * a counter clocked at ``1 / timer_resolution`` quantises each edge time: rms
      ``timer_resolution / sqrt(12)``;
    * edges taken from a sampled analogue signal at ``sample_rate`` without interpolation: rms
      ``1 / (sample_rate sqrt(12))``; with interpolation (:func:`measure.tacho.detect_edges`)
      the residual is taken as a tenth of that (a conservative figure for steep flanks);
    * jitter (pick-up noise, tooth-edge roughness): ``jitter`` s rms.

    The angle error per edge is ``omega sigma_t``; a least-squares fit of ``M`` edges per block
    gives each order coefficient a standard deviation ``omega sigma_t sqrt(2 / M)`` and a pure
    noise order an expected amplitude ``omega sigma_t sqrt(pi / M)``, for white timing noise
    (with ``mean_motion="block"`` the lowest orders are inflated, see
    :func:`angular_vibration`). Counter quantisation at a speed
    commensurate with the clock is not white: its error repeats with a short period and lands in
    a few high orders, leaving the low orders below this floor.

    Parameters
    ----------
    speed_rpm : float
        Shaft speed, rpm.
    pulses_per_rev : int
    timer_resolution : float
        Counter clock period, s (0 = ideal).
    sample_rate : float, optional
        Sample rate of an analogue pick-up channel the edges were detected on, Hz.
    interpolated : bool
        Whether sub-sample edge interpolation was used on the sampled channel.
    jitter : float
        Other timing noise, s rms.
    revs_per_block : int
    missing_teeth : int

    Returns
    -------
    ErrorFloor

    Examples
    --------
    >>> ef = error_floor(speed_rpm=1500, pulses_per_rev=60, timer_resolution=1e-7)
    >>> round(ef.order_amplitude_mean_deg, 7)    # 100 ns counter, 120 edges per block
    4.2e-05
    """
    speed_rpm = check_positive(speed_rpm, "speed_rpm")
    n = check_int(pulses_per_rev, "pulses_per_rev", minimum=1)
    comps = {"timer": check_nonnegative(timer_resolution, "timer_resolution") / np.sqrt(12.0),
             "jitter": check_nonnegative(jitter, "jitter")}
    if sample_rate is not None:
        fs = check_positive(sample_rate, "sample_rate")
        comps["sampling"] = (0.1 if interpolated else 1.0) / (fs * np.sqrt(12.0))
    sigma_t = float(np.sqrt(sum(v**2 for v in comps.values())))
    omega = speed_rpm * TWO_PI / 60.0
    m = (n - check_int(missing_teeth, "missing_teeth", minimum=0)) * \
        check_int(revs_per_block, "revs_per_block", minimum=1)
    angle = omega * sigma_t
    dt = TWO_PI / n / omega
    return ErrorFloor(timing_rms=sigma_t, edge_angle_rms=angle,
                      order_coefficient_std=angle * np.sqrt(2.0 / m),
                      order_amplitude_mean=angle * np.sqrt(np.pi / m),
                      speed_rms_rpm=float(np.sqrt(2.0) * sigma_t / dt * speed_rpm),
                      components=comps)
