"""Natural frequencies and modes of torsional systems: closed forms, mpmath references, hard
cases (stiffness ratio 1e9-1e12, inertia ratio 1e6-1e8, 2000 masses, repeated frequencies)."""

import mpmath
import numpy as np
import pytest

from crankbench.predict.errors import ModelError
from crankbench.predict.torsion import TorsionalSystem, chain


def mp_frequencies(inertias, edges, stiffnesses, dps=50):
    """ω (rad/s) of K x = ω² J x by mpmath's symmetric eigensolver at ``dps`` digits."""
    mpmath.mp.dps = dps
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
    return sorted(mpmath.sqrt(max(e, 0)) for e in ev)


def max_rel_error(omega, reference, skip_zero=True):
    errs = [abs(float((mpmath.mpf(float(w)) - r) / r)) for w, r in zip(omega, reference)
            if not (skip_zero and r < mpmath.mpf(10) ** -20)]
    return max(errs)


def test_uniform_free_free_chain_closed_form():
    """ω_k = 2√(k/J) sin(kπ/2n), k = 0..n−1, for n equal masses joined by equal springs."""
    n, j, k = 50, 3.0, 2.0e6
    got = chain(np.full(n, j), np.full(n - 1, k)).natural_frequencies("rad/s")
    want = 2 * np.sqrt(k / j) * np.sin(np.arange(n) * np.pi / (2 * n))
    assert got[0] == 0.0
    np.testing.assert_allclose(got[1:], want[1:], rtol=2e-14)


def test_uniform_fixed_free_chain_closed_form():
    """Grounded at one end: ω_j = 2√(k/J) sin((2j−1)π / (2(2n+1))), j = 1..n."""
    n, j, k = 40, 0.5, 1.0e5
    got = chain(np.full(n, j), np.full(n, k)).natural_frequencies("rad/s")
    want = 2 * np.sqrt(k / j) * np.sin((2 * np.arange(1, n + 1) - 1) * np.pi / (2 * (2 * n + 1)))
    np.testing.assert_allclose(got, want, rtol=2e-14)


def test_2000_masses_closed_form():
    n = 2000
    got = chain(np.ones(n), np.ones(n - 1) * 7.0).natural_frequencies("rad/s")
    want = 2 * np.sqrt(7.0) * np.sin(np.arange(n) * np.pi / (2 * n))
    assert got[0] == 0.0
    np.testing.assert_allclose(got[1:], want[1:], rtol=1e-13)


@pytest.mark.parametrize("grounded", [False, True])
def test_hard_chain_relative_accuracy_against_mpmath(grounded):
    """Stiffness ratio 1e9 and inertia ratio 1e6: every ω to ≤ 1e-12 relative."""
    rng = np.random.default_rng(7)
    n = 24
    j = 10 ** rng.uniform(0, 6, n)
    j[[0, 1]] = [1.0, 1e6]
    k = 10 ** rng.uniform(0, 9, n - (0 if grounded else 1))
    k[[0, 1]] = [1.0, 1e9]
    s = chain(j, k)
    ref = mp_frequencies(j, s.edges, k)
    got = s.natural_frequencies("rad/s")
    assert max_rel_error(got, ref) <= 1e-12
    if not grounded:
        assert got[0] == 0.0


def test_extreme_chain_stays_accurate():
    """Stiffness ratio 1e12, inertia ratio 1e8 (the dense solver loses the small ω)."""
    rng = np.random.default_rng(3)
    n = 20
    j = 10 ** rng.uniform(0, 8, n)
    j[[0, 1]] = [1.0, 1e8]
    k = 10 ** rng.uniform(0, 12, n - 1)
    k[[0, 1]] = [1.0, 1e12]
    s = chain(j, k)
    ref = mp_frequencies(j, s.edges, k, dps=60)
    assert max_rel_error(s.natural_frequencies("rad/s"), ref) <= 1e-12


def test_tree_relative_accuracy_against_mpmath():
    rng = np.random.default_rng(11)
    # hub 0 with three branches of different lengths, stiffness ratio 1e9
    edges = [(0, 1), (1, 2), (2, 3), (0, 4), (4, 5), (0, 6), (6, 7), (7, 8), (8, 9)]
    j = 10 ** rng.uniform(0, 6, 10)
    k = 10 ** rng.uniform(0, 9, len(edges))
    s = TorsionalSystem(j, edges, k)
    assert s.mode_shapes().method == "tree bisection"
    got = s.natural_frequencies("rad/s")
    assert got[0] == 0.0
    assert max_rel_error(got, mp_frequencies(j, edges, k)) <= 1e-12


def test_grounded_tree_with_springs_to_ground_inside():
    edges = [(-1, 2), (0, 1), (1, 2), (2, 3), (1, 4)]
    j = [2.0, 1e-3, 5.0, 1e3, 0.7]
    k = [1e4, 3e8, 2e2, 5e5, 1e3]
    s = TorsionalSystem(j, edges, k)
    got = s.natural_frequencies("rad/s")
    assert got[0] > 0
    assert max_rel_error(got, mp_frequencies(j, edges, k)) <= 1e-12


