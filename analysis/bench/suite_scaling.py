"""Scaling: cost against record length, number of orders, chain size and records per batch.

For each axis the sizes are timed together in interleaved rounds (:func:`analysis.bench.compare`,
process CPU time, one BLAS thread), one row per size, and a summary row gives the exponent p of
``cost ∝ size^p`` fitted by least squares to the median times (log-log). The summary row's
``error`` is that exponent, ``bound`` the largest the method claims (informational where no
claim is made), and its note the interquartile range of the exponents fitted round by round.

Axes
----
* **Record length**: ``measure.read`` of a ``.h5`` record of 1, 4 and 16 M float32 samples
  (1, 2, 4 M with ``--quick``; claimed linear, bound 1.25); ``analysis.order_track`` of 3
  orders of a run-up (600 -> 3000 rpm at 20 kHz, 10 ... 80 s; 10 ... 40 s with ``--quick``) by
  computed order tracking (bound 1.25) and, in the full run, by Vold-Kalman filtering (claimed
  linear, bound 1.25).
* **Number of orders** (10 s record): ``order_track`` COT over 1 ... 16 orders (1 ... 8 with
  ``--quick``; bound 1.25) and VKF (B = 4 Hz) over 3, 6, 12 and 24 orders (3 ... 12 with
  ``--quick``): orders 1, 1.5, 2, ... (0.5 apart: 5 Hz at 600 rpm, neighbours overlap) and
  always 12.5, so the highest order — hence the solve rate and the samples solved — is the
  same for every count and the fit sees the orders alone. Claimed at most quadratic (issue
  21), bound 2.0: the direct banded solve is cubic in the orders beyond ~8, so from
  ``vkf_iterative.MIN_ORDERS`` the solve is iterative (:mod:`analysis.vkf_iterative`, O(N K)
  per iteration).
* **Chain size**: ``chain().natural_frequencies()`` of every mode, 100 ... 3000 masses (dqds,
  claimed O(n²), bound 2.3), and ``natural_frequencies(n_modes=10)``, 10³ ... 10⁵ masses
  (bisection, claimed O(n), bound 1.25).
* **Records per batch** (1 ... 8 short synthetic I4 run-ups; 1 and 2 with ``--quick``):
  ``crankbench batch`` in-process with one worker on 3 s run-ups of the sample I4 scene
  (torsiograph and speed channels; claimed linear: no per-batch cost beyond a constant, bound
  1.25).
"""

from __future__ import annotations

import contextlib
import io
import shutil
import tempfile
from pathlib import Path

import numpy as np

from . import Row, compare

SUITE = "scaling"
FS = 20_000.0


def _fit(sizes, times):
    """Exponent of times ∝ sizes^p (least squares in log-log)."""
    return float(np.polyfit(np.log(np.asarray(sizes, float)), np.log(np.asarray(times)), 1)[0])


def _axis(axis, method, sizes, label, cands, bound, *, rounds, min_time=0.02) -> list[Row]:
    """Time ``cands`` (one per size, same order) together; a row per size plus the fit."""
    names = [f"{label}={s}" for s in sizes]
    t = compare(dict(zip(names, cands)), rounds=rounds, min_time=min_time)
    medians = [t.time(n) for n in names]
    per_round = [_fit(sizes, [t.cpu[n][r] for n in names]) for r in range(t.rounds)]
    p = _fit(sizes, medians)
    rows = [Row(SUITE, method, f"{axis}: {n}", 0.0, "-", "-",
                m, paired=True, rounds=t.rounds) for n, m in zip(names, medians)]
    lo, hi = np.percentile(per_round, [25, 75])
    rows.append(Row(SUITE, method, f"{axis}: fitted exponent over {label} = "
                    f"{sizes[0]}..{sizes[-1]}", p, "exponent p of cost ∝ size^p",
                    "least squares on log-log medians", medians[-1], bound=bound,
                    note=f"per-round exponents {lo:.2f}-{hi:.2f}", paired=True,
                    rounds=t.rounds))
    return rows


def _runup(duration):
    t = np.arange(int(duration * FS)) / FS
    rpm = 600.0 + (3000.0 - 600.0) * t / duration
    phase = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    x = sum(np.cos(q * phase) / q for q in (1, 2, 3, 4, 6, 8)) \
        + 0.1 * np.random.default_rng(1).standard_normal(t.size)
    return x, rpm


def _length_rows(quick, rounds, tmp: Path) -> list[Row]:
    from crankbench.analysis import order_track
    from crankbench.measure import io
    from crankbench.measure.record import make_record

    sizes = [1_000_000, 2_000_000, 4_000_000] if quick else [1_000_000, 4_000_000, 16_000_000]
    reads = []
    for n in sizes:
        x = np.random.default_rng(n).standard_normal(n).astype(np.float32)
        path = tmp / f"noise_{n}.h5"
        io.write(make_record({"acc": dict(data=x, sample_rate=FS, units="m/s^2",
                                          quantity="acceleration")}), path)
        reads.append(lambda p=path: io.read(p))
    rows = _axis("record length", "measure.read .h5 (file read before)", sizes, "samples",
                 reads, 1.25, rounds=rounds)
    durations = [10, 20, 40] if quick else [10, 20, 40, 80]
    runs = [_runup(d) for d in durations]
    n = [int(d * FS) for d in durations]
    cot = [lambda x=x, r=r: order_track(x, fs=FS, speed_rpm=r, orders=[2, 4, 6], method="cot")
           for x, r in runs]
    rows += _axis("record length", "order_track COT, 3 orders", n, "samples", cot, 1.25,
                  rounds=rounds)
    if not quick:
        vkf = [lambda x=x, r=r: order_track(x, fs=FS, speed_rpm=r, orders=[2, 4, 6],
                                            method="vkf", bandwidth_hz=4.0) for x, r in runs]
        rows += _axis("record length", "order_track VKF, 3 orders", n, "samples", vkf,
                      1.25, rounds=3)
    return rows


