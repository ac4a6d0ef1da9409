"""Rotor finite elements against closed forms, convergence rates and a second method."""

import numpy as np
import pytest

from crankbench.predict.errors import ModelError
from crankbench.predict.lateral.fe import Bearing, Disk, Material, Rotor, ShaftSection

STEEL = Material(2.1e11, 7850.0, poisson_ratio=0.3)
RIGID = np.inf


def pinned_shaft(n_elements, *, theory="euler-bernoulli", rotary_inertia=False, length=1.0,
                 diameter=0.05):
    return Rotor(shaft=[ShaftSection(length=length, outer_diameter=diameter, material=STEEL,
                                     n_elements=n_elements)],
                 bearings=[Bearing(0.0, RIGID), Bearing(length, RIGID)], theory=theory,
                 rotary_inertia=rotary_inertia)


def euler_bernoulli_pinned(n, length=1.0, diameter=0.05):
    area, inertia = np.pi * diameter**2 / 4, np.pi * diameter**4 / 64
    return (n * np.pi / length) ** 2 * np.sqrt(STEEL.youngs_modulus * inertia
                                               / (STEEL.density * area))


def timoshenko_pinned(n, length, diameter):
    """Exact pinned-pinned Timoshenko frequency: lower root of
    (κGAk² − ρAω²)(EIk² + κGA − ρIω²) − (κGAk)² = 0, k = nπ/L (Timoshenko, Young & Weaver,
    Vibration Problems in Engineering, §5.12)."""
    area, inertia = np.pi * diameter**2 / 4, np.pi * diameter**4 / 64
    nu = STEEL.poisson_ratio
    kga = 6 * (1 + nu) / (7 + 6 * nu) * STEEL.shear_modulus * area
    ei, rho = STEEL.youngs_modulus * inertia, STEEL.density
    k = n * np.pi / length
    # a ω⁴ + b ω² + c = 0
    a = rho * area * rho * inertia
    b = -(rho * area * (ei * k**2 + kga) + rho * inertia * kga * k**2)
    c = kga * k**2 * (ei * k**2 + kga) - (kga * k) ** 2
    return np.sqrt((-b - np.sqrt(b**2 - 4 * a * c)) / (2 * a))


def test_euler_bernoulli_pinned_shaft_matches_closed_form():
    modes = pinned_shaft(40).natural_frequencies(n_modes=6)
    expected = np.repeat([euler_bernoulli_pinned(n) for n in (1, 2, 3)], 2)
    np.testing.assert_allclose(modes.omega, expected, rtol=3e-6)  # h⁴ error of mode 3: 2e-6
    assert abs(modes.omega[0] / expected[0] - 1) < 5e-8
    assert modes.whirl == ("backward", "forward") * 3  # repeated pairs made circular
    assert modes.n_elements == 40


def test_fe_convergence_rate_is_fourth_order():
    """Error of the cubic Hermite element falls as h⁴: log2(e_h / e_h/2) ≈ 4."""
    exact = euler_bernoulli_pinned(2)
    errors = []
    for n in (4, 8, 16):
        w = pinned_shaft(n).natural_frequencies(n_modes=4, error_estimate=False).omega[2]
        errors.append(abs(w - exact) / exact)
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((rates > 3.8) & (rates < 4.2)), rates


def test_richardson_error_estimate_tracks_the_true_error():
    modes = pinned_shaft(6).natural_frequencies(n_modes=4)
    exact = np.repeat([euler_bernoulli_pinned(n) for n in (1, 2)], 2)
    true = np.abs(modes.omega - exact)
    ratio = modes.error_estimate / true
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio


