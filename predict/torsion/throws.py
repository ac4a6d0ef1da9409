"""Crank-throw torsional stiffness from the throw's dimensions, and shafts with distributed
inertia.

Crank throw
-----------
One throw (half a main journal, a web, the crank pin, the other web and the other half journal)
is the spring between two adjacent cylinder masses of the equivalent system. Its stiffness is
written as an *equivalent length* ``L_e`` of plain shaft of a reference diameter ``D_ref``
(default the journal diameter): ``k = G π D_ref⁴ / (32 L_e)``. The classical empirical
formulas (symbols: journal diameter D_j and bore d_j, journal length l_j — the bearing length
of one main journal —, pin diameter D_p, bore d_p and length l_p, web thickness h along the
shaft, web width b across it, crank radius R; every term scaled by D_ref⁴)::

    Carter (1928):   L_e = (l_j + 0.8 h)·D⁴/(D_j⁴ − d_j⁴) + 0.75 l_p·D⁴/(D_p⁴ − d_p⁴)
                           + 1.5 R·D⁴/(h b³)
    Ker Wilson:      L_e = (l_j + 0.4 D_j)·D⁴/(D_j⁴ − d_j⁴) + (l_p + 0.4 D_p)·D⁴/(D_p⁴ − d_p⁴)
                           + (R − 0.2 (D_j + D_p))·D⁴/(h b³)

Validity: both were fitted to crankshafts *without* overlap of pin and journal
(R ≥ (D_j + D_p)/2) and with webs wider than thick; for overlapped throws they over-estimate
the flexibility, and :func:`throw_stiffness` warns. ``uncertainty`` is ±15 %.

**Source status (read this before relying on the numbers).** The two formulas above were
written from memory of Ker Wilson vol. 1 ch. 3 and have *not* been checked against a printed
or otherwise readable copy of Carter (1928), Ker Wilson (1956), Tuplin or Nestorides (1958).
Two searches of the available public material (web pages, documentation, public code and
issue threads, in English, Chinese, Japanese, Korean, Russian, Polish and German; the second
in issue 18's follow-up) found only the title page and the start of the contents of
Nestorides' handbook (a scanned copy) and the title page and preface of Tuplin's *Vibration in
Machinery* (1940): no page giving any of the throw formulas, no reproduction of them, and no
published worked example or table of measured against formula stiffness. Every result of the two formulas therefore carries this in its ``note``.
For the same reason the Tuplin and BICERA (Nestorides 1958, with its overlap charts)
formulas are **not** implemented: ``method="tuplin"`` or ``"bicera"`` raises an error saying
so rather than returning an unchecked empirical formula.

**Second method.** ``method="fe"`` (:func:`predict.torsion.throw_fe.throw_stiffness_fe`) is a
3-D elastic finite-element model of the idealised throw these dimensions describe (sharp
corners, obround webs), with its discretisation error estimated; it is checked against the
closed form of a plain shaft, solid and bored, and holds for overlapped throws too. Against
it (tests/predict/test_throw_fe.py), in equivalent length, formula over FE minus one:

==============================================  ======  ======
throw (D_j, l_j, D_p, l_p, h, b, R; in D_j)     Carter  Wilson
==============================================  ======  ======
I6 sample (sample_data, D_j = 85 mm)            -8 %    +5 %
long stroke (1, .5, .95, .55, .45, 1.6, 1.35)   +3 %    +7 %
overlapped (1, .4, .9, .45, .3, 1.4, .65)       +3 %    +4 %
==============================================  ======  ======

The overlapped throw is outside both formulas' range and is flagged so. The ±15 %
``uncertainty`` thus holds against the idealised solid on these three throws: a check of order
of magnitude and form, not of the printed coefficients, and not against measured throws. A throw stiffness from the
engine maker, a finite-element model of the real drawing or a measurement should be
preferred (``stiffness =`` in the TOML).

Distributed inertia
-------------------
A heavy shaft is split into ``N`` equal elements with half an element's polar inertia at each
end (:func:`distributed_shaft`). The lumped chain carries waves with the exact dispersion
``ω = (2c/h) sin(κh/2)`` (h = L/N, c = √(G/ρ)), so every frequency of the shaft's own modes is
low by the factor ``sin x / x``, x = ω L / (2 N c): a relative error ``≈ x²/6``
(:func:`lumping_error`), checked against the exact uniform-shaft closed forms.

References
----------
.. [1] B. C. Carter, "An empirical formula for crankshaft stiffness in torsion",
   *Engineering* 126 (1928) 36.
.. [2] W. Ker Wilson, *Practical Solution of Torsional Vibration Problems*, vol. 1, 3rd ed.,
   Chapman & Hall, 1956, ch. 3 (stiffness of crankshafts: Carter's and Wilson's formulas).
.. [3] E. J. Nestorides, *A Handbook on Torsional Vibration*, B.I.C.E.R.A., Cambridge, 1958,
   part 1 (crankshaft stiffness; only its title page and the start of its contents were
   readable here).
.. [4] W. A. Tuplin, *Vibration in Machinery*, Pitman, 1940 (title and contents only were
   readable; no throw formula).
.. [5] S. Timoshenko, *Vibration Problems in Engineering*, 2nd ed., 1937, §55 (torsional
   vibration of a uniform shaft; shaft with a disk at its end, β tan β = J_shaft/J_disk).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from .._validate import check_int, check_nonnegative, check_option, check_positive
from ..errors import ModelError

__all__ = ["CrankThrow", "ThrowStiffness", "throw_stiffness", "THROW_METHODS",
           "UNAVAILABLE_THROW_METHODS",
           "lumping_error", "elements_for_tolerance", "uniform_shaft_frequencies"]

log = logging.getLogger("crankbench")

THROW_METHODS = ("carter", "wilson", "fe")

#: classical formulas an engineer may ask for that are not implemented, and why
UNAVAILABLE_THROW_METHODS = {
    "tuplin": "Tuplin's equivalent-length formula is not implemented: no readable source gave "
              "its coefficients (module predict.torsion.throws)",
    "bicera": "the BICERA formula (Nestorides 1958) is not implemented: no readable source "
              "gave its coefficients or overlap charts (module predict.torsion.throws)",
}


@dataclass(frozen=True)
class CrankThrow:
    """Dimensions of one crank throw, m.

    Parameters
    ----------
    journal_diameter, journal_length : float
        Main journal diameter D_j and bearing length l_j.
    pin_diameter, pin_length : float
        Crank pin diameter D_p and length l_p.
    web_thickness : float
        Web thickness h (along the shaft).
    web_width : float
        Web width b (across the shaft, perpendicular to the crank radius).
    crank_radius : float
        R (half the stroke).
    journal_bore, pin_bore : float
        Bores d_j, d_p (0 = solid).

    Examples
    --------
    >>> t = CrankThrow(journal_diameter=0.26, journal_length=0.12, pin_diameter=0.24,
    ...                pin_length=0.12, web_thickness=0.07, web_width=0.38, crank_radius=0.2)
    >>> round(t.overlap, 3)
    0.05
    """

    journal_diameter: float
    journal_length: float
    pin_diameter: float
    pin_length: float
    web_thickness: float
    web_width: float
    crank_radius: float
    journal_bore: float = 0.0
    pin_bore: float = 0.0

    def __post_init__(self):
        for name in ("journal_diameter", "journal_length", "pin_diameter", "pin_length",
                     "web_thickness", "web_width", "crank_radius"):
            object.__setattr__(self, name, check_positive(getattr(self, name), name,
                                                          error=ModelError))
        for bore, outer in (("journal_bore", "journal_diameter"), ("pin_bore", "pin_diameter")):
            value = check_nonnegative(getattr(self, bore), bore, error=ModelError)
            if value >= getattr(self, outer):
                raise ModelError(f"{bore}={value!r} must be smaller than {outer}="
                                 f"{getattr(self, outer)!r}")
            object.__setattr__(self, bore, value)

    @property
    def overlap(self) -> float:
        """Pin-journal overlap (D_j + D_p)/2 − R, m (> 0: the pin and journal overlap)."""
        return 0.5 * (self.journal_diameter + self.pin_diameter) - self.crank_radius


@dataclass(frozen=True)
class ThrowStiffness:
    """Torsional stiffness of one crank throw.

    Attributes
    ----------
    method : str
    stiffness : float
        N·m/rad.
    equivalent_length : float
        m of plain shaft of ``reference_diameter``.
    reference_diameter : float
        m.
    parts : dict
        Equivalent length of the journal, pin and web terms, m.
    within_validity : bool
        False when the throw lies outside the formula's stated range (see ``note``).
    uncertainty : float
        Relative uncertainty: for the formulas their stated ±15 % (checked against the FE of
        the idealised throw, module docstring); for ``"fe"`` the discretisation estimate.
    note : str
    """

    method: str
    stiffness: float
    equivalent_length: float
    reference_diameter: float
    parts: dict
    within_validity: bool
    uncertainty: float
    note: str

    def to_frame(self):
        """One row: method, stiffness (N·m/rad), equivalent length and its parts (m)."""
        import pandas as pd

        row = {"method": self.method, "stiffness_nm_per_rad": self.stiffness,
               "equivalent_length_m": self.equivalent_length,
               "reference_diameter_m": self.reference_diameter}
        row.update({f"{k}_m": v for k, v in self.parts.items()})
        row.update(within_validity=self.within_validity, note=self.note)
        return pd.DataFrame([row])

    def plot(self, ax=None):
        """Bar chart of the equivalent-length parts; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        ax.bar(list(self.parts), list(self.parts.values()))
        ax.set_ylabel("equivalent length (m)")
        ax.set_title(f"{self.method}: k = {self.stiffness:.4g} N·m/rad")
        return fig


