"""The shared-column and per-cylinder excitation paths describe the same torque.

``engine_excitation`` takes one harmonic column for alike cylinders (``tangential_torque``)
and per-cylinder columns otherwise (``predict.forces.cylinder_torque``); both must carry the
residual couple of the two-point rod (``rod_inertia_correction``) and agree with the FFT of the
virtual-work torque (``predict.forces.torque_harmonics``).
"""

import numpy as np
import pytest

from crankbench.predict.engine import Engine
from crankbench.predict.forces import torque_harmonics as forces_harmonics
from crankbench.predict.pressure import synthetic_pressure
from crankbench.predict.torsion.excitation import (_per_cylinder_excitation, engine_excitation,
                                                   tangential_torque)

INLINE = dict(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.06, rod_length=0.2,
              reciprocating_mass=1.5, bore=0.1, compression_ratio=16.0,
              firing_order=[1, 3, 4, 2])


@pytest.mark.parametrize("dj", [0.0, -4.0e-3])
def test_inline_engine_shared_and_per_cylinder_paths_agree(dj):
    e = Engine(**INLINE, rod_inertia_correction=dj)
    p = synthetic_pressure(e, imep=1.2e6)
    orders = np.arange(0.5, 12.5, 0.5)
    shared = engine_excitation(e, pressure=p, orders=orders)
    assert shared.gas.ndim == 1                       # alike cylinders: the shared column
    per = _per_cylinder_excitation(e, p, orders, 1440, "test")
    for c in range(e.n_cylinders):
        np.testing.assert_allclose(per.gas[:, c], shared.gas, atol=1e-9 * abs(shared.gas).max())
        np.testing.assert_allclose(per.inertia[:, c], shared.inertia,
                                   atol=1e-9 * abs(shared.inertia).max())
    # against the virtual-work torque's FFT at a speed (cos/sin form, T = Re Σ T_q e^{iqψ})
    w = 150.0
    ref = forces_harmonics(e, omega=w, pressure=p, max_order=12)
    tq = shared.harmonics([w], orders)[0, :, 0]
    np.testing.assert_allclose(tq.real, ref["cos"].sel(order=orders).values,
                               atol=1e-6 * abs(tq).max())
    np.testing.assert_allclose(-tq.imag, ref["sin"].sel(order=orders).values,
                               atol=1e-6 * abs(tq).max())


def test_residual_couple_enters_the_plain_rod_path():
    """With p = p_cc the torque is inertia only: −m ω² x' x'' − ΔJ ω² φ' φ''."""
    e0 = Engine(**INLINE)
    e1 = Engine(**INLINE, rod_inertia_correction=-4.0e-3)
    psi = np.linspace(0, 4 * np.pi, 97)
    w = 200.0
    diff = (tangential_torque(e1, psi, omega=w, pressure=1e5)
            - tangential_torque(e0, psi, omega=w, pressure=1e5))
    d1, d2 = e1.rod_motion(psi + e1.firing_tdc_shaft_angle)
    np.testing.assert_allclose(diff, 4.0e-3 * w * w * d1[0] * d2[0], rtol=1e-12, atol=1e-12)
    assert np.abs(diff).max() > 1.0


def test_cylinders_with_different_masses_get_their_own_columns():
    e = Engine(**{**INLINE, "reciprocating_mass": [1.5, 1.5, 1.7, 1.5]})
    x = engine_excitation(e, imep=1.0e6, orders=[1.0, 2.0])
    assert x.inertia.shape == (2, 4)
    assert abs(x.inertia[1, 2]) == pytest.approx(abs(x.inertia[1, 0]) * 1.7 / 1.5, rel=1e-12)
