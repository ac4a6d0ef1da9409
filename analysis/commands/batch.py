"""``crankbench batch 'runs/*.h5' --model MODEL.toml [-o summary.csv] [--scheduler ADDRESS]``.

Runs the chain of :mod:`analysis.pipeline` (a shaft-line model) or the vibrograph comparison
(an engine model with ``[mounts]``: the row carries the worst measured/predicted ratio and the
verdict) on many records in parallel with dask — threads
in this process by default, or an existing ``dask.distributed`` cluster with ``--scheduler``
(``pip install 'crankbench[distributed]'``) — and writes one summary row per record (CSV,
atomically). A record that fails is reported with its error and skipped; the others go on.

Resuming: each finished record's row is cached as JSON in ``<summary>.cache/`` under a key
made of the record's SHA-256, the model file's SHA-256 and the options, written atomically;
a re-run skips records whose row is cached (``--no-cache`` recomputes everything). Failed
records are not cached, so a re-run retries them.
"""

from __future__ import annotations

HELP = "run compare on many records in parallel (dask) into one summary table"


def configure(parser) -> None:
    from crankbench.analysis.commands._pipeline_cli import add_common_arguments

    parser.add_argument("pattern", metavar="PATTERN", nargs="+",
                        help="record files or glob patterns (quote them: 'runs/*.h5')")
    parser.add_argument("--model", required=True, metavar="MODEL.toml",
                        help="shaft-line model, or an engine model with [mounts] (TOML)")
    parser.add_argument("-o", "--output", default="summary.csv", metavar="FILE",
                        help="summary table (.csv or .json; default summary.csv)")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace an existing summary (cached rows are still reused)")
    parser.add_argument("--scheduler", metavar="ADDRESS", default=None,
                        help="address of a dask.distributed scheduler (default: local threads)")
    parser.add_argument("--workers", type=int, default=None,
                        help="threads for the local scheduler (default: dask's choice)")
    parser.add_argument("--no-cache", action="store_true", help="ignore and do not write cache")
    parser.add_argument("--reports", metavar="DIR", default=None,
                        help="also write one HTML report per record into DIR (existing "
                             "reports are replaced only with --overwrite)")
    add_common_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")


def expand(patterns) -> list:
    """Files matching the patterns (sorted, unique); a pattern matching nothing is an error."""
    import glob
    from pathlib import Path

    files = []
    for pat in patterns:
        hits = sorted(glob.glob(pat, recursive=True)) if any(c in pat for c in "*?[") else \
            ([pat] if Path(pat).exists() else [])
        if not hits:
            raise FileNotFoundError(f"no record matches {pat!r}")
        files.extend(hits)
    seen, out = set(), []
    for f in files:
        key = str(Path(f).resolve())
        if key not in seen and Path(f).is_file():
            seen.add(key)
            out.append(f)
    return out


def cache_key(record_path, model_sha, options) -> str:
    """Key of a record's cached row: record hash + model hash + options."""
    import hashlib
    import json

    from crankbench.analysis.report import file_sha256

    h = hashlib.sha256()
    h.update(file_sha256(record_path).encode())
    h.update(model_sha.encode())
    h.update(json.dumps(options, sort_keys=True, default=str).encode())
    return h.hexdigest()[:20]


def process_one(record_path, model_path, options, cache_file=None, report_dir=None,
                overwrite=False) -> dict:
    """Analyse one record; return its summary row (``status`` 'ok' or 'error').

    Never raises for a bad record: the error is returned in the row (``error``) so the batch
    goes on.
    """
    import json
    import logging
    import time
    from pathlib import Path

    from crankbench.analysis.pipeline import LoadCase, analyse, load_from_record_file
    from crankbench.measure._atomic import atomic_path

    log = logging.getLogger("crankbench")
    t0 = time.perf_counter()
    try:
        opts = dict(options)
        if opts.get("load") is None:
            opts["load"] = load_from_record_file(record_path)
        elif isinstance(opts["load"], dict):
            opts["load"] = LoadCase(**opts["load"])
        from crankbench.analysis.vibrograph import compare_vibrograph, model_kind

        if model_kind(model_path) == "engine":
            from crankbench.analysis.commands._pipeline_cli import vibrograph_options
            from crankbench.analysis.vibrograph_report import build_vibrograph_report

            result = compare_vibrograph(record_path, model_path, **vibrograph_options(opts))
            builder = build_vibrograph_report
        else:
            from crankbench.analysis.report.build import build_report as builder

            result = analyse(record_path, model_path, **opts)
        row = {"status": "ok", "error": ""}
        row.update(result.summary())
        row["record"] = str(record_path)
        if report_dir is not None:
            out = Path(report_dir) / (Path(record_path).stem + ".html")
            builder(result, record_path=record_path, model_path=model_path).save(
                out, overwrite=overwrite, option="--overwrite")
            row["report"] = str(out)
    except Exception as exc:  # noqa: BLE001 - a failing record is reported, never fatal
        log.warning("%s: failed: %s", record_path, exc)
        return {"record": str(record_path), "status": "error",
                "error": f"{type(exc).__name__}: {exc}",
                "elapsed_s": time.perf_counter() - t0}
    row["elapsed_s"] = time.perf_counter() - t0
    if cache_file is not None:
        cache_file = Path(cache_file)
        cache_file.parent.mkdir(parents=True, exist_ok=True)
        from crankbench.analysis._output import to_jsonable

        with atomic_path(cache_file, overwrite=True) as tmp:
            tmp.write_text(json.dumps(to_jsonable(row), indent=1), encoding="utf-8")
    return row


