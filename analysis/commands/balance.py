"""``crankbench balance RUNS...``: correction masses from trial-weight runs (influence
coefficients), with the condition number, trial-weight warnings and an ISO 21940-11 check.

A run is the 1st-order vibration (amplitude, phase) at each measurement plane together with the
trial masses present during that run. Runs come as TOML files (one run each) or CSV files (one
or more runs, a ``run`` column naming them):

TOML::

    [run]
    name = "trial plane 1"
    speed_rpm = 2400.0                      # optional; runs must agree (--speed-tolerance)
    [[run.trial]]                           # omit for the initial and check runs
    plane = 1                               # correction plane, 1-based
    mass = 0.010                            # kg at the balancing radius
    angle_deg = 0.0
    [[measurement]]
    plane = 1                               # measurement plane (bearing), 1-based
    amplitude = 85.0                        # any unit, the same in every run
    phase_deg = 30.0

CSV columns: ``run, measurement_plane, amplitude, phase_deg`` and optionally
``trial_plane, trial_mass, trial_angle_deg`` (blank for no trial) and ``speed_rpm``, one row per
measurement plane (and per trial mass when a run carries several).

Speeds. Influence coefficients hold at one speed: runs whose speeds are known (``speed_rpm`` of
a run file, the measured speed of a record run) must agree within ``--speed-tolerance``
(default 2 %), checked as soon as each speed is known and before any correction is computed
(:func:`analysis.balancing.check_run_speeds`).

The first run without trial masses is the initial run; runs with trial masses are the trial
runs (masses relative to the initial state); ``--check NAME`` marks a run made after fitting
the corrections.

Records. With ``--channel`` (repeatable, one per measurement plane, in plane order) every RUN is
a measurement record (any file :func:`measure.read` reads: .h5, .nc, .csv, .mf4, .tdms, ...;
the run's name is the file stem). The 1st-order amplitude (SI units of the channels) and phase
of each channel are averaged over the steady part of the run by
:func:`analysis.balancing.first_order_phasors`, with the phase referred to a once-per-rev tacho
when the record has one (all runs must share the same kind of reference). The trial masses of
record runs are given by ``--trial RUN:PLANE:MASS_KG@ANGLE_DEG`` (repeatable; RUN is the run's
1-based position among RUNS or its name), e.g.::

    crankbench balance initial.h5 trial_plane1.h5 trial_plane2.h5 \
        --channel bearing_a --channel bearing_b --trial 2:1:0.010@0 --trial 3:2:0.010@0

(sample records: ``sample_data/balance/records/``, see its ``generate.py``).
"""

from __future__ import annotations

from pathlib import Path

HELP = ("rotor balancing from trial-weight runs (run files or records with --channel): "
        "correction masses, conditioning, ISO grade")

__all__ = ["HELP", "configure", "parse_trial", "read_record_runs", "read_runs", "run"]