@pytest.mark.parametrize("slenderness", [20.0, 5.0, 2.5])
def test_timoshenko_converges_to_exact_thick_beam(slenderness):
    """Timoshenko elements → exact Timoshenko pinned-pinned frequency at rate h² (constant
    shear strain per element); Richardson extrapolation with p = 2 recovers it to 1e-6.
    Euler-Bernoulli overestimates more and more as the beam gets thicker."""
    d = 0.1
    L = slenderness * d
    exact = np.array([timoshenko_pinned(n, L, d) for n in (1, 2)])
    w = {}
    for n in (16, 32, 64):
        rotor = pinned_shaft(n, theory="timoshenko", rotary_inertia=True, length=L, diameter=d)
        w[n] = rotor.natural_frequencies(n_modes=4, error_estimate=False).omega[::2]
    rate = np.log2(np.abs(w[16] - exact) / np.abs(w[32] - exact))
    assert np.all((rate > 1.9) & (rate < 2.6)), rate
    assert np.all(np.abs(w[64] / exact - 1) < 1e-3)
    extrapolated = w[64] + (w[64] - w[32]) / 3
    np.testing.assert_allclose(extrapolated, exact, rtol=1e-6)
    eb = np.array([euler_bernoulli_pinned(n, L, d) for n in (1, 2)])
    over = eb / exact - 1
    assert np.all(over > 0)
    if slenderness <= 5:
        assert over[0] > 0.02  # the thick beam needs Timoshenko


def test_cantilever_with_clamp():
    L, d = 0.8, 0.04
    rotor = Rotor(shaft=[ShaftSection(length=L, outer_diameter=d, material=STEEL,
                                      n_elements=30)],
                  bearings=[Bearing(0.0, RIGID, clamp=True)], theory="euler-bernoulli",
                  rotary_inertia=False)
    area, inertia = np.pi * d**2 / 4, np.pi * d**4 / 64
    exact = 1.87510407**2 / L**2 * np.sqrt(STEEL.youngs_modulus * inertia / (STEEL.density * area))
    assert rotor.natural_frequencies(n_modes=1).omega[0] == pytest.approx(exact, rel=1e-7)


def _overhung(ip, id_, speed_free=False):
    """Massless cantilever (one element) with a disk at its tip."""
    light = Material(2.1e11, 1e-9, poisson_ratio=0.3)
    return Rotor(shaft=[ShaftSection(length=0.5, outer_diameter=0.04, material=light,
                                     n_elements=1)],
                 disks=[Disk(0.5, mass=10.0, diametral_inertia=id_, polar_inertia=ip)],
                 bearings=[Bearing(0.0, RIGID, clamp=True)], theory="euler-bernoulli",
                 rotary_inertia=False)


def _tip_stiffness():
    L, ei = 0.5, 2.1e11 * np.pi * 0.04**4 / 64
    return ei / L**3 * np.array([[12, -6 * L], [-6 * L, 4 * L**2]])


def test_gyroscopic_overhung_disk_synchronous_criticals():
    """Forward synchronous whirl sees the tilt inertia I_d − I_p, backward I_d + I_p:
    det(K − Ω² diag(m, I_d ∓ I_p)) = 0 (Friswell et al. 2010, §3.6 / §5.9)."""
    m, id_, ip = 10.0, 0.02, 0.03  # I_p > I_d: no forward tilt critical
    K = _tip_stiffness()
    crit = _overhung(ip, id_).critical_speeds(orders=[1.0], n_modes=4)
    frame = crit.to_frame()
    fwd = frame[frame.whirl == "forward"].omega.to_numpy()
    bwd = frame[frame.whirl == "backward"].omega.to_numpy()
    # forward: K − Ω² diag(m, Id − Ip) with Id − Ip < 0 → exactly one positive Ω²
    lam = np.linalg.eigvals(np.linalg.solve(np.diag([m, id_ - ip]), K))
    expected_fwd = np.sqrt(np.sort(lam[lam > 0].real))
    lam = np.linalg.eigvals(np.linalg.solve(np.diag([m, id_ + ip]), K))
    expected_bwd = np.sqrt(np.sort(lam.real))
    np.testing.assert_allclose(fwd, expected_fwd, rtol=1e-8)
    np.testing.assert_allclose(bwd, expected_bwd, rtol=1e-8)