def throw_stiffness(throw: CrankThrow, *, method: str = "wilson",
                    shear_modulus: float = 80.0e9, reference_diameter=None) -> ThrowStiffness:
    """Torsional stiffness of one crank throw by a classical equivalent-length formula.

    Parameters
    ----------
    throw : CrankThrow
    method : {"wilson", "carter", "fe"}
        Formula (module docstring), or ``"fe"``: the 3-D finite-element model of
        :func:`predict.torsion.throw_fe.throw_stiffness_fe` (seconds per throw; results are
        cached per throw). ``"tuplin"`` and ``"bicera"`` raise :class:`ModelError`: not
        implemented, no readable source gave their coefficients. The default stays Ker
        Wilson's formula, the one of the two implemented formulas that carries end
        corrections for journal and pin; BICERA's, the usual modern choice, is unavailable.
    shear_modulus : float
        G, Pa.
    reference_diameter : float, optional
        D_ref, m (default the journal diameter). The stiffness does not depend on it.

    Returns
    -------
    ThrowStiffness
        A throw outside the formula's range (overlapped pin and journal, webs thicker than
        wide, or a non-positive web term) gets ``within_validity=False`` and a logged warning
        (``"fe"`` has no such range).

    References
    ----------
    Carter (1928); Ker Wilson vol. 1 (1956) ch. 3; Nestorides (1958) §3 -- none of them
    readable here (module docstring).

    Examples
    --------
    >>> t = CrankThrow(journal_diameter=0.1, journal_length=0.05, pin_diameter=0.1,
    ...                pin_length=0.05, web_thickness=0.03, web_width=0.15, crank_radius=0.1)
    >>> r = throw_stiffness(t, method="carter")
    >>> round(r.equivalent_length, 4), round(r.stiffness / 1e6, 3)
    (0.2596, 3.025)
    """
    if not isinstance(throw, CrankThrow):
        raise ModelError(f"throw must be a CrankThrow, got {type(throw).__name__}")
    if method in UNAVAILABLE_THROW_METHODS:
        raise ModelError(f"throw_stiffness(method={method!r}): "
                         f"{UNAVAILABLE_THROW_METHODS[method]}; use one of "
                         f"{', '.join(repr(m) for m in THROW_METHODS)} or give the throw's "
                         "stiffness from the maker, an FE model or a measurement")
    method = check_option(method, "method", THROW_METHODS, error=ModelError)
    g = check_positive(shear_modulus, "shear_modulus", error=ModelError)
    dref = throw.journal_diameter if reference_diameter is None else check_positive(
        reference_diameter, "reference_diameter", error=ModelError)
    if method == "fe":
        from .throw_fe import _cached_fe

        return _cached_fe(throw, g, dref)
    d4 = dref ** 4
    jq = d4 / (throw.journal_diameter ** 4 - throw.journal_bore ** 4)
    pq = d4 / (throw.pin_diameter ** 4 - throw.pin_bore ** 4)
    wq = d4 / (throw.web_thickness * throw.web_width ** 3)
    h, r = throw.web_thickness, throw.crank_radius
    if method == "carter":
        parts = dict(journal=(throw.journal_length + 0.8 * h) * jq,
                     pin=0.75 * throw.pin_length * pq, webs=1.5 * r * wq)
    else:
        parts = dict(journal=(throw.journal_length + 0.4 * throw.journal_diameter) * jq,
                     pin=(throw.pin_length + 0.4 * throw.pin_diameter) * pq,
                     webs=(r - 0.2 * (throw.journal_diameter + throw.pin_diameter)) * wq)
    problems = []
    if throw.overlap > 0:
        problems.append(f"pin and journal overlap by {throw.overlap * 1e3:.3g} mm (the formula "
                        "was fitted to throws without overlap: it over-estimates the "
                        "flexibility)")
    if throw.web_thickness >= throw.web_width:
        problems.append("the web is thicker than it is wide")
    if parts["webs"] <= 0:
        problems.append("the web term is not positive (crank radius too small for the journal "
                        "and pin diameters)")
    le = sum(parts.values())
    if le <= 0:
        raise ModelError(f"throw_stiffness({method!r}): equivalent length {le:g} m is not "
                         "positive; the throw is far outside the formula's range")
    valid = not problems
    note = "; ".join(problems) if problems else "within the formula's range"
    note += ("; coefficients not verified against a printed source (see "
             "predict.torsion.throws)")
    if problems:
        log.warning("throw_stiffness(method=%r): outside the formula's range: %s", method, note)
    k = g * np.pi * d4 / (32.0 * le)
    return ThrowStiffness(method=method, stiffness=float(k), equivalent_length=float(le),
                          reference_diameter=float(dref), parts={k_: float(v) for k_, v in
                                                                 parts.items()},
                          within_validity=valid, uncertainty=0.15, note=note)


