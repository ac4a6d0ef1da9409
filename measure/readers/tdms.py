"""NI TDMS (.tdms) records via npTDMS; streams channel slices on demand.

Written layout: one TDMS group per clock (group name = the dim, ``time`` / ``time_<group>`` /
``pulse...``); each channel carries the NI waveform properties ``wf_start_offset`` (s),
``wf_increment`` (1/sample_rate, s), ``wf_samples``, ``wf_start_time``, the NI ``unit_string``
and a property ``crankbench`` holding the Record attrs as JSON (exact sample rate, quantity,
sensor metadata, pulse attrs). A clock that is not regular is stored as an extra channel named
after the dim with ``crankbench`` role ``"time"``. Record attrs: root property ``crankbench``.

Foreign TDMS files: each group is a clock (first group ``time``, the others
``time_<group name>``); a channel's unit comes from ``unit_string`` (or ``NI_UnitDescription``),
its clock from the waveform properties ``wf_increment``/``wf_start_offset``, else from a channel
named ``Time``/``time`` in the same group. ``wf_start_time`` of the first channel gives
``start_time``.
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import is_pulse_dim, time_coordinate
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

__all__ = ["FORMAT", "check_magic", "read", "write", "open"]

FORMAT = "NI TDMS"
_TIME_NAMES = ("time", "Time", "TIME", "t", "Zeit")


def check_magic(head: bytes) -> bool:
    """TDMS segments start with the lead-in tag ``TDSm``."""
    return head[:4] == b"TDSm"


def _nptdms():
    import nptdms

    return nptdms



def _datetime64(iso: str):
    import datetime as _dt

    start = _dt.datetime.fromisoformat(iso)
    if start.tzinfo is not None:
        start = start.astimezone(_dt.timezone.utc).replace(tzinfo=None)
    return np.datetime64(start, "us")


def write(record: xr.Dataset, path, *, truth=None) -> dict:
    """Write ``record`` as one TDMS segment per group."""
    refuse_truth(path, truth)
    nptdms = _nptdms()
    attrs = jsonable_attrs(dict(record.attrs))
    root_props = {"crankbench": json.dumps(attrs)}
    start64 = _datetime64(str(attrs["start_time"])) if "start_time" in attrs else None
    objects = [nptdms.RootObject(properties=root_props)]
    for dim, names in dims_of(record).items():
        objects.append(nptdms.GroupObject(dim, properties={}))
        t = None if is_pulse_dim(dim) else np.asarray(record[dim].values, dtype=np.float64)
        fs = record[names[0]].attrs.get("sample_rate")
        regular = None if t is None or fs is None else regular_start(t, float(fs))
        if t is not None and regular is None:
            objects.append(nptdms.ChannelObject(dim, dim, t, properties={
                "unit_string": "s", "crankbench": json.dumps({"role": "time"})}))
        for name in names:
            var = record[name]
            props = {"unit_string": str(var.attrs.get("units", "")),
                     "crankbench": json.dumps({**jsonable_attrs(channel_meta(var, dim=dim)),
                                               "n": int(var.size)})}
            if regular is not None:
                props.update(wf_start_offset=regular, wf_increment=1.0 / float(fs),
                             wf_samples=int(var.size))
                if start64 is not None:
                    props["wf_start_time"] = start64
            objects.append(nptdms.ChannelObject(dim, name, np.asarray(var.values), properties=props))
    with nptdms.TdmsWriter(str(path)) as writer:
        writer.write_segment(objects)
    return {}


def _props(obj) -> dict:
    return dict(obj.properties)


def _meta(channel) -> dict | None:
    text = channel.properties.get("crankbench")
    if not text:
        return None
    try:
        meta = json.loads(text)
    except ValueError:
        return None
    return meta if isinstance(meta, dict) else None


def _plan(tdms, file: str):
    """Return [(name, group, channel, dim, meta, time_spec)] and record attrs."""
    root = _meta(tdms)
    entries = []
    time_channels: dict[str, object] = {}
    for gi, group in enumerate(tdms.groups()):
        for ch in group.channels():
            meta = _meta(ch)
            if meta is not None and meta.get("role") == "time":
                time_channels[group.name] = ch
    first_start = None
    for gi, group in enumerate(tdms.groups()):
        foreign_time = None
        if root is None:
            for ch in group.channels():
                if ch.name in _TIME_NAMES:
                    foreign_time = ch
        for ch in group.channels():
            meta = _meta(ch)
            if meta is not None and meta.get("role") == "time":
                continue
            if root is None and ch is foreign_time:
                continue
            props = _props(ch)
            if meta is None:
                dim = f"time_{group.name}"  # the fastest clock is renamed 'time' below
                meta = {"dim": dim}
            else:
                meta = dict(meta)
                dim = meta["dim"]
            meta["units"] = props.get("unit_string") or props.get("NI_UnitDescription") \
                or meta.get("units")
            n = len(ch)
            declared = meta.pop("n", None)
            if declared is not None and int(declared) != n:
                raise RecordError(f"{file}: channel {ch.name!r} declares {int(declared)} samples "
                                  f"but holds {n} (header/body mismatch; file truncated?)")
            spec = None
            if not is_pulse_dim(dim):
                if "wf_increment" in props:
                    inc = float(props["wf_increment"])
                    if "wf_samples" in props and int(props["wf_samples"]) not in (n, 0):
                        raise RecordError(f"{file}: channel {ch.name!r} declares wf_samples="
                                          f"{int(props['wf_samples'])} but holds {n} samples "
                                          "(header/body mismatch)")
                    if not np.isfinite(inc) or inc <= 0:
                        raise RecordError(f"{file}: channel {ch.name!r} has wf_increment={inc!r}"
                                          " s; expected a finite value > 0")
                    meta.setdefault("sample_rate", 1.0 / inc)
                    spec = ("regular", float(props.get("wf_start_offset", 0.0)),
                            float(meta["sample_rate"]), n)
                    if first_start is None and "wf_start_time" in props:
                        first_start = props["wf_start_time"]
                elif group.name in time_channels or foreign_time is not None:
                    tch = time_channels.get(group.name, foreign_time)
                    spec = ("channel", tch)
                    if "sample_rate" not in meta and len(tch) >= 2:
                        t_first, t_last = float(tch[0]), float(tch[len(tch) - 1])
                        if t_last > t_first:
                            meta["sample_rate"] = (len(tch) - 1) / (t_last - t_first)
                else:
                    raise RecordError(f"{file}: channel {ch.name!r} has no clock: expected the "
                                      "waveform properties wf_increment/wf_start_offset or a "
                                      "'Time' channel in its group")
            entries.append((ch.name, ch, dim, meta, spec))
    if root is None and entries:
        rates = {e[2]: float(e[3].get("sample_rate", 0.0)) for e in entries
                 if not is_pulse_dim(e[2])}
        if rates:
            fastest = max(rates, key=rates.get)
            for e in entries:
                if e[2] == fastest:
                    e[3]["dim"] = "time"
            entries = [(n, c, "time" if d == fastest else d, m, sp)
                       for n, c, d, m, sp in entries]
    if root is not None:
        attrs = dict(root)
    else:
        attrs = {}
        if first_start is not None:
            attrs["start_time"] = str(np.datetime64(first_start, "us")) + "+00:00"
    return entries, attrs


def _time(spec, file: str, name: str) -> np.ndarray:
    if spec[0] == "regular":
        _, start, fs, n = spec
        return time_coordinate(n, fs, start)
    t = np.asarray(spec[1][:], dtype=np.float64)
    return t


def read(path, *, channels=None) -> xr.Dataset:
    """Read a TDMS file fully into memory."""
    nptdms = _nptdms()
    file = str(path)
    tdms = nptdms.TdmsFile.read(str(path))
    entries, attrs = _plan(tdms, file)
    wanted = select([e[0] for e in entries], channels, file=file)
    out, coords = [], {}
    for name, ch, dim, meta, spec in entries:
        if name not in wanted:
            continue
        values = ch[:]
        if values.dtype.kind in "iu":
            values = values.astype(np.float64)
        if spec is not None and dim not in coords:
            coords[dim] = _time(spec, file, name)
            if coords[dim].size != values.size:
                raise RecordError(f"{file}: channel {name!r} has {values.size} samples but its "
                                  f"time channel {coords[dim].size} (header/body mismatch)")
        values, vattrs = si_channel(name, values, meta, file=file)
        out.append((name, dim, values, vattrs))
    out.sort(key=lambda e: wanted.index(e[0]))
    regular = {e[2] for e in entries if e[4] is not None and e[4][0] == "regular"}
    return build_dataset(out, coords, attrs, regular=regular)


class _LazyTdms:
    """Array-like slice of one TDMS channel; reopens the file read-only (streaming) per access."""

    def __init__(self, path: str, group: str, name: str, shape: tuple, dtype):
        self.path, self.group, self.name = path, group, name
        self.shape, self.dtype, self.ndim = shape, np.dtype(dtype), len(shape)

    def __getitem__(self, key):
        nptdms = _nptdms()
        if isinstance(key, tuple):
            (key,) = key
        with nptdms.TdmsFile.open(self.path) as tdms:
            return np.asarray(tdms[self.group][self.name][key])


def open(path, *, chunk_seconds: float = 10.0, channels=None) -> xr.Dataset:  # noqa: A001
    """Open a TDMS file lazily: dask chunks of ``chunk_seconds`` read from disk on demand."""
    import dask.array as da

    nptdms = _nptdms()
    file = str(path)
    with nptdms.TdmsFile.open(str(path)) as tdms:
        entries, attrs = _plan(tdms, file)
        wanted = select([e[0] for e in entries], channels, file=file)
        data_vars, coords = {}, {}
        for name, ch, dim, meta, spec in entries:
            if name not in wanted:
                continue
            n = len(ch)
            fs = meta.get("sample_rate")
            step = max(1, int(round(chunk_seconds * float(fs)))) if fs else max(1, n)
            dtype = ch.dtype if np.dtype(ch.dtype).kind == "f" else np.float64
            arr = da.from_array(_LazyTdms(file, ch.group_name, name, (n,), ch.dtype),
                                chunks=(step,), lock=False, asarray=True,
                                meta=np.empty(0, ch.dtype)).astype(dtype)
            if spec is not None and dim not in coords:
                coords[dim] = _time(spec, file, name)
            values, vattrs = si_channel(name, arr, meta, file=file)
            data_vars[name] = (name, dim, values, vattrs)
    out = [data_vars[n] for n in wanted]
    return build_dataset(out, coords, attrs)
