"""Regenerate ``sample_data/records/``: a small I4 run-up in every supported format.

The record is an inline four-cylinder engine running up linearly from 1500 to 3000 rpm in 4 s:

* ``acc_block_z`` — engine-block vertical acceleration, 10 kHz, float32, dominated by the
  second engine order (the I4's unbalanced secondary inertia force, amplitude growing with the
  square of speed) with a smaller fourth order and white measurement noise;
* ``speed`` — shaft speed from the bench's speed channel, 100 Hz (rad/s in the Record);
* ``tacho`` — edge times of a 60-2 trigger wheel (58 teeth per revolution, gap of two).

Ground truth (order amplitudes along the run) is stored in ``i4_runup.h5``'s ``truth`` group.
Every file stays under 2 MB. Deterministic (fixed seed): running it twice gives identical
samples. Refuses to replace existing files unless ``--overwrite``.

Run::

    python sample_data/make_records.py [--out DIR] [--overwrite]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # allow running from a fresh clone without install
    sys.path.insert(0, str(ROOT))

from crankbench.measure import io  # noqa: E402
from crankbench.measure.record import make_record  # noqa: E402

SEED = 20260115
FS_ACC = 10_000.0          # Hz
FS_SPEED = 100.0           # Hz
DURATION = 4.0             # s
SPEED_START_RPM = 1500.0
SPEED_END_RPM = 3000.0
ORDER2_AT_3000 = 2.0       # m/s^2 peak of order 2 at 3000 rpm
ORDER4_AT_3000 = 0.4       # m/s^2 peak of order 4 at 3000 rpm
ORDER4_PHASE = 0.6         # rad
NOISE_RMS = 0.05           # m/s^2
TEETH = 60
MISSING = 2
FORMATS = (".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav")


def speed_rpm(t):
    """Linear run-up, rpm."""
    return SPEED_START_RPM + (SPEED_END_RPM - SPEED_START_RPM) * np.asarray(t) / DURATION


def revolutions(t):
    """Shaft revolutions since t = 0: integral of speed_rpm / 60."""
    t = np.asarray(t, dtype=np.float64)
    slope = (SPEED_END_RPM - SPEED_START_RPM) / DURATION
    return (SPEED_START_RPM * t + 0.5 * slope * t**2) / 60.0


def tooth_times():
    """Exact edge times of the 60-2 wheel: solve revolutions(t) = k/60 (quadratic)."""
    slope = (SPEED_END_RPM - SPEED_START_RPM) / DURATION
    a, b = 0.5 * slope / 60.0, SPEED_START_RPM / 60.0
    total = revolutions(DURATION)
    k = np.arange(int(np.floor(total * TEETH)) + 1)
    k = k[(k % TEETH) < TEETH - MISSING]   # teeth 58 and 59 of each revolution are missing
    r = k / TEETH
    t = 2.0 * r / (b + np.sqrt(b * b + 4.0 * a * r))  # stable root of a t^2 + b t - r = 0
    return t[(t > 0) & (t < DURATION)]


def order_amplitudes(rpm):
    """Peak amplitudes (m/s^2) of orders 2 and 4 at speed ``rpm``: both grow as speed^2."""
    scale = (np.asarray(rpm) / SPEED_END_RPM) ** 2
    return ORDER2_AT_3000 * scale, ORDER4_AT_3000 * scale


def build():
    """Return ``(record, truth)``."""
    rng = np.random.default_rng(SEED)
    t = np.arange(int(DURATION * FS_ACC)) / FS_ACC
    theta = 2.0 * np.pi * revolutions(t)
    a2, a4 = order_amplitudes(speed_rpm(t))
    acc = a2 * np.cos(2 * theta) + a4 * np.cos(4 * theta + ORDER4_PHASE)
    acc += rng.normal(0.0, NOISE_RMS, t.size)
    t_speed = np.arange(int(DURATION * FS_SPEED)) / FS_SPEED
    # the bench's speed channel: true speed plus 0.5 rpm quantisation
    speed = np.round(speed_rpm(t_speed) * 2.0) / 2.0
    record = make_record({
        "acc_block_z": dict(data=acc.astype(np.float32), sample_rate=FS_ACC, units="m/s^2",
                            quantity="acceleration", location="engine block, front",
                            direction="z", sensitivity=10.2, sensitivity_units="mV/(m/s^2)"),
        "speed": dict(data=speed, sample_rate=FS_SPEED, units="rpm"),
        "tacho": dict(data=tooth_times(), units="s", quantity="pulse_times",
                      pulses_per_rev=TEETH, missing_teeth=MISSING),
    }, start_time="2026-01-15T09:30:00+00:00",
        attrs={"engine_id": "I4-demo", "test_id": "runup-1500-3000"})
    rpm_grid = np.linspace(SPEED_START_RPM, SPEED_END_RPM, 31)
    g2, g4 = order_amplitudes(rpm_grid)
    truth = xr.Dataset(
        {"amplitude": (("rpm", "order"), np.stack([g2, g4], axis=1),
                       {"units": "m/s^2", "convention": "peak", "channel": "acc_block_z"}),
         "phase": (("rpm", "order"), np.tile([0.0, ORDER4_PHASE], (rpm_grid.size, 1)),
                   {"units": "rad", "reference": "tacho tooth 0 at t = 0"})},
        coords={"rpm": ("rpm", rpm_grid, {"units": "rpm"}),
                "order": ("order", [2.0, 4.0], {"units": "1"})},
        attrs={"description": "order amplitudes of acc_block_z along the run-up",
               "noise_rms": NOISE_RMS})
    return record, truth


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "sample_data" / "records",
                        help="output folder (default: sample_data/records)")
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")
    args = parser.parse_args(argv)
    targets = [args.out / f"i4_runup{ext}" for ext in FORMATS]
    existing = [p for p in targets + [args.out / "i4_runup.wav.json"] if p.exists()]
    if existing and not args.overwrite:
        print(f"make_records: {len(existing)} file(s) exist (e.g. {existing[0]}); pass "
              "--overwrite to replace them", file=sys.stderr)
        return 1
    record, truth = build()
    for path in targets:
        io.write(record, path, truth=truth if path.suffix == ".h5" else None,
                 overwrite=args.overwrite)
        size = path.stat().st_size
        print(f"{path}  {size / 1e6:.2f} MB")
        if size > 2e6:
            print(f"make_records: {path} is over 2 MB", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
