"""The compiled dqds (predict.torsion._dqds) against independent references.

References: bisection on extended-precision Sturm counts of the chain (analysis.bench._sturm,
no bidiagonal factor, no LAPACK) and LAPACK ``dlasq2`` on the same qd array (forced by raising
the kernel's size threshold). Every fallback path (range, no numba) must give the same values.
"""

from __future__ import annotations

import numpy as np
import pytest

from crankbench.analysis.bench._sturm import EXTENDED, chain_reference
from crankbench.predict.torsion import _dqds, chain
from crankbench.predict.torsion._lapack import lapack_qd_singular_values, qd_singular_values
from crankbench.predict.torsion.eigen import _free_chain_squares

pytestmark = pytest.mark.skipif(not _dqds.available(), reason="numba not available")


def _lapack_only(q, e2, monkeypatch):
    """Singular values by LAPACK dlasq2 (the kernel's size threshold out of reach)."""
    with monkeypatch.context() as m:
        m.setattr(_dqds, "MIN_SIZE", 10**9)
        out = qd_singular_values(q, e2)
    np.testing.assert_array_equal(out, lapack_qd_singular_values(q, e2))
    return out


def _hard_chain(n, seed, grounded):
    rng = np.random.default_rng(seed)
    j = 10 ** rng.uniform(0, 8, n)                       # inertia ratio 1e8
    k = 10 ** rng.uniform(0, 12, n if grounded else n - 1)  # stiffness ratio 1e12
    return j, k


@pytest.mark.skipif(not EXTENDED, reason="needs an extended long double")
@pytest.mark.parametrize("grounded", [True, False])
def test_hard_chains_every_mode_within_1e13_of_sturm_counts(grounded):
    n = 300
    j, k = _hard_chain(n, 3 if grounded else 4, grounded)
    q, e2 = (k / j, k[1:] / j[:-1]) if grounded else _free_chain_squares(j, k)
    assert _dqds.qd_eigenvalues(q, e2) is not None      # the compiled kernel did the work
    omega = chain(j, k).natural_frequencies("rad/s")
    ref = chain_reference(j, k, grounded=grounded, start=omega)
    pos = ref > 0
    assert np.max(np.abs(omega[pos] - ref[pos]) / ref[pos]) < 1e-13
    if not grounded:
        assert omega[0] == 0.0


def test_uniform_chain_matches_closed_form():
    n, jj, kk = 500, 1.5, 4.0e5          # ω_k = 2√(k/J) sin(kπ/2n)
    omega = chain(np.full(n, jj), np.full(n - 1, kk)).natural_frequencies("rad/s")
    ref = 2 * np.sqrt(kk / jj) * np.sin(np.arange(n) * np.pi / (2 * n))
    assert np.max(np.abs(omega[1:] - ref[1:]) / ref[1:]) < 1e-13


def _qd_arrays():
    """Graded, clustered, flat and random qd arrays (n >= MIN_SIZE, inside the safe range)."""
    rng = np.random.default_rng(2024)
    out = []
    for n in (64, 97, 250):
        out.append((10 ** rng.uniform(-12, 12, n), 10 ** rng.uniform(-12, 12, n - 1)))
        out.append((rng.uniform(1e-3, 1, n), rng.uniform(1e-3, 1, n - 1)))
        out.append((np.ones(n), np.ones(n - 1)))                     # uniform
        out.append((np.ones(n), np.full(n - 1, 1e-30)))              # tight cluster at 1
        # strongly graded, small end on top (reversed by the kernel) and at the bottom
        out.append((np.geomspace(1e-20, 1e20, n), 1e-22 * rng.uniform(0.5, 2, n - 1)))
        out.append((np.geomspace(1e20, 1e-20, n), 1e-22 * rng.uniform(0.5, 2, n - 1)))
    return out


def test_agrees_with_lapack_dlasq2_on_graded_and_clustered_arrays(monkeypatch):
    used = 0
    for q, e2 in _qd_arrays():
        ref = _lapack_only(q, e2, monkeypatch)
        assert ref.min() > 0                             # a well-posed case
        got = qd_singular_values(q, e2)
        used += _dqds.qd_eigenvalues(q, e2) is not None
        assert got.shape == ref.shape
        assert np.all(np.diff(got) <= 0)                 # descending, like dlasq2
        assert np.max(np.abs(got - ref) / ref) < 1e-13
    assert used >= 15                                    # nearly all ran compiled


