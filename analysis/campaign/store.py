"""The campaign results store: every analysed record's results as tidy tables in DuckDB.

A test campaign produces hundreds of records (run-ups per build, load step, damper variant,
engine serial). ``crankbench batch ... --store campaign.duckdb`` appends each record's results
to one embedded DuckDB database, so last week's runs and today's are queried together, trends
are drawn across builds, and other engines (pandas, Spark, Trino) read the tables exported to
Parquet.

Schema (version :data:`SCHEMA_VERSION`; every table keyed by ``run_id``):

``meta``
    ``key``, ``value``: ``schema_version``, ``created_by`` (software version), ``created_at``.
``runs``
    One row per (record, settings): identity (``record_path``, ``record_sha256``,
    ``start_time``, ``test_id``, ``engine_id``, ``build``, all record ``attrs`` as JSON, the
    channel map text), ``settings`` (JSON) and ``settings_key``, the model file and its hash,
    ``status`` ('ok' | 'error') and ``error``, the overall ``verdict`` ('pass' | 'fail' |
    'inconclusive') and its reason, the speed range and sweep rate, the report path, timing
    and the software version.
``criticals``
    Measured resonances matched to predicted critical speeds: ``mode``, ``order``, measured and
    predicted speed (rpm), deviation (%), measured and predicted amplitude and their ratio
    (``units``), and whether each agreed.
``resonances``
    Every measured resonance: speed (rpm), order, frequency (Hz), amplitude, damping ratio,
    confidence.
``order_amplitudes``
    Order amplitudes at reference speeds (rpm) from the order track.
``steady_orders``
    Steady-state order tables of steady runs (:func:`analysis.steady.steady_orders`): per
    steady segment and order the mean speed (rpm) and its spread, the revolutions used, the
    amplitude and its 1σ uncertainty (``units``), the phase (degrees, ``phase_reference``:
    TDC of cylinder 1 when the record has a wheel gap or mark) and its 1σ uncertainty.
``checks``
    Every verdict: check name, ``verdict``, rule, basis, reason, value, limit, units.

A ``run_id`` is a hash of the record's SHA-256 and the settings key (settings + model
hash): writing a run again replaces its rows in one transaction (no duplicates), and a batch
interrupted half-way resumes by skipping the run_ids already stored with status 'ok'.

Safety: the store is only ever created where no file exists; an existing file that is not a
crankbench store, is damaged, has a newer schema, or is locked by another process gives a
:class:`~crankbench.predict.errors.StoreError` and is left untouched. Older schemas are
migrated in place by :func:`migrate` (one transaction per step).

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "campaign.duckdb"
>>> with Store(path, create=True) as store:
...     _ = store.put({"runs": [{"run_id": "r1", "record_path": "a.h5", "status": "ok",
...                              "verdict": "pass"}],
...                    "criticals": [{"run_id": "r1", "mode": 1, "order": 6.0,
...                                   "speed_rpm_measured": 612.0}]})
...     _ = store.put({"runs": [{"run_id": "r1", "record_path": "a.h5", "status": "ok",
...                              "verdict": "pass"}]})  # again: replaces, never duplicates
...     print(store.count("runs"), store.count("criticals"), store.schema_version)
1 0 1
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
from contextlib import contextmanager
from pathlib import Path

from crankbench.predict.errors import StoreError

__all__ = ["SCHEMA_VERSION", "TABLES", "Store", "migrate", "export_parquet", "run_id_for"]

log = logging.getLogger("crankbench")

#: version of the schema below; bump it and add a step to ``_MIGRATIONS`` when it changes
SCHEMA_VERSION = 1

#: table -> ordered (column, DuckDB type); ``run_id`` first in every table
TABLES: dict[str, list[tuple[str, str]]] = {
    "runs": [
        ("run_id", "VARCHAR"), ("record_path", "VARCHAR"), ("record_name", "VARCHAR"),
        ("record_sha256", "VARCHAR"), ("settings_key", "VARCHAR"), ("settings", "VARCHAR"),
        ("model_path", "VARCHAR"), ("model_sha256", "VARCHAR"), ("start_time", "VARCHAR"),
        ("test_id", "VARCHAR"), ("engine_id", "VARCHAR"), ("build", "VARCHAR"),
        ("attrs", "VARCHAR"), ("channel_map", "VARCHAR"), ("channel", "VARCHAR"),
        ("status", "VARCHAR"), ("error", "VARCHAR"), ("verdict", "VARCHAR"),
        ("verdict_reason", "VARCHAR"), ("speed_min_rpm", "DOUBLE"),
        ("speed_max_rpm", "DOUBLE"), ("sweep_rate_rpm_per_s", "DOUBLE"),
        ("resonances", "INTEGER"), ("matched", "INTEGER"), ("max_abs_deviation_pct", "DOUBLE"),
        ("report_path", "VARCHAR"), ("elapsed_s", "DOUBLE"), ("software_version", "VARCHAR"),
        ("analysed_at", "VARCHAR"),
    ],
    "criticals": [
        ("run_id", "VARCHAR"), ("mode", "INTEGER"), ("order", "DOUBLE"),
        ("speed_rpm_measured", "DOUBLE"), ("speed_rpm_predicted", "DOUBLE"),
        ("deviation_pct", "DOUBLE"), ("amplitude_measured", "DOUBLE"),
        ("amplitude_predicted", "DOUBLE"), ("amplitude_ratio", "DOUBLE"), ("units", "VARCHAR"),
        ("speed_tolerance", "DOUBLE"), ("speed_ok", "BOOLEAN"), ("amplitude_ok", "BOOLEAN"),
    ],
    "resonances": [
        ("run_id", "VARCHAR"), ("speed_rpm", "DOUBLE"), ("order", "DOUBLE"),
        ("frequency_hz", "DOUBLE"), ("amplitude", "DOUBLE"), ("damping_ratio", "DOUBLE"),
        ("confidence", "DOUBLE"), ("units", "VARCHAR"),
    ],
    "order_amplitudes": [
        ("run_id", "VARCHAR"), ("order", "DOUBLE"), ("speed_rpm", "DOUBLE"),
        ("amplitude", "DOUBLE"), ("units", "VARCHAR"),
    ],
    "steady_orders": [
        ("run_id", "VARCHAR"), ("segment", "INTEGER"), ("order", "DOUBLE"),
        ("speed_rpm", "DOUBLE"), ("speed_spread_rpm", "DOUBLE"), ("revolutions", "INTEGER"),
        ("amplitude", "DOUBLE"), ("amplitude_uncertainty", "DOUBLE"), ("phase_deg", "DOUBLE"),
        ("phase_uncertainty_deg", "DOUBLE"), ("phase_reference", "VARCHAR"), ("units", "VARCHAR"),
    ],
    "checks": [
        ("run_id", "VARCHAR"), ("check", "VARCHAR"), ("verdict", "VARCHAR"), ("rule", "VARCHAR"),
        ("basis", "VARCHAR"), ("reason", "VARCHAR"), ("value", "DOUBLE"), ("limit", "DOUBLE"),
        ("units", "VARCHAR"),
    ],
}

# schema version n -> SQL statements taking a store from version n to n + 1
_MIGRATIONS: dict[int, list[str]] = {}


def _duckdb():
    import duckdb  # a core dependency; imported on first use (import time)

    return duckdb


def _quote(name: str) -> str:
    return '"' + name.replace('"', '""') + '"'


def _ddl(table: str) -> str:
    cols = ", ".join(f"{_quote(c)} {t}" for c, t in TABLES[table])
    key = ", PRIMARY KEY (run_id)" if table == "runs" else ""
    return f"CREATE TABLE {table} ({cols}{key})"


def run_id_for(record_sha256: str, settings_key: str) -> str:
    """Identity of one analysis of one record: hash of the record and the settings key.

    Examples
    --------
    >>> rid = run_id_for("ab" * 32, "cd" * 10)
    >>> len(rid), rid == run_id_for("ab" * 32, "cd" * 10), rid == run_id_for("ab" * 32, "ef" * 10)
    (24, True, False)
    """
    import hashlib

    return hashlib.sha256(f"{record_sha256}:{settings_key}".encode()).hexdigest()[:24]


def _open_error(path: Path, exc: Exception) -> StoreError:
    text = str(exc)
    if "lock" in text.lower():
        return StoreError(f"{path}: the store is locked by another process (a running batch "
                          "or an open session); wait for it or use another --store file")
    return StoreError(f"{path}: not a readable DuckDB database ({text.splitlines()[0]}); it "
                      "may be truncated or not a crankbench store; it was left untouched")


class Store:
    """An open campaign store (use as a context manager).

    Parameters
    ----------
    path : str or Path
        The DuckDB file.
    create : bool
        Create the store when ``path`` does not exist (never replaces an existing file).
    read_only : bool
        Open for queries only (several readers may share a store; a writer excludes others).
    migrate : bool
        Bring an older schema up to :data:`SCHEMA_VERSION` (else such a store is refused).

    Raises
    ------
    StoreError
        Missing (without ``create``), damaged, foreign, newer-schema or locked store.
    """

    def __init__(self, path, *, create: bool = False, read_only: bool = False,
                 migrate: bool = True):
        self.path = Path(path)
        self.read_only = bool(read_only)
        self._con = None
        duckdb = _duckdb()
        exists = self.path.exists()
        if not exists and not create:
            raise StoreError(f"{self.path}: no such store (create one with "
                             "crankbench batch ... --store FILE)")
        if exists and self.path.is_dir():
            raise StoreError(f"{self.path}: is a directory, expected a DuckDB store file")
        if not exists and read_only:
            raise StoreError(f"{self.path}: no such store")
        try:
            self._con = duckdb.connect(str(self.path), read_only=self.read_only)
        except Exception as exc:  # duckdb.IOException / InvalidInputException / ...
            raise _open_error(self.path, exc) from None
        try:
            if not exists:
                self._create()
            self._check_schema(migrate)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ lifecycle ---------
    def __enter__(self) -> "Store":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the connection (releases the lock)."""
        if self._con is not None:
            self._con.close()
            self._con = None

    @property
    def con(self):
        """The DuckDB connection (for ad-hoc SQL)."""
        if self._con is None:
            raise StoreError(f"{self.path}: the store is closed")
        return self._con

    def _create(self) -> None:
        from crankbench.analysis.report.report import crankbench_version

        with self._transaction():
            self.con.execute("CREATE TABLE meta (key VARCHAR PRIMARY KEY, value VARCHAR)")
            for table in TABLES:
                self.con.execute(_ddl(table))
            self.con.executemany("INSERT INTO meta VALUES (?, ?)", [
                ("schema_version", str(SCHEMA_VERSION)),
                ("created_by", f"crankbench {crankbench_version()}"),
                ("created_at", _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")),
            ])
        log.info("%s: new campaign store (schema %d)", self.path, SCHEMA_VERSION)

    def _check_schema(self, do_migrate: bool) -> None:
        tables = {r[0] for r in self.con.execute(
            "SELECT table_name FROM information_schema.tables").fetchall()}
        if "meta" not in tables:
            raise StoreError(f"{self.path}: a DuckDB database but not a crankbench store (no "
                             "'meta' table); it was left untouched")
        row = self.con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
        try:
            version = int(row[0])
        except (TypeError, ValueError):
            raise StoreError(f"{self.path}: the store's schema_version is missing or not a "
                             f"number ({row and row[0]!r})") from None
        if version > SCHEMA_VERSION:
            raise StoreError(f"{self.path}: store schema {version} is newer than this "
                             f"crankbench understands ({SCHEMA_VERSION}); upgrade crankbench")
        if version < SCHEMA_VERSION:
            if self.read_only or not do_migrate:
                raise StoreError(f"{self.path}: store schema {version} is older than "
                                 f"{SCHEMA_VERSION}; open it for writing to migrate it")
            migrate(self, from_version=version)
        missing = [t for t in TABLES if t not in tables and version == SCHEMA_VERSION]
        if missing:
            raise StoreError(f"{self.path}: store schema {version} lacks the tables "
                             f"{', '.join(missing)}; the file is damaged")

    @contextmanager
    def _transaction(self):
        self.con.execute("BEGIN TRANSACTION")
        try:
            yield
        except BaseException:
            self.con.execute("ROLLBACK")
            raise
        self.con.execute("COMMIT")

    # ------------------------------------------------------------------ reading -----------
    @property
    def schema_version(self) -> int:
        """The store's schema version."""
        return int(self.con.execute(
            "SELECT value FROM meta WHERE key = 'schema_version'").fetchone()[0])

    def count(self, table: str) -> int:
        """Number of rows in ``table``."""
        self._check_table(table)
        return int(self.con.execute(f"SELECT count(*) FROM {table}").fetchone()[0])

    def table(self, table: str, where: str = "", params=()):
        """A table (optionally filtered by an SQL ``where`` clause) as a DataFrame."""
        self._check_table(table)
        sql = f"SELECT * FROM {table}" + (f" WHERE {where}" if where else "")
        return self.con.execute(sql, list(params)).df()

    def done_run_ids(self) -> set[str]:
        """run_ids already stored with status 'ok' (what a resumed batch skips)."""
        return {r[0] for r in self.con.execute(
            "SELECT run_id FROM runs WHERE status = 'ok'").fetchall()}

    def _check_table(self, table: str) -> None:
        if table not in TABLES:
            from crankbench.predict._validate import suggest

            raise StoreError(f"no table {table!r} in a campaign store{suggest(table, TABLES)}; "
                             f"tables: {', '.join(TABLES)}")

    # ------------------------------------------------------------------ writing -----------
    def put(self, document: dict) -> str:
        """Write one run's rows, replacing any earlier rows of the same ``run_id``.

        Parameters
        ----------
        document : dict
            Table name -> list of row dicts (see :data:`TABLES`; missing columns are NULL,
            unknown columns are an error). ``runs`` holds exactly one row.

        Returns
        -------
        str
            The run_id written.
        """
        if self.read_only:
            raise StoreError(f"{self.path}: opened read-only")
        unknown = set(document) - set(TABLES)
        if unknown:
            raise StoreError(f"unknown store tables {sorted(unknown)}; tables: "
                             f"{', '.join(TABLES)}")
        runs = document.get("runs") or []
        if len(runs) != 1 or not runs[0].get("run_id"):
            raise StoreError("a store document holds exactly one 'runs' row with a run_id")
        run_id = str(runs[0]["run_id"])
        rows = {}
        for table, entries in document.items():
            cols = [c for c, _ in TABLES[table]]
            out = []
            for entry in entries:
                bad = set(entry) - set(cols)
                if bad:
                    raise StoreError(f"table {table!r} has no columns {sorted(bad)}")
                if entry.get("run_id", run_id) != run_id:
                    raise StoreError(f"table {table!r}: row of run {entry['run_id']!r} in the "
                                     f"document of run {run_id!r}")
                out.append(tuple(_cell({**entry, "run_id": run_id}.get(c)) for c in cols))
            rows[table] = (cols, out)
        with self._transaction():
            for table in TABLES:
                self.con.execute(f"DELETE FROM {table} WHERE run_id = ?", [run_id])
            for table, (cols, values) in rows.items():
                if values:
                    marks = ", ".join("?" * len(cols))
                    names = ", ".join(_quote(c) for c in cols)
                    self.con.executemany(f"INSERT INTO {table} ({names}) VALUES ({marks})",
                                         values)
        return run_id


def _cell(value):
    """A Python value DuckDB stores: JSON text for dicts/lists, None for NaN."""
    import math

    import numpy as np

    if isinstance(value, (dict, list, tuple)):
        from crankbench.analysis._output import to_jsonable

        return json.dumps(to_jsonable(value), sort_keys=True)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def migrate(store: Store, *, from_version: int) -> None:
    """Apply the schema steps from ``from_version`` to :data:`SCHEMA_VERSION` in place.

    Each step runs in its own transaction and records the new version, so an interrupted
    migration leaves the store at a consistent earlier version.
    """
    version = from_version
    while version < SCHEMA_VERSION:
        steps = _MIGRATIONS.get(version)
        if steps is None:
            raise StoreError(f"{store.path}: no migration from store schema {version}")
        with store._transaction():
            for sql in steps:
                store.con.execute(sql)
            store.con.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'",
                              [str(version + 1)])
        log.info("%s: store migrated from schema %d to %d", store.path, version, version + 1)
        version += 1


