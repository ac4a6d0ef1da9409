"""``crankbench bench``: run the speed-against-error suites and write one table.

Each suite (``analysis/bench/suite_<topic>.py``) returns rows of method, setting, error against
an independent reference, median CPU time and the paired ratio (with its spread) to a baseline
timed in interleaved rounds in the same run (:mod:`analysis.bench`). The command states the
machine, its load and the BLAS thread setting both sides ran with, prints the table (the
``versus`` column says "slower" where we are), optionally writes it (CSV, JSON with the
machine description, and a speed-against-error plot per suite) into ``-o DIR``, and exits with
status 1 if any method's error exceeds its documented bound.
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
    parser.add_argument("--threads", default="1", metavar="N|default",
                        help="BLAS threads for every method and baseline alike (default 1; "
                             "'default' keeps the BLAS library's own setting)")


def run(args) -> int:
    import time

    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.bench import BENCH_THREADS, machine, run_suites, suites
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
    threads = _threads(args.threads)
    before = machine()
    t0 = time.perf_counter()
    extra = {} if threads == BENCH_THREADS else {"threads": threads}
    rows = run_suites(names, quick=args.quick,
                      progress=lambda n: log.info("bench: suite %s ...", n), **extra)
    elapsed = time.perf_counter() - t0
    after = machine()
    settings = {"threads": "BLAS default" if threads is None else threads,
                "clock": "process CPU time (time.process_time), wall time in bench.json",
                "timing": "interleaved rounds after a warm-up; paired ratio = median of "
                          "per-round ratios, spread = interquartile range",
                "load_average_after": after["load_average_1_5_15min"],
                "elapsed_s": elapsed, "quick": bool(args.quick)}
    frame = rows_to_frame(rows)
    failed = frame[frame["fails_run"]]
    missed = frame[~frame["passed"] & ~frame["fails_run"]]
    if args.json:
        print_json({"elapsed_s": elapsed, "quick": args.quick, "machine": before,
                    "settings": settings, "rows": frame, "failed": int(len(failed)),
                    "targets_missed": int(len(missed))})
    else:
        for line in describe(before, settings):
            print(line)
        shown = frame[["suite", "method", "setting", "error", "error_kind", "bound", "time_s",
                       "versus", "throughput", "passed"]]
        print_table(shown, title=f"speed against error ({'quick' if args.quick else 'full'}, "
                                 f"{elapsed:.1f} s)")
    if args.output:
        write_outputs(frame, args.output, overwrite=args.overwrite,
                      meta={"machine": before, "settings": settings})
        log.info("bench: results written to %s", args.output)
    if len(missed):
        log.warning("bench: %d speed target(s) missed on this machine and load (reported, "
                    "not an error bound): %s", len(missed),
                    "; ".join(f"{r.suite}/{r.method}/{r.setting}: {r.error:.3g}x > {r.bound:.3g}x"
                              for r in missed.itertuples()))
    if len(failed):
        log.error("bench: %d row(s) exceed their documented error bound: %s", len(failed),
                  "; ".join(f"{r.suite}/{r.method}/{r.setting}: {r.error:.3g} > {r.bound:.3g}"
                            for r in failed.itertuples()))
        return 1
    return 0


def _threads(value):
    from crankbench.predict.errors import ConfigError

    if str(value).lower() == "default":
        return None
    try:
        threads = int(value)
    except ValueError:
        threads = 0
    if threads < 1:
        raise ConfigError(f"--threads={value!r} is not a positive integer or 'default'")
    return threads


def describe(info: dict, settings: dict) -> list[str]:
    """Header lines: machine, load, BLAS builds and the thread setting of the run."""
    blas = "; ".join(f"{b['internal_api']} {b['version']} ({b['architecture']}, "
                     f"{b['num_threads']} threads by default)" for b in info["blas"]) or "?"
    mem = info["memory_bytes"]
    return [f"machine: {info['cpu']}, {info['cpus_available']} of {info['cpus_logical']} "
            f"logical CPUs, {mem / 2**30:.0f} GiB" if mem else f"machine: {info['cpu']}",
            f"load average (1/5/15 min): before {info['load_average_1_5_15min']}, after "
            f"{settings['load_average_after']}",
            f"python {info['python']}, numpy {info['numpy']}, scipy {info['scipy']}; BLAS: {blas}",
            "resampling kernels: " + ("compiled (numba)" if info.get("compiled_kernels") else
                                      "numpy forms (numba not importable, or "
                                      "CRANKBENCH_NO_NUMBA set): slower"),
            f"threads: {settings['threads']} BLAS thread(s) for every method and baseline; "
            f"clock: {settings['clock']}",
            f"timing: {settings['timing']}"]


def rows_to_frame(rows):
    """Return the bench rows as a pandas DataFrame (one row per method and setting)."""
    import pandas as pd

    frame = pd.DataFrame([r.as_dict() for r in rows])
    if frame.empty:
        frame = pd.DataFrame(columns=["suite", "method", "setting", "error", "error_kind",
                                      "reference", "time_s", "baseline", "ratio", "throughput",
                                      "throughput_unit", "bound", "note", "extra", "ratio_lo",
                                      "ratio_hi", "paired", "clock", "rounds", "target",
                                      "passed", "fails_run", "versus"])
    return frame.drop(columns=["extra"], errors="ignore")


def write_outputs(frame, directory, *, overwrite: bool = False, meta=None) -> None:
    """Write ``bench.csv``, ``bench.json`` (``meta`` -- machine, settings -- and the rows) and
    ``<suite>.png`` (error against time) atomically."""
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
        tmp.write_text(json.dumps(to_jsonable({**(meta or {}), "rows": frame}), indent=1))
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
