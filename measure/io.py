"""Reading and writing Records in every test-bench format, and streaming long ones.

=============  ==========================  ====================================================
extension      format                      streams with :func:`open`
=============  ==========================  ====================================================
.h5 .hdf5      HDF5, crankbench layout     yes: dask chunks, lazy time index (bounded memory)
.nc            netCDF4 (h5netcdf)          data yes; time coordinates held in memory
.tdms          NI TDMS (npTDMS)            yes: channel slices read on demand
.wav           WAV + ``.wav.json`` sidecar yes: frames read on demand (main clock only)
.csv .txt      delimited text, any dialect no: parsed whole (8 bytes a value), then chunked
.tsv .tab
.asc .dat
.xlsx .xlsm    Excel workbook (openpyxl)   no: loaded whole, then chunked
.mf4 .mdf      ASAM MDF4 (asammdf)         no: loaded whole, then chunked
.uff .unv      UFF dataset 58 (pyuff)      no: loaded whole, then chunked
=============  ==========================  ====================================================

Text and spreadsheet exports whose headers do not say what a column is are read through a
channel map (``read(path, map=...)``, :mod:`measure.channelmap`), which also decodes raw wheel
and TDC signals into pulse trains. HDF5/netCDF records whose channels, clocks or groups are
external links or virtual datasets are refused (a record holds its own data).

Input files are opened read-only and never modified. :func:`write` is atomic (temporary file
in the target folder, then rename) and refuses to replace an existing file unless
``overwrite=True``. Units are converted to SI once, here; mixed sample rates keep their own
time dims and are never resampled.
"""

from __future__ import annotations

import logging
import os
import stat
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from crankbench.predict.errors import ConfigError, CrankbenchError, RecordError

from ._atomic import atomic_path, check_overwrite
from .provenance import STAT_ATTR, sha256_of, source_sha256, stamp_source
from .readers import EXTENSIONS, format_of_magic, module_for
from .readers._common import REGULAR_KEY
from .record import RecordWarning, _is_lazy, validate
from .scan import CLIP_QUANTITIES, clipped_spans, nonfinite_spans, shared_scans

__all__ = ["read", "write", "open", "read_truth", "iter_blocks", "sha256_of", "source_sha256",
           "EXTENSIONS"]

log = logging.getLogger("crankbench")

_FORMAT_EXT = {"hdf5": ".h5", "mdf": ".mf4", "tdms": ".tdms", "wav": ".wav", "uff": ".uff",
               "csv": ".csv", "xlsx": ".xlsx"}


def _check_input(path) -> tuple[Path, object, os.stat_result]:
    """Resolve the format module and check existence, size and magic bytes; the file's stat
    before any of its data is read (its identity for :mod:`measure.provenance`)."""
    path = Path(path)
    module = module_for(path)
    try:  # the usual case, a regular file: one stat
        st = os.stat(path)
    except (OSError, ValueError):
        st = None
    regular = st is not None and stat.S_ISREG(st.st_mode)
    if not regular:
        st = _check_exists(path, module)
    if st.st_size == 0:
        raise RecordError(f"{path}: file is empty (0 bytes); expected {module.FORMAT} content")
    if regular:  # one read gives the first 64 bytes (or all of a shorter file)
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0))
        try:
            head = os.read(fd, 64)
        finally:
            os.close(fd)
    else:
        with path.open("rb") as f:
            head = f.read(64)
    if not module.check_magic(head):
        actual = format_of_magic(head)
        hint = (f"; its first bytes look like {actual.upper()} — rename it to "
                f"{path.with_suffix(_FORMAT_EXT[actual]).name!r}?") if actual else ""
        raise RecordError(f"{path}: wrong magic bytes {head[:8]!r} for a {module.FORMAT} file "
                          f"(extension {path.suffix!r}){hint}")
    return path, module, st


def _check_exists(path: Path, module) -> os.stat_result:
    """The stat of ``path``, or the error naming what it is instead of a file."""
    if not path.exists():
        near = ""
        if path.parent.is_dir():
            import difflib

            close = difflib.get_close_matches(path.name, os.listdir(path.parent), n=1)
            near = f" (did you mean {str(path.parent / close[0])!r}?)" if close else ""
        raise FileNotFoundError(f"record file {str(path)!r} does not exist{near}")
    if path.is_dir():
        raise RecordError(f"{path} is a directory; expected a {module.FORMAT} file")
    return path.stat()


