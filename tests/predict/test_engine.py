"""Engine model: firing angles from geometry and firing order, exact piston motion of plain and
articulated rods against an independent construction, TOML loading and its errors."""

import numpy as np
import pytest

from crankbench.predict import kinematics as kin
from crankbench.predict.engine import ArticulatedRod, Engine
from crankbench.predict.errors import ModelError


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures the result objects' plot() made (matplotlib warns past 20)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


R, L = 0.05, 0.2


def _inline(angles, order=None, **kw):
    n = len(angles)
    return Engine(crank_angles_deg=angles, crank_radius=R, rod_length=L, reciprocating_mass=1.0,
                  cylinder_positions=np.arange(n) * 0.1, firing_order=order, **kw)


def test_i6_firing_angles_follow_firing_order():
    e = _inline([0, 240, 120, 120, 240, 0], [1, 5, 3, 6, 2, 4])
    np.testing.assert_allclose(e.firing_angles_deg(), [0, 480, 240, 600, 120, 360])
    np.testing.assert_allclose(e.firing_intervals_deg(), [120] * 6)
    assert e.firing_order == (1, 5, 3, 6, 2, 4)


def test_firing_order_rotated_to_start_at_cylinder_one():
    e = _inline([0, 180, 180, 0], [3, 4, 2, 1])
    assert e.firing_order == (1, 3, 4, 2)


def test_inconsistent_firing_order_is_rejected():
    with pytest.raises(ModelError, match=r"firing_order=\[1, 2, 3, 4\] is not consistent"):
        _inline([0, 180, 180, 0], [1, 2, 3, 4])
    with pytest.raises(ModelError, match=r"must list each cylinder 1..4 exactly once"):
        _inline([0, 180, 180, 0], [1, 2, 2, 4])


def test_two_stroke_firing_order_must_follow_tdcs():
    # throw 2 is 240° ahead of throw 1, so it reaches TDC 120° after cylinder 1
    e = _inline([0, 240, 120], [1, 2, 3], cycle=2)
    np.testing.assert_allclose(e.firing_angles_deg(), [0, 120, 240])
    with pytest.raises(ModelError, match="not consistent"):
        _inline([0, 240, 120], [1, 3, 2], cycle=2)


def test_v8_crossplane_without_firing_order_fires_every_90_degrees():
    pins = [0, 90, 270, 180]
    e = Engine(crank_angles_deg=pins + pins, crank_radius=R, rod_length=L,
               reciprocating_mass=1.0, bank_angles_deg=[-45] * 4 + [45] * 4,
               cylinder_positions=[0, .1, .2, .3, .02, .12, .22, .32])
    np.testing.assert_allclose(e.firing_intervals_deg(), [90] * 8)
    # each cylinder fires at one of its TDCs: θ + α − β ≡ 0 (mod 360)
    tdc = e.firing_tdc_shaft_angle + np.deg2rad(e.firing_angles_deg())
    psi = np.rad2deg(tdc) + e.crank_angles_deg - e.bank_angles_deg
    np.testing.assert_allclose(np.mod(psi + 1e-9, 360), 1e-9, atol=1e-6)


def test_explicit_firing_angles_for_uneven_vtwin():
    e = Engine(crank_angles_deg=[0, 0], crank_radius=R, rod_length=L, reciprocating_mass=1.0,
               bank_angles_deg=[-45, 45], firing_angles_deg=[0, 450])
    np.testing.assert_allclose(e.firing_intervals_deg(), [450, 270])
    with pytest.raises(ModelError, match=r"firing_angles_deg\[1\]=400 is not a TDC"):
        Engine(crank_angles_deg=[0, 0], crank_radius=R, rod_length=L, reciprocating_mass=1.0,
               bank_angles_deg=[-45, 45], firing_angles_deg=[0, 400])


def test_plain_piston_motion_matches_kinematics_functions():
    e = Engine(crank_angles_deg=[0, 90], bank_angles_deg=[0, 30], crank_radius=R, rod_length=L,
               reciprocating_mass=1.0)
    th = np.linspace(0, 2 * np.pi, 37)
    x, dx, d2x = e.piston_motion(th)
    psi = th + np.deg2rad(90 - 30)
    np.testing.assert_allclose(x[1], kin.piston_position(psi, crank_radius=R, rod_length=L))
    np.testing.assert_allclose(dx[1], kin.piston_velocity(psi, crank_radius=R, rod_length=L,
                                                          omega=1.0), atol=1e-15)
    np.testing.assert_allclose(d2x[1], kin.piston_acceleration(psi, crank_radius=R,
                                                               rod_length=L, omega=1.0),
                               atol=1e-15)


def _radial(link_radius=0.06, rod_a=0.17):
    n = 5
    beta = np.arange(n) * 72.0
    arts = [None] + [ArticulatedRod(master=0, link_radius=link_radius, link_angle_deg=b,
                                    rod_length=rod_a) for b in beta[1:]]
    return Engine(crank_angles_deg=[0] * n, bank_angles_deg=beta, crank_radius=R, rod_length=L,
                  reciprocating_mass=1.0, articulated=arts, firing_order=[1, 3, 5, 2, 4])


