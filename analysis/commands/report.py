"""``crankbench report RECORD MODEL.toml -o report.html [--pdf] [--overwrite]``: test report.

Runs the chain of :mod:`analysis.pipeline` (a shaft-line model) or the vibrograph comparison
of :mod:`analysis.vibrograph` (an engine model with ``[mounts]``) and writes the
self-contained HTML report (figures embedded, no network) built by
:func:`analysis.report.build.build_report` or
:func:`analysis.vibrograph_report.build_vibrograph_report`; ``--pdf`` also writes a PDF beside
it, typeset from the same HTML by WeasyPrint. Outputs are
written atomically and never replace an existing file without ``--overwrite``.
"""

from __future__ import annotations

HELP = ("write the test report (HTML, optionally PDF) of a record against a shaft-line model or "
        "an engine model on its mounts")


def configure(parser) -> None:
    from crankbench.analysis.commands._pipeline_cli import add_common_arguments

    parser.add_argument("record", metavar="RECORD", help="record file (any supported format)")
    parser.add_argument("model", metavar="MODEL.toml",
                        help="shaft-line model, or an engine model with [mounts] (TOML)")
    parser.add_argument("-o", "--output", required=True, metavar="REPORT.html",
                        help="report file (.html; .pdf writes only the PDF)")
    parser.add_argument("--pdf", action="store_true", help="also write REPORT.pdf")
    parser.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    parser.add_argument("--title", default=None, help="report title")
    parser.add_argument("--bench", action="store_true",
                        help="append the speed-against-error tables of `crankbench bench "
                             "--quick` (about a minute)")
    add_common_arguments(parser)
    parser.add_argument("--json", action="store_true",
                        help="print the written paths and the summary as JSON")


def add_bench_appendix(rep, rows) -> None:
    """Append the bench table (one table and one speed-against-error plot per suite)."""
    from crankbench.analysis.commands.bench import plot_suite, rows_to_frame

    frame = rows_to_frame(rows)
    section = "Appendix: speed against error"
    failed = int(frame["fails_run"].sum())
    missed = int((~frame["passed"] & ~frame["fails_run"]).sum())
    rep.add_text(f"{len(frame)} rows from `crankbench bench --quick`, run with this report: each "
                 "row is one method at one setting, its error against an independent reference "
                 "(closed form, mpmath, a second method), its median time and the ratio to a "
                 "baseline timed in the same run. "
                 + (f"{failed} row(s) exceed their documented bound." if failed else
                    "Every row is within its documented error bound.")
                 + (f" {missed} speed target(s) missed on this machine (a target is a goal "
                    "for the time ratio, not an error bound)." if missed else ""),
                 title=section, section=section)
    cols = ["method", "setting", "error", "error_kind", "bound", "time_s", "baseline", "ratio",
            "passed"]
    for suite, part in frame.groupby("suite"):
        rep.add_table(part[cols], title=f"bench: {suite}", section=section)
        rep.add_figure(plot_suite(part, suite), title=f"bench: {suite}, error against time",
                       section=section)


def write_outputs(result, output, *, pdf, overwrite, title=None, parameters=None,
                  record_path=None, model_path=None, bench_rows=None):
    """Build the report and write HTML (and PDF); return the written paths.

    ``bench_rows`` (rows of :func:`analysis.bench.run_suites`) adds the bench appendix.
    """
    from pathlib import Path

    from crankbench.measure._atomic import check_overwrite
    from crankbench.analysis.report.build import build_report

    output = Path(output)
    targets = [output]
    if pdf and output.suffix.lower() != ".pdf":
        targets.append(output.with_suffix(".pdf"))
    for t in targets:  # refuse before any work is written
        check_overwrite(t, overwrite, option="--overwrite")
    rep = build_report(result, title=title, parameters=parameters, record_path=record_path,
                       model_path=model_path)
    if bench_rows is not None:
        add_bench_appendix(rep, bench_rows)
    return [rep.save(t, overwrite=overwrite, option="--overwrite") for t in targets]


