"""Torsional vibratory stress against the rule: the transient limit, and barred speed ranges
placed where the rule allows them.

:func:`check_torsional_stress` turns a superposed stress per shaft section over speed (measured
through the torsiograph, or predicted, or predicted with one cylinder misfiring) into two
:class:`analysis.limits.LimitCheck` rows, in MPa:

1. **transient limit** — the stress never exceeds τ_T anywhere (IACS UR M68.5 τ_T = 1.7 τ_C/√C_K
   for shafting; the engine maker's transient figure for the crankshaft);
2. **continuous limit and barred speed ranges** — where the stress exceeds τ_C the speed range
   is barred, and the range is judged against where the rule allows it
   (:func:`predict.torsion.rules.judge_barred_ranges`: for propulsion no barred range above
   λ = 0.8 in normal operation, so a barred range at or near the rated speed fails).

A check whose data are missing (no limits in the model, a section without rule data, the
measured run not covering the operating range) is "not assessed": inconclusive with the reason,
never a pass.
"""

from __future__ import annotations

import numpy as np

from crankbench.predict._validate import check_finite_array
from crankbench.predict.errors import AnalysisError, ModelError

from .limits import LimitCheck

__all__ = ["check_torsional_stress", "not_assessed"]


def not_assessed(name, reason, *, rule="IACS UR M68.5 / engine maker's figure", basis="",
                 required=True) -> LimitCheck:
    """A torsional-stress check that could not be made: inconclusive with ``reason``.

    Examples
    --------
    >>> c = not_assessed("torsional stress", "the model has no [limits] table")
    >>> print(c.status, "|", c.detail)
    inconclusive | not assessed: the model has no [limits] table
    """
    return LimitCheck(name=name, quantity="shear stress amplitude", value=float("nan"),
                      limit=float("nan"), units="Pa", status="inconclusive",
                      detail=f"not assessed: {reason}", source=rule, basis=basis,
                      required=required)


def _ranges_text(ranges):
    return ", ".join(f"{a:.0f}–{b:.0f}" for a, b in ranges) + " rpm"


