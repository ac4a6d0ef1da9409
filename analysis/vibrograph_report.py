"""Presenting a vibrograph comparison: text tables, JSON, report sections.

The layer between :class:`analysis.vibrograph.VibrographResult` and the commands ``compare``,
``report`` and ``batch`` (and the torsional report, which gains the same sections when its
record carries vibrograph channels).
"""

from __future__ import annotations

import logging

__all__ = ["vibrograph_json", "print_vibrograph", "add_vibrograph", "build_vibrograph_report"]

log = logging.getLogger("crankbench")

#: columns of the per-(sensor, order) table shown to people
ROW_COLUMNS = ["sensor", "order", "measured", "predicted", "ratio", "ratio_median",
               "speed_rpm", "snr", "units", "verdict", "required"]
#: columns of the residual table shown to people
RESIDUAL_COLUMNS = ["order", "force_forward_n", "force_forward_unc_n", "force_backward_n",
                    "force_backward_unc_n", "predicted_force_forward_n",
                    "predicted_force_backward_n", "tolerance_force_forward_n",
                    "moment_forward_nm", "moment_forward_unc_nm", "moment_backward_nm",
                    "moment_backward_unc_nm", "predicted_moment_forward_nm",
                    "roll_nm", "predicted_roll_nm", "condition", "verdict_force",
                    "verdict_moment"]
#: shown beside ``predicted`` when the record has cylinder pressure
MEASURED_EXCITATION_COLUMNS = ["predicted_measured_excitation", "ratio_measured_excitation"]
UNBALANCE_COLUMNS = ["unbalance_kgm", "unbalance_unc_kgm", "unbalance_angle_deg",
                     "unbalance_angle_unc_deg", "unbalance_position_m",
                     "unbalance_position_unc_m"]


def _row_columns(table):
    """:data:`ROW_COLUMNS`, with the measured-excitation prediction after ``predicted`` when
    the table has it."""
    if "predicted_measured_excitation" not in table:
        return ROW_COLUMNS
    k = ROW_COLUMNS.index("ratio_median") + 1
    return ROW_COLUMNS[:k] + MEASURED_EXCITATION_COLUMNS + ROW_COLUMNS[k:]


def vibrograph_json(result) -> dict:
    """The comparison as JSON-ready data: ``summary``, ``rows`` (one per judged (sensor,
    order): ``sensor``, ``order``, ``measured``, ``predicted`` in SI units, ``ratio``,
    ``passed``, ``verdict``…), ``informational`` (the same for the orders too weak or too
    noisy to be judged), ``residuals``, ``verdicts``, ``sensors``, ``skipped``, ``settings``,
    ``indicator`` (summaries of the cylinder-pressure channels behind the measured excitation,
    empty without)."""
    res = result.residuals
    t = result.table
    return {"summary": result.summary(), "rows": t[t["required"]],
            "informational": t[~t["required"]],
            "residuals": None if res is None else {
                "speed_rpm": res.speed_rpm, "phase_reference": res.phase_reference,
                "orders": res.table, "settings": res.settings},
            "verdicts": [v.as_dict() for v in result.verdicts]
            + ([v.as_dict() for v in res.verdicts] if res is not None else []),
            "verdict": result.verdict.as_dict(),
            "sensors": [s.describe() for s in result.sensors],
            "skipped": [{"channel": c, "reason": r} for c, r in result.skipped],
            "settings": result.settings,
            "indicator": {c: r.summary() for c, r in getattr(result, "indicator", {}).items()}}


def print_vibrograph(result, *, header=True) -> None:
    """Human-readable tables of a vibrograph comparison on stdout (``header``: the record,
    model and speed lines of a stand-alone comparison)."""
    from ._output import print_table

    if header:
        print(f"record   {result.source}")
        print(f"model    {result.model_path}")
        print(f"speed    {result.speed_range_rpm[0]:.0f}–{result.speed_range_rpm[1]:.0f} rpm, "
              f"sweep {result.sweep_rate_rpm_per_s:.3g} rpm/s")
    print("sensors  " + "\n         ".join(s.describe() for s in result.sensors))
    for channel, reason in result.skipped:
        print(f"skipped  {channel}: {reason}")
    print()
    t = result.table
    shown = t[t["required"] | (t["verdict"] != "inconclusive")]
    print_table(shown[_row_columns(t)], title="block/mount vibration per order (peak, SI "
                f"units; agreement: ratio within ±{result.tolerance:g})")
    if "predicted_measured_excitation" in t:
        print(f"  (predicted_measured_excitation: {result.settings['measured excitation']})")
    hidden = len(t) - len(shown)
    if hidden:
        print(f"  ({hidden} weak orders below the noise or the significance threshold not "
              "shown; --json lists them)")
    res = result.residuals
    if res is not None:
        print()
        cols = [c for c in RESIDUAL_COLUMNS if c in res.table]
        print_table(res.table[cols], title=f"residual shaking forces (N) and moments (N·m) at "
                                           f"{res.speed_rpm:.0f} rpm, forward/backward "
                                           f"rotating components, 1-σ uncertainty; phases: "
                                           f"{res.phase_reference}")
        ub = [c for c in UNBALANCE_COLUMNS if c in res.table]
        if ub:
            one = res.table[res.table["order"] == 1]
            if len(one) and one[ub].notna().all(axis=None):
                print()
                print_table(one[ub], title="order 1 as one unbalance (kg·m, deg ahead of "
                                           "throw 1, axial position m)")
    print()
    v = result.verdict
    bad = [x for x in result.verdicts + (tuple(res.verdicts) if res is not None else ())
           if x.required and x.status != "pass"]
    for x in bad:
        print(f"{x.status.upper():12s} {x.name}: {x.reason}")
    label = "verdict" if header else "block/mount vibration verdict"
    print(f"{label}: {v.status.upper()}" + (f" — {v.reason}" if v.status != "pass" else
                                            "  (every required check passed)"))


