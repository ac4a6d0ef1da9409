"""HDF5 in crankbench's native layout (h5py): read, write, stream.

Layout (``crankbench_format = "record"`` and ``crankbench_format_version`` on the root)::

    /                      attrs: crankbench_format, crankbench_format_version = 2 and
                           crankbench_meta: the record's metadata as one JSON text (below)
    /dims/<dim>            group per time or pulse dim (dataset "values": explicit times, s)
    /channels/<name>       dataset (float32/float64; contiguous, starting on a 4 KiB boundary
                           when >= 64 KiB; files written before 2026-11 are chunked: both
                           read the same)
    /truth                 optional netCDF4 group (h5netcdf) holding the synthetic bench's
                           ground truth (order amplitudes along a run, critical speeds)

``crankbench_meta`` (version 2) is ``{"attrs": {record attrs}, "channel_order": [names],
"dims": {dim: {"kind": "regular" | "explicit" | "index", "length": n, "start": s,
"sample_rate": Hz}}, "channels": {name: {Record attrs..., "dim": dim}}}`` (numeric arrays as
``{"__ndarray__": [...], "dtype": "<f8"}``): one attribute read instead of one per attribute
and object (a read of a small record spends more on those than on its samples). The groups
and datasets carry no attribute of ours; any attribute found on them (or on the root besides
the three above) -- set with h5py after writing, say -- overrides the JSON's value of that
name, so a file edited by hand reads as edited. Version 1 files (every value an attribute of
its object: root record attrs and ``channel_order``, ``/dims/<dim>`` kind, length, start,
sample_rate, ``/channels/<name>`` its Record attrs and ``dim``), as written before 2026-11
or by other tools, read the same. Shapes, types, storage and byte offsets always come from
HDF5 itself, never from the JSON.

Regular clocks are stored as three numbers, not as a time array, and read back as an implicit
time coordinate (:class:`measure.timeindex.SampledTimeIndex`: values generated on access,
bit-identical to ``start + i / sample_rate``), by :func:`read` and :func:`open` alike: no time
array is built unless asked for, and a 2 GB record streams with bounded memory.
"""

from __future__ import annotations

import json
import os

import numpy as np
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import is_pulse_dim
from ..scan import _SCAN_BLOCK, note_block_extremes
from ..timeindex import regular_clock, sampled_dataset, sampled_time
from . import _h5raw
from ._common import (
    build_dataset,
    plain_variable,
    clean_attr,
    dims_of,
    refuse_external_links,
    regular_start,
    select,
    si_channel,
)

__all__ = ["FORMAT", "check_magic", "read", "write", "open", "read_truth", "write_truth"]

FORMAT = "HDF5 (crankbench layout)"
MAGIC = b"\x89HDF\r\n\x1a\n"
#: layout written (2: metadata in one JSON attribute); versions 1 and 2 are read
FORMAT_VERSION = 2
#: root attribute holding the version-2 metadata
META_ATTR = "crankbench_meta"
_OWN_ROOT = ("crankbench_format", "crankbench_format_version", "channel_order", META_ATTR)
#: Datasets of at least this many bytes start at a multiple of :data:`ALIGN_BYTES` in the
#: file (HDF5's alignment property): a full read then copies whole pages from the page cache
#: into a page-aligned array, the cheapest copy the kernel makes.
ALIGN_THRESHOLD = 1 << 16
ALIGN_BYTES = 4096


def check_magic(head: bytes) -> bool:
    """HDF5 signature at offset 0 (files with a user block are not written by us)."""
    return head[:8] == MAGIC


def _h5():
    import h5py

    return h5py


def _dim_info(record: xr.Dataset, dim: str, first_channel: xr.DataArray) -> dict:
    if is_pulse_dim(dim):
        return {"kind": "index", "length": int(record.sizes[dim])}
    clock = regular_clock(record, dim)
    if clock is not None:  # implicit coordinate: its numbers, no time array
        start, fs, n = clock
        if type(record.xindexes[dim]).__name__ == "RangeIndex":  # xarray's: step from a
            fs = float(first_channel.attrs["sample_rate"])       # float division, use ours
        return {"kind": "regular", "start": start, "sample_rate": fs, "length": n}
    t = np.asarray(record[dim].values, dtype=np.float64)
    fs = first_channel.attrs.get("sample_rate")
    if fs is not None:
        start = regular_start(t, float(fs))
        if start is not None:
            return {"kind": "regular", "start": start, "sample_rate": float(fs),
                    "length": int(t.size)}
    return {"kind": "explicit", "length": int(t.size), "values": t}


