"""Read throughput per record format against ``numpy.fromfile`` of the raw bytes.

One float32 accelerometer channel (51.2 kHz, white noise) is written in every format, and the
same samples as a headerless raw file. Every read of a size is timed in interleaved rounds
with ``numpy.fromfile`` of the raw file (:func:`analysis.bench.compare`, process CPU time,
files in the page cache), so ``ratio`` is the paired cost relative to the fastest possible
read (``1 / ratio`` is the fraction of raw throughput reached; the issue-21 target for HDF5 is
>= 0.6). ``error`` is the largest absolute difference between the samples read and the samples
written (all formats store float32 or wider, so the bound is 0: exact).

Rows per format: the format reader (parse, SI conversion, time coordinate) and, for the native
HDF5 layout, also h5py alone -- the floor of this format through its library: ``h5py
open + attributes`` (open the file, read the root's attributes, among them the record's
metadata as one JSON text (layout version 2), parse it, close; no sample), ``h5py open + read_direct`` (the samples only,
read by HDF5 into a preallocated array) and both together (all a record needs from the file,
with a paired ``speed`` row: the part of ``measure.read``'s time that is HDF5's) --, ``measure.read`` of a file read before
(validation, NaN/inf and clipping scan), ``measure.read`` of a file seen for the first time (a
freshly written copy of the same bytes each round, so no per-file state of the process is
reused; both it and the raw file are in the page cache, the same cache state for both sides),
``measure.read`` plus the SHA-256 of the file as provenance needs it
(:func:`measure.provenance.source_sha256` with its cache cleared: the cost a report or the
campaign store pays once per record; SHA-256 runs at about 1.8 GB/s, so this row cannot beat
0.4x raw and says so) and streaming through ``measure.open`` block by block.

The HDF5 target rows are measured twice. In this process both sides write into memory the
allocator hands back warm (glibc keeps a freed 20 MB block and reuses it: no page is faulted
in, the best case for ``numpy.fromfile``, whose whole cost is then the copy). The rows marked
``fresh output pages`` repeat the pairing in a child process where every array of 1 MB or more
is its own mapping, returned to the system when freed (glibc ``MALLOC_MMAP_THRESHOLD_``), so
both sides' output starts as untouched pages -- as for a process reading a record for the
first time, and for any array above glibc's 32 MB reuse limit (the 50 M rows).

Sizes: quick 5 M
samples, full 50 M (HDF5 also at 5 M and 0.5 M, where the fixed per-file cost decides the
ratio); the text and UFF formats (pure-Python parsers) use a tenth of that, and so does MDF4
in quick mode, as the ``setting`` column says. Everything runs on one thread (h5py, numpy and the
page-cache copy of ``numpy.fromfile`` alike).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import numpy as np

from . import Row, compare

SUITE = "io"
FS = 51_200.0
#: formats whose writer/reader is too slow for the full size run at 1/10 of it
SLOW = {".csv": 10, ".uff": 10}
#: ... and in quick mode (< 20 s in all) also MDF4, whose writer takes ~1 s per M samples
SLOW_QUICK = {**SLOW, ".mf4": 10}

#: the HDF5 target pairing run in a child process whose output arrays start as fresh pages
_FRESH_CHILD = r"""
import json, sys
import numpy as np
from crankbench.analysis._kernels import accelerated
from crankbench.analysis.bench import compare
from crankbench.measure import io

accelerated()  # numba loaded, as in the parent bench (the compiled scan of measure.scan)
path, raw, rounds, copies = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
at = [0]

def first():
    at[0] = (at[0] + 1) % len(copies)
    return io.read(copies[at[0]])["acc"].values

t = compare({"raw": lambda: np.fromfile(raw, dtype=np.float32),
             "again": lambda: io.read(path)["acc"].values, "first": first},
            rounds=rounds, min_time=0.0)
print(json.dumps({k: {n: np.asarray(v).tolist() for n, v in getattr(t, k).items()}
                  for k in ("cpu", "wall", "loops")}))
