"""Residual terms of the modal fit: a weak mode on the tails of strong out-of-band modes.

The order track is the closed-form receptance of three uncoupled modes (Ewins, *Modal
Testing*, 2nd ed., §2.2 and §4.3.5: a weak mode between a strong lower mode — the "residual
mass" tail, ∝ −1/ω² — and a strong higher mode — the "residual stiffness" tail, ≈ constant +
ω²). The reference is the weak mode's own pole (f_n, ζ), known in closed form; a single-mode
fit with only a constant + linear background is biased by the curvature of the tails.

Measured (this file's track): with the residual terms f_n within +0.006 % and ζ within
+0.5 %; constant + linear background over ±3 half-power widths: f_n −0.048 %, ζ −2.2 %.
"""

import numpy as np
import pytest
import xarray as xr

import crankbench.analysis.resonance.finder as finder
from crankbench.analysis.resonance import find_resonances

FN, ZETA, ORDER = 27.0, 0.058, 3.0


def _receptance(f, fn, zeta):
    nu = f / fn
    return 1.0 / (1.0 - nu**2 + 2j * zeta * nu)


def _track(rpm):
    f = ORDER * rpm / 60.0
    comp = (0.25 * np.exp(0.4j) * _receptance(f, FN, ZETA)      # the weak mode
            + 20.0 * _receptance(f, 6.1, 0.097)                  # strong mode below
            + 8.0 * _receptance(f, 54.0, 0.057))                 # strong mode above
    return xr.Dataset({"amplitude": (("order", "rpm"), np.abs(comp)[None], {"units": "rad"}),
                       "phase": (("order", "rpm"), np.angle(comp)[None], {"units": "rad"})},
                      coords={"order": [ORDER], "rpm": ("rpm", rpm)})


def _weak_mode(table):
    near = [r for r in table if abs(r.frequency_hz / FN - 1.0) < 0.05]
    assert len(near) == 1, [(r.frequency_hz, r.method) for r in table]
    return near[0]


def test_weak_mode_between_strong_modes_residual_terms(monkeypatch):
    """The pole of the weak mode against its closed form, with and without residual terms."""
    track = _track(np.linspace(200.0, 760.0, 1401))
    r = _weak_mode(find_resonances(track))
    assert r.method == "modal fit"
    assert r.frequency_hz == pytest.approx(FN, rel=2e-4)
    assert r.damping_ratio == pytest.approx(ZETA, rel=0.015)
    # the same track through a single-mode fit with a constant + linear background only
    monkeypatch.setattr(finder, "_RESIDUAL_TERMS", "cl")
    monkeypatch.setattr(finder, "_RESIDUAL_REACH", 3.0)
    old = _weak_mode(find_resonances(track))
    err_new = abs(r.frequency_hz / FN - 1.0)
    err_old = abs(old.frequency_hz / FN - 1.0)
    assert err_old > 5.0 * err_new
    assert abs(old.damping_ratio / ZETA - 1.0) > 2.0 * abs(r.damping_ratio / ZETA - 1.0)


def test_isolated_mode_stays_exact():
    """Residual terms do not disturb an isolated SDOF: the fit stays exact (closed form)."""
    rpm = np.linspace(200.0, 760.0, 1401)
    f = ORDER * rpm / 60.0
    comp = 1e-3 * _receptance(f, FN, ZETA) * np.exp(-1.1j)
    track = xr.Dataset({"amplitude": (("order", "rpm"), np.abs(comp)[None], {"units": "rad"}),
                        "phase": (("order", "rpm"), np.angle(comp)[None], {"units": "rad"})},
                       coords={"order": [ORDER], "rpm": ("rpm", rpm)})
    r = find_resonances(track).resonances[0]
    assert r.frequency_hz == pytest.approx(FN, rel=1e-7)
    assert r.damping_ratio == pytest.approx(ZETA, rel=1e-6)
    # the amplitude peak of a receptance: 1/(2ζ√(1 − ζ²)) at ν = √(1 − 2ζ²)
    assert r.amplitude == pytest.approx(1e-3 / (2 * ZETA * np.sqrt(1 - ZETA**2)), rel=1e-4)


def test_peak_near_the_end_of_the_run_uses_the_edge_model():
    """A peak with under three half-widths of data on one side keeps the constant + linear
    background over ±3 half-widths (a one-sided window cannot separate the residual terms);
    it is still found at its closed-form pole."""
    rpm = np.linspace(200.0, 570.0, 1001)  # ends 5.6 % above the 540 rpm critical
    track = _track(rpm)
    r = _weak_mode(find_resonances(track))
    assert r.frequency_hz == pytest.approx(FN, rel=2e-3)
