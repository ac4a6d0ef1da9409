"""Hard cases for the torsional eigen-solvers (numerical stability), each against an independent
reference: mpmath at 50-60 digits, a Sturm-sequence (Holzer) certificate written here, or a
system referred by hand.

Already covered elsewhere (not repeated here):

* free 2000-mass uniform chain against the closed form, free 20-mass chain with stiffness
  ratio 1e12 / inertia ratio 1e8 against mpmath, exactly repeated frequencies of three identical
  branches, the rigid-body mode exactly 0 and constant —
  ``tests/predict/test_torsion_eigen.py``;
* geared chains referred by ratio² (ratio 1/3.5 and 0.5) — ``tests/literature/test_torsion.py
  ::test_geared_shafts`` and ``tests/predict/test_torsion_model.py``.

This file adds the grounded chain and the tree at the extreme ratios (with mode shapes), a
2000-mass chain with ratios 1e6 certified by Sturm counts, nearly repeated frequencies, a free
tree's rigid-body mode, and a geared *branch* at ratio 10.
"""

import mpmath
import numpy as np
import pytest

from crankbench.predict.torsion import ShaftLine, TorsionalSystem, chain


def mp_frequencies(inertias, edges, stiffnesses, dps=60):
    """ω (rad/s), ascending, of K x = ω² J x by mpmath's symmetric eigensolver at ``dps``."""
    with mpmath.workdps(dps):
        n = len(inertias)
        h = mpmath.zeros(n, n)
        r = [1 / mpmath.sqrt(mpmath.mpf(float(j))) for j in inertias]
        for (a, b), k in zip(edges, stiffnesses):
            k = mpmath.mpf(float(k))
            h[b, b] += k * r[b] * r[b]
            if a >= 0:
                h[a, a] += k * r[a] * r[a]
                h[a, b] -= k * r[a] * r[b]
                h[b, a] -= k * r[a] * r[b]
        ev = mpmath.eigsy(h, eigvals_only=True)
        return [mpmath.sqrt(max(e, 0)) for e in sorted(ev)]


def rel_errors(omega, reference):
    """Relative errors of the elastic frequencies (reference > 1e-20), as floats."""
    return np.array([abs(float((mpmath.mpf(float(w)) - r) / r))
                     for w, r in zip(omega, reference) if r > mpmath.mpf(10) ** -20])


def sturm_count(inertias, stiffnesses, sigma, grounded):
    """Number of eigenvalues ω² < σ of a chain, for each σ (vector), without cancellation.

    LDLᵀ of K − σJ for a chain, written as the Holzer-type recursion on the dynamic stiffness
    seen from the left: q₁ = k₀ − σJ₁ (k₀ = 0 if free), q_i = k_{i−1} q_{i−1} / (q_{i−1} +
    k_{i−1}) − σJ_i; the pivots are p_i = q_i + k_i (k_n = 0). By Sylvester's law of inertia
    the number of negative pivots equals the number of eigenvalues below σ. The series-spring
    form has no cancellation between large stiffnesses, so it stays relatively accurate at
    any stiffness/inertia ratio.
    """
    j = np.asarray(inertias, float)
    k = np.asarray(stiffnesses, float)
    if grounded:
        k0, k = k[0], k[1:]
    else:
        k0 = 0.0
    sigma = np.asarray(sigma, float)
    count = np.zeros(sigma.shape, int)
    q = k0 - sigma * j[0]
    for i in range(1, j.size):
        p = q + k[i - 1]
        count += p < 0
        q = k[i - 1] * q / p - sigma * j[i]
    count += q < 0
    return count


def test_sturm_count_reproduces_the_uniform_chain_closed_form():
    """Check of the certificate itself against ω_k = 2√(k/J) sin(kπ/2n)."""
    n = 30
    w = 2 * np.sqrt(5.0) * np.sin(np.arange(n) * np.pi / (2 * n))
    lo = sturm_count(np.ones(n), np.full(n - 1, 5.0), (w * (1 - 1e-9)) ** 2, False)
    hi = sturm_count(np.ones(n), np.full(n - 1, 5.0), (w * (1 + 1e-9)) ** 2 + 1e-300, False)
    assert lo[1:].tolist() == list(range(1, n)) and hi.tolist() == list(range(1, n + 1))


