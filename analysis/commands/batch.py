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

Nothing lost. Every path is resolved before the work is submitted (a worker may run in
another directory); no output (summary, cache, report, store) may be a record, a record's
sidecar or the model, whatever ``--overwrite`` says; reports are named after each record's
path relative to the records' common folder (``a/run.h5`` → ``DIR/a/run.html``, ``b/run.h5``
→ ``DIR/b/run.html``; ``run.h5`` beside ``run.csv`` → ``run.h5.html``), so no two records
share a report, and an existing report is refused before any work unless ``--overwrite``.

Cluster. ``--scheduler ADDRESS`` is checked before anything is submitted: a scheduler that
does not answer within a few seconds is a one-line error.
"""

from __future__ import annotations

HELP = "run compare on many records in parallel (dask) into one summary table"


#: seconds to wait for a --scheduler to answer before giving up
CONNECT_TIMEOUT_S = 5.0


def configure(parser) -> None:
    from crankbench.analysis.commands._args import integer
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
    parser.add_argument("--workers", type=integer(low=1, high=1024), default=None,
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
            hint = ""
            if pat.replace(".", "", 1).replace(",", "").isdigit():
                hint = ("; a number here is usually a list written with spaces: list options "
                        "take commas (--orders 2,4) or are repeated (--orders 2 --orders 4)")
            raise FileNotFoundError(f"no record matches {pat!r}{hint}")
        files.extend(hits)
    seen, out = set(), []
    for f in files:
        key = str(Path(f).resolve())
        if key not in seen and Path(f).is_file():
            seen.add(key)
            out.append(f)
    return out


def report_names(files) -> list:
    """Report file name (relative path ending in ``.html``) of each record: its path relative
    to the records' common folder without the suffix, or with it where two records of one
    folder share a stem (``run.h5`` and ``run.csv``).

    Examples
    --------
    >>> [str(p) for p in report_names(["/d/a/run.h5", "/d/b/run.h5"])]
    ['a/run.html', 'b/run.html']
    >>> [str(p) for p in report_names(["/d/run.h5", "/d/run.csv", "/d/x.h5"])]
    ['run.h5.html', 'run.csv.html', 'x.html']
    """
    import os
    from pathlib import Path

    files = [Path(os.path.abspath(f)) for f in files]
    if not files:
        return []
    root = Path(os.path.commonpath([str(f.parent) for f in files]))
    rel = [f.relative_to(root) for f in files]
    stems = [r.parent / r.stem for r in rel]
    return [(st.parent / (st.name + ".html")) if stems.count(st) == 1 else
            (r.parent / (r.name + ".html")) for r, st in zip(rel, stems)]


def cache_key(record_path, model_sha, options, report=None) -> str:
    """Key of a record's cached row: record hash + model hash + options (+ report path)."""
    import hashlib
    import json

    from crankbench.analysis.report import file_sha256

    h = hashlib.sha256()
    h.update(file_sha256(record_path).encode())
    h.update(model_sha.encode())
    h.update(json.dumps(options, sort_keys=True, default=str).encode())
    if report is not None:
        h.update(str(report).encode())
    return h.hexdigest()[:20]