def test_gyroscopic_natural_frequencies_at_speed():
    """At spin Ω, circular whirl at ω: det([[k11 − mω², k12], [k12, k22 − I_d ω² ± I_p Ω ω]])
    = 0, + forward (stiffening), − backward; solved here as polynomials."""
    m, id_, ip, spin = 10.0, 0.05, 0.08, 800.0
    (k11, k12), (_, k22) = _tip_stiffness()
    expected = {}
    for whirl, sign in (("forward", 1.0), ("backward", -1.0)):
        # (k11 − mω²)(k22 − Id ω² + s Ip Ω ω) − k12² = 0 → quartic in ω
        p1 = np.poly1d([-m, 0.0, k11])
        p2 = np.poly1d([-id_, sign * ip * spin, k22])
        roots = (p1 * p2 - k12**2).roots
        expected[whirl] = np.sort(roots[(np.abs(roots.imag) < 1e-6) & (roots.real > 0)].real)
    modes = _overhung(ip, id_).natural_frequencies(spin_omega=spin, n_modes=4, error_estimate=False)
    for whirl in ("forward", "backward"):
        got = modes.omega[np.array(modes.whirl) == whirl]
        np.testing.assert_allclose(got, expected[whirl][:got.size], rtol=1e-8)
    assert set(modes.whirl) == {"forward", "backward"}


def _jeffcott(k=2.0e6, c=400.0, m=25.0):
    light = Material(2.1e11, 1e-9, poisson_ratio=0.3)
    return Rotor(shaft=[ShaftSection(length=0.6, outer_diameter=0.05, material=light,
                                     n_elements=2)],
                 disks=[Disk(0.3, mass=m, diametral_inertia=0.2, polar_inertia=0.3)],
                 bearings=[Bearing(0.0, k / 2, cxx=c / 2), Bearing(0.6, k / 2, cxx=c / 2)],
                 theory="euler-bernoulli", rotary_inertia=False)


def test_unbalance_response_matches_jeffcott_rotor():
    """Central disk on a massless shaft in damped bearings (Jeffcott rotor): the disk sees the
    bearing (k + icΩ) in series with the shaft 48EI/L³, X = m_u e Ω² / (K_eff − mΩ²),
    Y = −i X (forward circle) — Friswell et al. (2010) §3.4."""
    k, c, m, me = 2.0e6, 400.0, 25.0, 2e-4
    speeds = np.linspace(50.0, 600.0, 12)
    res = _jeffcott(k, c, m).unbalance_response(speeds, [(0.3, me, 0.0)])
    ks = 48 * 2.1e11 * np.pi * 0.05**4 / 64 / 0.6**3
    kb = k + 1j * c * speeds
    expected = me * speeds**2 / (kb * ks / (kb + ks) - m * speeds**2)
    np.testing.assert_allclose(res.response[:, 0, 0], expected, rtol=1e-9)
    np.testing.assert_allclose(res.response[:, 0, 1], -1j * expected, rtol=1e-9)
    np.testing.assert_allclose(res.major_axis[:, 0], np.abs(expected), rtol=1e-9)
    frame = res.to_frame()
    assert {"speed_rpm", "amplitude_x", "phase_x_deg", "major_axis"} <= set(frame.columns)
    assert len(res.plot().axes) == 2


def test_critical_speeds_agree_with_campbell_eigenvalues():
    """Second method: at each exact critical speed Ω_c the state-space eigen-solve at Ω_c has
    a natural frequency k·Ω_c with the same whirl."""
    rotor = Rotor(shaft=[ShaftSection(length=0.4, outer_diameter=0.06, material=STEEL),
                         ShaftSection(length=0.2, outer_diameter=0.045, material=STEEL)],
                  disks=[Disk(0.6, mass=25.0, diametral_inertia=0.35, polar_inertia=0.68)],
                  bearings=[Bearing(0.0, 5e7), Bearing(0.4, 5e7)])
    crit = rotor.critical_speeds(orders=[1.0, 2.0], n_modes=2)
    for om, k, whirl in zip(crit.omega, crit.order, crit.whirl):
        modes = rotor.natural_frequencies(spin_omega=om, n_modes=8, error_estimate=False)
        i = np.argmin(np.abs(modes.omega - k * om))
        assert modes.omega[i] == pytest.approx(k * om, rel=1e-9)
        assert modes.whirl[i] == whirl
    campbell = rotor.campbell(np.linspace(0, 3000, 7), n_modes=4, orders=(1.0, 2.0))
    assert campbell.omega.shape == (7, 4)
    assert campbell.plot().axes and len(campbell.to_frame()) == 28


