"""End-to-end synthesis: the record carries a truth that independent analysis recovers.

* steady I4 scene: the 60-2 tacho gives the speed (tacho.speed_from_pulses), the encoder edges
  give the truth's angular vibration per order (torsiograph.angular_vibration, an independent
  pulse-timing method), the torsiograph channel's orders (least squares against the crank
  angle) equal the truth, and the mount accelerometer equals a second route through
  predict.balance.shaking_forces (exact time-domain sum, FFT per order) and the mount model;
* marine run-up (the demo scene): analysis.order_track on the torsiograph channels, with the
  speed from the tacho, recovers the truth's order amplitudes within 1 % and its resonance
  peaks within 5 rpm;
* record and truth survive writing and reading (HDF5 group "truth"); the CLI writes, refuses
  to overwrite and prints JSON.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from crankbench.measure.synth import Scene, synthesize
from crankbench.measure.synth.imperfections import Imperfections
from crankbench.measure.synth.profile import steady
from crankbench.measure.synth.scene import LoadSpec, SensorSpec
from crankbench.measure.tacho import speed_from_pulses
from crankbench.measure.torsiograph import angular_vibration
from crankbench.predict.engine import Engine
from crankbench.predict.mounts import MountedEngine
from crankbench.predict.torsion import from_toml

ROOT = Path(__file__).resolve().parents[2]
TWO_PI = 2 * np.pi
RPM = 3000.0


@pytest.fixture(scope="module")
def steady_run():
    engine = Engine.from_toml(ROOT / "sample_data/engines/i4.toml")
    sensors = (
        SensorSpec("tv", "torsiograph", {"node": "pulley hub", "quantity": "angle",
                                         "sample_rate": 4000.0}),
        SensorSpec("enc", "encoder", {"node": "pulley hub", "pulses_per_rev": 120,
                                      "missing_teeth": 0, "tdc_offset_deg": 0.0}),
        SensorSpec("tacho", "tacho", {"node": "flywheel", "pulses_per_rev": 60,
                                      "missing_teeth": 2, "tdc_offset_deg": 84.0,
                                      "output": "pulses"}),
        SensorSpec("tacho_v", "tacho", {"node": "flywheel", "pulses_per_rev": 60,
                                        "missing_teeth": 2, "tdc_offset_deg": 84.0,
                                        "output": "analogue", "sample_rate": 50_000.0}),
        SensorSpec("acc", "vibrograph", {"mount": "engine side", "direction": "z",
                                         "quantity": "acceleration", "sample_rate": 4000.0}),
        # a transducer's noise keeps the model's flat gas-exchange pressure from looking clipped
        SensorSpec("p1", "pressure", {"cylinder": 1, "sample_rate": 20000.0},
                   Imperfections(noise_rms=2.0e3)),
        SensorSpec("speed", "speed", {"sample_rate": 100.0}),
    )
    scene = Scene(name="i4 steady", engine=engine,
                  shaftline=from_toml(ROOT / "sample_data/shaftlines/i4.toml"),
                  mounts=MountedEngine.from_toml(ROOT / "sample_data/engines/i4.toml"),
                  profile=steady(RPM, duration=2.0), load=LoadSpec(imep=1.0e6),
                  sensors=sensors, max_order=8.0)
    return synthesize(scene)


def _truth(run, channel, order):
    amp = run.truth["amplitude"].sel(channel=channel, order=order).values
    ph = run.truth["phase"].sel(channel=channel, order=order).values
    return float(np.median(amp)), float(np.median(ph))


def test_tacho_speed_of_steady_run(steady_run):
    """The 60-2 wheel on the vibrating flywheel gives 3000 rpm: a two-revolution window (one
    four-stroke cycle) cancels every order of the flywheel's vibration; one revolution leaves
    the small half orders of the elastic crankshaft."""
    edges = steady_run.record["tacho"].values
    sp = speed_from_pulses(edges, pulses_per_rev=60, missing_teeth=2, window_revs=2.0)
    np.testing.assert_allclose(sp.speed_rpm, RPM, atol=1e-6)
    one = speed_from_pulses(edges, pulses_per_rev=60, missing_teeth=2)
    assert 1e-3 < np.max(np.abs(one.speed_rpm - RPM)) < 0.5


def test_analogue_pickup_edges_match_pulse_train(steady_run):
    """Edges detected on the synthesized 60-2 pick-up voltage (50 kHz) coincide with the
    pulse-time channel of the same wheel within 1e-7 s, and the gap synchronises the angle."""
    from crankbench.measure.tacho import angle_from_pulses, detect_edges

    v = steady_run.record["tacho_v"]
    assert v.attrs["quantity"] == "voltage" and v.attrs["missing_teeth"] == 2
    edges = detect_edges(v.values, fs=v.attrs["sample_rate"])
    pulses = steady_run.record["tacho"].values
    inside = pulses[(pulses > edges[0] - 1e-5) & (pulses < edges[-1] + 1e-5)]
    assert edges.size == inside.size
    np.testing.assert_allclose(edges, inside, atol=1e-7)
    a = angle_from_pulses(edges, pulses_per_rev=60, missing_teeth=2, tdc_offset_deg=84.0)
    b = angle_from_pulses(inside, pulses_per_rev=60, missing_teeth=2, tdc_offset_deg=84.0)
    np.testing.assert_allclose(a.angle, b.angle)
    # the angle is the crank angle from TDC of cylinder 1 (start angle 0 at t = 0) up to the
    # flywheel's vibration (bounded by the sum of its truth order amplitudes)
    diff = b.angle - RPM * TWO_PI / 60 * inside
    wrapped = (diff + np.pi) % TWO_PI - np.pi
    bound = float(steady_run.truth["amplitude"].sel(channel="tacho").isel(time=5).sum())
    assert np.max(np.abs(wrapped)) <= 1.01 * bound


def test_encoder_edges_recover_truth_orders(steady_run):
    """angular_vibration on the ideal 120-line encoder at the pulley equals the truth's order
    amplitudes of that node within 1 % (orders above 5 % of the largest)."""
    res = angular_vibration(steady_run.record["enc"].values, pulses_per_rev=120, max_order=8.0)
    orders = steady_run.truth["order"].values
    amps = {q: _truth(steady_run, "enc", q)[0] for q in orders}
    big = [q for q in orders if amps[q] > 0.05 * max(amps.values())]
    assert 2.0 in big and len(big) >= 3
    for q in big:
        got = float(np.median(res.orders["amplitude"].sel(order=q).values))
        assert got == pytest.approx(amps[q], rel=0.01), q


def test_missing_tooth_wheel_torsiograph_recovers_truth_with_phase(steady_run):
    """angular_vibration on the 60-2 flywheel wheel (gap sync, TDC offset 84 deg) equals the
    truth's amplitudes within 0.1 % and its phases (crank angle from TDC of cylinder 1) within
    1 mrad; half orders only up to pi, the four-stroke cycle being unknown without a cam mark."""
    res = angular_vibration(steady_run.record["tacho"].values, pulses_per_rev=60,
                            missing_teeth=2, max_order=8.0, tdc_offset_deg=84.0)
    for q in (0.5, 2.0, 4.0, 6.0):
        amp, phase = _truth(steady_run, "tacho", q)
        got = res.orders.sel(order=q)
        assert float(np.median(got["amplitude"].values)) == pytest.approx(amp, rel=1e-3)
        d = np.angle(np.exp(1j * (float(np.median(got["phase"].values)) - phase)))
        if q == round(q):
            assert abs(d) < 1e-3
        else:
            assert min(abs(d), np.pi - abs(d)) < 1e-3


def test_torsiograph_channel_equals_truth(steady_run):
    """Least-squares fit of cos/sin of every order of the crank angle to the torsiograph
    channel reproduces the truth's amplitude and phase (signal = A cos(q psi + phase))."""
    ch = steady_run.record["tv"]
    t = ch[ch.dims[0]].values
    psi = RPM * TWO_PI / 60 * t
    orders = steady_run.truth["order"].values
    basis = np.column_stack([np.ones_like(t)] + [f(q * psi) for q in orders
                                                  for f in (np.cos, np.sin)])
    coef, *_ = np.linalg.lstsq(basis, ch.values, rcond=None)
    for k, q in enumerate(orders):
        c, s = coef[1 + 2 * k], coef[2 + 2 * k]
        amp, phase = _truth(steady_run, "tv", q)
        assert np.hypot(c, s) == pytest.approx(amp, rel=1e-4, abs=1e-9)
        if amp > 1e-6:
            assert np.angle((c - 1j * s) * np.exp(-1j * phase)) == pytest.approx(0, abs=1e-3)


