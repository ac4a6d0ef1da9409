"""HDF5 layout version 2 (the record's metadata in one JSON attribute) against version 1 (one
attribute per value, as written before 2026-11 and by hand with h5py): both read to the same
Record; attributes set with h5py after writing override the JSON; a damaged JSON or a newer
layout is refused by name; the block extremes taken while reading are the samples' own."""

import json
import os

import h5py
import numpy as np
import pytest
import xarray as xr

from crankbench.measure import io
from crankbench.measure.readers import _h5raw, hdf5
from crankbench.measure.record import _SCAN_BLOCK, clipped_spans, make_record
from crankbench.predict.errors import RecordError

FS = 1000.0


def _rich_record():
    """Every kind of channel and attr a Record holds: two clocks, pulse times, an explicit
    (irregular-free but non-implicit) time axis, array / list / dict / bool / NaN attrs."""
    t = np.arange(400) / FS
    rec = make_record({
        "acc": dict(data=np.sin(2 * np.pi * 30 * t).astype(np.float32), sample_rate=FS,
                    units="m/s^2", quantity="acceleration", location="bearing 2"),
        "disp": dict(data=1e-4 * np.cos(2 * np.pi * 30 * t), sample_rate=FS, units="m",
                     quantity="displacement"),
        "tacho": dict(data=np.arange(0.0, 0.4, 0.004), quantity="pulse_times", units="s",
                      pulses_per_rev=4),
        "slow": dict(data=np.linspace(0.0, 1e-3, 40), sample_rate=100.0, units="m",
                     quantity="displacement", dim="time_slow"),
    }, start_time="2026-01-31T12:00:00+00:00")
    rec.attrs.update(engine_id="E-7", cylinders=6, derated=True, note=None, ratio=np.nan,
                     tags=["run 3", "cold"], setup={"gain": 2.5, "filters": [1, 2]},
                     spans=np.array([0.1, 0.2, 0.35]))
    rec["acc"].attrs["clipped_spans_s"] = np.array([0.01, 0.02])
    return rec


def _attrs_equal(a: dict, b: dict):
    assert sorted(a) == sorted(b)  # v1 lists attributes by name, v2 as written
    for k in a:
        va, vb = a[k], b[k]
        assert type(va) is type(vb), (k, type(va), type(vb))
        if isinstance(va, np.ndarray):
            assert va.dtype == vb.dtype and np.array_equal(va, vb), k
        elif isinstance(va, float) and np.isnan(va):
            assert np.isnan(vb), k
        else:
            assert va == vb, k


def test_version_2_and_version_1_read_to_the_same_record(tmp_path):
    rec = _rich_record()
    new, old = tmp_path / "v2.h5", tmp_path / "v1.h5"
    io.write(rec, new)
    hdf5.write(rec, old, _version=1)
    with h5py.File(new, "r") as f:
        assert f.attrs["crankbench_format_version"] == 2
        assert set(f.attrs) == {"crankbench_format", "crankbench_format_version",
                                "crankbench_meta"}
        assert not f["channels/acc"].attrs and not f["dims/time"].attrs
        meta = json.loads(f.attrs["crankbench_meta"])
        assert meta["dims"]["time"] == {"kind": "regular", "start": 0.0, "sample_rate": FS,
                                        "length": 400}
    with h5py.File(old, "r") as f:
        assert f.attrs["crankbench_format_version"] == 1 and "crankbench_meta" not in f.attrs
        assert f["channels/acc"].attrs["units"] == "m/s^2"
    for lazy in (False, True):
        a = io.open(new) if lazy else io.read(new)
        b = io.open(old) if lazy else io.read(old)
        assert list(a.data_vars) == ["acc", "disp", "tacho", "slow"]
        xr.testing.assert_identical(a.drop_attrs(), b.drop_attrs())
        skip = ("source", "source_stat")
        _attrs_equal({k: v for k, v in a.attrs.items() if k not in skip},
                     {k: v for k, v in b.attrs.items() if k not in skip})
        for name in a.data_vars:
            _attrs_equal(a[name].attrs, b[name].attrs)
    got = io.read(new)
    np.testing.assert_array_equal(got["acc"].values, rec["acc"].values)
    assert got.attrs["setup"] == {"gain": 2.5, "filters": [1, 2]}
    assert got.attrs["tags"] == ["run 3", "cold"] and got.attrs["derated"] is True
    assert got.attrs["spans"].dtype == np.float64


