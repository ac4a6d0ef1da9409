"""``crankbench balance RUNS...``: correction masses from trial-weight runs (influence
coefficients), with the condition number, trial-weight warnings and an ISO 21940-11 check.

A run is the 1st-order vibration (amplitude, phase) at each measurement plane together with the
trial masses present during that run. Runs come as TOML files (one run each) or CSV files (one
or more runs, a ``run`` column naming them):

TOML::

    [run]
    name = "trial plane 1"
    speed_rpm = 2400.0                      # optional, informative
    [[run.trial]]                           # omit for the initial and check runs
    plane = 1                               # correction plane, 1-based
    mass = 0.010                            # kg at the balancing radius
    angle_deg = 0.0
    [[measurement]]
    plane = 1                               # measurement plane (bearing), 1-based
    amplitude = 85.0                        # any unit, the same in every run
    phase_deg = 30.0

CSV columns: ``run, measurement_plane, amplitude, phase_deg`` and optionally
``trial_plane, trial_mass, trial_angle_deg`` (blank for no trial), one row per measurement plane
(and per trial mass when a run carries several).

The first run without trial masses is the initial run; runs with trial masses are the trial
runs (masses relative to the initial state); ``--check NAME`` marks a run made after fitting
the corrections.
"""

from __future__ import annotations

from pathlib import Path

HELP = "rotor balancing from trial-weight runs: correction masses, conditioning, ISO grade"

__all__ = ["HELP", "configure", "run", "read_runs"]


def configure(parser) -> None:
    parser.add_argument("runs", nargs="+", help="run files (.toml one run each, .csv any number)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--check", default=None,
                        help="name of the check run (made with the corrections fitted)")
    parser.add_argument("--radius", type=float, default=None,
                        help="balancing radius, m (converts masses to unbalance for ISO)")
    parser.add_argument("--rotor-mass", type=float, default=None, help="rotor mass, kg")
    parser.add_argument("--max-speed", type=float, default=None,
                        help="maximum service speed, rpm (ISO 21940-11 check)")
    parser.add_argument("--grade", type=float, default=6.3,
                        help="required balance grade G, mm/s (default 6.3)")
    parser.add_argument("--min-change", type=float, default=0.25,
                        help="warn when a trial changed the vibration by less than this "
                             "fraction (default 0.25)")


def _toml_run(path: Path) -> list[dict]:
    from predict._toml import load_toml
    from predict.errors import RecordError

    doc = load_toml(path, error=RecordError)
    r = doc.table("run", {})
    name = r.string("name", path.stem)
    speed = r.number("speed_rpm", None, low=0.0)
    trials = [(t.integer("plane", minimum=1), t.positive("mass"), t.number("angle_deg", 0.0))
              for t in r.tables("trial", [])]
    for t in r.tables("trial", []):
        t.check_unknown(["plane", "mass", "angle_deg"])
    r.check_unknown()
    meas = []
    for m in doc.tables("measurement"):
        meas.append((m.integer("plane", minimum=1), m.number("amplitude", low=0.0),
                     m.number("phase_deg")))
        m.check_unknown()
    doc.check_unknown()
    if not meas:
        doc.fail("measurement", "needs at least one [[measurement]]")
    return [dict(name=name, source=str(path), speed_rpm=speed, trials=trials, meas=meas)]


def _csv_runs(path: Path) -> list[dict]:
    import pandas as pd

    from predict.errors import RecordError

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
        runs.append(dict(name=str(name), source=str(path), speed_rpm=None,
                         trials=sorted(trials), meas=sorted(meas.values())))
    return runs


def read_runs(paths) -> list[dict]:
    """Read run files into dicts: name, source, speed_rpm, trials [(plane, kg, deg)],
    meas [(plane, amplitude, phase_deg)]."""
    from predict.errors import RecordError

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


def run(args) -> int:
    import warnings

    import numpy as np
    import pandas as pd

    from analysis._output import print_json, print_table
    from predict.errors import ConfigError, RecordError
    from predict.rotor_balance import BalanceWarning, grade_check, influence_balance, phasor

    runs = read_runs(args.runs)
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
                            max_speed=args.max_speed * np.pi / 30, grade=args.grade)
            out["iso_21940_11"] = dict(grade=args.grade, passed=g.passed,
                                       achieved_e_omega_mm_s=g.achieved_grade,
                                       smallest_grade_met=g.smallest_grade, planes=g.to_frame())
        elif any(v is not None for v in (args.radius, args.rotor_mass, args.max_speed)):
            raise ConfigError("the ISO check needs all of --radius, --rotor-mass, --max-speed")
    if args.json:
        print_json(out)
        return 0
    print(f"initial run {initial['name']!r}, trial runs {out['trial_runs']}, "
          f"{len(planes)} measurement planes, {n_planes} correction planes")
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
