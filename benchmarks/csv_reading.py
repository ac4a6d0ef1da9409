"""CSV reading: time against the number of columns, and peak memory of a large file (by hand).

Issue 19 measured 52 s for a 1000-column CSV (one dataset merge per channel: quadratic) and
851 MB peak for a 284 MB CSV. This benchmark reproduces both cases and reports, each against a
baseline timed in the same process (interleaved, after a warm-up):

* ``columns``: ``measure.read`` and ``measure.open`` of CSVs with 250 and 1000 channel columns
  (2000 rows), divided by ``pandas.read_csv`` of the same file — linear reading keeps the ratio
  flat from 250 to 1000 columns;
* ``memory``: peak RSS of ``measure.read`` on a ~280 MB CSV (8 columns, time + 7 channels) in a
  fresh process, minus the RSS after the imports, against the 8 bytes per value the Record
  must hold, and against ``pandas.read_csv(...).to_numpy()`` in another fresh process.

Run::

    python benchmarks/csv_reading.py [--rows 2400000] [--keep]

Prints one JSON object. Files go to a temporary folder, deleted unless ``--keep``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from _memory import peak_mb, rss_mb, run_phases

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def _wide(path: Path, n_cols: int, rows: int = 2000) -> None:
    import numpy as np

    rng = np.random.default_rng(n_cols)
    data = np.column_stack([np.arange(rows) / 1000.0] + [rng.standard_normal(rows)
                                                          for _ in range(n_cols)])
    head = "time [s]," + ",".join(f"c{i} [g]" for i in range(n_cols))
    np.savetxt(path, data, delimiter=",", header=head, comments="", fmt="%.6g")


def _tall(path: Path, rows: int) -> None:
    import numpy as np

    with path.open("w") as f:
        f.write("time [s]," + ",".join(f"ch{i} [m/s^2]" for i in range(7)) + "\n")
        block = 200_000
        for start in range(0, rows, block):
            n = min(block, rows - start)
            rng = np.random.default_rng(start)
            data = np.column_stack([(start + np.arange(n)) / 51_200.0]
                                   + [rng.standard_normal(n) for _ in range(7)])
            np.savetxt(f, data, delimiter=",", fmt="%.9g")


def columns(folder: Path) -> dict:
    import pandas as pd

    from crankbench.measure import io

    out = {}
    for n_cols in (250, 1000):
        p = folder / f"wide_{n_cols}.csv"
        _wide(p, n_cols)
        io.read(p)
        pd.read_csv(p)  # warm-up
        times = {"read": [], "open": [], "pandas": []}
        for _ in range(3):
            for key, call in (("pandas", lambda: pd.read_csv(p)), ("read", lambda: io.read(p)),
                              ("open", lambda: io.open(p))):
                t0 = time.perf_counter()
                call()
                times[key].append(time.perf_counter() - t0)
        best = {k: min(v) for k, v in times.items()}
        out[f"columns_{n_cols}"] = {"read_s": best["read"], "open_s": best["open"],
                                    "pandas_s": best["pandas"],
                                    "read_ratio": best["read"] / best["pandas"],
                                    "open_ratio": best["open"] / best["pandas"]}
    out["read_s_per_column_1000_over_250"] = (out["columns_1000"]["read_s"] / 1000) / (
        out["columns_250"]["read_s"] / 250)
    return out


def memory_read(path: Path) -> dict:
    from crankbench.measure import io

    base = rss_mb()
    t0 = time.perf_counter()
    rec = io.read(path)
    elapsed = time.perf_counter() - t0
    values = sum(int(v.size) for v in rec.data_vars.values()) + rec.sizes["time"]
    return {"read_peak_mb": peak_mb() - base, "read_s": elapsed,
            "record_mb": values * 8 / 1e6, "file_mb": path.stat().st_size / 1e6}


def memory_pandas(path: Path) -> dict:
    import pandas as pd

    from crankbench.measure import io  # noqa: F401 - the same imports as the read phase

    base = rss_mb()
    t0 = time.perf_counter()
    arr = pd.read_csv(path).to_numpy()
    return {"pandas_peak_mb": peak_mb() - base, "pandas_s": time.perf_counter() - t0,
            "pandas_values": int(arr.size)}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=2_400_000)
    ap.add_argument("--folder", default=None)
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--phase", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    folder = Path(args.folder or tempfile.mkdtemp(prefix="crankbench-csv-"))
    folder.mkdir(parents=True, exist_ok=True)
    big = folder / "tall.csv"
    if args.phase == "columns":
        print(json.dumps(columns(folder)))
        return
    if args.phase == "read":
        print(json.dumps(memory_read(big)))
        return
    if args.phase == "pandas":
        print(json.dumps(memory_pandas(big)))
        return
    if not big.exists():
        _tall(big, args.rows)
    result = run_phases(__file__, ["columns", "pandas", "read"], ["--folder", str(folder)])
    result["read_peak_over_record"] = result["read_peak_mb"] / result["record_mb"]
    result["read_peak_over_pandas_peak"] = result["read_peak_mb"] / result["pandas_peak_mb"]
    print(json.dumps(result, indent=1))
    if not args.keep:
        import shutil

        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