def test_out_of_range_array_falls_back_to_lapack(monkeypatch):
    rng = np.random.default_rng(5)
    q, e2 = 10 ** rng.uniform(-80, 80, 100), 10 ** rng.uniform(-80, 80, 99)
    assert _dqds.qd_eigenvalues(q, e2) is None           # outside (1e-60, 1e60)
    got = qd_singular_values(q, e2)
    np.testing.assert_array_equal(got, _lapack_only(q, e2, monkeypatch))


def test_without_numba_the_public_call_gives_the_same_modes(monkeypatch):
    j, k = _hard_chain(200, 9, True)
    compiled = chain(j, k).natural_frequencies("rad/s")
    monkeypatch.setattr(_dqds, "_kernel", lambda: None)
    assert not _dqds.available()
    lapack = chain(j, k).natural_frequencies("rad/s")
    assert np.max(np.abs(compiled - lapack) / lapack) < 1e-13


def test_small_chains_do_not_start_the_compiler():
    q, e2 = np.ones(_dqds.MIN_SIZE - 1), np.ones(_dqds.MIN_SIZE - 2)
    assert _dqds.qd_eigenvalues(q, e2) is None


# --- the pass of three transforms, the Newton shift and the gap deflation (issue 21) -------

def test_grounded_uniform_chain_matches_closed_form():
    # fixed-free chain of n masses (first spring to ground): ω_m² = 4 (k/J) sin²((2m−1)π/(4n+2));
    # 2000 masses: thousands of passes that deflate by the gap test and the Weyl test
    n, jj, kk = 2000, 1.5, 4.0e5
    j, k = np.full(n, jj), np.full(n, kk)
    assert _dqds.qd_eigenvalues(k / j, k[1:] / j[:-1]) is not None
    omega = chain(j, k).natural_frequencies("rad/s")
    m = np.arange(1, n + 1)
    ref = 2 * np.sqrt(kk / jj) * np.sin((2 * m - 1) * np.pi / (4 * n + 2))
    assert np.max(np.abs(omega - ref) / ref) < 1e-13


@pytest.mark.skipif(not EXTENDED, reason="needs an extended long double")
def test_clusters_of_local_modes_far_from_the_bottom_against_sturm_counts():
    # 40 copies of a light mass between two stiff springs, each between heavy masses, spread
    # along a graded random chain: 40 eigenvalues within 1e-3 of each other, their modes far
    # from the bottom of the array (where dqds deflates) -- the case the Newton shift and the
    # gap test are for; every mode against bisection on extended-precision Sturm counts
    rng = np.random.default_rng(21)
    n = 400
    j = 10 ** rng.uniform(0, 8, n)
    k = 10 ** rng.uniform(0, 12, n)
    for pos in range(5, n, 10):
        j[pos] = 1.0 * (1 + 1e-4 * rng.standard_normal())
        j[pos - 1] = j[pos + 1] = 1e8
        k[pos] = k[pos + 1] = 1e6
    omega = chain(j, k).natural_frequencies("rad/s")
    assert _dqds.qd_eigenvalues(k / j, k[1:] / j[:-1]) is not None
    ref = chain_reference(j, k, grounded=True, start=omega)
    near = np.abs(ref / np.sqrt(2e6) - 1) < 1e-3
    assert near.sum() >= 40                                  # the cluster is there
    assert np.max(np.abs(omega - ref) / ref) < 1e-13


def test_hard_10000_mass_chain_agrees_with_lapack_dlasq2(monkeypatch):
    # the bench's target case (stiffness ratio 1e12, inertia ratio 1e8): every mode of the
    # compiled kernel against LAPACK's own dqds on the same array
    j, k = _hard_chain(10_000, 7, True)
    q, e2 = k / j, k[1:] / j[:-1]
    lam = _dqds.qd_eigenvalues(q, e2)
    assert lam is not None
    ref = np.sort(_lapack_only(q, e2, monkeypatch)) ** 2
    assert np.max(np.abs(lam - ref) / ref) < 1e-13
