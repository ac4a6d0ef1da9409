"""``crankbench bench``: run the speed-against-error suites and write one table.

Each suite (``analysis/bench/suite_<topic>.py``) returns rows of method, setting, error against
an independent reference, median time and the ratio to a baseline timed in the same run. The
command prints the table, optionally writes it (CSV, JSON and a speed-against-error plot per
suite) into ``-o DIR``, and exits with status 1 if any method's error exceeds its documented
bound.
"""

from __future__ import annotations

import logging

HELP = "run the speed-against-error benchmark suites (exit 1 if an error bound is exceeded)"

log = logging.getLogger("crankbench")


def configure(parser) -> None:
    parser.add_argument("--quick", action="store_true",
                        help="small problem sizes and few repeats (about 3 minutes on 2 cores)")
    parser.add_argument("--suite", action="append", default=None, metavar="NAME",
                        help="run only this suite (repeatable); default: all")
    parser.add_argument("--list", action="store_true", help="list the suites and exit")
    parser.add_argument("-o", "--output", metavar="DIR",
                        help="write bench.csv, bench.json and one PNG per suite into DIR")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace existing files in DIR")
    parser.add_argument("--json", action="store_true", help="print the table as JSON")


def run(args) -> int:
    import time

    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.bench import run_suites, suites
    from crankbench.predict._validate import check_option
    from crankbench.predict.errors import ConfigError

    available = suites()
    if args.list:
        for name in available:
            print(name)
        return 0
    names = args.suite or available
    for name in names:
        check_option(name, "--suite", available, error=ConfigError)
    t0 = time.perf_counter()
    rows = run_suites(names, quick=args.quick,
                      progress=lambda n: log.info("bench: suite %s ...", n))
    elapsed = time.perf_counter() - t0
    frame = rows_to_frame(rows)
    failed = frame[~frame["passed"]]
    if args.json:
        print_json({"elapsed_s": elapsed, "quick": args.quick, "rows": frame,
                    "failed": int(len(failed))})
    else:
        shown = frame[["suite", "method", "setting", "error", "error_kind", "bound", "time_s",
                       "baseline", "ratio", "throughput", "passed"]]
        print_table(shown, title=f"speed against error ({'quick' if args.quick else 'full'}, "
                                 f"{elapsed:.1f} s)")
    if args.output:
        write_outputs(frame, args.output, overwrite=args.overwrite)
        log.info("bench: results written to %s", args.output)
    if len(failed):
        log.error("bench: %d row(s) exceed their documented error bound: %s", len(failed),
                  "; ".join(f"{r.suite}/{r.method}/{r.setting}: {r.error:.3g} > {r.bound:.3g}"
                            for r in failed.itertuples()))
        return 1
    return 0


def rows_to_frame(rows):
    """Return the bench rows as a pandas DataFrame (one row per method and setting)."""
    import pandas as pd

    frame = pd.DataFrame([r.as_dict() for r in rows])
    if frame.empty:
        frame = pd.DataFrame(columns=["suite", "method", "setting", "error", "error_kind",
                                      "reference", "time_s", "baseline", "ratio", "throughput",
                                      "throughput_unit", "bound", "note", "extra", "passed"])
    return frame.drop(columns=["extra"], errors="ignore")


def write_outputs(frame, directory, *, overwrite: bool = False) -> None:
    """Write ``bench.csv``, ``bench.json`` and ``<suite>.png`` (error against time) atomically."""
    import json
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crankbench.analysis._output import to_jsonable
    from crankbench.measure._atomic import atomic_path

    from crankbench.measure._atomic import check_overwrite

    out = Path(directory)
    targets = [out / "bench.csv", out / "bench.json",
               *(out / f"{suite}.png" for suite in frame["suite"].unique())]
    for target in targets:  # refuse before writing anything: no mixed old/new output set
        check_overwrite(target, overwrite, option="--overwrite")
    out.mkdir(parents=True, exist_ok=True)
    with atomic_path(out / "bench.csv", overwrite=overwrite, option="--overwrite") as tmp:
        frame.to_csv(tmp, index=False)
    with atomic_path(out / "bench.json", overwrite=overwrite, option="--overwrite") as tmp:
        tmp.write_text(json.dumps(to_jsonable(frame), indent=1))
    for suite, part in frame.groupby("suite"):
        fig = plot_suite(part, suite)
        with atomic_path(out / f"{suite}.png", overwrite=overwrite, option="--overwrite") as tmp:
            fig.savefig(tmp, format="png", dpi=110)
        plt.close(fig)


def plot_suite(part, suite):
    """Error against time, one marker series per method, log-log (the speed-error front)."""
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    for method, rows in part.groupby("method"):
        err = np.maximum(rows["error"].astype(float).to_numpy(), 1e-17)
        ax.loglog(rows["time_s"].astype(float), err, "o-", label=method)
        for t, e, s in zip(rows["time_s"], err, rows["setting"]):
            ax.annotate(str(s), (t, e), fontsize=6, xytext=(2, 2), textcoords="offset points")
    ax.set_xlabel("median time per call (s)")
    ax.set_ylabel("error")
    ax.set_title(f"{suite}: speed against error")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    return fig
