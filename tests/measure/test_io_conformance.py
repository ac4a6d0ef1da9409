"""One conformance test run on every reader/writer: write -> read gives the same Record.

"Same" means: identical samples within the format's stated precision, same units, quantities,
sample rates, dims (mixed clocks never resampled), pulse attrs, start time and record attrs.
"""

import hashlib

import numpy as np
import pytest

from crankbench.measure import io
from crankbench.measure.record import make_record

#: extension -> (relative precision of samples, relative precision of times)
FORMATS = {
    ".h5": (0.0, 0.0),
    ".hdf5": (0.0, 0.0),
    ".nc": (0.0, 0.0),
    ".csv": (0.0, 0.0),
    ".mf4": (0.0, 0.0),
    ".tdms": (0.0, 0.0),
    ".uff": (0.0, 0.0),
    ".wav": (0.0, 0.0),
}


def bench_record(*, dtype=np.float32):
    """A small I4-like record: fast accelerometer, slow speed channel, 60-2 tacho edges."""
    rng = np.random.default_rng(42)
    fs = 2000.0
    n = 4000
    t = np.arange(n) / fs
    acc = (3.0 * np.sin(2 * np.pi * 80 * t) + rng.normal(0, 0.1, n)).astype(dtype)
    speed_rpm = np.linspace(1500.0, 3000.0, 40)
    edges = np.cumsum(rng.uniform(5e-4, 7e-4, 300))
    return make_record({
        "acc_block_z": dict(data=acc, sample_rate=fs, units="g", location="block",
                            direction="z", sensitivity=100.0, sensitivity_units="mV/g"),
        "vel_bearing": dict(data=(acc * 0.5).astype(dtype), sample_rate=fs, units="mm/s"),
        "speed": dict(data=speed_rpm, sample_rate=20.0, units="rpm"),
        "tacho": dict(data=edges, units="s", quantity="pulse_times", pulses_per_rev=60,
                      missing_teeth=2),
    }, start_time="2026-03-04T05:06:07.250000+00:00", attrs={"engine_id": "I4-1.6",
                                                           "test_id": "runup-01"})


@pytest.fixture(params=sorted(FORMATS))
def ext(request):
    return request.param


def test_round_trip(ext, tmp_path):
    rec = bench_record()
    path = tmp_path / f"record{ext}"
    io.write(rec, path)
    back = io.read(path)
    sample_rtol, time_rtol = FORMATS[ext]
    assert list(back.data_vars) == list(rec.data_vars)
    for name, var in rec.data_vars.items():
        got = back[name]
        assert got.dims == var.dims, name
        np.testing.assert_allclose(got.values, var.values, rtol=sample_rtol, atol=0,
                                   err_msg=f"{ext} {name}")
        for key in ("units", "quantity", "sample_rate", "location", "direction",
                    "pulses_per_rev", "missing_teeth", "sensitivity_units"):
            assert got.attrs.get(key) == var.attrs.get(key), (ext, name, key)
        if "sensitivity" in var.attrs:
            assert got.attrs["sensitivity"] == pytest.approx(var.attrs["sensitivity"], rel=1e-12)
    for dim in ("time", "time_speed"):
        np.testing.assert_allclose(back[dim].values, rec[dim].values, rtol=time_rtol,
                                   atol=time_rtol)
    assert back.attrs["start_time"] == rec.attrs["start_time"]
    assert back.attrs["engine_id"] == "I4-1.6" and back.attrs["test_id"] == "runup-01"
    assert back.attrs["source"] == path.name and "sha256" not in back.attrs  # hashed on demand
    assert io.source_sha256(back) == hashlib.sha256(path.read_bytes()).hexdigest()


def test_float64_round_trip(ext, tmp_path):
    rec = bench_record(dtype=np.float64)
    path = tmp_path / f"record{ext}"
    io.write(rec, path)
    back = io.read(path, channels=["acc_block_z"])
    assert list(back.data_vars) == ["acc_block_z"]
    np.testing.assert_array_equal(back["acc_block_z"].values, rec["acc_block_z"].values)


def test_open_streams_same_values(ext, tmp_path):
    rec = bench_record()
    path = tmp_path / f"record{ext}"
    io.write(rec, path)
    lazy = io.open(path, chunk_seconds=0.5)
    assert lazy["acc_block_z"].chunks is not None
    blocks = list(io.iter_blocks(lazy, "acc_block_z"))
    assert len(blocks) == 4 and blocks[1][0] == pytest.approx(0.5)
    np.testing.assert_array_equal(np.concatenate([b for _, b in blocks]),
                                  rec["acc_block_z"].values)
    np.testing.assert_array_equal(lazy["speed"].values, rec["speed"].values)


def test_write_refuses_overwrite_and_input_untouched(ext, tmp_path):
    rec = bench_record()
    path = tmp_path / f"record{ext}"
    io.write(rec, path)
    before = path.read_bytes()
    with pytest.raises(FileExistsError, match=r"record.* exists; pass overwrite=True"):
        io.write(rec, path)
    io.read(path)
    assert path.read_bytes() == before
    io.write(rec, path, overwrite=True)
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".part")]
