"""WAV records (soundfile) with units and metadata in a JSON sidecar ``<file>.wav.json``.

A WAV file has one sample rate, so it holds the channels of one clock (the record's ``time``
dim, else its fastest clock), one WAV channel each, written as 32-bit float (``FLOAT``) or, if
any is float64, 64-bit float (``DOUBLE``). Channels on other clocks and pulse trains go into the
sidecar inline (they are small: a 100 Hz speed channel, tacho edge times).

Sidecar schema (``<name>.wav.json``, UTF-8 JSON object)::

    {
      "crankbench_sidecar": 1,                  # schema version (required)
      "attrs": {"start_time": "2026-01-31T12:00:00+00:00", "engine_id": "I4", ...},
      "sample_rate": 10000.0,                   # exact rate in Hz (optional: WAV header rate)
      "t0": 0.0,                                # time of the first frame, s (optional, 0)
      "channels": [                             # one entry per WAV channel, in column order
        {"name": "acc", "units": "m/s^2",       # units: any spelling measure.units knows
         "quantity": "acceleration",            # optional if the unit implies it
         "scale": 1.0, "offset": 0.0,           # value = offset + scale * sample (optional;
                                                #   PCM samples are read as fractions of full
                                                #   scale in [-1, 1))
         "dtype": "float32",                    # optional, restores the stored precision
         "location": "block", "direction": "z",
         "sensitivity": 100.0, "sensitivity_units": "mV/g"}   # optional sensor metadata
      ],
      "extra": [                                # channels not on the WAV clock (optional)
        {"name": "rpm", "dim": "time_rpm", "units": "rad/s", "quantity": "rotational_speed",
         "sample_rate": 100.0, "t0": 0.0, "data": [157.08, ...]},
        {"name": "tacho", "dim": "pulse", "units": "s", "quantity": "pulse_times",
         "pulses_per_rev": 60, "missing_teeth": 2, "data": [0.0012, ...]}
      ]
    }

Without a sidecar, a WAV file is read with a :class:`measure.record.RecordWarning`: channels
``ch1``, ``ch2``... in units ``1`` (fraction of full scale), quantity ``other``. The main clock
streams (frames are read on demand by :func:`open`); the sidecar channels are in memory.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import RecordWarning, is_pulse_dim, time_coordinate
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

__all__ = ["FORMAT", "SIDECARS", "check_magic", "read", "write", "open", "sidecar_path"]

FORMAT = "WAV (+ .wav.json sidecar)"
#: Files written beside the target, by suffix.
SIDECARS = (".json",)
SCHEMA_VERSION = 1


def check_magic(head: bytes) -> bool:
    """RIFF/RF64/BW64 container whose form type is WAVE."""
    return head[:4] in (b"RIFF", b"RF64", b"BW64") and head[8:12] == b"WAVE"


def sidecar_path(path) -> Path:
    """``<path>.json`` — e.g. ``run.wav.json`` for ``run.wav``."""
    return Path(str(path) + ".json")


def _sf():
    import soundfile

    return soundfile



def write(record: xr.Dataset, path, *, truth=None) -> dict:
    """Write the main clock to ``path`` and return the sidecar bytes for ``.json``."""
    refuse_truth(path, truth)
    sf = _sf()
    groups = dims_of(record)
    clocks = [d for d in groups if not is_pulse_dim(d)]
    if not clocks:
        raise RecordError(f"{path}: record has no sampled channel; a WAV file needs one clock")
    main = "time" if "time" in clocks else max(
        clocks, key=lambda d: float(record[groups[d][0]].attrs["sample_rate"]))
    names = groups[main]
    fs = float(record[names[0]].attrs["sample_rate"])
    t = np.asarray(record[main].values, dtype=np.float64)
    t0 = regular_start(t, fs)
    if t0 is None:
        raise RecordError(f"{path}: clock {main!r} is not regular; WAV frames need a constant "
                          "sample rate (use .h5)")
    wide = any(record[n].dtype == np.float64 for n in names)
    frames = np.stack([np.asarray(record[n].values, dtype=np.float64 if wide else np.float32)
                       for n in names], axis=1)
    header_rate = int(round(fs))
    if header_rate < 1:
        raise RecordError(f"{path}: sample rate {fs} Hz is below 1 Hz; WAV cannot hold it")
    sf.write(str(path), frames, header_rate, subtype="DOUBLE" if wide else "FLOAT",
             format="WAV")
    side = {"crankbench_sidecar": SCHEMA_VERSION, "attrs": jsonable_attrs(dict(record.attrs)),
            "sample_rate": fs, "t0": t0, "channels": [], "extra": []}
    for n in names:
        meta = jsonable_attrs(channel_meta(record[n]))
        meta.pop("sample_rate", None)
        side["channels"].append({"name": n, **meta, "dtype": str(record[n].dtype)})
    for dim, others in groups.items():
        if dim == main:
            continue
        for n in others:
            var = record[n]
            meta = {"name": n, **jsonable_attrs(channel_meta(var, dim=dim)),
                    "dtype": str(var.dtype)}
            if not is_pulse_dim(dim):
                td = np.asarray(record[dim].values, dtype=np.float64)
                start = regular_start(td, float(var.attrs["sample_rate"]))
                if start is None:
                    meta["time"] = td.tolist()
                else:
                    meta["t0"] = start
            meta["data"] = np.asarray(var.values, dtype=np.float64).tolist()
            side["extra"].append(meta)
    text = json.dumps(side, indent=1, allow_nan=True)
    return {".json": text.encode("utf-8")}


def _load_sidecar(path: Path) -> dict | None:
    side = sidecar_path(path)
    if not side.exists():
        return None
    try:
        meta = json.loads(side.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise RecordError(f"{side}: sidecar is not valid JSON ({exc}); expected the schema in "
                          "measure.readers.wav") from None
    if not isinstance(meta, dict) or "channels" not in meta:
        raise RecordError(f"{side}: sidecar has no 'channels' list; expected the schema in "
                          "measure.readers.wav")
    version = meta.get("crankbench_sidecar", SCHEMA_VERSION)
    if version != SCHEMA_VERSION:
        raise RecordError(f"{side}: sidecar schema version {version!r}; this crankbench reads "
                          f"{SCHEMA_VERSION}")
    return meta


def _plan(path: Path, info, file: str):
    """Column metadata for the WAV frames, sample rate, t0, extra channels and attrs."""
    side = _load_sidecar(path)
    if side is None:
        warnings.warn(f"{file}: no sidecar {sidecar_path(path).name!r}; channels read as "
                      "fractions of full scale (units '1', quantity 'other')", RecordWarning,
                      stacklevel=4)
        cols = [{"name": f"ch{i + 1}", "units": "1", "quantity": "other"}
                for i in range(info.channels)]
        return cols, float(info.samplerate), 0.0, [], {}
    cols = side["channels"]
    if len(cols) != info.channels:
        raise RecordError(f"{file}: sidecar lists {len(cols)} channel(s) but the WAV file has "
                          f"{info.channels} (header/body mismatch)")
    fs = float(side.get("sample_rate", info.samplerate))
    if not np.isfinite(fs) or fs <= 0:
        raise RecordError(f"{file}: sidecar sample_rate={fs!r} Hz; expected a finite value > 0")
    if abs(round(fs) - info.samplerate) > 0.5:
        raise RecordError(f"{file}: sidecar sample_rate {fs:g} Hz disagrees with the WAV header "
                          f"{info.samplerate} Hz (header/body mismatch)")
    return cols, fs, float(side.get("t0", 0.0)), side.get("extra", []), dict(side.get("attrs", {}))


def _column_meta(col: dict, fs: float) -> dict:
    meta = {k: v for k, v in col.items() if k not in ("name", "scale", "offset", "dtype")}
    meta["sample_rate"] = fs
    return meta


def _apply(values, col: dict):
    scale, offset = float(col.get("scale", 1.0)), float(col.get("offset", 0.0))
    if scale != 1.0 or offset != 0.0:
        values = values * values.dtype.type(scale) + values.dtype.type(offset)
    if col.get("dtype") == "float32":
        values = values.astype(np.float32)
    return values


def _extras(extra: list, wanted, file: str):
    out, coords = [], {}
    for e in extra:
        name = e.get("name")
        if name not in wanted:
            continue
        dim = e.get("dim") or f"time_{name}"
        data = np.asarray(e.get("data", []), dtype=np.float64)
        if e.get("dtype") == "float32":
            data = data.astype(np.float32)
        meta = {k: v for k, v in e.items() if k not in ("name", "data", "time", "t0", "dtype")}
        meta["dim"] = dim
        if not is_pulse_dim(dim) and dim not in coords:
            if e.get("time") is not None:
                coords[dim] = np.asarray(e["time"], dtype=np.float64)
            else:
                fs = float(e.get("sample_rate", 0.0))
                if not fs > 0:
                    raise RecordError(f"{file}: sidecar channel {name!r} has sample_rate="
                                      f"{e.get('sample_rate')!r}; expected Hz > 0")
                coords[dim] = time_coordinate(data.size, fs, float(e.get("t0", 0.0)))
        values, attrs = si_channel(name, data, meta, file=file)
        out.append((name, dim, values, attrs))
    return out, coords


def _check_chunks(path: Path, file: str) -> None:
    """Walk the RIFF chunks: the data chunk must be complete (libsndfile reads short ones)."""
    import struct

    size = path.stat().st_size
    with path.open("rb") as f:
        head = f.read(12)
        if head[:4] != b"RIFF":
            return  # RF64/BW64: sizes live in ds64, leave it to libsndfile
        pos = 12
        while pos + 8 <= size:
            f.seek(pos)
            tag, length = struct.unpack("<4sI", f.read(8))
            if tag == b"data":
                if pos + 8 + length > size:
                    raise RecordError(
                        f"{file}: WAV data chunk declares {length} bytes but only "
                        f"{size - pos - 8} are present (header/body mismatch; file truncated?)")
                return
            pos += 8 + length + (length & 1)
    raise RecordError(f"{file}: WAV file has no complete data chunk ({size} bytes; file "
                      "truncated?)")


def read(path, *, channels=None) -> xr.Dataset:
    """Read a WAV file and its sidecar fully into memory."""
    sf = _sf()
    path = Path(path)
    file = str(path)
    _check_chunks(path, file)
    info = sf.info(file)
    cols, fs, t0, extra, attrs = _plan(path, info, file)
    names = [c["name"] for c in cols] + [e.get("name") for e in extra]
    wanted = select(names, channels, file=file)
    frames, _ = sf.read(file, dtype="float64" if info.subtype == "DOUBLE" else "float32",
                        always_2d=True)
    if frames.shape[0] != info.frames:
        raise RecordError(f"{file}: header declares {info.frames} frames, {frames.shape[0]} "
                          "could be read (file truncated?)")
    out, coords = [], {}
    for i, col in enumerate(cols):
        if col["name"] not in wanted:
            continue
        values = _apply(np.ascontiguousarray(frames[:, i]), col)
        values, vattrs = si_channel(col["name"], values, _column_meta(col, fs), file=file)
        out.append((col["name"], "time", values, vattrs))
    if out:
        coords["time"] = time_coordinate(frames.shape[0], fs, t0)
    more, more_coords = _extras(extra, wanted, file)
    out += more
    coords.update(more_coords)
    out.sort(key=lambda e: wanted.index(e[0]))
    return build_dataset(out, coords, attrs, regular=["time"])


class _LazyWav:
    """Array-like view of one WAV channel; reads only the requested frames (read-only)."""

    def __init__(self, path: str, column: int, n: int, dtype):
        self.path, self.column = path, column
        self.shape, self.dtype, self.ndim = (n,), np.dtype(dtype), 1

    def __getitem__(self, key):
        sf = _sf()
        if isinstance(key, tuple):
            (key,) = key
        start, stop, step = key.indices(self.shape[0])
        with sf.SoundFile(self.path, "r") as f:
            f.seek(start)
            block = f.read(max(0, stop - start), dtype=self.dtype.name, always_2d=True)
        return np.ascontiguousarray(block[::step, self.column])


def open(path, *, chunk_seconds: float = 10.0, channels=None) -> xr.Dataset:  # noqa: A001
    """Open a WAV record lazily: frames of ``chunk_seconds`` read on demand."""
    import dask.array as da

    sf = _sf()
    path = Path(path)
    file = str(path)
    _check_chunks(path, file)
    info = sf.info(file)
    cols, fs, t0, extra, attrs = _plan(path, info, file)
    names = [c["name"] for c in cols] + [e.get("name") for e in extra]
    wanted = select(names, channels, file=file)
    dtype = np.float64 if info.subtype == "DOUBLE" else np.float32
    step = max(1, int(round(chunk_seconds * fs)))
    out, coords = [], {}
    for i, col in enumerate(cols):
        if col["name"] not in wanted:
            continue
        arr = da.from_array(_LazyWav(file, i, info.frames, dtype), chunks=(step,), lock=False,
                            asarray=True, meta=np.empty(0, dtype))
        values, vattrs = si_channel(col["name"], _apply(arr, col), _column_meta(col, fs),
                                    file=file)
        out.append((col["name"], "time", values, vattrs))
    if out:
        coords["time"] = time_coordinate(info.frames, fs, t0)
    more, more_coords = _extras(extra, wanted, file)
    out += more
    coords.update(more_coords)
    out.sort(key=lambda e: wanted.index(e[0]))
    return build_dataset(out, coords, attrs)
