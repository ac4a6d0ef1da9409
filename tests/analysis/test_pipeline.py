"""The end-to-end chain on synthetic records with known truth, and its error paths.

The main check synthesizes the 6L32 run-up scene (``sample_data/scenes/marine_6l_runup.toml``,
truth from :mod:`measure.synth`: damped-model resonance peaks, steady-state order amplitudes)
and runs :func:`analysis.pipeline.analyse` against the shaft-line model.
"""

import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from crankbench.analysis.pipeline import LoadCase, analyse, torsional_channel
from crankbench.predict.errors import ConfigError, RecordError

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "sample_data/scenes/marine_6l_runup.toml"
MODEL = ROOT / "sample_data/shaftlines/marine_6l.toml"


@pytest.fixture(scope="module")
def marine():
    from crankbench.measure.synth import Scene, synthesize

    scene = Scene.from_toml(SCENE)
    run = synthesize(scene)
    result = analyse(run.record, MODEL, load=LoadCase.from_any(scene.load, scene.engine))
    return run, result


def _truth_critical(truth, mode, order):
    k = np.flatnonzero((truth["critical_mode"].values == mode)
                       & np.isclose(truth["critical_order"].values, order))
    return int(k[0]) if k.size else None


def _resonance_amplitude(rpm, steady, crit, zeta):
    """Steady amplitude of a resonance: the local maximum of the curve within one half-power
    half-width of the critical, or - a shoulder on a rising background has none - its value at
    the critical (the largest value over a wide window would read the background's slope)."""
    near = np.flatnonzero(np.abs(rpm - crit) <= zeta * crit)
    inner = [i for i in near[1:-1] if steady[i] >= steady[i - 1] and steady[i] >= steady[i + 1]]
    if inner:
        return float(steady[min(inner, key=lambda i: abs(rpm[i] - crit))])
    return float(np.interp(crit, rpm, steady))


@pytest.mark.slow
def test_significant_criticals_found_matched_and_accurate(marine):
    """Every significant critical (predicted amplitude ≥ 5 % of the largest) inside the run
    is found and assigned to the right (mode, order). Against the truth's damped-model
    resonance peaks (sweep 14 rpm/s): every mode within 0.5 % in speed and 5 % in amplitude
    (issue 8), mode 2 within its documented 0.8 %. Mode 2 — the damper mode, weak at the free
    end on a large background of the other modes — needs the modal fit's residual terms
    (measured with the phases referred to the 60-2 wheel's TDC: −0.54…−0.26 % in speed, ≤ 4.4 %
    in amplitude; against the integrated speed channel −0.32…+0.02 %; a single-mode fit with a
    linear background gave +0.74…+0.79 %)."""
    run, result = marine
    truth = run.truth
    comp = result.comparison
    sig = result.predicted[result.predicted["significant"]]
    assert len(sig) >= 6
    matched = {(int(r["mode"]), float(r.order)) for _, r in comp.matched.iterrows()}
    for _, p in sig.iterrows():
        assert (int(p["mode"]), float(p.order)) in matched, (p["mode"], p.order)
    rpm = truth["rpm"].values
    for _, m in comp.matched[comp.matched["significant"]].iterrows():
        k = _truth_critical(truth, int(m["mode"]), m.order)
        assert k is not None
        crit = float(truth["critical_speed_rpm"].values[k])
        res = next(r for r in result.resonances
                   if r.order == m.order and np.isclose(r.speed_rpm, m.speed_rpm_measured))
        # the right (mode, order): the nearest truth critical of that order is this mode's
        same = np.flatnonzero(np.isclose(truth["critical_order"].values, m.order))
        nearest = same[np.argmin(np.abs(truth["critical_speed_rpm"].values[same]
                                        - res.resonance_speed_rpm))]
        assert int(truth["critical_mode"].values[nearest]) == int(m["mode"])
        steady = truth["amplitude_steady"].sel(channel=result.channel, order=m.order).values
        amp = _resonance_amplitude(rpm, steady, crit,
                                   float(truth["critical_damping_ratio"].values[k]))
        # mode 2 (the damper mode, weak at the free end on a large background) carries the
        # background bias the resonance module documents (≈ 0.8 % in speed)
        speed_tol, amp_tol = (0.008 if int(m["mode"]) == 2 else 0.005), 0.05
        assert res.resonance_speed_rpm == pytest.approx(crit, rel=speed_tol)
        assert res.amplitude_corrected == pytest.approx(amp, rel=amp_tol)


