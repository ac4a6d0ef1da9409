"""Implicit time coordinates: a regular clock held as (start, sample rate, length), not an array.

A record's time coordinate on a regular clock is ``t_i = start + i / sample_rate``; as a
float64 array it is twice the size of float32 samples, and building it was half the cost of
reading an HDF5 record (issue 21). :class:`SampledTimeIndex` is an :mod:`xarray` index that
keeps the three numbers and generates values on demand, **bit-identical** to
:func:`measure.record.time_coordinate` (``i / sample_rate``, then ``+ start``), so a record
holding it satisfies the Record contract (docs/DESIGN.md "Data model") unchanged:
``record["time"].values`` is the float64 array it always was, only built when asked for.

What works as with a pandas index (checked in ``tests/measure/test_timeindex.py``):

* positional selection (``isel`` with slices -- the index stays implicit, strides included --,
  integers and arrays);
* label selection (``sel``): scalars and arrays match exactly (to 1e-9 of a sample step, the
  rounding of a decimal label), slices select every sample inside the closed interval,
  ``method="nearest" | "pad"/"ffill" | "backfill"/"bfill"`` and ``tolerance`` as in pandas;
* alignment and arithmetic with records on the same clock, on another clock (joins through
  pandas) and with pandas-indexed records of equal times;
* ``concat`` along time (contiguous pieces stay implicit, others become a pandas index),
  ``to_netcdf``, pickling (dask, distributed), ``get_index`` / ``indexes`` (a pandas
  ``Index``, materialised).

One difference: ``record.reindex(time=new_times)`` raises xarray's "conflicting indexes"
error (xarray aligns a reindex target only with an index of its own type); materialise first,
``record.drop_indexes("time").set_xindex("time").reindex(time=new_times)``, or interpolate
(``record.interp(time=new_times)`` works as is).

Examples
--------
>>> import numpy as np, xarray as xr
>>> rec = xr.Dataset({"acc": ("time", np.arange(5.0))}).assign_coords(
...     sampled_time(5, 1000.0, start=0.5))
>>> rec["time"].values
array([0.5  , 0.501, 0.502, 0.503, 0.504])
>>> print(rec.sel(time=slice(0.5012, 0.503))["acc"].values, rec.xindexes["time"])
[2. 3.] SampledTimeIndex(start=0.5, sample_rate=1000, size=5, offset=0, stride=1, dim='time')
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Mapping
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from xarray.indexes import CoordinateTransform, CoordinateTransformIndex, Index, PandasIndex
from xarray.core.indexing import IndexSelResult

__all__ = ["SampleClock", "SampledTimeIndex", "sampled_time", "sampled_dataset",
           "regular_clock", "is_implicit_time", "LABEL_RTOL"]

#: a label within this fraction of a sample step of a sample's time selects it exactly
LABEL_RTOL = 1e-9
#: attrs of an implicit time coordinate
TIME_ATTRS = {"units": "s", "long_name": "time from record start"}


class SampleClock(CoordinateTransform):
    """``t_i = (offset + i·stride) / sample_rate + start`` for ``i = 0 .. size-1`` (s).

    ``offset`` and ``stride`` are integers, so slices of slices stay exact: the values equal
    those of the unsliced clock at the same samples, bit for bit.
    """

    __slots__ = ("start", "sample_rate", "offset", "stride")

    def __init__(self, start: float, sample_rate: float, size: int, *, offset: int = 0,
                 stride: int = 1, coord_name: Hashable = "time", dim: str = "time"):
        super().__init__([coord_name], {dim: int(size)}, dtype=np.dtype(np.float64))
        self.start = float(start)
        self.sample_rate = float(sample_rate)
        self.offset = int(offset)
        self.stride = int(stride)

    @property
    def dim(self) -> str:
        return self.dims[0]

    @property
    def coord_name(self) -> Hashable:
        return self.coord_names[0]

    @property
    def size(self) -> int:
        return self.dim_size[self.dim]

    def forward(self, dim_positions: dict[str, Any]) -> dict[Hashable, Any]:
        pos = np.asarray(dim_positions[self.dim])
        if pos.dtype.kind in "iu":
            samples = self.offset + pos.astype(np.int64) * self.stride
        else:
            samples = self.offset + pos * float(self.stride)
        t = samples / self.sample_rate          # as time_coordinate: i / fs, then + start
        if self.start:
            t = t + self.start
        return {self.coord_name: t}

    def reverse(self, coord_labels: dict[Hashable, Any]) -> dict[str, Any]:
        labels = np.asarray(coord_labels[self.coord_name], dtype=np.float64)
        samples = (labels - self.start) * self.sample_rate
        return {self.dim: (samples - self.offset) / self.stride}

    def equals(self, other, exclude=None, **kwargs) -> bool:
        return (isinstance(other, SampleClock) and self.size == other.size
                and (self.start, self.sample_rate, self.offset, self.stride)
                == (other.start, other.sample_rate, other.offset, other.stride))

    def sliced(self, sl: slice) -> "SampleClock":
        """The clock of ``values[sl]`` (exact, integer offsets)."""
        r = range(self.size)[sl]
        return SampleClock(self.start, self.sample_rate, len(r),
                           offset=self.offset + r.start * self.stride,
                           stride=self.stride * r.step, coord_name=self.coord_name,
                           dim=self.dim)

    def values(self) -> np.ndarray:
        """All times, float64."""
        return self.forward({self.dim: np.arange(self.size)})[self.coord_name]


class SampledTimeIndex(CoordinateTransformIndex):
    """xarray index of a regular time coordinate that never stores its values (module
    docstring). Build it with :func:`sampled_time`."""

    transform: SampleClock

    def __init__(self, transform: SampleClock):
        super().__init__(transform)

    # ------------------------------------------------------------------ properties ----
    @property
    def start(self) -> float:
        """Time of sample 0, s."""
        return self.transform.start + self.transform.offset / self.transform.sample_rate

    @property
    def step(self) -> float:
        """Time between consecutive samples, s."""
        return self.transform.stride / self.transform.sample_rate

    @property
    def sample_rate(self) -> float:
        """Samples per second of this (possibly strided) index, Hz."""
        return self.transform.sample_rate / self.transform.stride

    @property
    def dim(self) -> str:
        return self.transform.dim

    @property
    def size(self) -> int:
        return self.transform.size

    def _pandas(self) -> PandasIndex:
        return PandasIndex(self.to_pandas_index(), self.dim, coord_dtype=np.dtype(np.float64))

    # ------------------------------------------------------------------ xarray API ----
    def to_pandas_index(self) -> pd.Index:
        return pd.Index(self.transform.values(), name=self.transform.coord_name)

    def isel(self, indexers: Mapping[Any, Any]) -> Index | None:
        idx = indexers[self.dim]
        if isinstance(idx, slice):
            return SampledTimeIndex(self.transform.sliced(idx))
        if isinstance(idx, xr.Variable):
            if idx.ndim != 1:
                return None
            new_dim, idx = idx.dims[0], idx.values
        else:
            new_dim = self.dim
        idx = np.asarray(idx)
        if idx.ndim == 0:
            return None
        if idx.dtype == bool:
            idx = np.flatnonzero(idx)
        values = self.transform.forward({self.dim: idx})[self.transform.coord_name]
        return PandasIndex(pd.Index(values, name=self.transform.coord_name), new_dim,
                           coord_dtype=np.dtype(np.float64))

    def sel(self, labels: dict[Any, Any], method=None, tolerance=None) -> IndexSelResult:
        label = labels[self.transform.coord_name]
        if isinstance(label, slice):
            if method is not None or tolerance is not None:
                raise NotImplementedError("cannot use method or tolerance with a slice")
            return IndexSelResult({self.dim: self._slice(label)})
        is_xr = isinstance(label, (xr.DataArray, xr.Variable))
        values = label.values if is_xr else np.asarray(label)
        pos = self._positions(np.asarray(values, dtype=np.float64), method, tolerance)
        if is_xr:
            pos = type(label)(label.dims, pos) if isinstance(label, xr.Variable) else \
                xr.DataArray(pos, dims=label.dims)
        elif np.ndim(pos) == 0:
            pos = int(pos)
        return IndexSelResult({self.dim: pos})

    def _positions(self, labels, method, tolerance):
        n = self.size
        p = self.transform.reverse({self.transform.coord_name: labels})[self.dim]
        near = np.rint(p)
        if method is None:
            ok = (np.abs(p - near) <= LABEL_RTOL) & (near >= 0) & (near < n)
            if not np.all(ok):
                bad = np.atleast_1d(labels)[~np.atleast_1d(ok)]
                raise KeyError(f"time {bad[0]!r} s is not a sample of this clock "
                               f"(start {self.start!r} s, step {self.step!r} s, {n} samples);"
                               " use method='nearest' or a slice")
            return near.astype(np.int64)
        if method == "nearest":
            pos = np.clip(near, 0, n - 1)
        elif method in ("pad", "ffill"):
            pos = np.floor(p + LABEL_RTOL)
            if np.any(pos < 0):
                raise KeyError("label before the first sample with method='pad'")
            pos = np.minimum(pos, n - 1)
        elif method in ("backfill", "bfill"):
            pos = np.ceil(p - LABEL_RTOL)
            if np.any(pos > n - 1):
                raise KeyError("label after the last sample with method='backfill'")
            pos = np.maximum(pos, 0)
        else:
            raise ValueError(f"method={method!r} is not one of None, 'nearest', 'pad', "
                             "'ffill', 'backfill', 'bfill'")
        if tolerance is not None:
            got = self.transform.forward({self.dim: pos})[self.transform.coord_name]
            if np.any(np.abs(got - labels) > tolerance):
                raise KeyError(f"no sample within tolerance={tolerance!r} s")
        return pos.astype(np.int64)

    def _slice(self, label: slice) -> slice:
        if label.step is not None:
            raise NotImplementedError("label slices with a step are not supported; use isel")
        n = self.size
        first, last = 0, n
        if label.start is not None:
            p = float(self.transform.reverse({self.transform.coord_name: label.start})[self.dim])
            first = min(max(math.ceil(p - LABEL_RTOL), 0), n)
        if label.stop is not None:
            p = float(self.transform.reverse({self.transform.coord_name: label.stop})[self.dim])
            last = min(max(math.floor(p + LABEL_RTOL) + 1, 0), n)
        return slice(first, max(first, last))

    def equals(self, other: Index, *, exclude=None, **kwargs) -> bool:
        if isinstance(other, SampledTimeIndex):
            if self.transform.equals(other.transform):
                return True
            return (self.size == other.size
                    and np.array_equal(self.transform.values(), other.transform.values()))
        if isinstance(other, PandasIndex):
            return self._pandas().equals(other)
        return False

    def join(self, other: Index, how: str = "inner") -> Index:
        mine = self._pandas()
        theirs = other._pandas() if isinstance(other, SampledTimeIndex) else other
        return mine.join(theirs, how=how)

    def reindex_like(self, other: Index, method=None, tolerance=None):
        theirs = other._pandas() if isinstance(other, SampledTimeIndex) else other
        return self._pandas().reindex_like(theirs, method=method, tolerance=tolerance)

    @classmethod
    def concat(cls, indexes, dim, positions=None) -> Index:
        first = indexes[0]
        contiguous = all(isinstance(i, SampledTimeIndex) for i in indexes)
        if contiguous:
            t0 = first.transform
            expect = t0.offset + t0.size * t0.stride
            for other in indexes[1:]:
                t = other.transform
                if (t.start, t.sample_rate, t.stride) != (t0.start, t0.sample_rate, t0.stride) \
                        or t.offset != expect:
                    contiguous = False
                    break
                expect += t.size * t.stride
        if contiguous:
            size = sum(i.size for i in indexes)
            t0 = first.transform
            return cls(SampleClock(t0.start, t0.sample_rate, size, offset=t0.offset,
                                   stride=t0.stride, coord_name=t0.coord_name, dim=t0.dim))
        pandas = [i._pandas() if isinstance(i, SampledTimeIndex) else i for i in indexes]
        return PandasIndex.concat(pandas, dim, positions)

    def roll(self, shifts):
        return self._pandas().roll(shifts)

    def __repr__(self) -> str:
        t = self.transform
        return (f"SampledTimeIndex(start={t.start!r}, sample_rate={t.sample_rate:g}, "
                f"size={t.size}, offset={t.offset}, stride={t.stride}, dim={t.dim!r})")

    def _repr_inline_(self, max_width) -> str:
        return f"SampledTimeIndex (start={self.start:.6g} s, {self.sample_rate:g} Hz)"


def sampled_time(n: int, sample_rate: float, *, start: float = 0.0, dim: str = "time",
                 attrs: Mapping | None = None) -> xr.Coordinates:
    """Coordinates holding an implicit time coordinate ``start + i / sample_rate`` (s).

    Parameters
    ----------
    n : int
        Samples.
    sample_rate : float
        Hz, > 0.
    start : float
        Time of the first sample, s.
    dim : str
        Dimension (and coordinate) name.
    attrs : mapping, optional
        Coordinate attrs; default ``units = "s"``, ``long_name = "time from record start"``.

    Returns
    -------
    xarray.Coordinates
        Pass to ``Dataset.assign_coords`` or the ``coords=`` of a Dataset.

    Examples
    --------
    >>> c = sampled_time(3, 4.0)
    >>> print(c["time"].values, c["time"].attrs["units"])
    [0.   0.25 0.5 ] s
    """
    index = SampledTimeIndex(SampleClock(start, sample_rate, n, coord_name=dim, dim=dim))
    coords = xr.Coordinates.from_xindex(index)
    coords.variables[dim].attrs.update(attrs if attrs is not None
                             else TIME_ATTRS)
    return coords


def sampled_dataset(variables: Mapping[Hashable, xr.Variable], n: int, sample_rate: float, *,
                    start: float = 0.0, dim: str = "time",
                    attrs: Mapping | None = None) -> xr.Dataset:
    """A Dataset of 1-D ``variables`` on ``dim`` with the implicit time coordinate
    ``start + i / sample_rate`` (s): ``xr.Dataset(variables, coords=sampled_time(...),
    attrs=attrs)`` built without xarray's merge and alignment pass (a tenth of its time; a
    reader's fixed cost), the same object (``tests/measure/test_timeindex.py``).

    Parameters
    ----------
    variables : mapping of name -> xarray.Variable
        Each with dims ``(dim,)`` and ``n`` values.
    n : int
        Samples.
    sample_rate : float
        Hz, > 0.
    start : float
        Time of the first sample, s.
    dim : str
        Dimension (and coordinate) name.
    attrs : mapping, optional
        The Dataset's attrs.

    Returns
    -------
    xarray.Dataset

    Examples
    --------
    >>> ds = sampled_dataset({"acc": xr.Variable(("time",), np.zeros(4))}, 4, 2.0, start=1.0)
    >>> print(ds["time"].values, ds["time"].attrs["units"], type(ds.xindexes["time"]).__name__)
    [1.  1.5 2.  2.5] s SampledTimeIndex
    """
    variables = dict(variables)
    if any(v.dims != (dim,) or v.shape != (n,) for v in variables.values()) or dim in variables:
        raise ValueError(f"every variable must have dims ({dim!r},) and {n} values")
    attrs = dict(attrs or {})
    construct = getattr(xr.Dataset, "_construct_direct", None)
    if construct is None:  # an xarray without its internal constructor: the public path
        return xr.Dataset(variables, coords=sampled_time(n, sample_rate, start=start, dim=dim),
                          attrs=attrs)
    index = SampledTimeIndex(SampleClock(start, sample_rate, n, coord_name=dim, dim=dim))
    coord = index.create_variables()
    coord[dim].attrs.update(TIME_ATTRS)
    return construct({**variables, **coord}, {dim}, {dim: n}, attrs, indexes={dim: index})


def is_implicit_time(index) -> bool:
    """True for indexes that generate a regular time coordinate instead of storing it
    (:class:`SampledTimeIndex`, xarray's ``RangeIndex``)."""
    return isinstance(index, SampledTimeIndex) or type(index).__name__ == "RangeIndex"


def regular_clock(record: xr.Dataset, dim: str):
    """``(start s, sample_rate Hz, n)`` of an implicit regular time coordinate, else None.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> rec = xr.Dataset({"x": ("time", np.zeros(8))}).assign_coords(sampled_time(8, 100.0))
    >>> regular_clock(rec.isel(time=slice(2, None, 2)), "time")
    (0.02, 50.0, 3)
    """
    index = record.xindexes.get(dim)
    if isinstance(index, SampledTimeIndex):
        return index.start, index.sample_rate, index.size
    if index is not None and type(index).__name__ == "RangeIndex":
        return float(index.start), 1.0 / float(index.step), int(index.size)
    return None