def _attr_value(value):
    if isinstance(value, (dict, list, tuple)) and not isinstance(value, np.ndarray):
        return "json:" + json.dumps(value)
    if value is None:
        return "json:null"
    return value


def _from_attr(value):
    if isinstance(value, str) and value.startswith("json:"):
        return json.loads(value[5:])
    return value


def _to_json(value):
    """An attribute value as JSON-ready data (numeric arrays tagged with their dtype)."""
    value = clean_attr(value)
    if isinstance(value, np.ndarray):
        return {"__ndarray__": value.tolist(), "dtype": value.dtype.str}
    return value


def _json_default(value):  # numpy scalars and arrays nested in lists or dicts
    value = clean_attr(value)
    return value.tolist() if isinstance(value, np.ndarray) else value


def _from_json(value):
    if isinstance(value, dict) and value.keys() == {"__ndarray__", "dtype"}:
        return np.asarray(value["__ndarray__"], dtype=np.dtype(value["dtype"]))
    return value


def write(record: xr.Dataset, path, *, truth: xr.Dataset | None = None,
          _version: int = FORMAT_VERSION) -> dict:
    """Write ``record`` (numpy- or dask-backed) to ``path`` in the layout above.

    Dask-backed channels are written block by block (bounded memory) into contiguous
    datasets. ``_version=1`` writes the older layout (one attribute per value; tests).
    """
    h5py = _h5()
    if _version not in (1, 2):
        raise ValueError(f"_version={_version!r}; expected 1 or 2")
    meta = {"attrs": {}, "channel_order": [str(n) for n in record.data_vars], "dims": {},
            "channels": {}}
    with h5py.File(path, "w", alignment_threshold=ALIGN_THRESHOLD,
                   alignment_interval=ALIGN_BYTES) as f:
        f.attrs["crankbench_format"] = "record"
        f.attrs["crankbench_format_version"] = _version
        for k, v in record.attrs.items():
            if _version == 1:
                f.attrs[str(k)] = _attr_value(v)
            else:
                meta["attrs"][str(k)] = _to_json(v)
        if _version == 1:
            f.attrs["channel_order"] = json.dumps(meta["channel_order"])
        gdims = f.create_group("dims")
        gch = f.create_group("channels")
        for dim, names in dims_of(record).items():
            info = _dim_info(record, dim, record[names[0]])
            g = gdims.create_group(dim)
            values = info.pop("values", None)
            if _version == 1:
                for k, v in info.items():
                    g.attrs[k] = v
            else:
                meta["dims"][dim] = info
            if values is not None:
                g.create_dataset("values", data=values)
        for name, var in record.data_vars.items():
            name = str(name)
            if "/" in name:
                raise RecordError(f"channel {name!r}: names may not contain '/' in HDF5")
            dtype = var.dtype if var.dtype.kind == "f" else np.float64
            n = int(var.size)
            # contiguous: one byte range, read by one system call (no chunk index to walk);
            # filled block by block below all the same
            ds = gch.create_dataset(name, shape=(n,), dtype=dtype, chunks=None)
            if var.chunks is not None:
                start = 0
                for block in var.data.blocks:
                    arr = np.asarray(block.compute(), dtype=dtype)
                    ds[start:start + arr.size] = arr
                    start += arr.size
            elif n:
                ds[...] = np.asarray(var.values, dtype=dtype)
            if _version == 1:
                for k, v in var.attrs.items():
                    ds.attrs[str(k)] = _attr_value(v)
                ds.attrs["dim"] = str(var.dims[0])
            else:
                meta["channels"][name] = {**{str(k): _to_json(v) for k, v in var.attrs.items()},
                                          "dim": str(var.dims[0])}
        if _version == 2:
            f.attrs[META_ATTR] = json.dumps(meta, default=_json_default, allow_nan=True,
                                            separators=(",", ":"))
    if truth is not None:
        write_truth(truth, path)
    return {}


