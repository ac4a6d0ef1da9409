"""Measured response against the response predicted from the *measured* excitation.

When a record carries cylinder pressure beside the torsional channel, the pipeline
(:func:`analysis.pipeline.analyse`) predicts the order response twice at the measured node:
once from the model's parametric pressure (:func:`predict.torsion.excitation.engine_excitation`)
and once from the measured pressure (mean cycles of :func:`analysis.pressure.indicator_analyses`
through :func:`predict.gas_torque.excitation_from_pressure`, the reciprocating inertia from the
model). If measurement and the measured-excitation prediction agree while the parametric one
does not, the pressure model is at fault; if both predictions miss alike, the dynamic model is.

On a sweep (cycle speeds spanning more than 5 % of their mean) the gas torque is taken per
speed bin as measured (:func:`analysis.pressure.measured_speed_excitation`, no load law); on a
steady run the cycles are averaged into one operating point whose gas torque is divided by the
load law's factor at the measured speed and then scaled over the model's speed grid by the
same law as the parametric excitation (:func:`excitation_from_indicator`) — stated in the
result. The same measured excitation drives the block on its mounts in the vibrograph
comparison (:func:`analysis.vibrograph.compare_vibrograph`, ``indicator``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict.errors import CrankbenchError

__all__ = ["ExcitationComparison", "measured_excitation_prediction", "add_pressure_section",
           "add_indicator_section", "excitation_from_indicator"]

log = logging.getLogger("crankbench")


@dataclass(frozen=True)
class ExcitationComparison:
    """Indicator results, the measured excitation and the response it predicts.

    Attributes
    ----------
    indicator : dict
        ``{channel: IndicatorResult}``.
    excitation : predict.torsion.excitation.Excitation
    response : xarray.DataArray
        Predicted order amplitude at the node from the measured excitation over (``order``,
        ``rpm``), channel units, peak.
    table : pandas.DataFrame
        Per order: measured peak amplitude and its speed, the peaks of both predictions over
        the same speeds, and the ratios measured / predicted.
    note : str
        What the measured excitation rests on.
    """

    indicator: dict
    excitation: object
    response: object
    table: object
    note: str = ""
    extra: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """JSON-able: indicator summaries, the excitation source and the order table."""
        return {"excitation": self.excitation.source, "note": self.note,
                "indicator": {c: r.summary() for c, r in self.indicator.items()},
                "orders": self.table.to_dict(orient="records")}

    def plot(self, ax=None, *, measured=None, model=None):
        """Measured track, model prediction and measured-excitation prediction per order."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4)) if ax is None else (ax.figure, ax)
        for i, q in enumerate(self.response["order"].values):
            color = f"C{i % 10}"
            ax.plot(self.response["rpm"], self.response.sel(order=q), color=color, lw=1.4,
                    label=f"order {q:g}: from measured pressure")
            if model is not None and q in model["order"].values:
                ax.plot(model["rpm"], model.sel(order=q), "--", color=color, lw=1)
            if measured is not None and q in measured["order"].values:
                tr = measured["amplitude"].sel(order=q)
                ax.plot(measured["rpm"], tr, ":", color=color, lw=1)
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel(f"amplitude ({self.response.attrs.get('units', '')})")
        ax.set_title("solid: from measured pressure, dashed: model pressure, dotted: measured")
        ax.legend(fontsize=7)
        return fig


