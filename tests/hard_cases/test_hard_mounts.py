"""Hard cases for the engine-on-mounts model: nearly singular mount layouts must give a clear
result (right to the stated digits, against mpmath) or a clear error — never garbage.

Not covered elsewhere: ``tests/predict/test_mounts.py`` checks well-conditioned layouts only.
"""

import mpmath
import numpy as np
import pytest

from crankbench.predict.errors import ModelError
from crankbench.predict.mounts import Mount, MountedEngine

MASS, INERTIA, CG = 800.0, [40.0, 90.0, 90.0], [0.5, 0.0, 0.0]


def mp_frequencies_hz(engine, dps=50):
    """Natural frequencies (Hz) of K φ = ω² M φ from the engine's own 6×6 matrices, by mpmath
    (M is diagonal here: the symmetric form M^{-1/2} K M^{-1/2} at ``dps`` digits)."""
    k, m = engine.stiffness_matrix(), engine.mass_matrix()
    assert np.count_nonzero(m - np.diag(np.diag(m))) == 0
    with mpmath.workdps(dps):
        s = [1 / mpmath.sqrt(mpmath.mpf(float(m[i, i]))) for i in range(6)]
        h = mpmath.matrix(6, 6)
        for a in range(6):
            for b in range(6):
                h[a, b] = mpmath.mpf(float(k[a, b])) * s[a] * s[b]
        ev = sorted(mpmath.eigsy(h, eigvals_only=True))
        return np.array([float(mpmath.sqrt(max(e, 0)) / (2 * mpmath.pi)) for e in ev])


def _nearly_collinear(offset):
    """Four mounts below the CG, alternately ``offset`` m either side of one line along x:
    rotation about that line is restrained only through offset² (free when offset = 0)."""
    pts = [(0.0, offset), (1.0, -offset), (0.5, offset), (0.2, -offset)]
    return [Mount(position=[x, y, -0.3], stiffness=[2e6, 2e6, 4e6]) for x, y in pts]


@pytest.mark.parametrize("offset", [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-8])
def test_nearly_collinear_mounts_give_right_frequency_or_clear_error(offset):
    """Either ModelError naming the unrestrained motion, or all six frequencies within 1e-5
    relative of mpmath (the soft roll mode goes as offset: 0.53 Hz at 1 cm)."""
    try:
        eng = MountedEngine(mass=MASS, inertia=INERTIA, cg=CG, mounts=_nearly_collinear(offset))
    except ModelError as exc:
        assert "do not restrain all six rigid-body motions" in str(exc)
        assert offset <= 1e-5          # a centimetre-to-0.1 mm layout must still be solved
        return
    got = eng.natural_frequencies()
    ref = mp_frequencies_hz(eng)
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, ref, rtol=1e-5)
    # the soft mode scales with the offset (restoring moment ∝ offset²)
    assert ref[0] == pytest.approx(0.5326 * offset / 1e-2, rel=1e-3)


def test_exactly_collinear_mounts_are_a_clear_error():
    with pytest.raises(ModelError, match="do not restrain all six rigid-body motions"):
        MountedEngine(mass=MASS, inertia=INERTIA, cg=CG, mounts=_nearly_collinear(0.0))


@pytest.mark.parametrize("ratio", [1e-2, 1e-6, 1e-10, 1e-14])
def test_one_direction_almost_free(ratio):
    """Axial stiffness ``ratio`` × the lateral one: the axial-pitch pair stays exact (mpmath,
    1e-9) down to a 1e-14 ratio; the softest mode → √(4 k_x / m)/2π as the coupling vanishes."""
    mounts = [Mount(position=[x, y, -0.3], stiffness=[2e6 * ratio, 2e6, 4e6])
              for x in (0.0, 1.0) for y in (-0.4, 0.4)]
    try:
        eng = MountedEngine(mass=MASS, inertia=INERTIA, cg=CG, mounts=mounts)
    except ModelError as exc:
        assert "do not restrain" in str(exc) and ratio <= 1e-12
        return
    got, ref = eng.natural_frequencies(), mp_frequencies_hz(eng)
    np.testing.assert_allclose(got, ref, rtol=1e-9)
    kx = 4 * 2e6 * ratio
    # x translation couples with pitch through the 0.3 m height: f below the uncoupled value
    assert got[0] <= np.sqrt(kx / MASS) / (2 * np.pi) * (1 + 1e-12)


def test_exactly_free_direction_is_a_clear_error():
    mounts = [Mount(position=[x, y, -0.3], stiffness=[0.0, 2e6, 4e6])
              for x in (0.0, 1.0) for y in (-0.4, 0.4)]
    with pytest.raises(ModelError, match="do not restrain all six rigid-body motions"):
        MountedEngine(mass=MASS, inertia=INERTIA, cg=CG, mounts=mounts)


def test_near_singular_layout_response_is_finite_and_satisfies_equilibrium():
    """Forced response of the 1e-4 m nearly-collinear layout at 2 Hz: finite, and the mount
    forces plus inertia balance the applied force (second route: q from a direct 6×6 solve)."""
    eng = MountedEngine(mass=MASS, inertia=INERTIA, cg=CG, mounts=_nearly_collinear(1e-4))
    w = 2 * np.pi * 2.0
    f = np.array([0.0, 0.0, 1000.0, 0.0, 0.0, 0.0])
    q = np.linalg.solve(eng.stiffness_matrix() - w * w * eng.mass_matrix(), f)
    assert np.all(np.isfinite(q))
    # the direct solve and mpmath agree on the near-singular system (conditioning check)
    with mpmath.workdps(40):
        a = mpmath.matrix((eng.stiffness_matrix() - w * w * eng.mass_matrix()).tolist())
        qm = mpmath.lu_solve(a, mpmath.matrix(f.tolist()))
        qref = np.array([float(v) for v in qm])
    np.testing.assert_allclose(q, qref, rtol=1e-8, atol=1e-12 * np.abs(qref).max())