@pytest.mark.parametrize("where, edit, check", [
    ("channels/acc", ("units", "g"),  # a unit fixed by hand: scaled on read
     lambda r, x: np.testing.assert_allclose(r["acc"].values, 9.80665 * x, rtol=1e-6)),
    ("channels/acc", ("location", "bearing 3"),
     lambda r, x: r["acc"].attrs["location"] == "bearing 3" or pytest.fail("not honoured")),
    ("/", ("engine_id", "E-8"),
     lambda r, x: r.attrs["engine_id"] == "E-8" or pytest.fail("not honoured")),
    ("/", ("channel_order", json.dumps(["disp", "acc", "tacho", "slow"])),
     lambda r, x: list(r.data_vars)[:2] == ["disp", "acc"] or pytest.fail("not honoured")),
])
def test_an_attribute_set_by_hand_overrides_the_json(tmp_path, where, edit, check):
    """The JSON is never trusted over what the file's objects say."""
    rec = _rich_record()
    path = tmp_path / "r.h5"
    io.write(rec, path)
    with h5py.File(path, "r+") as f:
        f[where].attrs[edit[0]] = edit[1]
    check(io.read(path), rec["acc"].values.astype(np.float64))


def test_a_dim_edited_by_hand_is_checked(tmp_path):
    path = tmp_path / "r.h5"
    io.write(_rich_record(), path)
    with h5py.File(path, "r+") as f:
        f["dims/time"].attrs["length"] = 401
    with pytest.raises(RecordError, match=r"r\.h5: channel 'acc' has 400 samples but its dim "
                                          r"'time' declares 401"):
        io.read(path)
    with h5py.File(path, "r+") as f:
        f["dims/time"].attrs["length"] = 400
        f["dims/time"].attrs["sample_rate"] = 0.0
    with pytest.raises(RecordError, match=r"r\.h5: dim 'time' declares sample_rate=0\.0 Hz"):
        io.read(path)


@pytest.mark.parametrize("text, match", [
    ("{not json", r"root attribute 'crankbench_meta' is not the JSON object"),
    (json.dumps({"attrs": {}}), r"root attribute 'crankbench_meta' is not the JSON object"),
    (json.dumps([1, 2]), r"root attribute 'crankbench_meta' is not the JSON object"),
])
def test_a_damaged_json_is_refused_by_name(tmp_path, text, match):
    path = tmp_path / "r.h5"
    io.write(_rich_record(), path)
    with h5py.File(path, "r+") as f:
        f.attrs.modify("crankbench_meta", text)
    with pytest.raises(RecordError, match=r"r\.h5: " + match):
        io.read(path)


def test_a_newer_layout_is_refused_by_name(tmp_path):
    path = tmp_path / "r.h5"
    io.write(_rich_record(), path)
    with h5py.File(path, "r+") as f:
        f.attrs.modify("crankbench_format_version", 3)
    with pytest.raises(RecordError, match=r"r\.h5: layout version 3 is not one this "
                                          r"crankbench reads \(1\.\.2\); upgrade"):
        io.read(path)


