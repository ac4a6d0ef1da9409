"""analysis._dataset: the direct Dataset build is identical to xarray's public constructor
(an xarray release that changes its direct form fails here), and inconsistent input gets the
public constructor's error."""

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from crankbench.analysis._dataset import dataset
from crankbench.analysis.orders import order_track
from crankbench.analysis.resample import shaft_angle


def _parts(n=50, k=3):
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.5, 1.5, n))              # not uniform: a real index
    orders = np.array([1.0, 2.0, 4.5])[:k]
    var = xr.Variable
    data = {"amplitude": var(("order", "time"), rng.random((k, n)), {"units": "m"}),
            "mean": var("time", rng.random(n), {"units": "m"})}
    coords = {"order": var("order", orders, {"units": "1"}), "time": var("time", t, {"units": "s"}),
              "rpm": var("time", rng.random(n) * 1e3, {"units": "rpm"})}
    indexes = {"order": xr.indexes.PandasIndex(pd.Index(orders, name="order"), "order"),
               "time": xr.indexes.PandasIndex(pd.Index(t, name="time"), "time")}
    return data, coords, indexes


def test_direct_build_is_identical_to_the_public_constructor():
    data, coords, indexes = _parts()
    fast = dataset(data, coords, indexes, {"channel": "x"})
    public = xr.Dataset(data, coords=xr.Coordinates(coords, indexes=indexes),
                        attrs={"channel": "x"})
    assert fast.identical(public)
    assert list(fast.variables) == list(public.variables)
    assert dict(fast.sizes) == dict(public.sizes) and list(fast.coords) == list(public.coords)
    assert set(fast.xindexes) == {"order", "time"}
    # and it behaves as one: label selection, arithmetic, a new variable
    t3 = float(coords["time"].values[3])
    assert float(fast.amplitude.sel(order=2.0, time=t3)) == data["amplitude"].values[1, 3]
    fast["double"] = fast.amplitude * 2
    np.testing.assert_array_equal(fast.double.values, 2 * data["amplitude"].values)


def test_inconsistent_lengths_get_xarrays_error():
    data, coords, indexes = _parts()
    data["mean"] = xr.Variable("time", np.zeros(7))
    with pytest.raises(ValueError, match="conflicting sizes|length"):
        dataset(data, coords, indexes, {})


def test_order_track_is_the_same_either_way(monkeypatch):
    """A VKF track (its Dataset built directly) equals the one from the public constructor."""
    from crankbench.analysis import _dataset

    fs = 2000.0
    t = np.arange(int(4 * fs)) / fs
    rpm = 900 + 100 * t
    x = np.cos(2 * shaft_angle(rpm, fs)) + 0.1 * np.cos(0.5 * shaft_angle(rpm, fs))
    kw = dict(fs=fs, speed_rpm=rpm, orders=[0.5, 2], method="vkf", bandwidth_hz=2.0)
    fast = order_track(x, **kw)
    public = _dataset.dataset
    monkeypatch.setattr(_dataset, "dataset", lambda *a, **k: public(*a, direct=False))
    assert fast.identical(order_track(x, **kw))