def _extreme_chain(n, seed, grounded):
    rng = np.random.default_rng(seed)
    j = 10 ** rng.uniform(0, 8, n)
    j[[0, 1]] = [1.0, 1e8]
    k = 10 ** rng.uniform(0, 12, n - (0 if grounded else 1))
    k[[0, 1]] = [1.0, 1e12]
    return j, k


def test_grounded_chain_stiffness_1e12_inertia_1e8_against_mpmath():
    """Grounded 20-mass chain, stiffness ratio 1e12 and inertia ratio 1e8: every ω within the
    stated relative bound (and ≤ 1e-12) of mpmath at 60 digits."""
    j, k = _extreme_chain(20, 5, grounded=True)
    s = chain(j, k)
    modes = s.mode_shapes()
    got = s.natural_frequencies("rad/s")
    err = rel_errors(got, mp_frequencies(j, s.edges, k)).max()
    assert err <= 1e-12
    assert err <= max(modes.relative_error_bound, 4 * np.finfo(float).eps)
    assert got[0] > 0


def mp_mode_errors(system, dps=60):
    """J-norm distance of each computed mass-normalised mode shape from mpmath's (sign-matched)."""
    j, k = system.inertias, system.stiffnesses
    with mpmath.workdps(dps):
        n = j.size
        h = mpmath.zeros(n, n)
        r = [1 / mpmath.sqrt(mpmath.mpf(float(v))) for v in j]
        for (a, b), kv in zip(system.edges, k):
            kv = mpmath.mpf(float(kv))
            h[b, b] += kv * r[b] * r[b]
            if a >= 0:
                h[a, a] += kv * r[a] * r[a]
                h[a, b] -= kv * r[a] * r[b]
                h[b, a] -= kv * r[a] * r[b]
        ev, q = mpmath.eigsy(h)
        order = sorted(range(n), key=lambda i: ev[i])
        ref = np.array([[float(q[i, c] * r[i]) for c in order] for i in range(n)])
    x = system.mode_shapes().shapes
    sign = np.sign(np.sum(ref * j[:, None] * x, axis=0))
    return np.sqrt(np.sum((x * sign - ref) ** 2 * j[:, None], axis=0))


def test_extreme_chain_mode_shapes_are_not_garbage():
    """Mode shapes of the free chain at ratios 1e12 / 1e8 against mpmath eigenvectors: every
    mode within 1e-4 in the J-norm (the solver states normwise accuracy n·eps·‖A‖/gap)."""
    j, k = _extreme_chain(20, 3, grounded=False)
    err = mp_mode_errors(chain(j, k))
    assert err[0] == 0.0            # rigid-body mode set exactly
    assert err.max() <= 1e-4


def test_extreme_chain_mode_shapes_relatively_accurate():
    """Mode shapes as accurate as the frequencies: every mode within 1e-9 of mpmath's."""
    j, k = _extreme_chain(20, 3, grounded=False)
    s = chain(j, k)
    x = s.mode_shapes().shapes
    np.testing.assert_allclose(x.T @ s.inertia_matrix() @ x, np.eye(j.size), atol=1e-9)
    assert mp_mode_errors(s).max() <= 1e-9


def test_tree_stiffness_1e12_inertia_1e8_against_mpmath():
    """A hub with three branches (10 masses), stiffness ratio 1e12 and inertia ratio 1e8."""
    rng = np.random.default_rng(17)
    edges = [(0, 1), (1, 2), (2, 3), (0, 4), (4, 5), (0, 6), (6, 7), (7, 8), (8, 9)]
    j = 10 ** rng.uniform(0, 8, 10)
    j[[0, 5]] = [1e8, 1.0]
    k = 10 ** rng.uniform(0, 12, len(edges))
    k[[0, 4]] = [1.0, 1e12]
    s = TorsionalSystem(j, edges, k)
    got = s.natural_frequencies("rad/s")
    assert got[0] == 0.0                      # free tree: rigid-body mode exactly zero
    assert rel_errors(got, mp_frequencies(j, edges, k)).max() <= 1e-12