def test_repeated_frequencies_of_symmetric_branches_are_equal():
    """Three identical branches on a hub: the two modes in which the hub stands still share
    ω = √(k_b/J_b) exactly (symmetry)."""
    jb, kb = 2.5, 4.0e5
    edges = [(0, 1), (0, 2), (0, 3), (-1, 0)]
    s = TorsionalSystem([10.0, jb, jb, jb], edges, [kb, kb, kb, 1e6])
    w = s.natural_frequencies("rad/s")
    hits = np.flatnonzero(np.isclose(w, np.sqrt(kb / jb), rtol=1e-14))
    assert hits.size == 2
    assert w[hits[0]] == w[hits[1]]


def test_rigid_body_mode_is_exactly_zero_and_constant():
    s = chain([1e-3, 4.0, 2e5], [1e9, 3.0])
    m = s.mode_shapes()
    assert m.frequencies_hz[0] == 0.0 and m.mode_numbers[0] == 0
    shape = m.shapes[:, 0]
    np.testing.assert_allclose(shape, shape[0], rtol=1e-15)


@pytest.mark.parametrize("layout", ["chain", "tree", "loop"])
def test_mode_shapes_are_mass_orthonormal_eigenvectors(layout):
    if layout == "chain":
        s = chain([1.0, 2.0, 3.0, 4.0], [1e4, 2e4, 3e4])
    elif layout == "tree":
        s = TorsionalSystem([1.0, 2.0, 3.0, 4.0], [(0, 1), (0, 2), (0, 3)], [1e4, 2e4, 3e4])
    else:
        s = TorsionalSystem([1.0, 2.0, 3.0], [(0, 1), (1, 2), (2, 0)], [1e4, 2e4, 3e4])
    m = s.mode_shapes()
    x = m.shapes
    jm, km = s.inertia_matrix(), s.stiffness_matrix()
    np.testing.assert_allclose(x.T @ jm @ x, np.eye(4 if layout != "loop" else 3), atol=1e-12)
    w2 = (2 * np.pi * m.frequencies_hz) ** 2
    resid = km @ x - jm @ x * w2
    assert np.abs(resid).max() <= 1e-9 * np.abs(km).max()


def test_loop_falls_back_to_dense_eigh():
    import scipy.linalg as sl

    s = TorsionalSystem([1.0, 2.0, 3.0], [(0, 1), (1, 2), (2, 0)], [1e4, 2e4, 3e4])
    assert s.mode_shapes().method == "dense eigh"
    ref = np.sqrt(np.clip(sl.eigh(s.stiffness_matrix(), s.inertia_matrix(),
                                  eigvals_only=True), 0, None))
    np.testing.assert_allclose(s.natural_frequencies("rad/s")[1:], ref[1:], rtol=1e-12)


def test_frequencies_invariant_to_node_order():
    j = np.array([3.0, 1e-2, 40.0, 2.0, 7.0])
    k = np.array([1e3, 5e7, 2.0, 8e4])
    a = chain(j, k).natural_frequencies()
    b = chain(j[::-1], k[::-1]).natural_frequencies()
    np.testing.assert_allclose(a, b, rtol=1e-14)
    # the same chain given as a tree with shuffled edges
    perm = np.array([3, 0, 4, 1, 2])  # new index of old node
    edges = [(perm[i], perm[i + 1]) for i in range(4)][::-1]
    jt = np.empty(5)
    jt[perm] = j
    c = TorsionalSystem(jt, edges, k[::-1]).natural_frequencies()
    np.testing.assert_allclose(a, c, rtol=1e-14)


def test_matrices():
    s = chain([1.0, 2.0], [3.0, 4.0])  # grounded
    np.testing.assert_array_equal(s.stiffness_matrix(), [[7.0, -4.0], [-4.0, 4.0]])
    np.testing.assert_array_equal(s.inertia_matrix(), np.diag([1.0, 2.0]))
    d = s.replace(edge_damping=[0.5, 1.0], node_damping=[0.1, 0.0],
                  edge_loss_factor=[0.0, 0.2])
    np.testing.assert_allclose(d.damping_matrix(), [[1.6, -1.0], [-1.0, 1.0]])
    # hysteretic η k / ω adds 0.2*4/2 = 0.4 across spring 2
    np.testing.assert_allclose(d.damping_matrix(2.0), [[2.0, -1.4], [-1.4, 1.4]])


def test_critical_speeds_and_vector_sums():
    """n_c = 60 f / q; for an in-phase mode on 6 cylinders major orders sum to Σ|a|."""
    s = chain([1.0] * 6 + [1e6], [1e12] * 5 + [1e6])
    s = s.replace(cylinder_nodes=list(range(6)),
                  firing_angles_deg=[0, 480, 240, 600, 120, 360])
    f1 = s.natural_frequencies()[1]
    cs = s.critical_speeds([3.0, 1.5], (0, 1e6))
    row = cs[cs.order == 3.0].iloc[0]
    assert row["mode"] == 1 and row.speed_rpm == pytest.approx(60 * f1 / 3.0, rel=1e-14)
    # cylinders nearly rigid against each other: a_c ≈ 1, major order 3 sums to 6
    assert row.vector_sum == pytest.approx(6.0, rel=1e-5) and bool(row.major)
    minor = cs[cs.order == 1.5].iloc[0]
    assert minor.vector_sum == pytest.approx(0.0, abs=1e-4) and not bool(minor.major)


