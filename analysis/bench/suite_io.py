"""Read throughput per record format against ``numpy.fromfile`` of the raw bytes.

One float32 accelerometer channel (51.2 kHz, white noise) is written in every format, and the
same samples as a headerless raw file. Each row times one read of the channel (median of a few
runs, files in the page cache) and divides by the time of ``numpy.fromfile`` on the raw file
timed in the same run, so ``ratio`` is the cost relative to the fastest possible read
(``1 / ratio`` is the fraction of raw throughput reached). ``error`` is the largest absolute
difference between the samples read and the samples written (all formats store float32 or
wider, so the bound is 0: exact).

Rows per format: the format reader (parse, SI conversion, time coordinate) and, for the native
HDF5 layout, also the storage layer alone (h5py ``read_direct``), the full ``measure.read``
(plus validation and SHA-256 of the file, hashed on a second thread) and streaming through
``measure.open`` block by block. Sizes: quick 5 M samples, full 50 M; the text and UFF formats
(pure-Python parsers) use a tenth of that, and so does MDF4 in quick mode, as the ``setting``
column says.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np

from . import Row, median_time

SUITE = "io"
FS = 51_200.0
#: formats whose writer/reader is too slow for the full size run at 1/10 of it
SLOW = {".csv": 10, ".uff": 10}
#: ... and in quick mode (< 20 s in all) also MDF4, whose writer takes ~1 s per M samples
SLOW_QUICK = {**SLOW, ".mf4": 10}


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
    try:
        sizes = sorted({n_full // slow.get(ext, 1) for ext in
                        (".h5", ".nc", ".tdms", ".wav", ".mf4", ".uff", ".csv")})
        records = {n: _record(n) for n in sizes}
        raw_time = {}
        for n, (_, x) in records.items():
            raw = tmp / f"raw_{n}.f32"
            x.tofile(raw)
            raw_time[n] = median_time(lambda raw=raw: np.fromfile(raw, dtype=np.float32),
                                      repeats=repeats)

        def add(method, setting, func, n, x, note=""):
            got = func()
            error = float(np.max(np.abs(np.asarray(got, dtype=np.float64) - x)))
            t = median_time(func, repeats=repeats)
            rows.append(Row(SUITE, method, setting, error, "max abs", "samples written", t,
                            baseline="numpy.fromfile raw float32", ratio=t / raw_time[n],
                            throughput=n / t, throughput_unit="samples/s", bound=0.0,
                            note=note))

        for ext in (".h5", ".nc", ".tdms", ".wav", ".mf4", ".uff", ".csv"):
            n = n_full // slow.get(ext, 1)
            rec, x = records[n]
            path = tmp / f"record{ext}"
            io.write(rec, path)
            module = module_for(path)
            setting = f"n={n:.3g}"
            add(f"reader {ext}", setting,
                lambda m=module, p=path: m.read(p)["acc"].values, n, x,
                note=f"{path.stat().st_size / 1e6:.0f} MB file")
            if ext == ".h5":
                import h5py

                def storage(p=path):
                    with h5py.File(p, "r") as f:
                        d = f["channels/acc"]
                        out = np.empty(d.shape, d.dtype)
                        d.read_direct(out)
                        return out

                add("h5py read_direct (storage only)", setting, storage, n, x)

                def full(p=path):
                    io._HASH_CACHE.clear()
                    return io.read(p)["acc"].values

                add("measure.read .h5 (validate + sha256)", setting, full, n, x)

                def stream(p=path):
                    lazy = io.open(p, chunk_seconds=20.0)
                    return np.concatenate([b for _, b in io.iter_blocks(lazy, "acc")])

                add("measure.open .h5 blocks of 20 s", setting, stream, n, x,
                    note="includes sha256 (cached after the first run)")
            path.unlink()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return rows
