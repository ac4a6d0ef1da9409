"""CSV records with a header naming units.

Written layout (read back exactly: floats as shortest round-trip repr)::

    # crankbench-record: {"start_time": "2026-01-31T12:00:00+00:00", "engine_id": "I4"}
    # channel: {"name": "acc", "dim": "time", "units": "m/s^2", "quantity": "acceleration", ...}
    # channel: {"name": "rpm", "dim": "time_rpm", ...}
    time [s],acc [m/s^2],time_rpm [s],rpm [rad/s],tacho [s]
    0,0.12,0,157.08,0.0012
    ...

Floats are written as their shortest round-trip repr. One column per time dim (``<dim> [s]``) followed by the channels on that clock; channels of a
slower clock or pulse trains end early and the rest of their column is left empty.

Foreign CSV files are accepted too: comment lines starting with ``#`` are skipped; the first
column whose name is ``time``/``t``/``Time`` (optionally with a unit) is the time axis; every
other column is a channel named ``name [unit]`` or ``name (unit)``, converted to SI with
:func:`measure.units.to_si`; the sample rate is inferred from the time column; the quantity from
the unit. A column without a unit is an error naming it.
"""

from __future__ import annotations

import io as _io
import json
import re

import numpy as np
import pandas as pd
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

FORMAT = "CSV with units in the header"
_HEADER_RE = re.compile(r"^\s*(?P<name>.*?)\s*(?:\[(?P<u1>[^\]]*)\]|\((?P<u2>.*)\))\s*$")
_TIME_NAMES = {"time", "t", "zeit", "timestamp", "time_s"}


def check_magic(head: bytes) -> bool:
    """Text without NUL bytes."""
    return b"\x00" not in head


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


def _split_header(line: str) -> tuple[str, str | None]:
    m = _HEADER_RE.match(line)
    if m:
        unit = m.group("u1") if m.group("u1") is not None else m.group("u2")
        return m.group("name"), unit.strip()
    return line.strip(), None


def read(path, *, channels=None) -> xr.Dataset:
    """Read a CSV record (crankbench layout or a foreign file with unit headers)."""
    file = str(path)
    record_attrs: dict = {}
    metas: list[dict] = []
    n_comment = 0
    with _io.open(path, "r", encoding="utf-8-sig", errors="strict") as f:
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
    try:
        frame = pd.read_csv(path, skiprows=n_comment, dtype=np.float64, skip_blank_lines=True,
                            encoding="utf-8-sig")
    except pd.errors.EmptyDataError:
        raise RecordError(f"{file}: CSV has no header row or data; expected a header naming "
                          "columns with units, e.g. 'time [s],acc [g]'") from None
    except ValueError as exc:
        raise RecordError(f"{file}: CSV contains a non-numeric value ({exc}); expected numbers "
                          "in every data cell") from None
    if frame.shape[0] == 0:
        raise RecordError(f"{file}: CSV has a header but no data rows")
    if metas:
        with _io.open(path, "rb") as f:
            f.seek(-1, 2)
            if f.read(1) != b"\n":
                raise RecordError(f"{file}: last line has no line break; the file was cut "
                                  "mid-row (truncated?) — expected crankbench CSV rows to end "
                                  "with a newline")
        return _read_native(frame, metas, record_attrs, channels, file)
    return _read_foreign(frame, channels, file)


def _column(frame: pd.DataFrame, header: str, file: str) -> np.ndarray:
    if header not in frame.columns:
        raise RecordError(f"{file}: header names column {header!r} but the table has no such "
                          "column (header/body mismatch)")
    return frame[header].to_numpy()


def _read_native(frame, metas, record_attrs, channels, file) -> xr.Dataset:
    names = [m.get("name") for m in metas]
    wanted = select(names, channels, file=file)
    out, coords = [], {}
    for meta in metas:
        name = meta["name"]
        if name not in wanted:
            continue
        dim = meta.get("dim", "time")
        n = int(meta.get("n", -1))
        col = _column(frame, f"{name} [{meta.get('units', '')}]", file)
        if n < 0:
            n = _trim_length(col)
        if n > col.size:
            raise RecordError(f"{file}: channel {name!r}: header declares {n} samples, the table "
                              f"has {col.size} rows (header/body mismatch; file truncated?)")
        if col.size > n and np.any(np.isfinite(col[n:])):
            raise RecordError(f"{file}: channel {name!r}: header declares {n} samples but the "
                              "column has more values (header/body mismatch)")
        values = col[:n]
        if meta.get("dtype") == "float32":
            values = values.astype(np.float32)
        if not is_pulse_dim(dim) and dim not in coords:
            t = _column(frame, f"{dim} [s]", file)[:n]
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


def _read_foreign(frame, channels, file) -> xr.Dataset:
    headers = [str(c) for c in frame.columns]
    parsed = [_split_header(h) for h in headers]
    time_idx = next((i for i, (name, _) in enumerate(parsed)
                     if name.strip().lower() in _TIME_NAMES), None)
    if time_idx is None:
        raise RecordError(f"{file}: no time column; expected a first column named 'time [s]' "
                          f"(found columns {headers})")
    tname, tunit = parsed[time_idx]
    t = frame[headers[time_idx]].to_numpy()
    n = _trim_length(t)
    t = t[:n]
    if tunit not in (None, "", "s"):
        from ..units import to_si

        t, si, _ = to_si(t, tunit, channel=tname)
        if si != "s":
            raise RecordError(f"{file}: time column {headers[time_idx]!r} has unit {tunit!r}; "
                              "expected a time unit (s, ms)")
    if n < 2:
        raise RecordError(f"{file}: time column has {n} value(s); expected at least 2 to infer "
                          "the sample rate")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise RecordError(f"{file}: time column {headers[time_idx]!r} is empty or NaN/inf at "
                          f"data row {i + 1}; expected a time in every row")
    span = t[-1] - t[0]
    fs = (n - 1) / span if np.isfinite(span) and span > 0 else float("nan")
    names = [p[0] for i, p in enumerate(parsed) if i != time_idx]
    wanted = select(names, channels, file=file)
    out = []
    for i, (name, unit) in enumerate(parsed):
        if i == time_idx or name not in wanted:
            continue
        if unit is None:
            raise RecordError(f"{file}: column {headers[i]!r} names no unit; expected "
                              f"'{name} [unit]', e.g. '{name} [g]'")
        values = frame[headers[i]].to_numpy()[:n]
        values, attrs = si_channel(name, values, {"units": unit, "sample_rate": fs}, file=file)
        out.append((name, "time", values, attrs))
    return build_dataset(out, {"time": t}, {})
