"""Crank-throw stiffness: the 3-D FE second method, and checks every throw formula must pass.

References
----------
* Plain shaft in torsion, k = G J / L, J = π (D⁴ - d⁴) / 32; sections in series add
  flexibilities (any strength-of-materials text, e.g. Timoshenko & Gere, *Mechanics of
  Materials*, torsion of circular shafts).
* Minimum potential energy: a conforming displacement FE model with imposed boundary
  displacements stores at least the exact strain energy, so its stiffness bounds the exact one
  from above and falls as the mesh is refined (e.g. Zienkiewicz & Taylor, *The Finite Element
  Method* vol. 1, on the bound property of displacement models).

The empirical formulas (Carter, Ker Wilson) could not be checked against a printed source
(predict.torsion.throws); here they are checked against the FE of the idealised throw at the
figures predict.torsion.throws states, and for dimensional homogeneity.
"""

import logging
from pathlib import Path

import numpy as np
import pytest

import crankbench.predict.torsion as pt
from crankbench.predict.errors import ModelError
from crankbench.predict.torsion.throw_fe import _throw_grid_stiffness, throw_stiffness_fe
from crankbench.predict.torsion.throws import CrankThrow, throw_stiffness

G = 81e9          # the I6 sample's shear modulus: the FE results are cached per (throw, G)
I6 = dict(journal_diameter=0.085, journal_length=0.036, pin_diameter=0.07, pin_length=0.042,
          web_thickness=0.026, web_width=0.13, crank_radius=0.08)
D = 0.3
LONG = dict(journal_diameter=D, journal_length=0.5 * D, pin_diameter=0.95 * D,
            pin_length=0.55 * D, web_thickness=0.45 * D, web_width=1.6 * D,
            crank_radius=1.35 * D)
OVERLAP = dict(journal_diameter=D, journal_length=0.4 * D, pin_diameter=0.9 * D,
               pin_length=0.45 * D, web_thickness=0.3 * D, web_width=1.4 * D,
               crank_radius=0.65 * D)
# predict.torsion.throws, module docstring table: formula L_e / FE L_e - 1
STATED = {"i6": (I6, -0.08, 0.05), "long": (LONG, 0.03, 0.07), "overlap": (OVERLAP, 0.03, 0.04)}


def plain_shaft_throw(diameter, bore):
    """A throw whose pin lies on the axis and whose webs are as wide as the journal: a plain
    shaft (journal and pin bored, webs solid)."""
    return CrankThrow(journal_diameter=diameter, journal_length=0.036, pin_diameter=diameter,
                      pin_length=0.042, web_thickness=0.026, web_width=diameter,
                      crank_radius=1e-9, journal_bore=bore, pin_bore=bore)


@pytest.mark.parametrize("bore", [0.0, 0.034])
def test_fe_of_a_plain_shaft_is_g_j_over_l(bore):
    d = 0.085
    res = throw_stiffness_fe(plain_shaft_throw(d, bore), shear_modulus=G)
    j_bored, j_solid = np.pi * (d ** 4 - bore ** 4) / 32, np.pi * d ** 4 / 32
    exact = 1.0 / ((0.036 + 0.042) / (G * j_bored) + 2 * 0.026 / (G * j_solid))
    assert abs(res.stiffness / exact - 1) < 0.005          # module docstring: within 0.5 %
    assert abs(res.stiffness / exact - 1) <= res.uncertainty
    assert res.method == "fe" and res.within_validity


def test_fe_grid_stiffness_falls_with_refinement():
    """The energy bound: a finer grid is softer (I6 throw, 12 and 8 mm elements)."""
    t = CrankThrow(**I6)
    coarse, n_coarse = _throw_grid_stiffness(t, 0.012, young=2 * G * 1.3, poisson=0.3)
    fine, n_fine = _throw_grid_stiffness(t, 0.008, young=2 * G * 1.3, poisson=0.3)
    assert n_fine > 2 * n_coarse
    assert fine < coarse


def test_fe_two_element_sizes_agree_within_the_stated_uncertainty():
    t = CrankThrow(**I6)
    default = throw_stiffness(t, method="fe", shear_modulus=G)
    coarse = throw_stiffness_fe(t, shear_modulus=G, element_size=0.01)
    assert abs(coarse.stiffness / default.stiffness - 1) <= max(coarse.uncertainty,
                                                                default.uncertainty)
    assert "7 and 4.67 mm" in default.note                    # the default grid named
    assert 0.0 < default.uncertainty < 0.05


