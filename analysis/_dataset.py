"""Building a labelled :class:`xarray.Dataset` from variables that agree by construction.

The trackers return Datasets of a few (order × time) variables on one time axis. xarray's
public constructor merges and aligns its inputs, a deep stack of Python calls that is a
visible part of a fast tracker's time (bench suite ``orders``, row ``order_track vkf speed``).
Here the variables, their dimensions and both indexes are built by
the caller, so there is nothing to merge: :func:`dataset` hands them to xarray's direct
constructor, and falls back to the public one when that is missing or refuses
them (``tests/analysis/test_dataset.py`` checks both give identical Datasets, so an xarray
release that changes the direct form fails the test, not a user's result).
"""

from __future__ import annotations

__all__ = ["dataset"]


def dataset(data_vars: dict, coords: dict, indexes: dict, attrs: dict, *,
            direct: bool = True):
    """The Dataset of these variables (no merge, no alignment).

    Parameters
    ----------
    data_vars, coords : dict of str -> xarray.Variable
        Data variables and coordinates (each dimension of one length throughout).
    indexes : dict of str -> xarray.indexes.Index
        The index of each indexed coordinate (e.g. ``PandasIndex`` of a dimension coordinate).
    attrs : dict
        The Dataset's attributes (taken, not copied).
    direct : bool
        Use xarray's direct constructor when it exists (False: the public constructor).

    Returns
    -------
    xarray.Dataset
        Identical to ``xr.Dataset(data_vars, coords=xr.Coordinates(coords, indexes=indexes),
        attrs=attrs)``.

    Examples
    --------
    >>> import numpy as np, pandas as pd, xarray as xr
    >>> t = np.arange(4) / 2.0
    >>> coords = {"time": xr.Variable("time", t, {"units": "s"})}
    >>> idx = {"time": xr.indexes.PandasIndex(pd.Index(t, name="time"), "time")}
    >>> ds = dataset({"x": xr.Variable("time", t ** 2)}, coords, idx, {"channel": "a"})
    >>> float(ds.x.sel(time=1.5)), ds.time.attrs["units"]
    (2.25, 's')
    >>> ds.identical(dataset({"x": xr.Variable("time", t ** 2)}, coords, idx,
    ...                      {"channel": "a"}, direct=False))
    True
    """
    import xarray as xr

    construct = getattr(xr.Dataset, "_construct_direct", None) if direct else None
    if construct is not None:
        try:
            variables = dict(data_vars)
            for name, var in coords.items():
                variables[name] = var
            for name, index in indexes.items():
                variables.update(index.create_variables({name: coords[name]}))
            dims: dict = {}
            for var in variables.values():
                for dim, size in zip(var.dims, var.shape):
                    if dims.setdefault(dim, size) != size:
                        raise ValueError(dim)          # the public form names the conflict
            return construct(variables, set(coords), dims, attrs, dict(indexes))
        except (TypeError, ValueError, KeyError):
            pass
    return xr.Dataset(data_vars, coords=xr.Coordinates(coords, indexes=indexes), attrs=attrs)
