"""A shaft-line bench without an engine, its speed from a raw wheel decoded at import.

The record is a transient simulation independent of the pipeline's prediction: the 3-mass
motor bench of ``sample_data/shaftlines/motor_bench.toml`` (motor held by its speed controller,
coupling, shaft, brake) integrated in time (``scipy.signal.lsim``, viscous damping equivalent to
the loss factors at mode 2) under its stated exciting torque (orders 1, 2, 4, ∝ speed²) during
a 300 -> 1800 rpm run-up. The speed source is the raw 0-5 V voltage of a 36-1 wheel sampled at
10 kHz, its layout left for the decoder to infer. Truth: the critical speeds 60 f_n / q from the
model's natural frequencies (an eigenvalue problem, not the forced response).
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.signal import lsim

from crankbench.analysis.cli import main
from crankbench.analysis.pipeline import analyse
from crankbench.measure import io
from crankbench.measure.record import make_record
from crankbench.measure.synth.pulses import pulse_voltage
from crankbench.predict.torsion import from_toml

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "sample_data" / "shaftlines" / "motor_bench.toml"
T, N0, N1 = 40.0, 300.0, 1800.0
MAP = """[channel.tv]
column = "tv_brake"
units = "rad"
quantity = "angle"
node = "brake"

[channel.wheel]
column = "wheel_v"
role = "wheel"
pulses_per_rev = 36
"""


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    folder = tmp_path_factory.mktemp("motor_bench")
    fn = from_toml(MODEL).natural_frequencies()
    fs = 1000.0
    t = np.arange(int(T * fs)) / fs
    theta = 2 * np.pi / 60 * (N0 * t + (N1 - N0) * t * t / (2 * T))
    n = N0 + (N1 - N0) * t / T
    torque = sum(a * (n / 1500.0) ** 2 * np.cos(q * theta) for q, a in ((1, 2.0), (2, 1.0),
                                                                          (4, 0.5)))
    inertia = np.diag([0.8, 0.2, 1.2])
    k1, k2, kg = 2.0e4, 3.0e4, 500.0
    stiff = np.array([[k1 + kg, -k1, 0], [-k1, k1 + k2, -k2], [0, -k2, k2]])
    w2 = 2 * np.pi * fn[1]
    c1, c2 = 0.06 * k1 / w2, 0.02 * k2 / w2
    damp = np.array([[c1 + 20.0, -c1, 0], [-c1, c1 + c2, -c2], [0, -c2, c2]])
    inv = np.linalg.inv(inertia)
    a = np.block([[np.zeros((3, 3)), np.eye(3)], [-inv @ stiff, -inv @ damp]])
    b = np.r_[np.zeros(3), inv[:, 0]][:, None]
    c = np.zeros((1, 6))
    c[0, 2] = 1.0
    _, angle, _ = lsim((a, b, c, np.zeros((1, 1))), torque, t)
    angle = angle + 1e-6 * np.random.default_rng(0).standard_normal(t.size)
    fsw = 10_000.0
    tw = np.arange(int(T * fsw)) / fsw
    aa, bb = 2 * np.pi / 60 * (N1 - N0) / (2 * T), 2 * np.pi / 60 * N0
    k = np.arange(1, int(theta[-1] / (2 * np.pi) * 36))
    k = k[np.mod(k, 36) < 35]
    edges = (-bb + np.sqrt(bb * bb + 4 * aa * (2 * np.pi * k / 36))) / (2 * aa)
    volts = pulse_voltage(edges, tw, widths=0.5 * 60 / (36 * (N0 + (N1 - N0) * edges / T)),
                          high=5.0) + 0.02 * np.random.default_rng(1).standard_normal(tw.size)
    rec = make_record({"tv_brake": dict(data=angle, sample_rate=fs, units="rad",
                                        quantity="angle", location="brake"),
                       "wheel_v": dict(data=volts.astype(np.float32), sample_rate=fsw,
                                       units="V")})
    path = folder / "bench.h5"
    io.write(rec, path)
    cmap = folder / "bench_map.toml"
    cmap.write_text(MAP)
    crit = {(mode, q): 60.0 * fn[mode] / q for mode in (1, 2) for q in (1.0, 2.0, 4.0)}
    return path, cmap, crit


def test_compare_without_engine_finds_the_criticals_of_the_given_excitation(bench):
    path, cmap, crit = bench
    res = analyse(path, MODEL, channel_map=cmap)
    wheel = res.record["wheel"]
    assert wheel.attrs["missing_teeth"] == 1 and wheel.attrs["role"] == "wheel"
    assert res.speed_channel == "wheel"
    matched = res.comparison.matched
    assert set(zip(matched["mode"], matched["order"])) >= {(2, 1.0), (2, 2.0)}
    for _, m in matched.iterrows():
        truth = crit[(int(m["mode"]) - 1, float(m["order"]))]   # model mode 2 = 2nd frequency
        assert m["speed_rpm_measured"] == pytest.approx(truth, rel=0.01)
        # the stated torques make the amplitudes comparable: within 10 %
        assert m["amplitude_ratio"] == pytest.approx(1.0, abs=0.1)
    verdicts = {c.name: c.status for c in res.limits}
    assert verdicts  # the stress check says it was not assessed (no limit data), not pass
    assert all(s in ("inconclusive", "pass") for s in verdicts.values())


def test_orders_without_torques_compare_speeds_only(bench, tmp_path):
    path, cmap, crit = bench
    text = MODEL.read_text().replace("torque = [2.0, 1.0, 0.5]", "").replace(
        'law = "speed_squared"\nreference_rpm = 1500.0', "")
    model = tmp_path / "motor_bench_orders_only.toml"
    model.write_text(text)
    res = analyse(path, model, channel_map=cmap)
    assert res.predicted["amplitude"].isna().all()
    assert res.response.attrs["note"].startswith("response to 1 N·m per order")
    matched = res.comparison.matched
    assert len(matched) >= 2 and matched["amplitude_ratio"].isna().all()
    assert res.comparison.agrees


@pytest.mark.slow
def test_cli_compare_report_batch_take_the_map(bench, tmp_path, capsys):
    path, cmap, _ = bench
    assert main(["compare", str(path), str(MODEL), "--map", str(cmap), "--json"]) in (0, 1)
    out = capsys.readouterr().out
    assert '"speed_rpm_measured"' in out
    html = tmp_path / "bench.html"
    assert main(["report", str(path), str(MODEL), "--map", str(cmap), "-o", str(html)]) == 0
    text = html.read_text()
    assert "motor_bench.toml" in text and "channel map" in text
    summary = tmp_path / "summary.csv"
    main(["batch", str(path), "--model", str(MODEL), "--map", str(cmap), "-o", str(summary)])
    table = summary.read_text()
    assert "error" not in table.splitlines()[1], table