def test_mount_channel_equals_shaking_force_route(steady_run):
    """Second route for the vibrograph: the exact time-domain shaking forces and roll moment
    of predict.balance.shaking_forces (with the same cylinder pressure) over one cycle, FFT per
    order, through MountedEngine.response at the sensor's mount: equals the truth and the
    channel (orders above 1 % of the largest) within 0.5 %."""
    from crankbench.predict.balance import shaking_forces
    from crankbench.predict.pressure import synthetic_pressure

    engine = steady_run.scene.engine
    mounted = steady_run.scene.mounts
    omega = RPM * TWO_PI / 60
    n = 2880
    psi = np.arange(n) * 4 * np.pi / n                    # one 4-stroke cycle from firing TDC
    theta = psi + engine.firing_tdc_shaft_angle
    sf = shaking_forces(engine, theta, omega=omega,
                        pressure=synthetic_pressure(engine, imep=1.0e6))
    point = next(m.position for m in mounted.mounts if m.name == "engine side")
    orders = steady_run.truth["order"].values
    amps = {}
    for q in orders:
        k = int(round(2 * q))
        coef = {name: 2 * np.fft.fft(sf[name].values)[k] / n for name in
                ("force_vertical", "force_horizontal", "moment_pitch", "moment_yaw",
                 "moment_roll")}
        force = np.array([0.0, coef["force_horizontal"], coef["force_vertical"]])
        # pitch = sum dz F_vertical acts about -y, yaw about +z; roll (rotation direction)
        # about -x
        moment = np.array([-coef["moment_roll"], -coef["moment_pitch"], coef["moment_yaw"]])
        r = mounted.response(np.conj(force), np.conj(moment), q * omega / TWO_PI,
                             point=[engine.reference_position, 0, 0], at=[point])
        amps[q] = abs(r.acceleration[0, 0, 2])
    top = max(amps.values())
    for q in orders:
        truth = _truth(steady_run, "acc", q)[0]
        if amps[q] > 0.01 * top:
            assert truth == pytest.approx(amps[q], rel=5e-3), q
        else:
            assert truth < 0.02 * top
    ch = steady_run.record["acc"]
    t = ch[ch.dims[0]].values
    psi_t = RPM * TWO_PI / 60 * t
    c = 2 * np.mean(ch.values * np.exp(-2j * psi_t))
    assert abs(c) == pytest.approx(amps[2.0], rel=5e-3)


