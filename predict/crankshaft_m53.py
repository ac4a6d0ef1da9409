"""IACS UR M53 acceptability of a crankshaft: equivalent alternating stress, fatigue strength
and the acceptability factor Q = σ_DW/σ_V at the crank-pin fillet, the journal fillet and the
outlet of the crank-pin oil bore.

The rule's chain (section numbers of UR M53 Rev.1 2004 and later; the same numbering in the
Indian Register's *Classification Notes: Calculation of Crankshafts for I.C. Engines*, 2012,
Sections 2-7, and in KR Guidance RA-05-E Pt 5 Annex 5-3)::

    §2   nominal alternating stresses   σ_BFN, σ_QFN (web), σ_BON (pin at the oil bore), τ_N
    §3   stress-concentration factors   α_B, α_T, β_B, β_Q, β_T, γ_B, γ_T
         (:func:`predict.crankshaft_scf.stress_concentration_factors`)
    §4   additional bending stress      σ_add = ±10 MPa trunk piston, ±30 MPa crosshead
    §5   equivalent alternating stress  fillets:   σ_V = √((σ_BH|G + σ_add)² + 3 τ_H|G²)
                                        oil bore:  σ_V = (σ_BO/3)[1 + 2 √(1 + (9/4)(τ_TO/σ_BO)²)]
    §6   fatigue strength               σ_DW (:func:`predict.crankshaft_scf.m53_fatigue_strength`;
                                        K > 1 only in the fillets)
    §7   acceptability                  Q = σ_DW/σ_V ≥ 1.15 at every location

What was read and what was not. The fatigue-strength formula of §6 and its K values were read
in the Indian Register's Classification Notes (2012), Section 6 (page 25 of its transcription
on yumpu.com), and agree with the code. The section structure (§5 equivalent alternating
stress, §6 fatigue strength, §7 acceptability criteria) was read in the table of contents of
UR M53 Rev.1 (Dec 2004) and of the IRS notes. The two §5 formulas and the §7 minimum
Q ≥ 1.15 could not be read in any text the search tool returned: they are the rule's as stated
in the task and as commonly quoted (the oil-bore formula is checked below against its own
limits). The tests therefore check them by closed forms — pure bending gives σ_V = σ_B
(fillet, without σ_add) and σ_V = σ_BO (oil bore), pure torsion σ_V = √3 τ (fillet, von
Mises) and σ_V = τ_TO (oil bore, the principal stress of pure shear) — by hand calculation
and by monotony, not against a published worked example (none with its inputs was found).

The oil-bore formula is not the largest principal stress σ/2 + √(σ²/4 + τ²) of the outlet's
(σ, τ) state: both agree at τ = 0 and σ = 0; in between the rule's value is lower by up to
5.2 % of it (at τ/σ ≈ 1.2 — an empirical fit of the oil-bore fatigue tests, used as printed).

Sign and angle conventions: ``oil_bore_angle_deg`` is the rule's ψ (UR M53 §2.1.2.2, Fig. 4):
the bending moment at the outlet is M_BO = M_BTO cos ψ + M_BRO sin ψ, with M_BRO the bending
moment of the radial force at the pin centre (:attr:`BearingLoads.pin_moment_radial`) and
M_BTO that of the tangential force. ψ = 90° puts the outlet where the radial bending peaks.

References
----------
.. [1] IACS UR M53, *Calculation of crankshafts for I.C. engines*, Rev.1 (2004), §2, §4-§7.
.. [2] Indian Register of Shipping, *Classification Notes: Calculation of Crankshafts for
   Internal Combustion Engines*, January 2012, Sections 2-7 (a transcription of [1]).
.. [3] Korean Register, Guidance RA-05-E (2025), Pt 5 Annex 5-3 (the §3 factors,
   :mod:`predict.crankshaft_scf`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_nonnegative, check_positive
from .crankshaft_scf import StressConcentration, m53_fatigue_strength
from .errors import ModelError

__all__ = ["REQUIRED_Q", "CLAUSE", "fillet_equivalent_stress", "oil_bore_equivalent_stress",
           "m53_oil_bore_stresses", "M53Acceptance", "M53Assessment", "m53_acceptability",
           "m53_throw_assessment", "m53_from_toml"]

#: the rule's minimum acceptability factor (UR M53 §7)
REQUIRED_Q = 1.15
#: the clause every result names
CLAUSE = "IACS UR M53 §7: Q = σ_DW/σ_V ≥ 1.15"

LOCATIONS = ("crank-pin fillet", "journal fillet", "oil-bore outlet")


def fillet_equivalent_stress(*, bending, torsion, additional_bending=0.0):
    """Equivalent alternating (von Mises) stress in a fillet, UR M53 §5, Pa.

    ``σ_V = √((σ_B + σ_add)² + 3 τ²)``.

    Parameters
    ----------
    bending : float or array_like
        Alternating bending stress in the fillet σ_BH or σ_BG (with its SCF), Pa.
    torsion : float or array_like
        Alternating torsional stress in the fillet τ_H or τ_G (with its SCF), Pa.
    additional_bending : float
        σ_add, Pa (§4: 10 MPa trunk piston, 30 MPa crosshead engines).

    Returns
    -------
    float or ndarray
        σ_V, Pa.

    Examples
    --------
    >>> round(fillet_equivalent_stress(bending=80e6, torsion=30e6, additional_bending=10e6)
    ...       / 1e6, 3)
    103.923
    """
    b = np.asarray(bending, float)
    t = np.asarray(torsion, float)
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(t))):
        raise ModelError("fillet_equivalent_stress: bending and torsion must be finite (Pa)")
    add = check_nonnegative(additional_bending, "additional_bending", error=ModelError)
    out = np.sqrt((np.abs(b) + add) ** 2 + 3.0 * t * t)
    return float(out) if out.ndim == 0 else out


def oil_bore_equivalent_stress(*, bending, torsion):
    """Equivalent alternating stress at the outlet of the crank-pin oil bore, UR M53 §5, Pa.

    ``σ_V = (σ_BO/3) [1 + 2 √(1 + (9/4)(τ_TO/σ_BO)²)]``, written as
    ``σ_BO/3 + (2/3) √(σ_BO² + (9/4) τ_TO²)`` so that σ_BO = 0 (pure torsion) gives τ_TO.

    Parameters
    ----------
    bending : float or array_like
        σ_BO = γ_B σ_BON, alternating bending stress at the outlet (≥ 0, an amplitude), Pa.
    torsion : float or array_like
        τ_TO = γ_T τ_N, alternating torsional stress at the outlet, Pa.

    Returns
    -------
    float or ndarray
        σ_V, Pa.

    Examples
    --------
    >>> print(round(oil_bore_equivalent_stress(bending=90e6, torsion=0.0) / 1e6, 6),
    ...       round(oil_bore_equivalent_stress(bending=0.0, torsion=40e6) / 1e6, 6))
    90.0 40.0
    >>> round(oil_bore_equivalent_stress(bending=90e6, torsion=40e6) / 1e6, 3)
    102.111
    """
    b = np.abs(np.asarray(bending, float))
    t = np.abs(np.asarray(torsion, float))
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(t))):
        raise ModelError("oil_bore_equivalent_stress: bending and torsion must be finite (Pa)")
    out = b / 3.0 + 2.0 / 3.0 * np.sqrt(b * b + 2.25 * t * t)
    return float(out) if out.ndim == 0 else out


def m53_oil_bore_stresses(scf: StressConcentration, *, radial_moment, tangential_moment,
                          torque, oil_bore_angle_deg) -> dict:
    """Alternating stresses at the crank-pin oil-bore outlet, UR M53 §2.1.2.2, §2.2, §5.

    ``M_BO = M_BTO cos ψ + M_BRO sin ψ`` over the cycle; ``σ_BON = ±½ range(M_BO)/W_e`` with
    the pin's section modulus ``W_e = π (D⁴ − D_BH⁴)/(32 D)``; ``σ_BO = γ_B σ_BON``;
    ``τ_TO = γ_T τ_N`` with ``τ_N = ±½ range(T)/W_P`` (pin polar modulus).

    Parameters
    ----------
    scf : StressConcentration
        Factors and geometry of the throw (needs an oil bore).
    radial_moment, tangential_moment : array_like
        M_BRO and M_BTO, bending moments at the pin centre from the radial and the tangential
        force over one cycle, N·m (e.g. ``BearingLoads.pin_moment_radial`` and the tangential
        component, statically determinate model).
    torque : array_like
        Torque through the pin over the cycle, N·m.
    oil_bore_angle_deg : float
        ψ, deg (module docstring).

    Returns
    -------
    dict
        Pa: ``sigma_bon``, ``sigma_bo``, ``tau_n``, ``tau_to``, ``equivalent``.

    Examples
    --------
    >>> from crankbench.predict.crankshaft_scf import (FilletGeometry,
    ...                                                stress_concentration_factors)
    >>> g = FilletGeometry(pin_diameter=0.30, journal_diameter=0.30, crank_radius=0.20,
    ...                    web_thickness=0.12, web_width=0.45, pin_fillet_radius=0.015,
    ...                    journal_fillet_radius=0.015, oil_bore=0.03)
    >>> k = stress_concentration_factors(g)
    >>> r = m53_oil_bore_stresses(k, radial_moment=[-1e4, 5e4], tangential_moment=[0.0, 0.0],
    ...                           torque=[-3e4, 3e4], oil_bore_angle_deg=90.0)
    >>> print(round(r["sigma_bon"] / 1e6, 3), round(r["equivalent"] / 1e6, 2))
    11.318 39.92
    """
    if not isinstance(scf, StressConcentration):
        raise ModelError(f"scf must be a StressConcentration, got {type(scf).__name__}")
    geo = scf.geometry
    if geo.oil_bore <= 0:
        raise ModelError("m53_oil_bore_stresses: the throw has no oil bore (oil_bore = 0)")
    mr = check_finite_array(radial_moment, "radial_moment", error=ModelError)
    mt = check_finite_array(tangential_moment, "tangential_moment", error=ModelError)
    tq = check_finite_array(torque, "torque", error=ModelError)
    if mr.shape != mt.shape:
        raise ModelError(f"radial_moment {mr.shape} and tangential_moment {mt.shape} must have "
                         "the same shape (one value per crank angle)")
    psi = np.deg2rad(float(oil_bore_angle_deg))
    if not np.isfinite(psi):
        raise ModelError(f"oil_bore_angle_deg={oil_bore_angle_deg!r} must be finite")
    d, dh = geo.pin_diameter, geo.pin_bore
    m_bo = mt * np.cos(psi) + mr * np.sin(psi)
    w_e = np.pi * (d ** 4 - dh ** 4) / (32.0 * d)
    sigma_bon = np.ptp(m_bo) / 2.0 / w_e
    tau_n = np.ptp(tq) / 2.0 / (2.0 * w_e)
    sigma_bo = scf.gamma_b * sigma_bon
    tau_to = scf.gamma_t * tau_n
    return dict(sigma_bon=float(sigma_bon), sigma_bo=float(sigma_bo), tau_n=float(tau_n),
                tau_to=float(tau_to),
                equivalent=oil_bore_equivalent_stress(bending=sigma_bo, torsion=tau_to))


@dataclass(frozen=True)
class M53Acceptance:
    """The UR M53 acceptability of one location of one throw (plain data; an analysis-side
    :class:`crankbench.analysis.verdict.Verdict` wraps it).

    Attributes
    ----------
    location : str
        "crank-pin fillet", "journal fillet" or "oil-bore outlet".
    equivalent_stress : float
        σ_V, Pa.
    fatigue_strength : float
        σ_DW, Pa.
    q : float
        Acceptability factor σ_DW/σ_V.
    required : float
        The minimum Q (1.15).
    passed : bool or None
        True: Q ≥ required; False: Q < required (or Q without torsion already below it);
        None: inconclusive (``reason`` says why — factors extrapolated outside the formulas'
        range, or a torque without torsional vibration), Q still reported.
    clause : str
    reason : str
    """

    location: str
    equivalent_stress: float
    fatigue_strength: float
    q: float
    required: float
    passed: bool | None
    clause: str = CLAUSE
    reason: str = ""

    @property
    def status(self) -> str:
        """'pass', 'fail' or 'inconclusive'."""
        return {True: "pass", False: "fail", None: "inconclusive"}[self.passed]


@dataclass(frozen=True)
class M53Assessment:
    """UR M53 acceptability of a throw at every assessed location.

    Attributes
    ----------
    locations : tuple of M53Acceptance
    basis : str
        What the stresses rest on (loads, speed, torque source).
    """

    locations: tuple
    basis: str = ""

    @property
    def q_min(self) -> float:
        """Smallest acceptability factor over the locations."""
        return float(min(a.q for a in self.locations))

    @property
    def passed(self) -> bool | None:
        """False if any location fails; else None if any is inconclusive; else True."""
        states = [a.passed for a in self.locations]
        if False in states:
            return False
        return None if None in states else True

    @property
    def status(self) -> str:
        """'pass', 'fail' or 'inconclusive' over all locations."""
        return {True: "pass", False: "fail", None: "inconclusive"}[self.passed]

    def to_frame(self):
        """One row per location: σ_V and σ_DW in MPa, Q, required Q, status, reason."""
        import pandas as pd

        return pd.DataFrame([{"location": a.location,
                              "equivalent_stress_mpa": a.equivalent_stress / 1e6,
                              "fatigue_strength_mpa": a.fatigue_strength / 1e6, "q": a.q,
                              "required_q": a.required, "status": a.status,
                              "reason": a.reason} for a in self.locations])


def _judge(location, sigma_v, sigma_dw, required, doubts, torque_note="", sigma_v_bending=0.0):
    q = float(sigma_dw / sigma_v) if sigma_v > 0 else float("inf")
    if torque_note and not doubts:
        # σ_V grows with |τ|: Q without torsion bounds Q from above, whatever the torque
        q_up = float(sigma_dw / sigma_v_bending) if sigma_v_bending > 0 else float("inf")
        if q_up < required:
            return M53Acceptance(location, float(sigma_v), float(sigma_dw), q, required, False,
                                 reason=f"fails on bending alone (Q ≤ {q_up:.3f} with no "
                                        "torsion), whatever the torque")
        doubts = [torque_note]
    if doubts:
        return M53Acceptance(location, float(sigma_v), float(sigma_dw), q, required, None,
                             reason="; ".join(doubts))
    return M53Acceptance(location, float(sigma_v), float(sigma_dw), q, required,
                         bool(q >= required))


def m53_acceptability(scf: StressConcentration, *, fillet_stresses: dict, tensile_strength,
                      oil_bore_stresses: dict | None = None, factor=1.0,
                      required=REQUIRED_Q, torque_note: str = "",
                      basis: str = "") -> M53Assessment:
    """Acceptability factors Q = σ_DW/σ_V of UR M53 §7 at the fillets and the oil bore.

    Parameters
    ----------
    scf : StressConcentration
        Factors and geometry of the throw.
    fillet_stresses : dict
        :func:`predict.crankshaft_scf.m53_fillet_stresses` of the throw (σ_BH, τ_H, σ_BG, τ_G,
        σ_add in Pa).
    tensile_strength : float
        Minimum tensile strength σ_B of the crankshaft material, Pa.
    oil_bore_stresses : dict, optional
        :func:`m53_oil_bore_stresses` (None: the oil bore is not assessed).
    factor : float
        K of §6 (1.05 continuous grain flow or drop forged, 1.0 free-form forged, 0.93 cast
        steel cold rolled); values above 1 are applied to the fillets only.
    required : float
        Minimum Q (default 1.15, §7).
    torque_note : str
        If not empty, the torque is not the rule's (e.g. a rigid-shaft torque without
        torsional vibration): a location is then inconclusive with this reason, unless it
        fails on bending alone (σ_V grows with the torsional stress, so Q without torsion is
        an upper bound of Q whatever the torque).
    basis : str
        What the stresses rest on, carried into the result.

    Returns
    -------
    M53Assessment
        Crank-pin fillet (σ_DW on D, R_H), journal fillet (on D_G, R_G; solid cranks only),
        oil-bore outlet (on D, D_O/2, K ≤ 1). A location is inconclusive when its factors were
        extrapolated outside the formulas' range (the rule then asks for measured or FE
        factors).

    Examples
    --------
    >>> from crankbench.predict.crankshaft_scf import (FilletGeometry, m53_fillet_stresses,
    ...                                                stress_concentration_factors)
    >>> g = FilletGeometry(pin_diameter=0.30, journal_diameter=0.30, crank_radius=0.20,
    ...                    web_thickness=0.12, web_width=0.45, pin_fillet_radius=0.015,
    ...                    journal_fillet_radius=0.015)
    >>> k = stress_concentration_factors(g)
    >>> st = m53_fillet_stresses(k, bending_moment=[-2.0e4, 6.0e4], radial_force=[-1e5, 3e5],
    ...                          torque=[-3.0e4, 3.0e4])
    >>> a = m53_acceptability(k, fillet_stresses=st, tensile_strength=800e6)
    >>> print([round(x.q, 3) for x in a.locations], a.status)
    [2.644, 2.277] pass
    """
    if not isinstance(scf, StressConcentration):
        raise ModelError(f"scf must be a StressConcentration, got {type(scf).__name__}")
    for key in ("sigma_bh", "tau_h", "sigma_bg", "tau_g", "sigma_add"):
        if key not in fillet_stresses:
            raise ModelError(f"fillet_stresses has no {key!r}: pass the dict of "
                             "predict.crankshaft_scf.m53_fillet_stresses")
    check_positive(tensile_strength, "tensile_strength", error=ModelError)
    k = check_positive(factor, "factor", error=ModelError)
    req = check_positive(required, "required", error=ModelError)
    geo = scf.geometry
    doubts = []
    if not scf.within_validity:
        doubts.append("factors extrapolated outside the UR M53 formulas' range ("
                      + "; ".join(scf.violations) + "): the rule asks for measured or FE "
                      "factors")
    fs = fillet_stresses
    out = []
    sv = fillet_equivalent_stress(bending=fs["sigma_bh"], torsion=fs["tau_h"],
                                  additional_bending=fs["sigma_add"])
    dw = m53_fatigue_strength(tensile_strength=tensile_strength, diameter=geo.pin_diameter,
                              fillet_radius=geo.pin_fillet_radius, factor=k)
    out.append(_judge(LOCATIONS[0], sv, dw, req, doubts, torque_note,
                      abs(fs["sigma_bh"]) + fs["sigma_add"]))
    if not geo.semi_built:
        sv = fillet_equivalent_stress(bending=fs["sigma_bg"], torsion=fs["tau_g"],
                                      additional_bending=fs["sigma_add"])
        dw = m53_fatigue_strength(tensile_strength=tensile_strength,
                                  diameter=geo.journal_diameter,
                                  fillet_radius=geo.journal_fillet_radius, factor=k)
        out.append(_judge(LOCATIONS[1], sv, dw, req, doubts, torque_note,
                          abs(fs["sigma_bg"]) + fs["sigma_add"]))
    if oil_bore_stresses is not None:
        if "equivalent" not in oil_bore_stresses:
            raise ModelError("oil_bore_stresses has no 'equivalent': pass the dict of "
                             "m53_oil_bore_stresses")
        dw = m53_fatigue_strength(tensile_strength=tensile_strength, diameter=geo.pin_diameter,
                                  fillet_radius=geo.oil_bore / 2.0, factor=min(k, 1.0))
        out.append(_judge(LOCATIONS[2], oil_bore_stresses["equivalent"], dw, req, doubts,
                          torque_note, abs(oil_bore_stresses.get("sigma_bo", 0.0))))
    return M53Assessment(locations=tuple(out), basis=basis)


RIGID_TORQUE_NOTE = ("torque of the rigid shaft (gas and inertia, no torsional vibration); the "
                     "rule takes the alternating torque from the forced-vibration calculation: "
                     "give [crankshaft.fillets] alternating_torque (N·m)")


def m53_throw_assessment(engine, loads, cylinder, scf, *, web_centre_distance, tensile_strength,
                         factor=1.0, engine_type="trunk", oil_bore_angle_deg=None,
                         alternating_torque=None) -> M53Assessment:
    """UR M53 acceptability of one throw from the loads of a statically determinate beam.

    The web carries the larger of the two bearing shares of the pin force; its radial
    component is Q_RF and the web-centre bending moment M_BRF = Q_RF L1 (§2.1.1.1). The
    centrifugal force of the rotating mass is constant along the throw and leaves the
    alternating (half-range) values unchanged.

    Parameters
    ----------
    engine : Engine
    loads : BearingLoads
        From :func:`predict.crankshaft.bearing_loads` with ``model="determinate"``.
    cylinder : int
        1-based cylinder (throw) number.
    scf : StressConcentration
    web_centre_distance : float
        L1, main-bearing centre to web centre, m.
    tensile_strength : float
        σ_B, Pa.
    factor : float
        K of §6.
    engine_type : {"trunk", "crosshead"}
        σ_add (§4).
    oil_bore_angle_deg : float, optional
        ψ of the oil-bore outlet (module docstring); needed when the throw has an oil bore.
    alternating_torque : float, optional
        M_TN from the forced torsional vibration, N·m (amplitude). None: the rigid-shaft torque
        through the journal after the pin, and every location inconclusive.

    Returns
    -------
    M53Assessment

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.crankshaft import bearing_loads
    >>> from crankbench.predict.crankshaft_scf import (FilletGeometry,
    ...                                                stress_concentration_factors)
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.2, rod_length=0.8,
    ...            reciprocating_mass=300.0, cylinder_positions=[0.0])
    >>> bl = bearing_loads(e, omega=60.0, bearing_positions=[-0.4, 0.4], model="determinate",
    ...                    points=360)
    >>> k = stress_concentration_factors(FilletGeometry(
    ...     pin_diameter=0.30, journal_diameter=0.30, crank_radius=0.20, web_thickness=0.12,
    ...     web_width=0.45, pin_fillet_radius=0.015, journal_fillet_radius=0.015))
    >>> a = m53_throw_assessment(e, bl, 1, k, web_centre_distance=0.2, tensile_strength=800e6,
    ...                          alternating_torque=2.0e4)
    >>> print([round(x.q, 2) for x in a.locations], a.status)
    [6.22, 5.54] pass
    """
    from .crankshaft_scf import m53_fillet_stresses

    i = int(cylinder) - 1
    if not 0 <= i < engine.n_cylinders:
        raise ModelError(f"cylinder={cylinder!r} must be 1..{engine.n_cylinders}")
    if loads.model != "determinate":
        raise ModelError("m53_throw_assessment needs the statically determinate loads "
                         "(bearing_loads(..., model='determinate')), as UR M53 §2 prescribes")
    l1 = check_positive(web_centre_distance, "web_centre_distance", error=ModelError)
    zb = loads.bearing_positions
    z = engine.cylinder_positions[i]
    s = int(np.searchsorted(zb, z) - 1)
    span = zb[s + 1] - zb[s]
    a = z - zb[s]
    if l1 >= span:
        raise ModelError(f"web_centre_distance={l1!r} m must be shorter than the bearing span "
                         f"{span:g} m of cylinder {cylinder}")
    u = np.exp(1j * (engine.shaft_angle(loads.angle) + np.deg2rad(engine.crank_angles_deg[i])))
    f_radial = np.real(loads.pin_forces[:, i] * np.conj(u))
    q_rf = f_radial * max(a, span - a) / span
    mom = loads.pin_moments[:, i] * np.conj(u)
    if alternating_torque is None:
        torque, note = loads.journal_torque[:, s + 1], RIGID_TORQUE_NOTE
        basis_t = "rigid-shaft torque"
    else:
        m_tn = check_nonnegative(alternating_torque, "alternating_torque", error=ModelError)
        torque, note, basis_t = np.array([-m_tn, m_tn]), "", f"M_TN = {m_tn:g} N·m given"
    fs = m53_fillet_stresses(scf, bending_moment=q_rf * l1, radial_force=q_rf, torque=torque,
                             cycle=engine.cycle, engine_type=engine_type)
    ob = None
    if scf.geometry.oil_bore > 0:
        if oil_bore_angle_deg is None:
            raise ModelError("the throw has an oil bore: give oil_bore_angle_deg (ψ, deg, "
                             "UR M53 §2.1.2.2) to assess its outlet")
        ob = m53_oil_bore_stresses(scf, radial_moment=mom.real, tangential_moment=mom.imag,
                                   torque=torque, oil_bore_angle_deg=oil_bore_angle_deg)
    basis = (f"cylinder {cylinder}, statically determinate span {span:g} m, "
             f"{loads.omega * 30 / np.pi:g} rpm, {basis_t}")
    return m53_acceptability(scf, fillet_stresses=fs, tensile_strength=tensile_strength,
                             oil_bore_stresses=ob, factor=factor, torque_note=note, basis=basis)


def m53_from_toml(path, *, speed_rpm=None, points=720):
    """UR M53 acceptability of every throw of the engine in a model file.

    Reads ``[engine]`` (with ``[engine.combustion]`` for the gas forces), ``[crankshaft]``
    ``bearing_positions`` and ``[crankshaft.fillets]`` (geometry:
    :func:`predict.crankshaft_scf.fillet_geometry_from_toml`) with the rule's keys::

        [crankshaft.fillets]
        tensile_strength = "800 MPa"   # σ_B (Pa or a quantity string)
        web_centre_distance = 0.045    # L1, m
        oil_bore_angle_deg = 90        # ψ, with an oil bore
        fatigue_factor = 1.0           # K (1.05 grain-flow forged, 0.93 cast and rolled)
        engine_type = "trunk"          # or "crosshead" (σ_add)
        alternating_torque = 1.2e3     # M_TN, N·m, from the torsional vibration calculation

    Parameters
    ----------
    path : str or Path
    speed_rpm : float, optional
        Default the engine's ``rated_speed_rpm``.
    points : int
        Crank angles over the cycle.

    Returns
    -------
    dict
        ``throws``: one :class:`M53Assessment` per cylinder; ``worst``: the one with the
        smallest Q; ``scf``: the factors; ``speed_rpm``.

    Raises
    ------
    ModelError
        A missing key, naming it and its unit.

    Examples
    --------
    >>> from pathlib import Path
    >>> p = Path(__file__).resolve().parents[1] / "sample_data/engines/i6.toml"
    >>> r = m53_from_toml(p, points=240)
    >>> print(r["worst"].status, round(r["worst"].q_min, 2))
    fail 0.87
    """
    from ._toml import load_toml
    from .crankshaft import bearing_loads
    from .crankshaft_scf import fillet_geometry_from_toml, stress_concentration_factors
    from .engine import Engine
    from .pressure import synthetic_pressure

    geometry = fillet_geometry_from_toml(path)
    doc = load_toml(path)
    ct = doc.table("crankshaft")
    t = ct.table("fillets")
    sb = t.positive("tensile_strength", unit="Pa", plausible=(2e8, 2.5e9))
    l1 = t.positive("web_centre_distance", unit="m", plausible=(1e-3, 3.0))
    psi = (t.number("oil_bore_angle_deg", None, unit="deg") if geometry.oil_bore > 0
           else None)
    if geometry.oil_bore > 0 and psi is None:
        t.fail("oil_bore_angle_deg", "is missing: the throw has an oil bore (ψ, deg, "
               "UR M53 §2.1.2.2)")
    k = t.positive("fatigue_factor", 1.0, unit="1", plausible=(0.8, 1.2))
    kind = t.string("engine_type", "trunk", options=("trunk", "crosshead"))
    m_tn = t.number("alternating_torque", None, low=0.0, unit="N*m")
    positions = ct.numbers("bearing_positions", unit="m", plausible=(1e-4, 100.0))
    engine = Engine.from_toml(path)
    rpm = engine.rated_speed_rpm if speed_rpm is None else check_positive(
        speed_rpm, "speed_rpm", error=ModelError)
    if rpm is None:
        raise ModelError(f"{path}: [engine] has no rated_speed_rpm; give speed_rpm")
    pressure = (synthetic_pressure(engine) if engine.bore is not None
                and engine.compression_ratio is not None else None)
    scf = stress_concentration_factors(geometry, extrapolate=True)
    try:
        loads = bearing_loads(engine, omega=rpm * np.pi / 30, bearing_positions=positions,
                              pressure=pressure, model="determinate", points=points)
        throws = [m53_throw_assessment(engine, loads, c + 1, scf, web_centre_distance=l1,
                                       tensile_strength=sb, factor=k, engine_type=kind,
                                       oil_bore_angle_deg=psi, alternating_torque=m_tn)
                  for c in range(engine.n_cylinders)]
    except ModelError as exc:
        raise ModelError(f"{t.where()} {exc}") from None
    worst = min(throws, key=lambda a: a.q_min)
    return dict(throws=throws, worst=worst, scf=scf, speed_rpm=float(rpm))
