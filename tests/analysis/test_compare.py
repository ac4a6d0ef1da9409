"""Matching measured resonances to predicted criticals; balance comparison.

Measured inputs are constructed (or derived from an independently perturbed model) so these
tests do not depend on the synthetic bench.
"""

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from crankbench.analysis.compare import compare_balance, match_criticals
from crankbench.predict.errors import AnalysisError


def _pred(rows):
    return pd.DataFrame(rows, columns=["mode", "order", "speed_rpm"])


def test_assignment_beats_nearest_neighbour():
    """Nearest neighbour would give the 425 rpm critical both peaks; the assignment gives
    each critical one peak with the least total deviation."""
    pred = _pred([(1, 6.0, 400.0), (2, 6.0, 425.0)])
    meas = pd.DataFrame({"order": [6.0, 6.0], "speed_rpm": [415.0, 440.0]})
    c = match_criticals(meas, pred, gate=0.2, tolerance=0.05)
    got = dict(zip(c.matched["mode"], c.matched["speed_rpm_measured"]))
    assert got == {1: 415.0, 2: 440.0}
    np.testing.assert_allclose(c.matched["deviation_pct"], [3.75, 100 * 15 / 425])
    assert len(c.unmatched_measured) == 0 and len(c.unmatched_predicted) == 0


def test_orders_never_mix_and_gate_leaves_unmatched():
    pred = _pred([(1, 6.0, 400.0), (1, 4.5, 533.3)])
    meas = pd.DataFrame({"order": [4.5, 6.0], "speed_rpm": [400.0, 600.0]})
    c = match_criticals(meas, pred, gate=0.1)
    assert len(c.matched) == 0
    assert len(c.unmatched_measured) == 2 and len(c.unmatched_predicted) == 2
    assert not c.agrees
    assert any("order 6: measured resonance at 600.0 rpm matches no predicted critical"
               in f for f in c.flags)
    assert any("mode 1 order 4.5: predicted critical at 533.3 rpm not found" in f
               for f in c.flags)


def test_amplitude_ratio_and_flags():
    pred = pd.DataFrame({"mode": [1], "order": [6.0], "speed_rpm": [400.0],
                         "amplitude": [2e-3]})
    meas = pd.DataFrame({"order": [6.0], "speed_rpm": [401.0], "amplitude": [5e-3]})
    c = match_criticals(meas, pred, amplitude_tolerance=0.5)
    r = c.matched.iloc[0]
    assert r.amplitude_ratio == pytest.approx(2.5)
    assert r.speed_ok and not r.amplitude_ok
    assert c.flags == ("mode 1 order 6: amplitude ratio measured/predicted 2.50 outside "
                       "[0.67, 1.50]",)


def test_sweeps_combined_before_assignment():
    pred = _pred([(1, 6.0, 400.0)])
    meas = pd.DataFrame({"order": [6.0, 6.0], "speed_rpm": [399.0, 401.0],
                         "sweep": [0, 1], "confidence": [1.0, 1.0]})
    c = match_criticals(meas, pred)
    assert len(c.matched) == 1 and len(c.unmatched_measured) == 0
    assert c.matched.speed_rpm_measured.iloc[0] == pytest.approx(400.0)


def test_natural_frequency_collected_across_orders():
    # mode 1 at 30 Hz crossed by orders 3, 4.5, 6 at 600, 400, 300 rpm
    pred = _pred([(1, 3.0, 600.0), (1, 4.5, 400.0), (1, 6.0, 300.0)])
    pred["frequency_hz"] = 30.0
    meas = pd.DataFrame({"order": [3.0, 4.5, 6.0], "speed_rpm": [606.0, 404.0, 303.0],
                         "confidence": [1.0, 1.0, 1.0]})
    nat = match_criticals(meas, pred).natural_frequencies
    row = nat.iloc[0]
    assert row.n_orders == 3 and row.orders == "3, 4.5, 6"
    assert row.frequency_hz_measured == pytest.approx(30.3)
    assert row.deviation_pct == pytest.approx(1.0)
    assert row.spread_hz == pytest.approx(0.0, abs=1e-9)