def _wrap(path: Path, module, exc: Exception) -> RecordError:
    size = path.stat().st_size
    return RecordError(f"{path}: cannot read as {module.FORMAT} ({type(exc).__name__}: {exc}); "
                       f"the file ({size} bytes) is truncated or corrupt")


def _named(path: Path, exc: CrankbenchError) -> CrankbenchError:
    msg = str(exc)
    if str(path) in msg or path.name in msg:
        return exc
    return type(exc)(f"{path}: {msg}")


def _mask_nonfinite(ds: xr.Dataset, path: Path) -> xr.Dataset:
    for name in list(ds.data_vars):
        var = ds.variables[name]  # a Variable: ds[name] would cost O(channels) each
        if var.dtype.kind != "f" or _is_lazy(var):
            continue
        values = var.values
        spans = nonfinite_spans(values)
        if not spans:
            continue
        fixed = values.copy()
        fixed[~np.isfinite(fixed)] = np.nan
        if var.attrs.get("quantity") == "pulse_times":
            raise RecordError(f"{path}: pulse-time channel {name!r} has NaN/inf edge times; "
                              "expected finite times in s (cannot be masked)")
        t = ds.variables[var.dims[0]].values if var.dims[0] in ds.coords else None
        flat = []
        text = []
        for a, b in spans:
            if t is not None:
                flat += [float(t[a]), float(t[b - 1])]
                text.append(f"{t[a]:.6g}..{t[b - 1]:.6g} s (samples {a}..{b - 1})")
            else:
                text.append(f"samples {a}..{b - 1}")
        shown = "; ".join(text[:5]) + (f" and {len(text) - 5} more" if len(text) > 5 else "")
        warnings.warn(f"{path.name}: channel {name!r}: {sum(b - a for a, b in spans)} NaN/inf "
                      f"sample(s) masked as NaN in {len(spans)} span(s): {shown}",
                      RecordWarning, stacklevel=4)
        ds[name] = var.copy(data=fixed)
        if flat:
            ds[name].attrs["masked_spans_s"] = np.asarray(flat)
    return ds


def _flag_clipping(ds: xr.Dataset, path: Path) -> None:
    for name in ds.data_vars:
        var = ds.variables[name]
        if (var.dtype.kind != "f" or _is_lazy(var)
                or var.attrs.get("quantity") not in CLIP_QUANTITIES):
            continue
        spans = clipped_spans(var.values)
        if not spans:
            continue
        values = var.values
        t = ds.variables[var.dims[0]].values
        flat = []
        for a, b in spans:
            flat += [float(t[a]), float(t[b - 1])]
        text = "; ".join(f"{t[a]:.6g}..{t[b - 1]:.6g} s" for a, b in spans[:5])
        more = f" and {len(spans) - 5} more" if len(spans) > 5 else ""
        hi, lo = float(np.nanmax(values)), float(np.nanmin(values))
        warnings.warn(
            f"{path.name}: channel {name!r} looks clipped (amplifier/ADC saturation): "
            f"{sum(b - a for a, b in spans)} sample(s) in {len(spans)} flat run(s) at its "
            f"extremes {hi:.6g} / {lo:.6g} {var.attrs.get('units', '')}: {text}{more}; spans "
            "listed in attr clipped_spans_s — amplitudes there are too low",
            RecordWarning, stacklevel=4)
        var.attrs["clipped_spans_s"] = np.asarray(flat)