def configure(parser) -> None:
    from crankbench.analysis.balancing import RUN_SPEED_TOLERANCE
    from crankbench.analysis.commands._args import add_list, integer, number

    parser.add_argument("runs", nargs="+",
                        help="run files (.toml one run each, .csv any number) or, with "
                             "--channel, records (.h5 .nc .csv .mf4 .tdms ...; e.g. "
                             "sample_data/balance/records/*.h5)")
    add_list(parser, "--channel", metavar="NAME",
             help="record channel of each measurement plane, in plane order; makes every RUN "
                  "a record")
    parser.add_argument("--trial", action="append", default=[], metavar="RUN:PLANE:KG@DEG",
                        help="trial mass carried by record run RUN (1-based position or name): "
                             "correction plane, mass kg, angle deg from the mark (repeatable)")
    parser.add_argument("--speed-channel", default=None,
                        help="record speed source (rotational_speed channel or pulse train; "
                             "default: found)")
    parser.add_argument("--steady-fraction", type=number(low=0.0, high=1.0, strict_low=True),
                        default=0.8, help="central fraction of each record averaged, (0, 1] "
                                          "(default 0.8)")
    parser.add_argument("--revolutions", type=integer(low=1, high=4096), default=16,
                        help="order-tracking block length, revolutions (default 16)")
    parser.add_argument("--speed-tolerance", type=number(low=0.0, high=1.0, strict_low=True),
                        default=RUN_SPEED_TOLERANCE,
                        help="largest relative speed difference between runs (default "
                             f"{RUN_SPEED_TOLERANCE:g}: influence coefficients hold at one "
                             "speed)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--check", default=None,
                        help="name of the check run (made with the corrections fitted)")
    parser.add_argument("--radius", type=number(low=0.0, strict_low=True, unit="m"),
                        default=None,
                        help="balancing radius, m (converts masses to unbalance for ISO)")
    parser.add_argument("--rotor-mass", type=number(low=0.0, strict_low=True, unit="kg"),
                        default=None, help="rotor mass, kg")
    parser.add_argument("--max-speed", type=number(low=0.0, strict_low=True, unit="rpm"),
                        default=None,
                        help="maximum service speed, rpm (ISO 21940-11 check)")
    parser.add_argument("--grade", type=number(low=0.0, strict_low=True), default=6.3,
                        help="required balance grade G, mm/s (default 6.3)")
    parser.add_argument("--min-change", type=number(low=0.0, high=1.0), default=0.25,
                        help="warn when a trial changed the vibration by less than this "
                             "fraction (default 0.25)")


def _toml_run(path: Path) -> list[dict]:
    from crankbench.predict._toml import load_toml
    from crankbench.predict.errors import RecordError

    doc = load_toml(path, error=RecordError)
    r = doc.table("run", {})
    name = r.string("name", path.stem)
    speed = r.number("speed_rpm", None, low=0.0, unit="rpm", plausible=(1.0, 1e6))
    trials = [(t.integer("plane", minimum=1), t.positive("mass", unit="kg", plausible=(1e-6, 100.0)),
               t.number("angle_deg", 0.0, unit="deg", plausible=(1e-3, 360.0)))
              for t in r.tables("trial", [])]
    for t in r.tables("trial", []):
        t.check_unknown(["plane", "mass", "angle_deg"])
    r.check_unknown()
    meas = []
    for m in doc.tables("measurement"):
        meas.append((m.integer("plane", minimum=1), m.number("amplitude", low=0.0, unit=None),
                     m.number("phase_deg", unit="deg", plausible=(1e-3, 720.0))))
        m.check_unknown()
    doc.check_unknown()
    if not meas:
        doc.fail("measurement", "needs at least one [[measurement]]")
    return [dict(name=name, source=str(path), speed_rpm=speed, trials=trials, meas=meas)]