def write_truth(truth: xr.Dataset, path) -> None:
    """Append ``truth`` as netCDF4 group ``/truth`` to an existing HDF5 file."""
    if not isinstance(truth, xr.Dataset):
        raise RecordError(f"truth must be an xarray.Dataset, got {type(truth).__name__}")
    truth.to_netcdf(path, mode="a", group="truth", engine="h5netcdf")


def read_truth(path) -> xr.Dataset:
    """Read the ``/truth`` group of an HDF5 or netCDF file into memory."""
    h5py = _h5()
    refuse_external_links(path)
    with h5py.File(path, "r") as f:
        if "truth" not in f:
            raise RecordError(f"{path}: no 'truth' group; ground truth is stored only by "
                              "measure.write(record, path, truth=ds) (synthetic records)")
    with xr.open_dataset(path, group="truth", engine="h5netcdf") as ds:
        return ds.load()


def _attrs(obj) -> dict:
    """``clean_attrs(obj.attrs)`` of an h5py object, read through h5py's low-level API (about
    2.5x faster per attribute than ``obj.attrs``, which a small record's read spends more time
    on than on its samples). Scalar numbers and scalar variable-length strings -- what
    :func:`write` stores -- are read here; anything else (arrays, fixed-length or empty
    attributes) goes through ``obj.attrs``."""
    h5py = _h5()
    # a high-level object or a low-level ObjectID (whose own ``.id`` is the integer handle)
    oid = obj.id if isinstance(obj, (h5py.Group, h5py.Dataset)) else obj
    out = {}
    for i in range(h5py.h5a.get_num_attrs(oid)):
        a = h5py.h5a.open(oid, index=i)
        name = a.name.decode("utf-8", "replace")
        dtype = a.dtype
        value = None
        if a.get_space().get_simple_extent_type() == h5py.h5s.SCALAR:
            if dtype.kind in "biuf":
                buf = np.empty((), dtype)
                a.read(buf)
                value = clean_attr(buf[()])
            elif dtype.kind == "O":
                info = h5py.check_string_dtype(dtype)
                if info is not None and info.length is None:
                    buf = np.empty((), dtype)
                    a.read(buf, mtype=h5py.h5t.py_create(dtype))
                    raw = buf[()]
                    value = raw.decode(info.encoding, "surrogateescape") if isinstance(
                        raw, bytes) else raw
        if value is None:
            value = clean_attr(h5py.AttributeManager(_Bound(oid))[name])
        out[name] = value
    return out


class _Bound:
    """A low-level h5py ObjectID where the high-level API wants an object with ``.id``."""

    def __init__(self, oid):
        self.id = oid


def _members(gid) -> list[str]:
    """Names of the links in a low-level group, in HDF5's (name) order."""
    return list(_member_links(gid))


def _member_links(gid) -> dict[str, bool]:
    """Name -> "is a hard link" of the links in a low-level group, in HDF5's (name) order."""
    hard = _h5().h5l.TYPE_HARD
    links = {}

    def note(name, info):
        links[name.decode("utf-8", "surrogateescape")] = info.type == hard

    gid.links.iterate(note, info=True)
    return links


def _has(gid, name: str) -> bool:
    try:
        return _h5().h5g.GroupID.__contains__(gid, name.encode("utf-8", "surrogateescape"))
    except (KeyError, ValueError, TypeError, RuntimeError):
        return False


def _open_member(parent, name: str):
    """Low-level object ``name`` of ``parent`` (a FileID or GroupID), opened only when it is
    this file's own: a link other than a hard link (external, soft) or a virtual dataset makes
    the whole file checked by :func:`refuse_external_links`, which refuses external links and
    virtual datasets anywhere in it (naming them) and lets soft links within it pass. The
    objects a read opens are thus checked one by one (a few microseconds each) instead of by a
    walk over the whole file at every read."""
    return _open_checked(parent, name)[0]