def _order_rows(quick, rounds) -> list[Row]:
    from crankbench.analysis import order_track

    x, rpm = _runup(10.0)
    counts = [1, 2, 4, 8] if quick else [1, 2, 4, 8, 16]
    orders = {k: list(np.arange(1, k + 1) * 0.5 + 0.5) for k in counts}
    cot = [lambda o=orders[k]: order_track(x, fs=FS, speed_rpm=rpm, orders=o, method="cot")
           for k in counts]
    vkf_counts = [3, 6, 12] if quick else [3, 6, 12, 24]
    vkf_orders = {k: [*(np.arange(1, k) * 0.5 + 0.5), 12.5] for k in vkf_counts}
    vkf = [lambda o=vkf_orders[k]: order_track(x, fs=FS, speed_rpm=rpm, orders=o, method="vkf",
                                               bandwidth_hz=4.0) for k in vkf_counts]
    return (_axis("orders", "order_track COT, 10 s at 20 kHz", counts, "orders", cot, 1.25,
                  rounds=rounds)
            + _axis("orders", "order_track VKF, 10 s at 20 kHz, top order 12.5", vkf_counts,
                    "orders", vkf, 2.0, rounds=3))


def _chain_rows(quick, rounds) -> list[Row]:
    from crankbench.predict.torsion import chain

    def make(n):
        rng = np.random.default_rng(n)
        return rng.uniform(1, 5, n), rng.uniform(1e5, 1e6, n - 1)

    full = [100, 300, 1000] if quick else [100, 300, 1000, 3000]
    subset = [1000, 10_000] if quick else [1000, 10_000, 100_000]
    data = {n: make(n) for n in sorted(set(full) | set(subset))}
    all_modes = [lambda n=n: chain(*data[n]).natural_frequencies() for n in full]
    lowest = [lambda n=n: chain(*data[n]).natural_frequencies(n_modes=10) for n in subset]
    return (_axis("chain size", "natural_frequencies(), every mode (dqds)", full, "masses",
                  all_modes, 2.3, rounds=rounds)
            + _axis("chain size", "natural_frequencies(n_modes=10) (bisection)", subset,
                    "masses", lowest, 1.25, rounds=rounds))


def _batch_rows(quick, rounds, tmp: Path) -> list[Row]:
    import logging
    from dataclasses import replace

    from crankbench.analysis.cli import main
    from crankbench.measure.io import write
    from crankbench.measure.synth import Scene, synthesize
    from crankbench.measure.synth.profile import ramp
    from crankbench.measure.synth.scene import SensorSpec

    root = Path(__file__).resolve().parents[2]
    model = root / "sample_data/shaftlines/i4.toml"
    sample = Scene.from_toml(root / "sample_data/scenes/i4_runup.toml")
    torsiograph = next(s for s in sample.sensors if s.kind == "torsiograph")
    scene = replace(sample, name="I4 batch scaling", max_order=6.0,
                    profile=ramp(1900.0, 3100.0, duration=3.0),
                    sensors=(torsiograph, SensorSpec("speed", "speed", {"sample_rate": 100.0})))
    counts = [1, 2] if quick else [1, 2, 4, 8]
    for i in range(max(counts)):
        run = synthesize(scene)
        write(run.record.assign_attrs(build=f"B{i}"), tmp / f"run{i:03d}.h5", truth=run.truth)
    files = sorted(str(p) for p in tmp.glob("run*.h5"))
    quiet = logging.getLogger("crankbench")

    def batch(k):
        def go():
            level = quiet.level
            quiet.setLevel(logging.ERROR)
            try:
                with contextlib.redirect_stdout(io.StringIO()):  # its summary table
                    status = main(["-q", "batch", *files[:k], "--model", str(model), "-o",
                                   str(tmp / f"summary{k}.csv"), "--overwrite", "--no-cache",
                                   "--workers", "1"])
            finally:
                quiet.setLevel(level)
            if status != 0:
                raise RuntimeError(f"crankbench batch exited with {status}")
        return go

    return _axis("records per batch", "crankbench batch, 1 worker, 3 s I4 run-ups", counts,
                 "records", [batch(k) for k in counts], 1.25, rounds=2 if quick else 3,
                 min_time=0.0)


def run(quick: bool) -> list[Row]:
    """Rows described in the module docstring."""
    rounds = 3 if quick else 5
    tmp = Path(tempfile.mkdtemp(prefix="crankbench-bench-scaling-"))
    try:
        return (_length_rows(quick, rounds, tmp) + _order_rows(quick, rounds)
                + _chain_rows(quick, rounds) + _batch_rows(quick, rounds, tmp))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
