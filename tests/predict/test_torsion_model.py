"""Shaft-line elements, TOML models, stress limits and the ``predict torsion`` command."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from crankbench.predict.engine import Engine
from crankbench.predict.errors import ModelError
from crankbench.predict.torsion import from_toml
from crankbench.predict.torsion.elements import (ShaftLine, crank_throw_inertia, shaft_stiffness,
                                      stepped_shaft)
from crankbench.predict.torsion.stress import StressLimits, check_stress

ROOT = Path(__file__).resolve().parents[2]
SHAFTLINES = ROOT / "sample_data" / "shaftlines"

# Stand-ins used only when the engine helper's files are not (yet) in sample_data/engines.
STAND_IN_ENGINES = {
    "marine_6l.toml": """[engine]
name = "6L32 stand-in"
crank_angles_deg = [0, 240, 120, 120, 240, 0]
crank_radius = 0.2
rod_length = 0.9
bore = 0.32
reciprocating_mass = 250.0
rotating_mass = 150.0
cylinder_spacing = 0.53
firing_order = [1, 5, 3, 6, 2, 4]
compression_ratio = 15.0
rated_speed_rpm = 720
[engine.combustion]
imep = 2.4e6
""",
    "i4.toml": """[engine]
name = "I4 stand-in"
crank_angles_deg = [0, 180, 180, 0]
crank_radius = 0.043
rod_length = 0.145
bore = 0.086
reciprocating_mass = 0.55
rotating_mass = 0.4
firing_order = [1, 3, 4, 2]
compression_ratio = 10.5
[engine.combustion]
imep = 1.2e6
""",
    "i6.toml": """[engine]
name = "I6 stand-in"
crank_angles_deg = [0, 240, 120, 120, 240, 0]
crank_radius = 0.083
rod_length = 0.26
bore = 0.126
reciprocating_mass = 3.2
rotating_mass = 2.5
firing_order = [1, 5, 3, 6, 2, 4]
compression_ratio = 17.0
[engine.combustion]
imep = 2.0e6
""",
}


@pytest.fixture
def models(tmp_path):
    """Copy of sample_data/{shaftlines,engines} with stand-in engines where missing."""
    (tmp_path / "shaftlines").mkdir()
    (tmp_path / "engines").mkdir()
    for f in SHAFTLINES.glob("*.toml"):
        shutil.copy(f, tmp_path / "shaftlines" / f.name)
    for name, text in STAND_IN_ENGINES.items():
        real = ROOT / "sample_data" / "engines" / name
        dest = tmp_path / "engines" / name
        if real.exists():
            shutil.copy(real, dest)
        else:
            dest.write_text(text)
    return tmp_path / "shaftlines"


def test_shaft_stiffness_and_stepped_shaft():
    g = 80e9
    k = shaft_stiffness(2.0, 0.1, bore=0.05, shear_modulus=g)
    assert k == pytest.approx(g * np.pi * (0.1 ** 4 - 0.05 ** 4) / 64.0)
    r = stepped_shaft([(1.0, 0.1), (2.0, 0.2, 0.1)], shear_modulus=g)
    k1, k2 = shaft_stiffness(1.0, 0.1, shear_modulus=g), shaft_stiffness(2.0, 0.2, bore=0.1,
                                                                          shear_modulus=g)
    assert r["stiffness"] == pytest.approx(1 / (1 / k1 + 1 / k2), rel=1e-14)
    assert r["equivalent_length"] == pytest.approx(1.0 + 2.0 * 0.1 ** 4 / (0.2 ** 4 - 0.1 ** 4))
    with pytest.raises(ModelError, match="bore=0.2 must be smaller than diameter=0.1"):
        shaft_stiffness(1.0, 0.1, bore=0.2)


def test_crank_throw_inertia_is_the_exact_energy_mean():
    """J = m_rot r² + m_rec ⟨x'²⟩ + ΔJ ⟨φ'²⟩, against quadrature of the closed-form velocity
    x' = −r sin ψ − r² sin ψ cos ψ / √(l² − r² sin² ψ) (and φ' = r cos ψ / √(l² − r² sin² ψ));
    the textbook 1/2 + λ²/8 is low by the series' next terms λ⁴/16 + 5λ⁶/128."""
    from scipy.integrate import quad

    r, l, m_rec, m_rot, dj = 0.1, 0.25, 4.0, 3.0, -0.02
    e = Engine(crank_angles_deg=[0], crank_radius=r, rod_length=l, reciprocating_mass=m_rec,
               rotating_mass=m_rot, rod_inertia_correction=dj)

    def xdot2(p):
        return (r * np.sin(p) + r * r * np.sin(p) * np.cos(p)
                / np.sqrt(l * l - (r * np.sin(p)) ** 2)) ** 2

    def phidot2(p):
        return (r * np.cos(p)) ** 2 / (l * l - (r * np.sin(p)) ** 2)

    mean_x = quad(xdot2, 0, 2 * np.pi, epsabs=0, epsrel=1e-13)[0] / (2 * np.pi)
    mean_p = quad(phidot2, 0, 2 * np.pi, epsabs=0, epsrel=1e-13)[0] / (2 * np.pi)
    j = crank_throw_inertia(e, 1, 0.5)
    assert j == pytest.approx(0.5 + m_rot * r * r + m_rec * mean_x + dj * mean_p, rel=1e-12)
    plain = Engine(crank_angles_deg=[0], crank_radius=r, rod_length=l, reciprocating_mass=m_rec)
    lam = r / l
    short = crank_throw_inertia(plain, 1, exact=False)
    assert short == pytest.approx(m_rec * r * r * (0.5 + lam ** 2 / 8), rel=1e-14)
    missing = crank_throw_inertia(plain, 1) - short
    # λ² ⟨sin²ψ cos²ψ / (1 − λ² sin²ψ)⟩ = λ²/8 + λ⁴/16 + 5λ⁶/128 + 7λ⁸/256 …
    assert missing == pytest.approx(m_rec * r * r * (lam ** 4 / 16 + 5 * lam ** 6 / 128),
                                    rel=1.2 * 7 / 16 * lam ** 4)


