"""Excitation from measured pressure (predict.gas_torque) against second methods.

* one cylinder's trace: identical to the parametric path (engine_excitation) for the same
  trace;
* per-cylinder traces: the multi-cylinder torque synthesised from the harmonics equals the
  time-domain engine torque of predict.forces.engine_torque (which shifts each trace by its
  firing angle itself) -- an independent sum;
* the roll moment of mount_excitation equals the FFT of predict.forces.engine_torque.
"""

import numpy as np
import pytest

from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.gas_torque import excitation_from_pressure, mount_excitation
from crankbench.predict.pressure import synthetic_pressure
from crankbench.predict.torsion.excitation import engine_excitation


@pytest.fixture(scope="module")
def i4():
    return Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.043, rod_length=0.145,
                  reciprocating_mass=0.55, bore=0.086, compression_ratio=10.5,
                  firing_order=[1, 3, 4, 2])


def test_one_trace_equals_the_parametric_path(i4):
    tr = synthetic_pressure(i4, imep=1.2e6)
    a = excitation_from_pressure(i4, tr)
    b = engine_excitation(i4, pressure=tr)
    assert np.allclose(a.gas, b.gas, rtol=0, atol=1e-9 * np.abs(b.gas).max())
    assert np.allclose(a.inertia, b.inertia)
    assert "equal cylinders" in a.source


def test_per_cylinder_traces_sum_to_the_engine_torque(i4):
    """Cylinders at different loads: Re Σ_c Σ_q T_q,c e^{iq(θ − φ_c)} + T0 = engine_torque."""
    traces = [synthetic_pressure(i4, imep=p) for p in (1.0e6, 1.2e6, 0.9e6, 1.1e6)]
    orders = np.arange(0.5, 48.5, 0.5)
    x = excitation_from_pressure(i4, traces, orders=orders, points=2880)
    assert x.gas.shape == (orders.size, 4)
    omega = 300.0
    h = x.harmonics([omega], orders)[0]                          # (n_o, 4)
    theta = np.linspace(0, 4 * np.pi, 1441)[:-1]
    fire = np.deg2rad(i4.firing_angles_deg())
    synth = sum(np.real(h[:, c][None, :] * np.exp(1j * np.outer(theta - fire[c], orders)))
                .sum(axis=1) for c in range(4))
    from crankbench.predict.forces import engine_torque

    direct = engine_torque(i4, theta, omega=omega, pressure=traces)
    ac = (direct - direct.mean())
    assert np.max(np.abs(synth - synth.mean() - ac)) < 0.02 * np.max(np.abs(ac))


def test_unmeasured_cylinders_take_the_mean_and_say_so(i4):
    t1, t2 = synthetic_pressure(i4, imep=1.0e6), synthetic_pressure(i4, imep=1.4e6)
    x = excitation_from_pressure(i4, {1: t1, 3: t2}, orders=[0.5, 1.0, 2.0])
    assert "cylinder(s) 2, 4 not measured" in x.source
    assert np.allclose(x.gas[:, 1], 0.5 * (x.gas[:, 0] + x.gas[:, 2]))
    h = x.harmonics([100.0], [0.5], misfire=3)[0]             # misfire removes cyl 3's gas
    i = x.harmonics([100.0], [0.5])[0] - x.gas[:1]            # inertia only (zero at 0.5)
    assert np.allclose(h[0, 2], i[0, 2])
    with pytest.raises(ModelError, match="cylinder 7"):
        excitation_from_pressure(i4, {7: t1})
    with pytest.raises(ModelError, match="2 pressure traces"):
        excitation_from_pressure(i4, [t1, t2])


def test_mount_roll_moment_is_the_engine_torque_harmonic(i4):
    tr = synthetic_pressure(i4, imep=1.0e6)
    x = excitation_from_pressure(i4, tr, orders=[1.0, 2.0, 4.0])
    omega = 250.0
    from crankbench.predict.forces import engine_torque

    n = 2880
    theta = np.arange(n) * 4 * np.pi / n
    t = engine_torque(i4, theta, omega=omega, pressure=tr)
    for q in (2.0, 4.0):
        ref = 2.0 / n * np.sum(t * np.exp(-1j * q * theta))
        m = mount_excitation(i4, x, order=q, omega=omega)
        assert abs(m["moment"][0] - ref) < 2e-3 * abs(ref)
        assert m["freq_hz"] == pytest.approx(q * omega / (2 * np.pi))
    # the free second-order vertical force of the flat-plane I4: 4 m r ω² A2 (Liang 1948 ch.
    # 3), A2 = λ + λ³/4 + 15λ⁵/128
    lam = 0.043 / 0.145
    a2 = lam + lam ** 3 / 4 + 15 * lam ** 5 / 128
    m2 = mount_excitation(i4, x, order=2.0, omega=omega)
    assert abs(m2["force"][2]) == pytest.approx(4 * 0.55 * 0.043 * omega ** 2 * a2, rel=1e-4)
    with pytest.raises(ModelError, match="omega"):
        mount_excitation(i4, x, order=2.0, omega=0.0)


def test_mount_response_matches_the_synthetic_bench_second_implementation():
    """mount_response against measure.synth.vibrograph.MountChannels (written apart) with a
    per-cylinder measured excitation: every axis, orders 1, 2, 4, three speeds."""
    from pathlib import Path

    from crankbench.measure.synth.vibrograph import MountChannels
    from crankbench.predict.gas_torque import mount_response
    from crankbench.predict.mounts import MountedEngine

    f = Path(__file__).resolve().parents[2] / "sample_data/engines/i4.toml"
    e, mounted = Engine.from_toml(f), MountedEngine.from_toml(f)
    traces = [synthetic_pressure(e, imep=p) for p in (1.0e6, 1.2e6, 0.9e6, 1.1e6)]
    orders = np.array([0.5, 1.0, 2.0, 4.0])
    x = excitation_from_pressure(e, traces, orders=orders)
    pts = np.array([[0.2, 0.05, 0.1], [-0.1, 0.25, 0.15]])
    speeds = np.array([1200.0, 3000.0, 5500.0])
    u = mount_response(mounted, e, x, speed_rpm=speeds, orders=orders, points=pts, load=0.8)
    mc = MountChannels(mounted, e, x, orders, pts, speeds * np.pi / 30)
    scale = np.abs(u).max()
    for k in range(orders.size):
        for p in range(2):
            for axis, name in enumerate("xyz"):
                ref = mc.table(k, p, name, "displacement", lambda w: np.full_like(w, 0.8))
                assert np.allclose(u[:, k, p, axis], ref, rtol=0, atol=1e-9 * scale)
