"""The record digest (measure.provenance): computed when provenance is written, never for a
file that changed after it was read.

The reference digest is ``hashlib.sha256`` of the file's bytes read here independently.
"""

import hashlib
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from crankbench.measure import io, provenance
from crankbench.measure.record import make_record
from crankbench.predict.errors import RecordError

ROOT = Path(__file__).resolve().parents[2]
RECORD = ROOT / "sample_data" / "records" / "i4_runup.h5"
ENGINE = ROOT / "sample_data" / "engines" / "i4.toml"


def _sha(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@pytest.fixture
def record_file(tmp_path):
    rec = make_record({"acc": dict(data=np.sin(np.arange(4096) / 7.0), sample_rate=2048.0,
                                   units="m/s^2", quantity="acceleration")})
    path = tmp_path / "bench.h5"
    io.write(rec, path)
    return path


@pytest.fixture
def no_cache(monkeypatch):
    monkeypatch.setattr(provenance, "_HASH_CACHE", {})


def _forbid_hashing(monkeypatch):
    def refuse(path):
        raise AssertionError(f"{path} hashed at read time")
    monkeypatch.setattr(provenance, "_hash_file", refuse)


@pytest.mark.parametrize("ext", [".h5", ".nc", ".tdms", ".wav", ".csv"])
def test_read_does_not_hash_and_the_digest_is_the_files(tmp_path, ext, monkeypatch, no_cache):
    rec = make_record({"acc": dict(data=np.linspace(-1.0, 1.0, 512), sample_rate=1000.0,
                                   units="m/s^2", quantity="acceleration")})
    path = tmp_path / f"r{ext}"
    io.write(rec, path)
    with monkeypatch.context() as m:
        _forbid_hashing(m)
        back = io.read(path)
        lazy = io.open(path)
    stat = json.loads(back.attrs["source_stat"])
    st = path.stat()
    assert stat == {"path": str(path.resolve()), "size": st.st_size,
                    "mtime_ns": st.st_mtime_ns, "inode": st.st_ino, "device": st.st_dev}
    assert back.attrs["source"] == path.name and "sha256" not in back.attrs
    assert io.source_sha256(back) == io.source_sha256(lazy) == _sha(path)


def test_a_file_modified_after_the_read_is_refused_by_name(record_file, no_cache):
    rec = io.read(record_file)
    with record_file.open("ab") as f:  # e.g. an acquisition still appending to it
        f.write(b"\0" * 16)
    with pytest.raises(RecordError, match=r"bench\.h5 changed since the record was read "
                                          r"\(size \d+ -> \d+ bytes"):
        io.source_sha256(rec)


def test_a_same_size_rewrite_is_caught_by_its_modification_time(record_file, no_cache):
    rec = io.read(record_file)
    st = record_file.stat()
    data = bytearray(record_file.read_bytes())
    data[-1] ^= 0xFF
    with record_file.open("r+b") as f:  # in place: same inode, same size
        f.write(data)
    os.utime(record_file, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
    with pytest.raises(RecordError, match=r"modification time \d+ -> \d+ ns"):
        io.source_sha256(rec)


def test_a_file_replaced_or_removed_after_the_read_is_refused(record_file, tmp_path,
                                                                no_cache):
    rec = io.read(record_file)
    other = tmp_path / "other.h5"
    shutil.copy2(record_file, other)  # same bytes, same size, same mtime: another inode
    os.replace(other, record_file)
    with pytest.raises(RecordError, match="now names another file"):
        io.source_sha256(rec)
    rec = io.read(record_file)
    record_file.unlink()
    with pytest.raises(RecordError, match=r"bench\.h5 was removed or renamed since the record "
                                          "was read"):
        io.source_sha256(rec)


def test_a_change_while_hashing_is_caught(record_file, monkeypatch, no_cache):
    rec = io.read(record_file)
    real = provenance._hash_file

    def hash_then_touch(path):
        digest = real(path)
        with open(path, "ab") as f:
            f.write(b"late")
        return digest
    monkeypatch.setattr(provenance, "_hash_file", hash_then_touch)
    with pytest.raises(RecordError, match="changed while its SHA-256 was computed"):
        io.source_sha256(rec)


def test_records_without_a_file_and_explicit_digests():
    rec = make_record({"a": dict(data=np.ones(4), sample_rate=1.0, units="m")})
    assert io.source_sha256(rec, missing="") == ""
    with pytest.raises(RecordError, match="not read from a file"):
        io.source_sha256(rec)
    assert io.source_sha256(rec.assign_attrs(sha256="ab" * 32)) == "ab" * 32
    with pytest.raises(RecordError, match="is not a file identity"):
        io.source_sha256(rec.assign_attrs(source_stat="{}"))


def test_a_written_record_names_its_new_file_not_the_one_read(record_file, tmp_path,
                                                               no_cache):
    rec = io.read(record_file)
    out = tmp_path / "copy.h5"
    io.write(rec.assign_attrs(sha256=_sha(record_file)), out)  # a stale digest in the attrs
    back = io.read(out)
    assert back.attrs["source"] == "copy.h5" and "sha256" not in back.attrs
    assert json.loads(back.attrs["source_stat"])["path"] == str(out.resolve())
    assert io.source_sha256(back) == _sha(out) != _sha(record_file)


def test_the_report_digest_is_checked_where_it_is_written(tmp_path, no_cache):
    """The analysis result a report/campaign row carries hashes the file at analysis time;
    a record file rewritten between the read and the report is refused, naming it."""
    from crankbench.analysis.vibrograph import compare_vibrograph

    path = tmp_path / "run.h5"
    shutil.copy(RECORD, path)
    rec = io.read(path, channels=["acc_block_z", "speed", "tacho"])
    res = compare_vibrograph(rec, ENGINE)
    assert res.record_sha256 == _sha(RECORD)
    with path.open("ab") as f:
        f.write(b"\0")
    with pytest.raises(RecordError, match=r"run\.h5 changed since the record was read"):
        compare_vibrograph(rec, ENGINE)


def test_a_virtual_dataset_is_refused_in_the_single_open(record_file, tmp_path):
    """The external-data check runs inside the read's own open: a channel turned into a
    virtual dataset reading another file is refused (its bytes are not this record's)."""
    import h5py

    other = tmp_path / "elsewhere.h5"
    with h5py.File(other, "w") as f:
        f["x"] = np.zeros(4096)
    with h5py.File(record_file, "a") as f:
        attrs = dict(f["channels/acc"].attrs)
        del f["channels/acc"]
        layout = h5py.VirtualLayout(shape=(4096,), dtype="f8")
        layout[:] = h5py.VirtualSource(str(other), "x", shape=(4096,))
        f["channels"].create_virtual_dataset("acc", layout)
        f["channels/acc"].attrs.update(attrs)
    with pytest.raises(RecordError, match=r"'channels/acc' is a virtual dataset reading "
                                          r".*elsewhere\.h5; a record must hold its own data"):
        io.read(record_file)
