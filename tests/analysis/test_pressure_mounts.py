"""Block and mount vibration predicted from the measured excitation (issue 17 point 2).

A short I4 run-up (1500 -> 3600 rpm, 4 s) from the synthetic bench with cylinder-1 pressure, a
60-2 wheel, a TDC mark, a pulley torsiograph and two mount accelerometers, at the scene's load
(imep 10 bar). The engine model's combustion table says 13 bar, so the fully predicted
gas-torque reaction on the block is 30 % too high; the prediction from the measured pressure
(gas roll from the pressure, inertia loads from the model) must match the measured order
amplitudes and the bench's own truth (the order amplitudes it synthesized), which do not
come from the analysis code.
"""

from pathlib import Path

import numpy as np
import pytest

from crankbench.analysis.vibrograph import compare_vibrograph
from crankbench.predict.errors import ConfigError
from pressure_scenes import ENGINE, MODEL, bench_scene

RUNUP = """kind = "runup"
start_rpm = 1500.0
end_rpm = 3600.0
duration = 4.0
hold_start = 0.3
hold_end = 0.3"""

MOUNTS = """
[[sensor]]
kind = "vibrograph"
name = "acc_engine_z"
mount = "engine side"
direction = "z"
quantity = "acceleration"
sample_rate = 4000.0
noise_rms = 0.02

[[sensor]]
kind = "vibrograph"
name = "acc_rod_y"
mount = "torque rod"
direction = "y"
quantity = "acceleration"
sample_rate = 4000.0
noise_rms = 0.02
"""
SCENE = bench_scene(name="I4 run-up, pressure and mounts", seed=11, profile=RUNUP,
                    extra=MOUNTS)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    from crankbench.measure.synth import synthesize

    path = tmp_path_factory.mktemp("pm") / "runup.toml"
    path.write_text(SCENE)
    return synthesize(path)


@pytest.fixture(scope="module")
def vib(run):
    return compare_vibrograph(run.record, ENGINE, max_order=6.0)


def test_mount_response_from_measured_pressure_matches_measurement_and_truth(run, vib):
    """Measured 1.000-1.0007 against measurement, within 0.05 % of the bench's truth; the
    model at 13 bar over-predicts the gas-dominated rows by 17-25 %."""
    t = vib.table.set_index(["sensor", "order"])
    assert "speed bins" in vib.settings["measured excitation"]
    truth = run.truth["amplitude"]
    for sensor in ("acc_engine_z", "acc_rod_y"):
        for q in (2.0, 4.0, 6.0):
            row = t.loc[(sensor, q)]
            assert abs(row["ratio_measured_excitation"] - 1) < 0.01
            ref = float(truth.sel(channel=sensor, order=q).max())      # the bench's amplitude
            assert abs(row["predicted_measured_excitation"] / ref - 1) < 0.005
    for key in [("acc_engine_z", 4.0), ("acc_engine_z", 6.0), ("acc_rod_y", 2.0),
                ("acc_rod_y", 4.0), ("acc_rod_y", 6.0)]:
        assert t.loc[key, "ratio"] < 0.88                       # the model's 13 bar is wrong
    # the free second-order force dominates there: both predictions alike
    assert abs(t.loc[("acc_engine_z", 2.0), "ratio"] - 1) < 0.01
    curve = vib.curves_measured_excitation[("acc_rod_y", 4.0)]
    assert curve.shape == vib.curves[("acc_rod_y", 4.0)][0].shape


def test_no_pressure_or_indicator_none_leaves_the_table_as_it_was(run, vib):
    plain = compare_vibrograph(run.record, ENGINE, max_order=6.0, indicator=None)
    assert "predicted_measured_excitation" not in plain.table
    assert plain.measured_excitation is None
    assert np.allclose(plain.table["predicted"], vib.table["predicted"])
    with pytest.raises(ConfigError, match="indicator="):
        compare_vibrograph(run.record, ENGINE, max_order=6.0, indicator="yes")
    with pytest.raises(ConfigError, match="IndicatorResult"):
        compare_vibrograph(run.record, ENGINE, max_order=6.0, indicator={"p": 1.0})


def test_pipeline_feeds_the_measured_excitation_to_the_block_and_reports_it(run, tmp_path):
    from crankbench.analysis.pipeline import analyse
    from crankbench.analysis.report.build import build_report

    res = analyse(run.record, MODEL, orders=[2.0, 4.0])
    assert res.pressure is not None and res.vibrograph is not None
    t = res.vibrograph.table.set_index(["sensor", "order"])
    assert abs(t.loc[("acc_rod_y", 4.0), "ratio_measured_excitation"] - 1) < 0.01
    # the pipeline's indicator results were reused, not analysed again
    assert res.vibrograph.measured_excitation.source == res.pressure.excitation.source
    html = Path(build_report(res, figures=False).save(tmp_path / "r.html")).read_text()
    assert "predicted measured excitation" in html           # the column beside "predicted"
    assert "from the measured excitation" in html