def _open_checked(parent, name: str):
    """:func:`_open_member`, and the dataset creation property list of a dataset (None for
    other objects)."""
    h5py = _h5()
    bname = name.encode("utf-8", "surrogateescape")
    if parent.links.get_info(bname).type != h5py.h5l.TYPE_HARD:
        _refuse_outside(parent)
    obj = h5py.h5o.open(parent, bname)
    dcpl = None
    if isinstance(obj, h5py.h5d.DatasetID):
        dcpl = obj.get_create_plist()
        if dcpl.get_layout() == h5py.h5d.VIRTUAL:
            _refuse_outside(parent)
    return obj, dcpl


def _refuse_outside(oid) -> None:
    """:func:`refuse_external_links` on the open file holding low-level object ``oid``."""
    h5py = _h5()
    fid = h5py.h5i.get_file_id(oid)
    name = h5py.h5f.get_name(fid).decode("utf-8", "surrogateescape")
    refuse_external_links(name, file=name, h5file=fid)


def _group(parent, name: str):
    """Low-level group ``name`` of ``parent`` (a FileID or GroupID), None if not a group."""
    h5py = _h5()
    try:
        obj = _open_member(parent, name)
    except (KeyError, RuntimeError):  # h5py's "name doesn't exist" -- or damage
        if _has(parent, name):
            raise
        return None
    return obj if isinstance(obj, h5py.h5g.GroupID) else None


def _scalar_attr(oid, name: str):
    """Value of the scalar attribute ``name`` of a low-level object, None if it has none (by
    name: the attributes of our layout, without listing the others)."""
    h5py = _h5()
    try:
        a = h5py.h5a.open(oid, name.encode())
    except KeyError:
        return None
    tid = a.get_type()
    scalar = a.get_space().get_simple_extent_type() == h5py.h5s.SCALAR
    if scalar and tid.get_class() == h5py.h5t.STRING and tid.is_variable_str():
        return _vlen_str(a, tid.get_cset())  # the JSON text (what write stores)
    dtype = a.dtype
    if scalar:
        if dtype.kind in "biuf":
            buf = np.empty((), dtype)
            a.read(buf)
            return clean_attr(buf[()])
        info = h5py.check_string_dtype(dtype)
        if dtype.kind == "O" and info is not None and info.length is None:
            buf = np.empty((), dtype)
            a.read(buf, mtype=h5py.h5t.py_create(dtype))
            raw = buf[()]
            return raw.decode(info.encoding, "surrogateescape") if isinstance(raw, bytes) else raw
    return clean_attr(h5py.AttributeManager(_Bound(oid))[name])


#: HDF5 character set -> (h5py's memory type of a variable-length string in it, encoding)
_VLEN = {}


def _vlen_str(a, cset: int) -> str:
    """Value of the scalar variable-length string attribute ``a`` (an ``h5py.h5a.AttrID``) of
    character set ``cset``, decoded as ``_attrs`` decodes it."""
    h5py = _h5()
    if cset not in _VLEN:
        encoding = "utf-8" if cset == h5py.h5t.CSET_UTF8 else "ascii"
        dtype = h5py.string_dtype(encoding)
        _VLEN[cset] = (dtype, h5py.h5t.py_create(dtype), encoding)
    dtype, mtype, encoding = _VLEN[cset]
    buf = np.empty((), dtype)
    a.read(buf, mtype=mtype)
    raw = buf[()]
    return raw.decode(encoding, "surrogateescape") if isinstance(raw, bytes) else raw


def _root(fid, file: str) -> tuple[dict, dict | None]:
    """The root's attributes of ours -- and the record attrs set on it -- and the version-2
    metadata (None for version 1, whose record attrs are all in the first dict)."""
    h5py = _h5()
    text = _scalar_attr(fid, META_ATTR)
    if text is None:  # version 1 (or not ours): every attribute of the root
        return _attrs(fid), None
    try:
        meta = json.loads(text)
        if not (isinstance(meta, dict) and all(isinstance(meta.get(k), dict)
                                               for k in ("attrs", "dims", "channels"))):
            raise ValueError("attrs, dims or channels missing")
    except (TypeError, ValueError) as exc:
        raise RecordError(f"{file}: root attribute {META_ATTR!r} is not the JSON object of "
                          f"crankbench's layout ({exc}); damaged or edited file?") from None
    if h5py.h5a.get_num_attrs(fid) == 3:  # as written: format, version, meta -- the JSON of
        # our layout says the format; the version is read (one typed read, no type query)
        root = {"crankbench_format": "record",
                "crankbench_format_version": _int_attr(fid, "crankbench_format_version")}
    else:  # attributes set on the root after writing override the JSON's
        root = _attrs(fid)
    return root, meta


