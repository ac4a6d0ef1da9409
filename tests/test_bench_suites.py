"""The bench-suite registry contract, checked cheaply: every ``analysis/bench/suite_*.py``
imports without doing work, has a docstring saying what it measures and a ``run(quick)``
callable. Running all suites is ``crankbench bench --quick`` (minutes); only the fidelity
suite (≈ 6 s quick) runs here, and its rows are checked against their own definition."""

import importlib
import inspect
import math

import numpy as np
import pytest

import crankbench.analysis.bench as bench
from crankbench.analysis.bench import Row
from crankbench.analysis.bench.suite_fidelity import paired_ratio, pareto_distance

SUITES = bench.suites()


def test_every_expected_suite_is_registered():
    expected = {"io", "kinematics", "balance", "orders", "torsion", "lateral", "fidelity"}
    missing = expected - set(SUITES)
    assert not missing, f"suites missing from analysis/bench: {sorted(missing)}"


@pytest.mark.parametrize("name", SUITES)
def test_suite_module_contract(name):
    module = importlib.import_module(f"crankbench.analysis.bench.suite_{name}")
    doc = inspect.getdoc(module)
    assert doc and len(doc.split()) >= 8, f"suite_{name} needs a docstring saying what it measures"
    assert callable(getattr(module, "run", None)), f"suite_{name} has no run(quick) callable"
    params = list(inspect.signature(module.run).parameters)
    assert params[:1] == ["quick"], f"suite_{name}.run must take quick as its first argument"


def test_pareto_distance_definition():
    sweep = [(2, 1e-3), (4, 1e-7), (6, 1e-9), (8, 1e-12)]
    asked = []

    def ratio(f):
        asked.append(f)
        return {4: 1.45}[f]

    # on the front: the cheapest fidelity meeting the tolerance costs nothing extra, unmeasured
    assert pareto_distance(4, 1e-7, sweep, 1e-6, cost_ratio=ratio) == 0.0 and asked == []
    # above it: the side-by-side cost ratio to the cheapest one (4), never below 0
    assert pareto_distance(8, 1e-12, sweep, 1e-6, cost_ratio=ratio) == pytest.approx(0.45)
    assert asked == [4]
    assert pareto_distance(6, 1e-9, sweep, 1e-6, cost_ratio=lambda f: 0.8) == 0.0
    # missing the tolerance is infinitely far; nothing manual meets it -> extends the front
    assert math.isinf(pareto_distance(2, 1e-3, sweep, 1e-6, cost_ratio=ratio))
    assert pareto_distance(8, 1e-14, sweep, 1e-13, cost_ratio=ratio) == 0.0


def test_paired_ratio_sees_a_twofold_cost():
    import time as _time

    # this thread's CPU time on both sides: busy threads elsewhere in the test process (BLAS
    # pools, hashing threads) count in the process clock and made the ratio flaky
    def spin(seconds):
        def run():
            t0 = _time.thread_time()
            while _time.thread_time() - t0 < seconds:
                pass
        return run

    r = paired_ratio(spin(0.004), spin(0.002), pairs=3, min_time=0.0,
                     cpu_clock=_time.thread_time)
    assert 1.3 < r < 3.0


def test_fidelity_suite_quick_rows():
    # (its < 20 s quick budget is measured by ``crankbench bench --quick``, not asserted here:
    # wall time on a shared CI machine is not a correctness property)
    rows = importlib.import_module("crankbench.analysis.bench.suite_fidelity").run(quick=True)
    assert rows and all(isinstance(r, Row) and r.suite == "fidelity" for r in rows)
    auto = [r for r in rows if " auto → " in r.setting]
    dist = [r for r in rows if r.setting.startswith("pareto distance")]
    assert {r.method for r in auto} == {r.method for r in dist}
    assert len(dist) == len(auto) >= 6
    for r in auto:                             # the automatic choice delivers its tolerance
        assert r.error <= r.bound, (r.method, r.setting, r.error)
        assert np.isfinite(r.time_s) and r.time_s > 0
    for r in dist:
        assert r.error_kind == "excess cost rel" and np.isfinite(r.error) and r.error >= 0
        if r.method.startswith("acceleration_series"):
            # the series order is the cheapest meeting the tolerance: exactly on the front
            assert r.extra["auto"] == r.extra["cheapest"] and r.error == 0.0
        elif r.method.startswith("exponential_coastdown"):
            # piece count from the chord bound: the cheapest, or one more piece
            assert r.extra["auto"] - r.extra["cheapest"] in (0, 1)
        else:
            assert r.extra["auto"] >= r.extra["cheapest"]


def test_fidelity_suite_examples_run():
    import doctest

    module = importlib.import_module("crankbench.analysis.bench.suite_fidelity")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
