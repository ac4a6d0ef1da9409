"""Batch throughput against the number of workers (issue 20: ≥ 0.8 × linear up to the cores).

Synthesizes ``--records`` short run-ups (the I4 scene, 5 s, torsiograph + speed channel), then
runs the batch chain (:func:`analysis.commands.batch.process_one`, the function every batch
worker runs, writing to a campaign store from this process) on a ``dask.distributed``
LocalCluster of 1, 2, … worker *processes* (one thread each, BLAS limited to one thread in
every worker), interleaving the worker counts over ``--repeats`` rounds after a warm-up round
that imports and compiles in every worker. Prints records per second per worker count, the
speed-up against one worker and the efficiency (speed-up / workers), median over the rounds,
and the fitted exponent of time against worker count; exits 1 when a worker count up to the
cores falls below 0.8 x linear (:data:`EFFICIENCY_BOUND`, issue 20).

Run by hand (not part of the test suite)::

    python benchmarks/batch_scaling.py --records 8 --repeats 3
    python benchmarks/batch_scaling.py --records 8 --workers 1 2 --json

The machine's other load is printed with the figures (os.getloadavg before and after).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: issue 20: records per second at n workers at least this fraction of n x one worker's
EFFICIENCY_BOUND = 0.8


def make_records(folder: Path, n: int) -> tuple[list[Path], Path]:
    """``n`` synthesized records (different seeds) and the shaft-line model they follow."""
    from crankbench.measure.io import write
    from crankbench.measure.synth import Scene, synthesize

    model = ROOT / "sample_data/shaftlines/i4.toml"
    scene = folder / "scene.toml"
    scene.write_text(f"""
[scene]
name = "I4 batch-scaling run-up"
engine = {json.dumps(str(ROOT / "sample_data/engines/i4.toml"))}
shaftline = {json.dumps(str(model))}
seed = 1
max_order = 8.0
[profile]
kind = "runup"
start_rpm = 1900.0
end_rpm = 3100.0
duration = 5.0
[load]
imep = 1.0e6
law = "constant"
[[sensor]]
kind = "torsiograph"
name = "tv_pulley"
node = "pulley hub"
quantity = "angle"
sample_rate = 4000.0
noise_rms = 1.0e-5
[[sensor]]
kind = "speed"
name = "speed"
sample_rate = 100.0
""")
    base = Scene.from_toml(scene)
    paths = []
    for i in range(n):
        run = synthesize(base)
        path = folder / f"run{i:03d}.h5"
        write(run.record.assign_attrs(build=f"B{i}"), path, truth=run.truth)
        paths.append(path)
    return paths, model


def _limit_blas():
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    return True


def time_batch(client, records, model, store_path) -> float:
    """Wall time (s) of one batch of ``records`` on ``client``, rows stored in this process."""
    import distributed

    from crankbench.analysis.campaign.documents import settings_key
    from crankbench.analysis.campaign.store import Store, run_id_for
    from crankbench.analysis.commands.batch import process_one
    from crankbench.analysis.report import file_sha256

    settings = {"bench": "batch_scaling"}
    model_sha = file_sha256(model)
    key = settings_key(settings, model_sha)
    t0 = time.perf_counter()
    with Store(store_path, create=True) as store:
        futures = []
        for path in records:
            sha = file_sha256(path)
            run = {"run_id": run_id_for(sha, key) + f"-{t0:.0f}", "settings": settings,
                   "settings_key": key, "model_sha256": model_sha, "record_sha256": sha}
            futures.append(client.submit(process_one, str(path), str(model), {}, None, None,
                                         False, run, pure=False))
        for fut in distributed.as_completed(futures):
            row = fut.result()
            if row.get("status") != "ok":
                raise RuntimeError(f"{row.get('record')}: {row.get('error')}")
            store.put(row.pop("_document"))
    return time.perf_counter() - t0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=8)
    parser.add_argument("--workers", type=int, nargs="+",
                        default=sorted({1, os.cpu_count() or 1}))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)

    import numpy as np
    from distributed import Client, LocalCluster

    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        records, model = make_records(folder, args.records)
        clusters = {}
        try:
            for w in args.workers:
                cluster = LocalCluster(n_workers=w, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.WARNING)
                client = Client(cluster)
                client.run(_limit_blas)
                # warm-up: one record per worker (imports, first-call set-up)
                time_batch(client, records[:w], model, folder / f"warm{w}.duckdb")
                clusters[w] = (cluster, client)
            times = {w: [] for w in args.workers}
            for r in range(args.repeats):
                for w in args.workers:  # interleaved: each round times every worker count
                    times[w].append(time_batch(clusters[w][1], records, model,
                                               folder / f"s{w}_{r}.duckdb"))
        finally:
            for cluster, client in clusters.values():
                client.close()
                cluster.close()
    load_after = os.getloadavg()
    base = statistics.median(times[args.workers[0]]) * args.workers[0]
    rows = []
    for w in args.workers:
        med = statistics.median(times[w])
        speedup = base / med
        rows.append({"workers": w, "median_s": med, "spread_s": [min(times[w]), max(times[w])],
                     "records_per_s": args.records / med, "speedup": speedup,
                     "efficiency": speedup / w})
    exponent = float("nan")
    if len(args.workers) > 1:
        exponent = float(np.polyfit(np.log(args.workers),
                                    np.log([statistics.median(times[w]) for w in args.workers]),
                                    1)[0])
    out = {"records": args.records, "repeats": args.repeats, "cpu_count": os.cpu_count(),
           "load_before": load_before, "load_after": load_after, "rows": rows,
           "time_exponent_vs_workers": exponent}
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"{args.records} records, {args.repeats} interleaved rounds, {os.cpu_count()} "
              f"cores, load {load_before[0]:.2f} → {load_after[0]:.2f}")
        for r in rows:
            print(f"  {r['workers']} worker(s): {r['median_s']:.2f} s "
                  f"({r['spread_s'][0]:.2f}–{r['spread_s'][1]:.2f}), "
                  f"{r['records_per_s']:.2f} records/s, speed-up {r['speedup']:.2f}, "
                  f"efficiency {r['efficiency']:.2f}")
        print(f"  time ∝ workers^{exponent:.2f}")
    # issue 20's bound: at least 0.8 x linear up to the cores available
    cores = os.cpu_count() or 1
    short = [r for r in rows if r["workers"] <= cores and r["efficiency"] < EFFICIENCY_BOUND]
    for r in short:
        print(f"  below the bound: {r['workers']} workers at efficiency {r['efficiency']:.2f} "
              f"< {EFFICIENCY_BOUND} (check the machine's other load, printed above)",
              file=sys.stderr)
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