def _compute(tasks, *, scheduler, workers, progress):
    """Run dask.delayed tasks locally (threads) or on a distributed cluster."""
    import dask

    if scheduler:
        from crankbench.predict._validate import require

        distributed = require("distributed", extra="distributed",
                              feature="crankbench batch --scheduler")
        client = distributed.Client(scheduler)
        try:
            futures = client.compute(tasks)
            rows = []
            for fut in distributed.as_completed(futures):
                rows.append(fut.result())
                progress()
            return rows
        finally:
            client.close()
    from dask.callbacks import Callback

    class _Bar(Callback):
        def _posttask(self, key, result, dsk, state, worker_id):
            name = key[0] if isinstance(key, tuple) else key
            if str(name).startswith("record-"):
                progress()

    with _Bar():
        return list(dask.compute(*tasks, scheduler="threads", num_workers=workers))


def run(args) -> int:
    import json
    import logging
    from pathlib import Path

    import dask
    import pandas as pd
    from tqdm import tqdm

    from crankbench.analysis._output import print_json, print_table, to_jsonable
    from crankbench.analysis.commands._pipeline_cli import options_from_args
    from crankbench.analysis.report import file_sha256
    from crankbench.measure._atomic import atomic_path, check_overwrite
    from crankbench.predict.errors import ConfigError

    log = logging.getLogger("crankbench")
    out = Path(args.output)
    if out.suffix.lower() not in (".csv", ".json"):
        raise ConfigError(f"-o {args.output!r} must end in .csv or .json")
    check_overwrite(out, args.overwrite, option="--overwrite")
    model = Path(args.model)
    if not model.is_file():
        raise FileNotFoundError(f"{model}: no such model file")
    files = expand(args.pattern)
    options = options_from_args(args)  # load per record from its truth when not given
    if options["load"] is not None:
        options["load"] = dict(imep=options["load"].imep, law=options["load"].law,
                               reference_rpm=options["load"].reference_rpm)
    model_sha = file_sha256(model)
    cache_dir = out.with_name(out.name + ".cache")
    rows, tasks = [], []
    for f in files:
        cache_file = None
        if not args.no_cache:
            cache_file = cache_dir / f"{Path(f).stem}-{cache_key(f, model_sha, options)}.json"
            if cache_file.is_file():
                try:
                    row = json.loads(cache_file.read_text(encoding="utf-8"))
                    row["status"] = "cached"
                    rows.append(row)
                    continue
                except (OSError, ValueError):
                    log.info("%s: unreadable cache entry, recomputing", cache_file)
        task = dask.delayed(process_one, pure=False, name=f"record-{Path(f).name}")(
            f, str(model), options, None if cache_file is None else str(cache_file),
            args.reports, args.overwrite)
        tasks.append(task)
    log.info("%d records: %d cached, %d to run", len(files), len(rows), len(tasks))
    quiet = args.json or log.getEffectiveLevel() > logging.INFO
    bar = tqdm(total=len(tasks), desc="batch", unit="record", leave=False, disable=quiet)
    try:
        if tasks:
            rows.extend(_compute(tasks, scheduler=args.scheduler, workers=args.workers,
                                 progress=lambda: bar.update(1)))
    finally:
        bar.close()
    order = {str(f): i for i, f in enumerate(files)}
    rows.sort(key=lambda r: order.get(r.get("record"), len(order)))
    table = pd.DataFrame(to_jsonable(rows))
    with atomic_path(out, overwrite=args.overwrite, option="--overwrite") as tmp:
        if out.suffix.lower() == ".json":
            tmp.write_text(json.dumps(to_jsonable(rows), indent=1), encoding="utf-8")
        else:
            table.to_csv(tmp, index=False)
    failed = table[table["status"] == "error"] if len(table) else table
    if args.json:
        print_json({"summary": str(out), "records": rows})
    else:
        cols = [c for c in ("record", "status", "verdict", "resonances", "matched",
                            "max_abs_deviation_pct", "comparison_verdict", "limits_verdict",
                            "vibration_worst_ratio", "vibration_verdict", "elapsed_s")
                if c in table]
        print_table(table[cols], title=f"{len(files)} records ({len(failed)} failed)")
        for _, r in failed.iterrows():
            print(f"FAILED {r.record}: {r.error}")
        print(f"summary written: {out}")
    return 0 if len(failed) == 0 else 1