def export_parquet(store_path, out_dir, *, overwrite: bool = False) -> list[Path]:
    """Export every table of a store to ``out_dir/<table>.parquet`` (atomically, as a folder).

    The folder is written next to ``out_dir`` under a temporary name and renamed when
    complete; an existing ``out_dir`` is replaced only with ``overwrite=True``.

    Returns
    -------
    list of Path
        The Parquet files.
    """
    import os
    import shutil
    import tempfile

    out_dir = Path(out_dir)
    if out_dir.exists() and not overwrite:
        raise FileExistsError(f"{out_dir} exists; pass --overwrite to replace it")
    if out_dir.resolve() == Path(store_path).resolve():
        raise StoreError(f"{out_dir}: the export folder would replace the store itself")
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", suffix=".part", dir=out_dir.parent))
    try:
        with Store(store_path, read_only=True) as store:
            for table in TABLES:
                target = tmp / f"{table}.parquet"
                store.con.execute(f"COPY (SELECT * FROM {table}) TO "
                                  f"'{str(target).replace(chr(39), chr(39) * 2)}' "
                                  "(FORMAT parquet)")
        if out_dir.exists():
            shutil.rmtree(out_dir)
        os.replace(tmp, out_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return [out_dir / f"{t}.parquet" for t in TABLES]