def test_record_and_truth_round_trip(tmp_path, steady_run):
    from crankbench.measure.io import read, read_truth

    path = tmp_path / "run.h5"
    steady_run.write(path)
    rec = read(path)
    np.testing.assert_array_equal(rec["enc"].values, steady_run.record["enc"].values)
    assert rec["tacho"].attrs["missing_teeth"] == 2
    truth = read_truth(path)
    np.testing.assert_allclose(truth["amplitude"].values, steady_run.truth["amplitude"].values)
    assert json.loads(truth.attrs["fidelity"])["method"] == "split"


@pytest.fixture(scope="module")
def marine_run():
    return synthesize(ROOT / "sample_data/scenes/marine_6l_runup.toml")


def test_marine_runup_truth_recovered_by_order_tracking(marine_run):
    """analysis.order_track (COT, 8-revolution blocks) on the torsiograph channels of the demo
    run-up (14 rpm/s, slow for these resonances), speed from the 60-2 tacho: order amplitudes
    within 1 % of the truth wherever they exceed 30 % of their maximum, and the resonance peak
    of order 6 (mode 3) within 5 rpm of the truth's."""
    analysis = pytest.importorskip("crankbench.analysis")
    rec, truth = marine_run.record, marine_run.truth
    sp = speed_from_pulses(rec["tacho"].values, pulses_per_rev=60, missing_teeth=2)
    for ch in ("tv_flywheel", "tv_free_end"):
        x = rec[ch]
        t = x[x.dims[0]].values
        res = analysis.order_track(x, speed_rpm=sp.at(t) * 60 / TWO_PI, orders=[1.5, 3.0, 4.5, 6.0],
                                   revolutions=8)
        tt = res["time"].values
        for q in (1.5, 3.0, 4.5, 6.0):
            got = res["amplitude"].sel(order=q).values
            ref = np.interp(tt, truth["time"].values,
                            truth["amplitude"].sel(channel=ch, order=q).values)
            big = (ref > 0.3 * ref.max()) & (tt > 2.0) & (tt < 40.0)
            assert np.max(np.abs(got[big] / ref[big] - 1)) < 0.01, (ch, q)
        got6 = res["amplitude"].sel(order=6.0).values
        ref6 = truth["amplitude"].sel(channel=ch, order=6.0)
        mid = (res["rpm"].values > 450) & (res["rpm"].values < 650)
        peak = res["rpm"].values[mid][np.argmax(got6[mid])]
        sel = (truth["rpm"] > 450) & (truth["rpm"] < 650)
        peak_truth = float(truth["rpm"].values[sel.values][int(np.argmax(ref6.values[sel.values]))])
        assert abs(peak - peak_truth) < 5.0