@pytest.mark.parametrize("grounded", [False, True])
def test_2000_mass_chain_with_ratios_1e6_certified_by_sturm_counts(grounded):
    """2000 random masses (inertia ratio 1e6, stiffness ratio 1e6): the i-th computed ω² has
    exactly i eigenvalues below ω²(1 − 1e-10) and i+1 below ω²(1 + 1e-10)."""
    rng = np.random.default_rng(2000)
    n = 2000
    j = 10 ** rng.uniform(0, 6, n)
    k = 10 ** rng.uniform(2, 8, n - (0 if grounded else 1))
    w = chain(j, k).natural_frequencies("rad/s")
    assert w.size == n and np.all(np.diff(w) > 0)
    first = 0 if grounded else 1
    if not grounded:
        assert w[0] == 0.0
    w2 = w[first:] ** 2
    below = sturm_count(j, k, w2 * (1 - 1e-10), grounded)
    upto = sturm_count(j, k, w2 * (1 + 1e-10), grounded)
    idx = np.arange(first, n)
    assert np.array_equal(below, idx)
    assert np.array_equal(upto, idx + 1)


def test_nearly_repeated_frequencies_are_resolved():
    """Three branches on a hub, the stiffnesses differing by 1e-8 relative: the near pair
    (split ≈ 5e-9 relative) is resolved — each ω within 1e-13 and the splitting within 1e-4 of
    mpmath — and the two mode shapes stay J-orthogonal."""
    jb, kb = 2.5, 4.0e5
    ks = [kb, kb * (1 + 1e-8), kb * (1 + 2e-8), 1e6]
    edges = [(0, 1), (0, 2), (0, 3), (-1, 0)]
    j = [10.0, jb, jb, jb]
    s = TorsionalSystem(j, edges, ks)
    got = s.natural_frequencies("rad/s")
    ref = mp_frequencies(j, edges, ks, dps=50)
    assert rel_errors(got, ref).max() <= 1e-13
    # the two modes with the hub (almost) still lie near √(kb/jb)
    near = np.flatnonzero(np.isclose(got, np.sqrt(kb / jb), rtol=1e-7))
    assert near.size == 2
    split, split_ref = got[near[1]] - got[near[0]], float(ref[near[1]] - ref[near[0]])
    assert split_ref > 0 and abs(split / split_ref - 1) <= 1e-4
    x = s.mode_shapes().shapes[:, near]
    np.testing.assert_allclose(x.T @ s.inertia_matrix() @ x, np.eye(2), atol=1e-7)


def test_free_tree_rigid_body_mode_exactly_zero_with_constant_shape():
    s = TorsionalSystem([1e-3, 50.0, 2.0, 7e4], [(0, 1), (1, 2), (1, 3)], [1e10, 3.0, 5e5])
    m = s.mode_shapes()
    assert m.frequencies_hz[0] == 0.0 and m.mode_numbers[0] == 0
    assert np.all(m.frequencies_hz[1:] > 0)
    # constant, mass-normalised (sign free); the tree path (dense eigh) leaves ~1e-11 spread
    shape = m.shapes[:, 0] * np.sign(m.shapes[0, 0])
    np.testing.assert_allclose(shape, 1 / np.sqrt(sum(s.inertias)), rtol=1e-10)


# ------------------------------------------------------------------ geared branch, ratio 10
def _geared_branch(mesh_stiffness=None):
    """Engine — hub — flywheel line, with a pump branch off the hub through a 10:1 step-up."""
    line = ShaftLine("geared branch")
    line.add_mass("engine", 4.0)
    line.add_mass("hub", 0.5)
    line.add_mass("flywheel", 12.0)
    line.add_mass("pinion", 0.002, ratio=10.0)
    line.add_mass("pump", 0.01, ratio=10.0)
    line.add_shaft("engine", "hub", stiffness=2.0e6)
    line.add_shaft("hub", "flywheel", stiffness=8.0e5)
    line.add_gear("hub", "pinion", ratio=10.0, mesh_stiffness=mesh_stiffness)
    line.add_shaft("pinion", "pump", stiffness=3.0e3)
    return line.build()


