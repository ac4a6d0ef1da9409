"""ASAM MDF4 (.mf4/.mdf) records via asammdf.

Written layout: one MDF data group per clock (its master channel holds the time stamps, s from
record start), channels carrying their unit in the MDF unit field and a JSON comment with the
Record attrs (``{"dim": "time", "quantity": "acceleration", "sample_rate": 51200.0, ...}``).
A pulse train is its own group whose samples are the edge times (time stamps = edge times).
The record attrs are a JSON text in the header comment; ``start_time`` also sets the MDF header
start time.

Foreign MDF files: every numeric 1-D channel is read; the unit comes from the MDF unit field
(converted to SI, unknown units are an error naming the channel), the sample rate from the mean
step of its group's master channel, the first group's clock becomes ``time`` and the others
``time_<first channel of the group>``; the header start time becomes ``start_time``. MDF files
cannot be read in parts here: :func:`measure.io.open` loads them whole.
"""

from __future__ import annotations

import datetime as _dt
import gc
import json
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import is_pulse_dim
from ._common import (
    build_dataset,
    channel_meta,
    dims_of,
    jsonable_attrs,
    refuse_truth,
    select,
    si_channel,
)

__all__ = ["FORMAT", "check_magic", "read", "write"]

FORMAT = "ASAM MDF4"
_TAG = "crankbench-record:"


def check_magic(head: bytes) -> bool:
    """MDF identification block starts with ``MDF     `` (or ``UnFinMF`` for unfinalised)."""
    return head[:8] in (b"MDF     ", b"UnFinMF ")


def _asammdf():
    import asammdf

    return asammdf



def write(record: xr.Dataset, path, *, truth=None) -> dict:
    """Write ``record`` as MDF 4.10."""
    refuse_truth(path, truth)
    asammdf = _asammdf()
    mdf = asammdf.MDF(version="4.10")
    try:
        for dim, names in dims_of(record).items():
            signals = []
            for name in names:
                var = record[name]
                values = np.asarray(var.values)
                if is_pulse_dim(dim):
                    stamps = values.astype(np.float64)
                else:
                    stamps = np.asarray(record[dim].values, dtype=np.float64)
                meta = channel_meta(var, dim=dim)
                meta.pop("units", None)
                signals.append(asammdf.Signal(values, stamps, name=name,
                                              unit=str(var.attrs.get("units", "")),
                                              comment=json.dumps(jsonable_attrs(meta))))
            mdf.append(signals, comment=f"crankbench clock {dim}")
        attrs = jsonable_attrs(dict(record.attrs))
        mdf.header.comment = _TAG + json.dumps(attrs)
        if "start_time" in attrs:
            start = _dt.datetime.fromisoformat(str(attrs["start_time"]))
            if start.tzinfo is None:
                start = start.replace(tzinfo=_dt.timezone.utc)
            mdf.header.start_time = start
        # asammdf appends ".mf4" to a name without it: save beside, then move onto ``path``
        saved = mdf.save(str(path) + ".mf4", overwrite=True)
        os.replace(saved, path)
    finally:
        mdf.close()
    return {}


def _header_attrs(mdf) -> dict | None:
    text = mdf.header.comment or ""
    if text.lstrip().startswith("<"):
        try:
            root = ET.fromstring(text)
            tx = root.find("TX")
            text = tx.text if tx is not None and tx.text else ""
        except ET.ParseError:
            text = ""
    text = text.strip()
    if text.startswith(_TAG):
        try:
            return json.loads(text[len(_TAG):])
        except ValueError:
            return None
    return None


def _channel_meta(comment: str) -> dict | None:
    try:
        meta = json.loads(comment) if comment else None
    except ValueError:
        return None
    return meta if isinstance(meta, dict) and "dim" in meta else None


def _open(asammdf, path, file: str):
    """``asammdf.MDF(path)``; on a corrupt file raise RecordError without asammdf's noise.

    A failed ``MDF(...)`` leaves a half-built object whose ``__del__`` raises; it is collected
    here with the unraisable-exception hook silenced, so users see one clear message.
    """
    hook = sys.unraisablehook
    sys.unraisablehook = lambda unraisable: None
    try:
        try:
            return asammdf.MDF(str(path))
        except Exception as exc:  # noqa: BLE001 - any library failure means a corrupt file
            reason = f"{type(exc).__name__}: {exc}"
        gc.collect()
    finally:
        sys.unraisablehook = hook
    size = os.path.getsize(path)
    raise RecordError(f"{file}: cannot read as {FORMAT} ({reason}); the file ({size} bytes) is "
                      "truncated or corrupt")


def read(path, *, channels=None) -> xr.Dataset:
    """Read an MDF4 file fully into memory."""
    asammdf = _asammdf()
    file = str(path)
    mdf = _open(asammdf, path, file)
    try:
        header = _header_attrs(mdf)
        entries = []  # (name, group, index, meta or None)
        for gi, group in enumerate(mdf.groups):
            for ci, ch in enumerate(group.channels):
                if ch.channel_type in (2, 3):  # master / virtual master
                    continue
                entries.append((ch.name, gi, ci, _channel_meta(ch.comment), ch.unit))
        names = [e[0] for e in entries]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise RecordError(f"{file}: channel name(s) {dup} appear in several MDF groups; "
                              "expected unique names")
        wanted = set(select(names, channels, file=file))
        out, coords = [], {}
        group_dims: dict[int, str] = {}
        for name, gi, ci, meta, unit in entries:
            if name not in wanted:
                continue
            sig = mdf.get(name, group=gi, index=ci, raw=False)
            samples = np.asarray(sig.samples)
            if samples.ndim != 1 or samples.dtype.kind not in "fiu":
                if channels is not None:
                    raise RecordError(f"{file}: channel {name!r} is not a numeric 1-D signal "
                                      f"(dtype {samples.dtype})")
                continue
            stamps = np.asarray(sig.timestamps, dtype=np.float64)
            if meta is None:  # foreign file
                dim = group_dims.setdefault(gi, "time" if not group_dims else f"time_{name}")
                meta = {"units": unit or sig.unit, "dim": dim}
                if stamps.size >= 2 and stamps[-1] > stamps[0]:
                    meta["sample_rate"] = (stamps.size - 1) / (stamps[-1] - stamps[0])
            else:
                meta = dict(meta)
                meta["units"] = unit if unit else sig.unit
                dim = meta["dim"]
            if is_pulse_dim(dim):
                samples = stamps if meta.get("quantity") == "pulse_times" else samples
            elif dim not in coords:
                coords[dim] = stamps
            elif coords[dim].shape != stamps.shape:
                raise RecordError(f"{file}: channel {name!r} on dim {dim!r} has {stamps.size} "
                                  f"time stamps, other channels {coords[dim].size} (header/body "
                                  "mismatch)")
            if samples.dtype.kind in "iu":
                samples = samples.astype(np.float64)
            values, attrs = si_channel(name, samples, meta, file=file)
            out.append((name, dim, values, attrs))
        if header is not None:
            attrs = dict(header)
        else:
            attrs = {}
            start = mdf.header.start_time
            if isinstance(start, _dt.datetime):
                attrs["start_time"] = start.isoformat()
    finally:
        mdf.close()
    order = {n: i for i, n in enumerate(select(names, channels, file=file))}
    out.sort(key=lambda e: order.get(e[0], 0))
    return build_dataset(out, coords, attrs)
