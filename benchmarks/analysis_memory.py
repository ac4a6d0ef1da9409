"""Peak memory of streamed order tracking of a 2 GB record (run by hand, not a test).

Writes (once, block by block through dask) a 2 GB HDF5 record: one float32 accelerometer
channel at 51.2 kHz, 500 M samples (2.7 h) of a slow linear run-up 600 -> 3000 rpm carrying
order 1 (0.5 m/s², phase 0.3 rad) and order 2 (2.0 m/s², phase -0.7 rad) plus white noise
(σ = 0.5 m/s²), and a 100 Hz ``rotational_speed`` channel (rad/s) on its own clock. The shaft
angle of the synthesis is the closed form ``φ = 2π/60 (n0 t + a t²/2)``, so the true order
amplitudes and phases are known. Then, in a fresh process, opens it with ``measure.open`` and
runs :func:`analysis.stream.order_track_stream` (COT, 16 revolutions, 64 samples/rev) over the
whole record, sampling VmRSS every 50 ms in a thread and reading ``ru_maxrss`` at the end.
Target (issues 5 and 10): peak ≤ 500 MB.

Run::

    python benchmarks/analysis_memory.py [--path /tmp/crankbench_cot_2GB.h5]
                                         [--samples 500000000] [--segment-seconds 20] [--keep]

The file is deleted afterwards unless ``--keep`` (an existing file is reused with ``--keep``).
Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import threading
import time
from pathlib import Path

from _memory import peak_mb, rss_mb, run_phases

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

FS = 51_200.0
FS_SPEED = 100.0
BLOCK = 2**21                     # samples per generated block (8 MB float32)
RPM0, RPM1 = 600.0, 3000.0
ORDERS = {1.0: (0.5, 0.3), 2.0: (2.0, -0.7)}   # order: (peak amplitude m/s², phase rad)
NOISE = 0.5



def _accel(samples: int) -> float:
    return (RPM1 - RPM0) / ((samples - 1) / FS)   # rpm/s


def make(path: Path, samples: int) -> dict:
    import dask.array as da
    import numpy as np
    import xarray as xr
    from xarray.indexes import RangeIndex

    from crankbench.measure import io

    acc = _accel(samples)

    def block(_, block_info=None):
        start, stop = block_info[None]["array-location"][0]
        rng = np.random.default_rng(start)
        t = np.arange(start, stop) / FS
        phi = 2 * np.pi / 60.0 * (RPM0 * t + 0.5 * acc * t * t)
        x = NOISE * rng.standard_normal(stop - start)
        for o, (a, p) in ORDERS.items():
            x += a * np.cos(o * phi + p)
        return x.astype(np.float32)

    data = da.empty(samples, chunks=BLOCK, dtype=np.float32).map_blocks(block, dtype=np.float32)
    duration = (samples - 1) / FS
    m = int(np.floor(duration * FS_SPEED)) + 2
    ts = np.arange(m) / FS_SPEED
    omega = (RPM0 + acc * ts) * (2 * np.pi / 60.0)
    rec = xr.Dataset(
        {"acc": ("time", data, {"units": "m/s^2", "quantity": "acceleration",
                                "sample_rate": FS}),
         "speed": ("time_speed", omega, {"units": "rad/s", "quantity": "rotational_speed",
                                         "sample_rate": FS_SPEED})},
        attrs={"start_time": "2026-01-01T00:00:00+00:00"})
    rec = rec.assign_coords(xr.Coordinates.from_xindex(
        RangeIndex.linspace(0.0, (samples - 1) / FS, samples, dim="time")))
    rec = rec.assign_coords(xr.Coordinates.from_xindex(
        RangeIndex.linspace(0.0, (m - 1) / FS_SPEED, m, dim="time_speed")))
    t0 = time.perf_counter()
    io.write(rec, path, overwrite=True)
    return {"write_s": time.perf_counter() - t0, "write_peak_rss_mb": peak_mb(),
            "file_gb": path.stat().st_size / 1e9}


def track(path: Path, segment_seconds: float) -> dict:
    import numpy as np
    import scipy.signal  # noqa: F401

    import crankbench.analysis.stream  # noqa: F401  (imports before the baseline)
    from crankbench.analysis.stream import order_track_stream
    from crankbench.measure import io

    base = rss_mb()
    peak = [base]
    done = threading.Event()

    def sample():
        while not done.wait(0.05):
            peak[0] = max(peak[0], rss_mb())

    thread = threading.Thread(target=sample, daemon=True)
    thread.start()
    t0 = time.perf_counter()
    lazy = io.open(path, chunk_seconds=segment_seconds)
    samples = int(lazy["acc"].shape[0])
    res = order_track_stream(lazy, "acc", orders=sorted(ORDERS), speed_channel="speed",
                             segment_seconds=segment_seconds, revolutions=16)
    elapsed = time.perf_counter() - t0
    done.set()
    thread.join()
    out = {"samples": samples, "record_s": samples / FS, "segment_seconds": segment_seconds,
           "blocks": int(res.sizes["time"]), "track_s": elapsed,
           "throughput_MB_s": samples * 4 / 1e6 / elapsed,
           "throughput_Msamples_s": samples / 1e6 / elapsed,
           "rss_after_imports_mb": base, "sampled_peak_rss_mb": peak[0],
           "stream_peak_rss_mb": peak_mb(),
           "speed_rpm_range": [float(res.rpm.min()), float(res.rpm.max())]}
    for o, (a, p) in ORDERS.items():
        amp = res.amplitude.sel(order=o).values
        ph = np.angle(np.exp(1j * (res.phase.sel(order=o).values - p)))
        noise = float(np.median(res.amplitude_noise.values))
        out[f"order_{o:g}"] = {"true_amplitude": a, "max_rel_amplitude_error": float(
            np.abs(amp / a - 1).max()), "mean_rel_amplitude_error": float(np.mean(amp / a - 1)),
            "max_phase_error_rad": float(np.abs(ph).max()),
            "expected_1sigma_rel_from_noise": noise / a}
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--path", type=Path, default=Path("/tmp/crankbench_cot_2GB.h5"))
    parser.add_argument("--samples", type=int, default=500_000_000)
    parser.add_argument("--segment-seconds", type=float, default=20.0)
    parser.add_argument("--keep", action="store_true", help="keep (and reuse) the 2 GB file")
    parser.add_argument("--phase", choices=["all", "make", "track"], default="all")
    args = parser.parse_args(argv)
    if args.phase == "make":
        print(json.dumps(make(args.path, args.samples)))
        return 0
    if args.phase == "track":
        print(json.dumps(track(args.path, args.segment_seconds)))
        return 0
    # each phase in a fresh process: its own peak RSS
    out = run_phases(__file__, ("make", "track"),
                     ["--path", str(args.path), "--samples", str(args.samples),
                      "--segment-seconds", str(args.segment_seconds)],
                     skip=("make",) if args.path.exists() and args.keep else ())
    out["target_peak_rss_mb"] = 500
    out["passed"] = max(out["stream_peak_rss_mb"], out["sampled_peak_rss_mb"]) <= 500
    print(json.dumps(out, indent=2))
    if not args.keep:
        os.unlink(args.path)
    return 0 if out["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
