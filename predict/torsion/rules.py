"""Torsional-vibration stress limits from the classification rule, and barred speed ranges.

**Shafting (propulsion and auxiliary): IACS UR M68.** The permissible amplitude of the
torsional vibration stress (half the range of the superposed alternating stress over a cycle,
nominal stress on the plain section) for

* continuous operation (λ = n/n_0):

  - ``τ_C = ± (σ_B + 160) / 18 · C_K · C_D · (3 − 2 λ²)``  for λ < 0.9,
  - ``τ_C = ± (σ_B + 160) / 18 · C_K · C_D · 1.38``         for 0.9 ≤ λ ≤ 1.05
    (the two branches meet at λ = 0.9: 3 − 2·0.81 = 1.38); no value above λ = 1.05;

* transient operation (passing rapidly through a barred speed range), **only below
  λ = 0.8**: ``τ_T = ± 1.7 τ_C / √C_K``. Above λ = 0.8 the rule gives no transient allowance,
  so :func:`m68_limits` returns τ_T = τ_C there (exceeding τ_C above 0.8 n_0 is not permitted
  even in passing);

with σ_B the specified minimum tensile strength of the shaft material (N/mm²), in the formula
limited to 760 N/mm² (carbon and carbon-manganese steel), 800 N/mm² (alloy steel) and
600 N/mm² for propeller shafts (:data:`TENSILE_CAP_MPA`); C_K the factor of the shaft's design
feature (:data:`M68_CK`); C_D = 0.35 + 0.93 d^(−0.2) the size factor (d in mm); n_0 the rated
(maximum continuous) speed, for constant-speed generating sets the full-load speed.

Barred speed ranges: where the stress exceeds τ_C — including one-cylinder misfiring if the
plant is intended to run so — a barred range is imposed, marked on the tachometer and passed
rapidly; its extent from a calculation is ``16 n_c/(18 − λ_c) ≤ n ≤ (18 − λ_c) n_c/16`` around
the critical speed n_c (:func:`m68_barred_range`); a range verified by measurement may be used
instead, having regard to the tachometer accuracy (what :func:`barred_ranges` plus
``tachometer_tolerance_rpm`` does on measured stress). **No barred range in normal firing above
λ = 0.8** (:func:`judge_barred_ranges`); under one-cylinder misfire the ranges must still allow
safe navigation (a judgement the report leaves to the surveyor, stating the ranges).

**Crankshafts** are outside M68 (its scope clause M68.1 sends them to UR M53): their
permissible vibratory stress is the engine maker's figure, entered in the model
(``[limits.crankshaft]``).

What was checked against published text, and where (the UR's own PDF was not reachable; these
are class-society rules that reproduce it, all IACS members):

* **Formulas, both τ_C branches with their λ ranges, τ_T = 1.7 τ_C/√C_K "within the range
  below 80 % of the maximum continuous revolutions", every C_K value of the table with its notes
  (keyways not to be used with a barred range; radial hole ≤ 0.3 d; slot limits; propeller
  shaft 0.55 from the aftmost bearing to the boss, ≥ 2.5 d_s; stern tube shaft 0.8),
  C_D = 0.35 + 0.93 d^(−0.2), and the barred-range extent 16 n_c/(18 − λ_c) … (18 − λ_c) n_c/16
  with the misfire and measured-range clauses**: Korean Register, *Rules for the
  Classification of Steel Ships* (2025), Pt 5 Ch 4 "Torsional vibration of shaftings",
  Sec 2, 202.1(1)–(2), Table 5.4.1, 206.1(1)–(3) and 206.3 [2]_. All match this module.
* **σ_B caps** 760 (carbon, C-Mn) / 800 (alloy) N/mm² and the 500 N/mm² minimum where
  stresses approach the transient limit: LR Rules for Naval Ships Vol 2 Pt 3 Ch 2 §3.1.2–3.1.5
  and LR Rules for Special Service Craft Pt 11 Ch 2 §3.1.2–3.1.5 [3]_; 600 N/mm² for propeller
  shafts, 760 carbon / 800 alloy otherwise (for the shaft formulae): GL (BKI) Rules I-1-2
  Sec 4 A.2 (2008) [4]_.
  **Differs**: KR 202.1(1) (amended 2017) caps carbon-steel σ_B at 600 N/mm² for *all*
  shafts — stricter than the 760 used here; a KR-classed ship needs ``tensile_strength_mpa``
  ≤ 600 entered for carbon steel.
* **Symbols and n_0 for constant-speed sets**: LR Naval Ships Vol 2 Pt 5 Ch 1 §3.1.1 [5]_.
* **No barred range above λ = 0.8 for normal firing**: the sentence itself in KR Guidance
  Annex 5-3 §2(2)(A)(d) (the UR M53 crankshaft text); for shafting it follows from τ_T being
  granted only below λ = 0.8 (KR 202.1(2)).
* **Clause numbers**: the headings M68.1 (scope, crankshafts excluded → M53) and M68.2
  (alternative calculation methods) were read in a published copy of the UR (Corr.2 Nov 2012,
  Aug 2014) [1]_. The numbers M68.3 (material), M68.4 (diameters, C_K table) and M68.5
  (permissible torsional vibration stresses, barred ranges) used in ``source`` texts follow the
  UR's layout as transcribed, **not seen in a published copy**. The current edition is Rev.3
  (Feb 2021) per two secondary sources; the formulas above are those of the 2025 KR rules.

References
----------
.. [1] IACS Unified Requirement M68, *Dimensions of propulsion shafts and their permissible
   torsional vibration stresses* (Corr.2 Nov 2012, Aug 2014; Rev.3 Feb 2021).
.. [2] Korean Register, Rules for the Classification of Steel Ships 2025 (RA-05-E), Pt 5 Ch 4,
   Sec 2 "Allowable limit of vibration stresses", 202 (intermediate, thrust, propeller and
   stern tube shafts), Table 5.4.1 (C_k), 206 (barred speed range); Guidance Annex 5-3.
.. [3] Lloyd's Register, Rules for the Classification of Naval Ships (Jan 2023), Vol 2 Pt 3
   Ch 2 §3.1 (materials for shafts); Rules for Special Service Craft Pt 11 Ch 2 §3.1.
.. [4] Germanischer Lloyd / BKI, Rules I-1-2 (2008), Section 4 Main Shafting, A.2 (limits of
   R_m used in the formulae).
.. [5] Lloyd's Register, Rules for the Classification of Naval Ships, Vol 2 Pt 5 Ch 1 §3.1
   (symbols, C_d size factor, C_k table, N_s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_finite_array, check_option, check_positive
from ..errors import ModelError

__all__ = ["M68_CK", "M68_SOURCE", "TENSILE_CAP_MPA", "size_factor", "m68_limits",
           "m68_barred_range", "SectionRule", "MakerLimit", "RuleLimits", "barred_ranges", "judge_barred_ranges"]

M68_SOURCE = "IACS UR M68"

#: C_K factors of UR M68 (M68.4, Table 1) by design feature of the shaft section
M68_CK = {
    "integral flange": 1.0,          # intermediate shaft, integral coupling flange, straight
    "shrink fit coupling": 1.0,
    "keyway tapered": 0.60,
    "keyway cylindrical": 0.45,
    "radial hole": 0.50,
    "longitudinal slot": 0.30,
    "thrust collar": 0.85,           # thrust shaft external to engine, either side of collar
    "axial roller bearing": 0.85,    # in way of an axial bearing that is a roller bearing
    "propeller flange": 0.55,        # propeller shaft, flange-mounted or keyless taper propeller
    "propeller key": 0.55,           # propeller shaft, key-fitted propeller
    "stern tube seal": 0.80,         # between the aftmost bearing's forward end and the seal
}

#: upper bound of σ_B in the M68 formulas, N/mm² (M68.3/M68.4)
TENSILE_CAP_MPA = {"carbon": 760.0, "alloy": 800.0, "propeller": 600.0}

_CLAUSE_BSR = "M68.5 (no barred speed range above λ = 0.8 in normal operation)"


def size_factor(diameter):
    """Size factor C_D = 0.35 + 0.93 d^(−0.2) of UR M68, d the shaft diameter.

    Parameters
    ----------
    diameter : float or array_like
        Shaft diameter, m (the rule's d is in mm).

    Returns
    -------
    float or ndarray

    Examples
    --------
    >>> print(round(size_factor(0.400), 4))
    0.6306
    """
    d_mm = np.asarray(diameter, float) * 1e3
    if np.any(~np.isfinite(d_mm)) or np.any(d_mm <= 0):
        raise ModelError(f"size_factor: diameter={diameter!r} must be > 0 (m)")
    out = 0.35 + 0.93 * d_mm ** -0.2
    return float(out) if out.ndim == 0 else out


def m68_limits(speed_rpm, *, tensile_strength, diameter, ck, rated_speed_rpm):
    """Continuous and transient torsional-vibration stress limits of IACS UR M68.5.

    Parameters
    ----------
    speed_rpm : array_like
        Speeds, rpm.
    tensile_strength : float
        σ_B used in the formula, Pa (already capped, see :data:`TENSILE_CAP_MPA`).
    diameter : float
        Shaft diameter, m.
    ck : float
        Design-feature factor C_K (:data:`M68_CK`), 0 < C_K ≤ 1.
    rated_speed_rpm : float
        n_0, rpm (full-load speed for constant-speed generating sets).

    Returns
    -------
    (ndarray, ndarray)
        τ_C and τ_T at each speed, Pa (stress amplitude). Above λ = 1.05 the rule gives no
        value: NaN. τ_T = 1.7 τ_C/√C_K below λ = 0.8 (the only range where the rule grants a
        transient allowance, KR Pt 5 Ch 4 202.1(2)); τ_T = τ_C from λ = 0.8 up.

    References
    ----------
    IACS UR M68 (permissible torsional vibration stresses), as reproduced in KR Rules for
    Steel Ships 2025 Pt 5 Ch 4 202.1(1)–(2); see the module docstring for what was checked.

    Examples
    --------
    Intermediate shaft, σ_B = 600 N/mm², d = 400 mm, integral flange, at λ = 0.5 and 1.0:

    >>> tc, tt = m68_limits([360.0, 720.0], tensile_strength=600e6, diameter=0.4, ck=1.0,
    ...                     rated_speed_rpm=720.0)
    >>> print(np.round(tc / 1e6, 2), np.round(tt / 1e6, 2))
    [66.56 36.74] [113.16 36.74]
    """
    s = check_finite_array(speed_rpm, "speed_rpm", ndim=1, error=ModelError)
    sigma = check_positive(tensile_strength, "tensile_strength", error=ModelError) / 1e6
    n0 = check_positive(rated_speed_rpm, "rated_speed_rpm", error=ModelError)
    if not 0.0 < float(ck) <= 1.0:
        raise ModelError(f"ck={ck!r} must be in (0, 1] (UR M68 C_K)")
    lam = s / n0
    base = (sigma + 160.0) / 18.0 * float(ck) * size_factor(diameter)
    shape = np.where(lam < 0.9, 3.0 - 2.0 * lam**2, 1.38)
    tc = np.where(lam <= 1.05 + 1e-12, base * shape, np.nan) * 1e6
    # no transient allowance from λ = 0.8 up (τ_T is granted "below 80 % of n_0" only)
    tt = np.where(lam < 0.8, 1.7 * tc / np.sqrt(float(ck)), tc)
    return tc, tt


def m68_barred_range(critical_speed_rpm, rated_speed_rpm):
    """Barred speed range of UR M68 around a critical speed found by calculation.

    ``16 n_c / (18 − λ_c) ≤ n ≤ (18 − λ_c) n_c / 16``, λ_c = n_c / n_0 (KR Rules for Steel
    Ships 2025 Pt 5 Ch 4 206.1(1), reproducing the UR). A range verified by measurement may
    replace it (206.3), with the tachometer accuracy added.

    Parameters
    ----------
    critical_speed_rpm : float
        n_c, the speed of the resonance whose stress exceeds τ_C, rpm.
    rated_speed_rpm : float
        n_0, rpm.

    Returns
    -------
    (float, float)
        Lower and upper end of the barred range, rpm.

    Examples
    --------
    A critical at 400 rpm on an engine rated 720 rpm (λ_c = 0.556):

    >>> lo, hi = m68_barred_range(400.0, 720.0)
    >>> print(round(lo, 1), round(hi, 1))
    366.9 436.1
    """
    nc = check_positive(critical_speed_rpm, "critical_speed_rpm", error=ModelError)
    n0 = check_positive(rated_speed_rpm, "rated_speed_rpm", error=ModelError)
    lam = nc / n0
    if lam >= 18.0:
        raise ModelError(f"critical_speed_rpm={nc!r} is {lam:.1f} × rated_speed_rpm: the M68 "
                         "barred-range formula needs λ_c < 18")
    return 16.0 * nc / (18.0 - lam), (18.0 - lam) * nc / 16.0


@dataclass(frozen=True)
class SectionRule:
    """The M68 data of one shaft section (propulsion or auxiliary shafting).

    Attributes
    ----------
    section : str
        Section (edge) name of the shaft line.
    tensile_strength : float
        Specified minimum tensile strength σ_B, Pa (as given; the cap is applied in
        :meth:`limits`).
    design : str
        Design feature, a key of :data:`M68_CK`.
    material : {'carbon', 'alloy'}
    kind : {'intermediate', 'propeller', 'thrust'}
        Propeller shafts cap σ_B at 600 N/mm².
    diameter : float
        m (from the model's section when not given).
    """

    section: str
    tensile_strength: float
    design: str = "integral flange"
    material: str = "carbon"
    kind: str = "intermediate"
    diameter: float | None = None

    def __post_init__(self):
        check_option(self.design, "design", tuple(M68_CK), error=ModelError)
        check_option(self.material, "material", ("carbon", "alloy"), error=ModelError)
        check_option(self.kind, "kind", ("intermediate", "propeller", "thrust"),
                     error=ModelError)
        check_positive(self.tensile_strength, "tensile_strength", error=ModelError)

    @property
    def ck(self) -> float:
        return M68_CK[self.design]

    @property
    def sigma_used(self) -> float:
        """σ_B entering the formula, Pa: capped per M68.3/M68.4."""
        cap = TENSILE_CAP_MPA["propeller" if self.kind == "propeller" else self.material]
        return min(self.tensile_strength, cap * 1e6)

    def limits(self, speed_rpm, rated_speed_rpm, diameter=None):
        """(τ_C, τ_T) in Pa at the speeds (see :func:`m68_limits`)."""
        d = self.diameter if self.diameter is not None else diameter
        if d is None or not np.isfinite(d):
            raise ModelError(f"[limits.shafting] section {self.section!r}: no diameter (give "
                             "diameter in the section or the limits table)")
        return m68_limits(speed_rpm, tensile_strength=self.sigma_used, diameter=d, ck=self.ck,
                          rated_speed_rpm=rated_speed_rpm)

    def describe(self, diameter=None) -> str:
        d = self.diameter if self.diameter is not None else diameter
        capped = " (capped)" if self.sigma_used < self.tensile_strength else ""
        dd = f", d = {d * 1e3:.0f} mm, C_D = {size_factor(d):.3f}" if d else ""
        return (f"σ_B = {self.sigma_used / 1e6:.0f} N/mm²{capped}, C_K = {self.ck:g} "
                f"({self.design}){dd}")


@dataclass(frozen=True)
class MakerLimit:
    """The engine maker's permissible vibratory stress of crankshaft sections (outside M68).

    Attributes
    ----------
    sections : tuple of str
    continuous, transient : float
        Pa (stress amplitude); transient ≥ continuous.
    source : str
        The maker's document the figure comes from.
    """

    sections: tuple
    continuous: float
    transient: float
    source: str = "engine maker's figure"

    def __post_init__(self):
        check_positive(self.continuous, "continuous", error=ModelError)
        if not self.transient >= self.continuous:
            raise ModelError("[limits.crankshaft] transient_mpa must be >= continuous_mpa")


@dataclass(frozen=True)
class RuleLimits:
    """Everything the rule check needs, read from a shaft line's ``[limits]`` table.

    Attributes
    ----------
    application : {'propulsion', 'auxiliary'}
        Propulsion shafting, or an auxiliary (constant-speed generating) set.
    rated_speed_rpm : float or None
        n_0 (default: the engine's rated speed).
    operating_range_rpm : (float, float) or None
        Range of continuous operation.
    shafting : tuple of SectionRule
    crankshaft : MakerLimit or None
    misfire_operation : bool
        The plant is intended to run continuously with one cylinder misfiring (then the
        misfire case is a required check, M68.5).
    tachometer_tolerance_rpm : float
        Added to each end of a barred range (M68.5 asks for the tachometer tolerance).
    source : str
        Rule edition named in the report.
    curves : StressLimits or None
        User-given limit curves for the sections they name (held after the rule data).
    vibration : dict or None
        ``[limits.vibration]``: ``standard``, ``machine_class``, ``boundaries_mm_s`` (A/B, B/C,
        C/D, mm/s rms), ``source``.
    """

    application: str = "propulsion"
    rated_speed_rpm: float | None = None
    operating_range_rpm: tuple | None = None
    shafting: tuple = ()
    crankshaft: MakerLimit | None = None
    misfire_operation: bool = False
    tachometer_tolerance_rpm: float = 0.0
    source: str = M68_SOURCE
    curves: object = None
    vibration: dict | None = None

    def __post_init__(self):
        check_option(self.application, "application", ("propulsion", "auxiliary"),
                     error=ModelError)
        if self.curves is not None and self.source == M68_SOURCE and not self.shafting:
            object.__setattr__(self, "source", self.curves.source)

    @property
    def has_rule_data(self) -> bool:
        """True when some section has a limit (M68 data, maker's figure or curves)."""
        return bool(self.shafting or self.crankshaft is not None or self.curves is not None)

    @property
    def sections(self) -> tuple:
        """Every section with a limit (shafting first, then the crankshaft)."""
        out = [r.section for r in self.shafting]
        if self.crankshaft is not None:
            out += [s for s in self.crankshaft.sections if s not in out]
        if self.curves is not None:
            out += [s for s in self.curves.sections if s not in out]
        return tuple(out)

    def limits_for(self, section, speed_rpm, *, diameter=None):
        """(τ_C, τ_T, rule text) of ``section`` at the speeds, Pa.

        Raises ModelError when the section has no limit or n_0 is unknown for an M68 section.
        """
        speed = np.asarray(speed_rpm, float)
        for r in self.shafting:
            if r.section == section:
                if self.rated_speed_rpm is None:
                    raise ModelError("[limits] rated_speed_rpm is needed for the M68 limits "
                                     "(or rated_speed_rpm in the engine model)")
                tc, tt = r.limits(speed, self.rated_speed_rpm, diameter)
                return tc, tt, (f"{section}: {self.source} M68.5 τ_C, τ_T "
                                f"({r.describe(diameter)})")
        c = self.crankshaft
        if c is not None and section in c.sections:
            return (np.full(speed.shape, c.continuous), np.full(speed.shape, c.transient),
                    f"crankshaft {c.continuous / 1e6:.3g}/{c.transient / 1e6:.3g} MPa: "
                    f"{c.source} (outside UR M68: M68.1)")
        if self.curves is not None and (not self.curves.sections or
                                        section in self.curves.sections):
            tc, tt = self.curves.at(speed)
            return tc, tt, f"user-given curves: {self.curves.source}"
        raise ModelError(f"[limits] has no limit for section {section!r}")


def barred_ranges(speed_rpm, stress, limit):
    """Speed intervals where ``stress`` exceeds ``limit``, ends interpolated linearly.

    Parameters
    ----------
    speed_rpm, stress, limit : array_like
        Ascending speeds (rpm), stress and limit (same units) at each; NaN limits count as
        not exceeded.

    Returns
    -------
    list of (float, float)

    Examples
    --------
    >>> barred_ranges([100, 200, 300], [10, 50, 10], [30, 30, 30])
    [(150.0, 250.0)]
    """
    s = np.asarray(speed_rpm, float)
    excess = np.nan_to_num(np.asarray(stress, float) - np.asarray(limit, float), nan=-1.0)
    out, n, i = [], len(s), 0
    while i < n:
        if excess[i] <= 0:
            i += 1
            continue
        j = i
        while j + 1 < n and excess[j + 1] > 0:
            j += 1
        lo = s[i] if i == 0 else s[i - 1] + (s[i] - s[i - 1]) * -excess[i - 1] / (
            excess[i] - excess[i - 1])
        hi = s[j] if j == n - 1 else s[j] + (s[j + 1] - s[j]) * excess[j] / (
            excess[j] - excess[j + 1])
        out.append((float(lo), float(hi)))
        i = j + 1
    return out


def judge_barred_ranges(ranges, *, application, rated_speed_rpm, operating_range_rpm=None,
                        tachometer_tolerance_rpm=0.0, misfire=False):
    """Where a barred speed range may lie, per the rule: (status, reason, rule).

    Propulsion (UR M68.5): no barred range in normal operation above λ = 0.8, i.e. above
    0.8 n_0; under one-cylinder misfire any range is stated (safe navigation is judged by the
    surveyor), so only a range covering the rated speed fails. Auxiliary constant-speed sets:
    no barred range inside the operating range (n_0 is the full-load speed; the model's
    operating range is the acceptance band), and never at n_0.

    Parameters
    ----------
    ranges : list of (float, float)
        Barred ranges, rpm (before the tachometer tolerance).
    application : {'propulsion', 'auxiliary'}
    rated_speed_rpm : float or None
    operating_range_rpm : (float, float), optional
    tachometer_tolerance_rpm : float
        Widens each range at both ends.
    misfire : bool
        The ranges are those of the one-cylinder misfire case.

    Returns
    -------
    (str, str, str)
        Status 'pass' | 'fail' | 'inconclusive', the reason, and the rule applied.

    Examples
    --------
    >>> judge_barred_ranges([(709.0, 744.0)], application="propulsion", rated_speed_rpm=720.0)[:2]
    ('fail', 'barred 709–744 rpm reaches above λ = 0.8 (576 rpm); it contains the rated speed 720 rpm')
    >>> judge_barred_ranges([(260.0, 290.0)], application="propulsion", rated_speed_rpm=720.0)[0]
    'pass'
    """
    tol = float(tachometer_tolerance_rpm)
    widened = [(a - tol, b + tol) for a, b in ranges]
    text = ", ".join(f"{a:.0f}–{b:.0f}" for a, b in widened)
    if application == "propulsion":
        rule = f"{M68_SOURCE} {_CLAUSE_BSR}"
        if rated_speed_rpm is None:
            if not widened:
                return "pass", "no barred speed range", rule
            return ("inconclusive", "rated speed unknown: λ = 0.8 cannot be placed (give "
                    "rated_speed_rpm)", rule)
        n0 = float(rated_speed_rpm)
        if not widened:
            return "pass", "no barred speed range", rule
        at_rated = [r for r in widened if r[0] <= n0 <= r[1]]
        if misfire:
            rule = f"{M68_SOURCE} M68.5 (misfire: barred ranges stated; safe navigation)"
            if at_rated:
                return ("fail", f"misfire barred {text} rpm contains the rated speed "
                        f"{n0:.0f} rpm", rule)
            return "pass", f"misfire barred {text} rpm, below the rated speed", rule
        above = [r for r in widened if r[1] > 0.8 * n0]
        if above:
            reason = (f"barred {text} rpm reaches above λ = 0.8 ({0.8 * n0:.0f} rpm)"
                      + (f"; it contains the rated speed {n0:.0f} rpm" if at_rated else ""))
            return "fail", reason, rule
        return "pass", f"barred {text} rpm, all below λ = 0.8 ({0.8 * n0:.0f} rpm)", rule
    rule = ("auxiliary set: no barred speed range inside the operating range (n_0 = "
            "full-load speed, LR Naval Ships Vol 2 Pt 5 Ch 1 §3.1.1)")
    if not widened:
        return "pass", "no barred speed range", rule
    if operating_range_rpm is None:
        if rated_speed_rpm is None:
            return ("inconclusive", "neither operating range nor rated speed in the model",
                    rule)
        lo = hi = float(rated_speed_rpm)
    else:
        lo, hi = map(float, operating_range_rpm)
    inside = [r for r in widened if r[1] >= lo and r[0] <= hi]
    if inside:
        return "fail", f"barred {text} rpm overlaps the operating range {lo:.0f}–{hi:.0f} rpm", \
            rule
    return "pass", f"barred {text} rpm, outside the operating range {lo:.0f}–{hi:.0f} rpm", rule
