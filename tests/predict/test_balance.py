"""Balance: the order-domain rotating-vector result against a second route (exact time-domain
sum over cylinders + FFT), counterweights, balance shafts, emergent symmetry rules."""

from pathlib import Path

import numpy as np
import pytest

from crankbench.predict import balance as bal
from crankbench.predict.engine import ArticulatedRod, Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.kinematics import series_coefficients


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures the result objects' plot() made (matplotlib warns past 20)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


R, L, M, W = 0.045, 0.15, 0.7, 2 * np.pi * 4000 / 60
SCALE = M * R * W**2


def _engine(angles, positions=None, banks=None, **kw):
    kw.setdefault("reciprocating_mass", M)
    kw.setdefault("rotating_mass", 0.5)
    return Engine(crank_angles_deg=angles, crank_radius=R, rod_length=L,
                  cylinder_positions=positions, bank_angles_deg=banks, **kw)


def _radial(articulated=True, n=5):
    beta = np.arange(n) * 360.0 / n
    arts = None
    if articulated:
        arts = [None] + [ArticulatedRod(master=0, link_radius=0.055, link_angle_deg=b,
                                        rod_length=0.125) for b in beta[1:]]
    return Engine(crank_angles_deg=[0] * n, bank_angles_deg=beta, crank_radius=R, rod_length=L,
                  reciprocating_mass=M, rotating_mass=0.0, articulated=arts)


LAYOUTS = {
    "single": lambda: _engine([0]),
    "i2_180": lambda: _engine([0, 180], [0, 0.1]),
    "i3": lambda: _engine([0, 240, 120], [0, 0.1, 0.2]),
    "i4": lambda: _engine([0, 180, 180, 0], [0, .1, .2, .3]),
    "i5": lambda: _engine([0, 144, 288, 72, 216], [0, .1, .2, .3, .4]),
    "v6_60": lambda: _engine([0, 0, 120, 120, 240, 240], [0, .02, .1, .12, .2, .22],
                             [-30, 30] * 3),
    "v8_cross": lambda: _engine([0, 90, 270, 180] * 2, [0, .1, .2, .3, .02, .12, .22, .32],
                                [-45] * 4 + [45] * 4),
    "boxer4": lambda: _engine([0, 180, 180, 0], [0, .1, .12, .22], [90, -90, 90, -90]),
    "w3": lambda: _engine([0, 0, 0], None, [-60, 0, 60]),
    "offset_i4": lambda: _engine([0, 180, 180, 0], [0, .1, .2, .3], pin_offset=0.004),
    "radial5": lambda: _radial(True),
}


def _fft_route(engine, orders, npts=256, **kw):
    th = 2 * np.pi * np.arange(npts) / npts
    ds = bal.shaking_forces(engine, th, omega=W, **kw)
    f = np.fft.fft(ds["force_vertical"].values + 1j * ds["force_horizontal"].values) / npts
    m = np.fft.fft(ds["moment_pitch"].values + 1j * ds["moment_yaw"].values) / npts
    o = np.asarray(orders)
    return f[o], f[npts - o], m[o], m[npts - o]


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_order_domain_agrees_with_time_domain_fft(name):
    """Second route: exact per-cylinder forces summed in time, FFT → same phasors to 1e-9."""
    e = LAYOUTS[name]()
    orders = (1, 2, 3, 4, 6, 8)
    ds = bal.unbalance(e, omega=W, orders=orders)
    P, Q, PM, QM = _fft_route(e, orders)
    fscale = max(float(ds["force"].max()), SCALE)
    mscale = max(float(ds["moment"].max()), SCALE * 0.1)
    np.testing.assert_allclose(ds["force_forward_phasor"].values, P, rtol=0, atol=1e-9 * fscale)
    np.testing.assert_allclose(ds["force_backward_phasor"].values, Q, rtol=0,
                               atol=1e-9 * fscale)
    np.testing.assert_allclose(ds["moment_forward_phasor"].values, PM, rtol=0,
                               atol=1e-9 * mscale)
    np.testing.assert_allclose(ds["moment_backward_phasor"].values, QM, rtol=0,
                               atol=1e-9 * mscale)
    # the largest magnitude over a revolution, from the time signal of each order alone
    th = np.linspace(0, 2 * np.pi, 4001)
    for k, n in enumerate(orders):
        z = P[k] * np.exp(1j * n * th) + Q[k] * np.exp(-1j * n * th)
        assert ds["force"].values[k] == pytest.approx(np.abs(z).max(), rel=1e-6, abs=1e-9 * fscale)


