"""Torsional vibration against textbook systems and closed forms.

Sources (seeds in /work/shared/seeds):

* [JT1958] 交通大学内燃机教研组, 《内燃机动力学、构造与计算》上册, 机械工业出版社, 1958:
  第二篇 第一章 §3 二质量振动系统 (p. 87), §4 三质量振动系统 (p. 91); 第二章 §1 代替系统
  (p. 96), §2 多质量振动系统 (p. 108, Holzer's tabular method); 第四章 §1 临界转速 (p. 150),
  §2 共振扭幅 (p. 153).
* [AM2] 《应用力学》下册 引擎动力学: §20 轴之有二轮者 (p. 91), §21 轴上有三个轮者 (p. 92),
  §22 Equivalent Shaft 及 Equivalent Inertia (p. 94), §23 联动之轴 (geared shafts, p. 100),
  §24 Forced Torsional Vibration (p. 107).
* [Tim] S. Timoshenko, *Vibration Problems in Engineering*, 2nd ed., Van Nostrand, 1937,
  ch. 5, torsional vibration of a uniform circular shaft (ω_m = mπ/l·√(G/ρ)).
* [Th] W. T. Thomson, *Theory of Vibration with Applications*, Prentice Hall: lumped chains by
  difference equations (uniform chain eigenvalues 4(k/J) sin²(…)).
* [KW] W. Ker Wilson, *Practical Solution of Torsional Vibration Problems*, vol. 1, 1956:
  branched systems with identical branches.
"""

import numpy as np
import pytest

from crankbench.predict.torsion import TorsionalSystem, chain
from crankbench.predict.torsion.elements import ShaftLine, shaft_stiffness, stepped_shaft
from crankbench.predict.torsion.resonance import resonance_amplitudes


def test_two_rotor_system():
    """[AM2] §20 p. 91, [JT1958] p. 87: ω² = k (J1 + J2)/(J1 J2); the node divides the shaft
    in the inverse ratio of the inertias, l1 = l J2/(J1 + J2)."""
    j1, j2, length = 12.0, 3.0, 1.2
    k = shaft_stiffness(length, 0.06)
    s = chain([j1, j2], [k])
    w = s.natural_frequencies("rad/s")[1]
    assert w == pytest.approx(np.sqrt(k * (j1 + j2) / (j1 * j2)), rel=1e-15)
    a1, a2 = s.mode_shapes().shapes[:, 1]
    node_from_1 = length * a1 / (a1 - a2)  # linear twist along the shaft
    assert node_from_1 == pytest.approx(length * j2 / (j1 + j2), rel=1e-13)


def three_rotor_roots(j1, j2, j3, k1, k2):
    """[AM2] §21 p. 92, [JT1958] p. 91: J1J2J3 ω⁴ − [k1 J3 (J1+J2) + k2 J1 (J2+J3)] ω²
    + k1 k2 (J1+J2+J3) = 0."""
    a = j1 * j2 * j3
    b = k1 * j3 * (j1 + j2) + k2 * j1 * (j2 + j3)
    c = k1 * k2 * (j1 + j2 + j3)
    disc = np.sqrt(b * b - 4 * a * c)
    return np.sqrt(np.sort([2 * c / (b + disc), (b + disc) / (2 * a)]))


def test_three_rotor_system():
    j, k = (4.0, 1.5, 9.0), (2.0e5, 7.0e5)
    s = chain(list(j), list(k))
    np.testing.assert_allclose(s.natural_frequencies("rad/s")[1:], three_rotor_roots(*j, *k),
                               rtol=1e-14)


