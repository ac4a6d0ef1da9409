"""The implicit time coordinate (measure.timeindex) behaves like the pandas-indexed array it
replaces: every operation below is run on a record holding SampledTimeIndex and on its twin
holding the materialised float64 coordinate, and the results must be identical."""

import pickle

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from crankbench.measure.record import time_coordinate
from crankbench.measure.timeindex import (SampledTimeIndex, is_implicit_time, regular_clock,
                                          sampled_time)

FS, N, T0 = 2048.0, 300, 0.25


def pair(n=N, fs=FS, start=T0):
    """(implicit, pandas) twins of one record."""
    data = {"acc": ("time", np.sin(np.arange(n) / 7.0), {"units": "m/s^2"})}
    lazy = xr.Dataset(data).assign_coords(sampled_time(n, fs, start=start))
    plain = xr.Dataset(data, coords={"time": ("time", time_coordinate(n, fs, start),
                                              {"units": "s", "long_name": "time from record start"})})
    return lazy, plain


def same(a, b):
    """Identical variables (dims, values bit for bit, attrs), whatever index holds them."""
    assert type(a) is type(b)
    if isinstance(a, xr.DataArray):
        a, b = a.to_dataset(name="_"), b.to_dataset(name="_")
    assert set(a.variables) == set(b.variables) and a.attrs == b.attrs
    for name in a.variables:
        va, vb = a.variables[name], b.variables[name]
        assert va.dims == vb.dims and va.attrs == vb.attrs and va.dtype == vb.dtype, name
        np.testing.assert_array_equal(va.values, vb.values, err_msg=str(name))


def test_values_are_bit_identical_to_time_coordinate():
    lazy, plain = pair()
    assert is_implicit_time(lazy.xindexes["time"])
    np.testing.assert_array_equal(lazy["time"].values, time_coordinate(N, FS, T0))
    assert lazy["time"].attrs == plain["time"].attrs
    sub = lazy.isel(time=slice(17, 250, 3)).isel(time=slice(5, None, 2))
    assert isinstance(sub.xindexes["time"], SampledTimeIndex)
    np.testing.assert_array_equal(sub["time"].values, time_coordinate(N, FS, T0)[17:250:3][5::2])


@pytest.mark.parametrize("op", [
    lambda d: d.isel(time=slice(10, 40)),
    lambda d: d.isel(time=slice(None, None, -3)),
    lambda d: d.isel(time=[3, 1, 299]),
    lambda d: d.isel(time=np.arange(N) % 7 == 0),
    lambda d: d.isel(time=5),
    lambda d: d.sel(time=T0 + 10 / FS),
    lambda d: d.sel(time=[T0 + 3 / FS, T0 + 100 / FS]),
    lambda d: d.sel(time=slice(T0 + 10.5 / FS, T0 + 20 / FS)),
    lambda d: d.sel(time=slice(None, T0 + 4 / FS)),
    lambda d: d.sel(time=slice(-1.0, 99.0)),
    lambda d: d.sel(time=slice(5.0, 9.0)),
    lambda d: d.sel(time=[0.0, 0.26, 9.0], method="nearest"),
    lambda d: d.sel(time=[0.2601, 0.27], method="pad"),
    lambda d: d.sel(time=[0.2601, 0.27], method="backfill"),
    lambda d: d.sel(time=0.26, method="nearest", tolerance=1e-3),
    lambda d: d.sel(time=xr.DataArray([T0, T0 + 1 / FS], dims="pick")),
    lambda d: d.where(d.time > 0.3, drop=True),
    lambda d: d.rolling(time=5).mean(),
    lambda d: d.coarsen(time=10).mean(),
    lambda d: d.interp(time=[0.26, 0.3]),
    lambda d: d.acc.idxmax(),
    lambda d: d.diff("time"),
    lambda d: d.shift(time=2),
    lambda d: d.roll(time=4, roll_coords=True),
    lambda d: d.chunk(time=64).compute(),
    lambda d: d.drop_indexes("time"),
    lambda d: d.acc.to_series().to_xarray().rename(index="time"),
])
def test_operation_matches_the_pandas_index(op):
    lazy, plain = pair()
    try:
        want = op(plain)
    except Exception as exc:  # noqa: BLE001 - the implicit index must fail alike
        with pytest.raises(type(exc)):
            op(lazy)
        return
    same(op(lazy), want)


