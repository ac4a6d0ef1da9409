"""CSV and other delimited text records (``.csv .txt .tsv .tab .asc .dat``).

Written layout (read back exactly: floats as shortest round-trip repr)::

    # crankbench-record: {"start_time": "2026-01-31T12:00:00+00:00", "engine_id": "I4"}
    # channel: {"name": "acc", "dim": "time", "units": "m/s^2", "quantity": "acceleration", ...}
    # channel: {"name": "rpm", "dim": "time_rpm", ...}
    time [s],acc [m/s^2],time_rpm [s],rpm [rad/s],tacho [s]
    0,0.12,0,157.08,0.0012
    ...

Floats are written as their shortest round-trip repr. One column per time dim (``<dim> [s]``)
followed by the channels on that clock; channels of a slower clock or pulse trains end early
and the rest of their column is left empty.

Foreign text files of any common dialect are accepted too (delimiter, decimal mark, encoding,
preamble and header rows sniffed by :mod:`measure.readers.text`): the column whose name is
``time``/``t``/``Time`` (optionally with a unit) is the time axis (else a sample rate stated in
the preamble); every other column is a channel named ``name [unit]`` or ``name (unit)`` (or
with a units row), converted to SI with :func:`measure.units.to_si`; the quantity from the
unit. What the headers cannot tell (no header row, a column without unit, no time) is an error
naming it; a channel map (:mod:`measure.channelmap`) supplies it. Numbers are parsed in chunks
into preallocated arrays, so memory stays near 8 bytes per value kept.
"""

from __future__ import annotations

import io as _io
import json

import numpy as np
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import is_pulse_dim
from ._common import (
    build_dataset,
    channel_meta,
    clean_attr,
    dims_of,
    meta_json,
    refuse_truth,
    select,
    si_channel,
)

__all__ = ["FORMAT", "check_magic", "read", "write"]

FORMAT = "CSV / delimited text"


def check_magic(head: bytes) -> bool:
    """Text: no NUL bytes (UTF-16 text with its byte-order mark allowed)."""
    return head.startswith((b"\xff\xfe", b"\xfe\xff")) or b"\x00" not in head


def write(record: xr.Dataset, path, *, truth=None) -> dict:
    """Write ``record`` in the layout above (``truth`` is not storable in CSV)."""
    refuse_truth(path, truth)
    columns: list[tuple[str, np.ndarray]] = []
    lines = ["# crankbench-record: " + meta_json({str(k): _jsonable(v)
                                                  for k, v in record.attrs.items()})]
    for name in record.data_vars:
        if any(c in str(name) for c in ',"[]\n\r') or str(name) != str(name).strip():
            raise RecordError(f"{path}: channel name {str(name)!r} cannot be a CSV column header "
                              "(no commas, quotes, brackets, line breaks or outer spaces)")
    for dim, names in dims_of(record).items():
        if not is_pulse_dim(dim):
            columns.append((f"{dim} [s]", np.asarray(record[dim].values, dtype=np.float64)))
        for name in names:
            var = record[name]
            meta = {"name": name, **channel_meta(var, dim=dim), "n": int(var.size),
                    "dtype": str(var.dtype)}
            lines.append("# channel: " + meta_json({k: _jsonable(v) for k, v in meta.items()}))
            columns.append((f"{name} [{var.attrs.get('units', '')}]", np.asarray(var.values)))
    n_rows = max(c.size for _, c in columns)
    with _io.open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
        f.write(",".join(_quote(h) for h, _ in columns) + "\n")
        texts = []
        for _, values in columns:
            # numpy's float -> str is the shortest repr that round-trips (float32 stays
            # exact when read as float64 and cast back)
            txt = values.astype(np.float32 if values.dtype == np.float32 else np.float64
                                ).astype(str)
            pad = np.full(n_rows - values.size, "", dtype=txt.dtype if txt.size else "<U1")
            texts.append(np.concatenate([txt, pad]) if pad.size else txt)
        block = 100_000
        for start in range(0, n_rows, block):
            rows = zip(*(t[start:start + block] for t in texts))
            f.write("\n".join(",".join(r) for r in rows))
            f.write("\n")
    return {}


