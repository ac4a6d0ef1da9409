"""Engine on elastic mounts: decoupled closed forms, single-DOF transmissibility, statics and
dynamic equilibrium of the transmitted forces, TOML loading."""

import numpy as np
import pytest

from crankbench.predict.balance import unbalance
from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.mounts import Mount, MountedEngine, excitation_from_unbalance


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures the result objects' plot() made (matplotlib warns past 20)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


MASS, J = 500.0, np.array([30.0, 60.0, 70.0])
KX, KY, KZ = 1.0e6, 1.5e6, 3.0e6
A, B = 0.6, 0.3          # mounts at x = ±A, y = ±B in the CG plane


def _symmetric(damping=(0.0, 0.0, 0.0), loss=0.0):
    mounts = [Mount(position=[x, y, 0.0], stiffness=[KX, KY, KZ], damping=damping,
                    loss_factor=loss) for x in (-A, A) for y in (-B, B)]
    return MountedEngine(mass=MASS, inertia=J, cg=[0.0, 0.0, 0.0], mounts=mounts)


def test_decoupled_layout_natural_frequencies_closed_form():
    """Mounts in the CG plane, symmetric: every mode is a single DOF (Liang 1948 ch. 4)."""
    eng = _symmetric()
    ref = np.sort(np.array([
        np.sqrt(4 * KX / MASS), np.sqrt(4 * KY / MASS), np.sqrt(4 * KZ / MASS),
        np.sqrt(4 * KZ * B**2 / J[0]),                    # roll about x
        np.sqrt(4 * KZ * A**2 / J[1]),                    # pitch about y
        np.sqrt(4 * (KX * B**2 + KY * A**2) / J[2]),      # yaw about z
    ])) / (2 * np.pi)
    np.testing.assert_allclose(eng.natural_frequencies(), ref, rtol=1e-12)
    modes = eng.modes()
    m = eng.mass_matrix()
    v = modes.mode_shapes
    np.testing.assert_allclose(v.T @ m @ v, np.eye(6), atol=1e-12)
    assert modes.to_frame().shape[0] == 6 and modes.plot() is not None


def test_single_dof_transmissibility_matches_classical_formula():
    """T = sqrt((1 + (2ζr)²) / ((1 − r²)² + (2ζr)²)) (Den Hartog §3.2)."""
    c = 2000.0
    eng = _symmetric(damping=(c, c, c))
    fn = np.sqrt(4 * KZ / MASS) / (2 * np.pi)
    zeta = 4 * c / (2 * np.sqrt(4 * KZ * MASS))
    f = np.array([0.3, 0.9, 1.0, np.sqrt(2), 3.0]) * fn
    r = f / fn
    ref = np.sqrt((1 + (2 * zeta * r) ** 2) / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2))
    np.testing.assert_allclose(eng.transmissibility(f, direction="z"), ref, rtol=1e-12)


def _coupled():
    mounts = [Mount(position=[0.1, -0.35, -0.25], stiffness=[8e5, 1.2e6, 2.5e6],
                    damping=[900, 900, 1500], name="front left"),
              Mount(position=[0.1, 0.35, -0.25], stiffness=[8e5, 1.2e6, 2.5e6],
                    damping=[900, 900, 1500], name="front right"),
              Mount(position=[0.9, 0.0, -0.3], stiffness=[1e6, 1.5e6, 3e6], loss_factor=0.1,
                    name="rear")]
    inertia = np.array([[25.0, 1.0, -2.0], [1.0, 55.0, 0.5], [-2.0, 0.5, 60.0]])
    return MountedEngine(mass=420.0, inertia=inertia, cg=[0.45, 0.02, 0.12], mounts=mounts)


