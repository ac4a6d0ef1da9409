"""Three-state verdicts: never green without a basis."""

import pytest

from crankbench.analysis.verdict import FAIL, INCONCLUSIVE, PASS, Verdict, combine
from crankbench.predict.errors import AnalysisError


def _v(status, name="x", required=True):
    reason = "" if status == PASS else "because"
    return Verdict(name, status, "rule", "data", reason, required)


@pytest.mark.parametrize(("statuses", "expected"), [
    ([], INCONCLUSIVE),
    ([PASS], PASS),
    ([PASS, PASS], PASS),
    ([PASS, INCONCLUSIVE], INCONCLUSIVE),
    ([PASS, FAIL, INCONCLUSIVE], FAIL),
    ([INCONCLUSIVE], INCONCLUSIVE),
])
def test_combine_truth_table(statuses, expected):
    assert combine([_v(s, f"c{i}") for i, s in enumerate(statuses)]).status == expected


def test_informational_checks_do_not_count():
    only_info = combine([_v(PASS, required=False)])
    assert only_info.status == INCONCLUSIVE and only_info.reason == "nothing was assessed"
    assert combine([_v(PASS), _v(FAIL, required=False)]).status == PASS


def test_combined_reason_names_the_checks():
    v = combine([_v(PASS, "stress"), _v(FAIL, "critical 1/6"), _v(FAIL, "vibration")])
    assert v.reason == "failed: critical 1/6, vibration"
    assert "stress: pass" in v.basis


def test_no_green_without_basis_and_no_red_without_reason():
    with pytest.raises(AnalysisError, match="passes with no basis"):
        Verdict.passed("stress", rule="M68", basis=" ")
    with pytest.raises(AnalysisError, match="is inconclusive with no reason"):
        Verdict("stress", INCONCLUSIVE, "M68", "data", "")
    with pytest.raises(AnalysisError, match="expected one of pass, fail, inconclusive"):
        Verdict("stress", "ok", "M68", "data")


def test_from_bool_and_ok():
    assert Verdict.from_bool("a", True, rule="r", basis="b").ok is True
    assert Verdict.from_bool("a", False, rule="r", basis="b").ok is False
    assert Verdict.inconclusive("a", rule="r", basis="b", reason="c").ok is None