def test_cross_coupled_bearings_use_the_general_pencil():
    rotor = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05, material=STEEL)],
                  disks=[Disk(0.5, mass=20.0, diametral_inertia=0.1, polar_inertia=0.2)],
                  bearings=[Bearing(0.0, 1e7, 8e6, kxy=2e5, kyx=-2e5),
                            Bearing(1.0, 1e7, 8e6, kxy=2e5, kyx=-2e5)])
    crit = rotor.critical_speeds(n_modes=2)
    for om in crit.omega:
        modes = rotor.natural_frequencies(spin_omega=om, n_modes=6, error_estimate=False)
        assert np.min(np.abs(modes.omega - om)) / om < 1e-7


def test_section_split_does_not_change_frequencies():
    """Property: one section or two identical sections meeting at a node give the same
    eigenvalues (assembly is invariant to how the shaft is cut)."""
    one = Rotor(shaft=[ShaftSection(1.0, 0.05, material=STEEL, n_elements=10)],
                bearings=[Bearing(0.0, 1e7), Bearing(1.0, 1e7)])
    two = Rotor(shaft=[ShaftSection(0.4, 0.05, material=STEEL, n_elements=4),
                       ShaftSection(0.6, 0.05, material=STEEL, n_elements=6)],
                bearings=[Bearing(0.0, 1e7), Bearing(1.0, 1e7)])
    np.testing.assert_allclose(one.natural_frequencies(200.0, n_modes=6).omega,
                               two.natural_frequencies(200.0, n_modes=6).omega, rtol=1e-12)


def test_model_errors_name_the_item():
    with pytest.raises(ModelError, match=r"disks\[0\].position=2.0 m lies beyond the shaft end"):
        Rotor(shaft=[ShaftSection(1.0, 0.05)], disks=[Disk(2.0, 1.0)])
    with pytest.raises(ModelError, match=r"^inner_diameter=0.06 must be < outer_diameter=0.05$"):
        ShaftSection(1.0, 0.05, inner_diameter=0.06)
    with pytest.raises(ModelError, match=r"theory='timoshenk' is not one of .*did you mean"):
        Rotor(shaft=[ShaftSection(1.0, 0.05)], theory="timoshenk")
    with pytest.raises(ModelError, match="rotor is not supported"):
        Rotor(shaft=[ShaftSection(1.0, 0.05)]).critical_speeds()
    with pytest.raises(ModelError, match=r"probes position 0.123 m is not a node"):
        _jeffcott().unbalance_response([10.0], [(0.3, 1e-4, 0.0)], probes=[0.123])
    with pytest.raises(ModelError, match="rigid bearing direction cannot carry cross-coupling"):
        Bearing(0.0, RIGID, kxy=1.0)


def test_result_frames_and_plots():
    rotor = Rotor(shaft=[ShaftSection(1.0, 0.05, material=STEEL)],
                  disks=[Disk(0.5, 20.0, 0.1, 0.2)], bearings=[Bearing(0.0, 1e7), Bearing(1.0,
                                                                                          1e7)])
    modes = rotor.natural_frequencies(400.0, n_modes=4)
    frame = modes.to_frame()
    assert list(frame.columns[:5]) == ["mode", "frequency_hz", "frequency_rpm", "damping_ratio",
                                       "whirl"]
    assert modes.plot().axes
    crit = rotor.critical_speeds(n_modes=2)
    assert list(crit.to_frame().columns) == ["mode", "order", "whirl", "speed_rpm", "omega",
                                             "frequency_hz"]
    assert crit.plot().axes
