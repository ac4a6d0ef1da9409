"""Balance of multi-cylinder engines against the closed forms of the source texts.

Sources (seeds in /work/shared/seeds):

* [Zhao] *Engine Design* (內燃機設計), ch. 3 "Balance of internal-combustion engines":
  §2 forward/backward rotating vectors of a single cylinder; §3 inline engines — 4-stroke twin
  (180°), three (120°), four (flat) and six; general formulas and the mirror-symmetry rule
  ("for an even number of throws arranged mirror-symmetrically about the middle of the
  crankshaft every inertia moment is zero").
* [Liang 1948] Liang Shoupan, *Engine Dynamics* (1948), ch. 2 §2-1 (half the reciprocating
  mass in the counterweight of a single cylinder), ch. 3 (radial engines: the primary force of a
  radial engine is a constant vector turning with the crank, balanced by a counterweight of half
  the reciprocating mass on the crank pin; master and articulated rods).

Closed forms are exact here (the source's λ in the second-order terms is the leading term of
the exact coefficient A₂ = a₂, computed independently by mpmath quadrature).
"""

import mpmath as mp
import numpy as np
import pytest

from crankbench.predict.balance import counterweights, unbalance
from crankbench.predict.engine import ArticulatedRod, Engine

R, L, M, MR = 0.043, 0.145, 0.55, 0.45
W = 6000 * np.pi / 30
C = M * R * W**2                 # m_j R ω²
S = 0.091                        # cylinder spacing l


def _a2_mpmath(lam):
    """Exact second-order coefficient: a₂ = 4 c₂ / λ, c₂ the cos 2θ Fourier coefficient of
    sqrt(1 − λ² sin² θ)."""
    with mp.workdps(30):
        lam = mp.mpf(lam)
        c2 = mp.quad(lambda t: mp.sqrt(1 - lam**2 * mp.sin(t) ** 2) * mp.cos(2 * t),
                     [0, mp.pi]) * 2 / mp.pi
        return float(4 * c2 / lam)


def _inline(angles, rotating=MR):
    n = len(angles)
    return Engine(crank_angles_deg=angles, crank_radius=R, rod_length=L, reciprocating_mass=M,
                  rotating_mass=rotating, cylinder_positions=np.arange(n) * S)


def test_zhao_i4_flat_plane_second_order_force():
    """[Zhao] §3.3: ΣP_jII = −4 m_j λ R ω² cos 2θ, largest at θ = 0°, 180°: 4 m_j R ω² λ
    (λ → exact A₂); everything else balanced."""
    ds = unbalance(_inline([0, 180, 180, 0]), omega=W, orders=(1, 2))
    a2 = _a2_mpmath(R / L)
    assert float(ds["force"].sel(order=2)) == pytest.approx(4 * C * a2, rel=1e-13)
    assert float(ds["force_horizontal"].sel(order=2)) < 1e-12 * C
    assert float(ds["force"].sel(order=1)) < 1e-12 * C
    assert np.all(ds["moment"].values < 1e-12 * C * S)


def test_zhao_i2_180_twin():
    """[Zhao] §3.1: ΣP_r = 0, ΣP_jI = 0, ΣP_jII = −2 m_j λ R ω² cos 2θ; ΣM_r = m_r R ω² l
    (rotating), ΣM_jI = m_j R ω² l cos θ, ΣM_jII = 0."""
    ds = unbalance(_inline([0, 180]), omega=W, orders=(1, 2))
    a2 = _a2_mpmath(R / L)
    assert float(ds["force"].sel(order=1)) < 1e-12 * C
    assert float(ds["force"].sel(order=2)) == pytest.approx(2 * C * a2, rel=1e-13)
    cr = MR * R * W**2
    assert float(ds["moment_forward"].sel(order=1)) == pytest.approx(cr * S + C * S / 2,
                                                                       rel=1e-13)
    assert float(ds["moment_backward"].sel(order=1)) == pytest.approx(C * S / 2, rel=1e-13)
    # reciprocating part alone: a planar couple m_j R ω² l cos θ
    ds0 = unbalance(_inline([0, 180], rotating=0.0), omega=W, orders=(1, 2))
    assert float(ds0["moment_pitch"].sel(order=1)) == pytest.approx(C * S, rel=1e-13)
    assert float(ds0["moment_yaw"].sel(order=1)) < 1e-12 * C * S
    assert float(ds0["moment"].sel(order=2)) < 1e-12 * C * S


def test_zhao_i3_couples_proportional_to_sqrt3():
    """[Zhao] §3.2: forces of orders 1 and 2 balanced; ΣM_jI,max = √3 m_j R ω² l,
    ΣM_jII,max = √3 λ m_j R ω² l (vertical plane), ΣM_r = √3 m_r R ω² l rotating, 30° from
    the first throw."""
    e = _inline([0, 240, 120])
    ds0 = unbalance(_inline([0, 240, 120], rotating=0.0), omega=W, orders=(1, 2))
    a2 = _a2_mpmath(R / L)
    assert np.all(ds0["force"].values < 1e-12 * C)
    assert float(ds0["moment_pitch"].sel(order=1)) == pytest.approx(np.sqrt(3) * C * S,
                                                                      rel=1e-13)
    assert float(ds0["moment_pitch"].sel(order=2)) == pytest.approx(np.sqrt(3) * a2 * C * S,
                                                                      rel=1e-13)
    assert float(ds0["moment_yaw"].sel(order=1)) < 1e-12 * C * S
    # rotating masses: a constant couple √3 m_r R ω² l turning with the crank
    rot = unbalance(e, omega=W, orders=(1,))["moment_forward_phasor"].values[0] - \
        ds0["moment_forward_phasor"].values[0]
    assert abs(rot) == pytest.approx(np.sqrt(3) * MR * R * W**2 * S, rel=1e-13)
    off = np.rad2deg(np.angle(rot)) % 180
    assert min(abs(off - 30), abs(off - 150)) < 1e-9