def _int_attr(oid, name: str):
    """Attribute ``name`` read as an integer by HDF5's conversion (anything else -- a string,
    an array, a float -- through :func:`_scalar_attr`)."""
    h5py = _h5()
    try:
        a = h5py.h5a.open(oid, name.encode())
        buf = np.empty((), np.int64)
        if a.get_type().get_class() == h5py.h5t.INTEGER:
            a.read(buf, mtype=_h5raw.native_type(buf.dtype))
            return int(buf)
    except (KeyError, TypeError, ValueError, OSError):
        pass
    return _scalar_attr(oid, name)


def _layout(fid, file: str) -> tuple[dict, list[str], dict, object, dict]:
    """Record attrs, channel order, dims, the ``/channels`` group (low-level GroupID) and the
    channels' attrs as far as known without opening them (version 2's JSON) of an open file
    (``h5py.h5f.FileID``: h5py's low-level API, several times cheaper per call than its
    high-level objects)."""
    h5py = _h5()
    root, meta = _root(fid, file)
    fmt = root.get("crankbench_format")
    if isinstance(fmt, bytes):
        fmt = fmt.decode()
    gch = _group(fid, "channels") if fmt == "record" else None
    gdims = _group(fid, "dims") if gch is not None else None
    if gdims is None:
        raise RecordError(
            f"{file}: HDF5 file is not in crankbench's record layout (expected root attr "
            "crankbench_format='record' and groups /channels, /dims); netCDF files should be "
            "named .nc")
    try:
        version = int(root.get("crankbench_format_version", 0))
    except (TypeError, ValueError):
        version = -1
    if version > FORMAT_VERSION or version < 0:
        raise RecordError(f"{file}: layout version {root.get('crankbench_format_version')!r} "
                          f"is not one this crankbench reads (1..{FORMAT_VERSION}); upgrade "
                          "crankbench")
    if meta is not None and version < 2:
        meta = None  # a version-1 file holding an attribute of that name: not ours
    meta = meta or {}
    record_attrs = {k: _from_json(v) for k, v in meta.get("attrs", {}).items()}
    record_attrs.update({k: _from_attr(v) for k, v in root.items() if k not in _OWN_ROOT})
    try:
        order = json.loads(root["channel_order"]) if "channel_order" in root else list(
            meta["channel_order"])
    except (KeyError, TypeError, ValueError):
        order = sorted(_members(gch))
    links = _member_links(gch)  # a hard link always has its object; others are resolved
    missing = [n for n in order if not (links.get(str(n)) or (str(n) in links
                                                             and _has(gch, str(n))))]
    if missing:
        raise RecordError(f"{file}: header lists channel(s) {missing} that have no data "
                          "(header/body mismatch; file truncated?)")
    dims = {dim: dict(info) for dim, info in meta.get("dims", {}).items()}
    for dim, hard in _member_links(gdims).items():
        if not hard:
            _refuse_outside(gdims)
        info = dims.setdefault(dim, {})
        # opened only when it has attributes (version 1, or edited) or explicit times
        obj = h5py.h5o.get_info(gdims, dim.encode("utf-8", "surrogateescape"))
        g = _open_member(gdims, dim) if obj.num_attrs else None
        if g is not None:
            info.update(_attrs(g))
        if obj.type == h5py.h5o.TYPE_GROUP and info.get("kind") == "explicit":
            g = g or _open_member(gdims, dim)
            if _has(g, "values"):
                info["values_ds"] = h5py.Dataset(_open_member(g, "values"))
    channels = {name: {k: _from_json(v) for k, v in attrs.items()}
                for name, attrs in meta.get("channels", {}).items()}
    return record_attrs, order, dims, gch, channels