def _articulated_position(theta, r, l, beta_m, beta_j, ra, gamma, la):
    """Independent construction in complex numbers (vertical + 1j·horizontal)."""
    um, uj = np.exp(1j * beta_m), np.exp(1j * beta_j)
    c = r * np.exp(1j * theta)
    b = (c * np.conj(um)).real
    s = b + np.sqrt(b * b - abs(c) ** 2 + l * l)          # master piston pin on its axis
    pm = s * um
    link = c + ra * np.exp(1j * gamma) * (pm - c) / l
    b = (link * np.conj(uj)).real
    return b + np.sqrt(b * b - abs(link) ** 2 + la * la)


def test_articulated_rod_motion_matches_independent_construction():
    e = _radial()
    th = np.linspace(0, 2 * np.pi, 25)
    x, dx, d2x = e.piston_motion(th)
    h = 1e-4
    for j in range(1, 5):
        beta = np.deg2rad(72.0 * j)
        ref = _articulated_position(th, R, L, 0.0, beta, 0.06, beta, 0.17)
        np.testing.assert_allclose(x[j], ref, rtol=1e-13)
        xp = _articulated_position(th + h, R, L, 0.0, beta, 0.06, beta, 0.17)
        xm = _articulated_position(th - h, R, L, 0.0, beta, 0.06, beta, 0.17)
        np.testing.assert_allclose(dx[j], (xp - xm) / (2 * h), atol=1e-9)
        np.testing.assert_allclose(d2x[j], (xp - 2 * ref + xm) / h**2, atol=2e-7)


def test_articulated_stroke_differs_from_master_stroke():
    """The link pin does not run on the crank circle: the articulated stroke is longer than 2r
    (Liang 1948 ch. 3, articulated-rod effect)."""
    e = _radial()
    th = np.linspace(0, 2 * np.pi, 20001)
    x, _, _ = e.piston_motion(th)
    strokes = x.max(axis=1) - x.min(axis=1)
    assert strokes[0] == pytest.approx(2 * R, rel=1e-8)
    assert np.all(strokes[1:] > 2 * R * 1.001)


def test_from_toml_reads_engine_and_ignores_other_tables(tmp_path):
    p = tmp_path / "i4.toml"
    p.write_text("""
[engine]
name = "test I4"
crank_angles_deg = [0, 180, 180, 0]
stroke = 0.08
rod_length = 0.14
reciprocating_mass = [0.5, 0.5, 0.5, 0.5]
rotating_mass = 0.3
cylinder_spacing = 0.09
firing_order = [1, 3, 4, 2]
bore = 0.08
compression_ratio = 10.5

[engine.combustion]
peak_pressure = 6.5e6

[mounts]
anything = "belongs to another loader"
""")
    e = Engine.from_toml(p)
    assert e.name == "test I4" and e.crank_radius == 0.04
    np.testing.assert_allclose(e.cylinder_positions, [0, 0.09, 0.18, 0.27])
    assert e.reference_position == pytest.approx(0.135)
    assert e.combustion == {"peak_pressure": 6.5e6}
    frame = e.to_frame()
    assert list(frame["firing_angle_deg"]) == [0, 540, 180, 360]


def test_from_toml_errors_name_file_and_key(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[engine]\ncrank_angles_deg = [0]\ncrank_radius = 0.05\nrod_length = 0.2\n"
                 "reciprocating_mass = 1.0\nbroe = 0.1\n")
    with pytest.raises(ModelError, match=r"bad.toml: engine.broe is not a known key "
                                         r"\(did you mean 'bore'\?\)"):
        Engine.from_toml(p)
    p.write_text("[engine]\ncrank_angles_deg = [0, 180]\ncrank_radius = 0.05\n"
                 "rod_length = 0.2\nreciprocating_mass = [1.0]\n")
    with pytest.raises(ModelError, match=r"bad.toml: engine.reciprocating_mass has 1 values, "
                                         r"expected 2"):
        Engine.from_toml(p)
    p.write_text("[other]\nx = 1\n")
    with pytest.raises(ModelError, match=r"bad.toml: has no \[engine\] table"):
        Engine.from_toml(p)
    p.write_text("[engine]\ncrank_angles_deg = [0]\ncrank_radius = 0.05\nrod_length = 0.04\n"
                 "reciprocating_mass = 1.0\n")
    with pytest.raises(ModelError, match=r"bad.toml: \[engine\] rod_length=0.04 must exceed"):
        Engine.from_toml(p)


def test_engine_argument_errors():
    with pytest.raises(ModelError, match=r"cylinder_positions has 2 values, expected 3"):
        Engine(crank_angles_deg=[0, 120, 240], crank_radius=R, rod_length=L,
               reciprocating_mass=1.0, cylinder_positions=[0, 1])
    with pytest.raises(ModelError, match=r"cycle=3 must be 2 or 4"):
        Engine(crank_angles_deg=[0], crank_radius=R, rod_length=L, reciprocating_mass=1.0,
               cycle=3)
    with pytest.raises(ModelError, match=r"reciprocating_mass\[1\]=-1.0 must be >= 0"):
        Engine(crank_angles_deg=[0, 180], crank_radius=R, rod_length=L,
               reciprocating_mass=[1.0, -1.0])
    e = Engine(crank_angles_deg=[0], crank_radius=R, rod_length=L, reciprocating_mass=1.0)
    with pytest.raises(ModelError, match="has no bore"):
        e.piston_area
    assert e.plot() is not None