def _system(stiffness_scale=1.0):
    from crankbench.predict.torsion import chain

    inertias = [8.0, 8.0, 8.0, 8.0, 8.0, 8.0, 60.0, 25.0]
    k = np.array([4e7, 4e7, 4e7, 4e7, 4e7, 3e7, 2e6])
    k[6] *= stiffness_scale  # the elastic coupling to the driven machine
    return chain(inertias, k)


def test_correct_model_agrees_and_wrong_stiffness_is_flagged():
    """'Measured' criticals come from the true system; a model with the coupling stiffness
    20 % off must be flagged, the true model must agree."""
    orders = [3.0, 4.5, 6.0, 7.5, 9.0]
    speed_range = (100.0, 1000.0)
    truth = _system().critical_speeds(orders, speed_range)
    measured = pd.DataFrame({"order": truth.order, "speed_rpm": truth.speed_rpm * 1.002})
    def predicted(system):
        crit = system.critical_speeds(orders, speed_range)
        crit["significant"] = True  # judge every critical (no amplitudes in this test)
        return crit

    good = match_criticals(measured, predicted(_system()), speed_range_rpm=speed_range)
    assert good.agrees, good.flags
    assert len(good.matched) == len(truth)
    wrong = match_criticals(measured, predicted(_system(1.2)), speed_range_rpm=speed_range)
    assert not wrong.agrees
    assert any("deviates" in f for f in wrong.flags)


def test_bad_inputs_are_named():
    with pytest.raises(AnalysisError, match="measured resonances need a column 'order'"):
        match_criticals(pd.DataFrame({"speed_rpm": [1.0]}), _pred([(1, 1.0, 1.0)]))
    with pytest.raises(AnalysisError, match="predicted criticals need a column 'mode'"):
        match_criticals(pd.DataFrame({"order": [1.0], "speed_rpm": [1.0]}),
                        pd.DataFrame({"order": [1.0], "speed_rpm": [1.0]}))
    with pytest.raises(ValueError, match=r"gate=0 must lie in \(0, 1\]"):
        match_criticals(pd.DataFrame({"order": [1.0], "speed_rpm": [1.0]}),
                        _pred([(1, 1.0, 1.0)]), gate=0)


def _balance_inputs(scale):
    rpm = np.linspace(600, 1800, 60)
    pred = xr.DataArray(np.vstack([1e-4 * (rpm / 1000) ** 2, 3e-5 * (rpm / 1000) ** 2]),
                        dims=("order", "rpm"), coords={"order": [1.0, 2.0], "rpm": rpm})
    meas = xr.Dataset({"amplitude": (("order", "time"), pred.values * np.array(scale)[:, None],
                                     {"units": "m/s"})},
                      coords={"order": [1.0, 2.0], "rpm": ("time", rpm)})
    return meas, pred


def test_balance_within_and_outside_factor():
    meas, pred = _balance_inputs([1.5, 0.8])
    res = compare_balance(meas, pred, factor=2.0, channel="mount FL z")
    np.testing.assert_allclose(res.table.median_ratio, [1.5, 0.8])
    np.testing.assert_allclose(res.table.rms_log_deviation_db,
                               [20 * np.log10(1.5), -20 * np.log10(0.8)])
    assert res.passed
    meas, pred = _balance_inputs([3.0, 1.0])
    res = compare_balance(meas, pred, factor=2.0)
    assert list(res.table.passed) == [False, True] and not res.passed
    assert res.plot().axes


def test_balance_errors():
    meas, pred = _balance_inputs([1.0, 1.0])
    with pytest.raises(AnalysisError, match="order 4 is not in the measured track"):
        compare_balance(meas, pred, orders=[4])
    with pytest.raises(AnalysisError, match=r"predicted must be an xarray.DataArray over"):
        compare_balance(meas, pred.values)


