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

Campaign store: ``--store campaign.duckdb`` also writes every record's full results (identity,
settings, matched criticals, resonances, order amplitudes at reference speeds, steady-state
tables, checks and verdict, timing, version) into the DuckDB store of
:mod:`analysis.campaign.store`, one transaction per record as it completes, written by this
process alone (workers send their results back); a run already in the store with the same
settings is skipped, so an interrupted batch resumes from the store.
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
    parser.add_argument("--store", metavar="FILE.duckdb", default=None,
                        help="also append every record's results to this campaign store "
                             "(created if missing; re-runs replace, never duplicate)")
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
                overwrite=False, store_run=None) -> dict:
    """Analyse one record; return its summary row (``status`` 'ok' or 'error').

    Never raises for a bad record: the error is returned in the row (``error``) so the batch
    goes on. With ``store_run`` (dict with ``run_id``, ``settings``, ``settings_key``,
    ``model_sha256``) the row carries the record's store document under ``"_document"``.
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
        if store_run is not None:
            from crankbench.analysis.campaign.documents import document_from_result

            document = document_from_result(
                result, record_path=record_path, run_id=store_run["run_id"],
                settings=store_run["settings"], model_path=model_path,
                model_sha256=store_run["model_sha256"],
                settings_key_=store_run["settings_key"], report_path=row.get("report"),
                elapsed_s=time.perf_counter() - t0)
    except Exception as exc:  # noqa: BLE001 - a failing record is reported, never fatal
        log.warning("%s: failed: %s", record_path, exc)
        error = {"record": str(record_path), "status": "error",
                 "error": f"{type(exc).__name__}: {exc}",
                 "elapsed_s": time.perf_counter() - t0}
        if store_run is not None:
            from crankbench.analysis.campaign.documents import document_from_error

            error["_document"] = document_from_error(
                record_path=record_path, run_id=store_run["run_id"], error=error["error"],
                settings=store_run["settings"], record_sha256=store_run["record_sha256"],
                model_path=model_path, model_sha256=store_run["model_sha256"],
                settings_key_=store_run["settings_key"], elapsed_s=error["elapsed_s"])
        return error
    row["elapsed_s"] = time.perf_counter() - t0
    if cache_file is not None:
        cache_file = Path(cache_file)
        cache_file.parent.mkdir(parents=True, exist_ok=True)
        from crankbench.analysis._output import to_jsonable

        with atomic_path(cache_file, overwrite=True) as tmp:
            tmp.write_text(json.dumps(to_jsonable(row), indent=1), encoding="utf-8")
    if store_run is not None:
        document["runs"][0]["elapsed_s"] = row["elapsed_s"]
        row["_document"] = document
    return row


def _compute(tasks, *, scheduler, workers, progress):
    """Run dask.delayed tasks locally (threads) or on a distributed cluster; ``progress(row)``
    is called in this process as each record's row arrives."""
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
                progress(rows[-1])
            return rows
        finally:
            client.close()
    from dask.callbacks import Callback

    class _Bar(Callback):
        def _posttask(self, key, result, dsk, state, worker_id):
            name = key[0] if isinstance(key, tuple) else key
            if str(name).startswith("record-"):
                progress(result)

    with _Bar():
        return list(dask.compute(*tasks, scheduler="threads", num_workers=workers))