def excitation_from_indicator(results, engine, *, orders, load):
    """The measured torque excitation of indicator results, ready for a load law.

    On a sweep (cycle speeds spanning more than 5 % of their mean) the gas torque per speed
    bin (:func:`analysis.pressure.measured_speed_excitation`, ``speed_dependent``: no load law
    applies); on a steady run the mean cycles (:func:`analysis.pressure.measured_excitation`)
    with the gas part divided by the load law's factor at the measured speed, so that the law
    (``load.scale``) applied to it gives the measured torque at the measured speed and the
    law's change elsewhere.

    Parameters
    ----------
    results : dict
        ``{channel: IndicatorResult}`` (:func:`analysis.pressure.indicator_analyses`).
    engine : predict.engine.Engine
    orders : array_like
        Orders of the excitation.
    load : analysis.pipeline.LoadCase

    Returns
    -------
    excitation : Excitation or SpeedExcitation
    note : str
        What the excitation rests on.

    Examples
    --------
    >>> from crankbench.analysis.pipeline import LoadCase
    >>> excitation_from_indicator({}, None, orders=[2.0], load=LoadCase())
    Traceback (most recent call last):
    ...
    crankbench.predict.errors.AnalysisError: no indicator results: the measured excitation needs at least one analysed pressure channel
    """
    from dataclasses import replace

    from crankbench.predict.errors import AnalysisError

    from .pressure import measured_excitation, measured_speed_excitation

    if not results:
        raise AnalysisError("no indicator results: the measured excitation needs at least one "
                            "analysed pressure channel")
    speeds = np.concatenate([r.speed_rpm for r in results.values()])
    if np.ptp(speeds) > 0.05 * speeds.mean():       # a sweep: the gas torque per speed
        exc = measured_speed_excitation(results, engine, orders=orders)
        return exc, f"{exc.source}; the gas torque of each speed as measured (no load law)"
    exc = measured_excitation(results, engine, orders=orders)
    mean = float(speeds.mean())
    factor = float(load.scale(np.array([mean]))[0])
    if factor != 1.0:
        exc = replace(exc, gas=exc.gas / factor,
                      source=f"{exc.source}; gas part divided by the load factor {factor:.4g} "
                             f"at {mean:.0f} rpm")
    lo, hi = float(speeds.min()), float(speeds.max())
    return exc, (f"{exc.source}; measured at {lo:.0f}-{hi:.0f} rpm and scaled over the sweep "
                 f"by the load law ({load.law})")


def measured_excitation_prediction(record, system, grid, orders, node, quantity, units, load,
                                   track, model_response):
    """The measured-excitation prediction of a pipeline run, or None without pressure.

    A problem with the pressure (no crank-angle source, no complete cycle, ...) is logged as a
    warning and gives None: the torsional comparison does not depend on it.
    """
    from .pressure import indicator_analyses, pressure_channels

    engine = getattr(system, "engine", None)
    if engine is None or not pressure_channels(record):
        return None
    try:
        results = indicator_analyses(record, engine)
        exc, note = excitation_from_indicator(results, engine, orders=orders, load=load)
    except CrankbenchError as exc_:
        log.warning("measured excitation skipped: %s", exc_)
        return None
    import pandas as pd
    import xarray as xr

    from .pipeline import predicted_response

    amp, _, _ = predicted_response(system, grid, orders, node, load=load, quantity=quantity,
                                   excitation=exc)
    response = xr.DataArray(amp.T, dims=("order", "rpm"), coords={"order": orders, "rpm": grid},
                            attrs={"units": units, "amplitude": "peak", "node": node,
                                   "excitation": exc.source})
    rows = []
    for q in track["order"].values:
        q = float(q)
        meas = track["amplitude"].sel(order=q)
        rpm = np.asarray(track["rpm"].values, float).reshape(-1)
        values = np.asarray(meas.values, float).reshape(-1)
        ok = np.isfinite(values)
        if not ok.any():
            continue
        k = int(np.argmax(np.where(ok, values, -np.inf)))
        lo, hi = np.nanmin(rpm), np.nanmax(rpm)
        inside = (grid >= lo) & (grid <= hi)
        if not inside.any():                     # a steady run: the nearest predicted speed
            inside = np.abs(grid - 0.5 * (lo + hi)) == np.abs(grid - 0.5 * (lo + hi)).min()
        pm = float(model_response.sel(order=q).values[inside].max())
        px = float(response.sel(order=q).values[inside].max())
        rows.append({"order": q, "measured_peak": float(values[k]),
                     "measured_peak_rpm": float(rpm[k]), "predicted_model_peak": pm,
                     "predicted_measured_excitation_peak": px,
                     "ratio_to_model": float(values[k]) / pm if pm > 0 else float("nan"),
                     "ratio_to_measured_excitation": float(values[k]) / px if px > 0
                     else float("nan")})
    table = pd.DataFrame(rows)
    table.attrs["units"] = units
    return ExcitationComparison(indicator=results, excitation=exc, response=response,
                                table=table, note=note)