def test_gear_referral_by_ratio_squared():
    line = ShaftLine("geared")
    line.add_mass("motor", 2.0)
    line.add_mass("wheel", 0.3, ratio=0.5)
    line.add_gear("motor", "wheel", ratio=0.5)
    line.add_mass("load", 8.0, ratio=0.5)
    line.add_shaft("wheel", "load", stiffness=4e4, diameter=0.05)
    s = line.build()
    assert s.inertias.tolist() == [2.0 + 0.3 * 0.25, 8.0 * 0.25]
    assert s.stiffnesses.tolist() == [4e4 * 0.25]
    # real torque in the slow shaft = referred torque / ratio
    s = s.replace(cylinder_nodes=[0], firing_angles_deg=[0.0])
    r = s.forced_response([300.0], torque=[10.0], orders=[1.0])
    w = 10 * np.pi
    x = np.linalg.solve(s.stiffness_matrix() - w * w * s.inertia_matrix(), [10.0, 0.0])
    assert abs(r.torque[0, 0, 0]) == pytest.approx(abs(1e4 * (x[1] - x[0])) / 0.5, rel=1e-12)
    assert abs(r.angle[0, 0, 1]) == pytest.approx(abs(x[1]) * 0.5, rel=1e-12)
    with pytest.raises(ModelError, match="'motor' turns at ratio 1 and 'load' at 0.5; join "
                                         "different speeds with add_gear"):
        line.add_shaft("motor", "load", stiffness=1.0)


def test_flexible_mesh_and_unknown_node():
    line = ShaftLine("mesh")
    line.add_mass("a", 1.0)
    line.add_mass("b", 1.0, ratio=2.0)
    line.add_gear("a", "b", ratio=2.0, mesh_stiffness=1e5)
    s = line.build()
    assert s.stiffnesses.tolist() == [4e5] and s.inertias.tolist() == [1.0, 4.0]
    with pytest.raises(ModelError, match="mesh: unknown node 'bb' \\(did you mean 'b'\\?\\)"):
        line.add_shaft("a", "bb", stiffness=1.0)


@pytest.mark.parametrize("name", ["marine_6l", "i4", "i6", "twin_propeller", "two_rotor"])
def test_sample_shaft_lines_load_and_solve(models, name):
    s = from_toml(models / f"{name}.toml")
    f = s.natural_frequencies()
    assert f[0] == 0.0 and np.all(np.diff(f) >= 0)
    if name != "two_rotor":
        assert s.engine is not None and len(s.cylinder_nodes) == s.engine.n_cylinders
        lo, hi = s.operating["speed_range_rpm"]
        r = s.forced_response(np.linspace(lo, hi, 40))
        assert np.all(np.isfinite(r.angle_total))