def run(args) -> int:
    import logging
    from pathlib import Path

    from tqdm import tqdm

    from crankbench.analysis._output import to_jsonable
    from crankbench.analysis.commands._pipeline_cli import options_from_args
    from crankbench.analysis.report import file_sha256
    from crankbench.measure._atomic import check_overwrite
    from crankbench.predict.errors import ConfigError

    log = logging.getLogger("crankbench")
    out = Path(args.output)
    if out.suffix.lower() not in (".csv", ".json"):
        raise ConfigError(f"-o {args.output!r} must end in .csv or .json")
    check_overwrite(out, args.overwrite, option="--overwrite")
    model = Path(args.model)
    if not model.is_file():
        raise FileNotFoundError(f"{model}: no such model file")
    from crankbench.analysis.vibrograph import model_kind

    if getattr(args, "store", None) and model_kind(model) == "engine":
        raise ConfigError("--store keeps shaft-line runs; an engine model's vibrograph "
                          "comparison is not stored (the summary CSV/JSON has its rows)")
    files = expand(args.pattern)
    options = options_from_args(args)  # load per record from its truth when not given
    if options["load"] is not None:
        options["load"] = dict(imep=options["load"].imep, law=options["load"].law,
                               reference_rpm=options["load"].reference_rpm)
    model_sha = file_sha256(model)
    if options.get("channel_map"):  # the map's text is part of what a cached row depends on
        from crankbench.measure.channelmap import load_map

        model_sha += load_map(options["channel_map"]).sha256   # validated before any record
        options["channel_map"] = str(Path(options["channel_map"]).resolve())
    cache_dir = out.with_name(out.name + ".cache")
    store, store_settings, skey, done = None, None, None, set()
    if args.store:
        from crankbench.analysis.campaign.documents import settings_key
        from crankbench.analysis.campaign.store import Store

        store_path = Path(args.store)
        if store_path.resolve() in {Path(f).resolve() for f in files} | {model.resolve(),
                                                                            out.resolve()}:
            raise ConfigError(f"--store {args.store!r} is one of the inputs or the summary")
        store = Store(store_path, create=True)
        store_settings = {**to_jsonable(options), "model": model.name}
        skey = settings_key(store_settings, model_sha)
        done = store.done_run_ids()
    rows, tasks = [], []
    try:
        _queue(files, args, options, model, model_sha, cache_dir, rows, tasks, store,
               store_settings, skey, done)
        log.info("%d records: %d cached or stored, %d to run", len(files), len(rows),
                 len(tasks))
        quiet = args.json or log.getEffectiveLevel() > logging.INFO
        bar = tqdm(total=len(tasks), desc="batch", unit="record", leave=False, disable=quiet)

        def arrived(row):
            bar.update(1)
            document = row.pop("_document", None) if isinstance(row, dict) else None
            if store is not None and document is not None:
                run_id = store.put(document)
                log.info("%s: stored as run %s in %s", row.get("record"), run_id, args.store)

        try:
            if tasks:
                rows.extend(_compute(tasks, scheduler=args.scheduler, workers=args.workers,
                                     progress=arrived))
        finally:
            bar.close()
    finally:
        if store is not None:
            store.close()
    _write_summary(rows, files, out, args)
    return _print_summary(rows, files, out, args)


def _queue(files, args, options, model, model_sha, cache_dir, rows, tasks, store,
           store_settings, skey, done) -> None:
    """Rows of cached/stored records into ``rows``; a dask task per other record."""
    import json
    import logging
    from pathlib import Path

    import dask

    from crankbench.analysis.report import file_sha256

    log = logging.getLogger("crankbench")
    for f in files:
        store_run = None
        if store is not None:
            from crankbench.analysis.campaign.store import run_id_for

            record_sha = file_sha256(f)
            run_id = run_id_for(record_sha, skey)
            if run_id in done:
                rows.append({"record": str(f), "status": "stored", "run_id": run_id})
                continue
            store_run = {"run_id": run_id, "settings": store_settings, "settings_key": skey,
                         "model_sha256": model_sha, "record_sha256": record_sha}
        cache_file = None
        if not args.no_cache:
            cache_file = cache_dir / f"{Path(f).stem}-{cache_key(f, model_sha, options)}.json"
            # with a store, the store is what resumes (a cached row has no full results)
            if store is None and cache_file.is_file():
                try:
                    row = json.loads(cache_file.read_text(encoding="utf-8"))
                    row["status"] = "cached"
                    rows.append(row)
                    continue
                except (OSError, ValueError):
                    log.info("%s: unreadable cache entry, recomputing", cache_file)
        # the key names the record (the progress callback and the store writer look for it)
        task = dask.delayed(process_one, pure=False)(
            f, str(model), options, None if cache_file is None else str(cache_file),
            args.reports, args.overwrite, store_run,
            dask_key_name=f"record-{len(tasks)}-{Path(f).name}")
        tasks.append(task)


def _write_summary(rows, files, out, args) -> None:
    import json

    import pandas as pd

    from crankbench.analysis._output import to_jsonable
    from crankbench.measure._atomic import atomic_path

    order = {str(f): i for i, f in enumerate(files)}
    rows.sort(key=lambda r: order.get(r.get("record"), len(order)))
    table = pd.DataFrame(to_jsonable(rows))
    with atomic_path(out, overwrite=args.overwrite, option="--overwrite") as tmp:
        if out.suffix.lower() == ".json":
            tmp.write_text(json.dumps(to_jsonable(rows), indent=1), encoding="utf-8")
        else:
            table.to_csv(tmp, index=False)


def _print_summary(rows, files, out, args) -> int:
    import pandas as pd

    from crankbench.analysis._output import print_json, print_table, to_jsonable

    table = pd.DataFrame(to_jsonable(rows))
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