def add_vibrograph(rep, result, *, figures=True, section="Block and mount vibration") -> None:
    """Add the vibrograph comparison's sections to a :class:`analysis.report.Report` (its
    verdict goes into the verdict box by the caller)."""
    res = result.residuals
    rep.add_text("Sensors: " + "; ".join(s.describe() for s in result.sensors)
                 + ("." if not result.skipped else ". Not placed: " + "; ".join(
                     f"{c} ({r})" for c, r in result.skipped) + "."),
                 title="Vibrograph sensors", section=section)
    t = result.table
    extra = ("" if "predicted_measured_excitation" not in t else
             " Beside it the prediction from the measured excitation (the gas-torque reaction "
             "from the measured cylinder pressure, the inertia loads from the model; same "
             f"speeds): {result.settings['measured excitation']}.")
    rep.add_table(t[t["required"] | (t["verdict"] != "inconclusive")][_row_columns(t)],
                  title="Measured against predicted order amplitude", section=section,
                  caption="measured/predicted: peak order amplitude (SI units, peak) over the "
                          "speeds where the prediction is at least 10 % of its largest; ratio "
                          f"band ±{result.tolerance:g}; prediction: the engine model's "
                          "inertia forces and moments and torque reaction through the mount "
                          "model." + extra)
    if figures:
        for s in result.sensors:
            try:
                rep.add_figure(result.plot(sensor=s.channel), title=f"{s.channel}: orders "
                               "against speed", section=section)
            except Exception as exc:  # a figure must never sink the report
                log.warning("figure for %s skipped: %s", s.channel, exc)
    if res is not None:
        sec = "Balance residuals from measurement"
        cols = [c for c in RESIDUAL_COLUMNS + UNBALANCE_COLUMNS if c in res.table]
        rep.add_table(res.table[cols], title=f"Residual forces and moments at "
                      f"{res.speed_rpm:.0f} rpm", section=sec,
                      caption="Least squares through the mount model over every block of "
                              f"every sensor; 1-σ uncertainties; phases: {res.phase_reference}. "
                              "Tolerance: the balance model's residual with the model's "
                              "manufacturing tolerances.")
        rep.add_table(_verdict_frame(res.verdicts), title="Residual checks", section=sec)
        if figures:
            try:
                rep.add_figure(res.plot(), title="Residuals against the balance model",
                               section=sec)
            except Exception as exc:
                log.warning("residual figure skipped: %s", exc)
    rep.add_table(_verdict_frame(result.verdicts), title="Vibration checks", section=section)


def _verdict_frame(verdicts):
    import pandas as pd

    return pd.DataFrame([v.as_dict() for v in verdicts],
                        columns=["check", "verdict", "rule", "basis", "reason", "required"])


def build_vibrograph_report(result, *, title=None, parameters=None, record_path=None,
                            model_path=None, figures=True):
    """The test report of a vibrograph comparison against an engine model.

    Returns
    -------
    analysis.report.Report
    """
    from pathlib import Path

    from .report.report import Report

    rep = Report(title or f"Block and mount vibration test report — {result.source}",
                 subtitle=f"record {result.source} · model {Path(result.model_path).name}")
    rep.add_verdict(result.verdict)
    if result.residuals is not None:
        rep.add_verdicts(v for v in result.residuals.verdicts if v.required)
    rep.add_metadata({"record": result.source, "model": result.model_path,
                      "speed range (rpm)": f"{result.speed_range_rpm[0]:.1f} – "
                                           f"{result.speed_range_rpm[1]:.1f}",
                      "sweep rate (rpm/s, median)": f"{result.sweep_rate_rpm_per_s:.3g}"})
    files = [p for p in (Path(record_path or result.source),) if p.is_file()]
    mp = Path(model_path or result.model_path)
    params = dict(parameters or {})
    if result.record_sha256:
        params.setdefault("record sha256 (from the reader)", result.record_sha256)
    rep.add_provenance(files=files, model=mp if mp.is_file() else None, parameters=params)
    rep.add_settings(result.settings)
    add_vibrograph(rep, result, figures=figures)
    if result.indicator:                # the cylinder pressure the measured excitation rests on
        from .excitation_compare import add_indicator_section

        add_indicator_section(rep, result.indicator, figures=figures)
    return rep
