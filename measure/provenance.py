"""Provenance of a Record: the SHA-256 of the file it was read from, computed when needed.

Hashing a file costs more than reading it (SHA-256 runs at about 1.8 GB/s with the CPU's SHA
instructions; a page-cached HDF5 record reads at 4-9 GB/s), and most reads never need the
digest: only what writes provenance (the analysis results a report or the campaign store
carries, ``crankbench info``, exports) does. So :func:`measure.io.read` does not hash: it
stamps the record with the file's identity at read time -- resolved path, size, modification
time (ns), inode and device -- in the attr ``source_stat``, and :func:`source_sha256` hashes
the file later, after checking that identity still holds. A file changed, replaced, moved or
removed since it was read is refused by a :class:`RecordError` naming the file and what
changed, instead of stamping the record with the digest of bytes it was not read from.

Limits, stated: the check is the same one ``make`` and rsync use (size + mtime_ns + inode),
so a same-size rewrite within the file system's timestamp granularity (a few ms on ext4 with a
coarse clock) that also keeps the inode is not seen. The file is stat-ed again after hashing,
so a change while hashing is caught.

Digests are cached per (path, size, mtime_ns, inode): a file hashed once in a process is not
hashed again while unchanged.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from crankbench.predict.errors import RecordError

__all__ = ["sha256_of", "source_sha256", "stamp_source", "STAT_ATTR"]

#: Dataset attr holding the source file's identity at read time (JSON text)
STAT_ATTR = "source_stat"
#: attrs that describe one particular source file: never taken over from a file's own attrs
#: (a record written out and read back names the new file, not the one it came from)
SOURCE_ATTRS = ("source", "sha256", STAT_ATTR)

_HASH_CACHE: dict[tuple, str] = {}
_FIELDS = ("size", "mtime_ns", "inode", "device")


def _identity(st: os.stat_result) -> dict:
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns, "inode": st.st_ino,
            "device": st.st_dev}


def _hash_file(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb", buffering=0) as f:
        buf = bytearray(1 << 20)
        view = memoryview(buf)
        while n := f.readinto(buf):
            h.update(view[:n])
    return h.hexdigest()


def sha256_of(path) -> str:
    """SHA-256 hex digest of a file (cached per path, size, mtime and inode).

    Parameters
    ----------
    path : path-like
        The file.

    Returns
    -------
    str
        64 lower-case hex digits.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.bin"
    >>> _ = p.write_bytes(b"abc")
    >>> sha256_of(p)[:16]
    'ba7816bf8f01cfea'
    """
    path = Path(path).resolve()
    st = path.stat()
    key = (str(path), st.st_size, st.st_mtime_ns, st.st_ino)
    if key not in _HASH_CACHE:
        digest = _hash_file(path)
        if _identity(path.stat()) != _identity(st):  # written to while we hashed it
            raise RecordError(f"{path}: the file changed while its SHA-256 was computed; "
                              "expected a file nobody is writing to")
        _HASH_CACHE[key] = digest
    return _HASH_CACHE[key]


def stamp_source(attrs: dict, path, st: os.stat_result | None = None) -> dict:
    """Record in ``attrs`` which file a record was read from and that file's identity now.

    Sets ``source`` (file name) and ``source_stat`` (JSON: resolved path, size in bytes,
    mtime in ns, inode, device) and drops any ``sha256`` the attrs carried (it described
    another file). No byte of the file is read.

    Parameters
    ----------
    attrs : dict
        The record's attrs, updated in place.
    path : path-like
        The file read.
    st : os.stat_result, optional
        Its stat taken when it was opened (default: now).

    Returns
    -------
    dict
        ``attrs``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.bin"
    >>> _ = p.write_bytes(b"abc")
    >>> a = stamp_source({"sha256": "stale"}, p)
    >>> print(a["source"], "sha256" in a, json.loads(a["source_stat"])["size"])
    x.bin False 3
    """
    real = os.path.realpath(path)  # what Path.resolve() gives, without its extra stat
    st = os.stat(real) if st is None else st
    attrs.pop("sha256", None)
    attrs["source"] = os.path.basename(real)
    attrs[STAT_ATTR] = json.dumps({"path": real, **_identity(st)})
    return attrs


def source_sha256(record, *, missing: str | None = None) -> str:
    """SHA-256 of the file ``record`` was read from, checked to be the file as it was read.

    Parameters
    ----------
    record : xarray.Dataset
        A Record from :func:`measure.io.read` / :func:`measure.io.open` (attr ``source_stat``),
        or one carrying an explicit ``sha256`` attr (returned as it is).
    missing : str, optional
        Returned for a record with neither attr (built in memory, never read from a file);
        default None raises.

    Returns
    -------
    str
        64 hex digits.

    Raises
    ------
    RecordError
        The source file was changed, replaced or removed since the record was read (the
        message names the file and what differs), or the record has no source and
        ``missing`` is None.

    Examples
    --------
    >>> import tempfile, pathlib, hashlib
    >>> import numpy as np
    >>> from crankbench.measure import io
    >>> from crankbench.measure.record import make_record
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.h5"
    >>> io.write(make_record({"a": dict(data=np.ones(8), sample_rate=1e3, units="m")}), p)
    >>> rec = io.read(p)
    >>> source_sha256(rec) == hashlib.sha256(p.read_bytes()).hexdigest()
    True
    >>> _ = p.write_bytes(b"other bytes")      # the file changes after the read
    >>> source_sha256(rec)
    Traceback (most recent call last):
    ...
    crankbench.predict.errors.RecordError: ...r.h5 changed since the record was read (size ... -> 11 bytes...
    """
    attrs = record.attrs
    text = attrs.get(STAT_ATTR)
    if text is None:
        if attrs.get("sha256"):
            return str(attrs["sha256"])
        if missing is not None:
            return missing
        raise RecordError("the record was not read from a file (no source_stat or sha256 "
                          "attr); expected a record from measure.io.read or measure.io.open")
    try:
        then = json.loads(text)
        path = Path(then["path"])
        then = {k: int(then[k]) for k in _FIELDS}
    except (ValueError, KeyError, TypeError):
        raise RecordError(f"record attr {STAT_ATTR}={text!r} is not a file identity; expected "
                          "the JSON written by measure.io.read") from None
    try:
        now = _identity(path.stat())
    except FileNotFoundError:
        raise RecordError(f"{path} was removed or renamed since the record was read; its "
                          "SHA-256 cannot be attested -- read the file again") from None
    if now != then:
        raise RecordError(f"{path} changed since the record was read ({_changes(then, now)}); "
                          "its SHA-256 would not describe the data in memory -- read the "
                          "file again")
    key = (str(path), then["size"], then["mtime_ns"], then["inode"])
    if key not in _HASH_CACHE:
        sha256_of(path)
        if key not in _HASH_CACHE:  # changed between our stat and the hash
            raise RecordError(f"{path} changed since the record was read; read it again")
    return _HASH_CACHE[key]


def _changes(then: dict, now: dict) -> str:
    words = {"size": ("size", " bytes"), "mtime_ns": ("modification time", " ns"),
             "inode": ("inode", ""), "device": ("device", "")}
    parts = [f"{words[k][0]} {then[k]} -> {now[k]}{words[k][1]}" for k in _FIELDS
             if then[k] != now[k]]
    if then["inode"] != now["inode"]:
        parts.append("the path now names another file")
    return ", ".join(parts)
