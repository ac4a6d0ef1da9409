"""``crankbench campaign STORE``: the runs of a campaign store, their trends and a report.

Lists the runs and their verdicts (filters ``--test-id``, ``--engine``, ``--build``,
``--verdict``, ``--status``, ``--since``, ``--until``); ``--trend "critical speed mode 1 order
6" [--by build|start_time|attr:NAME] [--plot FILE]`` follows one quantity across the runs beside
its prediction and tolerance band; ``--report FILE`` writes the campaign report (HTML, or PDF
with a .pdf name) linking each run's own report; ``--export DIR`` writes every table as
Parquet. The store is opened read-only.
"""

from __future__ import annotations

HELP = "list, trend, report and export the runs of a campaign results store (DuckDB)"


def configure(parser) -> None:
    parser.add_argument("store", metavar="STORE", help="campaign store (.duckdb) written by "
                                                       "batch --store")
    parser.add_argument("--test-id", default=None, help="only runs of this test id")
    parser.add_argument("--engine", default=None, help="only runs of this engine id")
    parser.add_argument("--build", default=None, help="only runs of this build")
    parser.add_argument("--verdict", default=None, choices=("pass", "fail", "inconclusive"))
    parser.add_argument("--status", default=None, choices=("ok", "error"))
    parser.add_argument("--since", default=None, metavar="YYYY-MM-DD")
    parser.add_argument("--until", default=None, metavar="YYYY-MM-DD")
    parser.add_argument("--trend", default=None, metavar="TEXT",
                        help="quantity to follow, e.g. 'critical speed mode 1 order 6', "
                             "'resonance amplitude mode 2 order 4.5', 'order amplitude order 6 "
                             "at 600 rpm', 'check torsional stress'")
    parser.add_argument("--by", default="run", metavar="AXIS",
                        help="trend axis: run, build, start_time, test_id, engine_id or "
                             "attr:NAME (a record attribute)")
    parser.add_argument("--plot", default=None, metavar="FILE",
                        help="write the trend figure (.svg, .png or .pdf)")
    parser.add_argument("--report", default=None, metavar="FILE",
                        help="write the campaign report (.html or .pdf)")
    parser.add_argument("--export", default=None, metavar="DIR",
                        help="export every table to DIR/<table>.parquet")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace existing --plot/--report/--export outputs")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def run(args) -> int:
    from pathlib import Path

    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.campaign.query import TrendSpec, list_runs, trend
    from crankbench.analysis.campaign.store import Store, export_parquet
    from crankbench.measure._atomic import atomic_path, check_overwrite
    from crankbench.predict.errors import ConfigError

    store_path = Path(args.store)
    outputs = [p for p in (args.plot, args.report, args.export) if p]
    for p in outputs:
        if Path(p).resolve() == store_path.resolve():
            raise ConfigError(f"{p}: an output may not replace the store {args.store}")
        check_overwrite(Path(p), args.overwrite, option="--overwrite")
    if args.plot and not args.trend:
        raise ConfigError("--plot draws a trend: give --trend too")
    if args.plot and Path(args.plot).suffix.lower() not in (".svg", ".png", ".pdf"):
        raise ConfigError(f"--plot {args.plot!r} must end in .svg, .png or .pdf")
    if args.report and Path(args.report).suffix.lower() not in (".html", ".pdf"):
        raise ConfigError(f"--report {args.report!r} must end in .html or .pdf")
    spec = TrendSpec.parse(args.trend) if args.trend else None
    filters = dict(test_id=args.test_id, engine_id=args.engine, build=args.build,
                   verdict=args.verdict, since=args.since, until=args.until)
    out: dict = {"store": str(store_path)}
    with Store(store_path, read_only=True) as store:
        runs = list_runs(store, status=args.status, **filters)
        cols = ["record_name", "test_id", "engine_id", "build", "start_time", "status",
                "verdict", "verdict_reason"]
        out["runs"] = runs[["run_id", "record_path", *cols, "error", "report_path"]]
        result = None
        if spec is not None:
            result = trend(store, spec, by=args.by, **filters)
            out["trend"] = {"quantity": spec.label(), "by": args.by, "rows": result.table}
            if args.plot:
                import matplotlib.pyplot as plt

                fig = result.plot()
                plot = Path(args.plot)
                with atomic_path(plot, overwrite=args.overwrite, option="--overwrite") as tmp:
                    fig.savefig(tmp, format=plot.suffix[1:].lower())
                plt.close(fig)
                out["plot"] = str(plot)
        if args.report:
            from crankbench.analysis.campaign.report import campaign_report

            rep = campaign_report(store, out_path=args.report, **filters)
            out["report"] = str(rep.save(args.report, overwrite=args.overwrite,
                                         option="--overwrite"))
    if args.export:
        out["export"] = [str(p) for p in export_parquet(store_path, args.export,
                                                         overwrite=args.overwrite)]
    if args.json:
        print_json(out)
        return 0
    print_table(runs[cols], title=f"{args.store}: {len(runs)} runs")
    if result is not None:
        print()
        print_table(result.table[["record_name", "x", "value", "predicted", "verdict"]],
                    title=f"trend: {spec.label()} by {args.by}")
    for key in ("plot", "report"):
        if key in out:
            print(f"{key} written: {out[key]}")
    if "export" in out:
        print(f"exported {len(out['export'])} tables to {args.export}")
    return 0
