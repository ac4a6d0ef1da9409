"""Regenerate the sample trial-weight runs: ``python sample_data/balance/generate.py``.

Synthetic machine: the two-disk rotor of ``sample_data/rotors/two_disk.toml`` run at 2400 rpm,
with a known unbalance of 12.4 g at 43° in plane 1 (disk at 0.5 m) and 8.7 g at 212° in plane 2
(disk at 1.0 m), both at radius 0.14 m. Measurements: 1st-order x vibration at the two
bearings, µm peak, phase of x(t) = A cos(Ωt + φ). Trial weights 10 g at 0° in each plane.
``crankbench balance initial.toml trial_plane1.toml trial_plane2.toml`` should recover
12.4 g at 223° and 8.7 g at 32° (the masses that cancel the unbalance). The check run is made
with those corrections as a fitter would place them: rounded to 1 g and 5°.

``records/*.h5`` are the same four runs as measurement records: x displacement (m) at the two
bearings (channels ``bearing_a`` at 0 m, ``bearing_b`` at 1.5 m), 1024 Hz for 6 s, white noise
of 5 % of each channel's amplitude, and a once-per-rev tacho ``tacho`` whose mark is at 0° of
the rotor; each run starts at another shaft angle (as real runs do). ::

    crankbench balance sample_data/balance/records/{initial,trial_plane1,trial_plane2,check}.h5 \
        --channel bearing_a --channel bearing_b --trial 2:1:0.010@0 --trial 3:2:0.010@0 \
        --check check
"""

from pathlib import Path

import numpy as np

from crankbench.predict.lateral.toml import load_rotor
from crankbench.predict.rotor_balance import influence_balance

HERE = Path(__file__).resolve().parent
RADIUS = 0.14
SPEED = 2400 * np.pi / 30
PLANES = (0.5, 1.0)
UNBALANCE = np.array([0.0124 * np.exp(1j * np.radians(43)),
                      0.0087 * np.exp(1j * np.radians(212))])


def measure(rotor, masses):
    items = [(p, abs(m) * RADIUS, np.angle(m)) for p, m in zip(PLANES, masses) if abs(m) > 0]
    x = rotor.unbalance_response([SPEED], items, probes=[0.0, 1.5]).response[0, :, 0]
    return x * 1e6  # µm


FS = 1024.0
DURATION = 6.0


def write_record(name, v_um, start_angle, seed):
    """Record of x(t) = Re(X e^{i(Ωt + start)}) + noise with a 1/rev tacho at rotor angle 0."""
    from crankbench.measure import write
    from crankbench.measure.record import make_record

    rng = np.random.default_rng(seed)
    t = np.arange(int(DURATION * FS)) / FS
    chans = {}
    for ch, z in zip(("bearing_a", "bearing_b"), np.asarray(v_um) * 1e-6):
        x = np.real(z * np.exp(1j * (SPEED * t + start_angle)))
        chans[ch] = {"data": x + 0.05 * abs(z) * rng.standard_normal(t.size),
                     "sample_rate": FS, "units": "m", "quantity": "displacement",
                     "direction": "x"}
    k = np.arange(np.ceil(start_angle / (2 * np.pi)),
                  (SPEED * DURATION + start_angle) / (2 * np.pi))
    chans["tacho"] = {"data": (2 * np.pi * k - start_angle) / SPEED, "quantity": "pulse_times",
                      "units": "s", "pulses_per_rev": 1}
    rec = make_record(chans, attrs={"test_id": f"balancing run {name}"})
    (HERE / "records").mkdir(exist_ok=True)
    write(rec, HERE / "records" / f"{name}.h5", overwrite=True)


def write_toml(name, title, v, trials=()):
    lines = ["# synthetic run, see generate.py", "[run]", f'name = "{title}"',
             "speed_rpm = 2400.0"]
    for plane, m in trials:
        lines += ["", "[[run.trial]]", f"plane = {plane}", f"mass = {abs(m):.6g}",
                  f"angle_deg = {np.degrees(np.angle(m)) % 360:.6g}"]
    for k, z in enumerate(v, start=1):
        lines += ["", "[[measurement]]", f"plane = {k}", f"amplitude = {abs(z):.6g}",
                  f"phase_deg = {np.degrees(np.angle(z)):.6g}"]
    (HERE / name).write_text("\n".join(lines) + "\n", encoding="utf-8")


def main():
    rotor = load_rotor(HERE.parent / "rotors" / "two_disk.toml").rotor
    trial = 0.010
    v0 = measure(rotor, UNBALANCE)
    v1 = measure(rotor, UNBALANCE + [trial, 0])
    v2 = measure(rotor, UNBALANCE + [0, trial])
    write_toml("initial.toml", "initial", v0)
    write_toml("trial_plane1.toml", "trial plane 1", v1, [(1, trial)])
    write_toml("trial_plane2.toml", "trial plane 2", v2, [(2, trial)])
    result = influence_balance(v0, np.array([v1, v2]), [trial, trial])
    # the fitter rounds to 1 g and 5 degrees
    fitted = np.round(np.abs(result.corrections) * 1e3) / 1e3 * np.exp(
        1j * np.radians(5 * np.round(np.degrees(np.angle(result.corrections)) / 5)))
    vc = measure(rotor, UNBALANCE + fitted)
    write_toml("check.toml", "check", vc)
    rows = ["run,measurement_plane,amplitude,phase_deg,trial_plane,trial_mass,trial_angle_deg"]
    for name, v, tp in (("initial", v0, ""), ("trial plane 1", v1, 1), ("trial plane 2", v2, 2)):
        for k, z in enumerate(v, start=1):
            tm = f"{trial:g},0" if tp else ","
            rows.append(f"{name},{k},{abs(z):.6g},{np.degrees(np.angle(z)):.6g},{tp},{tm}")
    (HERE / "runs.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    for seed, (name, v, start) in enumerate((("initial", v0, 0.0), ("trial_plane1", v1, 1.9),
                                             ("trial_plane2", v2, 4.4), ("check", vc, 2.7))):
        write_record(name, v, start, seed)


if __name__ == "__main__":
    main()
