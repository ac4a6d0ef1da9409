"""Limit checks for the test report: vibration severity zones, torsional stress, unbalance.

Each check returns a :class:`LimitCheck` — one line of the report's pass/fail table with the
worst value, the limit it was held against, where the limit comes from, and the detailed data
behind it (for the figure).

Each check carries a three-state status (pass / fail / inconclusive, see
:mod:`analysis.verdict`): a check without the data it needs is "not assessed" (inconclusive),
never a pass.

* **Vibration severity** — broadband velocity rms on the machine structure against the
  evaluation zones. For engines the default is ISO 10816-6:1995 (reciprocating machines with
  power ratings above 100 kW, still in force; ISO 20816-3:2022 excludes them), machine class 1–7
  chosen from the model's power and mounting (:func:`reciprocating_class`); see
  :data:`ISO_10816_6_CLASSES` for what was and was not verified. The general ISO 10816-1 table is
  kept as an option (``standard="ISO 10816-1"``), typical values of Annex B, Table B.1 for machine
  classes I–IV (velocity rms, mm/s):

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
* **Torsional vibratory stress** — against the rule limits in the model (IACS UR M68 for
  shafting, the engine maker's figure for the crankshaft; :mod:`predict.torsion.rules`) or
  user-given curves, with barred speed ranges judged where the rule allows them
  (:func:`check_torsional_stress`, in :mod:`analysis.torsional_limits`).
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

__all__ = ["ZoneBoundaries", "ISO_10816_1_CLASSES", "ISO_10816_6_GRADES",
           "ISO_10816_6_CLASSES", "zone_boundaries", "reciprocating_class", "LimitCheck",
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

#: ISO 10816-6:1995 Annex A, vibration severity grades: upper velocity rms of each grade, m/s
#: (the preferred-number series 1.12, 1.78, 2.82 ... mm/s, ratio 10^0.2)
ISO_10816_6_GRADES = (1.12e-3, 1.78e-3, 2.82e-3, 4.46e-3, 7.07e-3, 11.2e-3, 17.8e-3, 28.2e-3,
                      44.6e-3, 70.7e-3, 112e-3, 178e-3)
#: ISO 10816-6 machine classes 1–7: (A/B–C, C–D) velocity rms boundaries, m/s. Zones A and B
#: are one zone (A/B) in this part. NOT VERIFIED: no published copy or transcription of
#: Table A.1 was found (searched Nov 2026: the standard's text, vendor and class notes, papers,
#: public code; found only its scope — reciprocating machines above 100 kW, rigid or resilient
#: mounting, marine propulsion/auxiliary engines, generating sets, compressors, locomotives,
#: not road vehicles — and the different ISO 8528-9 genset values quoted in LR's vibration
#: guidance, Table 7.5.1). These are the boundaries as recalled (each class one severity grade
#: above the one before: class 1 at grades 1.78/2.82 mm/s … class 7 at 28.2/44.6 mm/s); the
#: table's displacement and acceleration columns are not implemented. Check them against your
#: copy of the standard or pass your own ZoneBoundaries; the report says so (``verified``).
ISO_10816_6_CLASSES = {k: (ISO_10816_6_GRADES[k], ISO_10816_6_GRADES[k + 1])
                       for k in range(1, 8)}
_ISO6_SOURCE = ("ISO 10816-6:1995 Annex A Table A.1, velocity rms 2–1000 Hz (boundaries NOT "
                "verified against the published table: confirm, or give boundaries_mm_s)")


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
    verified: bool = True

    def __post_init__(self):
        ab = check_positive(self.ab, "ab", error=AnalysisError)
        bc = check_positive(self.bc, "bc", error=AnalysisError)
        cd = check_positive(self.cd, "cd", error=AnalysisError)
        if not ab <= bc < cd:
            raise AnalysisError(f"zone boundaries must ascend: ab={ab!r} < bc={bc!r} < "
                                f"cd={cd!r} (m/s rms)")

    @property
    def merged_ab(self) -> bool:
        """Zones A and B are one zone 'A/B' (ISO 10816-6)."""
        return self.ab == self.bc

    def zone(self, velocity_rms):
        """Zone letter(s) 'A'..'D' ('A/B' when merged) of a velocity rms (m/s)."""
        v = np.asarray(velocity_rms, float)
        idx = np.searchsorted([self.ab, self.bc, self.cd], v, side="right")
        names = np.array(("A/B", "A/B", "C", "D") if self.merged_ab else ZONES, dtype=object)
        letters = np.asarray(names[idx], dtype=object)
        return str(letters) if letters.ndim == 0 else letters.astype(str)

    def upper(self, zone: str) -> float:
        """Upper boundary of ``zone`` (m/s rms; inf for D)."""
        zone = "B" if zone == "A/B" else zone
        check_option(zone, "zone", ZONES, error=AnalysisError)
        return {"A": self.ab, "B": self.bc, "C": self.cd, "D": np.inf}[zone]


def zone_boundaries(machine_class, *, standard: str = "ISO 10816-1") -> ZoneBoundaries:
    """Zone boundaries of a machine class.

    Parameters
    ----------
    machine_class : str or int
        ISO 10816-1: 'I'..'IV' (case-insensitive; 1–4 accepted). I: small machines (motors to
        15 kW); II: medium machines (15–75 kW, or up to 300 kW on special foundations); III:
        large prime movers on rigid foundations; IV: large prime movers on soft foundations.
        ISO 10816-6: 1..7 (reciprocating machines above 100 kW).
    standard : {'ISO 10816-1', 'ISO 10816-6'}

    Returns
    -------
    ZoneBoundaries

    References
    ----------
    ISO 10816-1:1995, *Mechanical vibration — Evaluation of machine vibration by measurements
    on non-rotating parts — Part 1: General guidelines*, Annex B, Table B.1 (superseded by
    ISO 20816-1:2016). ISO 10816-6:1995, *Part 6: Reciprocating machines with power ratings
    above 100 kW*, Annex A, Table A.1 (see :data:`ISO_10816_6_CLASSES`).

    Examples
    --------
    >>> z = zone_boundaries("II")
    >>> print(round(z.ab * 1e3, 3), round(z.bc * 1e3, 3), round(z.cd * 1e3, 3))
    1.12 2.8 7.1
    >>> z6 = zone_boundaries(5, standard="ISO 10816-6")
    >>> print(z6.zone(9e-3), z6.zone(15e-3), round(z6.bc * 1e3, 1), z6.verified)
    A/B C 11.2 False
    """
    check_option(standard, "standard", ("ISO 10816-1", "ISO 10816-6"), error=AnalysisError)
    if standard == "ISO 10816-6":
        try:
            k = int(str(machine_class).strip())
        except ValueError:
            k = 0
        if k not in ISO_10816_6_CLASSES:
            raise AnalysisError(f"machine_class={machine_class!r} is not an ISO 10816-6 class "
                                "(1 to 7)")
        bc, cd = ISO_10816_6_CLASSES[k]
        return ZoneBoundaries(bc, bc, cd, machine_class=str(k), source=_ISO6_SOURCE,
                              verified=False)
    key = str(machine_class).strip().upper()
    key = {"1": "I", "2": "II", "3": "III", "4": "IV"}.get(key, key)
    if key not in ISO_10816_1_CLASSES:
        check_option(machine_class, "machine_class", ISO_10816_1_CLASSES, error=AnalysisError)
    machine_class = key
    ab, bc, cd = ISO_10816_1_CLASSES[machine_class]
    return ZoneBoundaries(ab, bc, cd, machine_class=machine_class, source=_ISO_SOURCE)


def reciprocating_class(*, power_w=None, rated_speed_rpm=None, resilient=None):
    """ISO 10816-6 machine class (1–7) from power, speed and mounting, with the reason.

    crankbench's rule, stated in the report, not the standard's text: the standard classes
    machines by type, rated power, speed and mounting (Annex A/B, not verified here), so the
    class agreed in the contract should be given in the model (``[limits.vibration]
    machine_class``). Here: rigidly mounted engines class 2 up to 600 rpm rated, else 3;
    resiliently mounted class 5 up to 1000 rpm, 6 up to 1800 rpm, else 7. The pipeline takes
    the rated power from ``[limits.vibration] rated_power_kw`` (else the indicated power, said
    so) and the mounting from ``[limits.vibration] mounting`` (else resilient when the engine
    model has ``[mounts]``, else unknown: no class).

    Parameters
    ----------
    power_w : float, optional
        Rated power, W (the part covers machines above 100 kW).
    rated_speed_rpm : float, optional
    resilient : bool, optional
        Mounted on resilient (rubber, spring) mounts; False: rigidly mounted.

    Returns
    -------
    (int or None, str)
        The class (None when the data are missing or the machine is outside the part), and why.

    Examples
    --------
    >>> reciprocating_class(power_w=3.1e6, rated_speed_rpm=720, resilient=True)
    (5, 'class 5: resiliently mounted, rated 720 rpm, 3100 kW (crankbench rule, not the standard: give the contract class)')
    >>> reciprocating_class(power_w=1.2e6, rated_speed_rpm=500, resilient=False)[0]
    2
    """
    if power_w is None or rated_speed_rpm is None or resilient is None:
        missing = [n for n, v in (("power", power_w), ("rated speed", rated_speed_rpm),
                                  ("mounting", resilient)) if v is None]
        return None, f"no {', '.join(missing)} in the model to choose an ISO 10816-6 class"
    if power_w <= 100e3:
        return None, (f"rated power {power_w / 1e3:.0f} kW is not above 100 kW: outside "
                      "ISO 10816-6")
    n = float(rated_speed_rpm)
    if resilient:
        k = 5 if n <= 1000 else 6 if n <= 1800 else 7
    else:
        k = 2 if n <= 600 else 3
    return k, (f"class {k}: {'resiliently' if resilient else 'rigidly'} mounted, rated "
               f"{n:.0f} rpm, {power_w / 1e3:.0f} kW (crankbench rule, not the standard: give "
               "the contract class)")


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
        Worst value found, in ``units`` (SI); NaN when not assessed.
    limit : float
        The limit the worst value is held against, same units; NaN when not assessed.
    units : str
    status : {'pass', 'fail', 'inconclusive'}
        Inconclusive ("not assessed") when the data the rule needs are missing.
    detail : str
        Zone reached, barred ranges, smallest grade met, or what was missing.
    source : str
        The rule and clause the limit comes from.
    basis : str
        The data the check rests on (channel, speed range, model).
    required : bool
        Counts towards the overall verdict.
    data : object
        Detailed result (DataFrame, StressCheck, GradeCheck) for tables and figures.
    """

    name: str
    quantity: str
    value: float
    limit: float
    units: str
    status: str
    detail: str = ""
    source: str = ""
    basis: str = ""
    required: bool = True
    data: object = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        from .verdict import STATUSES

        if self.status not in STATUSES:
            raise AnalysisError(f"LimitCheck status {self.status!r}: expected one of "
                                f"{', '.join(STATUSES)}")

    @property
    def passed(self) -> bool:
        """True only for a pass (an inconclusive check is not a pass)."""
        return self.status == "pass"

    @property
    def verdict(self):
        """The check as a :class:`analysis.verdict.Verdict`."""
        from .verdict import Verdict

        reason = self.detail or ("not assessed" if self.status == "inconclusive" else "")
        return Verdict(self.name, self.status, self.source or "—",
                       self.basis or self.detail or "—",
                       reason if self.status != "pass" else self.detail, self.required)

    def as_dict(self) -> dict:
        """Row for tables and JSON (without ``data``)."""
        return {"check": self.name, "quantity": self.quantity, "value": self.value,
                "limit": self.limit, "units": self.units, "verdict": self.status,
                "detail": self.detail, "source": self.source, "basis": self.basis,
                "required": self.required}

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
                             boundaries=None, allowed_zone="B", name="vibration severity",
                             standard="ISO 10816-1", basis="", class_reason=""):
    """Hold velocity rms against ISO evaluation zones; pass if no point exceeds the allowed
    zone.

    Parameters
    ----------
    velocity_rms : array_like or xarray.Dataset
        Velocity rms, m/s (or the output of :func:`vibration_severity`).
    speed_rpm : array_like, optional
        Speed per value, rpm (for the figure and the worst-speed detail).
    machine_class : str or int or None
        Class of ``standard``, used when ``boundaries`` is not given ('I'..'IV' for
        ISO 10816-1, 1..7 for ISO 10816-6). None: not assessed (inconclusive).
    boundaries : ZoneBoundaries, optional
        Other zone boundaries (a contract's, or the machine-specific part of ISO 20816).
    allowed_zone : {'A', 'B', 'C'}
        Highest acceptable zone (B, or A/B: unrestricted long-term operation).
    name : str
    standard : {'ISO 10816-1', 'ISO 10816-6'}
    basis : str
        The data the check rests on (channel, band, speed range), for the verdict.
    class_reason : str
        How the class was chosen (printed with the source).

    Returns
    -------
    LimitCheck
        ``value`` the worst velocity rms, ``limit`` the allowed zone's upper boundary, m/s;
        ``data`` a DataFrame per point with the zone.

    Examples
    --------
    >>> c = check_vibration_severity([2e-3, 3.9e-3, 5e-3], machine_class="III")
    >>> print(c.status, c.detail)
    fail worst 5 mm/s rms is in zone C (allowed up to B, 4.5 mm/s)
    >>> print(check_vibration_severity([2e-3], machine_class=None).status)
    inconclusive
    """
    import pandas as pd

    if boundaries is None and machine_class is None:
        return LimitCheck(name=name, quantity="velocity rms", value=float("nan"),
                          limit=float("nan"), units="m/s", status="inconclusive",
                          detail="not assessed: " + (class_reason or "no machine class"),
                          source=standard, basis=basis)

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
    b = boundaries if boundaries is not None else zone_boundaries(machine_class,
                                                                   standard=standard)
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
    shown = "A/B" if b.merged_ab and allowed_zone in ("A", "B") else allowed_zone
    detail = (f"worst {worst * 1e3:.3g} mm/s rms{at} is in zone {worst_zone} (allowed up to "
              f"{shown}, {limit * 1e3:.3g} mm/s)")
    source = f"{cls}{b.source}" + (f"; {class_reason}" if class_reason else "")
    return LimitCheck(name=name, quantity="velocity rms", value=worst, limit=float(limit),
                      units="m/s", status="pass" if passed else "fail", detail=detail,
                      source=source, basis=basis, data=frame)


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
                      value=float(ratio[k]), limit=1.0, units="1",
                      status="pass" if g.passed else "fail", detail=detail,
                      source="ISO 21940-11:2016 §5, U_per = G m / Ω",
                      basis=f"{len(g.residual)} correction plane(s), {rotor_mass:g} kg, "
                            f"{speed:g} rpm", data=g)


def __getattr__(name):
    if name == "check_torsional_stress":  # lives beside the rule verdicts
        from .torsional_limits import check_torsional_stress

        return check_torsional_stress
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