def test_marine_truth_contents(marine_run):
    truth = marine_run.truth
    crit = truth["critical_speed_rpm"].values
    major = truth["critical_major"].values
    orders = truth["critical_order"].values
    # the run crosses the major-order criticals of modes 2 and 3 (orders 3, 6, 9)
    assert np.any(major & (orders == 3.0) & (crit > 500) & (crit < 560))
    assert np.any(major & (orders == 6.0) & (crit > 250) & (crit < 290))
    assert set(truth["channel"].values) >= {"tv_free_end", "tv_flywheel", "enc_free_end",
                                            "tacho", "acc_port1_z"}
    assert marine_run.fidelity["integration_rate_hz"] == 2000.0
    # slow sweep: the time-domain amplitudes agree with the steady-state ones (second method)
    a = truth["amplitude"].sel(channel="tv_flywheel", order=6.0).values[40:-40]
    s = truth["amplitude_steady"].sel(channel="tv_flywheel", order=6.0).values[40:-40]
    assert np.max(np.abs(a / s - 1)) < 0.02


def test_cli_synth_writes_and_refuses_overwrite(tmp_path, capsys):
    from crankbench.analysis.cli import main

    scene = tmp_path / "scene.toml"
    scene.write_text(f"""
[scene]
name = "short"
engine = "{(ROOT / 'sample_data/engines/i4.toml').as_posix()}"
shaftline = "{(ROOT / 'sample_data/shaftlines/i4.toml').as_posix()}"
max_order = 4.0
[profile]
kind = "runup"
start_rpm = 1500.0
end_rpm = 2000.0
duration = 1.0
[[sensor]]
kind = "tacho"
name = "tacho"
node = "flywheel"
pulses_per_rev = 60
missing_teeth = 2
[[sensor]]
kind = "torsiograph"
name = "tv"
node = "pulley hub"
sample_rate = 2000.0
""")
    out = tmp_path / "short.h5"
    assert main(["synth", str(scene), "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["truth_written"] and out.exists()
    assert {c["channel"] for c in summary["channels"]} == {"tv", "tacho"}
    assert main(["synth", str(scene), "-o", str(out)]) == 2
    assert "exists; pass --overwrite to replace it" in capsys.readouterr().err
    assert main(["synth", str(scene), "-o", str(out), "--overwrite"]) == 0
    assert "critical speeds crossed" in capsys.readouterr().out


def test_seismic_torsiograph_reading_and_correction():
    """A seismic torsiograph (f_n = 4 Hz, zeta = 0.6) on the pulley: the channel's order-2
    amplitude is the truth times |H| of the instrument at 100 Hz, and correcting the channel with
    measure.instruments recovers the truth within 1 % away from the record ends."""
    from crankbench.measure.instruments import torsiograph

    engine = Engine.from_toml(ROOT / "sample_data/engines/i4.toml")
    sensor = SensorSpec("tv", "torsiograph", {"node": "pulley hub", "quantity": "angle",
                                              "sample_rate": 2000.0,
                                              "instrument_frequency": 4.0,
                                              "instrument_damping": 0.6})
    scene = Scene(name="seismic", engine=engine,
                  shaftline=from_toml(ROOT / "sample_data/shaftlines/i4.toml"), mounts=None,
                  profile=steady(RPM, duration=4.0), load=LoadSpec(imep=1.0e6),
                  sensors=(sensor,), max_order=4.0)
    run = synthesize(scene)
    ch = run.record["tv"]
    assert ch.attrs["instrument_natural_frequency"] == 4.0
    inst = torsiograph(natural_frequency=4.0, damping_ratio=0.6)
    t = ch[ch.dims[0]].values
    psi = RPM * TWO_PI / 60 * t
    late = t > 2.0                                    # instrument start transient decayed
    c = 2 * np.mean(ch.values[late] * np.exp(-2j * psi[late]))
    amp, _ = _truth(run, "tv", 2.0)
    assert abs(c) == pytest.approx(amp * abs(inst.frf(100.0)), rel=2e-3)
    fixed = inst.correct(ch.values[late], fs=2000.0)
    c2 = 2 * np.mean(fixed.data * np.exp(-2j * psi[late]))
    assert abs(c2) == pytest.approx(amp, rel=0.01)


def test_synthetic_run_tabulates_and_plots(steady_run):
    import matplotlib

    matplotlib.use("Agg")
    frame = steady_run.to_frame()
    assert list(frame["channel"]) == [s.name for s in steady_run.scene.sensors]
    fig = steady_run.plot(channel="tv")
    assert fig.axes[0].get_xlabel() == "speed (rpm)"
    matplotlib.pyplot.close(fig)
