"""HDF5 channels are read straight from their byte ranges when storage allows, through HDF5
otherwise; either way the samples equal what was written (every storage variant below is
produced with h5py and read back through measure.read)."""

import h5py
import numpy as np
import pytest

from crankbench.measure import io
from crankbench.measure.readers import _h5raw, hdf5
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
    ({}, True),                                          # as written: contiguous
    ({"chunks": (262144,)}, True),                       # as written before: 1 MB chunks
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
        assert (_h5raw.raw_runs(f["channels/acc"]) is not None) == direct
    got = io.read(path)["acc"].values
    np.testing.assert_array_equal(got.astype(np.float64), x.astype(np.float64))


@pytest.mark.parametrize("chunked", [False, True])  # written now; before (1 MB chunks)
def test_chunks_written_in_order_are_one_read(tmp_path, chunked):
    path, x = _file(tmp_path)
    if chunked:  # a fresh file (no space freed by a deleted dataset), chunks in order
        src, path = path, tmp_path / "chunked.h5"
        with h5py.File(src, "r") as f, h5py.File(path, "w") as g:
            g.attrs.update(f.attrs)
            f.copy(f["dims"], g)
            ds = g.create_group("channels").create_dataset("acc", data=x, chunks=(262144,))
            ds.attrs.update(f["channels/acc"].attrs)
        np.testing.assert_array_equal(io.read(path)["acc"].values, x)
    with h5py.File(path, "r") as f:
        assert (f["channels/acc"].chunks is not None) == chunked
        runs = _h5raw.raw_runs(f["channels/acc"])
    assert len(runs) == 1 and runs[0][1:] == (0, N)
    if not chunked:  # >= 64 KiB: starts on a page, read into a page-aligned array
        assert runs[0][0] % hdf5.ALIGN_BYTES == 0
        got = _h5raw.congruent_empty(N, np.float32, runs[0][0])
        assert got.ctypes.data % hdf5.ALIGN_BYTES == 0 and got.shape == (N,)


def test_a_datatype_other_than_numpys_is_read_by_hdf5(tmp_path):
    """Samples whose file datatype differs from numpy's in the bits (12-bit integers at bit
    offset 2 in 16-bit words: h5py shows them as int16) are converted by HDF5, not copied."""
    path, _ = _file(tmp_path)
    x = np.arange(-1000, 1000, 7, dtype=np.int16)
    ftype = h5py.h5t.STD_I16LE.copy()
    ftype.set_precision(12)
    ftype.set_offset(2)
    with h5py.File(path, "r+") as f:
        del f["channels/acc"]
        space = h5py.h5s.create_simple(x.shape)
        h5py.h5d.create(f["channels"].id, b"acc", ftype, space)
        f["channels/acc"][...] = x
        f["dims/time"].attrs["length"] = x.size
        raw = np.fromfile(path, np.int16, count=x.size,
                          offset=f["channels/acc"].id.get_offset())
        assert f["channels/acc"].dtype == np.int16 and _h5raw.raw_runs(f["channels/acc"]) is None
    assert not np.array_equal(raw, x)  # the bytes are not the values
    np.testing.assert_array_equal(io.read(path)["acc"].values, x.astype(np.float64))


def test_low_level_attributes_equal_h5py_high_level(tmp_path):
    """The reader's attribute path (h5py low-level API, scalars) gives exactly what
    ``clean_attrs(obj.attrs)`` gives, type and value, for every kind of attribute h5py writes;
    the kinds it does not decode itself (arrays, fixed-length, empty) go through ``attrs``."""
    from crankbench.measure.readers._common import clean_attrs

    path = tmp_path / "a.h5"
    with h5py.File(path, "w") as f:
        a = f.attrs
        a["s"], a["u"], a["b"], a["i"], a["f"] = "hello", "µm/s² ü", np.bool_(True), 3, 2.5
        a["i8"], a["u16"], a["f32"] = np.int8(-3), np.uint16(7), np.float32(1.5)
        a["fixed"], a["arr"], a["sarr"] = np.bytes_(b"abc"), np.arange(3.0), ["x", "y"]
        a["empty"], a["c"], a["nan"] = h5py.Empty("f8"), 1 + 2j, np.nan
        a.create("ascii", data="plain", dtype=h5py.string_dtype("ascii"))
        a.create("bad", data=b"\xff\xfe", dtype=h5py.string_dtype("utf-8"))
    with h5py.File(path, "r") as f:
        fast, ref = hdf5._attrs(f), clean_attrs(f.attrs)
    assert list(fast) == list(ref)
    assert len(ref) == 16
    for k in ref:
        assert type(fast[k]) is type(ref[k]) and repr(fast[k]) == repr(ref[k]), k