def test_zhao_i6_free_of_orders_1_2_4():
    """[Zhao] §3.4: the six (120°, 1-5-3-6-2-4) has ΣP and ΣM of every listed order zero."""
    ds = unbalance(_inline([0, 240, 120, 120, 240, 0]), omega=W, orders=(1, 2, 4, 6))
    assert np.all(ds["force"].sel(order=[1, 2, 4]).values < 1e-12 * C)
    assert np.all(ds["moment"].values < 1e-12 * C * S)
    # the 6th order adds up: 6 m_j R ω² a₆
    from crankbench.predict.kinematics import series_coefficients

    a6 = series_coefficients(R / L, 6)[6]
    assert float(ds["force"].sel(order=6)) == pytest.approx(6 * C * abs(a6), rel=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_zhao_mirror_symmetric_crankshafts_have_no_moments(seed):
    """[Zhao] §3 general rule: even number of throws, mirror-symmetric about the middle →
    every inertia moment is zero (emerges from the vector sums, not coded)."""
    rng = np.random.default_rng(seed)
    half = list(rng.uniform(0, 360, size=int(rng.integers(1, 5))))
    angles = half + half[::-1]
    ds = unbalance(_inline(angles), omega=W, orders=range(1, 13))
    assert np.all(ds["moment"].values < 1e-11 * C * S)
    # while an asymmetric arrangement of the same throws generally is not
    if len(half) > 1:
        ds2 = unbalance(_inline(half + half), omega=W, orders=(1,))
        assert float(ds2["moment"][0]) > 1e-3 * C * S


def _radial(articulated, link_offset_deg=0.0):
    n = 5
    beta = np.arange(n) * 72.0
    arts = None
    if articulated:
        arts = [None] + [ArticulatedRod(master=0, link_radius=0.062,
                                        link_angle_deg=b + link_offset_deg, rod_length=0.2)
                         for b in beta[1:]]
    return Engine(crank_angles_deg=[0] * n, bank_angles_deg=beta, crank_radius=0.057,
                  rod_length=0.262, reciprocating_mass=1.9, rotating_mass=0.0,
                  articulated=arts)


def test_liang_radial_primary_force_constant_and_half_mass_counterweight():
    """[Liang 1948] ch. 3: with all rods on the crank pin the primary force of a Z-cylinder
    radial is a constant vector Z m_j r ω²/2 turning with the crank; a counterweight of half the
    reciprocating mass (Z m_j / 2 at the crank radius) removes it."""
    e = _radial(False)
    w = 2200 * np.pi / 30
    c = 1.9 * 0.057 * w**2
    ds = unbalance(e, omega=w, orders=(1, 2))
    assert float(ds["force_forward"].sel(order=1)) == pytest.approx(5 * c / 2, rel=1e-13)
    assert float(ds["force_backward"].sel(order=1)) < 1e-12 * c
    th = np.linspace(0, 2 * np.pi, 721)
    from crankbench.predict.balance import shaking_forces

    sf = shaking_forces(e, th, omega=w)
    # the first-order part of the time signal has constant magnitude
    p = complex(ds["force_forward_phasor"].sel(order=1))
    assert np.ptp(np.abs(p * np.exp(1j * th))) < 1e-9 * c
    cw = counterweights(e, balance_factor=0.5)
    assert sum(x.mass_radius for x in cw) == pytest.approx(5 * 1.9 / 2 * 0.057)
    ds = unbalance(e, omega=w, orders=(1,), counterweights=cw)
    assert float(ds["force"][0]) < 1e-12 * c
    assert sf["force_vertical"].size == th.size


def test_liang_radial_articulated_rod_correction():
    """[Liang 1948] ch. 3 (主連桿與副連桿, 連桿斜連之影響): the link pins do not run on the
    crank circle. With the link pins at the cylinder spacing the extra first-harmonic motion
    of each link pin is square to its own cylinder axis, so the primary force stays the constant
    forward vector (the half-mass counterweight still cancels it exactly), but the second-order
    forces no longer cancel as they do with plain rods. Link pins off the cylinder spacing
    leave a primary residual, forward and backward."""
    w = 2200 * np.pi / 30
    c = 1.9 * 0.057 * w**2
    plain = unbalance(_radial(False), omega=w, orders=(1, 2))
    assert float(plain["force"].sel(order=2)) < 1e-12 * c
    e = _radial(True)
    cw = counterweights(e, balance_factor=0.5)
    ds = unbalance(e, omega=w, orders=(1, 2, 3), counterweights=cw)
    assert float(ds["force"].sel(order=1)) < 1e-12 * c
    secondary = float(ds["force"].sel(order=2)) / (5 * c / 2)
    assert 0.05 < secondary < 0.3            # 14 % of the primary for this geometry
    skew = _radial(True, link_offset_deg=3.0)
    ds = unbalance(skew, omega=w, orders=(1,), counterweights=counterweights(
        skew, balance_factor=0.5))
    residual = float(ds["force"][0]) / (5 * c / 2)
    assert 1e-4 < residual < 0.05
    assert float(ds["force_backward"][0]) > 1e-6 * c