def test_marine_6l_criticals_in_operating_range(models):
    """Orders 3, 4.5 and 6 have criticals of the first engine modes within 200-800 rpm."""
    s = from_toml(models / "marine_6l.toml")
    cs = s.critical_speeds([3.0, 4.5, 6.0], (200, 800))
    assert {3.0, 4.5, 6.0} <= set(cs.order)
    assert cs["vector_sum"].notna().all()
    assert s.limits is not None and "crankshaft output" in s.limits.sections
    assert s.mode_shapes().method == "bidiagonal dqds"
    assert "damper housing viscous ring" in s.node_names
    assert not s.eigen_nodes[s.node_names.index("damper housing viscous ring")]


def test_twin_propeller_antisymmetric_mode(models):
    """Identical branches: one mode has the gearbox still and ω of one propeller on its shaft,
    clamped at the wheel: ω² = k/J at propeller speed."""
    s = from_toml(models / "twin_propeller.toml")
    assert s.mode_shapes().method == "tree bisection"
    k = stepped_shaft([(3.0, 0.30), (8.0, 0.28)])["stiffness"]
    w = np.sqrt(k / 2600.0)
    f = s.natural_frequencies("rad/s")
    assert np.min(np.abs(f - w) / w) < 1e-13


def test_toml_errors_name_file_and_key(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text('[shaftline]\nname = "x"\n[[shaftline.mass]]\nname = "a"\ninertia = -1\n')
    with pytest.raises(ModelError, match=r"bad.toml: shaftline.mass\[0\].inertia = -1.0 must "
                                         r"be > 0"):
        from_toml(p)
    p.write_text('[shaftline]\n[[shaftline.mass]]\nname = "a"\ninertia = 1\ninerta = 2\n')
    with pytest.raises(ModelError, match=r"shaftline.mass\[0\].inerta is not a known key "
                                         r"\(did you mean 'inertia'\?\)"):
        from_toml(p)
    p.write_text('[shaftline]\nengine = "../engines/nope.toml"\n')
    with pytest.raises(ModelError, match=r"shaftline.engine = '../engines/nope.toml': engine "
                                         r"file .* does not exist"):
        from_toml(p)
    p.write_text('[shaftline]\n[[shaftline.damper]]\ntype = "viscus"\nnode = "a"\n')
    with pytest.raises(ModelError, match=r"type = 'viscus' is not one of 'viscous', 'tuned', "
                                         r"'pendulum', 'friction' \(did you mean 'viscous'\?\)"):
        from_toml(p)


def test_stress_limits_barred_ranges(models):
    s = from_toml(models / "marine_6l.toml")
    r = s.forced_response(np.linspace(200, 800, 121))
    tight = StressLimits([0, 1000], [2e6, 2e6], [4e6, 4e6], sections=s.limits.sections)
    chk = check_stress(r, tight)
    assert chk.barred_ranges_rpm and not chk.passed
    for lo, hi in chk.barred_ranges_rpm:
        inside = (r.speed_rpm > lo + 1e-9) & (r.speed_rpm < hi - 1e-9)
        assert np.all(chk.worst_stress[inside] > 2e6)
    with pytest.raises(ModelError, match="need 0 < continuous <= transient at every speed"):
        StressLimits([0, 1], [5e6, 5e6], [4e6, 4e6])


def test_cli_json(models, capsys):
    from crankbench.analysis.cli import main

    rc = main(["predict", "torsion", str(models / "marine_6l.toml"), "--json",
               "--speeds", "60"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["eigen_method"] == "bidiagonal dqds"
    assert out["modes"][0]["mode"] == 1
    assert {"resonances", "worst_stresses", "limits", "critical_speeds"} <= set(out)
    first = out["resonances"][0]
    assert {"energy_balance_deg", "exact_deg", "method_error"} <= set(first)


def test_plots_return_figures(models, tmp_path):
    import matplotlib

    s = from_toml(models / "marine_6l.toml")
    figs = [s.plot_campbell([3.0, 4.5, 6.0], (200, 800)), s.mode_shapes().plot(),
            check_stress(s.forced_response(np.linspace(200, 800, 30)), s.limits).plot()]
    for i, fig in enumerate(figs):
        assert isinstance(fig, matplotlib.figure.Figure)
        fig.savefig(tmp_path / f"{i}.png")
    table = s.mode_shapes().to_frame()
    assert table.shape == (s.n_nodes, s.n_nodes - 1)