def test_geared_branch_ratio_10_equals_branch_referred_by_hand():
    """Rigid 10:1 mesh: pinion inertia joins the hub as 100·J, the pump branch becomes
    (100·J_pump, 100·k) — [AM2] §23 p. 100 (refer by the speed ratio squared). The built
    system's frequencies equal those of the hand-referred tree and mpmath's."""
    s = _geared_branch()
    j = [4.0, 0.5 + 100 * 0.002, 12.0, 100 * 0.01]
    edges = [(0, 1), (1, 2), (1, 3)]
    k = [2.0e6, 8.0e5, 100 * 3.0e3]
    hand = TorsionalSystem(j, edges, k)
    np.testing.assert_allclose(s.inertias, j, rtol=1e-15)
    np.testing.assert_allclose(s.stiffnesses, k, rtol=1e-15)
    got = s.natural_frequencies("rad/s")
    np.testing.assert_allclose(got, hand.natural_frequencies("rad/s"), rtol=1e-14)
    assert rel_errors(got, mp_frequencies(j, edges, k)).max() <= 1e-13


def test_geared_branch_ratio_10_flexible_mesh_against_physical_coordinates():
    """Flexible mesh (k_mesh at the pinion speed): the referred model's frequencies equal those
    of the physical model with the gear constraint θ_wheel-side = θ_hub, θ_pinion = 10 θ at the
    mesh, solved in physical coordinates with mpmath (K_phys, J_phys, no referral)."""
    km = 5.0e4
    s = _geared_branch(mesh_stiffness=km)
    # physical coordinates: engine, hub, flywheel, pinion, pump (pinion and pump at 10× speed);
    # mesh spring twists by θ_pinion − 10 θ_hub; energy ½ km (θp − 10 θh)²
    with mpmath.workdps(50):
        jp = [mpmath.mpf(v) for v in (4.0, 0.5, 12.0, 0.002, 0.01)]
        kmat = mpmath.zeros(5, 5)

        def spring(a, b, k, ga=1, gb=1):
            k = mpmath.mpf(k)
            kmat[a, a] += k * ga * ga
            kmat[b, b] += k * gb * gb
            kmat[a, b] -= k * ga * gb
            kmat[b, a] -= k * ga * gb

        spring(0, 1, 2.0e6)
        spring(1, 2, 8.0e5)
        spring(1, 3, km, ga=10)
        spring(3, 4, 3.0e3)
        h = mpmath.zeros(5, 5)
        for a in range(5):
            for b in range(5):
                h[a, b] = kmat[a, b] / mpmath.sqrt(jp[a] * jp[b])
        ref = [mpmath.sqrt(max(e, 0)) for e in sorted(mpmath.eigsy(h, eigvals_only=True))]
    got = s.natural_frequencies("rad/s")
    assert got[0] == 0.0
    assert rel_errors(got, ref).max() <= 1e-13


def test_geared_branch_ratio_10_forced_torque_in_the_fast_shaft():
    """Forced response at the engine node: the real torque in the pump shaft (at 10× speed)
    is the referred torque / 10; reference = a hand solve (K − Ω² J) x = T of the referred
    model."""
    s = _geared_branch().replace(cylinder_nodes=[0], firing_angles_deg=[0.0])
    r = s.forced_response([600.0], torque=[100.0], orders=[1.0])
    om = 600.0 * 2 * np.pi / 60
    x = np.linalg.solve(s.stiffness_matrix() - om ** 2 * s.inertia_matrix(),
                        [100.0, 0.0, 0.0, 0.0])
    pump_shaft = s.edge_names.index("pinion-pump")
    want = abs(100 * 3.0e3 * (x[3] - x[1])) / 10.0
    assert abs(r.torque[0, 0, pump_shaft]) == pytest.approx(want, rel=1e-10)


