"""Crankshaft fillet and oil-bore stress-concentration factors from the throw's geometry, and
the fillet stresses and fatigue strength of the classification rule that carries them.

The empirical formulas are those of IACS UR M53 "Calculation of crankshafts for I.C. engines"
§3 (FVV strain-gauge investigations for the fillets, ESDU for the oil hole), read in the text
of the Korean Register's *Rules for the Classification of Steel Ships*, Guidance RA-05-E
(2025), Part 5 Annex 5-3 "Guidance for Calculation of Crankshaft Stress", which reproduces the
rule (§3 (1)-(3); symbols of its Fig. 5). Dimensions are related to the crank-pin diameter D::

    r = R_H/D (pin fillet) or R_G/D (journal fillet)   0.03 ≤ r ≤ 0.13
    s = S/D, S = (D + D_G)/2 − E (pin overlap)          s ≤ 0.5
    w = W/D (web thickness)                             0.2 ≤ w ≤ 0.8
    b = B/D (web width)                                 1.1 ≤ b ≤ 2.2
    d_O = D_O/D (oil bore)                              0 ≤ d_O ≤ 0.2
    d_G = D_BG/D, d_H = D_BH/D (journal, pin bores)      0 ≤ d ≤ 0.8
    t_H = T_H/D, t_G = T_G/D (fillet recesses)

s may be extended to large negative values (no overlap): f(recess) is then not taken below 1
and f(s, w), f(r, s) are evaluated with s = −0.5 when s < −0.5 (§3 (1)(H)). The text names
only f(s, w) and f(r, s); the journal's f_B(s, w) and f_Q(s) are frozen the same way here (an
interpretation: f_Q(s) would turn negative below s ≈ −0.58). For 2-stroke
semi-built crankshafts with T_H > R_H the web thickness is W_red = W − (T_H − R_H) (§3 (1)(G));
their journal fillets are outside the formulas.

Crank-pin fillet (§3 (2))::

    α_B = 2.6914 f(s,w) f(w) f(b) f(r) f(d_G) f(d_H) f(recess)
    f(s,w) = −4.1883 + 29.2004 w − 77.5925 w² + 91.9454 w³ − 40.0416 w⁴
             + (1−s)(9.5440 − 58.3480 w + 159.3415 w² − 192.5846 w³ + 85.2916 w⁴)
             + (1−s)²(−3.8399 + 25.0444 w − 70.5571 w² + 87.0328 w³ − 39.1832 w⁴)
    f(w) = 2.1790 w^0.7171            f(b) = 0.6840 − 0.0077 b + 0.1473 b²
    f(r) = 0.2081 r^−0.5231
    f(d_G) = 0.9993 + 0.27 d_G − 1.0211 d_G² + 0.5306 d_G³
    f(d_H) = 0.9978 + 0.3145 d_H − 1.5241 d_H² + 2.4147 d_H³
    f(recess) = 1 + (t_H + t_G)(1.8 + 3.2 s)
    α_T = 0.8 f(r,s) f(b) f(w),  f(r,s) = r^(−0.322 + 0.1015 (1−s)),
    f(b) = 7.8955 − 10.654 b + 5.3482 b² − 0.85 b³,  f(w) = w^−0.145

Journal fillet (§3 (3), solid cranks)::

    β_B = 2.7146 f_B(s,w) f_B(w) f_B(b) f_B(r) f_B(d_G) f_B(d_H) f(recess)
    f_B(s,w) = −1.7625 + 2.9821 w − 1.527 w² + (1−s)(5.1169 − 5.8089 w + 3.1391 w²)
               + (1−s)²(−2.1567 + 2.3297 w − 1.2952 w²)
    f_B(w) = 2.2422 w^0.7548     f_B(b) = 0.5616 + 0.1197 b + 0.1176 b²
    f_B(r) = 0.1908 r^−0.5568    f_B(d_G) = 1.0012 − 0.6441 d_G + 1.2265 d_G²
    f_B(d_H) = 1.0022 − 0.1903 d_H + 0.0073 d_H²
    β_Q = 3.0128 f_Q(s) f_Q(w) f_Q(b) f_Q(r) f_Q(d_H) f(recess)
    f_Q(s) = 0.4368 + 2.1630 (1−s) − 1.5212 (1−s)²   f_Q(w) = w/(0.0637 + 0.9369 w)
    f_Q(b) = −0.5 + b   f_Q(r) = 0.5331 r^−0.2038   f_Q(d_H) = 0.9937 − 1.1949 d_H + 1.7373 d_H²
    β_T = α_T's formula with r = R_G/D_G (= α_T when pin and journal diameters and radii agree)

Oil-bore outlet (§3 (4)): γ_B = 3 − 5.88 d_O + 34.6 d_O², γ_T = 4 − 6 d_O + 30 d_O² (→ 3 and 4,
Kirsch's hole in a plate under tension and under shear, as d_O → 0).

Definitions (§3 (1)(B)-(E)): α_B, β_B relate the largest von Mises fillet stress to the nominal
bending stress of the *web* section (W_eqw = B W²/6), β_Q the von Mises stress from the radial
force to its nominal compressive stress over B·W, α_T, β_T the largest equivalent shear stress
to the nominal torsional stress of the (bored) pin or journal, γ the largest principal stress
at the oil-bore outlet to the nominal pin stress.

Transcription note: the readable text prints the cubic coefficient of α_T's f(b) as 0.85;
other transcriptions are quoted with 0.857. IACS's own text and a second class society's
transcription (IRS Classification Notes 2012, LR Naval Ship Rules Vol 2 Pt 2 Ch 1 §3.8) were
found but their §3 formulas could not be read through the search tool, so the choice is not
settled by a source. 0.85 is kept because it is the conservative one: 0.857 lowers f(b), and
α_T, by 0.007 b³/f(b) — 2.2 % at b = 1.5, 5.8 % at b = 2.2 (test_crankshaft_m53.py).
No worked example with published factor values was found either; the tests check the
formulas' limits and continuity (γ → Kirsch, β_T = α_T for equal pin and journal, the
normalisation f(d) → 1 at d = 0) and the validity-range refusals.

References
----------
.. [1] IACS UR M53, *Calculation of crankshafts for I.C. engines*, §2-§6 (via [2]).
.. [2] Korean Register, *Rules for the Classification of Steel Ships*, Guidance RA-05-E, 2025,
   Part 5 Annex 5-3, §2 (nominal stresses), §3 (stress-concentration factors), §4 (additional
   bending stresses), §5 (equivalent alternating stress), §6 (fatigue strength).
.. [3] G. Kirsch, "Die Theorie der Elastizität und die Bedürfnisse der Festigkeitslehre",
   Z. VDI 42 (1898) 797-807 (circular hole: K_t = 3 in tension, 4 in pure shear).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_nonnegative, check_option, check_positive
from .errors import ModelError

__all__ = ["FilletGeometry", "StressConcentration", "stress_concentration_factors",
           "m53_fillet_stresses", "m53_fatigue_strength", "fillet_geometry_from_toml",
           "M53_RANGES", "ADDITIONAL_BENDING"]

log = logging.getLogger("crankbench")

#: validity ranges of the empirical formulas (§3 (1)(G)); s has no lower bound (§3 (1)(H))
M53_RANGES = {"r_pin": (0.03, 0.13), "r_journal": (0.03, 0.13), "s": (-np.inf, 0.5),
              "w": (0.2, 0.8), "b": (1.1, 2.2), "d_o": (0.0, 0.2), "d_g": (0.0, 0.8),
              "d_h": (0.0, 0.8)}

#: keys of ``[crankshaft.fillets]`` read by :func:`predict.crankshaft_m53.m53_from_toml`
M53_KEYS = ("tensile_strength", "web_centre_distance", "oil_bore_angle_deg", "fatigue_factor",
            "engine_type", "alternating_torque")

#: additional bending stress σ_add (axial vibration, misalignment), Pa (§4 table)
ADDITIONAL_BENDING = {"crosshead": 30.0e6, "trunk": 10.0e6}

_SOURCE = ("IACS UR M53 §3 empirical formulas (as reproduced in KR Rules RA-05-E 2025, "
           "Pt 5 Annex 5-3)")


@dataclass(frozen=True)
class FilletGeometry:
    """Dimensions of one crank throw for the fillet factors, m (symbols of UR M53 Fig. 5).

    Parameters
    ----------
    pin_diameter : float
        D.
    journal_diameter : float
        D_G.
    crank_radius : float
        E, the pin eccentricity (half the stroke).
    web_thickness, web_width : float
        W (along the shaft) and B (across it, taken in way of the pin fillet's centre).
    pin_fillet_radius, journal_fillet_radius : float
        R_H, R_G.
    pin_bore, journal_bore : float
        D_BH, D_BG (0 = solid).
    pin_recess, journal_recess : float
        T_H, T_G: depth of the fillet recess into the web (0 = none).
    oil_bore : float
        D_O, radial oil hole in the pin (0 = none).
    semi_built : bool
        Semi-built crankshaft (shrunk journals): no journal-fillet factors; with T_H > R_H
        the web thickness is reduced to W − (T_H − R_H).

    Examples
    --------
    >>> g = FilletGeometry(pin_diameter=0.30, journal_diameter=0.30, crank_radius=0.20,
    ...                    web_thickness=0.12, web_width=0.45, pin_fillet_radius=0.015,
    ...                    journal_fillet_radius=0.015)
    >>> round(g.overlap, 3)
    0.1
    """

    pin_diameter: float
    journal_diameter: float
    crank_radius: float
    web_thickness: float
    web_width: float
    pin_fillet_radius: float
    journal_fillet_radius: float
    pin_bore: float = 0.0
    journal_bore: float = 0.0
    pin_recess: float = 0.0
    journal_recess: float = 0.0
    oil_bore: float = 0.0
    semi_built: bool = False

    def __post_init__(self):
        for name in ("pin_diameter", "journal_diameter", "crank_radius", "web_thickness",
                     "web_width", "pin_fillet_radius", "journal_fillet_radius"):
            object.__setattr__(self, name, check_positive(getattr(self, name), name,
                                                          error=ModelError))
        for name in ("pin_bore", "journal_bore", "pin_recess", "journal_recess", "oil_bore"):
            object.__setattr__(self, name, check_nonnegative(getattr(self, name), name,
                                                             error=ModelError))
        for bore, outer in (("pin_bore", "pin_diameter"), ("journal_bore", "journal_diameter"),
                            ("oil_bore", "pin_diameter")):
            if getattr(self, bore) >= getattr(self, outer):
                raise ModelError(f"{bore}={getattr(self, bore)!r} must be smaller than "
                                 f"{outer}={getattr(self, outer)!r}")
        if not isinstance(self.semi_built, (bool, np.bool_)):
            raise ModelError(f"semi_built={self.semi_built!r} must be true or false")

    @property
    def overlap(self) -> float:
        """Pin overlap S = (D + D_G)/2 − E, m (negative: no overlap)."""
        return 0.5 * (self.pin_diameter + self.journal_diameter) - self.crank_radius

    @property
    def effective_web_thickness(self) -> float:
        """W, or W_red = W − (T_H − R_H) for a semi-built crank with T_H > R_H, m."""
        if self.semi_built and self.pin_recess > self.pin_fillet_radius:
            return self.web_thickness - (self.pin_recess - self.pin_fillet_radius)
        return self.web_thickness

    def parameters(self) -> dict:
        """The dimensionless throw parameters of UR M53 §3 (1)(G)."""
        d = self.pin_diameter
        return dict(r_pin=self.pin_fillet_radius / d, r_journal=self.journal_fillet_radius / d,
                    r_journal_own=self.journal_fillet_radius / self.journal_diameter,
                    s=self.overlap / d, w=self.effective_web_thickness / d,
                    b=self.web_width / d, d_o=self.oil_bore / d, d_g=self.journal_bore / d,
                    d_h=self.pin_bore / d, t_h=self.pin_recess / d,
                    t_g=self.journal_recess / d)


@dataclass(frozen=True)
class StressConcentration:
    """Fillet and oil-bore stress-concentration factors of one throw (UR M53 §3).

    Attributes
    ----------
    alpha_b, alpha_t : float
        Crank-pin fillet, bending (web basis) and torsion (pin basis).
    beta_b, beta_q, beta_t : float
        Journal fillet, bending, radial-force compression (web basis) and torsion (journal
        basis); NaN for a semi-built crankshaft.
    gamma_b, gamma_t : float
        Oil-bore outlet, bending and torsion (pin basis); NaN without an oil bore.
    parameters : dict
        The dimensionless throw parameters used.
    within_validity : bool
    violations : tuple of str
        Parameters outside the formulas' range (only with ``extrapolate=True``).
    geometry : FilletGeometry
    source : str
    """

    alpha_b: float
    alpha_t: float
    beta_b: float
    beta_q: float
    beta_t: float
    gamma_b: float
    gamma_t: float
    parameters: dict
    within_validity: bool
    violations: tuple
    geometry: FilletGeometry
    source: str = _SOURCE

    def to_frame(self):
        """One row per factor: name, value, location, load, nominal-stress basis."""
        import pandas as pd

        rows = [("alpha_b", self.alpha_b, "pin fillet", "bending", "web B·W²/6"),
                ("alpha_t", self.alpha_t, "pin fillet", "torsion", "pin polar modulus"),
                ("beta_b", self.beta_b, "journal fillet", "bending", "web B·W²/6"),
                ("beta_q", self.beta_q, "journal fillet", "radial force", "web B·W"),
                ("beta_t", self.beta_t, "journal fillet", "torsion", "journal polar modulus"),
                ("gamma_b", self.gamma_b, "oil bore", "bending", "pin section modulus"),
                ("gamma_t", self.gamma_t, "oil bore", "torsion", "pin polar modulus")]
        frame = pd.DataFrame(rows, columns=["factor", "value", "location", "load", "basis"])
        frame.attrs.update(source=self.source, within_validity=self.within_validity)
        return frame

    def plot(self, ax=None):
        """Bar chart of the factors; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        f = self.to_frame()
        ax.bar(f["factor"], f["value"])
        ax.set_ylabel("stress-concentration factor")
        ax.set_title("UR M53 empirical factors" + ("" if self.within_validity else
                                                    " (extrapolated)"))
        return fig


def _alpha_t(r, s, b, w):
    f_rs = r ** (-0.322 + 0.1015 * (1 - s))
    f_b = 7.8955 - 10.654 * b + 5.3482 * b ** 2 - 0.85 * b ** 3
    return 0.8 * f_rs * f_b * w ** -0.145


def stress_concentration_factors(geometry: FilletGeometry, *,
                                 extrapolate: bool = False) -> StressConcentration:
    """Fillet and oil-bore stress-concentration factors by the UR M53 empirical formulas.

    Parameters
    ----------
    geometry : FilletGeometry
    extrapolate : bool
        Outside the formulas' ranges (module docstring) the rule asks for measurements or a
        finite-element evaluation (its Appendix III), and this function refuses; True
        evaluates the formulas anyway, with ``within_validity=False`` and a logged warning.

    Returns
    -------
    StressConcentration

    Raises
    ------
    ModelError
        A parameter is outside its range (naming it, its value and the range).

    References
    ----------
    IACS UR M53 §3 (as reproduced in KR Rules RA-05-E 2025, Pt 5 Annex 5-3 §3).

    Examples
    --------
    >>> g = FilletGeometry(pin_diameter=0.30, journal_diameter=0.30, crank_radius=0.20,
    ...                    web_thickness=0.12, web_width=0.45, pin_fillet_radius=0.015,
    ...                    journal_fillet_radius=0.015, oil_bore=0.03)
    >>> k = stress_concentration_factors(g)
    >>> print(round(k.alpha_b, 3), round(k.alpha_t, 3), round(k.beta_b, 3), round(k.beta_q, 3))
    2.224 2.112 2.323 3.225
    >>> print(round(k.gamma_b, 3), round(k.gamma_t, 3), k.beta_t == k.alpha_t)
    2.758 3.7 True
    """
    if not isinstance(geometry, FilletGeometry):
        raise ModelError(f"geometry must be a FilletGeometry, got {type(geometry).__name__}")
    p = geometry.parameters()
    checked = dict(p)
    checked["r_journal"] = p["r_journal_own"] if geometry.semi_built else p["r_journal"]
    violations = []
    for key, (lo, hi) in M53_RANGES.items():
        if key == "r_journal" and geometry.semi_built:
            continue
        if key == "d_g" and geometry.semi_built:
            continue
        v = checked[key]
        if not lo <= v <= hi:
            violations.append(f"{key} = {v:.4g} outside [{lo:g}, {hi:g}]")
    if violations and not extrapolate:
        raise ModelError("stress_concentration_factors: the throw is outside the range of the "
                         "UR M53 empirical formulas (" + "; ".join(violations) + "); the rule "
                         "then asks for measured or finite-element factors (pass "
                         "extrapolate=True to evaluate the formulas anyway)")
    if violations:
        log.warning("stress_concentration_factors: extrapolating the UR M53 formulas: %s",
                    "; ".join(violations))
    s_raw, w, b = p["s"], p["w"], p["b"]
    s = max(s_raw, -0.5)                      # f(s,w), f(r,s) at s = −0.5 below it (§3 (1)(H))
    u = 1.0 - s
    recess = max(1.0, 1.0 + (p["t_h"] + p["t_g"]) * (1.8 + 3.2 * s_raw))
    dg, dh = p["d_g"], p["d_h"]
    # crank-pin fillet, bending (§3 (2)(A))
    f_sw = (-4.1883 + 29.2004 * w - 77.5925 * w ** 2 + 91.9454 * w ** 3 - 40.0416 * w ** 4
            + u * (9.5440 - 58.3480 * w + 159.3415 * w ** 2 - 192.5846 * w ** 3
                   + 85.2916 * w ** 4)
            + u * u * (-3.8399 + 25.0444 * w - 70.5571 * w ** 2 + 87.0328 * w ** 3
                       - 39.1832 * w ** 4))
    alpha_b = (2.6914 * f_sw * 2.1790 * w ** 0.7171 * (0.6840 - 0.0077 * b + 0.1473 * b * b)
               * 0.2081 * p["r_pin"] ** -0.5231
               * (0.9993 + 0.27 * dg - 1.0211 * dg ** 2 + 0.5306 * dg ** 3)
               * (0.9978 + 0.3145 * dh - 1.5241 * dh ** 2 + 2.4147 * dh ** 3) * recess)
    alpha_t = _alpha_t(p["r_pin"], s, b, w)
    if geometry.semi_built:
        beta_b = beta_q = beta_t = float("nan")
    else:
        rj = p["r_journal"]
        fb_sw = (-1.7625 + 2.9821 * w - 1.527 * w ** 2 + u * (5.1169 - 5.8089 * w + 3.1391 * w ** 2)
                 + u * u * (-2.1567 + 2.3297 * w - 1.2952 * w ** 2))
        beta_b = (2.7146 * fb_sw * 2.2422 * w ** 0.7548 * (0.5616 + 0.1197 * b + 0.1176 * b * b)
                  * 0.1908 * rj ** -0.5568 * (1.0012 - 0.6441 * dg + 1.2265 * dg ** 2)
                  * (1.0022 - 0.1903 * dh + 0.0073 * dh ** 2) * recess)
        beta_q = (3.0128 * (0.4368 + 2.1630 * u - 1.5212 * u * u) * (w / (0.0637 + 0.9369 * w))
                  * (b - 0.5) * 0.5331 * rj ** -0.2038 * (0.9937 - 1.1949 * dh + 1.7373 * dh ** 2)
                  * recess)
        same = (np.isclose(geometry.pin_diameter, geometry.journal_diameter, rtol=1e-12)
                and np.isclose(geometry.pin_fillet_radius, geometry.journal_fillet_radius,
                               rtol=1e-12))
        beta_t = alpha_t if same else _alpha_t(p["r_journal_own"], s, b, w)
    d_o = p["d_o"]
    if geometry.oil_bore > 0:
        gamma_b = 3.0 - 5.88 * d_o + 34.6 * d_o ** 2
        gamma_t = 4.0 - 6.0 * d_o + 30.0 * d_o ** 2
    else:
        gamma_b = gamma_t = float("nan")
    return StressConcentration(alpha_b=float(alpha_b), alpha_t=float(alpha_t),
                               beta_b=float(beta_b), beta_q=float(beta_q), beta_t=float(beta_t),
                               gamma_b=float(gamma_b), gamma_t=float(gamma_t), parameters=p,
                               within_validity=not violations, violations=tuple(violations),
                               geometry=geometry)


def m53_fillet_stresses(scf: StressConcentration, *, bending_moment, radial_force, torque,
                        cycle=4, engine_type="trunk", additional_bending=None) -> dict:
    """Alternating fillet stresses and their von Mises equivalent per UR M53 §2, §4, §5.

    Parameters
    ----------
    scf : StressConcentration
        Factors and geometry of the throw.
    bending_moment : array_like
        M_BRF, bending moment from the radial force at the web centre over one working cycle
        (statically determinate throw between the main-bearing midpoints), N·m.
    radial_force : array_like
        Q_RF, radial force in the web over the same cycle, N.
    torque : array_like
        Torque through the throw over a cycle (from the forced-vibration synthesis), N·m;
        its half range is the nominal alternating torque M_TN.
    cycle : {4, 2}
        Strokes per cycle: sets the empirical factor K_e (1.0 for 4-stroke, 0.8 for 2-stroke)
        on the web stresses (§2 (1)(B)(b)).
    engine_type : {"trunk", "crosshead"}
        Sets the additional bending stress σ_add (±10 or ±30 MPa, §4).
    additional_bending : float, optional
        σ_add, Pa, overriding ``engine_type`` (e.g. from an axial-vibration calculation).

    Returns
    -------
    dict
        Pa: ``sigma_bfn``, ``sigma_qfn`` (nominal web bending and compression), ``tau_n_pin``,
        ``tau_n_journal``, ``sigma_bh`` = α_B σ_BFN, ``tau_h`` = α_T τ_N, ``sigma_bg`` =
        β_B σ_BFN + β_Q σ_QFN, ``tau_g`` = β_T τ_N, ``sigma_add``, ``equivalent_pin`` =
        √((σ_BH + σ_add)² + 3 τ_H²) and ``equivalent_journal`` (NaN for semi-built cranks).

    Examples
    --------
    >>> g = FilletGeometry(pin_diameter=0.30, journal_diameter=0.30, crank_radius=0.20,
    ...                    web_thickness=0.12, web_width=0.45, pin_fillet_radius=0.015,
    ...                    journal_fillet_radius=0.015)
    >>> k = stress_concentration_factors(g)
    >>> r = m53_fillet_stresses(k, bending_moment=[-2.0e4, 6.0e4], radial_force=[-1e5, 3e5],
    ...                         torque=[-3.0e4, 3.0e4])
    >>> round(r["sigma_bfn"] / 1e6, 3), round(r["equivalent_pin"] / 1e6, 2)
    (37.037, 94.67)
    """
    geo = scf.geometry
    m = check_finite_array(bending_moment, "bending_moment", error=ModelError)
    q = check_finite_array(radial_force, "radial_force", error=ModelError)
    t = check_finite_array(torque, "torque", error=ModelError)
    cycle = check_option(cycle, "cycle", (4, 2), error=ModelError)
    ke = 1.0 if cycle == 4 else 0.8
    if additional_bending is None:
        engine_type = check_option(engine_type, "engine_type", tuple(ADDITIONAL_BENDING),
                                   error=ModelError)
        s_add = ADDITIONAL_BENDING[engine_type]
    else:
        s_add = check_nonnegative(additional_bending, "additional_bending", error=ModelError)
    w, b = geo.effective_web_thickness, geo.web_width
    sigma_bfn = ke * np.ptp(m) / 2 / (b * w * w / 6)
    sigma_qfn = ke * np.ptp(q) / 2 / (b * w)
    mtn = np.ptp(t) / 2
    d, dh, dg, dbg = geo.pin_diameter, geo.pin_bore, geo.journal_diameter, geo.journal_bore
    tau_pin = mtn / (np.pi / 16 * (d ** 4 - dh ** 4) / d)
    tau_jnl = mtn / (np.pi / 16 * (dg ** 4 - dbg ** 4) / dg)
    sigma_bh = scf.alpha_b * sigma_bfn
    tau_h = scf.alpha_t * tau_pin
    sigma_bg = scf.beta_b * sigma_bfn + scf.beta_q * sigma_qfn
    tau_g = scf.beta_t * tau_jnl
    return dict(sigma_bfn=float(sigma_bfn), sigma_qfn=float(sigma_qfn),
                tau_n_pin=float(tau_pin), tau_n_journal=float(tau_jnl),
                sigma_bh=float(sigma_bh), tau_h=float(tau_h), sigma_bg=float(sigma_bg),
                tau_g=float(tau_g), sigma_add=float(s_add),
                equivalent_pin=float(np.hypot(sigma_bh + s_add, np.sqrt(3) * tau_h)),
                equivalent_journal=float(np.hypot(sigma_bg + s_add, np.sqrt(3) * tau_g)))


def m53_fatigue_strength(*, tensile_strength, diameter, fillet_radius, factor=1.0) -> float:
    """Fatigue strength of the crankshaft at a fillet or oil bore, UR M53 §6, Pa.

    ``σ_DW = K (0.42 σ_B + 39.3) [0.264 + 1.073 D^−0.2 + (785 − σ_B)/4900 + (196/σ_B)
    √(1/R_X)]`` in N/mm² with D and R_X in mm (R_X the fillet radius, or half the oil-bore
    diameter; not taken below 2 mm).

    Parameters
    ----------
    tensile_strength : float
        Minimum tensile strength σ_B of the crankshaft material, Pa.
    diameter : float
        Crank-pin (or journal) diameter, m.
    fillet_radius : float
        R_H, R_G or D_O/2, m.
    factor : float
        K: 1.05 continuous-grain-flow or drop forged, 1.0 free-form forged, 0.93 cast steel
        with approved cold rolling (values above 1 apply to fillets only).

    Examples
    --------
    >>> round(m53_fatigue_strength(tensile_strength=800e6, diameter=0.3,
    ...                            fillet_radius=0.015) / 1e6, 2)
    250.36
    """
    sb = check_positive(tensile_strength, "tensile_strength", error=ModelError) / 1e6
    d = check_positive(diameter, "diameter", error=ModelError) * 1e3
    rx = max(check_positive(fillet_radius, "fillet_radius", error=ModelError) * 1e3, 2.0)
    k = check_positive(factor, "factor", error=ModelError)
    val = k * (0.42 * sb + 39.3) * (0.264 + 1.073 * d ** -0.2 + (785 - sb) / 4900
                                     + 196 / sb * np.sqrt(1 / rx))
    return float(val * 1e6)


def fillet_geometry_from_toml(path) -> FilletGeometry:
    """Fillet geometry from the ``[crankshaft.fillets]`` table of a model file (m)::

        [crankshaft.fillets]
        pin_diameter = 0.30
        journal_diameter = 0.30
        crank_radius = 0.20          # default: the [engine]'s crank radius
        web_thickness = 0.12
        web_width = 0.45
        pin_fillet_radius = 0.015
        journal_fillet_radius = 0.015
        # pin_bore, journal_bore, pin_recess, journal_recess, oil_bore = 0; semi_built = false

    Examples
    --------
    >>> from pathlib import Path
    >>> p = Path(__file__).resolve().parents[1] / "sample_data/engines/i6.toml"
    >>> g = fillet_geometry_from_toml(p)
    >>> round(stress_concentration_factors(g).alpha_b, 3)
    2.439
    """
    from ._toml import load_toml

    doc = load_toml(path)
    ct = doc.table("crankshaft", None)
    t = None if ct is None else ct.table("fillets", None)
    if t is None:
        raise ModelError(f"{path}: has no [crankshaft.fillets] table (pin_diameter, "
                         "journal_diameter, web_thickness, web_width, pin_fillet_radius, "
                         "journal_fillet_radius)")
    radius = t.positive("crank_radius", None, unit="m", plausible=(1e-3, 3.0))
    if radius is None:
        if "engine" not in doc:
            t.fail("crank_radius", "is missing and the file has no [engine] table")
        from .engine import Engine

        radius = Engine.from_toml(path).crank_radius
    kw = {k: t.positive(k, unit="m", plausible=(1e-4, 3.0))
          for k in ("pin_diameter", "journal_diameter", "web_thickness", "web_width",
                    "pin_fillet_radius", "journal_fillet_radius")}
    kw.update({k: t.number(k, 0.0, low=0.0, unit="m", plausible=(1e-5, 3.0))
               for k in ("pin_bore", "journal_bore", "pin_recess", "journal_recess",
                         "oil_bore")})
    semi = t.raw("semi_built", False)
    if not isinstance(semi, bool):
        t.fail("semi_built", f"= {semi!r} must be true or false")
    t.check_unknown(M53_KEYS)     # the rule's material and load keys: predict.crankshaft_m53
    try:
        return FilletGeometry(crank_radius=radius, semi_built=semi, **kw)
    except ModelError as exc:
        raise ModelError(f"{t.where()} {exc}") from None