def test_i4_flat_plane_second_order_force_closed_form():
    e = LAYOUTS["i4"]()
    ds = bal.unbalance(e, omega=W, orders=(1, 2, 4))
    a = series_coefficients(R / L, 4)
    assert float(ds["force"].sel(order=2)) == pytest.approx(4 * SCALE * a[2], rel=1e-13)
    assert float(ds["force_vertical"].sel(order=2)) == pytest.approx(4 * SCALE * a[2], rel=1e-13)
    assert float(ds["force_horizontal"].sel(order=2)) == pytest.approx(0, abs=1e-9 * SCALE)
    assert float(ds["force"].sel(order=4)) == pytest.approx(4 * SCALE * abs(a[4]), rel=1e-12)
    # mirror-symmetric crankshaft: every moment vanishes (not hard-coded anywhere)
    assert np.all(ds["moment"].values < 1e-12 * SCALE)
    assert float(ds["force"].sel(order=1)) < 1e-12 * SCALE


def test_single_cylinder_half_reciprocating_counterweight_leaves_backward_half():
    """Liang 1948 §2-1: with ½ of the reciprocating mass in the counterweight the primary
    force becomes a vector of magnitude A₁/2 rotating against the crank."""
    e = LAYOUTS["single"]()
    cw = bal.counterweights(e, balance_factor=0.5)
    ds = bal.unbalance(e, omega=W, orders=(1,), counterweights=cw)
    assert float(ds["force_forward"][0]) == pytest.approx(0.0, abs=1e-9 * SCALE)
    assert float(ds["force_backward"][0]) == pytest.approx(SCALE / 2, rel=1e-13)
    assert float(ds["force_vertical"][0]) == pytest.approx(SCALE / 2, rel=1e-13)
    assert float(ds["force_horizontal"][0]) == pytest.approx(SCALE / 2, rel=1e-13)
    # adding a backward-turning order-1 shaft kills it entirely
    shafts = bal.lanchester_shafts(e, order=1, counterweights=cw)
    assert [s.direction for s in shafts] == [-1]
    ds = bal.unbalance(e, omega=W, orders=(1,), counterweights=cw, shafts=shafts)
    assert float(ds["force"][0]) < 1e-9 * SCALE


def test_two_plane_shafts_cancel_force_and_moment():
    e = LAYOUTS["i3"]()
    for order in (1, 2):
        shafts = bal.lanchester_shafts(e, order=order, positions=(-0.05, 0.25))
        ds = bal.unbalance(e, omega=W, orders=(order,), shafts=shafts)
        assert float(ds["force"][0]) < 1e-9 * SCALE
        assert float(ds["moment"][0]) < 1e-9 * SCALE * 0.1
        # and the time-domain route sees the same cancellation
        P, Q, PM, QM = _fft_route(e, [order], shafts=shafts)
        assert abs(P[0]) + abs(Q[0]) < 1e-9 * SCALE


def test_residual_table_reports_before_and_after():
    e = LAYOUTS["i4"]()
    res = bal.balance_residuals(e, omega=W, orders=(1, 2, 4), balance_factor=0.0,
                                shaft_orders=(2,))
    df = res.to_frame()
    assert list(df["order"]) == [1, 2, 4]
    assert df["force_unbalanced_n"][1] > 1e3 and df["force_n"][1] < 1e-6
    assert df["force_n"][2] == pytest.approx(df["force_unbalanced_n"][2])
    assert "balance shafts, order 2" in res.measures[-1]
    assert res.plot() is not None


def test_v8_crossplane_forces_balanced_primary_couple_rotating():
    e = LAYOUTS["v8_cross"]()
    ds = bal.unbalance(e, omega=W, orders=(1, 2))
    assert np.all(ds["force"].values < 1e-9 * SCALE)
    # 90° V: the primary couple is a pure forward-rotating vector (balanceable by counterweights)
    assert float(ds["moment_backward"].sel(order=1)) < 1e-9 * SCALE
    assert float(ds["moment_forward"].sel(order=1)) > 0.1 * SCALE