def read(path, *, channels=None, allow_nonfinite: bool = False, map=None) -> xr.Dataset:  # noqa: A002
    """Read a record file into a validated Record, by extension.

    Parameters
    ----------
    path : path-like
        ``.h5 .hdf5 .nc .mf4 .mdf .tdms .uff .unv .wav`` (WAV with its ``.wav.json``), delimited
        text ``.csv .txt .tsv .tab .asc .dat`` of any common dialect, ``.xlsx`` workbooks.
    channels : list of str, optional
        Load only these channels (an unknown name is an error suggesting the close one).
    map : path-like, dict or ChannelMap, optional
        A channel map (:mod:`measure.channelmap`): which column is which channel, its units,
        calibration and sensor metadata, raw pulse signals to decode (``role`` "wheel" or
        "tdc"), the file's dialect and time axis. The Record then keeps its provenance in attrs
        ``raw_source``, ``raw_sha256``, ``channel_map`` (the map's text) and
        ``channel_map_sha256``.
    allow_nonfinite : bool
        Accept NaN/inf dropouts: they are masked as NaN, listed in the channel attr
        ``masked_spans_s`` (start, end pairs in s) and reported by a :class:`RecordWarning`
        naming channel and span. By default they are an error.

    Notes
    -----
    Clipping (runs of >= 3 samples flat at a vibration-type channel's own maximum or minimum,
    see :func:`measure.scan.clipped_spans`) is reported by a :class:`RecordWarning` naming
    channel and spans, which are listed in the channel attr ``clipped_spans_s``; the samples
    are kept as recorded.

    Returns
    -------
    xarray.Dataset
        The Record, units in SI, with attrs ``source`` (file name) and ``source_stat`` (the
        file's identity at read time). The file is not hashed here (that would cost more than
        the read): :func:`source_sha256` gives its SHA-256 when provenance is written, after
        checking the file is still the one read.

    Raises
    ------
    FileNotFoundError
        The file does not exist (the message names it).
    RecordError
        Unknown extension (suggesting the likely one), empty, truncated or corrupt file, wrong
        magic bytes, header/body mismatch, unknown unit, schema violation — naming the file,
        the channel and what was expected.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"acc": dict(data=np.arange(4.0), sample_rate=1000.0, units="g")})
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.h5"
    >>> write(rec, p)
    >>> back = read(p)
    >>> print(back["acc"].attrs["units"], back["acc"].values[1], back.attrs["source"])
    m/s^2 9.80665 r.h5
    """
    path, module, st = _check_input(path)
    cmap = None
    if map is not None:
        from .channelmap import load_map

        cmap = load_map(map)
    return _read_checked(path, module, st, cmap, channels, allow_nonfinite)


def _read_checked(path, module, st, cmap, channels, allow_nonfinite) -> xr.Dataset:
    """Body of :func:`read`: parse (through the channel map ``cmap`` if any), mask, validate,
    flag clipping, stamp the source's identity ``st`` (its SHA-256 is computed on demand by
    :func:`measure.provenance.source_sha256`; a channel map's raw export is hashed now)."""
    # the NaN/inf check and the clipping check share one scan of each channel, or none where
    # the reader scanned the samples while reading them (measure.scan.note_block_extremes)
    with shared_scans():
        ds = _parse(path, module, cmap, channels, allow_nonfinite)
        if allow_nonfinite:
            ds = _mask_nonfinite(ds, path)
        regular = frozenset(ds.encoding.pop(REGULAR_KEY, ()))
        try:
            validate(ds, allow_nonfinite=allow_nonfinite, _regular_dims=regular)
        except RecordError as exc:
            raise _named(path, exc) from None
        _flag_clipping(ds, path)
    stamp_source(ds.attrs, path, st)
    if cmap is not None:  # the raw export's digest travels into the files written from it
        ds.attrs.update(raw_source=path.name, raw_sha256=source_sha256(ds),
                        channel_map=cmap.text, channel_map_source=Path(cmap.origin).name,
                        channel_map_sha256=cmap.sha256)
    return ds


def _parse(path, module, cmap, channels, allow_nonfinite) -> xr.Dataset:
    """The format module's (or the channel map's) read, its errors named after ``path``."""
    try:
        if cmap is None:
            return module.read(path, channels=channels)
        return _read_mapped(path, module, cmap, channels, allow_nonfinite)
    except ConfigError as exc:  # the map's fault: name the map and the data file
        if cmap is None:
            raise
        raise ConfigError(f"{cmap.origin} (for {path.name}): {exc}") from None
    except CrankbenchError as exc:
        raise _named(path, exc) from None
    except (MemoryError, KeyboardInterrupt):
        raise
    except Exception as exc:  # libraries raise anything on a corrupt file
        raise _wrap(path, module, exc) from exc


def _read_mapped(path, module, cmap, channels, allow_nonfinite):
    from .channelmap import read_mapped

    ds = read_mapped(path, module, cmap, allow_nonfinite=allow_nonfinite)
    if channels is not None:
        from .readers._common import select

        ds = ds[select([str(n) for n in ds.data_vars], channels, file=path.name)]
    return ds


