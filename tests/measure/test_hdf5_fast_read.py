"""HDF5 channels are read straight from their byte ranges when storage allows, through HDF5
otherwise; either way the samples equal what was written (every storage variant below is
produced with h5py and read back through measure.read)."""

import h5py
import numpy as np
import pytest

from crankbench.measure import io
from crankbench.measure.readers import hdf5
from crankbench.measure.record import make_record

N, FS = 300_001, 1000.0   # a partial last chunk


def _file(tmp_path, **storage):
    x = np.random.default_rng(3).standard_normal(N).astype(np.float32)
    rec = make_record({"acc": dict(data=x, sample_rate=FS, units="m/s^2",
                                   quantity="acceleration")})
    path = tmp_path / "r.h5"
    io.write(rec, path)
    if storage:
        with h5py.File(path, "r+") as f:
            attrs = dict(f["channels/acc"].attrs)
            del f["channels/acc"]
            dtype = storage.pop("dtype", np.float32)
            ds = f["channels"].create_dataset("acc", data=x.astype(dtype), **storage)
            ds.attrs.update(attrs)
    return path, x


@pytest.mark.parametrize("storage, direct", [
    ({}, True),                                          # as written: 1 MB chunks
    ({"chunks": None}, True),                            # contiguous
    ({"chunks": (4096,)}, True),                         # many small chunks
    ({"chunks": (65536,), "compression": "gzip"}, False),  # filtered: HDF5 decodes
    ({"chunks": (65536,), "shuffle": True}, False),
    ({"dtype": ">f4"}, False),                           # foreign byte order
    ({"dtype": np.float64, "chunks": (10_000,)}, True),
])
def test_every_storage_reads_back_exactly(tmp_path, storage, direct):
    path, x = _file(tmp_path, **storage)
    with h5py.File(path, "r") as f:
        assert (hdf5._raw_runs(f["channels/acc"]) is not None) == direct
    got = io.read(path)["acc"].values
    np.testing.assert_array_equal(got.astype(np.float64), x.astype(np.float64))


def test_chunks_written_in_order_are_one_read(tmp_path):
    path, _ = _file(tmp_path)
    with h5py.File(path, "r") as f:
        runs = hdf5._raw_runs(f["channels/acc"])
    assert len(runs) == 1 and runs[0][1:] == (0, N)


def test_bytes_that_disagree_with_hdf5_fall_back_to_hdf5(tmp_path, monkeypatch):
    """A wrong byte range (simulated) is caught by the three-sample check."""
    path, x = _file(tmp_path)
    monkeypatch.setattr(hdf5, "_raw_runs", lambda ds: [(0, 0, ds.shape[0])])
    np.testing.assert_array_equal(io.read(path)["acc"].values, x)