def test_holzer_table_residual_zero_at_natural_frequencies():
    s = chain([2.0, 1.0, 3.0], [1e4, 2e4])
    for f in s.natural_frequencies():
        t = s.holzer_table(f)
        assert abs(t.attrs["residual_torque"]) <= 1e-8 * (2 * np.pi * max(f, 1)) ** 2 * 6
    g = chain([2.0, 1.0, 3.0], [5e3, 1e4, 2e4])
    for f in g.natural_frequencies():
        assert abs(g.holzer_table(f).attrs["residual_amplitude"]) <= 1e-9
    assert abs(g.holzer_table(1.0).attrs["residual_amplitude"]) > 0.1


def test_validation_messages():
    with pytest.raises(ModelError, match=r"stiffnesses has 5 values; a chain of 3 inertias "
                                         r"needs 2 \(free-free\) or 3 \(first inertia grounded\)"):
        chain([1, 2, 3], [1, 2, 3, 4, 5])
    with pytest.raises(ModelError, match=r"inertias\[1\]=-2.0 must be > 0 \(kg·m²\)"):
        chain([1, -2], [1])
    with pytest.raises(ModelError, match=r"inertias contains 1 NaN/inf value\(s\), first at "
                                         r"index 0"):
        chain([np.nan, 1], [1])
    with pytest.raises(ModelError, match="units='rpm' is not one of 'hz', 'rad/s', 'cpm'"):
        chain([1, 1], [1]).natural_frequencies("rpm")
    with pytest.raises(ModelError, match=r"node_damping must be >= 0, got \[-1.0, 0.0\]"):
        chain([1, 1], [1]).replace(node_damping=[-1.0, 0.0])
    with pytest.raises(ModelError, match="edge_damping contains NaN/inf, first at index 0"):
        chain([1, 1], [1]).replace(edge_damping=[np.nan])
    with pytest.raises(ModelError, match="holzer_table: the system is branched"):
        TorsionalSystem([1, 1, 1, 1], [(0, 1), (0, 2), (0, 3)], [1, 1, 1]).holzer_table(1.0)


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.floats(0.1, 10.0), st.floats(1e3, 1e5)), min_size=2,
                max_size=12),
       st.booleans())
def test_chain_and_tree_solvers_agree_with_dense_eigh(data, grounded):
    """Well-conditioned random chains: bidiagonal dqds, tree bisection (the same chain as a
    tree with its nodes permuted) and dense eigh agree to 1e-11 relative."""
    import scipy.linalg as sl

    j = np.array([d[0] for d in data])
    k = np.array([d[1] for d in data])[: len(data) - (0 if grounded else 1)]
    s = chain(j, k)
    ref = sl.eigh(s.stiffness_matrix(), s.inertia_matrix(), eigvals_only=True)  # ω²
    got = s.natural_frequencies("rad/s")
    scale = np.sqrt(ref.max())
    np.testing.assert_allclose(got ** 2, ref, rtol=1e-11, atol=1e-11 * scale ** 2)
    n = j.size
    perm = np.roll(np.arange(n), 1)  # node i -> perm[i]
    edges = [(perm[a] if a >= 0 else -1, perm[b]) for a, b in s.edges]
    jt = np.empty(n)
    jt[perm] = j
    # a chain given with an extra relabelling goes through the general layout detection
    t = TorsionalSystem(jt, edges[::-1], k[::-1])
    np.testing.assert_allclose(t.natural_frequencies("rad/s"), got, rtol=1e-13, atol=1e-13 * scale)


def test_n_modes_argument_is_checked():
    s = chain([1.0, 2.0, 3.0], [1e4, 2e4])
    for bad, msg in ((0, "n_modes=0 must be >= 1"), (4, "n_modes=4 exceeds the 3 modes"),
                     (2.5, "n_modes=2.5 must be an integer")):
        with pytest.raises(ModelError, match=msg):
            s.natural_frequencies(n_modes=bad)
        with pytest.raises(ModelError, match=msg):
            s.mode_shapes(n_modes=bad)
    np.testing.assert_array_equal(s.natural_frequencies(n_modes=2), s.natural_frequencies()[:2])
    m = s.mode_shapes(n_modes=2)
    np.testing.assert_array_equal(m.shapes, s.mode_shapes().shapes[:, :2])


def test_chain_copies_its_inputs():
    """The system is immutable: it keeps its own copies and never freezes the caller's arrays."""
    j, k = np.array([1.0, 2.0]), np.array([3e4])
    s = chain(j, k)
    j[0] = 5.0
    assert j.flags.writeable and s.inertias[0] == 1.0
    t = TorsionalSystem(j, [(0, 1)], k)
    k[0] = 1.0
    assert k.flags.writeable and t.stiffnesses[0] == 3e4