def process_one(record_path, model_path, options, cache_file=None, report_path=None,
                overwrite=False, store_run=None, display=None) -> dict:
    """Analyse one record; return its summary row (``status`` 'ok' or 'error').

    Never raises for a bad record: the error is returned in the row (``error``) so the batch
    goes on. Paths are absolute (resolved before submission); ``display`` is the record as
    the user named it (the row's ``record``). With ``store_run`` (dict with ``run_id``,
    ``settings``, ``settings_key``, ``model_sha256``) the row carries the record's store
    document under ``"_document"``.
    """
    import json
    import logging
    import time
    from pathlib import Path

    from crankbench.analysis.pipeline import LoadCase, analyse, load_from_record_file
    from crankbench.measure._atomic import atomic_path

    log = logging.getLogger("crankbench")
    display = str(display or record_path)
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
        row["record"] = display
        if report_path is not None:
            builder(result, record_path=record_path, model_path=model_path).save(
                report_path, overwrite=overwrite, option="--overwrite")
            row["report"] = str(report_path)
        if store_run is not None:
            from crankbench.analysis.campaign.documents import document_from_result

            document = document_from_result(
                result, record_path=record_path, run_id=store_run["run_id"],
                settings=store_run["settings"], model_path=model_path,
                model_sha256=store_run["model_sha256"],
                settings_key_=store_run["settings_key"], report_path=row.get("report"),
                elapsed_s=time.perf_counter() - t0)
    except Exception as exc:  # noqa: BLE001 - a failing record is reported, never fatal
        log.warning("%s: failed: %s", display, exc)
        error = {"record": display, "status": "error",
                 "error": f"{type(exc).__name__}: {exc}".replace(str(record_path), display),
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


def check_scheduler(address: str, *, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Refuse a ``--scheduler`` address that nothing answers, in one line, before any work.

    A ``tcp://HOST:PORT`` (or ``HOST:PORT``) address is probed with a plain TCP connection
    (``timeout`` seconds); other protocols are left to the client's own connection timeout.

    Raises
    ------
    ConfigError
        Malformed address, unknown host, refused or timed-out connection.
    """
    import socket

    from crankbench.predict.errors import ConfigError

    text = address.strip()
    proto, sep, rest = text.partition("://")
    if not sep:
        proto, rest = "tcp", text
    if proto not in ("tcp", "tls", "inproc", "ucx", "ws", "wss"):
        raise ConfigError(f"--scheduler {address!r}: unknown protocol {proto!r}; expected an "
                          "address such as tcp://HOST:8786")
    if proto != "tcp":
        return
    host, _, port = rest.rstrip("/").rpartition(":")
    host = host.strip("[]")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"--scheduler {address!r}: expected tcp://HOST:PORT (e.g. "
                          "tcp://127.0.0.1:8786)")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            pass
    except socket.gaierror:
        raise ConfigError(f"--scheduler {address!r}: unknown host {host!r}") from None
    except TimeoutError:
        raise ConfigError(f"--scheduler {address!r}: no answer within {timeout:g} s; is a "
                          "dask scheduler running there (dask scheduler)?") from None
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ConfigError(f"--scheduler {address!r}: no dask scheduler answers there "
                          f"({reason.lower()}); start one with `dask scheduler` and workers "
                          "with `dask worker ADDRESS`, or omit --scheduler to use local "
                          "threads") from None


def _client(distributed, address):
    """A distributed Client, with connection failures as one-line ConfigErrors."""
    from crankbench.predict.errors import ConfigError

    try:
        return distributed.Client(address, timeout=f"{max(CONNECT_TIMEOUT_S, 10.0):g}s")
    except (OSError, TimeoutError, ValueError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ConfigError(f"--scheduler {address!r}: could not connect ({first})") from None


def _compute(tasks, *, scheduler, workers, progress):
    """Run dask.delayed tasks locally (threads) or on a distributed cluster; ``progress(row)``
    is called in this process as each record's row arrives."""
    import dask

    if scheduler:
        from crankbench.predict._validate import require

        distributed = require("distributed", extra="distributed",
                              feature="crankbench batch --scheduler")
        client = _client(distributed, scheduler)
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


def _cached_row(cache_file, report_path):
    """The cached row of a finished record, or None (missing, unreadable, or its report was
    asked for and is gone)."""
    import json
    import logging

    if cache_file is None or not cache_file.is_file():
        return None
    try:
        row = json.loads(cache_file.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        logging.getLogger("crankbench").info("%s: unreadable cache entry, recomputing",
                                             cache_file)
        return None
    if report_path is not None and not (row.get("report") and report_path.is_file()):
        return None
    return row


def run(args) -> int:
    import logging
    from pathlib import Path

    from tqdm import tqdm

    from crankbench.analysis._output import to_jsonable
    from crankbench.analysis.commands._pipeline_cli import check_common, options_from_args
    from crankbench.analysis.report import file_sha256
    from crankbench.measure._atomic import check_overwrite
    from crankbench.predict.errors import ConfigError

    log = logging.getLogger("crankbench")
    out = Path(args.output)
    if out.suffix.lower() not in (".csv", ".json"):
        raise ConfigError(f"-o {args.output!r} must end in .csv or .json")
    model = Path(args.model)
    if not model.is_file():
        raise FileNotFoundError(f"{model}: no such model file")
    if args.reports is not None and Path(args.reports).exists() and \
            not Path(args.reports).is_dir():
        raise ConfigError(f"--reports {args.reports}: exists and is not a folder")
    from crankbench.analysis.vibrograph import model_kind

    if getattr(args, "store", None) and model_kind(model) == "engine":
        raise ConfigError("--store keeps shaft-line runs; an engine model's vibrograph "
                          "comparison is not stored (the summary CSV/JSON has its rows)")
    files = expand(args.pattern)
    plan = _plan(files, model, out, args)          # every output checked against every input
    check_overwrite(out, args.overwrite, option="--overwrite")
    check_common(args, records=plan["records"][:1], model=plan["model"])
    if args.scheduler:
        from crankbench.predict._validate import require

        require("distributed", extra="distributed", feature="crankbench batch --scheduler")
        check_scheduler(args.scheduler)
    model = plan["model"]                          # absolute from here on
    options = options_from_args(args)  # load per record from its truth when not given
    if options["load"] is not None:
        options["load"] = dict(imep=options["load"].imep, law=options["load"].law,
                               reference_rpm=options["load"].reference_rpm)
    model_sha = file_sha256(model)
    if options.get("channel_map"):  # the map's text is part of what a cached row depends on
        from crankbench.measure.channelmap import load_map

        model_sha += load_map(options["channel_map"]).sha256   # validated before any record
        options["channel_map"] = str(Path(options["channel_map"]).resolve())
    cache_dir = plan["cache_dir"]
    store, store_settings, skey, done = None, None, None, set()
    if args.store:
        from crankbench.analysis.campaign.documents import settings_key
        from crankbench.analysis.campaign.store import Store

        store_path = Path(args.store)
        store_settings = {**to_jsonable(options), "model": model.name}
        skey = settings_key(store_settings, model_sha)
        if store_path.exists():   # what is done, without creating anything yet
            with Store(store_path, read_only=True) as peek:
                done = peek.done_run_ids()
    rows, tasks = [], []
    # every task planned (and existing reports refused) before the store is created
    _queue(files, args, options, model, model_sha, cache_dir, rows, tasks, bool(args.store),
           store_settings, skey, done, plan)
    if args.store:
        store = Store(store_path, create=True)
    try:
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


def _plan(files, model, out, args) -> dict:
    """Absolute paths of every input and output, checked: no output is an input (records,
    sidecars, the model and the files it names) or another output."""
    import os
    from pathlib import Path

    from crankbench.analysis.commands._files import (check_outputs, map_inputs, model_inputs,
                                                     record_inputs)
    from crankbench.predict.errors import ConfigError

    # every path absolute before anything is submitted: a worker may run elsewhere
    records = [Path(os.path.abspath(f)) for f in files]
    model = Path(os.path.abspath(model))
    cache_dir = Path(os.path.abspath(out.with_name(out.name + ".cache")))
    reports = [None] * len(records)
    if args.reports is not None:
        base = Path(os.path.abspath(args.reports))
        reports = [base / name for name in report_names(records)]
    inputs = ([pair for f in records for pair in record_inputs(f)] + model_inputs(model)
              + map_inputs(args))
    outputs = [(out, f"-o {out}")]
    if args.store:
        outputs.append((Path(args.store), f"--store {args.store}"))
    if args.reports is not None:
        outputs += [(r, f"the report of {f} ({r})") for f, r in zip(files, reports)]
    check_outputs(outputs, inputs)
    for f in records:
        if same_tree(cache_dir, f):
            raise ConfigError(f"record {f} lies in the batch cache {cache_dir}; move it or "
                              "choose another -o")
    return {"records": records, "model": model, "cache_dir": cache_dir, "reports": reports}


def _queue(files, args, options, model, model_sha, cache_dir, rows, tasks, store: bool,
           store_settings, skey, done, plan) -> None:
    """Rows of cached/stored records into ``rows``; a dask task per other record (absolute
    paths); existing reports of records to run are refused here, before any work."""
    import dask

    from crankbench.analysis.report import file_sha256

    existing = []
    for f, path, report in zip(files, plan["records"], plan["reports"]):
        store_run = None
        if store:
            from crankbench.analysis.campaign.store import run_id_for

            record_sha = file_sha256(path)
            run_id = run_id_for(record_sha, skey)
            if run_id in done:
                rows.append({"record": str(f), "status": "stored", "run_id": run_id})
                continue
            store_run = {"run_id": run_id, "settings": store_settings, "settings_key": skey,
                         "model_sha256": model_sha, "record_sha256": record_sha}
        cache_file = None
        if not args.no_cache:
            key = cache_key(path, model_sha, options, report)
            cache_file = cache_dir / f"{path.stem}-{key}.json"
            # with a store, the store is what resumes (a cached row has no full results)
            row = None if store else _cached_row(cache_file, report)
            if row is not None:
                row.update(status="cached", record=str(f))
                rows.append(row)
                continue
        if report is not None and report.exists() and not args.overwrite:
            existing.append(report)
        # the key names the record (the progress callback and the store writer look for it)
        task = dask.delayed(process_one, pure=False)(
            str(path), str(model), options, None if cache_file is None else str(cache_file),
            None if report is None else str(report), args.overwrite, store_run, str(f),
            dask_key_name=f"record-{len(tasks)}-{path.name}")
        tasks.append(task)
    if existing:  # refused before any work, never a good record marked failed
        shown = ", ".join(str(p) for p in existing[:3]) + (" ..." if len(existing) > 3 else "")
        raise FileExistsError(f"{len(existing)} report(s) exist ({shown}); pass --overwrite "
                              "to replace them")


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


def same_tree(folder, path) -> bool:
    """True when ``path`` lies inside ``folder`` (after resolving links)."""
    import os

    folder, path = os.path.realpath(folder), os.path.realpath(path)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)

