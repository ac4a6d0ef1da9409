"""Byte-level fuzzing of the readers: a damaged file gives a RecordError or a valid Record.

Small valid records are written in every format, then damaged by hypothesis — truncated, bits
flipped, a run of bytes overwritten. ``measure.read`` must either return a Record that passes the
schema (no NaN slipped through) or raise an error of the project's family naming the file; never
another exception, never a hang (each read runs under a 20 s alarm).
"""

from __future__ import annotations


import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from crankbench.measure import io as mio
from crankbench.measure.readers import hdf5
from crankbench.measure.record import make_record, validate
from hang_guard import time_limit
from crankbench.predict.errors import CrankbenchError

FORMATS = [".h5", ".nc", ".csv", ".tdms", ".mf4", ".wav", ".uff"]
FUZZ = settings(max_examples=10, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])




@pytest.fixture(scope="module")
def valid_files(tmp_path_factory):
    """One small record per format: two channels on the main clock, a tacho pulse-time
    channel and a channel on a second clock; returns {ext: bytes} (and the WAV sidecar)."""
    folder = tmp_path_factory.mktemp("fuzz_valid")
    fs, n = 1000.0, 200
    t = np.arange(n) / fs
    rec = make_record({
        "acc": dict(data=np.sin(2 * np.pi * 30 * t), sample_rate=fs, units="m/s^2",
                    quantity="acceleration"),
        "disp": dict(data=1e-4 * np.cos(2 * np.pi * 30 * t), sample_rate=fs, units="m",
                     quantity="displacement"),
        "tacho": dict(data=np.arange(0.0, 0.2, 0.004), quantity="pulse_times", units="s",
                      pulses_per_rev=4),
        "slow": dict(data=np.linspace(0.0, 1e-3, 20), sample_rate=100.0, units="m",
                     quantity="displacement", dim="time_slow"),
    })
    out = {}
    for ext in FORMATS:
        path = folder / f"valid{ext}"
        mio.write(rec, path)
        out[ext] = path.read_bytes()
    out[".wav.json"] = (folder / "valid.wav.json").read_bytes()
    hdf5.write(rec, folder / "valid_v1.h5", _version=1)  # the layout written before 2026-11
    out[".h5 v1"] = (folder / "valid_v1.h5").read_bytes()
    return out


def _check_read(path, expected_name):
    """Read ``path``: a valid Record or one of our errors naming the file."""
    try:
        with time_limit(20, "read"):
            rec = mio.read(path)
    except CrankbenchError as exc:
        assert expected_name in str(exc), f"error does not name the file: {exc}"
        return None
    except FileNotFoundError as exc:  # only for a missing sidecar, which names the file
        assert path.name in str(exc) or ".json" in str(exc), str(exc)
        return None
    validate(rec)
    for name, var in rec.data_vars.items():
        values = np.asarray(var.values)
        assert values.dtype.kind in "fiu", name
        if values.dtype.kind == "f":
            assert np.all(np.isfinite(values)), f"channel {name!r} has NaN/inf without error"
    return rec


def _mutate(data: bytes, op: str, where: float, count: int, value: int) -> bytes:
    n = len(data)
    pos = min(n - 1, int(where * n))
    if op == "truncate":
        return data[:pos]
    buf = bytearray(data)
    if op == "flip":
        rng = np.random.default_rng(value)
        for p in rng.integers(0, n, size=count):
            buf[p] ^= 1 << int(rng.integers(0, 8))
        return bytes(buf)
    if op == "overwrite":
        end = min(n, pos + 4 * count)
        buf[pos:end] = bytes([value % 256]) * (end - pos)
        return bytes(buf)
    # "zero-tail": a logger that pre-allocated the file and crashed
    return data[:pos] + b"\x00" * (n - pos)


mutation = st.tuples(st.sampled_from(["truncate", "flip", "overwrite", "zero-tail"]),
                     st.floats(0.0, 1.0, allow_nan=False), st.integers(1, 16),
                     st.integers(0, 2**16))


@pytest.mark.parametrize("ext", FORMATS)
@FUZZ
@given(m=mutation)
def test_damaged_file_reads_or_raises_our_error(ext, m, valid_files, tmp_path):
    path = tmp_path / f"fuzzed{ext}"
    path.write_bytes(_mutate(valid_files[ext], *m))
    if ext == ".wav":
        path.with_name(path.name + ".json").write_bytes(valid_files[".wav.json"])
    _check_read(path, path.name)


@FUZZ
@given(m=mutation)
def test_damaged_wav_sidecar_reads_or_raises_our_error(m, valid_files, tmp_path):
    path = tmp_path / "fuzzed.wav"
    path.write_bytes(valid_files[".wav"])
    path.with_name("fuzzed.wav.json").write_bytes(_mutate(valid_files[".wav.json"], *m))
    _check_read(path, "fuzzed.wav")


@pytest.mark.parametrize("ext", FORMATS)
def test_every_truncation_point_of_small_file(ext, valid_files, tmp_path):
    """Deterministic sweep: 12 truncation points over the whole file."""
    data = valid_files[ext]
    for k in np.unique(np.linspace(1, len(data) - 1, 12).astype(int)):
        path = tmp_path / f"trunc{k}{ext}"
        path.write_bytes(data[:k])
        if ext == ".wav":
            path.with_name(path.name + ".json").write_bytes(valid_files[".wav.json"])
        _check_read(path, path.name)


def _check_open(path, expected_name):
    """Lazy open of a damaged file, then load every channel: the same contract as read —
    our error naming the file (at open or at load) or valid finite data."""
    try:
        with time_limit(20, "read"):
            rec = mio.open(path, chunk_seconds=0.05)
            rec = rec.load()
    except CrankbenchError as exc:
        assert expected_name in str(exc), f"error does not name the file: {exc}"
        return None
    except FileNotFoundError as exc:
        assert path.name in str(exc) or ".json" in str(exc), str(exc)
        return None
    for name, var in rec.data_vars.items():
        values = np.asarray(var.values)
        if values.dtype.kind == "f":
            assert np.all(np.isfinite(values)), f"channel {name!r} has NaN/inf without error"
    return rec


@pytest.mark.parametrize("ext", [".h5", ".nc", ".tdms", ".wav"])
@FUZZ
@given(m=mutation)
def test_damaged_file_opened_lazily_gives_our_error_or_valid_data(ext, m, valid_files,
                                                                   tmp_path):
    """The streaming readers defer reading samples: damage found at load time must still be
    our error naming the file, not a dask/h5py/npTDMS exception."""
    path = tmp_path / f"lazy{ext}"
    path.write_bytes(_mutate(valid_files[ext], *m))
    if ext == ".wav":
        path.with_name(path.name + ".json").write_bytes(valid_files[".wav.json"])
    _check_open(path, path.name)


def test_lazy_h5_with_zeroed_tail_fails_with_our_error_at_load(valid_files, tmp_path):
    path = tmp_path / "zeroed.h5"
    path.write_bytes(_mutate(valid_files[".h5 v1"], "zero-tail", 0.8632, 3, 1448))
    with pytest.raises(CrankbenchError, match=r"zeroed\.h5"):
        mio.open(path, chunk_seconds=0.05).load()