def run(args) -> int:
    import logging
    from pathlib import Path

    from crankbench.analysis.commands._pipeline_cli import options_from_args, progress_bar
    from crankbench.analysis.pipeline import analyse
    from crankbench.measure._atomic import check_overwrite

    from crankbench.analysis.commands._files import (check_outputs, map_inputs, model_inputs,
                                                     record_inputs)
    from crankbench.analysis.commands._pipeline_cli import check_common

    log = logging.getLogger("crankbench")
    out = Path(args.output)
    if out.suffix.lower() not in (".html", ".htm", ".pdf"):
        from crankbench.predict.errors import ConfigError

        raise ConfigError(f"-o {args.output!r} must end in .html or .pdf")
    outputs = [(out, f"-o {out}")]
    if args.pdf and out.suffix.lower() != ".pdf":
        outputs.append((out.with_suffix(".pdf"), f"the PDF beside it ({out.with_suffix('.pdf')})"))
    check_outputs(outputs, record_inputs(args.record) + model_inputs(args.model)
                  + map_inputs(args))
    for path, _ in outputs:
        check_overwrite(path, args.overwrite, option="--overwrite")
    check_common(args, records=[args.record], model=args.model)   # before any work
    options = options_from_args(args, args.record)
    from crankbench.analysis.vibrograph import model_kind

    quiet = args.json or log.getEffectiveLevel() > logging.INFO
    if model_kind(args.model) == "engine":
        return _run_engine(args, options, out, quiet)
    bar, progress = progress_bar(desc="report", disable=quiet)
    try:
        result = analyse(args.record, args.model, progress=progress, **options)
    finally:
        bar.close()
    params = {"channel": result.channel, "method": args.method, "gate": args.gate,
              "tolerance": args.tolerance}
    if args.machine_class is not None:
        params["machine class"] = args.machine_class
    if args.map:
        params["channel map"] = (f"{args.map} (sha256 "
                                 f"{result.record.attrs.get('channel_map_sha256', '')})")
    bench_rows = None
    if args.bench:
        from crankbench.analysis.bench import run_suites

        log.info("report: running the quick bench suites for the appendix ...")
        bench_rows = run_suites(quick=True, progress=lambda n: log.info("bench: suite %s", n))
    paths = write_outputs(result, out, pdf=args.pdf, overwrite=args.overwrite,
                          title=args.title, parameters=params, record_path=args.record,
                          model_path=args.model, bench_rows=bench_rows)
    _print_outcome(args, paths, result)
    return 0


def _print_outcome(args, paths, result) -> None:
    """The written paths and the overall verdict (JSON with the summary under ``--json``)."""
    from crankbench.analysis._output import print_json

    if args.json:
        print_json({"written": [str(p) for p in paths], "summary": result.summary()})
        return
    for p in paths:
        print(f"report written: {p}")
    v = result.verdict
    print(f"verdict: {v.status.upper()}" + (f" — {v.reason}" if v.status != "pass" else
                                            "  (every required check passed)"))


def _run_engine(args, options, out, quiet) -> int:
    """An engine model on its mounts: the vibrograph report."""
    from pathlib import Path

    from crankbench.analysis.commands._pipeline_cli import progress_bar, vibrograph_options
    from crankbench.analysis.vibrograph import compare_vibrograph
    from crankbench.analysis.vibrograph_report import build_vibrograph_report

    bar, progress = progress_bar(3, desc="report", disable=quiet)
    try:
        result = compare_vibrograph(args.record, args.model, progress=progress,
                                    **vibrograph_options(options))
    finally:
        bar.close()
    params = {"method": "COT", "vibration tolerance": args.vibration_tolerance}
    rep = build_vibrograph_report(result, title=args.title, parameters=params,
                                  record_path=args.record, model_path=args.model)
    targets = [out]
    if args.pdf and out.suffix.lower() != ".pdf":
        targets.append(out.with_suffix(".pdf"))
    paths = [rep.save(Path(t), overwrite=args.overwrite, option="--overwrite")
             for t in targets]
    _print_outcome(args, paths, result)
    return 0