def test_shaking_force_values_for_single_cylinder():
    e = _engine([0], rotating_mass=0.0)
    ds = bal.shaking_forces(e, [0.0, np.pi], omega=W)
    # at TDC m r ω² (1 + λ) upwards, at BDC m r ω² (1 − λ) downwards
    np.testing.assert_allclose(ds["force_vertical"].values,
                               [SCALE * (1 + R / L), -SCALE * (1 - R / L)], rtol=1e-13)


def test_bad_arguments():
    e = LAYOUTS["i4"]()
    with pytest.raises(ModelError, match=r"orders=0 must be >= 1"):
        bal.unbalance(e, omega=W, orders=(0, 2))
    with pytest.raises(ModelError, match=r"balance_factor=1.5 must lie in \[0, 1\]"):
        bal.counterweights(e, balance_factor=1.5)
    with pytest.raises(ModelError, match=r"omega=-1 must lie in"):
        bal.unbalance(e, omega=-1)


ENGINES_DIR = Path(__file__).resolve().parents[2] / "sample_data" / "engines"
SAMPLES = sorted(p.stem for p in ENGINES_DIR.glob("*.toml")
                 if not Engine.from_toml(p).rotary)    # rotary engines: refused, see below


def test_rotary_engine_balance_is_refused_not_guessed():
    e = Engine.from_toml(ENGINES_DIR / "rotary9.toml")
    with pytest.raises(ModelError, match="rotary engine"):
        bal.unbalance(e, omega=100.0)
    with pytest.raises(ModelError, match="rotary engine"):
        bal.shaking_forces(e, [0.0], omega=100.0)


@pytest.mark.parametrize("name", SAMPLES)
def test_sample_engines_second_route(name):
    """Every sample engine: order-domain phasors = FFT of the exact time-domain sum (1e-9)."""
    e = Engine.from_toml(ENGINES_DIR / f"{name}.toml")
    w = e.rated_speed_rpm * np.pi / 30
    orders = (1, 2, 3, 4, 6, 8)
    ds = bal.unbalance(e, omega=w, orders=orders)
    th = 2 * np.pi * np.arange(256) / 256
    sf = bal.shaking_forces(e, th, omega=w)
    f = np.fft.fft(sf["force_vertical"].values + 1j * sf["force_horizontal"].values) / 256
    m = np.fft.fft(sf["moment_pitch"].values + 1j * sf["moment_yaw"].values) / 256
    o = np.asarray(orders)
    scale = float(np.sum(e.reciprocating_mass + e.rotating_mass) * e.crank_radius) * w**2
    span = max(float(np.ptp(e.cylinder_positions)), e.crank_radius)
    np.testing.assert_allclose(ds["force_forward_phasor"].values, f[o], atol=1e-9 * scale)
    np.testing.assert_allclose(ds["force_backward_phasor"].values, f[256 - o], atol=1e-9 * scale)
    np.testing.assert_allclose(ds["moment_forward_phasor"].values, m[o],
                               atol=1e-9 * scale * span)
    np.testing.assert_allclose(ds["moment_backward_phasor"].values, m[256 - o],
                               atol=1e-9 * scale * span)


def test_predict_balance_cli(capsys):
    import json

    from crankbench.analysis.cli import main

    assert main(["predict", "balance", str(ENGINES_DIR / "i4.toml"), "--json",
                 "--speed-rpm", "3000", "--shafts", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    rows = {r["order"]: r for r in out["residuals"]}
    a2 = series_coefficients(0.043 / 0.145, 2)[2]
    assert rows[2]["force_unbalanced_n"] == pytest.approx(
        4 * 0.55 * 0.043 * (3000 * np.pi / 30) ** 2 * a2, rel=1e-12)
    assert rows[2]["force_n"] == 0.0
    assert len(out["mount_modes"]) == 6 and len(out["transmitted"]) == 5
    assert main(["predict", "balance", str(ENGINES_DIR / "radial5.toml"),
                 "--balance-factor", "0.5"]) == 0
    text = capsys.readouterr().out
    assert "balance residuals" in text and "counterweights" in text