# -------------------------------------------------------------------------------------------
# distributed inertia
# -------------------------------------------------------------------------------------------
def lumping_error(omega, *, length, wave_velocity, elements):
    """Relative frequency error of a uniform shaft lumped into ``elements`` equal pieces.

    The lumped chain's dispersion ω_N = (2c/h) sin(κh/2) against the continuum's ω = cκ gives
    ω_N/ω = sin x / x with x = ω L / (2 N c); the returned value is ``1 − sin x / x`` (≈ x²/6),
    the amount by which the lumped model is low at vibration frequency ``omega``.

    Parameters
    ----------
    omega : float or array_like
        Vibration frequency of the continuum mode, rad/s.
    length : float
        Shaft length L, m.
    wave_velocity : float
        Torsional wave speed c = √(G/ρ), m/s.
    elements : int
        N.

    Examples
    --------
    >>> c = (80e9 / 7850) ** 0.5
    >>> round(float(lumping_error(np.pi * c / 2.0, length=2.0, wave_velocity=c, elements=10)), 6)
    0.004107
    """
    n = check_int(elements, "elements", minimum=1, error=ModelError)
    length = check_positive(length, "length", error=ModelError)
    c = check_positive(wave_velocity, "wave_velocity", error=ModelError)
    x = np.asarray(omega, float) * length / (2 * n * c)
    if np.any(x >= np.pi / 2):
        raise ModelError(f"omega is beyond the cut-off 2Nc/L = {2 * n * c / length:.6g} rad/s "
                         f"of {n} elements: no lumped mode represents it; use more elements")
    return 1.0 - np.sinc(x / np.pi)


