"""Peak memory of streaming a 2 GB record through ``measure.open`` (run by hand, not a test).

Writes (once) a 2 GB HDF5 record: one float32 accelerometer channel at 51.2 kHz, 500 M samples
(2.7 h), a 2nd-order sine plus noise generated block by block through dask, so writing is
bounded in memory as well. Then, in a fresh process, opens it with ``measure.open`` and computes
a running RMS over 1 s windows block by block (``measure.io.iter_blocks``), and reports the
process's peak resident set size (``ru_maxrss``) together with the RSS right after the imports.
Target (issue 2 / issue 10): peak ≤ 500 MB.

Run::

    python benchmarks/io_memory.py [--path /tmp/crankbench_2GB.h5] [--samples 500000000]
                                   [--chunk-seconds 20] [--keep]

The file is deleted afterwards unless ``--keep``. Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from _memory import peak_mb, rss_mb, run_phases

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

FS = 51_200.0
BLOCK = 2**21  # samples per generated block (8 MB float32)



def make(path: Path, samples: int) -> dict:
    import dask.array as da
    import numpy as np
    import xarray as xr
    from xarray.indexes import RangeIndex

    from crankbench.measure import io

    def block(_, block_info=None):
        start, stop = block_info[None]["array-location"][0]
        rng = np.random.default_rng(start)
        t = np.arange(start, stop) / FS
        return (2.0 * np.sin(2 * np.pi * 100.0 * t) + rng.standard_normal(stop - start)
                ).astype(np.float32)

    template = da.empty(samples, chunks=BLOCK, dtype=np.float32)
    data = template.map_blocks(block, dtype=np.float32)
    rec = xr.Dataset({"acc": ("time", data, {"units": "m/s^2", "quantity": "acceleration",
                                              "sample_rate": FS})},
                     attrs={"start_time": "2026-01-01T00:00:00+00:00"})
    rec = rec.assign_coords(xr.Coordinates.from_xindex(
        RangeIndex.linspace(0.0, (samples - 1) / FS, samples, dim="time")))
    t0 = time.perf_counter()
    io.write(rec, path, overwrite=True)
    return {"write_s": time.perf_counter() - t0, "write_peak_rss_mb": peak_mb(),
            "file_gb": path.stat().st_size / 1e9}


def stream(path: Path, chunk_seconds: float) -> dict:
    import numpy as np

    from crankbench.measure import io

    base = rss_mb()
    t0 = time.perf_counter()
    lazy = io.open(path, chunk_seconds=chunk_seconds)
    t_open = time.perf_counter() - t0
    window = int(FS)  # 1 s windows; blocks are whole seconds long
    rms = []
    total_sq, total_n = 0.0, 0
    carry = np.empty(0, np.float64)
    for _, block in io.iter_blocks(lazy, "acc"):
        x = np.concatenate([carry, block.astype(np.float64)])
        whole = (x.size // window) * window
        if whole:
            rms.append(np.sqrt(np.mean(x[:whole].reshape(-1, window) ** 2, axis=1)))
        carry = x[whole:]
        total_sq += float(np.dot(block, block))
        total_n += block.size
    elapsed = time.perf_counter() - t0
    rms = np.concatenate(rms)
    return {"samples": total_n, "chunk_seconds": chunk_seconds, "open_s": t_open,
            "stream_s": elapsed, "throughput_MB_s": total_n * 4 / 1e6 / elapsed,
            "rss_after_imports_mb": base, "stream_peak_rss_mb": peak_mb(),
            "overall_rms": float(np.sqrt(total_sq / total_n)),
            "expected_rms": float(np.sqrt(2.0**2 / 2 + 1.0)),
            "windows": int(rms.size), "window_rms_min": float(rms.min()),
            "window_rms_max": float(rms.max())}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--path", type=Path, default=Path("/tmp/crankbench_2GB.h5"))
    parser.add_argument("--samples", type=int, default=500_000_000)
    parser.add_argument("--chunk-seconds", type=float, default=20.0)
    parser.add_argument("--keep", action="store_true", help="keep the 2 GB file")
    parser.add_argument("--phase", choices=["all", "make", "stream"], default="all")
    args = parser.parse_args(argv)
    if args.phase == "make":
        print(json.dumps(make(args.path, args.samples)))
        return 0
    if args.phase == "stream":
        print(json.dumps(stream(args.path, args.chunk_seconds)))
        return 0
    # each phase in a fresh process: its own peak RSS
    out = run_phases(__file__, ("make", "stream"),
                     ["--path", str(args.path), "--samples", str(args.samples),
                      "--chunk-seconds", str(args.chunk_seconds)],
                     skip=("make",) if args.path.exists() and args.keep else ())
    out["target_peak_rss_mb"] = 500
    out["passed"] = out["stream_peak_rss_mb"] <= 500
    print(json.dumps(out, indent=2))
    if not args.keep:
        os.unlink(args.path)
    return 0 if out["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