# ----------------------------------------- every mode at N = 1000, the lowest-k subset solve
def sturm_count_extended(inertias, stiffnesses, sigma, grounded):
    """:func:`sturm_count` in 80-bit extended precision (numpy ``longdouble``, eps ≈ 1e-19;
    the bench's reference, :mod:`analysis.bench._sturm`): the recursion's own rounding stays
    far below a 1e-13 certificate at 20 000 masses."""
    from crankbench.analysis.bench._sturm import EXTENDED, sturm_count as extended

    assert EXTENDED, "needs 80-bit or wider long double"
    return extended(inertias, stiffnesses, sigma, grounded=grounded)


def certified_within(omega, inertias, stiffnesses, grounded, rel, first_index=0):
    """True where the extended-precision Sturm counts put exactly ``first_index + i``
    eigenvalues below ω_i²(1 − rel)² and one more below ω_i²(1 + rel)²: each ω_i is within
    ``rel`` of the true i-th frequency."""
    w = np.asarray(omega, np.longdouble)
    lo = sturm_count_extended(inertias, stiffnesses, (w * (1 - rel)) ** 2, grounded)
    hi = sturm_count_extended(inertias, stiffnesses, (w * (1 + rel)) ** 2, grounded)
    idx = first_index + np.arange(w.size)
    return (lo == idx) & (hi == idx + 1)


def test_extended_sturm_count_against_mpmath_on_a_hard_chain():
    """The certificate checked against mpmath's 50-digit eigenvalues of a 24-mass chain at
    ratios 1e12 / 1e8: the counts bracket every reference value at ±1e-15."""
    j, k = _extreme_chain(24, 11, grounded=True)
    ref = np.array([float(r) for r in mp_frequencies(j, [(i - 1, i) for i in range(24)], k,
                                                     dps=50)])
    assert certified_within(ref, j, k, True, 1e-15).all()
    assert not certified_within(ref * (1 + 1e-12), j, k, True, 1e-15).any()


@pytest.mark.parametrize("grounded", [False, True])
@pytest.mark.parametrize("ratios", [(1e9, 1e6), (1e12, 1e8)])
def test_every_mode_of_a_hard_1000_mass_chain_within_1e13(grounded, ratios):
    """All modes of a 1000-mass chain at stiffness/inertia ratios 1e9/1e6 and 1e12/1e8 within
    1e-13 relative (the fast public call, dqds on the squared factor), certified mode by mode
    by extended-precision Sturm counts."""
    k_ratio, j_ratio = ratios
    rng = np.random.default_rng(1000)
    n = 1000
    j = 10 ** rng.uniform(0, np.log10(j_ratio), n)
    k = 10 ** rng.uniform(0, np.log10(k_ratio), n - (0 if grounded else 1))
    w = chain(j, k).natural_frequencies("rad/s")
    first = 0 if grounded else 1
    if not grounded:
        assert w[0] == 0.0
    ok = certified_within(w[first:], j, k, grounded, 1e-13, first_index=first)
    assert ok.all(), f"modes {np.flatnonzero(~ok)[:5] + first} not within 1e-13"


@pytest.mark.parametrize("grounded", [False, True])
def test_lowest_modes_of_a_20000_mass_chain_by_subset_solve(grounded):
    """natural_frequencies(n_modes=8) of a 20 000-mass chain (ratios 1e9 / 1e6) takes the
    bisection path, never the O(n²) full solve, and each value is certified within 1e-13."""
    rng = np.random.default_rng(20000)
    n = 20000
    j = 10 ** rng.uniform(0, 6, n)
    k = 10 ** rng.uniform(0, 9, n - (0 if grounded else 1))
    s = chain(j, k)
    w = s.natural_frequencies("rad/s", n_modes=8)
    assert w.size == 8 and "_values" not in s.__dict__        # the full solve never ran
    first = 0 if grounded else 1
    assert certified_within(w[first:], j, k, grounded, 1e-13, first_index=first).all()
    m = s.mode_shapes(n_modes=8)
    assert "bisection" in m.method and m.shapes.shape == (n, 8)
    np.testing.assert_array_equal(m.frequencies_hz, w / (2 * np.pi))
    np.testing.assert_allclose(m.shapes.T @ (j[:, None] * m.shapes), np.eye(8), atol=1e-9)