def check_torsional_stress(speed_rpm, stress, limits, *, sections=None, section="",
                           operating_range_rpm=None, rated_speed_rpm=None, misfire=False,
                           name="torsional vibratory stress", basis="", required=True,
                           covered_rpm=None, predicted=False):
    """Hold a vibratory shear stress over speed against the rule's limits.

    Parameters
    ----------
    speed_rpm : array_like
        Speeds, rpm, strictly ascending (engine speed; λ = speed / rated speed).
    stress : array_like
        Vibratory shear stress amplitude, Pa: (n_speeds,) for one section or
        (n_speeds, n_sections).
    limits : predict.torsion.rules.RuleLimits or predict.torsion.stress.StressLimits
        From the model's ``[limits]``.
    sections : sequence of str, optional
        Section names of the columns of ``stress`` (default ``[section]``).
    section : str
        Name of a single section.
    operating_range_rpm : (float, float), optional
        Continuous-operation range (default: the limits' own).
    rated_speed_rpm : float, optional
        n_0 (default: the limits' own).
    misfire : bool
        The stress is that of the one-cylinder misfire case (barred ranges are stated; M68.5).
    name : str
    basis : str
        The data the check rests on.
    required : bool
        Counts towards the overall verdict.
    covered_rpm : (float, float), optional
        Speed range the data cover (default: that of ``speed_rpm``); a check whose data do not
        cover the operating range is inconclusive for the barred-range judgement.
    predicted : bool
        The stress is calculated, not measured: each barred range is widened to at least the
        rule's extent 16 n_c/(18 − λ_c) … (18 − λ_c) n_c/16 around its worst speed n_c
        (:func:`predict.torsion.rules.m68_barred_range`). Measured ranges are used as measured
        (plus the tachometer tolerance), which the rule allows for a range verified by
        measurement (KR Rules for Steel Ships 2025 Pt 5 Ch 4 206.3).

    Returns
    -------
    tuple of LimitCheck
        (transient limit, continuous limit and barred ranges); values and limits in Pa,
        ``data`` the :class:`predict.torsion.stress.StressCheck`.

    References
    ----------
    IACS UR M68 (permissible torsional vibration stresses, barred speed ranges), as reproduced
    in KR Rules for Steel Ships 2025 Pt 5 Ch 4 202 and 206; see :mod:`predict.torsion.rules`
    for what was checked against which text.

    Examples
    --------
    A crankshaft section with the maker's 42/105 MPa, rated 720 rpm, resonance at rated speed:

    >>> from crankbench.predict.torsion.rules import MakerLimit, RuleLimits
    >>> lim = RuleLimits(rated_speed_rpm=720.0, operating_range_rpm=(500.0, 750.0),
    ...                  crankshaft=MakerLimit(("crank",), 42e6, 105e6))
    >>> speed = np.linspace(400.0, 760.0, 37)
    >>> tau = 20e6 + 40e6 * np.exp(-((speed - 720.0) / 15.0) ** 2)  # 42 MPa at 720 ± 11.6 rpm
    >>> trans, cont = check_torsional_stress(speed, tau, lim, section="crank")
    >>> print(trans.status, "|", cont.status, "|", cont.detail)
    pass | fail | barred 708–732 rpm reaches above λ = 0.8 (576 rpm); it contains the rated speed 720 rpm
    """
    from crankbench.predict.torsion.rules import (
        RuleLimits,
        judge_barred_ranges,
        m68_barred_range,
    )
    from crankbench.predict.torsion.stress import StressLimits, check_stress

    if not isinstance(limits, (RuleLimits, StressLimits)):
        raise AnalysisError(f"limits must be a predict.torsion.rules.RuleLimits or "
                            f"predict.torsion.stress.StressLimits, got {type(limits).__name__}")
    speed = check_finite_array(speed_rpm, "speed_rpm", ndim=1, min_length=2, error=AnalysisError)
    tau = np.asarray(stress, float)
    if tau.ndim == 1:
        tau = tau[:, None]
    if tau.ndim != 2 or tau.shape[0] != speed.size:
        raise AnalysisError(f"stress has {tau.shape[0] if tau.ndim else 0} values, speed_rpm "
                            f"{speed.size}")
    if not np.isfinite(tau).all():
        raise AnalysisError("stress must be finite (Pa)")
    if np.any(np.diff(speed) <= 0):
        raise AnalysisError("speed_rpm must be strictly ascending")
    names = list(sections) if sections is not None else [section or "section"]
    if len(names) != tau.shape[1]:
        raise AnalysisError(f"{len(names)} section names for {tau.shape[1]} stress columns")
    application = getattr(limits, "application", "propulsion")
    rated = rated_speed_rpm if rated_speed_rpm is not None else getattr(
        limits, "rated_speed_rpm", None)
    op = operating_range_rpm if operating_range_rpm is not None else getattr(
        limits, "operating_range_rpm", None)
    tol = float(getattr(limits, "tachometer_tolerance_rpm", 0.0))
    label = f"{name} ({names[0]})" if len(names) == 1 and names[0] != "section" else name
    from types import SimpleNamespace

    response = SimpleNamespace(speed_rpm=speed, stress_total=tau, edge_names=tuple(names))
    lim_names = tuple(getattr(limits, "sections", ()))
    if lim_names and not set(lim_names) & set(names):
        return (not_assessed(f"{label}, transient", "no section with rule data was evaluated",
                             basis=basis, required=required),
                not_assessed(f"{label}, continuous and barred ranges",
                             "no section with rule data was evaluated", basis=basis,
                             required=required))
    shown = [n for n in names if not lim_names or n in lim_names]
    keep = [names.index(n) for n in shown]
    response.stress_total, response.edge_names = tau[:, keep], tuple(shown)
    try:
        result = check_stress(response, _Only(limits, shown))
    except ModelError as exc:
        return (not_assessed(f"{label}, transient", str(exc), basis=basis, required=required),
                not_assessed(f"{label}, continuous and barred ranges", str(exc), basis=basis,
                             required=required))
    rules = "; ".join(sorted(set((result.rules or {}).values())))
    # transient limit
    with np.errstate(invalid="ignore", divide="ignore"):
        rt = np.nan_to_num(result.worst_stress / result.transient, nan=-np.inf)
        rc = np.nan_to_num(result.worst_stress / result.continuous, nan=-np.inf)
    kt = int(np.argmax(rt))
    if result.transient_exceeded_rpm:
        t_status, t_detail = "fail", (f"transient limit exceeded at "
                                      f"{_ranges_text(result.transient_exceeded_rpm)} "
                                      f"({result.worst_section[kt]})")
    else:
        t_status, t_detail = "pass", (f"worst {result.worst_stress[kt] / 1e6:.3g} MPa at "
                                      f"{speed[kt]:.0f} rpm ({result.worst_section[kt]}), "
                                      f"{100 * rt[kt]:.0f} % of τ_T")
    transient = LimitCheck(
        name=f"{label}, transient", quantity="shear stress amplitude",
        value=float(result.worst_stress[kt]), limit=float(result.transient[kt]), units="Pa",
        status=t_status, detail=t_detail, source=rules, basis=basis, required=required,
        data=result)
    # continuous limit: barred ranges where the rule allows them
    kc = int(np.argmax(rc))
    ranges = list(result.barred_ranges_rpm)
    if predicted and rated is not None:
        widened = []
        for a, b in ranges:
            inside = (speed >= a) & (speed <= b)
            nc = float(speed[inside][np.argmax(rc[inside])]) if inside.any() else 0.5 * (a + b)
            lo_r, hi_r = m68_barred_range(nc, rated)
            widened.append((min(a, lo_r), max(b, hi_r)))
        ranges = widened
    status, reason, rule = judge_barred_ranges(
        ranges, application=application, rated_speed_rpm=rated,
        operating_range_rpm=op, tachometer_tolerance_rpm=tol, misfire=misfire)
    if predicted and ranges:
        rule += "; calculated stress: barred extent 16 n_c/(18 − λ_c) … (18 − λ_c) n_c/16"
    lo, hi = covered_rpm if covered_rpm is not None else (speed[0], speed[-1])
    need = op if op is not None else ((None, rated) if rated is not None else None)
    if status == "pass" and need is not None:
        gaps = []
        if need[0] is not None and lo > need[0] * 1.01:
            gaps.append(f"{need[0]:.0f}–{lo:.0f}")
        if need[1] is not None and hi < need[1] * 0.99:
            gaps.append(f"{hi:.0f}–{need[1]:.0f}")
        if gaps:
            status = "inconclusive"
            reason = (f"{reason}; but the data cover {lo:.0f}–{hi:.0f} rpm only: "
                      f"{', '.join(gaps)} rpm of the operating range not assessed")
    if op is not None and ranges and status == "pass" and \
            application == "propulsion" and not misfire:
        inside = [r for r in ranges if r[1] >= op[0] and r[0] <= op[1]]
        if inside:
            reason += (f"; {_ranges_text(inside)} lies in the operating range "
                       f"{op[0]:.0f}–{op[1]:.0f} rpm: to be passed rapidly")
    continuous = LimitCheck(
        name=f"{label}, continuous and barred ranges", quantity="shear stress amplitude",
        value=float(result.worst_stress[kc]), limit=float(result.continuous[kc]), units="Pa",
        status=status, detail=reason, source=f"{rules}; {rule}", basis=basis,
        required=required, data=result)
    return transient, continuous


class _Only:
    """Limits restricted to the given sections (the others were not evaluated)."""

    def __init__(self, limits, sections):
        self._limits, self.sections = limits, tuple(sections)

    def limits_for(self, section, speed_rpm, *, diameter=None):
        return self._limits.limits_for(section, speed_rpm, diameter=diameter)