@pytest.mark.parametrize("storage", [
    {},                                        # contiguous: one run
    {"chunks": (50_000,)},                     # chunks not on block edges
    {"chunks": (_SCAN_BLOCK,)},                # chunks on block edges
])
@pytest.mark.parametrize("piece_bytes", [None, 400_012])  # pieces across block edges
def test_block_extremes_taken_while_reading_are_the_samples_own(tmp_path, storage,
                                                                piece_bytes, monkeypatch):
    """Per-block min/max from the read equal numpy's over the samples, NaN and inf
    included, also where a block spans chunks read by separate runs or pieces."""
    if piece_bytes:
        monkeypatch.setattr(_h5raw, "_PIECE_BYTES", piece_bytes)
    n = 3 * _SCAN_BLOCK + 12_345
    x = np.random.default_rng(5).standard_normal(n).astype(np.float32)
    x[_SCAN_BLOCK + 7] = np.nan
    x[2 * _SCAN_BLOCK + 1] = np.inf
    path = tmp_path / "x.h5"
    with h5py.File(path, "w") as f:
        if storage:  # chunks written in reverse: file order differs from sample order
            ds = f.create_dataset("x", shape=(n,), dtype=np.float32, **storage)
            c = storage["chunks"][0]
            for a in range(-(-n // c) * c - c, -1, -c):
                ds[a:a + c] = x[a:a + c]
        else:
            f.create_dataset("x", data=x)
    with h5py.File(path, "r") as f:
        runs = _h5raw.raw_runs(f["x"])
        assert runs is not None and (len(runs) > 1) == bool(storage)
        got, runs = _h5raw.prepare(f["x"].id, (n,))
        fd = os.open(path, os.O_RDONLY)
        try:
            lows, highs = _h5raw.read_runs(_h5raw.positioned_reader(fd), runs, got, _SCAN_BLOCK)
        finally:
            os.close(fd)
    np.testing.assert_array_equal(got, x)
    blocks = [x[a:a + _SCAN_BLOCK] for a in range(0, n, _SCAN_BLOCK)]
    np.testing.assert_array_equal(lows, [b.min() for b in blocks])
    np.testing.assert_array_equal(highs, [b.max() for b in blocks])
    assert np.isnan(lows[1]) and np.isnan(highs[1]) and highs[2] == np.inf


@pytest.mark.parametrize("units", [None, "g"])
def test_read_finds_nonfinite_and_clipping_from_the_read_scan(tmp_path, units):
    """Clipped and NaN samples are found the same whether the scan came with the read (SI
    units: samples untouched) or after it (units scaled on read: scanned again)."""
    n = max(2 * _SCAN_BLOCK, 250_000) + 999  # several blocks, runs in different ones
    x = (0.3 * np.random.default_rng(2).standard_normal(n)).astype(np.float32)
    hi = np.float32(1.0)
    for a in (1000, 90_000, 200_000):  # flat runs at the amplifier limit
        x[a - 1] = 0.0
        x[a:a + 5] = hi
    x = np.clip(x, -2.0, hi)
    rec = make_record({"acc": dict(data=x, sample_rate=FS, units="m/s^2",
                                   quantity="acceleration")})
    path = tmp_path / "c.h5"
    io.write(rec, path)
    if units:  # the file says g: scaled to m/s^2 on read, after the read's scan
        with h5py.File(path, "r+") as f:
            f["channels/acc"].attrs["units"] = units
    with pytest.warns(Warning, match="looks clipped"):
        got = io.read(path)
    np.testing.assert_allclose(got["acc"].values, x * (9.80665 if units else 1.0), rtol=1e-6)
    expect = clipped_spans(got["acc"].values)
    assert [a for a, _ in expect] == [1000, 90_000, 200_000]
    t = np.array([[a, b - 1] for a, b in expect]).ravel() / FS
    np.testing.assert_allclose(got["acc"].attrs["clipped_spans_s"], t)
    x[150_000] = np.nan
    with h5py.File(path, "r+") as f:
        f["channels/acc"][150_000] = np.nan
    with pytest.raises(RecordError, match=r"c\.h5.*channel 'acc' has 1 NaN/inf sample\(s\) "
                                          r"in 1 run\(s\): samples 150000\.\.150000"):
        io.read(path)


def test_links_on_the_read_path_are_checked(tmp_path):
    """A soft link within the file reads; an external link where the read goes is refused by
    name (the whole file is then checked), one elsewhere is never followed."""
    rec = _rich_record()
    path = tmp_path / "r.h5"
    io.write(rec, path)
    with h5py.File(path, "r+") as f:
        f["notes"] = h5py.ExternalLink("elsewhere.h5", "/notes")  # not part of the record
    np.testing.assert_array_equal(io.read(path)["acc"].values, rec["acc"].values)
    with h5py.File(path, "r+") as f:
        del f["notes"]
        f.move("channels/acc", "stored_acc")
        f["channels/acc"] = h5py.SoftLink("/stored_acc")
    np.testing.assert_array_equal(io.read(path)["acc"].values, rec["acc"].values)
    with h5py.File(path, "r+") as f:
        f.move("dims/time_slow", "stored_dim")
        f["dims/time_slow"] = h5py.ExternalLink("elsewhere.h5", "/dims/time_slow")
    with pytest.raises(RecordError, match=r"r\.h5: HDF5 object 'dims/time_slow' is an "
                                          r"external link to elsewhere\.h5:/dims/time_slow"):
        io.read(path)