@pytest.mark.slow
def test_correct_model_agrees(marine):
    _, result = marine
    assert result.comparison.agrees, result.comparison.flags
    row = result.summary()
    assert row["matched"] >= 8 and row["model_agrees"] and row["comparison_verdict"] == "pass"
    # the model's order-4.5 resonance sits at the rated speed (720 rpm): the crankshaft's
    # continuous limit is exceeded there, a barred range IACS UR M68.5 does not allow above
    # λ = 0.8, so the overall verdict fails on that check alone
    cont = [c for c in result.limits if c.name.startswith("measured torsional stress, cont")]
    assert len(cont) == 1 and cont[0].status == "fail"
    lo, hi = cont[0].data.barred_ranges_rpm[-1]
    assert lo < 720.0 < hi and lo > 0.8 * 720.0
    assert row["verdict"] == "fail" and not result.passed
    assert row["verdict_reason"] == "failed: measured torsional stress, continuous and barred ranges"
    # the stress check uses the model's [limits]; the severity checks the two vibrographs
    names = [c.name for c in result.limits]
    assert any(n.startswith("measured torsional stress") for n in names)
    assert sum(n.startswith("vibration severity") for n in names) == 2


@pytest.mark.slow
def test_wrong_stiffness_is_flagged(marine, tmp_path):
    """The same record against a model whose flexible-coupling stiffness is 20 % high."""
    run, _ = marine
    text = MODEL.read_text()
    wrong = re.sub(r"(name = \"flexible coupling\"\nfrom = \"flywheel\"\nto = \"coupling "
                   r"secondary\"\nstiffness = )9.0e5", r"\g<1>1.08e6", text)
    assert wrong != text
    wrong = wrong.replace('engine = "../engines/marine_6l.toml"',
                          f'engine = "{(MODEL.parent / "../engines/marine_6l.toml").resolve()}"')
    path = tmp_path / "wrong.toml"
    path.write_text(wrong)
    scene_load = LoadCase(imep=2.4e6, law="propeller", reference_rpm=720.0)
    result = analyse(run.record, path, load=scene_load)
    assert not result.comparison.agrees
    assert any("deviates" in f or "not found" in f or "matches no" in f
               for f in result.comparison.flags)


def test_channel_selection_and_errors():
    rec = xr.Dataset({"acc": ("time", np.zeros(10), {"quantity": "acceleration",
                                                       "units": "m/s^2"}),
                      "tv_free_end": ("time", np.zeros(10), {"quantity": "angle",
                                                             "units": "rad"})})
    assert torsional_channel(rec) == "tv_free_end"
    with pytest.raises(RecordError, match=r"record has no channel 'tv_fre_end' \(did you mean "
                                          r"'tv_free_end'\?\)"):
        torsional_channel(rec, "tv_fre_end")
    with pytest.raises(RecordError, match="record has no torsional channel"):
        torsional_channel(rec[["acc"]])


def test_load_case_validation():
    assert LoadCase().scale([100.0, 200.0]).tolist() == [1.0, 1.0]
    assert LoadCase(law="propeller", reference_rpm=200.0).scale([100.0]).tolist() == [0.25]
    with pytest.raises(ConfigError, match=r"law='cubic' is not one of 'constant', 'propeller'"):
        LoadCase(law="cubic")
    with pytest.raises(ConfigError, match="load law 'propeller' needs reference_rpm"):
        LoadCase.from_any({"law": "propeller"}, engine=None)


@pytest.mark.slow
def test_vibrograph_channels_compared_with_the_engine_on_its_mounts_i4():
    """I4 run-up: the torsional comparison also sets the two mount accelerometers against the
    engine model on its mounts (truth: the same quasi-steady mount response plus noise). Every
    judged (sensor, order) agrees — order 2 (the free second-order force and the torque
    reaction) within 1 % —, order 1 is balanced by design and shows nothing but noise, and
    the torsional comparison still agrees."""
    from crankbench.measure.synth import Scene, synthesize

    scene = Scene.from_toml(ROOT / "sample_data/scenes/i4_runup.toml")
    run = synthesize(scene)
    result = analyse(run.record, ROOT / "sample_data/shaftlines/i4.toml",
                     load=LoadCase.from_any(scene.load, scene.engine))
    vib = result.vibrograph
    assert vib is not None and len(vib.sensors) == 2
    table = vib.table
    judged = table[table["required"]]
    assert len(judged) >= 4 and (judged["verdict"] == "pass").all()
    two = table[table["order"] == 2.0]
    assert len(two) == 2 and np.allclose(two["ratio"], 1.0, atol=0.01)
    assert not (table["order"] == 1.0).any()
    assert vib.verdict.status == "pass" and result.comparison.agrees
    row = result.summary()
    assert row["vibration_verdict"] == "pass"
    assert row["vibration_worst_ratio"] == pytest.approx(1.0, abs=0.02)


