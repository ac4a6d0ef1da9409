"""Three-state verdicts: pass, fail or inconclusive, each naming its rule and its data.

Every check that ends up in front of a customer or a surveyor (a limit, a comparison of a
measured critical speed with its prediction, a balance residual against its tolerance) is a
:class:`Verdict`. A verdict is never green without a basis: a check that could not be made (no
resonance crossed, no limit data in the model, a steady run with nothing to compare) is
``inconclusive`` with the reason, and :func:`combine` makes the overall verdict ``pass`` only
when every required check passed and at least one was made.

Examples
--------
>>> a = Verdict.passed("torsional stress, continuous", rule="IACS UR M68 (τ_C)",
...                    basis="predicted response 500-750 rpm")
>>> b = Verdict.inconclusive("vibration severity", rule="ISO 10816-6",
...                          basis="no block accelerometer in the record",
...                          reason="no channel to assess")
>>> combine([a, b]).status
'inconclusive'
>>> combine([a]).status
'pass'
>>> combine([]).reason
'nothing was assessed'
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from crankbench.predict.errors import AnalysisError

__all__ = ["PASS", "FAIL", "INCONCLUSIVE", "STATUSES", "Verdict", "combine"]

PASS = "pass"
FAIL = "fail"
INCONCLUSIVE = "inconclusive"
STATUSES = (PASS, FAIL, INCONCLUSIVE)


@dataclass(frozen=True)
class Verdict:
    """The outcome of one check.

    Attributes
    ----------
    name : str
        What was judged ("torsional stress, continuous", "critical mode 1 order 6").
    status : {'pass', 'fail', 'inconclusive'}
    rule : str
        The rule or criterion and where it comes from (standard and clause, or the stated
        tolerance: "measured critical within ±3 % of predicted").
    basis : str
        The data it rests on (channel, speed range, record, model file).
    reason : str
        Why it failed or could not be made; for a pass, optional detail.
    required : bool
        Whether it counts towards the overall verdict (informational checks do not).
    """

    name: str
    status: str
    rule: str
    basis: str
    reason: str = ""
    required: bool = True

    def __post_init__(self):
        if self.status not in STATUSES:
            raise AnalysisError(f"verdict status {self.status!r} for {self.name!r}: expected one "
                                f"of {', '.join(STATUSES)}")
        if self.status == PASS and not self.basis.strip():
            raise AnalysisError(f"verdict {self.name!r} passes with no basis: name the data "
                                "it rests on")
        if self.status != PASS and not self.reason.strip():
            raise AnalysisError(f"verdict {self.name!r} is {self.status} with no reason")

    @classmethod
    def passed(cls, name: str, *, rule: str, basis: str, reason: str = "",
               required: bool = True) -> "Verdict":
        """A passed check."""
        return cls(name, PASS, rule, basis, reason, required)

    @classmethod
    def failed(cls, name: str, *, rule: str, basis: str, reason: str,
               required: bool = True) -> "Verdict":
        """A failed check; ``reason`` says what exceeded what."""
        return cls(name, FAIL, rule, basis, reason, required)

    @classmethod
    def inconclusive(cls, name: str, *, rule: str, basis: str, reason: str,
                     required: bool = True) -> "Verdict":
        """A check that could not be made; ``reason`` says what was missing."""
        return cls(name, INCONCLUSIVE, rule, basis, reason, required)

    @classmethod
    def from_bool(cls, name: str, ok: bool, *, rule: str, basis: str, reason: str = "",
                  required: bool = True) -> "Verdict":
        """Pass when ``ok``; fail with ``reason`` otherwise."""
        if ok:
            return cls.passed(name, rule=rule, basis=basis, reason=reason, required=required)
        return cls.failed(name, rule=rule, basis=basis, reason=reason or "limit exceeded",
                          required=required)

    @property
    def ok(self) -> bool | None:
        """True for pass, False for fail, None for inconclusive."""
        return {PASS: True, FAIL: False}.get(self.status)

    def as_dict(self) -> dict:
        """Row for tables and JSON."""
        return {"check": self.name, "verdict": self.status, "rule": self.rule,
                "basis": self.basis, "reason": self.reason, "required": self.required}


def combine(verdicts: Iterable[Verdict], *, name: str = "overall") -> Verdict:
    """The overall verdict of several checks.

    ``fail`` if any required check failed; otherwise ``inconclusive`` if none was required and
    made, or any required check was inconclusive; otherwise ``pass``.

    Parameters
    ----------
    verdicts : iterable of Verdict
    name : str
        Name of the combined verdict.

    Returns
    -------
    Verdict
        Its ``rule`` says how it was combined, its ``basis`` lists the checks.
    """
    verdicts = [v for v in verdicts if v.required]
    rule = "fail if any required check fails; pass only if every required check passed"
    basis = "; ".join(f"{v.name}: {v.status}" for v in verdicts) or "no checks"
    failed = [v.name for v in verdicts if v.status == FAIL]
    open_ = [v.name for v in verdicts if v.status == INCONCLUSIVE]
    if failed:
        return Verdict.failed(name, rule=rule, basis=basis, reason="failed: " + ", ".join(failed))
    if not verdicts:
        return Verdict.inconclusive(name, rule=rule, basis=basis, reason="nothing was assessed")
    if open_:
        return Verdict.inconclusive(name, rule=rule, basis=basis,
                                    reason="not assessed: " + ", ".join(open_))
    return Verdict.passed(name, rule=rule, basis=basis)