def test_holzer_residual_matches_frequency_polynomial():
    """[JT1958] 第二章 §2 p. 108 (Holzer table): for a free three-mass chain started with unit
    amplitude, the residual torque at trial ω is ω²·P(ω²)/(k1 k2) with
    P = k1k2(J1+J2+J3) − [k1J3(J1+J2) + k2J1(J2+J3)] ω² + J1J2J3 ω⁴."""
    j1, j2, j3, k1, k2 = 4.0, 1.5, 9.0, 2.0e5, 7.0e5
    s = chain([j1, j2, j3], [k1, k2])
    for f in [3.0, 17.5, 60.0, 123.4]:
        w2 = (2 * np.pi * f) ** 2
        p = (k1 * k2 * (j1 + j2 + j3) - (k1 * j3 * (j1 + j2) + k2 * j1 * (j2 + j3)) * w2
             + j1 * j2 * j3 * w2 * w2)
        t = s.holzer_table(f)
        assert t.attrs["residual_torque"] == pytest.approx(w2 * p / (k1 * k2), rel=1e-12)
        # the table's first rows: inertia torque J1 ω², twist J1 ω²/k1
        assert t.inertia_torque.iloc[0] == pytest.approx(j1 * w2)
        assert t.amplitude.iloc[1] == pytest.approx(1 - j1 * w2 / k1)


def test_five_disk_chain():
    """[Th]: five equal disks on equal shaft lengths: free-free ω_r = 2√(k/J) sin(rπ/10);
    clamped at one end, ω_r = 2√(k/J) sin((2r−1)π/22)."""
    j, k = 0.8, 3.2e4
    free = chain([j] * 5, [k] * 4).natural_frequencies("rad/s")
    np.testing.assert_allclose(free, 2 * np.sqrt(k / j) * np.sin(np.arange(5) * np.pi / 10),
                               rtol=1e-14, atol=0)
    fixed = chain([j] * 5, [k] * 5).natural_frequencies("rad/s")
    np.testing.assert_allclose(
        fixed, 2 * np.sqrt(k / j) * np.sin((2 * np.arange(1, 6) - 1) * np.pi / 22), rtol=1e-14)


def test_equivalent_shaft():
    """[AM2] §22 p. 94: a stepped shaft acts like a uniform shaft of the reference diameter and
    equivalent length L_e = Σ L_i (D_ref/D_i)⁴."""
    segs = [(0.4, 0.05), (0.3, 0.08), (0.5, 0.06)]
    r = stepped_shaft(segs, reference_diameter=0.05)
    le = sum(length * (0.05 / d) ** 4 for length, d in segs)
    assert r["equivalent_length"] == pytest.approx(le, rel=1e-14)
    line = ShaftLine("stepped")
    line.add_mass("a", 2.0)
    line.add_mass("b", 5.0)
    line.add_shaft("a", "b", segments=segs)
    w = line.build().natural_frequencies("rad/s")[1]
    k_e = shaft_stiffness(le, 0.05)
    assert w == pytest.approx(np.sqrt(k_e * 7.0 / 10.0), rel=1e-13)


def test_geared_shafts():
    """[AM2] §23 p. 100: refer the driven side to the driver by the speed ratio n: inertias and
    stiffnesses × n². Motor J1 —k1— pinion Jp | wheel Jw (n) —k2— load J2 is the three-rotor
    system (J1, Jp + n²Jw, n²J2; k1, n²k2)."""
    n = 1 / 3.5
    j1, jp, jw, j2, k1, k2 = 6.0, 0.2, 1.1, 40.0, 3.0e5, 1.2e6
    line = ShaftLine("geared")
    line.add_mass("motor", j1)
    line.add_mass("pinion", jp)
    line.add_mass("wheel", jw, ratio=n)
    line.add_mass("load", j2, ratio=n)
    line.add_shaft("motor", "pinion", stiffness=k1)
    line.add_gear("pinion", "wheel", ratio=n)
    line.add_shaft("wheel", "load", stiffness=k2)
    w = line.build().natural_frequencies("rad/s")[1:]
    np.testing.assert_allclose(w, three_rotor_roots(j1, jp + n * n * jw, n * n * j2, k1,
                                                    n * n * k2), rtol=1e-14)


def test_branched_system_with_identical_branches():
    """[KW]: two identical branches on a hub. Antisymmetric mode: hub still, ω² = k_b/J_b.
    Symmetric modes: the branches move together and act as one branch of 2J_b, 2k_b."""
    jh, jb, kb, k0, j0 = 30.0, 2.0, 5.0e5, 8.0e5, 12.0
    s = TorsionalSystem([j0, jh, jb, jb], [(0, 1), (1, 2), (1, 3)], [k0, kb, kb])
    w = s.natural_frequencies("rad/s")
    sym = chain([j0, jh, 2 * jb], [k0, 2 * kb]).natural_frequencies("rad/s")
    np.testing.assert_allclose(np.sort(np.r_[sym, np.sqrt(kb / jb)]), w, rtol=1e-13)


