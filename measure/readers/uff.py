"""Universal File Format dataset 58 (.uff/.unv) records via pyuff.

Written layout: a dataset 151 header whose description/db_app/program lines carry the record
attrs as JSON (prefix ``crankbench:``, continued over the three 80-character lines), then one
binary dataset 58 (58b, float64) per channel: ``id1`` = channel name, ``id2``..``id5`` = the
channel's Record attrs as compact JSON continued over the four 80-character lines (exact sample
rate, start offset ``t0``, dim, quantity, sensor metadata), ordinate units label = SI unit,
function type 1 (time response), abscissa in s. Regular clocks use even abscissa spacing;
irregular ones store the abscissa values. Pulse trains: ordinate = edge times (s), abscissa =
pulse index.

The 58 header prints abscissa start and step with 6 significant digits only; our JSON keeps the
exact values. Foreign UFF files are read from the header alone: sample rate = 1/abscissa step
(6 digits), unit from the ordinate units label, channels grouped into clocks by (step, length,
start) — the first clock is ``time``, the others ``time_<first channel>``. UFF files are read
whole (no streaming).
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import is_pulse_dim, nonfinite_spans, time_coordinate
from ._common import (
    build_dataset,
    channel_meta,
    dims_of,
    jsonable_attrs,
    refuse_truth,
    regular_start,
    select,
    si_channel,
)

__all__ = ["FORMAT", "check_magic", "read", "write"]

FORMAT = "UFF dataset 58"
_TAG = "crankbench:"
_LINE = 80
# UFF "specific data type" codes for the ordinate (IDEAS/UFF dataset 58 record 8)
_SPEC = {"displacement": 8, "velocity": 11, "acceleration": 12, "force": 13, "pressure": 15,
         "pulse_times": 17, "voltage": 1, "torque": 1, "angle": 1, "angular_velocity": 1,
         "rotational_speed": 19, "other": 0}


def check_magic(head: bytes) -> bool:
    """A UFF file starts with a ``-1`` delimiter line (right-aligned in 6 columns)."""
    first = head.lstrip(b"\r\n").split(b"\n", 1)[0].strip()
    return first == b"-1"


def _pyuff():
    import pyuff

    return pyuff


def _pack(payload: dict, n_lines: int, what: str, file: str) -> list[str]:
    text = _TAG + json.dumps(payload, separators=(",", ":"), ensure_ascii=True).replace(
        " ", "\\u0020")
    if len(text) > n_lines * _LINE:
        raise RecordError(f"{file}: {what} metadata needs {len(text)} characters, UFF has room "
                          f"for {n_lines * _LINE}; shorten names/attrs or use .h5")
    lines = [text[i:i + _LINE] for i in range(0, len(text), _LINE)]
    return lines + [""] * (n_lines - len(lines))


def _unpack(lines: list[str]) -> dict | None:
    text = "".join(str(s).rstrip() for s in lines)
    if not text.startswith(_TAG):
        return None
    try:
        meta = json.loads(text[len(_TAG):])
    except ValueError:
        return None
    return meta if isinstance(meta, dict) else None



def write(record: xr.Dataset, path, *, truth=None) -> dict:
    """Write ``record`` as a 151 header plus one binary dataset 58 per channel."""
    refuse_truth(path, truth)
    pyuff = _pyuff()
    file = str(path)
    header = jsonable_attrs(dict(record.attrs))
    header["_n_channels"] = len(record.data_vars)
    d1, d2, d3 = _pack(header, 3, "record", file)
    sets = [dict(type=151, model_name="crankbench record", description=d1, db_app=d2,
                 program=d3, date_db_created="", time_db_created="", date_db_saved="",
                 time_db_saved="", date_file_written="", time_file_written="")]
    for dim, names in dims_of(record).items():
        pulse = is_pulse_dim(dim)
        t = None if pulse else np.asarray(record[dim].values, dtype=np.float64)
        for i, name in enumerate(names):
            var = record[name]
            values = np.asarray(var.values, dtype=np.float64)
            spans = nonfinite_spans(values)
            if spans:
                a, b = spans[0]
                raise RecordError(
                    f"{file}: channel {name!r} has NaN/inf samples ({len(spans)} span(s), first "
                    f"samples {a}..{b - 1}); UFF 58 cannot store NaN/inf (they would be written "
                    "as numbers) — write .h5/.nc/.csv/.mf4/.tdms/.wav, or fill the spans")
            meta = channel_meta(var, dim=dim)
            meta.pop("units", None)
            meta["dtype"] = str(var.dtype)
            if pulse:
                x, even = np.arange(values.size, dtype=np.float64), 1
            else:
                fs = float(var.attrs["sample_rate"])
                t0 = regular_start(t, fs)
                even = int(t0 is not None)
                x = t
                if t0 is not None:
                    meta["t0"] = t0
            if values.size < 2:
                raise RecordError(f"{file}: channel {name!r} has {values.size} sample(s); UFF 58 "
                                  "needs at least 2")
            ids = _pack(jsonable_attrs(meta), 4, f"channel {name!r}", file)
            sets.append(dict(
                type=58, binary=1, id1=name[:_LINE], id2=ids[0], id3=ids[1], id4=ids[2],
                id5=ids[3], func_type=1, func_id=i + 1, ver_num=0, load_case_id=0,
                rsp_ent_name=str(var.attrs.get("location", "NONE"))[:10] or "NONE",
                rsp_node=len(sets), rsp_dir=0, ref_ent_name="NONE", ref_node=0, ref_dir=0,
                ord_data_type=4, abscissa_spacing=even,
                abscissa_spec_data_type=0 if pulse else 17,
                abscissa_axis_units_lab="index" if pulse else "s",
                ordinate_spec_data_type=_SPEC.get(var.attrs.get("quantity"), 0),
                ordinate_axis_units_lab=str(var.attrs.get("units", "")),
                orddenom_spec_data_type=0, z_axis_spec_data_type=0, z_axis_value=0.0,
                data=values, x=x))
    pyuff.UFF(file).write_sets(sets, mode="overwrite")
    return {}


def _check_complete(path, file: str) -> None:
    """A complete UFF file ends with the ``-1`` delimiter closing its last dataset."""
    with open(path, "rb") as f:
        f.seek(0, 2)
        size = f.tell()
        f.seek(max(0, size - 16))
        tail = f.read()
    # binary 58 data runs straight into the delimiter, so test the 6-column field only
    if tail.rstrip(b"\r\n\x00")[-6:] != b"    -1":
        raise RecordError(f"{file}: UFF file does not end with the '-1' delimiter of its last "
                          f"dataset ({size} bytes; file truncated?)")


def read(path, *, channels=None) -> xr.Dataset:
    """Read every dataset 58 of a UFF file."""
    pyuff = _pyuff()
    file = str(path)
    _check_complete(path, file)
    uff = pyuff.UFF(file)
    types = list(uff.get_set_types())
    if 58 not in types:
        raise RecordError(f"{file}: UFF file has no dataset 58 (found types "
                          f"{sorted(set(int(t) for t in types))}); expected time records")
    sets = uff.read_sets()
    if isinstance(sets, dict):
        sets = [sets]
    record_attrs: dict = {}
    fn = [s for s in sets if s.get("type") == 58]
    for s in sets:
        if s.get("type") == 151:
            meta = _unpack([s.get("description", ""), s.get("db_app", ""), s.get("program", "")])
            if meta is not None:
                record_attrs = meta
    declared = record_attrs.pop("_n_channels", None)
    if declared is not None and int(declared) != len(fn):
        raise RecordError(f"{file}: header declares {int(declared)} channel(s), the file holds "
                          f"{len(fn)} dataset(s) 58 (header/body mismatch; file truncated?)")
    names = [str(s.get("id1", "")).strip() or f"ch{i + 1}" for i, s in enumerate(fn)]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise RecordError(f"{file}: channel name(s) {dup} repeat; expected unique id1 lines")
    wanted = select(names, channels, file=file)
    out, coords = [], {}
    foreign_clocks: list[tuple] = []
    for name, s in zip(names, fn):
        if name not in wanted:
            continue
        data = np.asarray(s["data"])
        if np.iscomplexobj(data):
            raise RecordError(f"{file}: channel {name!r} holds complex data (a spectrum?); "
                              "expected a real time response (function type 1)")
        x = np.asarray(s.get("x", []), dtype=np.float64)
        n = int(s.get("num_pts", data.size))
        if data.size != n:
            raise RecordError(f"{file}: channel {name!r} declares {n} points but holds "
                              f"{data.size} (header/body mismatch; file truncated?)")
        meta = _unpack([s.get("id2", ""), s.get("id3", ""), s.get("id4", ""), s.get("id5", "")])
        unit = str(s.get("ordinate_axis_units_lab", "")).strip()
        if meta is None:  # foreign file: clock from the header
            inc = float(s.get("abscissa_inc", 0.0))
            key = (inc, n, float(s.get("abscissa_min", 0.0)))
            if key not in foreign_clocks:
                foreign_clocks.append(key)
            dim = "time" if foreign_clocks.index(key) == 0 else f"time_{name}"
            meta = {"dim": dim, "units": unit}
            if inc > 0:
                meta["sample_rate"] = 1.0 / inc
            if dim not in coords:
                coords[dim] = x if x.size == n else time_coordinate(n, 1.0 / inc, key[2])
        else:
            meta = dict(meta)
            meta["units"] = unit
            dim = meta["dim"]
            if not is_pulse_dim(dim) and dim not in coords:
                if "t0" in meta:
                    coords[dim] = time_coordinate(n, float(meta["sample_rate"]), float(meta["t0"]))
                else:
                    coords[dim] = x
            meta.pop("t0", None)
        dtype = meta.pop("dtype", None)
        if dtype == "float32":
            data = data.astype(np.float32)
        values, attrs = si_channel(name, data, meta, file=file)
        out.append((name, dim, values, attrs))
    return build_dataset(out, coords, record_attrs)