def _dataset(gch, name: str):
    """Channel ``name`` of the low-level ``/channels`` group: its ``h5py.h5d.DatasetID`` and
    dataset creation property list."""
    h5py = _h5()
    obj, dcpl = _open_checked(gch, name)
    if not isinstance(obj, h5py.h5d.DatasetID):
        raise RecordError(f"channel {name!r} is an HDF5 {type(obj).__name__[:-2].lower()}, "
                          "not a dataset; expected one dataset per channel under /channels")
    return obj, dcpl


def _channel_attrs(did, shape: tuple, name: str, dims: dict, file: str,
                   known: dict | None = None) -> tuple[str, dict]:
    """Dim and attrs of the channel dataset ``did`` (``h5py.h5d.DatasetID``) of ``shape``:
    ``known`` (version 2's JSON) updated with the dataset's own attributes, if it has any."""
    attrs = dict(known or {})
    if _h5().h5a.get_num_attrs(did):
        attrs.update({k: _from_attr(v) for k, v in _attrs(did).items()})
    dim = attrs.pop("dim", None)
    if dim not in dims:
        raise RecordError(f"{file}: channel {name!r} refers to dim {dim!r} which is not in "
                          "/dims (header/body mismatch)")
    length = int(dims[dim].get("length", -1))
    if shape != (length,):
        raise RecordError(f"{file}: channel {name!r} has {shape[0] if shape else 0} "
                          f"samples but its dim {dim!r} declares {length} (header/body mismatch;"
                          " file truncated?)")
    return dim, attrs


def _regular(dim: str, info: dict, file: str) -> tuple[int, float, float]:
    """``(length, sample_rate Hz, start s)`` of a regular clock, checked."""
    fs = float(info["sample_rate"])
    if not np.isfinite(fs) or fs <= 0:
        raise RecordError(f"{file}: dim {dim!r} declares sample_rate={fs!r} Hz; expected a "
                          "finite value > 0")
    return int(info.get("length", 0)), fs, float(info.get("start", 0.0))


def _coordinate(dim: str, info: dict, file: str):
    """The dim's time coordinate: ``xarray.Coordinates`` (implicit, regular clocks), a float64
    array (explicit times) or None (pulse dims)."""
    kind = info.get("kind")
    n = int(info.get("length", 0))
    if kind == "index":
        return None
    if kind == "regular":
        n, fs, start = _regular(dim, info, file)
        return sampled_time(n, fs, start=start, dim=dim)
    if kind == "explicit":
        values = np.asarray(info["values_ds"][...], dtype=np.float64)
        if values.size != n:
            raise RecordError(f"{file}: dim {dim!r} has {values.size} time values but declares "
                              f"length {n} (header/body mismatch)")
        return values
    raise RecordError(f"{file}: dim {dim!r} has unknown kind {kind!r}; expected regular, "
                      "explicit or index")


def _userblock(fid) -> int:
    """User-block size of an open file (``h5py.h5f.FileID``), bytes."""
    return fid.get_create_plist().get_userblock()


_FAPL = []


def _open_read(path):
    """``path`` opened read-only as a low-level ``h5py.h5f.FileID`` whose close also closes
    every object opened in it (what ``h5py.File.close`` does by enumerating them).

    HDF5 opens a file that this process holds open already (an ``h5py.File`` in a notebook)
    only with the close degree it was opened with -- h5py's is "weak" -- and refused the strong
    one as "file close degree doesn't match", which read as a corrupt file. Then the file is
    opened weak: its objects close as they are released, the other handle keeps it open."""
    h5py = _h5()
    if not _FAPL:  # one property list each (they describe how to open, not any file)
        for degree in (h5py.h5f.CLOSE_STRONG, h5py.h5f.CLOSE_WEAK):
            fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
            fapl.set_fclose_degree(degree)
            _FAPL.append(fapl)
    name = os.fsencode(os.fspath(path))
    try:
        return h5py.h5f.open(name, h5py.h5f.ACC_RDONLY, fapl=_FAPL[0])
    except OSError as exc:
        if "close degree" not in str(exc):
            raise
        return h5py.h5f.open(name, h5py.h5f.ACC_RDONLY, fapl=_FAPL[1])


