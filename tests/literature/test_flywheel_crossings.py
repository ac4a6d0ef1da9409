"""Turning-moment crossings, load torque with harmonics, and the texts' mean speeds.

* [Khurmi] R. S. Khurmi, J. K. Gupta, *A Textbook of Theory of Machines*, ch. 16, Example 16.2:
  turning-moment diagram of a petrol engine repeating every half revolution, scales 1 mm =
  5 N·m and 1 mm = 1°, areas above and below the mean line in order +295, −685, +40, −340,
  +960, −270 mm²; rotating parts 36 kg at 150 mm radius of gyration, 1800 rpm → ΔE = 985 mm²
  = 86 N·m, coefficient of fluctuation of speed 0.3 %.
* [AM2] 應用力學 下冊, 第二章 §6-§7: ΔE between the largest and smallest excess energy, read
  at the crossings of the turning moment with the resisting torque; δ = (ω₁ − ω₂)/ω with
  ω = (ω₁ + ω₂)/2 makes ΔE = J ω² δ exact.
"""

import numpy as np
import pytest

from crankbench.predict.flywheel import TurningMoment, harmonic_load

MM2 = 5.0 * np.pi / 180          # J per mm² of the diagram (1 mm = 5 N·m, 1 mm = 1°)


def _khurmi_diagram():
    areas = np.array([295, -685, 40, -340, 960, -270]) * MM2
    n = 1800                                  # 0.1° steps over the half revolution
    a = np.arange(n) * np.pi / n
    seg = np.pi / 6
    k = np.minimum((a // seg).astype(int), 5)
    local = a - k * seg
    # each loop a half sine of the printed area over 30°
    excess = areas[k] * np.pi / (2 * seg) * np.sin(np.pi * local / seg)
    return TurningMoment.from_torque(a, 400.0 + excess, omega=1800 * np.pi / 30)


def test_khurmi_16_2_loop_areas_and_fluctuation():
    tm = _khurmi_diagram()
    c = tm.crossings()
    assert len(c) == 6
    np.testing.assert_allclose(c.loop_area_j / MM2, [295, -685, 40, -340, 960, -270],
                               rtol=2e-4)
    assert tm.fluctuation_of_energy / MM2 == pytest.approx(985, rel=2e-3)
    assert tm.fluctuation_of_energy == pytest.approx(86, abs=0.5)
    delta = tm.speed_fluctuation(36 * 0.15 ** 2)
    assert round(100 * delta, 1) == 0.3
    # the speed is largest at the crossing where the excess energy peaks (a "down" crossing)
    st = tm.speed_statistics(36 * 0.15 ** 2)
    downs = c[c.direction == "down"]
    top = downs.angle_deg.iloc[int(np.argmax(downs.energy_j))]
    assert st["angle_max_deg"] == pytest.approx(top, abs=0.2)


def test_load_torque_with_its_own_harmonics():
    a = np.arange(1440) * 4 * np.pi / 1440
    engine = 500 + 300 * np.sin(2 * a) + 80 * np.cos(3 * a)
    load = harmonic_load(mean=500.0, orders=[2.0], amplitudes=[100.0], phases_deg=[90.0])
    tm = TurningMoment.from_torque(a, engine, omega=150.0, load_torque=load)
    # T − T_load = 200 sin 2φ + 80 cos 3φ: E = 100 (1 − cos 2φ) + (80/3) sin 3φ
    fine = np.linspace(0, 4 * np.pi, 200001)
    e = 100 * (1 - np.cos(2 * fine)) + 80 / 3 * np.sin(3 * fine)
    assert tm.fluctuation_of_energy == pytest.approx(np.ptp(e), rel=1e-6)
    const = TurningMoment.from_torque(a, engine, omega=150.0)
    assert const.fluctuation_of_energy > tm.fluctuation_of_energy
    np.testing.assert_allclose(tm.load, load(a), rtol=1e-14)


def test_mean_speed_definitions():
    a = np.arange(2880) * 4 * np.pi / 2880
    tm = TurningMoment.from_torque(a, 2000 + 3000 * np.sin(2 * a) + 900 * np.sin(4 * a),
                                   omega=80.0)
    j = 2.0
    st = tm.speed_statistics(j)
    # the time mean is the speed the diagram was given (tachometer)
    assert st["mean_time"] == pytest.approx(80.0, rel=1e-12)
    # harmonic ≤ arithmetic ≤ quadratic mean
    assert st["mean_time"] < st["mean_angle"] < st["mean_rms"]
    # energy: ½J(ω₁² − ω₂²) = ΔE  ⇔  δ = ΔE/(J ω²) with ω the mean of the extremes
    w = tm.speed(j)
    e = tm.excess_energy()
    de = e.max() - e.min()
    assert st["coefficient_mean_extremes"] == pytest.approx(
        de / (j * st["mean_extremes"] ** 2), rel=1e-10)
    assert 0.5 * j * (w.max() ** 2 - w.min() ** 2) == pytest.approx(de, rel=1e-10)


def test_load_table_in_the_model_file(tmp_path):
    from crankbench.predict.flywheel import load_from_toml

    p = tmp_path / "engine_with_load.toml"
    p.write_text("[engine]\ncrank_angles_deg = [0]\ncrank_radius = 0.05\nrod_length = 0.2\n"
                 "reciprocating_mass = 1.0\n\n[load]\norders = [2.0]\namplitudes_nm = [30.0]\n"
                 "phases_deg = [90.0]\nmean_nm = 100.0\n")
    load = load_from_toml(p)
    a = np.array([0.0, np.pi / 4])
    np.testing.assert_allclose(load(a), 100.0 + 30.0 * np.cos(2 * a - np.pi / 2), atol=1e-12)
    p.write_text(p.read_text() + "orderz = [1]\n")
    with pytest.raises(ValueError, match="orderz"):
        load_from_toml(p)