def _jsonable(v):
    v = clean_attr(v)
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v


def _quote(text: str) -> str:
    return f'"{text}"' if "," in text else text


def read(path, *, channels=None) -> xr.Dataset:
    """Read a CSV record (crankbench layout) or a foreign delimited-text table with headers."""
    from .table import TextTable, table_record

    file = str(path)
    record_attrs: dict = {}
    metas: list[dict] = []
    n_comment = 0
    with _io.open(path, "r", encoding="utf-8-sig", errors="replace") as f:
        for line in f:
            if not line.startswith("#"):
                break
            n_comment += 1
            body = line[1:].strip()
            key, sep, rest = body.partition(":")
            if not sep or key.strip() not in ("crankbench-record", "channel"):
                continue
            try:
                value = json.loads(rest)
            except ValueError as exc:
                raise RecordError(f"{file}: line {n_comment}: bad JSON in '# {key.strip()}:' "
                                  f"header ({exc})") from None
            if key.strip() == "crankbench-record":
                record_attrs = value
            else:
                metas.append(value)
    table = TextTable(path)
    if metas:
        with _io.open(path, "rb") as f:
            f.seek(-1, 2)
            if f.read(1) != b"\n":
                raise RecordError(f"{file}: last line has no line break; the file was cut "
                                  "mid-row (truncated?) — expected crankbench CSV rows to end "
                                  "with a newline")
        return _read_native(table, metas, record_attrs, channels, file)
    return table_record(table, channels=channels)


def _read_native(table, metas, record_attrs, channels, file) -> xr.Dataset:
    from .table import duplicate_names

    duplicate_names(table)
    index = {str(h): i for i, h in enumerate(table.names) if h}
    names = [m.get("name") for m in metas]
    wanted = select(names, channels, file=file)

    def col(header):
        if header not in index:
            raise RecordError(f"{file}: header names column {header!r} but the table has no "
                              "such column (header/body mismatch)")
        return index[header]

    plan = []
    for meta in metas:
        if meta["name"] in wanted:
            dim = meta.get("dim", "time")
            plan.append((meta, col(f"{meta['name']} [{meta.get('units', '')}]"),
                         None if is_pulse_dim(dim) else col(f"{dim} [s]")))
    needed = sorted({c for _, c, tc in plan for c in (c, tc) if c is not None})
    data = dict(zip(needed, table.read(needed))) if needed else {}
    out, coords = [], {}
    for meta, c, tc in plan:
        name = meta["name"]
        dim = meta.get("dim", "time")
        n = int(meta.get("n", -1))
        column = data[c]
        if n < 0:
            n = _trim_length(column)
        if n > column.size:
            raise RecordError(f"{file}: channel {name!r}: header declares {n} samples, the table "
                              f"has {column.size} rows (header/body mismatch; file truncated?)")
        if column.size > n and np.any(np.isfinite(column[n:])):
            raise RecordError(f"{file}: channel {name!r}: header declares {n} samples but the "
                              "column has more values (header/body mismatch)")
        values = column[:n]
        if meta.get("dtype") == "float32":
            values = values.astype(np.float32)
        if tc is not None and dim not in coords:
            t = data[tc][:n]
            if t.size < n or np.isnan(t).any():
                raise RecordError(f"{file}: time column {dim!r} has fewer than the {n} values "
                                  f"channel {name!r} declares (header/body mismatch)")
            coords[dim] = t
        meta = {k: v for k, v in meta.items() if k not in ("name", "n", "dtype")}
        values, attrs = si_channel(name, values, meta, file=file)
        out.append((name, dim, values, attrs))
    return build_dataset(out, coords, dict(record_attrs))


def _trim_length(col: np.ndarray) -> int:
    finite = np.flatnonzero(~np.isnan(col))
    return int(finite[-1]) + 1 if finite.size else 0