def test_static_response_transmits_applied_force_and_moment():
    eng = _coupled()
    force = np.array([300.0, -200.0, 1000.0])
    moment = np.array([50.0, -80.0, 20.0])
    point = np.array([0.3, 0.0, 0.0])
    r = eng.response(force, moment, 0.0, point=point)
    tot = r.transmitted[0].real
    np.testing.assert_allclose(tot, force, rtol=1e-10)
    mom = sum(np.cross(mt.position - point, r.mount_forces[0, j].real)
              for j, mt in enumerate(eng.mounts))
    np.testing.assert_allclose(mom, moment, rtol=1e-9, atol=1e-9)


def test_dynamic_equilibrium_of_forces():
    """Applied force − force into the mounts = m · a_CG (Newton), at any frequency."""
    eng = _coupled()
    force = np.array([100.0 + 20j, 0.0, -400.0j])
    f = np.array([3.0, 11.0, 47.0])
    r = eng.response(force, None, f, point=[0.2, 0.1, 0.0], at=[eng.cg])
    acc_cg = r.acceleration[:, 0, :]
    np.testing.assert_allclose(force[None, :] - r.transmitted, eng.mass * acc_cg,
                               rtol=1e-9, atol=1e-9 * np.abs(force).max())
    assert r.to_frame().shape[0] == 9 and r.plot() is not None


def test_unbalance_drives_mounts_through_excitation_helper():
    e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.04, rod_length=0.14,
               reciprocating_mass=0.5, cylinder_positions=[0.0, 0.09, 0.18, 0.27])
    ds = unbalance(e, omega=300.0, orders=(2,))
    ex = excitation_from_unbalance(ds, 2)
    assert abs(ex["force"][2]) == pytest.approx(float(ds["force_vertical"][0]))
    eng = _symmetric()
    r = eng.response(ex["force"], ex["moment"], ex["freq_hz"], point=ex["point"])
    # a vertical force through the CG plane of a decoupled mounting: pure bounce
    np.testing.assert_allclose(np.abs(r.body[0, [0, 1, 3, 5]]), 0.0, atol=1e-15)
    kz, w = 4 * KZ, 2 * np.pi * ex["freq_hz"]
    assert abs(r.body[0, 2]) == pytest.approx(abs(ex["force"][2]) / abs(kz - MASS * w**2),
                                              rel=1e-10)


def test_from_toml_and_errors(tmp_path):
    p = tmp_path / "m.toml"
    p.write_text("""
[engine]
ignored = true

[mounts]
mass = 500.0
inertia = [30.0, 60.0, 70.0]
cg = [0.0, 0.0, 0.0]
[[mounts.mount]]
position = [-0.6, -0.3, 0.0]
stiffness = [1e6, 1.5e6, 3e6]
[[mounts.mount]]
position = [-0.6, 0.3, 0.0]
stiffness = [1e6, 1.5e6, 3e6]
[[mounts.mount]]
position = [0.6, -0.3, 0.0]
stiffness = [1e6, 1.5e6, 3e6]
[[mounts.mount]]
position = [0.6, 0.3, 0.0]
stiffness = [1e6, 1.5e6, 3e6]
""")
    eng = MountedEngine.from_toml(p)
    np.testing.assert_allclose(eng.natural_frequencies(), _symmetric().natural_frequencies())
    assert eng.to_frame().shape[0] == 4
    p.write_text("[mounts]\nmass = 1.0\ninertia = [1, 1, 1]\ncg = [0, 0, 0]\n"
                 "[[mounts.mount]]\nposition = [0, 0, 0]\nstifness = [1, 1, 1]\n")
    with pytest.raises(ModelError, match=r"m.toml: mounts.mount\[0\].stiffness is missing"):
        MountedEngine.from_toml(p)
    p.write_text("[mounts]\nmass = 1.0\ninertia = [1, 1, 1]\ncg = [0, 0, 0]\n"
                 "[[mounts.mount]]\nposition = [0, 0, 0]\nstiffness = [1, 1, 1]\n")
    with pytest.raises(ModelError, match=r"do not restrain all six rigid-body motions"):
        MountedEngine.from_toml(p)