def elements_for_tolerance(omega, *, length, wave_velocity, tol=1e-3) -> int:
    """Fewest equal elements whose :func:`lumping_error` at ``omega`` is ≤ ``tol``.

    Examples
    --------
    >>> c = (80e9 / 7850) ** 0.5
    >>> elements_for_tolerance(np.pi * c / 2.0, length=2.0, wave_velocity=c, tol=1e-3)
    21
    """
    tol = check_positive(tol, "tol", error=ModelError)
    length = check_positive(length, "length", error=ModelError)
    c = check_positive(wave_velocity, "wave_velocity", error=ModelError)
    w = check_positive(omega, "omega", error=ModelError)
    n = max(1, int(np.ceil(w * length / (2 * c * np.sqrt(6 * tol)))))
    while lumping_error(w, length=length, wave_velocity=c, elements=n) > tol:
        n += 1
    return n


def uniform_shaft_frequencies(*, length, shear_modulus, density, ends="free-free",
                              end_inertia_ratio=None, n_modes=3):
    """Exact natural frequencies (rad/s) of a uniform shaft in torsion.

    Parameters
    ----------
    length : float
        m.
    shear_modulus, density : float
        G (Pa) and ρ (kg/m³); c = √(G/ρ).
    ends : {"free-free", "fixed-free", "fixed-disk"}
        free-free and fixed-free: ω_m = mπc/L and (2m−1)πc/(2L); fixed-disk: a disk at the free
        end, β tan β = J_shaft/J_disk with β = ωL/c (Timoshenko 1937 §55).
    end_inertia_ratio : float
        J_shaft/J_disk, for ``fixed-disk``.
    n_modes : int

    Examples
    --------
    >>> w = uniform_shaft_frequencies(length=1.0, shear_modulus=1.0, density=1.0,
    ...                               ends="fixed-disk", end_inertia_ratio=1.0, n_modes=1)
    >>> round(float(w[0]), 6)   # β tan β = 1
    0.860334
    """
    from scipy.optimize import brentq

    length = check_positive(length, "length", error=ModelError)
    c = np.sqrt(check_positive(shear_modulus, "shear_modulus", error=ModelError)
                / check_positive(density, "density", error=ModelError))
    ends = check_option(ends, "ends", ("free-free", "fixed-free", "fixed-disk"),
                        error=ModelError)
    n = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
    m = np.arange(1, n + 1)
    if ends == "free-free":
        return m * np.pi * c / length
    if ends == "fixed-free":
        return (2 * m - 1) * np.pi * c / (2 * length)
    mu = check_positive(end_inertia_ratio, "end_inertia_ratio", error=ModelError)
    beta = [brentq(lambda b: b * np.sin(b) - mu * np.cos(b), (k - 1) * np.pi + 1e-12,
                   (k - 0.5) * np.pi - 1e-12, xtol=1e-15) for k in m]
    return np.asarray(beta) * c / length