def read(path, *, channels=None) -> xr.Dataset:
    """Read a crankbench HDF5 record fully into memory.

    HDF5 gives the layout, the metadata and where each channel's samples lie in the file; it
    is closed before plain samples are read, straight from those byte ranges through its own
    file descriptor and scanned for the record checks as they arrive
    (:mod:`measure.readers._h5raw`). Samples HDF5 must convert are read by HDF5 first.

    Parameters
    ----------
    path : path-like
        The ``.h5`` file.
    channels : list of str, optional
        Only these channels.

    Returns
    -------
    xarray.Dataset
        Channels in SI units, time coordinates in s.
    """
    file = str(path)
    fid = _open_read(path)
    fd = None
    try:
        attrs, planned, clock, (explicit, implicit) = _plan(fid, file, channels)
        if any(runs for *_, runs in planned):
            fd = _h5raw.vfd_dup(fid)
            if fd is None:  # no descriptor to share: one of our own
                fd = os.open(os.fsencode(os.fspath(path)), os.O_RDONLY | getattr(os, "O_BINARY", 0))
    finally:
        _close(fid)
    try:
        out = _fill(path, planned, fd, file)
    finally:
        if fd is not None:
            os.close(fd)
    if clock is not None:  # built in one step (no merge/align pass)
        clock, (n, fs, start) = clock
        data_vars = {name: plain_variable(dim, values, vattrs)
                     for name, dim, values, vattrs in out}
        return sampled_dataset(data_vars, n, fs, start=start, dim=clock, attrs=attrs)
    ds = build_dataset(out, explicit, attrs)
    for coords in implicit:
        ds = ds.assign_coords(coords)
    return ds


def _plan(fid, file: str, channels):
    """What :func:`read` takes from the open file ``fid``: record attrs; per channel ``(name,
    dim, attrs, array, byte runs)`` (the array already filled by HDF5 where the runs are None);
    ``(dim, (n, sample_rate, start))`` of the one regular clock of the usual record, else None;
    and the explicit and implicit time coordinates otherwise. No HDF5 object outlives it."""
    attrs, order, dims, group, known = _layout(fid, file)
    names = select(order, channels, file=file)
    planned, used = [], {}
    userblock = _userblock(fid)
    for name in names:  # every object opened is checked to be the file's own (_open_member)
        did, dcpl = _dataset(group, name)
        shape = did.shape
        dim, cattrs = _channel_attrs(did, shape, name, dims, file, known.get(name))
        raw, runs = _h5raw.prepare(did, shape, userblock, dcpl)
        if runs is None and raw.size:
            did.read(_h5().h5s.ALL, _h5().h5s.ALL, raw)  # HDF5 converts: it reads
        planned.append((name, dim, cattrs, raw, runs))
        used[dim] = True
    explicit, implicit = {}, []
    if len(used) == 1 and dims[next(iter(used))].get("kind") == "regular":
        clock = next(iter(used))  # the usual record: one regular clock
        return attrs, planned, (clock, _regular(clock, dims[clock], file)), (explicit, implicit)
    for dim in used:
        c = _coordinate(dim, dims[dim], file)
        if isinstance(c, np.ndarray):
            explicit[dim] = c
        elif c is not None:
            implicit.append(c)
    return attrs, planned, None, (explicit, implicit)


def _close(fid) -> None:
    """Close the file ``fid`` with every object opened in it (strong close degree). When
    nothing else of the file is open -- after a read has released all it opened -- h5py's
    sweep over every HDF5 object of the process (``nonlocal_close``, which marks the handles
    such a close invalidated) has nothing to mark and is skipped."""
    h5py = _h5()
    quick = getattr(fid, "_close", None)  # FileID.close without the sweep (h5py >= 3)
    if quick is not None and h5py.h5f.get_obj_count(fid, h5py.h5f.OBJ_ALL) == 1:
        quick()
    else:
        fid.close()