def test_distributed_shaft_discretisation_converges():
    """[Tim] ch. 5: a free-free uniform shaft has ω_m = mπ/l·√(G/ρ). [JT1958] p. 96: replace it by
    N lumped sections (half masses at the ends); the error falls as 1/N²."""
    g, rho, length, d = 80e9, 7850.0, 2.0, 0.1
    ip = np.pi * d ** 4 / 32
    exact = np.arange(1, 4) * np.pi / length * np.sqrt(g / rho)
    errors = []
    for n in (10, 20, 40, 80, 1000):
        j = np.full(n + 1, rho * ip * length / n)
        j[[0, -1]] /= 2
        k = np.full(n, g * ip * n / length)
        w = chain(j, k).natural_frequencies("rad/s")[1:4]
        errors.append(np.abs(w - exact) / exact)
    errors = np.array(errors)
    ratios = errors[:3, 0] / errors[1:4, 0]
    np.testing.assert_allclose(ratios, 4.0, rtol=0.02)  # second-order convergence
    assert errors[-1].max() < 1e-5


def test_forced_vibration_of_single_rotor():
    """[AM2] §24 p. 107: rotor J on a shaft k to ground, torque T cos ωt, viscous c:
    amplitude = (T/k) / |1 − r² + 2iζr|, r = ω/ω_n, ζ = c/(2√(kJ))."""
    j, k, c, t = 2.0, 5.0e4, 15.0, 40.0
    s = chain([j], [k]).replace(node_damping=[c], cylinder_nodes=[0], firing_angles_deg=[0.0])
    rpm = np.linspace(200, 3000, 57)
    amp = np.abs(s.forced_response(rpm, torque=[t], orders=[1.0]).angle[:, 0, 0])
    wn, zeta = np.sqrt(k / j), c / (2 * np.sqrt(k * j))
    r = rpm * np.pi / 30 / wn
    np.testing.assert_allclose(amp, (t / k) / np.abs(1 - r * r + 2j * zeta * r), rtol=1e-12)


def test_energy_method_gap_for_one_degree_of_freedom():
    """[JT1958] 第四章 §2 p. 153: the energy method gives (T/k)/(2ζ) at ω_n; the true peak is
    (T/k)/(2ζ√(1−ζ²)), so the reported method error is √(1−ζ²) − 1."""
    j, k, c = 2.0, 5.0e4, 40.0
    s = chain([j], [k]).replace(node_damping=[c], cylinder_nodes=[0], firing_angles_deg=[0.0])
    t = resonance_amplitudes(s, torque=lambda q, w: 25.0, orders=[2.0])
    zeta = c / (2 * np.sqrt(k * j))
    row = t.iloc[0]
    assert row.energy_balance_deg == pytest.approx(np.rad2deg(25.0 / k / (2 * zeta)), rel=1e-12)
    assert row.exact_deg == pytest.approx(np.rad2deg(25.0 / k / (2 * zeta * np.sqrt(
        1 - zeta ** 2))), rel=1e-8)
    assert row.method_error == pytest.approx(np.sqrt(1 - zeta ** 2) - 1, rel=1e-5)
    assert row.dynamic_magnifier == pytest.approx(1 / (2 * zeta), rel=1e-12)


def test_critical_speed_definition():
    """[JT1958] 第四章 §1 p. 150: n_c = 60 f / q for every mode and order."""
    s = chain([5.0, 1.0, 8.0], [3.0e5, 1.0e5])
    f = s.natural_frequencies()[1:]
    cs = s.critical_speeds([1.5, 4.5])
    for _, row in cs.iterrows():
        assert row.speed_rpm == pytest.approx(60 * f[row["mode"] - 1] / row.order, rel=1e-15)
