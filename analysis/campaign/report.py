"""The campaign report: every run with its verdict and a link to its own report, and the
trends of the measured criticals across the runs beside their predictions."""

from __future__ import annotations

import html
import os
from pathlib import Path

__all__ = ["campaign_report"]


def _link(target, out_dir: Path) -> str:
    if not isinstance(target, str) or not target:
        return ""
    try:
        rel = os.path.relpath(target, out_dir)
    except ValueError:  # another drive
        rel = target
    return f'<a href="{html.escape(Path(rel).as_posix())}">report</a>'


def campaign_report(store, *, out_path, max_trends: int = 6, **filters):
    """Build the campaign report (a :class:`~analysis.report.Report`, not yet saved).

    Parameters
    ----------
    store : Store
    out_path : str or Path
        Where the report will be saved (links to the runs' reports are made relative to it).
    max_trends : int
        Trend figures for the (mode, order) criticals measured in the most runs.
    **filters
        As :func:`~analysis.campaign.query.list_runs`.
    """
    import matplotlib.pyplot as plt
    import pandas as pd

    from crankbench.analysis.report import Report

    from .query import TrendSpec, list_runs, trend

    runs = list_runs(store, **filters)
    out_dir = Path(out_path).resolve().parent
    counts = runs["verdict"].value_counts().reindex(["pass", "fail", "inconclusive"],
                                                    fill_value=0)
    rep = Report(f"Campaign report — {Path(store.path).name}",
                 subtitle=f"{len(runs)} runs: {counts['pass']} pass, {counts['fail']} fail, "
                          f"{counts['inconclusive']} inconclusive")
    rep.add_metadata({"store": str(Path(store.path).resolve()),
                      "schema version": store.schema_version,
                      "runs": len(runs), "failed to analyse": int((runs["status"] == "error")
                                                                   .sum()),
                      **{f"filter {k}": v for k, v in filters.items() if v is not None}},
                     title="Campaign")
    rows = []
    for _, r in runs.iterrows():
        cells = [r.record_name, r.test_id, r.engine_id, r.build, r.start_time, r.verdict,
                 r.verdict_reason if r.status == "ok" else r.error]
        tds = "".join(f"<td>{html.escape('' if c is None or c != c else str(c))}</td>"
                      for c in cells)
        rows.append(f'<tr class="verdict-{html.escape(str(r.verdict))}">{tds}'
                    f"<td>{_link(r.report_path, out_dir)}</td></tr>")
    head = "".join(f"<th>{h}</th>" for h in ("record", "test id", "engine", "build", "start",
                                              "verdict", "reason / error", "report"))
    rep.add_html(f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>",
                 title="Runs")
    crit = store.table("criticals")
    if len(crit):
        crit = crit[crit["run_id"].isin(set(runs["run_id"]))]
        top = (crit.groupby(["mode", "order"]).size().sort_values(ascending=False)
               .head(max_trends))
        for (mode, order), n in top.items():
            if n < 2:
                continue
            t = trend(store, TrendSpec("critical_speed", mode=int(mode), order=float(order)),
                      **filters)
            fig = t.plot()
            rep.add_figure(fig, title=f"Critical speed, mode {int(mode)} order {order:g}",
                           caption=f"{n} runs; measured against predicted with the speed "
                                   "tolerance band", section="Trends")
            plt.close(fig)
            rep.add_table(pd.DataFrame(t.table[["record_name", "x", "value", "predicted",
                                                "verdict"]]),
                          title=f"Mode {int(mode)} order {order:g} by run", section="Trends")
    return rep