def write(record: xr.Dataset, path, *, truth: xr.Dataset | None = None,
          overwrite: bool = False) -> None:
    """Write a Record atomically, format by extension.

    Parameters
    ----------
    record : xarray.Dataset
        A valid Record (NaN-masked spans allowed). Dask-backed channels are written block by
        block to ``.h5``.
    path : path-like
        Target file. Its extension picks the format; ``.wav`` also writes ``<path>.json``.
    truth : xarray.Dataset, optional
        Ground truth of a synthetic record, stored as HDF5 group ``truth`` (.h5/.hdf5/.nc only).
    overwrite : bool
        Replace existing files; otherwise ``FileExistsError`` naming the option.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"v": dict(data=np.ones(3), sample_rate=10.0, units="mm/s")})
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> write(rec, p)
    >>> print(p.read_text().splitlines()[2])
    time [s],v [m/s]
    """
    path = Path(path)
    module = module_for(path)
    validate(record, allow_nonfinite=True)
    if STAT_ATTR in record.attrs:  # identity of the file it was read from: not this file's
        record = record.copy(deep=False)
        record.attrs = {k: v for k, v in record.attrs.items() if k != STAT_ATTR}
    if truth is not None and not hasattr(module, "write_truth"):
        raise RecordError(f"{path}: ground truth can only be stored in .h5/.hdf5/.nc records")
    check_overwrite(path, overwrite)
    sidecars = getattr(module, "SIDECARS", ())
    for suffix in sidecars:
        check_overwrite(Path(str(path) + suffix), overwrite)
    with atomic_path(path, overwrite=overwrite) as tmp:
        try:
            extras = module.write(record, tmp, truth=truth) or {}
        except CrankbenchError as exc:  # name the target, not the temporary file
            raise type(exc)(str(exc).replace(str(tmp), str(path))) from None
        for suffix, payload in extras.items():
            with atomic_path(Path(str(path) + suffix), overwrite=overwrite) as side:
                side.write_bytes(payload)
    log.debug("wrote %s (%s)", path, module.FORMAT)


def read_truth(path) -> xr.Dataset:
    """Read the ground truth stored by ``write(record, path, truth=ds)`` (group ``truth``).

    Raises
    ------
    RecordError
        The file is not HDF5/netCDF or has no ``truth`` group.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"v": dict(data=np.ones(3), sample_rate=10.0, units="V")})
    >>> truth = xr.Dataset({"critical_speed_rpm": ("mode", [1200.0, 2900.0])})
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "synth.h5"
    >>> write(rec, p, truth=truth)
    >>> read_truth(p)["critical_speed_rpm"].values
    array([1200., 2900.])
    """
    path, module, _ = _check_input(path)
    if not hasattr(module, "read_truth"):
        raise RecordError(f"{path}: ground truth is stored only in .h5/.hdf5/.nc records")
    try:
        return module.read_truth(path)
    except CrankbenchError as exc:
        raise _named(path, exc) from None
    except Exception as exc:
        raise _wrap(path, module, exc) from exc


def open(path, *, chunk_seconds: float = 10.0, channels=None,  # noqa: A001
         allow_nonfinite: bool = False, map=None) -> xr.Dataset:  # noqa: A002
    """Open a record lazily: a Record whose channels are dask arrays of ``chunk_seconds``.

    Parameters
    ----------
    path : path-like
        Record file. ``.h5``/``.hdf5`` stream with bounded memory (lazy time index);
        ``.nc``, ``.tdms`` and ``.wav`` stream the samples; ``.csv``, ``.mf4`` and ``.uff``
        cannot be read in parts and are loaded whole, then chunked (logged at INFO).
    chunk_seconds : float
        Target chunk length per clock, s (> 0).
    channels : list of str, optional
        Only these channels.
    map : path-like, dict or ChannelMap, optional
        A channel map (see :func:`read`): the file is read through it (whole), then chunked.
    allow_nonfinite : bool
        Keep NaN/inf samples. By default every block is checked as it is computed, and one
        holding NaN/inf raises :class:`RecordError` naming the file, the channel and the time
        of the first bad sample (a lazy record cannot be scanned up front without reading it
        all).

    Returns
    -------
    xarray.Dataset
        Lazily loaded Record (attrs ``source`` and ``source_stat`` set, as by :func:`read`).
        Use :func:`iter_blocks` or dask reductions to process it.

    Notes
    -----
    For ``.h5`` the regular time coordinates are lazy :class:`xarray.indexes.RangeIndex`
    objects (no time array in memory). xarray's RangeIndex selects by position (``isel``) or
    with ``sel(..., method="nearest")``; label slices and alignment with records read by
    :func:`read` (pandas index) are not supported — ``isel`` by ``round(t * sample_rate)``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"acc": dict(data=np.ones(5000), sample_rate=1000.0, units="m/s^2")})
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "long.h5"
    >>> write(rec, p)
    >>> lazy = open(p, chunk_seconds=2.0)
    >>> print(lazy["acc"].chunks, float(lazy["acc"].mean()))
    ((2000, 2000, 1000),) 1.0
    """
    from crankbench.predict._validate import check_positive

    chunk_seconds = check_positive(chunk_seconds, "chunk_seconds", error=RecordError)
    if map is not None:
        ds = read(path, channels=channels, allow_nonfinite=allow_nonfinite, map=map)
        return ds.chunk(_chunks_of(ds, chunk_seconds))
    path, module, st = _check_input(path)
    try:
        if hasattr(module, "open"):
            ds = module.open(path, chunk_seconds=chunk_seconds, channels=channels)
        else:
            log.debug("%s: %s cannot be read in parts; loading it whole", path.name,
                     module.FORMAT)
            ds = module.read(path, channels=channels)
            ds = ds.chunk(_chunks_of(ds, chunk_seconds))
    except CrankbenchError as exc:
        raise _named(path, exc) from None
    except (MemoryError, KeyboardInterrupt):
        raise
    except Exception as exc:
        raise _wrap(path, module, exc) from exc
    stamp_source(ds.attrs, path, st)
    try:
        ds = validate(ds, allow_nonfinite=True)
    except RecordError as exc:
        raise _named(path, exc) from None
    return ds if allow_nonfinite else _guard_finite(ds, path)