def test_weak_criticals_are_listed_not_judged():
    """A critical below significant_fraction of the largest predicted amplitude is matched
    and listed, but its deviation is not flagged."""
    pred = pd.DataFrame({"mode": [1, 2], "order": [6.0, 3.0], "speed_rpm": [400.0, 600.0],
                         "amplitude": [1e-3, 1e-5]})
    meas = pd.DataFrame({"order": [6.0, 3.0], "speed_rpm": [401.0, 660.0],
                         "amplitude": [1e-3, 1e-5]})
    c = match_criticals(meas, pred, significant_fraction=0.05)
    assert len(c.matched) == 2
    weak = c.matched[c.matched["mode"] == 2].iloc[0]
    assert not weak.significant and not weak.speed_ok
    assert c.agrees


def test_no_measured_resonance_leaves_criticals_unmatched():
    """A record that crosses no critical gives an empty resonance table: the comparison
    lists the criticals as not found instead of failing."""
    from crankbench.analysis.resonance import ResonanceTable

    empty = ResonanceTable(())
    assert empty.to_frame()["speed_rpm"].dtype == float
    pred = pd.DataFrame({"mode": [1], "order": [2.0], "speed_rpm": [3000.0],
                         "amplitude": [1e-3]})
    c = match_criticals(empty, pred)
    assert len(c.matched) == 0 and len(c.unmatched_predicted) == 1
    assert c.flags == ("mode 1 order 2: predicted critical at 3000.0 rpm not found in the "
                       "measurement (gate ±15 %)",)


def test_a_critical_hidden_by_noise_is_unresolved_not_failed():
    """A significant critical not found fails the comparison only where the record could have
    shown it: its expected rise (predicted amplitude less the measured level) at least
    (1 + amplitude_tolerance) times the finder's detection limit there. Below that, or with
    amplitudes not judged (the rise is unknown), it is unresolved: verdict inconclusive."""
    meas = pd.DataFrame({"order": [6.0], "speed_rpm": [401.0], "amplitude": [1e-3]})

    def pred(limit):
        return pd.DataFrame({"mode": [1, 2], "order": [6.0, 3.0],
                             "speed_rpm": [400.0, 600.0], "amplitude": [1e-3, 4e-4],
                             "detection_limit": [1e-5, limit],
                             "measured_level": [2e-4, 1e-4]})

    # rise 3e-4 against a limit of 1e-4: 3 >= 1.5, it should have been seen
    seen = match_criticals(meas, pred(1e-4), speed_range_rpm=(300, 700))
    assert seen.verdict().status == "fail" and not seen.unresolved
    assert "above the detection limit" in seen.flags[0]
    # the same critical under 3x the noise: 3e-4 < 1.5 x 3e-4
    hidden = match_criticals(meas, pred(3e-4), speed_range_rpm=(300, 700))
    v = hidden.verdict()
    assert not hidden.flags and v.status == "inconclusive"
    assert "mode 2 order 3 at 600.0 rpm not found and not resolvable" in v.reason
    up = hidden.unmatched_predicted.set_index("mode")
    assert up.loc[2, "status"].startswith("not found, not resolvable: expected rise 0.0003")
    # amplitudes on an assumed load: the rise is unknown, whatever the limit
    unknown = match_criticals(meas, pred(1e-6), speed_range_rpm=(300, 700),
                              amplitudes_not_judged="the run's load is not stated")
    assert not unknown.flags and "expected rise unknown" in unknown.unresolved[0]
    # without a detection limit, not found is a disagreement as before
    plain = match_criticals(meas, pred(1e-4).drop(columns=["detection_limit"]),
                            speed_range_rpm=(300, 700))
    assert plain.verdict().status == "fail" and "not found" in plain.flags[0]
