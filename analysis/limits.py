"""Limit checks for the test report: vibration severity zones, torsional stress, unbalance.

Each check returns a :class:`LimitCheck` — one line of the report's pass/fail table with the
worst value, the limit it was held against, where the limit comes from, and the detailed data
behind it (for the figure).

* **Vibration severity** — broadband velocity rms on the machine structure against the
  evaluation zones A/B/C/D. The default zone boundaries are the typical values of
  ISO 10816-1:1995, Annex B, Table B.1 for machine classes I–IV (velocity rms, mm/s):

  ======  =====  =====  =====
  class    A/B    B/C    C/D
  ======  =====  =====  =====
  I       0.71   1.8    4.5
  II      1.12   2.8    7.1
  III     1.8    4.5    11.2
  IV      2.8    7.1    18
  ======  =====  =====  =====

  ISO 10816-1 has been superseded by ISO 20816-1:2016, and reciprocating machines have their
  own part (ISO 10816-6 / ISO 20816 series) with machine-specific classes: where a contract or
  the current part of the standard gives other boundaries, pass them as
  :class:`ZoneBoundaries` (the report prints the source given).
* **Torsional vibratory stress** — against user-given continuous and transient limit curves
  (classification-society rules), with barred speed ranges
  (:mod:`predict.torsion.stress`).
* **Residual unbalance** — against the permissible unbalance ``U_per = G m / Ω`` of a balance
  grade (ISO 21940-11:2016 §5; :func:`predict.rotor_balance.grade_check`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from crankbench.predict._validate import (
    check_finite_array,
    check_option,
    check_positive,
    check_range,
)
from crankbench.predict.errors import AnalysisError
from crankbench.predict._deprecate import renamed

__all__ = ["ZoneBoundaries", "ISO_10816_1_CLASSES", "zone_boundaries", "LimitCheck",
           "vibration_severity", "check_vibration_severity", "check_torsional_stress",
           "check_residual_unbalance"]

#: ISO 10816-1:1995 Annex B Table B.1, typical zone boundaries, velocity rms in m/s
ISO_10816_1_CLASSES = {
    "I": (0.71e-3, 1.8e-3, 4.5e-3),
    "II": (1.12e-3, 2.8e-3, 7.1e-3),
    "III": (1.8e-3, 4.5e-3, 11.2e-3),
    "IV": (2.8e-3, 7.1e-3, 18.0e-3),
}
_ISO_SOURCE = ("ISO 10816-1:1995 Annex B Table B.1 (typical zone boundaries; superseded by "
               "ISO 20816-1:2016)")
ZONES = ("A", "B", "C", "D")


@dataclass(frozen=True)
class ZoneBoundaries:
    """Evaluation-zone boundaries of broadband velocity rms, m/s.

    Attributes
    ----------
    ab, bc, cd : float
        Boundaries A/B, B/C, C/D, m/s rms, ascending.
    machine_class : str
    source : str
        Standard, edition and table (printed in the report).

    Examples
    --------
    >>> z = zone_boundaries("III")
    >>> print(z.zone(3.0e-3), z.zone(12e-3))
    B D
    """

    ab: float
    bc: float
    cd: float
    machine_class: str = ""
    source: str = "user-given"

    def __post_init__(self):
        ab = check_positive(self.ab, "ab", error=AnalysisError)
        bc = check_positive(self.bc, "bc", error=AnalysisError)
        cd = check_positive(self.cd, "cd", error=AnalysisError)
        if not ab < bc < cd:
            raise AnalysisError(f"zone boundaries must ascend: ab={ab!r} < bc={bc!r} < "
                                f"cd={cd!r} (m/s rms)")

    def zone(self, velocity_rms):
        """Zone letter(s) 'A'..'D' of a velocity rms (m/s); arrays give an array."""
        v = np.asarray(velocity_rms, float)
        idx = np.searchsorted([self.ab, self.bc, self.cd], v, side="right")
        letters = np.array(ZONES)[idx]
        return str(letters) if letters.ndim == 0 else letters

    def upper(self, zone: str) -> float:
        """Upper boundary of ``zone`` (m/s rms; inf for D)."""
        check_option(zone, "zone", ZONES, error=AnalysisError)
        return {"A": self.ab, "B": self.bc, "C": self.cd, "D": np.inf}[zone]


def zone_boundaries(machine_class: str) -> ZoneBoundaries:
    """Typical zone boundaries of ISO 10816-1:1995 Annex B (Table B.1) for a machine class.

    Parameters
    ----------
    machine_class : {'I', 'II', 'III', 'IV'}
        Case-insensitive; 1–4 are accepted too. I: small machines (motors to 15 kW); II: medium machines (15–75 kW, or up to 300 kW on
        special foundations); III: large prime movers on rigid foundations; IV: large prime
        movers on soft foundations.

    Returns
    -------
    ZoneBoundaries

    References
    ----------
    ISO 10816-1:1995, *Mechanical vibration — Evaluation of machine vibration by
    measurements on non-rotating parts — Part 1: General guidelines*, Annex B, Table B.1
    (superseded by ISO 20816-1:2016).

    Examples
    --------
    >>> z = zone_boundaries("II")
    >>> print(round(z.ab * 1e3, 3), round(z.bc * 1e3, 3), round(z.cd * 1e3, 3))
    1.12 2.8 7.1
    """
    key = str(machine_class).strip().upper()
    key = {"1": "I", "2": "II", "3": "III", "4": "IV"}.get(key, key)
    if key not in ISO_10816_1_CLASSES:
        check_option(machine_class, "machine_class", ISO_10816_1_CLASSES, error=AnalysisError)
    machine_class = key
    ab, bc, cd = ISO_10816_1_CLASSES[machine_class]
    return ZoneBoundaries(ab, bc, cd, machine_class=machine_class, source=_ISO_SOURCE)


@dataclass(frozen=True)
class LimitCheck:
    """One row of the report's limit table.

    Attributes
    ----------
    name : str
        What was checked and where ("vibration severity at mount FL z").
    quantity : str
        e.g. "velocity rms", "shear stress", "residual unbalance".
    value : float
        Worst value found, in ``units`` (SI).
    limit : float
        The limit the worst value is held against, same units.
    units : str
    passed : bool
    detail : str
        Zone reached, barred ranges, smallest grade met...
    source : str
        Where the limit comes from.
    data : object
        Detailed result (DataFrame, StressCheck, GradeCheck) for tables and figures.
    """

    name: str
    quantity: str
    value: float
    limit: float
    units: str
    passed: bool
    detail: str = ""
    source: str = ""
    data: object = field(default=None, compare=False, repr=False)

    def as_dict(self) -> dict:
        """Row for tables and JSON (without ``data``)."""
        return {"check": self.name, "quantity": self.quantity, "value": self.value,
                "limit": self.limit, "units": self.units, "passed": self.passed,
                "detail": self.detail, "source": self.source}

    def to_frame(self):
        import pandas as pd

        return pd.DataFrame([self.as_dict()])

    def plot(self, ax=None):
        """Figure of the detailed data (severity vs speed with zones, stress vs limits, or
        unbalance bars)."""
        import matplotlib.pyplot as plt

        if hasattr(self.data, "plot") and not hasattr(self.data, "columns"):
            return self.data.plot(ax=ax)
        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 4))
        else:
            fig = ax.figure
        frame = self.data
        if frame is not None and "velocity_rms" in frame:
            x = frame["speed_rpm"] if "speed_rpm" in frame and np.isfinite(
                frame["speed_rpm"]).all() else frame["time"]
            ax.plot(x, frame["velocity_rms"] * 1e3, "k", lw=1.2, label="velocity rms")
            b = frame.attrs["boundaries"]
            top = max(float(frame["velocity_rms"].max() * 1e3) * 1.2, b[2] * 1e3 * 1.1)
            edges = [0.0, b[0] * 1e3, b[1] * 1e3, b[2] * 1e3, top]
            for z, lo, hi, col in zip(ZONES, edges[:-1], edges[1:],
                                      ("#cfe8cf", "#e8f0c0", "#f5dfb0", "#f3c0c0")):
                ax.axhspan(lo, hi, color=col, alpha=0.7, lw=0)
                ax.text(0.01, (lo + hi) / 2, z, transform=ax.get_yaxis_transform(),
                        va="center", fontsize=8)
            ax.set_ylim(0, top)
            ax.set_xlabel("speed (rpm)" if x.name == "speed_rpm" else "time (s)")
            ax.set_ylabel("velocity rms (mm/s)")
            ax.set_title(self.name, fontsize=9)
        return fig


@renamed(rpm="speed_rpm")
def vibration_severity(x, *, fs, speed_rpm=None, quantity="velocity", band_hz=(10.0, 1000.0),
                       window_s=1.0, overlap=0.5):
    """Broadband velocity rms in consecutive windows (the vibration severity).

    Parameters
    ----------
    x : array_like
        Vibration signal: velocity (m/s) or acceleration (m/s²).
    fs : float
        Sample rate, Hz.
    speed_rpm : array_like, optional
        Speed per sample, rpm; the mean per window is returned as ``speed_rpm``.
    quantity : {'velocity', 'acceleration'}
        What ``x`` is; acceleration is integrated in the frequency domain (division by iω).
    band_hz : (float, float)
        Measurement band, Hz (ISO 10816-1: 10–1000 Hz; 2–1000 Hz for machines running at
        600 rpm or less).
    window_s : float
        Window length, s (≥ 10 periods of the band's lower edge is advisable).
    overlap : float
        Fraction of overlap between windows, 0 ≤ overlap < 1.

    Returns
    -------
    xarray.Dataset
        ``velocity_rms`` (m/s) over ``time`` (window centres), coordinate ``speed_rpm``.

    Notes
    -----
    rms by Parseval over the FFT bins inside the band of each Hann-windowed segment
    (energy-corrected), so no time-domain filter transients; error about one bin width at
    each band edge.

    Examples
    --------
    >>> fs = 5000.0
    >>> t = np.arange(0, 4, 1 / fs)
    >>> v = 5e-3 * np.sin(2 * np.pi * 50 * t)          # 5 mm/s peak at 50 Hz
    >>> sev = vibration_severity(v, fs=fs)
    >>> print(f"{float(sev.velocity_rms.mean()) * 1e3:.3f} mm/s")
    3.536 mm/s
    """
    import xarray as xr

    quantity = check_option(quantity, "quantity", ("velocity", "acceleration"),
                            error=AnalysisError)
    fs = check_positive(fs, "fs", error=AnalysisError)
    x = check_finite_array(x, "x", ndim=1, min_length=8, error=AnalysisError)
    window_s = check_positive(window_s, "window_s", error=AnalysisError)
    overlap = check_range(overlap, "overlap", 0.0, 1.0, inclusive=(True, False),
                          error=AnalysisError)
    lo, hi = (float(v) for v in band_hz)
    if not 0 <= lo < hi:
        raise AnalysisError(f"band_hz={band_hz!r} must be (low, high) with 0 <= low < high")
    n = int(round(window_s * fs))
    if n > x.size:
        raise AnalysisError(f"window_s={window_s!r} ({n} samples) is longer than the signal "
                            f"({x.size} samples)")
    if speed_rpm is not None:
        speed_rpm = check_finite_array(speed_rpm, "speed_rpm", ndim=1, error=AnalysisError)
        if speed_rpm.size != x.size:
            raise AnalysisError(f"speed_rpm has {speed_rpm.size} samples, x has {x.size}; expected equal")
    step = max(1, int(round(n * (1 - overlap))))
    starts = np.arange(0, x.size - n + 1, step)
    win = np.hanning(n)
    norm = np.sqrt(np.mean(win**2))
    f = np.fft.rfftfreq(n, 1 / fs)
    inband = (f >= lo) & (f <= min(hi, fs / 2))
    seg = x[starts[:, None] + np.arange(n)[None, :]]
    seg = seg - seg.mean(axis=1, keepdims=True)
    spec = np.fft.rfft(seg * win / norm, axis=1)
    if quantity == "acceleration":
        with np.errstate(divide="ignore", invalid="ignore"):
            spec = np.where(f > 0, spec / (2j * np.pi * np.where(f > 0, f, 1.0)), 0.0)
    # one-sided Parseval: rms² = (2/N²) Σ |X_k|² (DC and Nyquist once)
    weight = np.full(f.size, 2.0)
    weight[0] = 1.0
    if n % 2 == 0:
        weight[-1] = 1.0
    rms = np.sqrt(np.sum(weight[inband] * np.abs(spec[:, inband]) ** 2, axis=1)) / n
    t = (starts + n / 2) / fs
    speed = (np.array([speed_rpm[s:s + n].mean() for s in starts]) if speed_rpm is not None
             else np.full(starts.size, np.nan))
    return xr.Dataset({"velocity_rms": ("time", rms, {"units": "m/s", "amplitude": "rms"})},
                      coords={"time": ("time", t, {"units": "s"}),
                              "speed_rpm": ("time", speed, {"units": "rpm"})},
                      attrs={"method": "Hann-windowed FFT, Parseval over the band",
                             "band_hz": [lo, hi], "window_s": window_s, "overlap": overlap})


def check_vibration_severity(velocity_rms, *, speed_rpm=None, machine_class="III",
                             boundaries=None, allowed_zone="B", name="vibration severity"):
    """Hold velocity rms against ISO evaluation zones; pass if no point exceeds the allowed
    zone.

    Parameters
    ----------
    velocity_rms : array_like or xarray.Dataset
        Velocity rms, m/s (or the output of :func:`vibration_severity`).
    speed_rpm : array_like, optional
        Speed per value, rpm (for the figure and the worst-speed detail).
    machine_class : {'I', 'II', 'III', 'IV'}
        ISO 10816-1 Annex B class, used when ``boundaries`` is not given.
    boundaries : ZoneBoundaries, optional
        Other zone boundaries (e.g. from the machine-specific part of ISO 20816).
    allowed_zone : {'A', 'B', 'C'}
        Highest acceptable zone (B: unrestricted long-term operation).
    name : str

    Returns
    -------
    LimitCheck
        ``value`` the worst velocity rms, ``limit`` the allowed zone's upper boundary, m/s;
        ``data`` a DataFrame per point with the zone.

    Examples
    --------
    >>> c = check_vibration_severity([2e-3, 3.9e-3, 5e-3], machine_class="III")
    >>> print(c.passed, c.detail)
    False worst 5 mm/s rms is in zone C (allowed up to B, 4.5 mm/s)
    """
    import pandas as pd

    if hasattr(velocity_rms, "data_vars"):
        ds = velocity_rms
        values = np.asarray(ds["velocity_rms"].values, float)
        time = np.asarray(ds["time"].values, float)
        if speed_rpm is None and "speed_rpm" in ds.coords:
            speed_rpm = np.asarray(ds["speed_rpm"].values, float)
    else:
        values = check_finite_array(velocity_rms, "velocity_rms", ndim=1, min_length=1,
                                    error=AnalysisError)
        time = np.arange(values.size, dtype=float)
    if np.any(values < 0):
        raise AnalysisError("velocity_rms must be >= 0 (m/s rms)")
    check_option(allowed_zone, "allowed_zone", ("A", "B", "C"), error=AnalysisError)
    b = boundaries if boundaries is not None else zone_boundaries(machine_class)
    if not isinstance(b, ZoneBoundaries):
        raise AnalysisError(f"boundaries must be a ZoneBoundaries, got {type(b).__name__}")
    speed = (np.full(values.size, np.nan) if speed_rpm is None
             else np.asarray(speed_rpm, float))
    if speed.size != values.size:
        raise AnalysisError(f"speed_rpm has {speed.size} values, velocity_rms {values.size}")
    zones = b.zone(values)
    frame = pd.DataFrame({"time": time, "speed_rpm": speed, "velocity_rms": values,
                          "zone": np.atleast_1d(zones)})
    frame.attrs["boundaries"] = (b.ab, b.bc, b.cd)
    k = int(np.argmax(values))
    worst, worst_zone = float(values[k]), str(np.atleast_1d(zones)[k])
    limit = b.upper(allowed_zone)
    passed = worst <= limit
    at = f" at {speed[k]:.0f} rpm" if np.isfinite(speed[k]) else ""
    cls = f"class {b.machine_class}, " if b.machine_class else ""
    detail = (f"worst {worst * 1e3:.3g} mm/s rms{at} is in zone {worst_zone} (allowed up to "
              f"{allowed_zone}, {limit * 1e3:.3g} mm/s)")
    return LimitCheck(name=name, quantity="velocity rms", value=worst, limit=float(limit),
                      units="m/s", passed=bool(passed), detail=detail,
                      source=f"{cls}{b.source}", data=frame)


def check_torsional_stress(speed_rpm, stress, limits, *, section="", operating_range_rpm=None,
                           name="torsional vibratory stress"):
    """Hold a vibratory shear stress over speed against continuous and transient limits.

    Parameters
    ----------
    speed_rpm : array_like
        Speeds, rpm, ascending.
    stress : array_like
        Vibratory shear stress amplitude at each speed, Pa (measured via the torsiograph and
        the mode's stress per unit amplitude, or predicted).
    limits : predict.torsion.stress.StressLimits
        User-given continuous and transient limit curves.
    section : str
        Shaft section the stress belongs to.
    operating_range_rpm : (float, float), optional
        Continuous-operation speed range: exceeding the continuous limit inside it fails the
        check; outside it the continuous limit only bars the speed range.
    name : str

    Returns
    -------
    LimitCheck
        ``value`` the worst ratio stress/limit (dimensionless, the limit is 1); passed when
        the transient limit is never exceeded and the continuous limit is not exceeded inside
        the operating range; ``data`` the :class:`predict.torsion.stress.StressCheck`.

    References
    ----------
    内燃机动力学 (1958), 第二篇 第四章 §4 (additional stresses at critical speeds).

    Examples
    --------
    >>> from crankbench.predict.torsion.stress import StressLimits
    >>> lim = StressLimits([0, 1000], [30e6, 30e6], [60e6, 60e6])
    >>> c = check_torsional_stress([100, 200, 300], [10e6, 45e6, 10e6], lim)
    >>> print(c.passed, c.detail)
    True barred 157–243 rpm (continuous limit exceeded); transient limit held
    """
    from types import SimpleNamespace

    from crankbench.predict.torsion.stress import StressLimits, check_stress

    if not isinstance(limits, StressLimits):
        raise AnalysisError(f"limits must be a predict.torsion.stress.StressLimits, got "
                            f"{type(limits).__name__}")
    speed = check_finite_array(speed_rpm, "speed_rpm", ndim=1, min_length=2, error=AnalysisError)
    tau = check_finite_array(stress, "stress", ndim=1, error=AnalysisError)
    if tau.size != speed.size:
        raise AnalysisError(f"stress has {tau.size} values, speed_rpm {speed.size}")
    if np.any(np.diff(speed) <= 0):
        raise AnalysisError("speed_rpm must be strictly ascending")
    label = section or "section"
    response = SimpleNamespace(speed_rpm=speed, stress_total=tau[:, None], edge_names=(label,))
    lim = StressLimits(limits.speed_rpm, limits.continuous, limits.transient, sections=(),
                       source=limits.source)
    result = check_stress(response, lim)
    cont, trans = lim.at(speed)
    ratio_c = tau / cont
    ratio_t = tau / trans
    passed = result.passed
    inside_fail = []
    if operating_range_rpm is not None:
        lo, hi = map(float, operating_range_rpm)
        inside = (speed >= lo) & (speed <= hi) & (ratio_c > 1)
        if inside.any():
            passed = False
            inside_fail = speed[inside]
    parts = []
    if result.barred_ranges_rpm:
        ranges = ", ".join(f"{a:.0f}–{b:.0f}" for a, b in result.barred_ranges_rpm)
        parts.append(f"barred {ranges} rpm (continuous limit exceeded)")
    else:
        parts.append("continuous limit held")
    if result.transient_exceeded_rpm:
        ranges = ", ".join(f"{a:.0f}–{b:.0f}" for a, b in result.transient_exceeded_rpm)
        parts.append(f"TRANSIENT LIMIT EXCEEDED {ranges} rpm")
    else:
        parts.append("transient limit held")
    if len(inside_fail):
        parts.append(f"continuous limit exceeded inside the operating range at "
                     f"{inside_fail.min():.0f}–{inside_fail.max():.0f} rpm")
    k = int(np.argmax(ratio_t))
    return LimitCheck(name=f"{name} ({section})" if section else name,
                      quantity="stress / transient limit", value=float(ratio_t[k]), limit=1.0,
                      units="1", passed=bool(passed), detail="; ".join(parts),
                      source=lim.source, data=result)


def check_residual_unbalance(residual, *, rotor_mass, speed_rpm, grade=6.3, plane_shares=None,
                             name="residual unbalance"):
    """Residual unbalance against the permissible unbalance of a balance grade.

    Parameters
    ----------
    residual : array_like
        Residual unbalance per correction plane, kg·m.
    rotor_mass : float
        kg.
    speed_rpm : float
        Maximum service speed, rpm.
    grade : float
        Balance grade G, mm/s (6.3 for G 6.3; crankshaft assemblies typically G 16–G 40).
    plane_shares : array_like, optional
        Fraction of U_per per plane (default equal).
    name : str

    Returns
    -------
    LimitCheck
        ``value`` the worst plane's residual / permissible share (dimensionless), ``data``
        the :class:`predict.rotor_balance.GradeCheck`.

    References
    ----------
    ISO 21940-11:2016, *Rotor balancing — Part 11: Procedures and tolerances for rotors with
    rigid behaviour*, §5 (U_per = G·m/Ω) and Table 1 (grades).

    Examples
    --------
    >>> c = check_residual_unbalance([1.0e-3, 0.8e-3], rotor_mass=100.0, speed_rpm=3000.0,
    ...                              grade=6.3)
    >>> print(c.passed, c.detail)
    True achieved G 5.65 (smallest standard grade met: G 6.3; required G 6.3)
    """
    from crankbench.predict.rotor_balance import grade_check

    speed = check_positive(speed_rpm, "speed_rpm", error=AnalysisError)
    g = grade_check(residual, rotor_mass=rotor_mass, max_omega=speed * np.pi / 30.0,
                    grade=grade, plane_shares=plane_shares)
    ratio = g.residual / g.permissible
    k = int(np.argmax(ratio))
    detail = (f"achieved G {g.achieved_grade:.3g} (smallest standard grade met: "
              f"G {g.smallest_grade:g}; required G {g.grade:g})")
    return LimitCheck(name=name, quantity="residual / permissible unbalance",
                      value=float(ratio[k]), limit=1.0, units="1", passed=g.passed,
                      detail=detail, source="ISO 21940-11:2016 §5, U_per = G m / Ω", data=g)