def test_a_channel_that_is_a_group_is_refused_by_name(tmp_path):
    from crankbench.predict.errors import RecordError

    path, _ = _file(tmp_path)
    with h5py.File(path, "r+") as f:
        attrs = dict(f["channels/acc"].attrs)
        del f["channels/acc"]
        f["channels"].create_group("acc").attrs.update(attrs)
    with pytest.raises(RecordError, match=r"r\.h5: channel 'acc' is an HDF5 group, not a "
                                          r"dataset; expected one dataset per channel"):
        io.read(path)


def test_the_file_is_closed_after_a_read(tmp_path):
    """The low-level open closes the file with every object opened in it: the file can be
    opened for writing right after (HDF5 refuses while a read-only handle is open)."""
    path, x = _file(tmp_path)
    rec = io.read(path)
    with h5py.File(path, "r+") as f:
        f.attrs["touched"] = 1
    np.testing.assert_array_equal(rec["acc"].values, x)


def test_a_read_leaves_no_hdf5_object_open_and_other_handles_valid(tmp_path):
    """A read closes all it opened (the file too: no HDF5 identifier is left behind), and the
    quick close taken when nothing else of the file is open does not touch handles another
    opener of the same file holds."""
    path, x = _file(tmp_path)
    before = h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_ALL)
    np.testing.assert_array_equal(io.read(path)["acc"].values, x)
    assert h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_ALL) == before
    fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
    fapl.set_fclose_degree(h5py.h5f.CLOSE_STRONG)  # what the reader opens with
    with h5py.File(h5py.h5f.open(str(path).encode(), h5py.h5f.ACC_RDONLY, fapl=fapl)) as f:
        d = f["channels/acc"]
        np.testing.assert_array_equal(io.read(path)["acc"].values, x)
        assert d.id.valid
        np.testing.assert_array_equal(d[...], x)


def test_a_file_open_in_an_h5py_file_of_this_process_reads(tmp_path):
    """A notebook holds the record open with ``h5py.File`` (close degree "weak"); HDF5 refused
    the reader's strong open of the same file ("file close degree doesn't match") and the
    read failed as "truncated or corrupt". Now the same samples, the other handle still valid,
    and nothing left open once both are done."""
    path, x = _file(tmp_path)
    io.read(path)                  # (the reader's and h5py's datatypes, made once per process)
    with h5py.File(path, "r") as f:
        f["channels/acc"][...]
    before = h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_ALL)
    with h5py.File(path, "r") as f:
        d = f["channels/acc"]
        for _ in range(2):
            np.testing.assert_array_equal(io.read(path)["acc"].values, x)
        assert d.id.valid
        np.testing.assert_array_equal(d[...], x)
    del d                          # (h5py keeps the dataset's datatype while it is referenced)
    assert h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_ALL) == before
    np.testing.assert_array_equal(io.read(path)["acc"].values, x)     # strong again


def test_a_byte_range_that_reads_short_is_read_again_by_hdf5(tmp_path, monkeypatch):
    """A piece that comes back short (the file shrank under the reader) is not taken: HDF5
    reads the channel again from the file and reports what it finds there (here, the same
    intact file: the samples, scanned afterwards by the record checks)."""
    path, x = _file(tmp_path)
    real = _h5raw.positioned_reader

    def short(fd):
        pread = real(fd)
        return lambda buffer, offset: pread(buffer[:-4], offset)

    monkeypatch.setattr(_h5raw, "positioned_reader", short)
    np.testing.assert_array_equal(io.read(path)["acc"].values, x)


def test_without_positioned_reads_the_reader_opens_the_file_itself(tmp_path, monkeypatch):
    """Where ``os.preadv`` is missing, HDF5's descriptor is not shared (a seek would move its
    position): the reader opens the file itself and reads by seek and ``readinto``."""
    path, x = _file(tmp_path)
    monkeypatch.delattr("os.preadv")
    with h5py.File(path, "r") as f:
        assert _h5raw.vfd_dup(f.id) is None
    got = io.read(path)
    np.testing.assert_array_equal(got["acc"].values, x)
