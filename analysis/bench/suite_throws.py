"""Crank-throw torsional stiffness: the empirical formulas against the 3-D FE, and its cost.

The fidelity choice of ``throw_stiffness(method=...)``: Carter's and Ker Wilson's
equivalent-length formulas (microseconds; coefficients not checked against a printed source)
or the finite-cell FE of the idealised throw (``method="fe"``, seconds;
:mod:`predict.torsion.throw_fe`).

Rows, per throw (the I6 sample; with the full run also the long-stroke and the overlapped
throws of the :mod:`predict.torsion.throws` table):

* **carter**, **wilson**: relative error of the equivalent length against the FE at its
  default grid; bound = the formulas' stated ``uncertainty`` (±15 %). The overlapped throw is
  outside both formulas' range (flagged in the note), so its rows show what ignoring the flag
  costs. Timed against the FE (paired, one round: the FE takes seconds).
* **fe**: the default two-grid result against the two-grid result one step finer (element
  size / 1.25: the finer pair stays within the FE's element limit); bound = the default result's own ``uncertainty`` (its discretisation
  estimate). With ``--quick`` the reference is one step *coarser* instead (10 mm elements:
  seconds rather than half a minute), still a check of the stated estimate.
"""

from __future__ import annotations

from . import Row, compare

SUITE = "throws"
G = 81e9


def _throws(quick: bool):
    from crankbench.predict.torsion.throws import CrankThrow

    d = 0.3
    cases = {"I6 sample": CrankThrow(journal_diameter=0.085, journal_length=0.036,
                                     pin_diameter=0.07, pin_length=0.042, web_thickness=0.026,
                                     web_width=0.13, crank_radius=0.08)}
    if not quick:
        cases["long stroke"] = CrankThrow(
            journal_diameter=d, journal_length=0.5 * d, pin_diameter=0.95 * d,
            pin_length=0.55 * d, web_thickness=0.45 * d, web_width=1.6 * d,
            crank_radius=1.35 * d)
        cases["overlapped"] = CrankThrow(
            journal_diameter=d, journal_length=0.4 * d, pin_diameter=0.9 * d,
            pin_length=0.45 * d, web_thickness=0.3 * d, web_width=1.4 * d,
            crank_radius=0.65 * d)
    return cases


def run(quick: bool) -> list[Row]:
    """Rows described in the module docstring."""
    import logging

    rows = []
    quiet = logging.getLogger("crankbench")
    level, quiet.level = quiet.level, logging.ERROR    # range warnings go to the rows' notes
    try:
        for name, throw in _throws(quick).items():
            rows += _rows(name, throw, quick)
    finally:
        quiet.level = level
    return rows


def _rows(name, throw, quick):
    from crankbench.predict.torsion.throw_fe import throw_stiffness_fe
    from crankbench.predict.torsion.throws import throw_stiffness

    rows = []
    formulas = {m: throw_stiffness(throw, method=m, shear_modulus=G)
                for m in ("carter", "wilson")}
    solved = []                                          # the timed FE call's result

    def fe_call(throw=throw, solved=solved):
        solved.append(throw_stiffness_fe(throw, shear_modulus=G))

    t = compare({"fe": fe_call,
                 "carter": lambda: throw_stiffness(throw, method="carter", shear_modulus=G),
                 "wilson": lambda: throw_stiffness(throw, method="wilson", shear_modulus=G)},
                rounds=1, warmup=0)
    fe = solved[-1]
    for method, res in formulas.items():
        err = abs(res.equivalent_length / fe.equivalent_length - 1)
        note = "" if res.within_validity else "outside the formula's range (flagged)"
        rows.append(t.row(SUITE, method, method, "fe", name, err, "rel L_e",
                          "3-D FE of the idealised throw (default grid)",
                          bound=res.uncertainty, note=note))
    default_size = min(min(throw.journal_diameter, throw.pin_diameter) / 10.0,
                       throw.web_thickness / 2.0)
    other_size = 0.01 if quick else default_size / 1.25
    other = throw_stiffness_fe(throw, shear_modulus=G, element_size=other_size)
    rows.append(t.row(SUITE, "fe", "fe", None, name,
                      abs(fe.stiffness / other.stiffness - 1), "rel k",
                      f"FE at element size {other_size * 1e3:.3g} mm",
                      bound=fe.uncertainty, note=fe.note))
    return rows