@pytest.mark.parametrize("grounded", [False, True])
def test_subset_shapes_match_relatively_accurate_svd_vectors(grounded):
    """Inverse-iteration shapes (the path of every chain above 400 masses) against LAPACK
    dbdsqr's singular vectors of the same factor (relatively accurate, O(n³), the path below
    400 masses) at 600 masses and ratios 1e12 / 1e8: every one of the 12 lowest, and a few
    high ones, within 1e-11 in the J-norm. MRRR on the scaled tridiagonal (the previous path)
    is off by order 1 here."""
    from crankbench.predict.torsion import eigen
    from crankbench.predict.torsion.subset import chain_shapes

    j, k = _extreme_chain(600, 8, grounded)
    w = chain(j, k).natural_frequencies("rad/s")
    y = eigen._chain_singular_vectors(1 / np.sqrt(j), np.sqrt(k), grounded)
    ref = y / np.sqrt(j)[:, None]
    if not grounded:
        ref[:, 0] = 1 / np.sqrt(j.sum())
    pick = np.r_[0:12, 300, 598, 599]
    x = chain_shapes(j, k, w, grounded=grounded)[:, pick]
    sign = np.sign(np.sum(ref[:, pick] * j[:, None] * x, axis=0))
    dist = np.sqrt(np.sum((x * sign - ref[:, pick]) ** 2 * j[:, None], axis=0))
    assert dist.max() <= 1e-11, dist


def test_lowest_mode_shapes_use_memory_linear_in_length():
    """mode_shapes(n_modes=4) of a 100 000-mass chain: traced peak within the stated
    estimate (about 8·n·(40 + 2k) bytes = 38 MB), where all shapes would need 80 GB."""
    import tracemalloc

    n = 100_000
    s = chain(np.linspace(1.0, 3.0, n), np.full(n - 1, 2e6))
    estimate = s.eigen_memory_bytes(n_modes=4, shapes=True)
    assert estimate < 50e6 and s.eigen_memory_bytes(shapes=True) > 1e11
    tracemalloc.start()
    try:
        m = s.mode_shapes(n_modes=4)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert m.shapes.shape == (n, 4) and m.frequencies_hz[0] == 0.0
    assert peak <= estimate, f"peak {peak / 1e6:.1f} MB > estimate {estimate / 1e6:.1f} MB"


def test_critical_speeds_of_a_long_chain_solve_only_the_modes_below_the_top_speed():
    """critical_speeds on a 1500-mass chain with a speed range: the crossings equal those from
    the full solution, but only the few modes below the top order's frequency were solved."""
    n = 1500
    rng = np.random.default_rng(5)
    j, k = rng.uniform(0.5, 2.0, n), rng.uniform(1e9, 3e9, n - 1)
    fast = chain(j, k).replace(cylinder_nodes=[0, 1, 2], firing_angles_deg=[0, 240, 480])
    table = fast.critical_speeds([1, 2, 3], (0, 3000))
    assert "_eigen" not in fast.__dict__ and len(table) > 3
    full = chain(j, k).replace(cylinder_nodes=[0, 1, 2], firing_angles_deg=[0, 240, 480])
    full.mode_shapes()                                   # force the full path
    ref = full.critical_speeds([1, 2, 3], (0, 3000))
    np.testing.assert_array_equal(table[["mode", "order"]], ref[["mode", "order"]])
    np.testing.assert_allclose(table["speed_rpm"], ref["speed_rpm"], rtol=1e-13)
    np.testing.assert_allclose(table["vector_sum"], ref["vector_sum"], rtol=1e-9, atol=1e-12)