def _chunks_of(ds: xr.Dataset, chunk_seconds: float) -> dict:
    """Chunk length per dim: ``chunk_seconds`` of samples, a pulse train whole."""
    chunks = {}
    for name in ds.data_vars:
        var = ds.variables[name]
        fs = var.attrs.get("sample_rate")
        chunks[var.dims[0]] = max(1, int(round(chunk_seconds * float(fs)))) if fs else -1
    return chunks


def _guard_finite(ds: xr.Dataset, path: Path) -> xr.Dataset:
    """Wrap each lazy float channel so a block with NaN/inf raises RecordError when computed."""
    import dask.array as da

    guarded = {}
    for name in ds.data_vars:
        var = ds.variables[name]
        data = var.data
        if not isinstance(data, da.Array) or data.dtype.kind != "f" or data.ndim != 1:
            continue
        fs = var.attrs.get("sample_rate")
        t0 = float(ds.variables[var.dims[0]][0].values) if fs and var.dims[0] in ds.coords \
            and var.size else 0.0

        def check(block, block_info=None, _name=name, _fs=fs, _t0=t0):
            bad = ~np.isfinite(block)
            if bad.any():
                start = block_info[0]["array-location"][0][0] if block_info else 0
                i = start + int(np.flatnonzero(bad)[0])
                when = f" (t = {_t0 + i / float(_fs):.6g} s)" if _fs else ""
                raise RecordError(
                    f"{path.name}: channel {_name!r} has {int(bad.sum())} NaN/inf value(s) in "
                    f"the block from sample {start}, first at sample {i}{when}; expected finite "
                    "samples (open(..., allow_nonfinite=True) keeps them)")
            return block

        # a name from the input's (unique) name: dask would otherwise pickle ``check`` to hash it
        guarded[name] = var.copy(data=data.map_blocks(check, dtype=data.dtype,
                                                      name=f"crankbench-finite-{data.name}"))
    # one assignment for all channels: one merge per channel made this quadratic in their number
    return ds.assign(guarded) if guarded else ds


def iter_blocks(record: xr.Dataset, name: str):
    """Yield ``(t0, block)`` for channel ``name`` of a (lazy) record, one chunk at a time.

    ``t0`` is the time of the block's first sample (s); ``block`` a numpy array. For
    numpy-backed channels the whole channel is one block.

    Examples
    --------
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"x": dict(data=np.arange(6.0), sample_rate=2.0, units="V")})
    >>> [(t0, b.tolist()) for t0, b in iter_blocks(rec.chunk({"time": 4}), "x")]
    [(0.0, [0.0, 1.0, 2.0, 3.0]), (2.0, [4.0, 5.0])]
    """
    if name not in record.data_vars:
        from crankbench.predict._validate import suggest

        raise RecordError(f"record has no channel {name!r}"
                          f"{suggest(name, map(str, record.data_vars))}")
    var = record[name]
    dim = var.dims[0]
    has_time = dim in record.coords
    if var.chunks is None:
        yield (float(record[dim][0]) if has_time and var.size else 0.0), np.asarray(var.values)
        return
    start = 0
    for block in var.data.blocks:
        arr = np.asarray(block.compute())
        t0 = float(record[dim][start]) if has_time and arr.size else float(start)
        yield t0, arr
        start += arr.size
