"""Crank-throw stiffness formulas and shafts with distributed inertia.

Sources:
* [Carter] B. C. Carter, *Engineering* 126 (1928) 36; [KW] W. Ker Wilson, *Practical Solution
  of Torsional Vibration Problems* vol. 1, 3rd ed. (1956) ch. 3 — the equivalent-length
  formulas as predict.torsion.throws states them. That form could not be checked against a
  printed copy (none readable was found, in two searches): the test below checks the
  implementation against the stated form only, not the coefficients against the literature;
  tests/predict/test_throw_fe.py checks the formulas against a 3-D FE of the idealised throw.
* [Tim] S. Timoshenko, *Vibration Problems in Engineering*, 2nd ed. (1937) §55: free-free
  uniform shaft ω_m = mπc/L; shaft fixed at one end with a disk at the other,
  β tan β = J_shaft/J_disk, β = ωL/c.
"""

import logging
from pathlib import Path

import numpy as np
import pytest

import crankbench.predict.torsion as pt
from crankbench.predict.torsion.elements import ShaftLine, shaft_stiffness
from crankbench.predict.torsion.throws import (CrankThrow, elements_for_tolerance,
                                               lumping_error, throw_stiffness,
                                               uniform_shaft_frequencies)

G, RHO = 80e9, 7850.0
C = np.sqrt(G / RHO)
THROW = dict(journal_diameter=0.085, journal_length=0.036, pin_diameter=0.07, pin_length=0.042,
             web_thickness=0.026, web_width=0.13, crank_radius=0.08)


def test_carter_and_wilson_equivalent_lengths_term_by_term():
    dj, lj, dp, lp, h, b, r = THROW.values()
    carter = (lj + 0.8 * h) + 0.75 * lp * (dj / dp) ** 4 + 1.5 * r * dj ** 4 / (h * b ** 3)
    wilson = ((lj + 0.4 * dj) + (lp + 0.4 * dp) * (dj / dp) ** 4
              + (r - 0.2 * (dj + dp)) * dj ** 4 / (h * b ** 3))
    t = CrankThrow(**THROW)
    for method, le in (("carter", carter), ("wilson", wilson)):
        res = throw_stiffness(t, method=method, shear_modulus=G)
        assert res.equivalent_length == pytest.approx(le, rel=1e-13)
        # k is that of a plain journal-diameter shaft of the equivalent length
        assert res.stiffness == pytest.approx(shaft_stiffness(le, dj, shear_modulus=G),
                                              rel=1e-13)
        assert res.within_validity and "not verified" in res.note
    # the two formulas agree within their stated scatter on a throw without overlap
    c, w = (throw_stiffness(t, method=m).stiffness for m in ("carter", "wilson"))
    assert abs(c / w - 1) < 0.3


def test_hollow_pin_and_reference_diameter():
    t = CrankThrow(**{**THROW, "pin_bore": 0.03})
    a = throw_stiffness(t, method="carter")
    b = throw_stiffness(t, method="carter", reference_diameter=0.05)
    assert a.stiffness == pytest.approx(b.stiffness, rel=1e-13)
    solid = throw_stiffness(CrankThrow(**THROW), method="carter")
    ratio = 0.07 ** 4 / (0.07 ** 4 - 0.03 ** 4)
    assert a.parts["pin"] == pytest.approx(solid.parts["pin"] * ratio, rel=1e-13)


def test_overlapped_throw_is_flagged_and_warned(caplog):
    t = CrankThrow(**{**THROW, "crank_radius": 0.06})     # (85 + 70)/2 = 77.5 mm > 60 mm
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        res = throw_stiffness(t, method="wilson")
    assert not res.within_validity and "overlap" in res.note
    assert "outside the formula's range" in caplog.text


def test_throw_in_the_toml_sample_gives_wilson_stiffness():
    model = Path(__file__).resolve().parents[2] / "sample_data/shaftlines/i6_geometry.toml"
    s = pt.from_toml(model)
    k = throw_stiffness(CrankThrow(**THROW), method="wilson", shear_modulus=81e9).stiffness
    i = s.edge_names.index("cyl 2-cyl 3")
    assert s.stiffnesses[i] == pytest.approx(k, rel=1e-13)
    # the intermediate shaft carries its own inertia: 16 pieces, total = ρ Ip L
    own = RHO * np.pi * 0.11 ** 4 / 32 * 2.4
    inner = [j for j, n in enumerate(s.node_names) if n.startswith("intermediate shaft [")]
    assert len(inner) == 15
    assert s.inertias[inner].sum() == pytest.approx(own * 15 / 16, rel=1e-13)


@pytest.mark.parametrize("n", [8, 20, 60])
def test_free_free_heavy_shaft_error_is_the_stated_sinc(n):
    """[Tim] §55: the lumped shaft is low by exactly 1 − sin x / x, x = ωL/(2Nc)."""
    length, d = 2.0, 0.1
    line = ShaftLine("free shaft")
    line.add_mass("a", 1e-12)
    line.add_mass("b", 1e-12)
    line.add_shaft("a", "b", length=length, diameter=d, density=RHO, shear_modulus=G,
                   elements=n)
    w = line.build().natural_frequencies("rad/s")[1:4]
    exact = uniform_shaft_frequencies(length=length, shear_modulus=G, density=RHO)
    stated = lumping_error(exact, length=length, wave_velocity=C, elements=n)
    np.testing.assert_allclose(1 - w / exact, stated, rtol=1e-6, atol=1e-12)


def test_shaft_with_disk_against_timoshenko_transcendental_equation():
    """[Tim] §55: fixed at one end, disk J_d at the other: β tan β = J_shaft/J_disk."""
    length, d = 1.5, 0.12
    j_shaft = RHO * np.pi * d ** 4 / 32 * length
    j_disk = 0.5 * j_shaft
    exact = uniform_shaft_frequencies(length=length, shear_modulus=G, density=RHO,
                                      ends="fixed-disk", end_inertia_ratio=j_shaft / j_disk,
                                      n_modes=2)
    errors = []
    for n in (10, 20, 40):
        line = ShaftLine("disk")
        line.add_mass("root", 1e-9)
        line.add_mass("disk", j_disk)
        line.add_ground("root", stiffness=1e6 * shaft_stiffness(length, d, shear_modulus=G))
        line.add_shaft("root", "disk", length=length, diameter=d, density=RHO,
                       shear_modulus=G, elements=n)
        w = line.build().natural_frequencies("rad/s")[:2]
        errors.append(1 - w / exact)
        # the lumped model is low, of the order of the shaft's own-wave error (the half element
        # at the disk adds a boundary term of the same order: within twice it here)
        bound = lumping_error(exact, length=length, wave_velocity=C, elements=n)
        assert np.all(errors[-1] > 0) and np.all(errors[-1] < 2.0 * bound)
    errors = np.array(errors)
    np.testing.assert_allclose(errors[:-1, 0] / errors[1:, 0], 4.0, rtol=0.02)   # O(1/N²)


def test_automatic_element_count_meets_its_tolerance():
    w = np.pi * C / 2.0
    n = elements_for_tolerance(w, length=2.0, wave_velocity=C, tol=1e-4)
    assert lumping_error(w, length=2.0, wave_velocity=C, elements=n) <= 1e-4
    assert lumping_error(w, length=2.0, wave_velocity=C, elements=n - 1) > 1e-4