def _fill(path, planned, fd, file: str) -> list[tuple[str, str, np.ndarray, dict]]:
    """Read the ``planned`` channels' byte ranges through descriptor ``fd`` and convert them to
    SI: ``[(name, dim, values, attrs)]``. A channel whose file ended early is read again by
    HDF5, which reports the damage."""
    pread = None if fd is None else _h5raw.positioned_reader(fd)
    out = []
    for name, dim, cattrs, raw, runs in planned:
        extremes = None
        if runs is not None:
            extremes = _h5raw.read_runs(pread, runs, raw, _SCAN_BLOCK)
            if extremes is False:
                extremes = None
                _reread(path, name, raw)
        unit = cattrs.get("units")
        values, cattrs = si_channel(name, raw, cattrs, file=file)
        if extremes is not None and values is raw and cattrs["units"] == unit:
            note_block_extremes(values, *extremes)  # samples unchanged since the scan
        out.append((name, dim, values, cattrs))
    return out


def _reread(path, name: str, out: np.ndarray) -> None:
    """Channel ``name`` read into ``out`` by HDF5 itself (raises what HDF5 finds wrong)."""
    h5py = _h5()
    fid = _open_read(path)
    try:
        gch = _group(fid, "channels")
        did, _ = _dataset(gch, name)
        did.read(h5py.h5s.ALL, h5py.h5s.ALL, out)
    finally:
        fid.close()


class _LazyH5:
    """Array-like slice of one HDF5 dataset; reopens the file read-only on each access.

    Picklable (path + name), so dask can ship it to threads, processes or distributed workers.
    """

    def __init__(self, path: str, name: str, shape: tuple, dtype):
        self.path, self.name = path, name
        self.shape, self.dtype, self.ndim = shape, np.dtype(dtype), len(shape)

    def __getitem__(self, key):
        h5py = _h5()
        try:
            with h5py.File(self.path, "r") as f:
                return f["channels"][self.name][key]
        except (OSError, KeyError) as exc:  # damage found only now, at a deferred read
            raise RecordError(f"{self.path}: channel {self.name!r} cannot be read at {key!r} "
                              f"(damaged or truncated HDF5 file: {exc}); expected an intact "
                              "record file") from None


def open(path, *, chunk_seconds: float = 10.0, channels=None) -> xr.Dataset:  # noqa: A001
    """Open a crankbench HDF5 record lazily: dask chunks of ``chunk_seconds`` per clock.

    Regular time coordinates are implicit (:class:`measure.timeindex.SampledTimeIndex`, no
    time array in memory), so peak memory is bounded by the chunks being processed, whatever
    the file size.
    """
    import dask.array as da

    h5py = _h5()
    file = str(path)
    refuse_external_links(path, file=file)
    with h5py.File(path, "r") as f:
        record_attrs, order, dims, _, known = _layout(f.id, file)
        names = select(order, channels, file=file)
        data_vars, used = {}, {}
        for name in names:
            ds = f["channels"][name]
            dim, attrs = _channel_attrs(ds.id, ds.shape, name, dims, file, known.get(name))
            fs = attrs.get("sample_rate")
            n = ds.shape[0]
            if fs is not None and n:
                step = max(1, int(round(float(chunk_seconds) * float(fs))))
                c = ds.chunks[0] if ds.chunks else 0
                if c and step >= c:  # align dask chunks on HDF5 chunks
                    step = (step // c) * c
            else:
                step = max(1, n)
            arr = da.from_array(_LazyH5(file, name, ds.shape, ds.dtype), chunks=(step,),
                                name=f"crankbench-h5-{file}-{name}", lock=False,
                                asarray=True, meta=np.empty(0, ds.dtype))
            arr, attrs = si_channel(name, arr, attrs, file=file)
            data_vars[name] = xr.Variable((dim,), arr, attrs)
            used[dim] = True
        coords = []
        plain = {}
        for dim in used:
            c = _coordinate(dim, dims[dim], file)
            if c is None:
                continue
            if isinstance(c, np.ndarray):
                plain[dim] = (dim, c, {"units": "s", "long_name": "time from record start"})
            else:
                coords.append(c)
    ds = xr.Dataset(data_vars, coords=plain, attrs=record_attrs)
    for c in coords:
        ds = ds.assign_coords(c)
    return ds