def test_exact_label_selection_refuses_a_time_between_samples():
    lazy, plain = pair()
    with pytest.raises(KeyError):
        plain.sel(time=0.2501)
    with pytest.raises(KeyError, match="not a sample of this clock"):
        lazy.sel(time=0.2501)
    with pytest.raises(KeyError, match="tolerance"):
        lazy.sel(time=0.2501, method="nearest", tolerance=1e-6)


def test_reindex_to_new_times_needs_the_materialised_index():
    """The one documented difference: xarray aligns a reindex target only with an index of
    the same type, so ``reindex(time=...)`` asks for the pandas index first."""
    lazy, plain = pair()
    targets = [0.25, 0.5, 3.0]
    with pytest.raises(ValueError, match="conflicting indexes"):
        lazy.reindex(time=targets)
    same(lazy.drop_indexes("time").set_xindex("time").reindex(time=targets),
         plain.reindex(time=targets))


def test_alignment_and_arithmetic():
    lazy, plain = pair()
    same(lazy.acc * 2 + lazy.acc, plain.acc * 2 + plain.acc)          # same clock
    same(lazy.acc + plain.acc, plain.acc + plain.acc)                  # pandas twin
    other, other_plain = pair(start=T0 + 50 / FS)                      # overlapping clock
    same(lazy.acc + other.acc, plain.acc + other_plain.acc)
    same(xr.align(lazy, other, join="outer")[0], xr.align(plain, other_plain, join="outer")[0])
    same(xr.merge([lazy.rename(acc="a"), other.rename(acc="b")], join="outer"),
         xr.merge([plain.rename(acc="a"), other_plain.rename(acc="b")], join="outer"))


def test_concat_contiguous_stays_implicit_else_pandas():
    lazy, plain = pair()
    parts = [lazy.isel(time=slice(0, 100)), lazy.isel(time=slice(100, None))]
    joined = xr.concat(parts, "time")
    assert isinstance(joined.xindexes["time"], SampledTimeIndex)
    same(joined, plain)
    gap = xr.concat([lazy.isel(time=slice(0, 10)), lazy.isel(time=slice(20, 30))], "time")
    same(gap, xr.concat([plain.isel(time=slice(0, 10)), plain.isel(time=slice(20, 30))], "time"))


def test_netcdf_pickle_and_pandas_views(tmp_path):
    lazy, plain = pair()
    lazy.to_netcdf(tmp_path / "x.nc", engine="h5netcdf")
    with xr.open_dataset(tmp_path / "x.nc", engine="h5netcdf") as back:
        same(back.load(), plain)
    again = pickle.loads(pickle.dumps(lazy))
    assert isinstance(again.xindexes["time"], SampledTimeIndex)
    same(again, plain)
    pd.testing.assert_index_equal(lazy.get_index("time"), plain.get_index("time"))
    pd.testing.assert_index_equal(lazy.indexes["time"], plain.indexes["time"])
    pd.testing.assert_frame_equal(lazy.to_dataframe(), plain.to_dataframe())


def test_regular_clock_reads_start_rate_and_length():
    lazy, _ = pair()
    assert regular_clock(lazy, "time") == (T0, FS, N)
    assert regular_clock(lazy.isel(time=slice(4, None, 4)), "time") == (T0 + 4 / FS, FS / 4,
                                                                      74)
    assert regular_clock(pair()[1], "time") is None


def test_sampled_dataset_is_the_public_construction():
    """The direct build (no merge/align pass) gives exactly what ``xr.Dataset(...,
    coords=sampled_time(...))`` gives: values, attrs, index type and behaviour."""
    from crankbench.measure.timeindex import sampled_dataset

    x = np.arange(10.0)
    variables = {"a": xr.Variable(("time_b",), x, {"units": "m"}),
                 "b": xr.Variable(("time_b",), -x, {"units": "V"})}
    got = sampled_dataset(variables, 10, 250.0, start=0.5, dim="time_b", attrs={"k": 1})
    ref = xr.Dataset(variables, coords=sampled_time(10, 250.0, start=0.5, dim="time_b"),
                     attrs={"k": 1})
    xr.testing.assert_identical(got, ref)
    assert type(got.xindexes["time_b"]) is type(ref.xindexes["time_b"])
    np.testing.assert_array_equal(got["time_b"].values, 0.5 + np.arange(10) / 250.0)
    xr.testing.assert_identical(got.sel(time_b=slice(0.51, 0.52)),
                                ref.sel(time_b=slice(0.51, 0.52)))
    with pytest.raises(ValueError, match="dims \\('time_b',\\) and 11 values"):
        sampled_dataset(variables, 11, 250.0, dim="time_b")