"""


def _fresh_pages_timing(path, raw, rounds, copies):
    """:class:`Timing` of ``raw``/``again``/``first`` (as in :func:`run`) measured in a child
    process where glibc maps every allocation of 1 MB or more afresh (None where the child
    fails: not glibc, or no subprocess)."""
    import os
    import subprocess
    import sys

    from . import Timing

    env = dict(os.environ, MALLOC_MMAP_THRESHOLD_=str(1 << 20), OMP_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1")
    try:
        out = subprocess.run([sys.executable, "-c", _FRESH_CHILD, str(path), str(raw),
                              str(rounds), *map(str, copies)], env=env, capture_output=True,
                             text=True, timeout=600, check=True)
        got = json.loads(out.stdout.strip().splitlines()[-1])
    except (OSError, subprocess.SubprocessError, ValueError, IndexError):
        return None
    return Timing(cpu={k: np.asarray(v) for k, v in got["cpu"].items()},
                  wall={k: np.asarray(v) for k, v in got["wall"].items()},
                  loops={k: int(v) for k, v in got["loops"].items()})


def _record(n: int):
    from crankbench.measure.record import make_record

    x = np.random.default_rng(0).standard_normal(n, dtype=np.float32)
    return make_record({"acc": dict(data=x, sample_rate=FS, units="m/s^2",
                                    quantity="acceleration")}), x


def run(quick: bool) -> list[Row]:
    from crankbench.measure import io
    from crankbench.measure.readers import module_for

    n_full = 5_000_000 if quick else 50_000_000
    repeats = 3 if quick else 5
    slow = SLOW_QUICK if quick else SLOW
    rows: list[Row] = []
    tmp = Path(tempfile.mkdtemp(prefix="crankbench-bench-io-"))
    # HDF5 (the issue-21 rows) also at 5 M in the full run; at 5 M a read lasts ~5 ms, so
    # more rounds cost little and steady the median
    runs = [(".h5", n_full, 9 if quick else repeats)]
    runs += [] if quick else [(".h5", n_full // 10, 9), (".h5", n_full // 100, 15)]
    runs += [(ext, n_full // slow.get(ext, 1), repeats)
             for ext in (".nc", ".tdms", ".wav", ".mf4", ".uff", ".csv")]
    try:
        records = {n: _record(n) for n in sorted({n for _, n, _ in runs})}
        raw_files = {}
        for n, (_, x) in records.items():
            raw_files[n] = tmp / f"raw_{n}.f32"
            x.tofile(raw_files[n])

        for ext, n, rounds in runs:
            rec, x = records[n]
            path = tmp / f"record{ext}"
            io.write(rec, path)
            module = module_for(path)
            setting = f"n={n:.3g}"
            raw = raw_files[n]
            cands = {"raw": lambda raw=raw: np.fromfile(raw, dtype=np.float32),
                     "reader": lambda m=module, p=path: m.read(p)["acc"].values}
            labels = {"reader": (f"reader {ext}",
                                 f"{path.stat().st_size / 1e6:.0f} MB file")}
            if ext == ".h5":
                import h5py

                def storage(p=path):
                    with h5py.File(p, "r") as f:
                        d = f["channels/acc"]
                        out = np.empty(d.shape, d.dtype)
                        d.read_direct(out)
                        return out

                def metadata(p=path):
                    with h5py.File(p, "r") as f:
                        root = dict(f.attrs)
                        meta = json.loads(root["crankbench_meta"])  # layout version 2
                    return [root, meta["dims"]["time"], meta["channels"]["acc"]]

                def floor(p=path):  # what a record needs from the file, through h5py
                    with h5py.File(p, "r") as f:
                        json.loads(f.attrs["crankbench_meta"])
                        d = f["channels/acc"]
                        out = np.empty(d.shape, d.dtype)
                        d.read_direct(out)
                        return out

                def again(p=path):
                    return io.read(p)["acc"].values

                fresh = [0]

                def first(p=path):
                    # each call reads the next copy made below: same bytes, a file this
                    # process never read, in the page cache like the raw file
                    fresh[0] = (fresh[0] + 1) % len(copies)
                    return io.read(copies[fresh[0]])["acc"].values

                def provenance(p=path):
                    from crankbench.measure import provenance as prov

                    prov._HASH_CACHE.clear()
                    rec = io.read(p)
                    prov.source_sha256(rec)
                    return rec["acc"].values

                def stream(p=path):
                    lazy = io.open(p, chunk_seconds=20.0)
                    return np.concatenate([b for _, b in io.iter_blocks(lazy, "acc")])

                copies = []
                for k in range(rounds + 2):  # warm-up + rounds, each a file never read
                    c = tmp / f"record_copy{k}{ext}"
                    shutil.copyfile(path, c)
                    copies.append(c)
                cands.update(metadata=metadata, storage=storage, floor=floor, again=again,
                             first=first, provenance=provenance, stream=stream)
                labels.update(
                    metadata=("h5py alone: open + attributes, no sample",
                              "the format's fixed cost through h5py; error: sample_rate, Hz"),
                    storage=("h5py alone: open + read_direct", "samples only"),
                    floor=("h5py alone: open + attributes + read_direct",
                           "all a record needs from the file: the format's floor via h5py"),
                    again=("measure.read .h5, file read before", "validate + NaN/clip scan"),
                    first=("measure.read .h5, first read", "a copy never read before; the "
                           "SHA-256 is not computed at read time"),
                    provenance=("measure.read .h5 + SHA-256 for provenance",
                                "source_sha256 uncached: what a report or store pays once"),
                    stream=("measure.open .h5 blocks of 20 s", ""))
            t = compare(cands, rounds=rounds, min_time=0.0)
            for name, (method, note) in labels.items():
                got = cands[name]()
                kind, ref = "max abs", "samples written"
                if name == "metadata":  # no samples: check the clock it read instead
                    error = max(abs(float(a["sample_rate"]) - FS) for a in got[1:])
                    kind, ref = "abs, Hz", "sample_rate written"
                else:
                    error = float(np.max(np.abs(np.asarray(got, dtype=np.float64) - x)))
                rows.append(t.row(SUITE, method, name, ("raw", "numpy.fromfile raw float32"),
                                  setting, error, kind, ref,
                                  throughput_items=n, throughput_unit="samples/s", bound=0.0,
                                  note=note))
            if ext == ".h5":  # issue-21 target rows: time / raw time <= 1 / 0.6
                rows.append(t.row(SUITE, "h5py alone: open + attributes + read_direct speed",
                                  "floor", ("raw", "numpy.fromfile raw float32"), setting,
                                  t.ratio("floor", "raw")[0], "time / raw time (paired)",
                                  "the format's floor through h5py (not a target)",
                                  note="what HDF5 through h5py costs before any of ours"))
                for name in ("first", "again"):
                    rows.append(t.row(SUITE, labels[name][0] + " speed", name,
                                      ("raw", "numpy.fromfile raw float32"), setting,
                                      t.ratio(name, "raw")[0], "time / raw time (paired)",
                                      "issue 21 target: >= 0.6x np.fromfile", bound=1 / 0.6,
                                      note="bound = the target ratio, not an error; output "
                                      "memory reused warm by both sides", target=True))
                fresh = _fresh_pages_timing(path, raw, rounds, copies[:rounds + 2])
                for name in ("first", "again") if fresh is not None else ():
                    rows.append(fresh.row(
                        SUITE, labels[name][0] + ", fresh output pages speed", name,
                        ("raw", "numpy.fromfile raw float32"), setting,
                        fresh.ratio(name, "raw")[0], "time / raw time (paired)",
                        "issue 21 target: >= 0.6x np.fromfile", bound=1 / 0.6,
                        note="child process, MALLOC_MMAP_THRESHOLD_=1 MiB: both sides' "
                        "output starts as fresh pages", target=True))
            path.unlink()
            for c in tmp.glob(f"record_copy*{ext}"):
                c.unlink()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return rows + _scan_rows(n_full, rounds=9)


def _scan_rows(n: int, rounds: int) -> list[Row]:
    """The record checks' scan alone (:class:`measure.scan.BlockExtremes` over ``n`` float32
    samples in memory): numpy's min and max per block against the compiled one-pass fold,
    paired; error: the largest difference from numpy's ``min``/``max`` of each block taken
    separately (exact: 0)."""
    import os

    from crankbench.measure import scan

    x = np.random.default_rng(1).standard_normal(n, dtype=np.float32)
    x[n // 3] = -7.5  # extremes away from the block edges
    x[2 * n // 3 + 5] = 8.25
    rows_ = x[:n - n % scan._SCAN_BLOCK].reshape(-1, scan._SCAN_BLOCK)
    tail = x[rows_.size:]
    want_lo = np.r_[rows_.min(axis=1), [tail.min()] if tail.size else []]
    want_hi = np.r_[rows_.max(axis=1), [tail.max()] if tail.size else []]

    def fold():
        acc = scan.BlockExtremes(x.size, x.dtype)
        acc.fold(x, 0, x.size)
        return acc.result()

    def numpy_form():
        had = os.environ.get("CRANKBENCH_NO_NUMBA")
        os.environ["CRANKBENCH_NO_NUMBA"] = "1"
        try:
            return fold()
        finally:
            if had is None:
                del os.environ["CRANKBENCH_NO_NUMBA"]
            else:
                os.environ["CRANKBENCH_NO_NUMBA"] = had

    cands = {"numpy": numpy_form}
    if scan._bits_kernel() is not None:
        cands["compiled"] = fold
    t = compare(cands, rounds=rounds, min_time=0.0)
    out = []
    if "compiled" in cands:  # the docstring's figure (1.8-2.1x faster) as a target
        out.append(t.row(SUITE, "record scan: compiled / numpy speed", "compiled",
                         ("numpy", "numpy min + max per block"), f"n={n:.3g} float32",
                         t.ratio("compiled", "numpy")[0], "time / numpy time (paired)",
                         "measure.scan.BlockExtremes: 1.8-2.1x faster measured", bound=1 / 1.5,
                         target=True, note="bound: at least 1.5x faster"))
    for name, method in (("numpy", "record scan: numpy min + max per block"),
                         ("compiled", "record scan: compiled one-pass fold (numba loaded)")):
        if name not in cands:
            continue
        lo, hi = cands[name]()
        error = float(max(np.max(np.abs(lo - want_lo)), np.max(np.abs(hi - want_hi))))
        out.append(t.row(SUITE, method, name, None if name == "numpy" else
                         ("numpy", "numpy min + max per block"), f"n={n:.3g} float32", error,
                         "max abs", "numpy min/max of each block", throughput_items=n,
                         throughput_unit="samples/s", bound=0.0,
                         note="in memory, no file; blocks of measure.scan._SCAN_BLOCK"))
    return out
