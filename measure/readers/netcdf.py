"""netCDF4 (.nc) records via xarray + h5netcdf, following the Record schema directly.

The Dataset is written as is (CF-style: each channel a variable, ``time``/``time_<group>``
coordinates, attrs carried verbatim); the optional ground truth goes to group ``truth``. Files
from other tools are accepted when each variable carries a ``units`` attr (any spelling
:func:`measure.units.to_si` knows) and, for sampled channels, a time coordinate in s;
``sample_rate`` is inferred from the coordinate when absent. Streams via dask chunks.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import is_pulse_dim
from ._common import clean_attrs, refuse_external_links, select, si_channel
from .hdf5 import read_truth as _read_truth
from .hdf5 import write_truth

__all__ = ["FORMAT", "check_magic", "read", "write", "open", "read_truth"]

FORMAT = "netCDF4/HDF5"


def check_magic(head: bytes) -> bool:
    """netCDF4 files are HDF5 files."""
    return head[:8] == b"\x89HDF\r\n\x1a\n"


def write(record: xr.Dataset, path, *, truth: xr.Dataset | None = None) -> dict:
    """Write ``record`` as netCDF4 (h5netcdf engine)."""
    out = record.copy()
    for dim in out.dims:
        if dim in out.xindexes and type(out.xindexes[dim]).__name__ == "RangeIndex":
            out = out.assign_coords({dim: (dim, np.asarray(out[dim].values), out[dim].attrs)})
    out.to_netcdf(path, engine="h5netcdf", mode="w")
    if truth is not None:
        write_truth(truth, path)
    return {}


def read_truth(path) -> xr.Dataset:
    """Read group ``truth``."""
    return _read_truth(path)


def _convert(ds: xr.Dataset, file: str, *, lazy: bool) -> xr.Dataset:
    data_vars = {}
    for name, var in ds.data_vars.items():
        name = str(name)
        if var.ndim != 1:
            raise RecordError(f"{file}: variable {name!r} has dims {var.dims}; expected 1-D "
                              "channels")
        meta = clean_attrs(var.attrs)
        dim = str(var.dims[0])
        if "sample_rate" not in meta and not is_pulse_dim(dim) and dim in ds.coords:
            t = np.asarray(ds[dim].values, dtype=np.float64)
            if t.size >= 2 and t[-1] > t[0]:
                meta["sample_rate"] = (t.size - 1) / (t[-1] - t[0])
        values = var.data if lazy else np.asarray(var.values)
        values, attrs = si_channel(name, values, meta, file=file)
        data_vars[name] = xr.Variable((dim,), values, attrs)
    coords = {}
    for c in ds.coords:
        if c in ds.dims:
            coords[c] = (c, pd.Index(np.asarray(ds[c].values, dtype=np.float64), copy=False),
                         {"units": "s", **clean_attrs(ds[c].attrs)})
    return xr.Dataset(data_vars, coords=coords, attrs=clean_attrs(ds.attrs))


def read(path, *, channels=None) -> xr.Dataset:
    """Read a netCDF4 record into memory."""
    file = str(path)
    refuse_external_links(path, file=file)
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        names = select([str(n) for n in ds.data_vars], channels, file=file)
        return _convert(ds[names].load(), file, lazy=False)


def open(path, *, chunk_seconds: float = 10.0, channels=None) -> xr.Dataset:  # noqa: A001
    """Open a netCDF4 record lazily with dask chunks of about ``chunk_seconds`` per clock.

    The time coordinates are read into memory (netCDF stores them explicitly): 8 bytes per
    sample of each clock. For records larger than memory prefer the ``.h5`` layout.
    """
    file = str(path)
    refuse_external_links(path, file=file)
    ds = xr.open_dataset(path, engine="h5netcdf")
    names = select([str(n) for n in ds.data_vars], channels, file=file)
    ds = ds[names]
    chunks = {}
    for name in names:
        var = ds[name]
        fs = var.attrs.get("sample_rate")
        dim = var.dims[0]
        chunks[dim] = max(1, int(round(chunk_seconds * float(fs)))) if fs else -1
    return _convert(ds.chunk(chunks), file, lazy=True)