def add_indicator_section(rep, results, *, figures=True,
                          section="Cylinder pressure and measured excitation"):
    """Add indicator-analysis results (``{channel: IndicatorResult}``) to a Report.

    Examples
    --------
    >>> from crankbench.analysis.report import Report
    >>> rep = Report("pressure")
    >>> add_indicator_section(rep, {}, figures=False)          # nothing to add: no error
    """
    import pandas as pd

    if not results:
        return
    rows = []
    for c, r in results.items():
        s = r.summary()
        check = s["tdc"]["check"]
        rows.append({"channel": c, "cylinder": s["cylinder"], "cycles": s["cycles"],
                     "speed_rpm": s["speed_rpm"], "peak_bar": s["peak_pressure_bar"],
                     "peak_angle_deg": s["peak_angle_deg"], "imep_net_bar": s["imep_net_bar"],
                     "imep_gross_bar": s["imep_gross_bar"], "pmep_bar": s["pmep_bar"],
                     "cov_imep_pct": s["cov_imep_net_percent"], "peg": s["peg"]["method"],
                     "tdc_check_deg": None if check is None else check["offset_deg"],
                     "mfb50_deg": None if s["heat_release"] is None
                     else s["heat_release"]["mfb50_deg"]})
    rep.add_table(pd.DataFrame(rows), title="Indicator analysis", section=section,
                  caption="Peak of the cycle-averaged trace; IMEP net over 720/360 deg, gross "
                          "over compression and expansion, PMEP = gross - net (Heywood 1988 "
                          "§2.4); COV of net IMEP; TDC check: thermodynamic TDC after the "
                          "reference (compression polytropic fit); heat release single-zone.")
    for c, r in results.items():
        rep.add_text(f"{c}: TDC reference {r.tdc['reference']}; firing TDC {r.tdc['phase']}; "
                     f"pegging {r.peg['method']} ({r.peg.get('note', '')}).", section=section)
        for w in r.warnings:
            rep.add_text(f"{c}: warning: {w}", section=section)
    if figures:
        for c, r in results.items():
            try:
                rep.add_figure(r.plot(), title=f"{c}: pressure against crank angle",
                               section=section)
                if r.volume is not None:
                    rep.add_figure(r.plot_log_pv(), title=f"{c}: log p - log V",
                                   section=section)
                    rep.add_figure(r.plot_heat_release(), title=f"{c}: heat release",
                                   section=section)
            except Exception as exc:       # a figure must never sink the report
                log.warning("pressure figure skipped: %s", exc)


def add_pressure_section(rep, comparison, *, result=None, figures=True,
                         section="Cylinder pressure and measured excitation"):
    """Add the indicator analysis and the measured-excitation comparison to a Report."""
    add_indicator_section(rep, comparison.indicator, figures=figures, section=section)
    units = comparison.table.attrs.get("units", "")
    rep.add_table(comparison.table, title="Measured response against both predictions",
                  section=section, amplitude_units=units, caption=f"Peaks over the measured speed range, {units} "
                                           f"(peak). {comparison.note}.")
    if figures:
        try:
            rep.add_figure(comparison.plot(measured=getattr(result, "track", None),
                                           model=getattr(result, "response", None)),
                           title="Order response: measured and both predictions",
                           section=section)
        except Exception as exc:
            log.warning("excitation figure skipped: %s", exc)