def test_mount_excitation_takes_a_run_up_excitation_at_its_speed():
    """A single cylinder with gas harmonics measured as 10 N·m at 1000 rpm and 20 N·m at
    2000 rpm: at 1500 rpm the roll moment's gas part is 15 N·m (linear between bins), not the
    lowest bin's 10 (what the block loads at ω = 0 would give)."""
    from crankbench.predict.engine import Engine
    from crankbench.predict.gas_torque import SpeedExcitation, mount_excitation, torque_reaction

    e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2, reciprocating_mass=0.0)
    x = SpeedExcitation(speed_rpm=np.array([1000.0, 2000.0]), orders=np.array([2.0]),
                        gas=np.array([[[10.0]], [[20.0]]], complex),
                        inertia=np.array([0.0], complex), n_cylinders=1, source="two bins",
                        cycles=np.array([5, 5]))
    w = 1500.0 * np.pi / 30.0
    m = mount_excitation(e, x, order=2.0, omega=w)
    assert m["moment"][0] == pytest.approx(15.0)
    assert torque_reaction(e, x, [2.0], [w, 2500 * np.pi / 30])[:, 0] == pytest.approx(
        [15.0, 20.0])


def test_steady_part_load_measured_excitation_is_referred_to_the_load_law(tmp_path):
    """A steady 1600 rpm run on the propeller law (10 bar at 2000 rpm: load factor 0.64).
    The excitation measured there is divided by the law's factor at the measured speed before
    the law scales it over the model's speed grid, so with the right load case both
    predictions agree: orders 4 and 6 within 0.5 % (torsional and block; applying the law on
    top of the measured torque would put them 36 % low). Order 2 is 2-4 % off on this
    synthetic record: the bench's part-load cycle is the model's gas pressure scaled by 0.64
    above 1 bar (measure.synth.pressure), whose compression the default peg reads as a
    -0.36 bar offset, and a constant pressure drives order 2 of an I4."""
    from crankbench.analysis.pipeline import LoadCase, analyse
    from crankbench.measure.synth import synthesize

    text = bench_scene(name="I4 steady part load", seed=11,
                       profile='kind = "steady"\nspeed_rpm = 1600.0\nduration = 1.5',
                       load='imep = 1.0e6\nlaw = "propeller"\nreference_rpm = 2000.0',
                       extra=MOUNTS)
    path = tmp_path / "steady.toml"
    path.write_text(text)
    run = synthesize(path)
    load = LoadCase(imep=1.0e6, law="propeller", reference_rpm=2000.0)
    res = analyse(run.record, MODEL, orders=[4.0, 6.0], load=load)
    assert "divided by the load factor 0.64" in res.pressure.excitation.source
    assert len(res.pressure.table) == 2
    for _, row in res.pressure.table.iterrows():
        assert row["predicted_measured_excitation_peak"] == pytest.approx(
            row["predicted_model_peak"], rel=0.005)
    t = res.vibrograph.table.set_index(["sensor", "order"])
    for sensor in ("acc_rod_y", "acc_engine_z"):
        for q in (4.0, 6.0):
            assert abs(t.loc[(sensor, q), "ratio_measured_excitation"] - 1) < 0.005
        assert abs(t.loc[(sensor, 2.0), "ratio_measured_excitation"] - 1) < 0.05


def test_the_sensor_plot_draws_the_measured_excitation_prediction(vib):
    fig = vib.plot(sensor="acc_rod_y")
    ax = fig.axes[0]
    dotted = [ln for ln in ax.get_lines() if ln.get_linestyle() == ":"]
    assert len(dotted) == len(vib.table[(vib.table["sensor"] == "acc_rod_y")
                                        & vib.table["required"]])
    assert "from the measured pressure" in ax.get_title()
    row = vib.table.set_index(["sensor", "order"]).loc[("acc_rod_y", 4.0)]
    assert any(np.isclose(np.max(ln.get_ydata()), row["predicted_measured_excitation"])
               for ln in dotted)


def test_engine_model_report_has_the_indicator_section(vib, tmp_path):
    from crankbench.analysis.vibrograph_report import build_vibrograph_report

    assert set(vib.indicator) == {"p_cyl1"}
    html = Path(build_vibrograph_report(vib, figures=False).save(tmp_path / "v.html")
                ).read_text()
    assert "Indicator analysis" in html and "predicted measured excitation" in html


def test_compare_json_of_an_engine_model_carries_both_predictions(run, tmp_path, capsys):
    import json

    from crankbench.analysis.cli import main

    path = tmp_path / "r.h5"
    run.write(path)
    assert main(["compare", str(path), str(ENGINE), "--json"]) in (0, 1)
    out = json.loads(capsys.readouterr().out)
    vib = out.get("vibrograph", out)
    rows = {(r["sensor"], r["order"]): r for r in vib["rows"]}
    assert abs(rows[("acc_rod_y", 4.0)]["ratio_measured_excitation"] - 1) < 0.01
    assert abs(vib["indicator"]["p_cyl1"]["imep_net_bar"] - 10.0) < 0.1


def test_pipeline_steps_in_the_order_they_run(run):
    """The measured excitation runs before the balance step that uses it; STEPS says so."""
    from crankbench.analysis.pipeline import STEPS, analyse

    seen = []
    analyse(run.record, MODEL, orders=[2.0], progress=seen.append)
    assert [s for s in seen if s in STEPS] == list(STEPS)
