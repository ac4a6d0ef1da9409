"""Centrifugal pendulum modes move with speed and appear in natural_frequencies(speed_rpm=)
and the Campbell data (critical speeds as roots of ω_m(Ω) = qΩ)."""

import numpy as np
import pytest

from crankbench.predict.torsion import dampers
from crankbench.predict.torsion.campbell import campbell_frequencies, system_at_speed
from crankbench.predict.torsion.elements import ShaftLine


def _line(flexible=True):
    line = ShaftLine("pendulum demo")
    line.add_mass("hub", 1.0)
    if flexible:
        line.add_mass("flywheel", 3.0)
        line.add_shaft("hub", "flywheel", stiffness=1e5)
    dampers.add_pendulum_absorber(line, "hub", mass=0.5, pivot_radius=0.1, length=0.025)
    return line.build().replace(cylinder_nodes=[0], firing_angles_deg=[0.0])


@pytest.mark.parametrize("rpm", [500.0, 3000.0])
def test_pendulum_on_a_free_hub_closed_form(rpm):
    """Den Hartog §5.7: hub J + pendulum J_a on k = J_a n² Ω²: ω = n Ω √(1 + J_a/J)."""
    s = _line(flexible=False)
    w = rpm * np.pi / 30
    j_a = 0.5 * 0.125 ** 2
    got = s.natural_frequencies("rad/s", speed_rpm=rpm)
    np.testing.assert_allclose(got, [0.0, 2.0 * w * np.sqrt(1 + j_a / 1.0)], rtol=1e-13)
    # without a speed the pendulum is left out (no stiffness at standstill)
    assert s.natural_frequencies().tolist() == [0.0]


def test_critical_speeds_are_crossings_of_speed_dependent_modes():
    s = _line()
    crit = s.critical_speeds([1.0, 2.0, 3.0, 4.0], (100, 6000))
    assert len(crit) >= 3
    for _, row in crit.iterrows():
        f = s.natural_frequencies(speed_rpm=row.speed_rpm)[row["mode"]]
        assert f == pytest.approx(row.order * row.speed_rpm / 60, rel=1e-8)
        assert row.frequency_hz == pytest.approx(f, rel=1e-12)
    camp = campbell_frequencies(s, [500.0, 1000.0, 2000.0])
    assert set(camp["mode"]) == {1, 2}
    # the pendulum branch grows with speed, the shaft mode stays near its standstill value
    m1 = camp[camp["mode"] == 1].frequency_hz.to_numpy()
    assert np.all(np.diff(m1) > 0)


def test_mode_shapes_at_speed_include_the_pendulum():
    s = _line()
    m = s.mode_shapes(speed_rpm=1500.0)
    assert m.shapes.shape == (3, 3) and np.all(np.abs(m.shapes[2, 1:]) > 0)
    assert system_at_speed(s, 1500.0).edge_stiffness_omega2.max() == 0.0


def test_campbell_plot_draws_the_moving_branches():
    s = _line()
    fig = s.plot_campbell([1.0, 2.0], (100, 3000))
    curves = [ln for ln in fig.axes[0].lines if len(ln.get_xdata()) > 2]
    assert len(curves) == 2          # one line per mode branch, not horizontal lines
    ys = curves[0].get_ydata()
    assert ys[-1] > 5 * ys[0]        # the pendulum branch rises with speed