def _csv_runs(path: Path) -> list[dict]:
    import pandas as pd

    from crankbench.predict.errors import RecordError

    try:
        frame = pd.read_csv(path, comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise RecordError(f"{path}: not a readable CSV ({exc})") from None
    need = {"run", "measurement_plane", "amplitude", "phase_deg"}
    missing = need - set(frame.columns)
    if missing:
        raise RecordError(f"{path}: missing column(s) {sorted(missing)}; expected "
                          "run, measurement_plane, amplitude, phase_deg [, trial_plane, "
                          "trial_mass, trial_angle_deg]")
    runs = []
    for name, group in frame.groupby("run", sort=False):
        meas = {}
        trials = set()
        for i, row in group.iterrows():
            try:
                plane, amp, ph = int(row["measurement_plane"]), float(row["amplitude"]), float(
                    row["phase_deg"])
            except (TypeError, ValueError):
                raise RecordError(f"{path}: row {i + 2}: measurement_plane, amplitude and "
                                  "phase_deg must be numbers") from None
            if amp < 0 or plane < 1:
                raise RecordError(f"{path}: row {i + 2}: amplitude must be >= 0 and "
                                  "measurement_plane >= 1")
            meas[plane] = (plane, amp, ph)
            if "trial_mass" in group and pd.notna(row.get("trial_mass")):
                trials.add((int(row["trial_plane"]), float(row["trial_mass"]),
                            float(row.get("trial_angle_deg", 0.0) or 0.0)))
        speed = None
        if "speed_rpm" in group:
            values = pd.to_numeric(group["speed_rpm"], errors="coerce").dropna().unique()
            if len(values) > 1:
                raise RecordError(f"{path}: run {name!r} has several speed_rpm values "
                                  f"{sorted(values.tolist())}; one speed per run")
            speed = float(values[0]) if len(values) else None
        runs.append(dict(name=str(name), source=str(path), speed_rpm=speed,
                         trials=sorted(trials), meas=sorted(meas.values())))
    return runs


def read_runs(paths) -> list[dict]:
    """Read run files into dicts: name, source, speed_rpm, trials [(plane, kg, deg)],
    meas [(plane, amplitude, phase_deg)]."""
    from crankbench.predict.errors import RecordError

    runs = []
    for p in map(Path, paths):
        if not p.exists():
            raise FileNotFoundError(f"{p}: no such run file")
        if p.suffix.lower() == ".toml":
            runs.extend(_toml_run(p))
        elif p.suffix.lower() == ".csv":
            runs.extend(_csv_runs(p))
        else:
            raise RecordError(f"{p}: unknown run file type {p.suffix!r}; expected .toml or .csv")
    names = [r["name"] for r in runs]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise RecordError(f"run names must be unique, repeated: {sorted(dup)}")
    return runs


def parse_trial(text: str) -> tuple[str, int, float, float]:
    """Parse ``RUN:PLANE:MASS_KG@ANGLE_DEG`` into (run, plane, mass kg, angle deg).

    Examples
    --------
    >>> parse_trial("2:1:0.010@30")
    ('2', 1, 0.01, 30.0)
    """
    from crankbench.predict.errors import ConfigError

    try:
        run_id, plane, rest = text.rsplit(":", 2)
        mass, _, angle = rest.partition("@")
        out = (run_id.strip(), int(plane), float(mass), float(angle or 0.0))
    except ValueError:
        raise ConfigError(f"--trial {text!r}: expected RUN:PLANE:MASS_KG@ANGLE_DEG, e.g. "
                          "2:1:0.010@0") from None
    if not out[0] or out[1] < 1 or not out[2] > 0 or not _finite(out[2], out[3]):
        raise ConfigError(f"--trial {text!r}: needs a run, a plane >= 1, a mass > 0 kg and a "
                          "finite angle")
    return out


def _finite(*values) -> bool:
    import math

    return all(math.isfinite(v) for v in values)


def read_record_runs(paths, channels, trials=(), *, speed_channel=None, steady_fraction=0.8,
                     revolutions=16, speed_tolerance=None):
    """Read records into run dicts (like :func:`read_runs`) plus the table of phasors.

    ``trials`` are :func:`parse_trial` tuples. ``speed_tolerance`` (relative) refuses a run
    whose speed differs from the first run's as soon as it is read. Returns
    (runs, phasors DataFrame).
    """
    from ..balancing import check_run_speeds

    import pandas as pd

    from crankbench.measure import read
    from crankbench.predict.errors import ConfigError, RecordError

    from ..balancing import first_order_phasors

    paths = [Path(p) for p in paths]
    names = [p.stem for p in paths]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise RecordError(f"record runs are named by file stem, repeated: {sorted(dup)}")
    carried = {n: [] for n in names}
    for run_id, plane, mass, angle in trials:
        if run_id.isdigit():
            k = int(run_id)
            if not 1 <= k <= len(paths):
                raise ConfigError(f"--trial {run_id}:...: run position must be 1..{len(paths)}")
            name = names[k - 1]
        elif run_id in carried:
            name = run_id
        else:
            raise ConfigError(f"--trial {run_id}:...: no run named {run_id!r}; runs: {names}")
        carried[name].append((plane, mass, angle))
    runs, frames = [], []
    for p, name in zip(paths, names):
        if not p.exists():
            raise FileNotFoundError(f"{p}: no such record file")
        record = read(p)
        ph = first_order_phasors(record, channels, speed_channel=speed_channel,
                                 steady_fraction=steady_fraction, revolutions=revolutions)
        ph.insert(0, "run", name)
        ph.insert(2, "measurement_plane", range(1, len(ph) + 1))
        frames.append(ph)
        runs.append(dict(name=name, source=str(p), speed_rpm=float(ph.rpm.mean()),
                         trials=sorted(carried[name]),
                         meas=[(k, a, d) for k, a, d in zip(ph.measurement_plane, ph.amplitude,
                                                           ph.phase_deg)]))
        if speed_tolerance is not None:   # refuse now, before the other records are read
            check_run_speeds([(r["name"], r["speed_rpm"]) for r in runs],
                             speed_tolerance=speed_tolerance)
    phasors = pd.concat(frames, ignore_index=True)
    refs = {r.split(" ")[0] for r in phasors.phase_reference}
    if len(refs) > 1:
        bad = phasors.groupby("run").phase_reference.first().to_dict()
        raise RecordError("runs have different phase references (some have a 1/rev tacho, some "
                          f"not); influence coefficients would be inconsistent: {bad}")
    units = set(phasors.units)
    if len(units) > 1:
        raise RecordError(f"channels have different units {sorted(units)}; use channels of one "
                          "quantity")
    return runs, phasors


def run(args) -> int:
    import warnings

    import numpy as np
    import pandas as pd

    from crankbench.analysis._output import print_json, print_table
    from crankbench.predict.errors import ConfigError, RecordError
    from crankbench.predict.rotor_balance import BalanceWarning, grade_check, influence_balance, phasor

    from crankbench.analysis.balancing import check_run_speeds

    iso = (args.radius, args.rotor_mass, args.max_speed)
    if any(v is not None for v in iso) and None in iso:
        raise ConfigError("the ISO check needs all of --radius, --rotor-mass, --max-speed")
    if any(v is not None for v in iso) and args.check is None:
        raise ConfigError("--radius, --rotor-mass and --max-speed grade the check run: give "
                          "--check NAME")
    phasors = None
    if getattr(args, "channel", None):
        trials = [parse_trial(t) for t in args.trial]   # all arguments checked first
        for p in args.runs:
            if not Path(p).exists():
                raise FileNotFoundError(f"{p}: no such record file")
        stems = [Path(p).stem for p in args.runs]
        if args.check is not None and args.check not in stems:
            raise ConfigError(f"--check {args.check!r} names no run; runs: {stems}")
        runs, phasors = read_record_runs(
            args.runs, args.channel, trials,
            speed_channel=args.speed_channel, steady_fraction=args.steady_fraction,
            revolutions=args.revolutions, speed_tolerance=args.speed_tolerance)
    else:
        if getattr(args, "trial", None):
            raise ConfigError("--trial applies to record runs (with --channel); run files "
                              "carry their trial masses")
        runs = read_runs(args.runs)
        check_run_speeds([(r["name"], r["speed_rpm"]) for r in runs],
                         speed_tolerance=args.speed_tolerance)
    planes = sorted({m[0] for r in runs for m in r["meas"]})
    for r in runs:
        got = [m[0] for m in r["meas"]]
        if got != planes:
            raise RecordError(f"{r['source']}: run {r['name']!r} has measurement planes {got}, "
                              f"expected {planes} like the other runs")
    check = None
    if args.check is not None:
        match = [r for r in runs if r["name"] == args.check]
        if not match:
            raise ConfigError(f"--check {args.check!r} names no run; runs: "
                              f"{[r['name'] for r in runs]}")
        check = match[0]
    plain = [r for r in runs if not r["trials"] and r is not check]
    trial_runs = [r for r in runs if r["trials"] and r is not check]
    if not plain:
        raise RecordError("no initial run (a run without trial masses)")
    if not trial_runs:
        raise RecordError("no trial runs (runs with [[run.trial]] / trial_mass)")
    initial = plain[0]
    n_planes = max(t[0] for r in trial_runs for t in r["trials"])

    def vec(r):
        return phasor([m[1] for m in r["meas"]], [m[2] for m in r["meas"]])

    masses = np.zeros((len(trial_runs), n_planes), dtype=complex)
    for i, r in enumerate(trial_runs):
        for plane, mass, ang in r["trials"]:
            masses[i, plane - 1] += phasor(mass, ang)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BalanceWarning)  # reported in the output instead
        result = influence_balance(vec(initial), np.array([vec(r) for r in trial_runs]), masses,
                                   min_response_change=args.min_change)
    out = dict(initial_run=initial["name"], trial_runs=[r["name"] for r in trial_runs],
               corrections=result.to_frame().rename(columns={"mass": "mass_kg"}),
               influence=result.influence_frame(), condition_number=result.condition_number,
               trial_condition=result.trial_condition,
               response_change=list(result.response_change), warnings=list(result.warnings),
               phasors=phasors,
               predicted_residual=pd.DataFrame({
                   "measurement_plane": planes, "amplitude": np.abs(result.residual),
                   "phase_deg": np.degrees(np.angle(result.residual))}))
    if check is not None:
        res = result.residual_unbalance(vec(check))
        out["check_run"] = check["name"]
        out["residual_unbalance"] = pd.DataFrame({
            "plane": np.arange(1, res.size + 1), "mass_kg": np.abs(res),
            "angle_deg": np.degrees(np.mod(np.angle(res), 2 * np.pi))})
        if None not in (args.radius, args.rotor_mass, args.max_speed):
            g = grade_check(res * args.radius, rotor_mass=args.rotor_mass,
                            max_omega=args.max_speed * np.pi / 30, grade=args.grade)
            out["iso_21940_11"] = dict(grade=args.grade, passed=g.passed,
                                       achieved_e_omega_mm_s=g.achieved_grade,
                                       smallest_grade_met=g.smallest_grade, planes=g.to_frame())
    if phasors is None:
        del out["phasors"]
    if args.json:
        print_json(out)
        return 0
    print(f"initial run {initial['name']!r}, trial runs {out['trial_runs']}, "
          f"{len(planes)} measurement planes, {n_planes} correction planes")
    if phasors is not None:
        print_table(phasors.drop(columns=["units"]),
                    title=f"1st-order phasors ({phasors.units.iloc[0]}, peak)")
    print_table(out["corrections"], title="\ncorrection masses (at the trial-weight radius)")
    print(f"\ninfluence matrix condition number {result.condition_number:.4g}; response change "
          f"per trial {', '.join(f'{100 * c:.3g} %' for c in result.response_change)}")
    for msg in result.warnings:
        print(f"WARNING: {msg}")
    print_table(out["predicted_residual"], title="\npredicted residual vibration")
    if "residual_unbalance" in out:
        print_table(out["residual_unbalance"], title=f"\nresidual unbalance from check run "
                                                     f"{check['name']!r}")
    if "iso_21940_11" in out:
        iso = out["iso_21940_11"]
        print(f"\nISO 21940-11 G {iso['grade']:g}: {'PASS' if iso['passed'] else 'FAIL'} "
              f"(e·Ω = {iso['achieved_e_omega_mm_s']:.3g} mm/s, smallest grade met "
              f"G {iso['smallest_grade_met']:g})")
        print_table(iso["planes"])
    return 0