@pytest.mark.slow
def test_fast_sweep_100_rpm_per_s(tmp_path):
    """The same scene run up in 5.6 s (100 rpm/s): significant criticals of every mode
    within 0.5 % (speed) and 5 % (steady-state amplitude, after the sweep correction; the raw
    peaks are up to 18 % low); mode 2 (weak at the free end on the other modes' background,
    identified with the residual terms) within its documented 0.8 % and 8 % (measured with the
    phases referred to the 60-2 wheel: order 2.5 −0.41 % and +7.0 %, order 3 −0.04 % and
    +3.4 %). Mode 3 × order 4.5 (718 rpm, 5.5 % below the end of the run) keeps a sweep-
    correction bias of +0.56…+0.59 % in speed (seeds 1–4 and 6, the 60-2 wheel's mean rotation
    as the angle; +0.48 % with the integrated speed): allowed 0.6 % there. (The earlier
    +0.38 % came from a reference angle that carried the flywheel's vibration.)"""
    from crankbench.measure.synth import Scene, synthesize

    text = SCENE.read_text().replace("duration = 40.0", "duration = 5.6")
    text = text.replace('"../', f'"{SCENE.parent.parent.as_posix()}/')
    scene_path = tmp_path / "fast.toml"
    scene_path.write_text(text)
    scene = Scene.from_toml(scene_path)
    run = synthesize(scene)
    result = analyse(run.record, MODEL, load=LoadCase.from_any(scene.load, scene.engine))
    assert result.sweep_rate_rpm_per_s == pytest.approx(100.0, rel=0.01)
    truth, rpm = run.truth, run.truth["rpm"].values
    checked = 0
    for _, m in result.comparison.matched[result.comparison.matched["significant"]].iterrows():
        k = _truth_critical(truth, int(m["mode"]), m.order)
        crit = float(truth["critical_speed_rpm"].values[k])
        res = next(r for r in result.resonances
                   if r.order == m.order and np.isclose(r.speed_rpm, m.speed_rpm_measured))
        steady = truth["amplitude_steady"].sel(channel=result.channel, order=m.order).values
        amp = _resonance_amplitude(rpm, steady, crit,
                                   float(truth["critical_damping_ratio"].values[k]))
        # mode 2 (the damper mode, weak at the free end on a large background) carries the
        # background bias the resonance module documents (≈ 0.8 % in speed)
        speed_tol, amp_tol = (0.008, 0.08) if int(m["mode"]) == 2 else (0.005, 0.05)
        if int(m["mode"]) == 3 and m.order == 4.5:
            speed_tol = 0.006             # the sweep correction's bias near the run's end
        assert res.resonance_speed_rpm == pytest.approx(crit, rel=speed_tol), (m["mode"], m.order)
        assert res.amplitude_corrected == pytest.approx(amp, rel=amp_tol), (m["mode"], m.order)
        checked += 1
    assert checked >= 5


def test_steady_run_with_nothing_compared_is_inconclusive(tmp_path):
    """A constant-speed record crosses no critical: the comparison is inconclusive, and so is
    the overall verdict when nothing else failed — never 'all checks passed'."""
    import dataclasses

    from crankbench.measure.synth import Scene, synthesize
    from crankbench.measure.synth.profile import steady

    scene = Scene.from_toml(ROOT / "sample_data/scenes/marine_6l_runup.toml")
    scene = dataclasses.replace(scene, profile=steady(420.0, duration=6.0))
    run = synthesize(scene)
    result = analyse(run.record, ROOT / "sample_data/shaftlines/marine_6l.toml",
                     load=LoadCase.from_any(scene.load, scene.engine))
    comp = result.verdicts[0]
    assert result.steady and comp.status == "inconclusive" and "steady-speed run" in comp.reason
    assert result.verdict.status in ("inconclusive", "fail") and not result.passed
    assert result.summary()["comparison_verdict"] == "inconclusive"


@pytest.mark.slow
def test_misfire_case_that_cannot_be_computed_is_listed_not_dropped(marine, monkeypatch):
    """A stated misfire case the model cannot compute is 'not assessed' (inconclusive) in the
    limit table, never silently missing."""
    import crankbench.analysis.pipeline_limits as pipeline_limits
    from crankbench.predict.errors import ModelError

    def broken(*args, **kwargs):
        raise ModelError("no cylinder pressure model for the misfire case")

    monkeypatch.setattr(pipeline_limits, "_misfire_stress", broken)
    run, normal = marine
    scene_load = LoadCase(imep=2.4e6, law="propeller", reference_rpm=720.0)
    result = analyse(run.record, MODEL, load=scene_load)
    before = [c for c in normal.limits if "misfiring" in c.name]
    after = [c for c in result.limits if "misfiring" in c.name]
    assert before and all(c.status != "inconclusive" for c in before)
    assert len(after) == 1 and after[0].status == "inconclusive"
    assert "could not be computed" in after[0].detail and "no cylinder pressure" in after[0].detail


