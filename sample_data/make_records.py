"""Regenerate ``sample_data/records/``: a small I4 run-up in every supported format.

The record is the in-line four of ``sample_data/engines/i4.toml`` on its mounts, running up
linearly from 1500 to 3000 rpm in 4 s at the model's combustion load (imep 13 bar, constant):

* ``acc_block_z`` — vertical acceleration of the engine block at the front of the cylinder
  head, ``position`` = [-0.08, 0.0, 0.35] m in the engine frame (docs/DESIGN.md, "Vibrograph
  sensors"), 10 kHz, float32: every order the model excites at that point — the second-order
  free force and the torque reaction at orders 2, 4, 6, … — computed through the mount model
  by the synthetic bench (:class:`measure.synth.vibrograph.MountChannels`, the loads of
  :func:`predict.mounts.block_excitation`), plus white measurement noise;
* ``speed`` — shaft speed from the bench's speed channel, 100 Hz (rad/s in the Record);
* ``tacho`` — edge times of a 60-2 trigger wheel (58 teeth per revolution, gap of two), the
  first tooth after the gap at cylinder 1's firing TDC (``tdc_offset_deg`` = 0).

``crankbench compare sample_data/records/i4_runup.h5 sample_data/engines/i4.toml`` sets it
against its own model. Ground truth (order amplitudes and phases along the run, phase referred
to cylinder 1's firing TDC) is stored in ``i4_runup.h5``'s ``truth`` group. Every file stays
under 2 MB. Deterministic (fixed seed): running it twice gives identical samples. Refuses to
replace existing files unless ``--overwrite``.

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
POSITION = (-0.08, 0.0, 0.35)   # m, engine frame: front of the cylinder head
DIRECTION = "z"
MAX_ORDER = 24.0           # every order the model's excitation carries
NOISE_RMS = 0.05           # m/s^2
TEETH = 60
MISSING = 2
FORMATS = (".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav")
MODEL = ROOT / "sample_data" / "engines" / "i4.toml"


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


def _model_channel(omega_grid):
    """Order responses of the sensor on the speed grid (rad/s): (orders, complex table)."""
    from crankbench.measure.synth.vibrograph import MountChannels
    from crankbench.predict.balance_tolerance import BalanceSpec
    from crankbench.predict.engine import Engine
    from crankbench.predict.mounts import MountedEngine
    from crankbench.predict.torsion.excitation import engine_excitation

    engine = Engine.from_toml(MODEL)
    orders = np.arange(0.5, MAX_ORDER + 0.25, 0.5)
    mc = MountChannels(MountedEngine.from_toml(MODEL), engine,
                       engine_excitation(engine, orders=orders), orders, [POSITION],
                       omega_grid, counterweights=BalanceSpec.from_toml(MODEL).masses)
    table = np.array([mc.table(k, 0, DIRECTION, "acceleration") for k in range(orders.size)])
    keep = np.abs(table).max(axis=1) > 1e-9 * np.abs(table).max()
    return orders[keep], table[keep]


def model_imep():
    """imep of the model's default combustion (the load the record is made at), Pa."""
    from crankbench.predict.engine import Engine
    from crankbench.predict.pressure import synthetic_pressure

    engine = Engine.from_toml(MODEL)
    return float(synthetic_pressure(engine).imep(engine))


def order_amplitudes(rpm):
    """Complex amplitudes (m/s^2, peak; phase from cylinder 1's firing TDC) of every excited
    order at speeds ``rpm``: (orders, (n_orders, n_speeds) complex)."""
    rpm = np.atleast_1d(np.asarray(rpm, float))
    grid = np.linspace(SPEED_START_RPM, SPEED_END_RPM, 301) * np.pi / 30.0
    orders, table = _model_channel(grid)
    w = rpm * np.pi / 30.0
    return orders, np.array([np.interp(w, grid, t.real) + 1j * np.interp(w, grid, t.imag)
                             for t in table])


def build():
    """Return ``(record, truth)``."""
    rng = np.random.default_rng(SEED)
    t = np.arange(int(DURATION * FS_ACC)) / FS_ACC
    psi = 2.0 * np.pi * revolutions(t)          # cylinder 1 at firing TDC at t = 0
    orders, amp = order_amplitudes(speed_rpm(t))
    acc = np.zeros(t.size)
    for q, a in zip(orders, amp):
        acc += np.real(a * np.exp(1j * q * psi))
    acc += rng.normal(0.0, NOISE_RMS, t.size)
    t_speed = np.arange(int(DURATION * FS_SPEED)) / FS_SPEED
    # the bench's speed channel: true speed plus 0.5 rpm quantisation
    speed = np.round(speed_rpm(t_speed) * 2.0) / 2.0
    record = make_record({
        "acc_block_z": dict(data=acc.astype(np.float32), sample_rate=FS_ACC, units="m/s^2",
                            quantity="acceleration", location="engine block, front",
                            direction=DIRECTION, sensitivity=10.2,
                            sensitivity_units="mV/(m/s^2)",
                            attrs={"position": list(POSITION)}),
        "speed": dict(data=speed, sample_rate=FS_SPEED, units="rpm"),
        "tacho": dict(data=tooth_times(), units="s", quantity="pulse_times",
                      pulses_per_rev=TEETH, missing_teeth=MISSING,
                      attrs={"tdc_offset_deg": 0.0}),
    }, start_time="2026-01-15T09:30:00+00:00",
        attrs={"engine_id": "I4-demo", "test_id": "runup-1500-3000",
               # the run's load, stated so the gas-torque orders can be judged
               "imep": model_imep(), "load_law": "constant"})
    rpm_grid = np.linspace(SPEED_START_RPM, SPEED_END_RPM, 31)
    _, g = order_amplitudes(rpm_grid)
    truth = xr.Dataset(
        {"amplitude": (("rpm", "order"), np.abs(g).T,
                       {"units": "m/s^2", "convention": "peak", "channel": "acc_block_z"}),
         "phase": (("rpm", "order"), np.angle(g).T,
                   {"units": "rad", "reference": "cylinder 1 firing TDC (tacho tooth 0) at "
                                                 "t = 0: signal = amplitude cos(order psi + "
                                                 "phase)"})},
        coords={"rpm": ("rpm", rpm_grid, {"units": "rpm"}),
                "order": ("order", orders, {"units": "1"})},
        attrs={"description": "order amplitudes of acc_block_z along the run-up, from the "
                              "engine model on its mounts (sample_data/engines/i4.toml)",
               "noise_rms": NOISE_RMS, "model": "sample_data/engines/i4.toml"})
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