@pytest.mark.parametrize("method", ["carter", "wilson"])
def test_formulas_are_dimensionally_homogeneous(method):
    """Every length ×s: L_e ×s, k ×s³; k ∝ G. Independent of the coefficients."""
    t = CrankThrow(**I6, pin_bore=0.02)
    big = CrankThrow(**{k: 7.0 * v for k, v in I6.items()}, pin_bore=0.14)
    a, b = throw_stiffness(t, method=method), throw_stiffness(big, method=method)
    assert b.equivalent_length == pytest.approx(7.0 * a.equivalent_length, rel=1e-12)
    assert b.stiffness == pytest.approx(343.0 * a.stiffness, rel=1e-12)
    doubled = throw_stiffness(t, method=method, shear_modulus=160e9)
    assert doubled.stiffness == pytest.approx(2.0 * a.stiffness, rel=1e-12)


def test_fe_is_dimensionally_homogeneous():
    t = CrankThrow(**I6)
    big = CrankThrow(**{k: 10.0 * v for k, v in I6.items()})
    a = throw_stiffness_fe(t, shear_modulus=G, element_size=0.012)
    b = throw_stiffness_fe(big, shear_modulus=G, element_size=0.12)
    assert b.stiffness == pytest.approx(1000.0 * a.stiffness, rel=1e-6)
    assert b.equivalent_length == pytest.approx(10.0 * a.equivalent_length, rel=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(STATED))
def test_formulas_against_the_fe_at_the_stated_figures(name, caplog):
    dims, carter_dev, wilson_dev = STATED[name]
    t = CrankThrow(**dims)
    fe = throw_stiffness(t, method="fe", shear_modulus=G)
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        c, w = (throw_stiffness(t, method=m, shear_modulus=G) for m in ("carter", "wilson"))
    for res, stated in ((c, carter_dev), (w, wilson_dev)):
        dev = res.equivalent_length / fe.equivalent_length - 1
        assert abs(dev - stated) < 0.01                       # the table, to its 1 % digits
        assert abs(dev) < res.uncertainty                     # the stated ±15 %
        assert res.within_validity == (name != "overlap")
    assert fe.within_validity


@pytest.mark.parametrize("method", ["tuplin", "bicera"])
def test_unavailable_formulas_say_why(method):
    with pytest.raises(ModelError, match=rf"method='{method}'.*not implemented: no readable "
                                         r"source gave its coefficients.*use one of 'carter', "
                                         r"'wilson', 'fe'"):
        throw_stiffness(CrankThrow(**I6), method=method)


def test_unknown_method_lists_the_valid_ones():
    with pytest.raises(ModelError, match=r"method='wilsn' is not one of 'carter', 'wilson', "
                                         r"'fe' \(did you mean 'wilson'\?\)"):
        throw_stiffness(CrankThrow(**I6), method="wilsn")


def _sample_with(tmp_path, method):
    root = Path(__file__).resolve().parents[2] / "sample_data"
    text = (root / "shaftlines/i6_geometry.toml").read_text()
    text = text.replace('engine = "../engines/i6.toml"',
                        f'engine = "{(root / "engines/i6.toml").as_posix()}"')
    text = text.replace('method = "wilson"', f'method = "{method}"')
    path = tmp_path / "model.toml"
    path.write_text(text)
    return path


def test_toml_bicera_names_the_table_and_the_reason(tmp_path):
    with pytest.raises(ModelError, match=r"throw.*BICERA formula \(Nestorides 1958\) is not "
                                         r"implemented"):
        pt.from_toml(_sample_with(tmp_path, "bicera"))


def test_toml_fe_method_builds_the_shaft_line(tmp_path):
    line = pt.from_toml(_sample_with(tmp_path, "fe"))
    k = throw_stiffness(CrankThrow(**I6), method="fe", shear_modulus=G).stiffness
    i = line.edge_names.index("cyl 2-cyl 3")
    assert line.stiffnesses[i] == pytest.approx(k, rel=1e-13)


def test_fe_grid_size_is_checked(caplog):
    t = CrankThrow(**I6)
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        throw_stiffness_fe(t, element_size=0.02)
    assert "more than a quarter of the smaller of the journal and pin diameters" in caplog.text
    with pytest.raises(ModelError, match=r"throw FE: a grid of \d+ x \d+ x \d+ cells is too "
                                         r"fine .*use a larger element_size"):
        throw_stiffness_fe(t, element_size=0.001)
    with pytest.raises(ModelError, match=r"poisson_ratio=0.5 must lie in \[0, 0.5\)"):
        throw_stiffness_fe(t, poisson_ratio=0.5)
    with pytest.raises(ModelError, match="throw must be a CrankThrow, got dict"):
        throw_stiffness_fe(I6)