@pytest.mark.slow
def test_unstated_load_leaves_amplitudes_unjudged_and_a_model_law_judges_them(marine, tmp_path):
    """The 6L32 run-up ran on the propeller law. Without a stated load the prediction assumes
    the model's imep at every speed: amplitude ratios 0.13-0.58 at the low-speed criticals,
    which must not fail the model (nor pass it on amplitudes) — speeds are still judged and
    the verdict says why amplitudes are not. With the law in the model's [shaftline] the
    amplitudes are judged and agree (ratios within [0.67, 1.5])."""
    run, _ = marine
    result = analyse(run.record, MODEL)                 # an in-memory record: no stored load
    comp = result.comparison
    ratios = comp.matched.loc[comp.matched["significant"], "amplitude_ratio"]
    assert ratios.min() < 0.67                          # the assumed load is far off ...
    assert not any("amplitude ratio" in f for f in comp.flags)   # ... and not judged
    v = comp.verdict()
    assert v.status == "pass" and "amplitudes not judged" in v.rule
    assert "load is not stated" in v.reason and "--load-law" in v.reason
    text = MODEL.read_text().replace('imep = 2.4e6', 'imep = 2.4e6\nload_law = "propeller"')
    text = text.replace('engine = "../engines/marine_6l.toml"',
                        f'engine = "{(MODEL.parent / "../engines/marine_6l.toml").resolve()}"')
    path = tmp_path / "marine_propeller.toml"
    path.write_text(text)
    judged = analyse(run.record, path).comparison
    assert judged.settings["amplitudes_not_judged"] is None
    sig = judged.matched["significant"]
    assert judged.matched.loc[sig, "amplitude_ok"].all(), judged.flags
    assert "amplitude ratio within" in judged.verdict().rule


@pytest.mark.slow
def test_requested_orders_do_not_drop_the_others_from_the_stress_checks(marine):
    """Tracking only order 4.5 (the rated-speed critical) must not shrink the measured stress
    to that order's: the other orders of the engine are superposed as predicted and the basis
    says which and how much. Before, --orders 4.5 turned the run-up's barred-range FAIL into a
    PASS (no barred range). Checked against the default run: the same barred-range verdict,
    the worst stress within 5 % (order 4.5 measured in both; the rest measured or predicted)."""
    run, normal = marine
    result = analyse(run.record, MODEL, orders=[4.5],
                     load=LoadCase(imep=2.4e6, law="propeller", reference_rpm=720.0))

    def check(res, name):
        return next(c for c in res.limits if c.name == name)

    barred = "measured torsional stress, continuous and barred ranges"
    assert check(result, barred).status == check(normal, barred).status == "fail"
    worst = "measured torsional stress, transient"
    assert check(result, worst).value == pytest.approx(check(normal, worst).value, rel=0.05)
    basis = check(result, worst).basis
    assert "not measured, taken as predicted" in basis and "% of the worst stress" in basis
    assert list(result.comparison.matched["order"]) == [4.5]


@pytest.mark.slow
def test_ten_times_the_noise_is_never_a_false_fail(marine):
    """The synthetic run-up comes from the model itself, so the model is right: with ten
    times the torsiograph's noise (white, 2e-4 rad rms added) the criticals the noise hides
    must make the comparison inconclusive — never a failure — and every critical still found
    agrees within the tolerances. (Before: either spurious peaks 4–8 % off that failed the
    model, or 'not found' failures of criticals the record could not show.)"""
    run, _ = marine
    scene_load = LoadCase(imep=2.4e6, law="propeller", reference_rpm=720.0)
    rec = run.record.copy()
    x = rec["tv_free_end"]
    rec["tv_free_end"] = x + 2e-4 * np.random.default_rng(3).standard_normal(x.shape[0])
    comp = analyse(rec, MODEL, load=scene_load).comparison
    v = comp.verdict()
    assert v.status != "fail", v.reason
    assert len(comp.matched) >= 4 and comp.matched["speed_ok"].all()
    assert comp.matched.loc[comp.matched["significant"], "amplitude_ok"].all()
    if v.status == "inconclusive":
        assert comp.unresolved and "not resolvable" in v.reason
